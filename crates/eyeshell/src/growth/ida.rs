//! Growth by IDA (issue 11): the coupled DAE of `dae.rs` (growth rates as differential
//! rows, the elastic equations and z as algebraic rows) by variable-order BDF with one
//! Newton iteration of the whole system per iterate. The Newton matrix is assembled
//! analytically and factored by the system's own solver (KLU on the whole matrix by
//! default when KLU is built, else the Schur complement of the growth unknowns; see
//! [`default_linear`]), through IDA's custom linear-solver hook; IDA decides when to
//! refresh it. A failure inside a step (an evaluation that cannot be made, a singular
//! matrix) is recoverable: IDA cuts the step and tries again.

use super::dae::{CoupledDae, DaeLinear};
use super::GrowthSettings;
use crate::text::decimals6;
use eyeshell_sundials::{
    CallbackError, CallbackResult, DaeSystem, Ida, IdaLinearSolver, IdaOptions, IdaStats,
};

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
            .and_then(|_| self.dae.residual(y, yp, r))
            .map_err(|e| e.to_callback())
    }

    fn linear_setup(
        &mut self,
        _t: f64,
        cj: f64,
        y: &[f64],
        _yp: &[f64],
        _r: &[f64],
    ) -> CallbackResult {
        self.dae.setup(cj, y).map_err(recoverable)
    }

    fn linear_solve(&mut self, b: &[f64], x: &mut [f64]) -> CallbackResult {
        self.dae.solve(b, x).map_err(recoverable)
    }
}

/// Whether the local error test leaves out the algebraic unknowns (IDASetSuppressAlg): no.
/// Measured on the const scene's work-precision diagram (BENCHMARKS.md): testing them too
/// costs more steps per rtol but gives far smaller errors per second at the tight end
/// (axial length 1.2e-7 in 0.40 s against 0.98 s for 4.9e-8 suppressed) and at the loose
/// end, loses between 1e-4 and 1e-5, and keeps the field errors near the tolerance (5e-5
/// against 3e-4 at rtol 1e-6): the elastic state is what the retina is measured on.
pub const SUPPRESS_ALGEBRAIC: bool = false;

/// Integrate the coupled system from its consistent state at t = 0 to `t_end`, calling
/// `output(dae, t, y)` at each of `times` (increasing, in (0, t_end]) and `progress(t)`
/// after every step. Returns IDA's counters and, on failure, the time reached and why.
#[allow(clippy::too_many_arguments)] // the integrator's whole set-up, each argument distinct
pub fn integrate(
    dae: &mut CoupledDae,
    y0: &[f64],
    yp0: &[f64],
    t_end: f64,
    settings: &GrowthSettings,
    r0: f64,
    times: &[f64],
    output: &mut DaeOutput<'_>,
    progress: &mut dyn FnMut(f64),
) -> (IdaStats, Result<(), (f64, String)>) {
    let options = IdaOptions {
        rtol: settings.rtol,
        atol: settings.atol,
        atol_vector: Some(dae.abs_tolerances(settings.rtol, settings.atol, r0)),
        stop_time: Some(t_end),
        max_steps: 100_000,
        id: Some(dae.id()),
        suppress_algebraic: SUPPRESS_ALGEBRAIC,
        ..IdaOptions::default()
    };
    let mut ida = match Ida::new(
        GrowthDae { dae },
        0.0,
        y0,
        yp0,
        IdaLinearSolver::Custom,
        &options,
    ) {
        Ok(ida) => ida,
        Err(e) => return (IdaStats::default(), Err((0.0, e.to_string()))),
    };
    let n = y0.len();
    let result = super::march(
        &mut IdaStepper {
            ida: &mut ida,
            yp: vec![0.0; n],
            output,
        },
        n,
        t_end,
        times,
        progress,
    );
    (ida.stats(), result)
}

/// What receives the coupled system's state at an output time.
pub type DaeOutput<'a> = dyn FnMut(&mut CoupledDae, f64, &[f64]) -> Result<(), String> + 'a;

/// IDA as [`super::march`] drives it.
struct IdaStepper<'a, 'b, 'c> {
    ida: &'a mut Ida<GrowthDae<'b>>,
    yp: Vec<f64>,
    output: &'a mut DaeOutput<'c>,
}

impl super::Stepper for IdaStepper<'_, '_, '_> {
    fn step(&mut self, t_end: f64, y: &mut [f64]) -> Result<f64, (f64, String)> {
        self.ida.step(t_end, y, &mut self.yp).map_err(|e| {
            // The deadline's own message rather than IDA's "the residual failed".
            let why = self.ida.system_mut().dae.sys.take_out_of_time();
            let why = why.map_or_else(|| e.to_string(), |o| o.to_string());
            (self.ida.stats().current_time, why)
        })
    }

    fn interpolate(&self, t: f64, y: &mut [f64]) -> Result<(), String> {
        self.ida.interpolate(t, y).map_err(|e| e.to_string())
    }

    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), String> {
        (self.output)(self.ida.system_mut().dae, t, y)
    }
}

/// The default linear solver of the coupled system, the fastest measured (BENCHMARKS.md):
/// KLU on the whole system where KLU was built in (a set-up 3.3 ms, a solve 154 µs at
/// N = 501, against 3.8 ms and 174 µs for the Schur complement with KLU on the reduced
/// matrix), else the Schur complement with band LU (a solve 446 µs, against 914 µs for
/// band LU of the whole interleaved system).
pub fn default_linear() -> DaeLinear {
    if eyeshell_sundials::klu_available() {
        DaeLinear::Klu
    } else {
        DaeLinear::Schur
    }
}
