//! Growth in time (docs/MODEL.md §5–6): a method-of-lines system on the material points the
//! elastic scheme uses. By default IDA integrates the coupled DAE of growth and elastic
//! equilibrium (one Newton per step, [`dae`]); beside it CVODE (BDF) integrates the growth
//! ODE with the elastic problem solved at every right-hand side (warm-started), and the
//! published explicit Euler does the same with fixed steps.

pub(crate) mod cvode;
// The coupled DAE and the growth system are public for the numerics tests and the benches
// (analytic against finite-difference Jacobians, timings of their pieces), not as API.
#[doc(hidden)]
pub mod crossing;
pub mod dae;
pub(crate) mod euler;
pub(crate) mod ida;
#[doc(hidden)]
pub mod integral;
pub(crate) mod points;
pub mod refraction;
pub mod schedule;
#[doc(hidden)]
pub mod system;
pub mod tolerance;
pub(crate) mod view;

pub mod settings;

pub use crate::model::growth_law::ThicknessLaw;
use crate::model::optics::Source;
use crate::model::stimulus::{EyeMeasure, Refraction};
use crate::names::Quantity;
pub use settings::{DaeLinear, GrowthParams, GrowthSettings, Integrator};

pub mod problem;
pub use problem::GrowthProblem;
pub mod real_time;

/// One row of series.csv: the eye at one output time, at the posterior pole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeriesRow {
    pub t: f64,
    /// z of the retina at the posterior pole (docs/MODEL.md §6).
    pub axial_length: f64,
    /// The largest radius of the retina.
    pub equatorial_radius: f64,
    /// Distance of the retina behind the blue surface along its polar ray (negative: in front).
    pub retina_minus_blue: f64,
    /// The same for the red surface.
    pub retina_minus_red: f64,
    pub class: Refraction,
    /// The pole's refraction (D): the spectacle power at 12 mm that brings the naked eye's
    /// best focus onto the retina (NaN where none was computed).
    pub refraction_d: f64,
    /// The growth rule's drive at the pole (mm; g_v is its positive part), NaN for an
    /// elastic solve.
    pub drive: f64,
    /// The defocus (D) of the stimulus image at the pole through the lenses worn, when the
    /// rule reads defocus (else NaN).
    pub defocus_d: f64,
}

impl SeriesRow {
    /// The row at time `t` of the eye measured as `eye`.
    pub fn new(t: f64, eye: EyeMeasure) -> SeriesRow {
        SeriesRow {
            t,
            axial_length: eye.axial_length,
            equatorial_radius: eye.equatorial_radius,
            retina_minus_blue: eye.retina_minus_blue,
            retina_minus_red: eye.retina_minus_red,
            class: eye.class,
            refraction_d: eye.refraction_d,
            drive: f64::NAN,
            defocus_d: f64::NAN,
        }
    }
}

/// The growth fields at one node, beside the elastic fields.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GrowthRow {
    pub rho: f64,
    pub zeta: f64,
    pub eta: f64,
    pub g_v: f64,
    pub z_retina: f64,
    pub r_retina: f64,
    /// The rule's drive at the node's own view (mm; beyond φ_max g_v reads the crossing's).
    pub drive: f64,
    /// The defocus there (D), when the rule reads defocus (else NaN).
    pub defocus_d: f64,
}

/// Extra columns of a snapshot, after `bvp::COLUMNS`.
pub const GROWTH_COLUMNS: [&str; 8] = [
    "rho",
    "zeta",
    "eta",
    "g_v",
    "z_retina",
    "r_retina",
    "drive",
    "defocus_D",
];

impl GrowthRow {
    pub fn values(&self) -> [f64; 8] {
        [
            self.rho,
            self.zeta,
            self.eta,
            self.g_v,
            self.z_retina,
            self.r_retina,
            self.drive,
            self.defocus_d,
        ]
    }
}

/// The peripheral refraction at one field angle (a row of peripheral.csv).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeripheralRow {
    /// The field angle (degrees, in air).
    pub field_deg: f64,
    /// The spectacle power (D) at 12 mm that brings the naked eye's best focus of this field
    /// onto the retina: the pole's refraction_D's conversion, off the axis.
    pub refraction_d: f64,
    /// `refraction_d` minus the same at field 0 (the pole's): the relative peripheral
    /// refraction, positive where the periphery is more hyperopic than the pole.
    pub relative_d: f64,
}

/// The columns of peripheral.csv.
pub const PERIPHERAL_COLUMNS: [&str; 4] = ["t", "field_deg", "refraction_D", "relative_D"];

/// The state of the eye at one output time.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub t: f64,
    pub fields: Vec<crate::bvp::FieldRow>,
    pub growth: Vec<GrowthRow>,
    pub series: SeriesRow,
    /// The peripheral refraction at each field angle (field 0 first).
    pub peripheral: Vec<PeripheralRow>,
    /// The refraction through the lenses worn, one entry per image they form, with each
    /// image's share of the light (none without lenses: [`refraction::through_lenses`]).
    pub through: Vec<refraction::ThroughLenses>,
}

/// Work done by a growth run (summary.json records it: eyeshell's `rundir::record`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GrowthStats {
    pub steps: usize,
    pub rhs_evaluations: usize,
    pub bvp_solves: usize,
    pub newton_iterations: usize,
    pub jacobian_products: usize,
    pub error_test_failures: usize,
    pub nonlinear_iterations: usize,
    pub nonlinear_failures: usize,
    pub linear_iterations: usize,
    /// IDA: residual evaluations of the coupled system, and Newton-matrix evaluations
    /// (assembly and factorisation).
    pub residual_evaluations: usize,
    pub jacobian_evaluations: usize,
    /// IDA with a Schur linear solver: Newton matrices whose growth block was too close to
    /// singular to eliminate unpivoted, factored by the pivoting fallback instead.
    pub linear_fallbacks: usize,
    /// IDA with forward sensitivities: their work (absent without).
    pub sensitivities: Option<SensitivityWork>,
    pub t_reached: f64,
    pub wall_seconds: f64,
    /// With `solver.tol`: what was chosen ([`tolerance`]; absent otherwise).
    pub accuracy: Option<tolerance::Accuracy>,
    /// With `solver.tol`: the estimated error of the outputs (absent otherwise).
    pub error_estimate: Option<tolerance::ErrorEstimate>,
}

/// The forward sensitivities' share of a growth run's work (summary.json), IDAS's counters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensitivityWork {
    /// The scene keys, in the order of sensitivities.csv.
    pub parameters: Vec<String>,
    /// Whether they took part in the local error test.
    pub error_control: bool,
    /// Sensitivity residual evaluations (each for every parameter at once).
    pub residual_evaluations: usize,
    pub nonlinear_iterations: usize,
    pub nonlinear_failures: usize,
    pub error_test_failures: usize,
    pub linear_setups: usize,
    /// Assemblies of F_y for the sensitivity residual (one per state it is evaluated at:
    /// IDAS's staggered corrector evaluates it at each step's converged state), and the
    /// seconds the sensitivity residual spent assembling F_y, forming ∂F/∂p and the
    /// products F_y s (docs/MODEL.md §5; the linear solves are the state's, counted there).
    pub jacobian_assemblies: usize,
    pub jacobian_seconds: f64,
    pub parameter_seconds: f64,
    pub product_seconds: f64,
}

/// One row of sensitivities.csv: how the eye at time `t` moves with one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensitivityRow {
    pub t: f64,
    /// The scene key.
    pub parameter: &'static str,
    /// Its value in the run.
    pub value: f64,
    /// The axial length itself (for the scaled sensitivity).
    pub axial_length: f64,
    /// d(axial length)/dp, d(equatorial radius)/dp, d(retina − blue)/dp, per unit of p.
    pub d_axial_length: f64,
    pub d_equatorial_radius: f64,
    pub d_retina_minus_blue: f64,
}

impl SensitivityRow {
    /// (p/L) dL/dp: the relative change of the axial length per relative change of p.
    pub fn scaled_axial_length(&self) -> f64 {
        self.value / self.axial_length * self.d_axial_length
    }
}

/// Why an observer (or an output callback) stopped a run: any error of the caller's, a full
/// disk or a closed pipe. The growth layer only reports it, as the reason of a [`GrowthError`]
/// at the time it happened, so it needs to know nothing of the layers above it.
pub type ObserverError = Box<dyn std::error::Error + Send + Sync>;

/// Receives the results as they come, so that nothing is lost if the run fails later.
pub trait Observer {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError>;
    /// The series row at every recorded time (the snapshot times and the history times)
    /// when `output.history_points` > 0, in time order.
    fn history(&mut self, _row: &SeriesRow) -> Result<(), ObserverError> {
        Ok(())
    }
    /// Called after every step with the time reached (for a progress bar). An error stops
    /// the run there, as a failed snapshot would (a caller's Ctrl-C, a cancelled job).
    fn progress(&mut self, _t: f64, _t_end: f64) -> Result<(), ObserverError> {
        Ok(())
    }
    /// With `GrowthSettings::sensitivities`: one row per parameter at every recorded time
    /// (t = 0, the output and history times), in time order (after t = 0's snapshot, before
    /// each later time's snapshot or history row).
    fn sensitivities(&mut self, _rows: &[SensitivityRow]) -> Result<(), ObserverError> {
        Ok(())
    }
}

/// No observer: `scene.grow(&mut ())`.
impl Observer for () {
    fn snapshot(&mut self, _s: &Snapshot) -> Result<(), ObserverError> {
        Ok(())
    }
}

/// The largest growth rate at t = 0 the integrators can follow, weighted as their error
/// test weighs it: |∂p/∂t| / (solver.rtol·|p| + solver.atol), per unit time. Their error
/// norms and step selection square it and multiply it by steps: measured on the const
/// scene (N = 21), a weighted rate of 4e124 (growth.eta0 = 1e120) still integrated, 4e154
/// (growth.eta0 = 1e150) overflowed IDA's norms at the first step ("tstop is behind t").
pub const MAX_WEIGHTED_RATE: f64 = 1e100;

/// Refuse growth rates at t = 0 (`rates`, of the growth state `p`) that the integrators
/// cannot follow ([`MAX_WEIGHTED_RATE`]), in the scene's keys.
fn check_rates(
    p: &[f64],
    rates: &[f64],
    settings: &GrowthSettings,
    growth: &GrowthParams,
) -> Result<(), String> {
    let weighted = p
        .iter()
        .zip(rates)
        .map(|(x, r)| r.abs() / (settings.rtol * x.abs() + settings.atol))
        .fold(
            0.0_f64,
            |m, w| if w.is_nan() { f64::INFINITY } else { m.max(w) },
        );
    if weighted <= MAX_WEIGHTED_RATE {
        return Ok(());
    }
    Err(format!(
        "the growth rates at t = 0 are too fast for the integrators: |∂p/∂t| / ({rtol}·|p| + {atol}) reaches {} per unit time, above {} (their error norms square it); the rates grow with {} = {} ({rtol} = {}, {atol} = {})",
        crate::text::decimals6(weighted),
        crate::text::number(MAX_WEIGHTED_RATE),
        Quantity::GrowthRate,
        crate::text::number(growth.eta0),
        crate::text::number(settings.rtol),
        crate::text::number(settings.atol),
        rtol = Quantity::RelativeTolerance,
        atol = Quantity::AbsoluteTolerance,
    ))
}

/// The tolerances and end of a growth run, for [`integrator_words`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct RunTerms {
    pub rtol: f64,
    pub atol: f64,
    pub t_end: f64,
}

impl RunTerms {
    pub(crate) fn of(settings: &GrowthSettings, t_end: f64) -> RunTerms {
        RunTerms {
            rtol: settings.rtol,
            atol: settings.atol,
            t_end,
        }
    }
}

/// A SUNDIALS failure of a growth run in eyeshell's words: what the integrator could not
/// do, with the step it had come down to and the quantities that set its tolerances,
/// numbers short; the call and flag follow in parentheses. Every SUNDIALS error of a
/// growth run (IDA's and CVODE's) is reported through this one translation. `h` is the
/// last step tried (0 before any).
pub(crate) fn integrator_words(
    e: &eyeshell_sundials::SundialsError,
    h: f64,
    run: RunTerms,
) -> String {
    use crate::text::{decimals6, number};
    use eyeshell_sundials::SundialsError;
    let SundialsError::Flag {
        function,
        name,
        message,
        ..
    } = e
    else {
        return match e {
            // Our own callbacks' words (the elastic solve, the deadline, an observer).
            SundialsError::Callback(m) => m.clone(),
            other => format!("the integrator could not be set up: {other}"),
        };
    };
    // The last error our callbacks reported inside the failed call: eyeshell's own words
    // for why an evaluation failed.
    let ours = message
        .split_once(eyeshell_sundials::RECOVERABLE_NOTE)
        .map(|(_, why)| format!("; the last evaluation that failed: {why}"))
        .unwrap_or_default();
    let kind = name.trim_start_matches("IDA_").trim_start_matches("CV_");
    let tolerances = format!(
        "{} = {}, {} = {}",
        Quantity::RelativeTolerance,
        number(run.rtol),
        Quantity::AbsoluteTolerance,
        number(run.atol)
    );
    let step = if h != 0.0 {
        format!(" (last step {})", decimals6(h))
    } else {
        String::new()
    };
    let what = match kind {
        "TOO_MUCH_WORK" => format!(
            "the integrator took the most steps it may without reaching {} = {}{step}: the growth is too stiff for its steps at {tolerances}",
            Quantity::EndTime,
            number(run.t_end)
        ),
        "TOO_MUCH_ACC" => format!(
            "{tolerances} ask for more accuracy than double precision gives here{step}"
        ),
        "ERR_FAIL" | "ERR_FAILURE" => format!(
            "the error test failed repeatedly{step}: the solution changes faster than the integrator can follow at {tolerances}{ours}"
        ),
        "CONV_FAIL" | "CONV_FAILURE" | "NLS_FAIL" | "LINESEARCH_FAIL" | "NO_RECOVERY" => {
            format!("the Newton iteration of a step failed repeatedly{step}{ours}")
        }
        "LINIT_FAIL" | "LSETUP_FAIL" | "LSOLVE_FAIL" | "NLS_SETUP_FAIL" | "NLS_INIT_FAIL" => {
            format!("the Newton matrix could not be factored or solved{step}{ours}")
        }
        "RES_FAIL" | "REP_RES_ERR" | "FIRST_RES_FAIL" | "SRES_FAIL" | "REP_SRES_ERR"
        | "RHSFUNC_FAIL" | "FIRST_RHSFUNC_ERR" | "REPTD_RHSFUNC_ERR" | "UNREC_RHSFUNC_ERR" => {
            format!("the equations could not be evaluated{step}{ours}")
        }
        "ILL_INPUT" | "TOO_CLOSE" | "BAD_T" => format!(
            "the integrator cannot step from here{step}: the times or the rates of the run lie beyond what double precision resolves ({} = {}, {tolerances})",
            Quantity::EndTime,
            number(run.t_end)
        ),
        "MEM_FAIL" => "out of memory".into(),
        _ => format!("the integrator failed{step}{ours}"),
    };
    format!("{what} ({function}: {name})")
}

/// A growth run that stopped: where, why, and the work done until then.
#[derive(Debug, thiserror::Error)]
#[error("growth failed at t = {}: {reason}", crate::text::decimals6(*t))]
pub struct GrowthError {
    pub t: f64,
    pub reason: String,
    /// The work done up to the failure (boxed: the error travels, the counters rarely).
    pub stats: Box<GrowthStats>,
}

/// Run the growth `problem` from t = 0 to t_end, handing each snapshot (t = 0, each
/// output time, t_end) to `observer` as soon as it is computed.
///
/// # Errors
/// A [`GrowthError`] (the time reached, why, the work done) when the run stops: a failed
/// integration or elastic solve, rates too fast to follow, the observer's own error.
pub fn grow(
    problem: &GrowthProblem,
    observer: &mut dyn Observer,
) -> Result<GrowthStats, GrowthError> {
    // Both the snapshots and the progress reports go to the one observer.
    let observer = std::cell::RefCell::new(observer);
    let (settings, t_end) = (problem.settings(), problem.growth().t_end);
    let snapshot_times = snapshot_times(settings, t_end);
    let with_history = settings.history_points > 0;
    run_with(
        problem,
        &mut |rows| observer.borrow_mut().sensitivities(rows),
        &mut |sys, t, p| {
            let mut obs = observer.borrow_mut();
            if t == 0.0 || snapshot_times.contains(&t) {
                let snap = sys.snapshot(t, p)?;
                if with_history {
                    obs.history(&snap.series)?;
                }
                obs.snapshot(&snap)?;
            } else if with_history {
                // A history point needs the series row only, not every field.
                obs.history(&sys.series(t, p)?)?;
            }
            Ok(())
        },
        &mut |t| observer.borrow_mut().progress(t, t_end),
    )
}

/// The snapshot times after t = 0: the output times before t_end, then t_end.
fn snapshot_times(settings: &GrowthSettings, t_end: f64) -> Vec<f64> {
    let mut times: Vec<f64> = settings
        .output_times
        .iter()
        .copied()
        .filter(|&t| t > 0.0 && t < t_end)
        .collect();
    times.push(t_end);
    times
}

/// Every time after t = 0 at which [`run`] calls its output: the snapshot times and the
/// history times t_end·k/n, merged in order (times closer than 1e-12·t_end are one).
pub(crate) fn recorded_times(settings: &GrowthSettings, t_end: f64) -> Vec<f64> {
    let n = settings.history_points;
    let mut times = snapshot_times(settings, t_end);
    times.extend((1..n).map(|k| t_end * k as f64 / n as f64));
    times.sort_by(f64::total_cmp);
    times.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * t_end);
    times
}

/// What hears of the time reached after every step: `progress(t)`; an error stops the run.
pub type ProgressFn<'a> = dyn FnMut(f64) -> Result<(), ObserverError> + 'a;

/// What receives the growth state at each output time: `output(sys, t, p)`.
pub type OutputFn<'a> =
    dyn FnMut(&mut system::GrowthSystem, f64, &[f64]) -> Result<(), ObserverError> + 'a;

/// The growth run behind [`grow`], for callers that want the system itself at each output
/// time (t = 0, the output times, t_end): `output(sys, t, p)` with p the growth state.
/// With `solver.tol` the mesh and the integrator's tolerances are chosen for it, and the
/// outputs are those of the delivered run, with their estimated error ([`tolerance`]).
///
/// # Errors
/// As [`grow`]'s, `output`'s and `progress`'s errors among them.
pub fn run(
    problem: &GrowthProblem,
    output: &mut OutputFn<'_>,
    progress: &mut ProgressFn<'_>,
) -> Result<GrowthStats, GrowthError> {
    run_with(problem, &mut |_| Ok(()), output, progress)
}

/// What receives the sensitivity rows of one recorded time.
pub type SensitivityFn<'a> = dyn FnMut(&[SensitivityRow]) -> Result<(), ObserverError> + 'a;

/// [`run`] with the forward sensitivities of the problem's settings handed to `sens`.
///
/// # Errors
/// As [`run`]'s, `sens`'s errors among them.
pub fn run_with(
    problem: &GrowthProblem,
    sens: &mut SensitivityFn<'_>,
    output: &mut OutputFn<'_>,
    progress: &mut ProgressFn<'_>,
) -> Result<GrowthStats, GrowthError> {
    let parts = Parts::of(problem);
    let hooks = Hooks {
        sens,
        output,
        progress,
    };
    let outside = parts.settings.sensitivities.iter().any(|p| !p.in_dae());
    if parts.growth.schedule.is_constant() && !outside {
        return run_plain(parts, hooks);
    }
    schedule::run(parts, hooks)
}

/// The pieces of a [`GrowthProblem`] as the run's stages hand them on: a schedule runs the
/// model on its own clock (other growth parameters and output times), `solver.tol` starts
/// the solver's clock and chooses the mesh, each a variation of the checked problem.
#[derive(Clone, Copy)]
pub(crate) struct Parts<'a> {
    pub params: &'a crate::model::params::Params,
    pub solver: &'a crate::bvp::settings::SolverSettings,
    pub growth: &'a GrowthParams,
    pub settings: &'a GrowthSettings,
    /// On a schedule's clock with optics that change with age: the real time of each clock
    /// time, which the growth system reads its surfaces at ([`real_time`]).
    pub real_time: Option<&'a real_time::RealTime>,
}

impl<'a> Parts<'a> {
    fn of(problem: &'a GrowthProblem) -> Parts<'a> {
        Parts {
            params: problem.params(),
            solver: problem.solver(),
            growth: problem.growth(),
            settings: problem.settings(),
            real_time: None,
        }
    }
}

/// What a growth run hands its results to as they come: the sensitivity rows of each
/// recorded time, the growth state at each recorded time, the time reached after each step.
pub(crate) struct Hooks<'h, 'f> {
    pub sens: &'h mut SensitivityFn<'f>,
    pub output: &'h mut OutputFn<'f>,
    pub progress: &'h mut ProgressFn<'f>,
}

/// The stretch of time an integrator covers: from t = 0 to `t_end`, handing on the state at
/// `times` (increasing, in (0, t_end]), with the tolerances and steps of `settings`.
pub(crate) struct Span<'a> {
    pub t_end: f64,
    pub times: &'a [f64],
    pub settings: &'a GrowthSettings,
}

/// [`run_with`] on the model's own clock, every sensitivity from the DAE.
pub(crate) fn run_plain(
    parts: Parts<'_>,
    hooks: Hooks<'_, '_>,
) -> Result<GrowthStats, GrowthError> {
    let Parts { solver, growth, .. } = parts;
    // The stimulus's surfaces, when computed from the eye's optics, are traced once here,
    // before t = 0, and shared by the mesh choice and the run.
    let growth = &*growth.resolved().map_err(|e| GrowthError {
        t: 0.0,
        reason: e.to_string(),
        stats: Box::default(),
    })?;
    let parts = Parts { growth, ..parts };
    let Some(_) = solver.tol else {
        return run_on(parts, None, hooks);
    };
    // solver.max_seconds bounds every run of the choice together: one clock for all.
    let solver = &solver.clock_started();
    tolerance::run(Parts { solver, ..parts }, hooks)
}

/// The growth run on `mesh` (None: the mesh of `solver.nodes`).
pub(crate) fn run_on(
    parts: Parts<'_>,
    mesh: Option<crate::mesh::Mesh>,
    hooks: Hooks<'_, '_>,
) -> Result<GrowthStats, GrowthError> {
    let Parts {
        params,
        solver,
        growth,
        settings,
        real_time,
    } = parts;
    let Hooks {
        sens,
        output,
        progress,
    } = hooks;
    let start = std::time::Instant::now();
    let t_end = growth.t_end;
    let fail = |t: f64, reason: String, stats: GrowthStats| GrowthError {
        t,
        reason,
        stats: Box::new(stats),
    };
    if let Some(why) = settings
        .sensitivities
        .iter()
        .find_map(|s| s.check(params).err())
    {
        return Err(fail(0.0, why.to_string(), GrowthStats::default()));
    }
    if let Some(why) = settings
        .sensitivities
        .iter()
        .find_map(|&p| sensitivity_unavailable(p, growth))
    {
        return Err(fail(0.0, why, GrowthStats::default()));
    }
    if !settings.sensitivities.is_empty() && settings.integrator != Integrator::Ida {
        return Err(fail(
            0.0,
            format!(
                "sensitivities need {} = \"ida\" (the scene has \"{}\")",
                Quantity::Integrator,
                settings.integrator.name()
            ),
            GrowthStats::default(),
        ));
    }
    let sys = match mesh {
        None => system::GrowthSystem::new(params, solver, growth),
        Some(mesh) => system::GrowthSystem::on_mesh(params, solver, growth, mesh),
    };
    let mut sys = sys
        .and_then(|mut sys| sys.set_real_time(real_time.cloned()).map(|_| sys))
        .map_err(|e| fail(0.0, e.to_string(), GrowthStats::default()))?;
    let p0 = sys.points.initial_state();
    if settings.integrator != Integrator::Ida {
        // IDA checks the rates of its consistent start (`run_ida`), which it computes anyway.
        let mut rates = vec![0.0; p0.len()];
        sys.rhs(&p0, &mut rates)
            .map_err(|e| e.to_string())
            .and_then(|_| check_rates(&p0, &rates, settings, growth))
            .map_err(|why| fail(0.0, why, GrowthStats::default()))?;
    }
    let times = recorded_times(settings, t_end);
    output(&mut sys, 0.0, &p0).map_err(|e| fail(0.0, e.to_string(), GrowthStats::default()))?;
    let mut stats = GrowthStats::default();
    let span = Span {
        t_end,
        times: &times,
        settings,
    };
    let outcome = match settings.integrator {
        Integrator::Euler => {
            let r = euler::integrate(&mut sys, &p0, &span, output, progress);
            stats.steps = settings.steps;
            stats.rhs_evaluations = sys.work.rhs_evaluations;
            r.map(|_| ()).map_err(|(t, e)| (t, e.to_string()))
        }
        Integrator::Cvode => {
            let (cv, r) = cvode::integrate(&mut sys, &p0, &span, output, progress);
            stats.steps = cv.steps;
            stats.rhs_evaluations = cv.rhs_evaluations;
            stats.error_test_failures = cv.error_test_failures;
            stats.nonlinear_iterations = cv.nonlinear_iterations;
            stats.nonlinear_failures = cv.nonlinear_convergence_failures;
            stats.linear_iterations = cv.linear_iterations;
            stats.t_reached = cv.current_time;
            r
        }
        Integrator::Ida => {
            let hooks = Hooks {
                sens,
                output,
                progress,
            };
            let (back, r) = run_ida(sys, &span, hooks, &mut stats);
            sys = back;
            r
        }
    };
    stats.bvp_solves = sys.work.bvp_solves;
    stats.newton_iterations = sys.elastic.newton_iterations();
    stats.jacobian_products = sys.work.jacobian_products;
    stats.wall_seconds = start.elapsed().as_secs_f64();
    match outcome {
        Ok(()) => {
            stats.t_reached = t_end;
            Ok(stats)
        }
        Err((t, reason)) => {
            stats.t_reached = t;
            Err(fail(t, reason, stats))
        }
    }
}

/// The IDA branch of [`run`]: the coupled system built on `sys` (solved at t = 0), its
/// consistent start, and the integration; outputs hand the interpolated state to the growth
/// system (no re-solve). Returns the growth system for the caller's counters.
fn run_ida(
    sys: system::GrowthSystem,
    span: &Span<'_>,
    hooks: Hooks<'_, '_>,
    stats: &mut GrowthStats,
) -> (system::GrowthSystem, Result<(), (f64, String)>) {
    let settings = span.settings;
    let Hooks {
        sens,
        output,
        progress,
    } = hooks;
    let mut dae = dae::CoupledDae::new(sys);
    dae.set_sensitivities(&settings.sensitivities);
    let start = dae
        .set_linear(settings.dae_linear)
        .and_then(|_| dae.initial_state())
        .and_then(|y| dae.derivative(&y).map(|yp| (y, yp)));
    // Rates the integrator cannot follow are refused before anything else is computed
    // from them.
    if let Ok((y, yp)) = &start {
        let n_p = dae.differential_len();
        let growth = dae.sys.growth_params().clone();
        if let Err(why) = check_rates(&y[..n_p], &yp[..n_p], settings, &growth) {
            return (dae.sys, Err((0.0, why)));
        }
    }
    let start = start.and_then(|(y, yp)| {
        let s = match settings.sensitivities.is_empty() {
            true => (vec![], vec![]),
            false => dae.initial_sensitivities(&y, &yp)?,
        };
        Ok((y, yp, s))
    });
    let result = match start {
        Err(e) => Err((
            0.0,
            format!("the consistent start of the coupled system: {e}"),
        )),
        Ok((y0, yp0, (s0, sp0))) => {
            let n_p = dae.differential_len();
            let mut out = |dae: &mut dae::CoupledDae, t: f64, y: &[f64]| {
                dae.adopt(y);
                output(&mut dae.sys, t, &y[..n_p])
            };
            let mut sens_out = |dae: &mut dae::CoupledDae, t: f64, y: &[f64], s: &[Vec<f64>]| {
                let rows = sensitivity_rows(dae, t, y, s)?;
                sens(&rows)
            };
            let mut sensitivities = None;
            if !sp0.is_empty() {
                // The rows at t = 0: zero for η0, Γ, δ; the t = 0 equilibrium's for the rest.
                if let Err(e) = sens_out(&mut dae, 0.0, &y0, &s0) {
                    return (dae.sys, Err((0.0, e.to_string())));
                }
                let (p, g) = (dae.sys.elastic.params(), dae.sys.growth_params().clone());
                sensitivities = Some(ida::Sensitivities {
                    scales: settings
                        .sensitivities
                        .iter()
                        .map(|s| s.scale(&p, &g))
                        .collect(),
                    ys0: s0,
                    yps0: sp0,
                    error_control: settings.sensitivity_error_control,
                    output: &mut sens_out,
                });
            }
            let start = ida::ConsistentStart { y: &y0, yp: &yp0 };
            let (st, sst, r) =
                ida::integrate(&mut dae, start, span, &mut out, progress, sensitivities);
            if !settings.sensitivities.is_empty() {
                stats.sensitivities = Some(SensitivityWork {
                    parameters: settings
                        .sensitivities
                        .iter()
                        .map(|p| p.key().to_string())
                        .collect(),
                    error_control: settings.sensitivity_error_control,
                    residual_evaluations: sst.residual_evaluations,
                    nonlinear_iterations: sst.nonlinear_iterations,
                    nonlinear_failures: sst.nonlinear_convergence_failures,
                    error_test_failures: sst.error_test_failures,
                    linear_setups: sst.linear_setups,
                    jacobian_assemblies: dae.counters.sensitivity_jacobians,
                    jacobian_seconds: dae.counters.sensitivity_jacobian_seconds,
                    parameter_seconds: dae.counters.sensitivity_parameter_seconds,
                    product_seconds: dae.counters.sensitivity_product_seconds,
                });
            }
            stats.steps = st.steps;
            stats.residual_evaluations = st.residual_evaluations;
            stats.jacobian_evaluations = st.jacobian_evaluations;
            stats.error_test_failures = st.error_test_failures;
            stats.nonlinear_iterations = st.nonlinear_iterations;
            stats.nonlinear_failures = st.nonlinear_convergence_failures;
            stats.t_reached = st.current_time;
            stats.linear_fallbacks = dae.counters.fallbacks;
            r
        }
    };
    (dae.sys, result)
}

/// The measured eye's derivatives along each sensitivity s_j = ∂y/∂p_j at the state y:
/// the measurement (retina, stimulus, largest radius) is a function of y and of the
/// parameters it reads itself (C and D through α_s in the retina's loaded thickness, ΔP
/// through the cornea's z* that z is integrated from, z_B through the blue surface), and
/// its total derivative is taken as a central difference
/// M(y ± ε s_j, p_j ± ε) — the one place a directional difference stands in for an
/// analytic derivative (the measurement reads the retina through the stimulus code, which
/// has no derivative). ε moves y by at most 1e-6 of its largest entry and p_j by at most
/// 1e-6 of max(|p_j|, 1): truncation (ε²) and round-off (u/ε) both stay below 1e-9 relative.
fn sensitivity_rows(
    dae: &mut dae::CoupledDae,
    t: f64,
    y: &[f64],
    s: &[Vec<f64>],
) -> Result<Vec<SensitivityRow>, String> {
    let n_p = dae.differential_len();
    let measure = |dae: &mut dae::CoupledDae, y: &[f64]| -> Result<SeriesRow, String> {
        dae.adopt(y);
        dae.sys.series(t, &y[..n_p]).map_err(|e| e.to_string())
    };
    let at = measure(dae, y)?;
    let (p, g) = (dae.sys.elastic.params(), dae.sys.growth_params().clone());
    let y_max = y.iter().fold(1.0_f64, |a, v| a.max(v.abs()));
    let mut rows = Vec::with_capacity(s.len());
    for (sj, &param) in s.iter().zip(dae.sensitivity_params().to_vec().iter()) {
        let value = param.value(&p, &g);
        let reads = dae.measurement_reads(param);
        let s_max = sj.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        let mut eps = if s_max > 0.0 {
            1e-6 * y_max / s_max
        } else {
            f64::INFINITY
        };
        if reads {
            eps = eps.min(1e-6 * value.abs().max(1.0));
        }
        let mut d = [0.0; 3];
        if eps.is_finite() {
            let shifted = |dae: &mut dae::CoupledDae, sign: f64| -> Result<SeriesRow, String> {
                let ys: Vec<f64> = y.iter().zip(sj).map(|(a, b)| a + sign * eps * b).collect();
                dae.set_measured_parameter(param, value + sign * eps);
                let m = measure(dae, &ys);
                dae.set_measured_parameter(param, value);
                m
            };
            let plus = shifted(dae, 1.0)?;
            let minus = shifted(dae, -1.0)?;
            let diff = |f: fn(&SeriesRow) -> f64| (f(&plus) - f(&minus)) / (2.0 * eps);
            d = [
                diff(|r| r.axial_length),
                diff(|r| r.equatorial_radius),
                diff(|r| r.retina_minus_blue),
            ];
        }
        rows.push(SensitivityRow {
            t,
            parameter: param.key(),
            value,
            axial_length: at.axial_length,
            d_axial_length: d[0],
            d_equatorial_radius: d[1],
            d_retina_minus_blue: d[2],
        });
    }
    dae.adopt(y);
    Ok(rows)
}

/// A time integrator as [`march`] drives it: one internal step at a time, its interpolant
/// inside the last step, and where the state at an output time goes.
trait Stepper {
    /// One step towards `t_end`; `y` gets the state reached. On failure: (time reached, why).
    fn step(&mut self, t_end: f64, y: &mut [f64]) -> Result<f64, (f64, String)>;
    /// The state at `t` inside the last step.
    fn interpolate(&self, t: f64, y: &mut [f64]) -> Result<(), String>;
    /// Hand the state at output time `t` on.
    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), String>;
}

/// Step to `t_end`, handing on the state at each of `times` (increasing, in (0, t_end]) from
/// the step that contains it, and calling `progress(t)` after every step.
fn march(
    s: &mut dyn Stepper,
    n: usize,
    t_end: f64,
    times: &[f64],
    progress: &mut ProgressFn<'_>,
) -> Result<(), (f64, String)> {
    let (mut y, mut yo) = (vec![0.0; n], vec![0.0; n]);
    let mut next = times.iter().peekable();
    let mut t = 0.0;
    while t < t_end {
        t = s.step(t_end, &mut y)?;
        progress(t).map_err(|e| (t, e.to_string()))?;
        while let Some(&&tout) = next.peek() {
            if tout > t {
                break;
            }
            if tout == t {
                yo.copy_from_slice(&y);
            } else {
                s.interpolate(tout, &mut yo).map_err(|e| (t, e))?;
            }
            s.output(tout, &yo).map_err(|e| (tout, e))?;
            next.next();
        }
    }
    Ok(())
}

/// Why a run of `growth` cannot take the sensitivity to `param`, in the model's words:
/// the blue surface's centre z_B of a surface computed from the optics (traced about its
/// centre once), or under a rule that reads defocus in dioptres from the cornea, which
/// moving z_B does not move; or a schedule's parameter beside optics that change with age
/// (its closed-form sensitivity needs a clock nothing else reads). Callers check it before a
/// run (the fit's keys, `grow --sensitivities`); a run checks it again at t = 0.
pub fn sensitivity_unavailable(param: dae::SensParam, growth: &GrowthParams) -> Option<String> {
    if let Some(sp) = param.schedule_param() {
        // ∂S/∂θ carries over to L only on an autonomous clock ([`schedule`]): optics that
        // read t make the run on S(t) depend on θ through t = S⁻¹(τ) as well.
        return growth.optics_change().then(|| {
            format!(
                "the sensitivity to {} needs optics that do not change with age ({} has tables over time): the schedule's closed form holds only while nothing but the schedule reads t; those to {} and {} stay exact",
                sp.quantity(),
                Quantity::Surfaces,
                Quantity::GrowthRate,
                Quantity::Radius
            )
        });
    }
    if param != dae::SensParam::BlueCentre {
        return None;
    }
    if growth.source == Source::Optics {
        return Some(format!(
            "the sensitivity to {} needs {} = \"polynomial\" (a computed surface is traced about its centre once)",
            Quantity::BlueCentre,
            Quantity::StimulusSource
        ));
    }
    if growth.stimulus.rule().reads().defocus {
        // Moving z_B moves the surfaces and not the cornea the dioptres are measured from:
        // the shift is no longer the retina's moving the other way.
        return Some(format!(
            "the sensitivity to the blue surface's centre z_B needs a growth rule that reads the surfaces alone (the {} rule reads defocus in dioptres from the cornea)",
            growth.stimulus.rule().name()
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use eyeshell_sundials::{SundialsError, RECOVERABLE_NOTE};

    fn flag(name: &'static str, message: &str) -> SundialsError {
        SundialsError::Flag {
            function: "IDASolve (one step)",
            flag: -3,
            name,
            message: message.into(),
        }
    }

    /// SUNDIALS' failures in eyeshell's words: what could not be done, the step, the
    /// tolerances by name (core's own: no front end gave its words in this binary), short numbers, our callbacks' own reason; the call and the
    /// flag only in parentheses at the end, SUNDIALS' own text not at all.
    #[test]
    fn integrator_failures_speak_the_scenes_terms() {
        let run = RunTerms {
            rtol: 1e-10,
            atol: 1e-250,
            t_end: 1.0,
        };
        let sundials = "IDASolve: At t = 0 and h = 3.5e-13, the error test failed repeatedly";
        let words = integrator_words(&flag("IDA_ERR_FAIL", sundials), 3.5e-13, run);
        assert_eq!(
            words,
            "the error test failed repeatedly (last step 3.500000e-13): the solution changes \
             faster than the integrator can follow at rtol = 1e-10, atol = 1e-250 (IDASolve \
             (one step): IDA_ERR_FAIL)"
        );
        let with_ours = format!("{sundials}{RECOVERABLE_NOTE}the elastic solve failed at node 3");
        let words = integrator_words(&flag("IDA_CONV_FAIL", &with_ours), 0.0, run);
        assert_eq!(
            words,
            "the Newton iteration of a step failed repeatedly; the last evaluation that failed: \
             the elastic solve failed at node 3 (IDASolve (one step): IDA_CONV_FAIL)"
        );
        for name in [
            "IDA_TOO_MUCH_WORK",
            "CV_TOO_MUCH_ACC",
            "IDA_ILL_INPUT",
            "CV_RHSFUNC_FAIL",
        ] {
            let words = integrator_words(&flag(name, sundials), 1e-300, run);
            assert!(
                words.ends_with(&format!("(IDASolve (one step): {name})")),
                "{words}"
            );
            assert!(!words.contains("At t ="), "{words}");
            assert!(words.len() < 300, "{words}");
        }
        let callback = SundialsError::Callback("out of time: solver.max_seconds = 1".into());
        assert_eq!(
            integrator_words(&callback, 0.0, run),
            "out of time: solver.max_seconds = 1"
        );
    }
}
