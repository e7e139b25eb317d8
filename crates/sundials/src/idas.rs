//! Forward sensitivity analysis of a DAE through IDAS (the library IDA links is IDAS, a
//! superset of IDA with the same function names): s_j = ∂y/∂p_j satisfies
//! F_y s_j + F_y' s_j' + ∂F/∂p_j = 0, integrated beside y by the same BDF formulas.
//!
//! The staggered corrector (IDA_STAGGERED) solves the state's Newton system first, then all
//! sensitivities with the same Newton matrix (the system's [`DaeSystem::linear_solve`] for
//! the custom solver): the sensitivity systems are linear, so they cost back-substitutions,
//! not factorisations. The sensitivity residual is the system's own
//! ([`DaeSystem::sensitivity_residual`]), never IDAS's difference quotients.
//!
//! Tolerances: IDASensEEtolerances, i.e. the state's, with the absolute ones divided by the
//! scale |p̄_j| of each parameter (IDASetSensParams with pbar only), so that s_j is controlled
//! as an error on p̄_j s_j, in the units of y. Error control on the sensitivities
//! (IDASetSensErrCon) is an option: without it the sensitivities follow the state's steps and
//! are only made to converge.

use std::os::raw::{c_int, c_void};

use sundials_sys::{
    realtype, IDAGetNumResEvalsSens, IDAGetSensDky, IDAGetSensNumErrTestFails,
    IDAGetSensNumLinSolvSetups, IDAGetSensNumNonlinSolvConvFails, IDAGetSensNumNonlinSolvIters,
    IDAGetSensNumResEvals, IDASensEEtolerances, IDASensInit, IDASetSensErrCon, IDASetSensParams,
    N_Vector, IDA_STAGGERED,
};

use super::callback::counter;
use super::error::{flag_error, FlagFamily, SundialsError};
use super::ida::{DaeSystem, Ida};
use super::integrator::{invalid, to_int, Shared};
use super::nvector::{self, NVector};

/// How IDAS integrates the sensitivities.
#[derive(Clone, Debug, PartialEq)]
pub struct SensitivityOptions {
    /// Include the sensitivities in the local error test (IDASetSensErrCon).
    pub error_control: bool,
    /// The scale |p̄_j| of each parameter (its value, typically); > 0 and finite.
    pub scales: Vec<f64>,
}

/// IDAS's sensitivity counters (cumulative).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IdaSensStats {
    /// Calls of [`DaeSystem::sensitivity_residual`] (IDAGetSensNumResEvals; each for every
    /// parameter at once).
    pub residual_evaluations: usize,
    /// State residuals IDAS spent on the sensitivities (IDAGetNumResEvalsSens: 0 with the
    /// system's own sensitivity residual).
    pub state_residual_evaluations: usize,
    pub error_test_failures: usize,
    pub linear_setups: usize,
    pub nonlinear_iterations: usize,
    pub nonlinear_convergence_failures: usize,
}

impl<S: DaeSystem> Ida<S> {
    /// Start the forward sensitivities of `ys0.len()` parameters from s(t0) = ys0,
    /// s'(t0) = yps0 (consistent: F_y s + F_y' s' + F_p = 0 at t0). Before the first step.
    pub fn init_sensitivities(
        &mut self,
        ys0: &[Vec<f64>],
        yps0: &[Vec<f64>],
        options: &SensitivityOptions,
    ) -> Result<(), SundialsError> {
        let (n, ns) = (self.n(), ys0.len());
        if ns == 0 || yps0.len() != ns || options.scales.len() != ns {
            return invalid(format!(
                "sensitivities: {ns} initial values, {} derivatives and {} scales (need the same number, ≥ 1)",
                yps0.len(),
                options.scales.len()
            ));
        }
        if self.n_sens > 0 {
            return invalid("sensitivities are already initialised".into());
        }
        if let Some(v) = ys0.iter().chain(yps0).find(|v| v.len() != n) {
            return invalid(format!(
                "a sensitivity has length {}, expected {n}",
                v.len()
            ));
        }
        if let Some(j) = options
            .scales
            .iter()
            .position(|&p| !(p > 0.0 && p.is_finite()))
        {
            return invalid(format!(
                "sensitivity scale {j} = {} must be positive and finite",
                options.scales[j]
            ));
        }
        if self.stats().steps > 0 {
            return invalid("sensitivities must be initialised before the first step".into());
        }
        let nsi = to_int("the number of sensitivities", ns)?;
        let (mem, log, ctx) = self.parts_mut();
        let (mem, ctx) = (mem.raw(), ctx.clone());
        let ys: Vec<NVector> = ys0
            .iter()
            .map(|v| NVector::from_slice(&ctx, v))
            .collect::<Result<_, _>>()?;
        let yps: Vec<NVector> = yps0
            .iter()
            .map(|v| NVector::from_slice(&ctx, v))
            .collect::<Result<_, _>>()?;
        // IDAS clones its sensitivity work vectors from ys0[0]: with our kernels installed
        // they run the several passes a step makes over each sensitivity at the speed of the
        // state's (fastops.rs; measured: the library's loops were 14% of a k = 3 run).
        // SAFETY: the vectors are live serial vectors owned here, each with its own table.
        for v in ys.iter().chain(&yps) {
            unsafe { super::fastops::install(v.raw()) };
        }
        let mut ys_raw: Vec<N_Vector> = ys.iter().map(|v| v.raw()).collect();
        let mut yps_raw: Vec<N_Vector> = yps.iter().map(|v| v.raw()).collect();
        let mut pbar = options.scales.clone();
        // SAFETY (all calls): mem is live IDAS memory; IDASensInit clones and copies the
        // vectors (which outlive the call); IDASetSensParams copies pbar (p and plist NULL:
        // the residual is ours, so IDAS never perturbs p itself).
        log.call("IDASensInit", FlagFamily::Ida, || unsafe {
            IDASensInit(
                mem,
                nsi,
                IDA_STAGGERED,
                Some(sensitivity_residual_trampoline::<S>),
                ys_raw.as_mut_ptr(),
                yps_raw.as_mut_ptr(),
            )
        })?;
        log.call("IDASetSensParams", FlagFamily::Ida, || unsafe {
            IDASetSensParams(
                mem,
                std::ptr::null_mut(),
                pbar.as_mut_ptr(),
                std::ptr::null_mut(),
            )
        })?;
        log.call("IDASensEEtolerances", FlagFamily::Ida, || unsafe {
            IDASensEEtolerances(mem)
        })?;
        let errcon = c_int::from(options.error_control);
        log.call("IDASetSensErrCon", FlagFamily::Ida, || unsafe {
            IDASetSensErrCon(mem, errcon)
        })?;
        self.n_sens = ns;
        Ok(())
    }

    /// The number of sensitivities (0 before [`init_sensitivities`](Self::init_sensitivities)).
    pub fn sensitivity_count(&self) -> usize {
        self.n_sens
    }

    /// The sensitivities s_j(t) at any t within the last step (IDAGetSensDky, k = 0), into
    /// `out[j]`.
    pub fn sensitivities_at(&self, t: f64, out: &mut [Vec<f64>]) -> Result<(), SundialsError> {
        if self.n_sens == 0 {
            return invalid("no sensitivities were initialised".into());
        }
        if out.len() != self.n_sens || out.iter().any(|v| v.len() != self.n()) {
            return invalid(format!(
                "sensitivity output: {} vectors, expected {} of length {}",
                out.len(),
                self.n_sens,
                self.n()
            ));
        }
        self.check_dense_output_time(t)?;
        let (mem, log, ctx) = self.parts();
        let mem = mem.raw();
        let vs: Vec<NVector> = (0..self.n_sens)
            .map(|_| NVector::new(ctx, self.n()))
            .collect::<Result<_, _>>()?;
        let mut raw: Vec<N_Vector> = vs.iter().map(|v| v.raw()).collect();
        // SAFETY: mem and the vectors are live; IDAGetSensDky copies into them and calls no
        // user callback.
        let flag = unsafe { IDAGetSensDky(mem, t, 0, raw.as_mut_ptr()) };
        if flag != 0 {
            // SAFETY: the call has returned; no reference to the log is alive.
            let message = unsafe { log.get().last_message() };
            return Err(flag_error("IDAGetSensDky", flag, FlagFamily::Ida, message));
        }
        for (o, v) in out.iter_mut().zip(&vs) {
            o.copy_from_slice(v.as_slice());
        }
        Ok(())
    }

    /// IDAS's sensitivity counters so far (zero without sensitivities).
    pub fn sensitivity_stats(&self) -> IdaSensStats {
        if self.n_sens == 0 {
            return IdaSensStats::default();
        }
        let mem = self.parts().0.raw();
        // SAFETY: mem is live IDAS memory with sensitivities, and the getters are IDAS's.
        let count = |f| unsafe { counter(mem, f) };
        IdaSensStats {
            residual_evaluations: count(IDAGetSensNumResEvals),
            state_residual_evaluations: count(IDAGetNumResEvalsSens),
            error_test_failures: count(IDAGetSensNumErrTestFails),
            linear_setups: count(IDAGetSensNumLinSolvSetups),
            nonlinear_iterations: count(IDAGetSensNumNonlinSolvIters),
            nonlinear_convergence_failures: count(IDAGetSensNumNonlinSolvConvFails),
        }
    }
}

/// IDASensResFn: rs_j = F_y ys_j + F_y' yps_j + ∂F/∂p_j for every j.
#[allow(clippy::too_many_arguments)] // IDASensResFn's signature
unsafe extern "C" fn sensitivity_residual_trampoline<S: DaeSystem>(
    ns: c_int,
    t: realtype,
    y: N_Vector,
    yp: N_Vector,
    r: N_Vector,
    ys: *mut N_Vector,
    yps: *mut N_Vector,
    rs: *mut N_Vector,
    data: *mut c_void,
    _tmp1: N_Vector,
    _tmp2: N_Vector,
    _tmp3: N_Vector,
) -> c_int {
    // SAFETY: `data` is the Shared<S> registered with IDASetUserData; IDAS calls us from
    // inside IDASolve, while no other reference to it exists. y, yp, r and the ns vectors of
    // each array are distinct live serial vectors of length n (IDAS's own, never aliased):
    // the inputs only read, the rs only written.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let ns = ns.max(0) as usize;
    let (y, yp, r) = unsafe { (nvector::slice(y), nvector::slice(yp), nvector::slice(r)) };
    let (ys, yps, rs) = unsafe {
        (
            std::slice::from_raw_parts(ys, ns),
            std::slice::from_raw_parts(yps, ns),
            std::slice::from_raw_parts(rs, ns),
        )
    };
    let ys: Vec<&[f64]> = ys.iter().map(|&v| unsafe { nvector::slice(v) }).collect();
    let yps: Vec<&[f64]> = yps.iter().map(|&v| unsafe { nvector::slice(v) }).collect();
    let mut rs: Vec<&mut [f64]> = rs
        .iter()
        .map(|&v| unsafe { nvector::slice_mut(v) })
        .collect();
    shared.guard("sensitivity_residual", |system| {
        system.sensitivity_residual(t, y, yp, r, &ys, &yps, &mut rs)
    })
}
