//! Growth by CVODE (docs/MODEL.md §5): BDF with variable order and step, error-controlled. The
//! Newton iteration inside each step uses GMRES with the implicit-function-theorem
//! Jacobian product of [`GrowthSystem::jac_times`] (one back-substitution per product, no
//! elastic re-solve). An elastic solve that fails inside a step is a recoverable error:
//! CVODE cuts the step and tries again.

use super::system::GrowthSystem;
use crate::text::decimals6;
use eyeshell_sundials::{
    CallbackResult, Cvode, CvodeLinearSolver, CvodeOptions, CvodeStats, OdeSystem,
};

/// The growth system as CVODE sees it.
pub struct GrowthOde<'a> {
    pub sys: &'a mut GrowthSystem,
}

impl OdeSystem for GrowthOde<'_> {
    fn rhs(&mut self, t: f64, y: &[f64], ydot: &mut [f64]) -> CallbackResult {
        self.sys
            .check_deadline(|| format!("in CVODE's right-hand side at t = {}", decimals6(t)))
            .and_then(|_| self.sys.set_time(t))
            .and_then(|_| self.sys.rhs(y, ydot))
            .map_err(|e| e.to_callback())
    }

    fn jac_times_setup(&mut self, _t: f64, y: &[f64], _fy: &[f64]) -> CallbackResult {
        self.sys.jac_setup(y).map_err(|e| e.to_callback())
    }

    fn jac_times(
        &mut self,
        _t: f64,
        y: &[f64],
        fy: &[f64],
        v: &[f64],
        jv: &mut [f64],
    ) -> CallbackResult {
        self.sys
            .jac_times(y, fy, v, jv)
            .map_err(|e| e.to_callback())
    }
}

/// The Krylov subspace of GMRES.
const MAX_KRYLOV: usize = 30;

/// Integrate to `span.t_end`, calling `output(sys, t, p)` at each of `span.times`
/// (increasing, in (0, t_end]) and `progress(t)` after every internal step. Returns CVODE's
/// counters and, on failure, the time reached and why.
pub fn integrate(
    sys: &mut GrowthSystem,
    p0: &[f64],
    span: &super::Span<'_>,
    output: &mut super::OutputFn<'_>,
    progress: &mut super::ProgressFn<'_>,
) -> (CvodeStats, Result<(), (f64, String)>) {
    let (settings, t_end, times) = (span.settings, span.t_end, span.times);
    let options = CvodeOptions {
        rtol: settings.rtol,
        atol: settings.atol,
        stop_time: Some(t_end),
        max_steps: 100_000,
        ..CvodeOptions::default()
    };
    let linear = CvodeLinearSolver::Spgmr {
        max_krylov: MAX_KRYLOV,
        user_product: true,
        preconditioned: false,
    };
    let run = super::RunTerms::of(settings, t_end);
    let mut cv = match Cvode::new(GrowthOde { sys }, 0.0, p0, linear, &options) {
        Ok(cv) => cv,
        Err(e) => {
            let why = super::integrator_words(&e, 0.0, run);
            return (CvodeStats::default(), Err((0.0, why)));
        }
    };
    let result = super::march(
        &mut CvodeStepper {
            cv: &mut cv,
            output,
            run,
        },
        p0.len(),
        t_end,
        times,
        progress,
    );
    (cv.stats(), result)
}

/// CVODE as [`super::march`] drives it.
struct CvodeStepper<'a, 'b, 'c> {
    cv: &'a mut Cvode<GrowthOde<'b>>,
    output: &'a mut super::OutputFn<'c>,
    /// The run's terms, for CVODE's failures.
    run: super::RunTerms,
}

impl super::Stepper for CvodeStepper<'_, '_, '_> {
    fn step(&mut self, t_end: f64, y: &mut [f64]) -> Result<f64, (f64, String)> {
        self.cv.step(t_end, y).map_err(|e| {
            let stats = self.cv.stats();
            // The deadline's own message rather than CVODE's "the right side failed".
            let why = self.cv.system_mut().sys.take_out_of_time();
            let why = why.map_or_else(
                || super::integrator_words(&e, stats.last_step, self.run),
                |o| o.to_string(),
            );
            (stats.current_time, why)
        })
    }

    fn interpolate(&self, t: f64, y: &mut [f64]) -> Result<(), String> {
        self.cv
            .interpolate(t, y)
            .map_err(|e| super::integrator_words(&e, 0.0, self.run))
    }

    fn output(&mut self, t: f64, y: &[f64]) -> Result<(), String> {
        (self.output)(self.cv.system_mut().sys, t, y).map_err(|e| e.to_string())
    }
}
