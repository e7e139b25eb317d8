//! Growth by IDA: the coupled DAE of `dae.rs` (growth rates as differential
//! rows, the elastic equations and z as algebraic rows) by variable-order BDF with one
//! Newton iteration of the whole system per iterate. The Newton matrix is assembled
//! analytically and factored by the system's own solver (the Schur complement of the
//! growth unknowns by default, KLU for the matrices it refuses; see [`default_linear`]),
//! through
//! IDA's custom linear-solver hook; IDA decides when to refresh it. The first step comes
//! from y'' at t = 0 ([`initial_step`]) and the step grows by any factor ≥
//! [`STEP_GROWTH_THRESHOLD`]. A failure inside a step (an evaluation that cannot be made, a singular
//! matrix) is recoverable: IDA cuts the step and tries again.

use super::dae::CoupledDae;
use super::settings::DaeLinear;
use super::ObserverError;
use crate::text::decimals6;
use eyeshell_sundials::{
    CallbackError, CallbackResult, DaeSystem, Ida, IdaLinearSolver, IdaOptions, IdaSensStats,
    IdaStats, SensitivityOptions,
};

/// The first step, from the second derivative of the growth state at t = 0 as CVODE
/// estimates its own (IDA's default, 0.5/‖y'‖, took 1e-7-long first steps here and a dozen
/// doubling steps, each with a new Newton matrix, to reach the step the error allows):
/// BDF1's local error h²/2 ‖y''‖ within the tolerance, halved for safety. y''_P comes from
/// one residual at y + δ y' (its growth rows are y'_P − rates(y + δ y') ≈ −δ y''_P; the
/// elastic part of y + δ y' is consistent to O(δ²)). None (IDA's own estimate) if that
/// evaluation fails or y'' vanishes.
fn initial_step(
    dae: &mut CoupledDae,
    y0: &[f64],
    yp0: &[f64],
    rtol: f64,
    atol: &[f64],
    t_end: f64,
) -> Option<f64> {
    let n_p = dae.differential_len();
    // δ moves no growth unknown by more than 1e-6 of its size (and atol).
    let speed = (0..n_p)
        .map(|k| yp0[k].abs() / (y0[k].abs() + atol[k]))
        .fold(0.0, f64::max);
    if !(speed.is_finite() && speed > 0.0) {
        return None;
    }
    let delta = (1e-6 / speed).min(1e-6 * t_end);
    let y: Vec<f64> = y0.iter().zip(yp0).map(|(a, b)| a + delta * b).collect();
    let mut r = vec![0.0; y0.len()];
    dae.residual(&y, yp0, &mut r).ok()?;
    let sum: f64 = (0..n_p)
        .map(|k| (r[k] / delta / (rtol * y0[k].abs() + atol[k])).powi(2))
        .sum();
    let norm = (sum / n_p as f64).sqrt();
    let h = 0.5 * (2.0 / norm).sqrt();
    // At most a tenth of the run; no lower bound tied to t_end (t_end may be absurd).
    (h.is_finite() && h > 0.0).then(|| h.min(0.1 * t_end))
}

/// IDA keeps its step unless the error allows one at least this much longer
/// (IDASetEtaFixedStepBounds; IDA's default is 2). Measured on the const scene (BENCHMARKS.md):
/// with 2, the step sat at 8.6e-4 for the first 120 steps and at a quarter of what the
/// error allowed after t = 0.3 (weighted local errors 0.05–0.3 against the test's 1), because
/// the estimate never promised a doubling; with 1.2 a run to t = 1 takes 140 steps instead
/// of 258 (300 with the initial step below alone) at rtol 1e-6, with errors in axial length
/// as small or smaller at every rtol from 3e-6 to 1e-7, on the const, thick and fibre scenes.
pub const STEP_GROWTH_THRESHOLD: f64 = 1.2;

/// The coupled system as IDA sees it.
pub struct GrowthDae<'a> {
    pub dae: &'a mut CoupledDae,
}

fn recoverable(e: impl std::fmt::Display) -> CallbackError {
    CallbackError::Recoverable(e.to_string())
}

impl DaeSystem for GrowthDae<'_> {
    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult {
        self.dae
            .sys
            .check_deadline(|| format!("in IDA's residual at t = {}", decimals6(t)))
            .and_then(|_| self.dae.sys.set_time(t))
            .and_then(|_| self.dae.residual(y, yp, r))
            .map_err(|e| e.to_callback())
    }

    fn linear_setup(
        &mut self,
        t: f64,
        cj: f64,
        y: &[f64],
        _yp: &[f64],
        _r: &[f64],
    ) -> CallbackResult {
        self.dae.sys.set_time(t).map_err(|e| e.to_callback())?;
        self.dae.setup(cj, y).map_err(recoverable)
    }

    fn linear_solve(&mut self, b: &[f64], x: &mut [f64]) -> CallbackResult {
        self.dae.solve(b, x).map_err(recoverable)
    }

    fn sensitivity_residual(
        &mut self,
        t: f64,
        y: &[f64],
        _yp: &[f64],
        _r: &[f64],
        ys: &[&[f64]],
        yps: &[&[f64]],
        rs: &mut [&mut [f64]],
    ) -> CallbackResult {
        self.dae.sys.set_time(t).map_err(|e| e.to_callback())?;
        self.dae
            .sensitivity_residual(y, ys, yps, rs)
            .map_err(recoverable)
    }
}

/// The forward sensitivities of a run: s(0), s'(0) (from
/// [`CoupledDae::initial_sensitivities`]), whether they take part in the error test, and
/// what receives them at each output time.
pub struct Sensitivities<'a> {
    pub ys0: Vec<Vec<f64>>,
    pub yps0: Vec<Vec<f64>>,
    pub scales: Vec<f64>,
    pub error_control: bool,
    pub output: &'a mut SensOutput<'a>,
}

/// What receives the sensitivities at an output time: `output(dae, t, y, s)`, called before
/// the state's own output there.
pub type SensOutput<'a> =
    dyn FnMut(&mut CoupledDae, f64, &[f64], &[Vec<f64>]) -> Result<(), ObserverError> + 'a;

/// Whether the local error test leaves out the algebraic unknowns (IDASetSuppressAlg): no.
/// Measured on the const scene's work-precision diagram (BENCHMARKS.md): testing them too
/// costs more steps per rtol but gives far smaller errors per second at the tight end
/// (axial length 1.2e-7 in 0.40 s against 0.98 s for 4.9e-8 suppressed) and at the loose
/// end, loses between 1e-4 and 1e-5, and keeps the field errors near the tolerance (5e-5
/// against 3e-4 at rtol 1e-6): the elastic state is what the retina is measured on.
pub const SUPPRESS_ALGEBRAIC: bool = false;

/// The consistent state of the coupled system at t = 0 that IDA starts from: y and y'.
pub struct ConsistentStart<'a> {
    pub y: &'a [f64],
    pub yp: &'a [f64],
}

/// Integrate the coupled system from its consistent state at t = 0 to `span.t_end`, calling
/// `output(dae, t, y)` at each of `span.times` (increasing, in (0, t_end]) and `progress(t)`
/// after every step. Returns IDA's counters and, on failure, the time reached and why.
pub fn integrate(
    dae: &mut CoupledDae,
    start: ConsistentStart<'_>,
    span: &super::Span<'_>,
    output: &mut DaeOutput<'_>,
    progress: &mut super::ProgressFn<'_>,
    sens: Option<Sensitivities<'_>>,
) -> (IdaStats, IdaSensStats, Result<(), (f64, String)>) {
    let (y0, yp0) = (start.y, start.yp);
    let (settings, t_end, times) = (span.settings, span.t_end, span.times);
    // The absolute tolerances scale with the shell's radius (the lengths are in mm).
    let r0 = dae.sys.elastic.params().r0;
    let atol = dae.abs_tolerances(settings.rtol, settings.atol, r0);
    let h0 = initial_step(dae, y0, yp0, settings.rtol, &atol, t_end);
    // With the sensitivities in the error test, the test leaves out the border d, whose
    // sensitivity jumps ([`CoupledDae::sensitivity_error_mask`]).
    let (id, suppress_algebraic) = match &sens {
        Some(s) if s.error_control => (dae.sensitivity_error_mask(), true),
        _ => (dae.id(), SUPPRESS_ALGEBRAIC),
    };
    let options = IdaOptions {
        rtol: settings.rtol,
        atol: settings.atol,
        atol_vector: Some(atol),
        stop_time: Some(t_end),
        max_steps: 100_000,
        id: Some(id),
        suppress_algebraic,
        fixed_step_bounds: Some((1.0, STEP_GROWTH_THRESHOLD)),
        initial_step: h0,
        ..IdaOptions::default()
    };
    let run = super::RunTerms::of(settings, t_end);
    let mut ida = match Ida::new(
        GrowthDae { dae },
        0.0,
        y0,
        yp0,
        IdaLinearSolver::Custom,
        &options,
    ) {
        Ok(ida) => ida,
        Err(e) => {
            return (
                IdaStats::default(),
                IdaSensStats::default(),
                Err((0.0, super::integrator_words(&e, 0.0, run))),
            )
        }
    };
    let n = y0.len();
    let mut sens_output = None;
    if let Some(sens) = sens {
        let options = SensitivityOptions {
            error_control: sens.error_control,
            scales: sens.scales,
        };
        if let Err(e) = ida.init_sensitivities(&sens.ys0, &sens.yps0, &options) {
            return (
                IdaStats::default(),
                IdaSensStats::default(),
                Err((0.0, super::integrator_words(&e, 0.0, run))),
            );
        }
        sens_output = Some(sens.output);
    }
    let result = super::march(
        &mut IdaStepper {
            ida: &mut ida,
            yp: vec![0.0; n],
            output,
            sens_output,
            s: vec![],
            run,
        },
        n,
        t_end,
        times,
        progress,
    );
    (ida.stats(), ida.sensitivity_stats(), result)
}

/// What receives the coupled system's state at an output time.
pub type DaeOutput<'a> = dyn FnMut(&mut CoupledDae, f64, &[f64]) -> Result<(), ObserverError> + 'a;

/// IDA as [`super::march`] drives it.
struct IdaStepper<'a, 'b, 'c, 'd> {
    ida: &'a mut Ida<GrowthDae<'b>>,
    yp: Vec<f64>,
    output: &'a mut DaeOutput<'c>,
    sens_output: Option<&'d mut SensOutput<'d>>,
    /// The sensitivities at the output time (scratch).
    s: Vec<Vec<f64>>,
    /// The run's terms, for IDA's failures.
    run: super::RunTerms,
}

impl super::Stepper for IdaStepper<'_, '_, '_, '_> {
    fn step(&mut self, t_end: f64, y: &mut [f64]) -> Result<f64, (f64, String)> {
        self.ida.step(t_end, y, &mut self.yp).map_err(|e| {
            let stats = self.ida.stats();
            // The deadline's own message rather than IDA's "the residual failed".
            let why = self.ida.system_mut().dae.sys.take_out_of_time();
            let why = why.map_or_else(
                || super::integrator_words(&e, stats.current_step, self.run),
                |o| o.to_string(),
            );
            (stats.current_time, why)
        })
    }

    fn interpolate(&self, t: f64, y: &mut [f64]) -> Result<(), String> {
        self.ida
            .interpolate(t, y)
            .map_err(|e| super::integrator_words(&e, 0.0, self.run))
    }

    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), String> {
        if let Some(sens_output) = self.sens_output.as_deref_mut() {
            let (ns, n) = (self.ida.sensitivity_count(), self.ida.n());
            self.s.resize(ns, vec![0.0; n]);
            self.ida
                .sensitivities_at(t, &mut self.s)
                .map_err(|e| super::integrator_words(&e, 0.0, self.run))?;
            sens_output(self.ida.system_mut().dae, t, y, &self.s).map_err(|e| e.to_string())?;
        }
        (self.output)(self.ida.system_mut().dae, t, y).map_err(|e| e.to_string())
    }
}

/// The default linear solver of the coupled system: the Schur complement of the growth
/// unknowns, its reduced matrix by the crate's almost-block-diagonal LU of 6×6 node blocks
/// (`Reduced::Block`), the fastest (BENCHMARKS.md, "The reduced matrix by block LU":
/// `cargo bench --bench growth -- "const_scene|dae_pieces"`). It eliminates c I − ∂rates/∂P
/// without pivoting, so a Newton matrix whose growth block is too small for that (huge
/// steps where a point's rates barely depend on its own state: t_end = 1e200) goes to a
/// pivoting solver instead, KLU where it was built in ([`CoupledDae`]'s fallback).
pub fn default_linear() -> DaeLinear {
    DaeLinear::SchurBlock
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvp::settings::SolverSettings;
    use crate::growth::system::GrowthSystem;
    use crate::growth::GrowthParams;
    use crate::model::params::Params;

    /// Which kinks a run is stopped at.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Events {
        /// The crossing of φ_max passing to the next pair of points.
        Crossing,
        /// That, and every point's [d]⁺, [r − ρ]⁺ and [α_s − 1]⁺ switching.
        All,
    }

    /// A signature of the kinks at y that changes exactly when one of `which` switches.
    fn signature(dae: &mut CoupledDae, y: &[f64], which: Events) -> Vec<usize> {
        let (cross, on) = dae.kink_state(y).expect("the kinks' state");
        let mut sig = vec![cross.unwrap_or(usize::MAX)];
        if which == Events::All {
            sig.extend(on.iter().flat_map(|f| f.iter().map(|&b| usize::from(b))));
        }
        sig
    }

    struct Run {
        steps: usize,
        error_test_failures: usize,
        residuals: usize,
        jacobians: usize,
        /// Axial length and equatorial radius at the output times.
        lengths: Vec<(f64, f64)>,
        /// Where `which` switched (located by bisection in the dense output).
        events: Vec<f64>,
        seconds: f64,
    }

    const OUTPUT: [f64; 4] = [0.1, 0.2, 0.4, 1.0];

    /// The const scene on N = 501 to t = 1, as [`integrate`] runs it, stopped at each of
    /// `stops` (IDASetStopTime; then IDA re-initialised there if `reinit`, else continued);
    /// the kinks of `locate` located along the way.
    fn run(rtol: f64, stops: &[f64], reinit: bool, locate: Option<Events>) -> Run {
        let start = std::time::Instant::now();
        let (p, g) = (Params::default(), GrowthParams::default());
        let s = SolverSettings::default();
        let mut dae = CoupledDae::new(GrowthSystem::new(&p, &s, &g).unwrap());
        dae.set_linear(default_linear()).unwrap();
        let y0 = dae.initial_state().unwrap();
        let yp0 = dae.derivative(&y0).unwrap();
        let n = y0.len();
        let n_p = dae.differential_len();
        let atol = dae.abs_tolerances(rtol, 1e-2 * rtol, p.r0);
        let h0 = initial_step(&mut dae, &y0, &yp0, rtol, &atol, 1.0);
        let options = IdaOptions {
            rtol,
            atol: 1e-2 * rtol,
            atol_vector: Some(atol),
            stop_time: Some(1.0),
            max_steps: 100_000,
            id: Some(dae.id()),
            suppress_algebraic: SUPPRESS_ALGEBRAIC,
            fixed_step_bounds: Some((1.0, STEP_GROWTH_THRESHOLD)),
            initial_step: h0,
            ..IdaOptions::default()
        };
        let mut ida = Ida::new(
            GrowthDae { dae: &mut dae },
            0.0,
            &y0,
            &yp0,
            IdaLinearSolver::Custom,
            &options,
        )
        .unwrap();
        let (mut y, mut yp, mut yo) = (y0.clone(), yp0.clone(), vec![0.0; n]);
        let mut stops = stops
            .iter()
            .copied()
            .filter(|&t| t > 0.0 && t < 1.0)
            .peekable();
        let mut next_out = OUTPUT.iter().copied().peekable();
        let mut lengths = vec![];
        let mut events = vec![];
        let mut total = (0, 0, 0, 0);
        let (mut t, mut sig) = (0.0, None);
        if let Some(which) = locate {
            sig = Some(signature(ida.system_mut().dae, &y0, which));
        }
        let mut stop_set = false;
        while t < 1.0 {
            if !stop_set {
                if let Some(&e) = stops.peek() {
                    ida.set_stop_time(e).unwrap();
                    stop_set = true;
                }
            }
            let t_prev = t;
            t = ida.step(1.0, &mut y, &mut yp).unwrap();
            while let Some(&tout) = next_out.peek() {
                if tout > t {
                    break;
                }
                ida.interpolate(tout, &mut yo).unwrap();
                let dae = &mut *ida.system_mut().dae;
                dae.adopt(&yo);
                let row = dae.sys.series(tout, &yo[..n_p]).unwrap();
                lengths.push((row.axial_length, row.equatorial_radius));
                next_out.next();
            }
            if let (Some(which), Some(s0)) = (locate, sig.as_ref()) {
                let s1 = signature(ida.system_mut().dae, &y, which);
                // Every switch in the step, by bisection on the dense output.
                let mut stack = vec![(t_prev, s0.clone(), t, s1.clone())];
                while let Some((a, sa, b, sb)) = stack.pop() {
                    if sa == sb {
                        continue;
                    }
                    if b - a < 1e-10 {
                        events.push(b);
                        continue;
                    }
                    let m = 0.5 * (a + b);
                    ida.interpolate(m, &mut yo).unwrap();
                    let sm = signature(ida.system_mut().dae, &yo, which);
                    stack.push((m, sm.clone(), b, sb));
                    stack.push((a, sa, m, sm));
                }
                sig = Some(s1);
            }
            if stop_set && stops.peek().is_some_and(|&e| t >= e) {
                stops.next();
                stop_set = false;
                if reinit {
                    let st = ida.stats();
                    total.0 += st.steps;
                    total.1 += st.error_test_failures;
                    total.2 += st.residual_evaluations;
                    total.3 += st.jacobian_evaluations;
                    ida.reinit(t, &y, &yp).unwrap();
                }
            }
        }
        let st = ida.stats();
        events.sort_by(f64::total_cmp);
        events.dedup();
        Run {
            steps: total.0 + st.steps,
            error_test_failures: total.1 + st.error_test_failures,
            residuals: total.2 + st.residual_evaluations,
            jacobians: total.3 + st.jacobian_evaluations,
            lengths,
            events,
            seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// Whether stopping IDA at the kinks (docs/MODEL.md §6: the crossing of φ_max passing to
    /// the next pair, points stopping growth) cuts its steps and error-test failures at equal
    /// accuracy: the best case of IDA's root finding (IDARootInit), with the roots known
    /// exactly (located to 1e-10 on a reference run at rtol 1e-10) and no root function to
    /// evaluate. Errors against that reference on the same mesh (the time error alone).
    /// A measurement for BENCHMARKS.md ("Stopping at the kinks"), run by hand:
    /// `cargo test --release -p eyeshell-core --lib stopping_at_the_kinks -- --ignored --nocapture`.
    #[test]
    #[ignore = "a measurement (about a minute), recorded in BENCHMARKS.md"]
    fn stopping_at_the_kinks() {
        let crossing = run(1e-10, &[], false, Some(Events::Crossing));
        let all = run(1e-10, &[], false, Some(Events::All));
        let reference = &crossing.lengths;
        println!(
            "reference rtol 1e-10: {} steps, {} crossing events, {} events in all ({:.2} s)",
            crossing.steps,
            crossing.events.len(),
            all.events.len(),
            crossing.seconds
        );
        for rtol in [1e-5, 1e-6, 1e-7, 1e-8] {
            for (what, stops, reinit) in [
                ("no stops", &[][..], false),
                ("crossing, continue", &crossing.events[..], false),
                ("crossing, reinit", &crossing.events[..], true),
                ("all, continue", &all.events[..], false),
                ("all, reinit", &all.events[..], true),
            ] {
                let r = run(rtol, stops, reinit, None);
                let err = r
                    .lengths
                    .iter()
                    .zip(reference)
                    .map(|(a, b)| (a.0 - b.0).abs().max((a.1 - b.1).abs()))
                    .fold(0.0, f64::max);
                println!(
                    "rtol {rtol:e}, {what}: {} steps, {} error-test failures, {} residuals, {} Jacobians, error {err:.2e} mm, {:.3} s",
                    r.steps, r.error_test_failures, r.residuals, r.jacobians, r.seconds
                );
            }
        }
    }
}
