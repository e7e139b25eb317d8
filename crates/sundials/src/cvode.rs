//! CVODE: variable-order, variable-step BDF for stiff ODEs y' = f(t, y), with Newton's method
//! (CVODE's default nonlinear solver) and either a direct linear solver (dense or band, with
//! the caller's Jacobian or CVODE's difference quotients) or matrix-free GMRES (with the
//! caller's Jacobian-vector product or CVODE's difference quotient, optionally with the
//! caller's left preconditioner).
//!
//! Ownership: [`Cvode`] owns the CVODE memory, the linear solver, the matrix (if any), the
//! vectors and the user's system; its fields are declared in the order they must be freed
//! (CVODE memory → linear solver → matrix → everything else → context), as in
//! [`Kinsol`](super::Kinsol).
//!
//! Callbacks are registered only when the solver spec asks for them, so the trait's default
//! methods (which fail) are never called by a correctly configured solver: a default
//! `jac_times` with `user_product: false` is never seen by CVODE.

use std::os::raw::{c_int, c_void};
use std::rc::Rc;

use sundials_sys::{
    realtype, CVode, CVodeCreate, CVodeFree, CVodeGetCurrentTime, CVodeGetDky, CVodeGetLastOrder,
    CVodeGetLastStep, CVodeGetNumErrTestFails, CVodeGetNumJTSetupEvals, CVodeGetNumJacEvals,
    CVodeGetNumJtimesEvals, CVodeGetNumLinConvFails, CVodeGetNumLinIters, CVodeGetNumLinRhsEvals,
    CVodeGetNumNonlinSolvConvFails, CVodeGetNumNonlinSolvIters, CVodeGetNumPrecEvals,
    CVodeGetNumPrecSolves, CVodeGetNumRhsEvals, CVodeGetNumSteps, CVodeInit, CVodeReInit,
    CVodeSStolerances, CVodeSVtolerances, CVodeSetEpsLin, CVodeSetErrHandlerFn, CVodeSetInitStep,
    CVodeSetJacFn, CVodeSetJacTimes, CVodeSetLinearSolver, CVodeSetMaxConvFails,
    CVodeSetMaxErrTestFails, CVodeSetMaxNumSteps, CVodeSetMaxOrd, CVodeSetMaxStep,
    CVodeSetPreconditioner, CVodeSetStopTime, CVodeSetUserData, N_Vector, SUNLinSolFree,
    SUNLinSol_SPGMR, SUNLinearSolver, SUNMatrix, CV_BDF, CV_NORMAL, CV_ONE_STEP, SUN_PREC_LEFT,
    SUN_PREC_NONE,
};

use super::callback::{
    self, counter, CallbackError, CallbackResult, CountGetter, ErrorLog, RawBox, RealGetter,
};
use super::context::Context;
use super::error::{FlagFamily, SundialsError};
use super::integrator::{common_options, invalid, named, reset_reports, to_int, Api, Mem, Shared};
use super::linsol::{LinearSolver, LinearSolverSpec};
use super::matrix::JacobianMatrix;
use super::nvector::{self, NVector};

/// y' = f(t, y) and the optional derivative information CVODE's linear solvers use.
pub trait OdeSystem {
    /// ydot = f(t, y). A Recoverable error makes CVODE cut the step (the trampoline returns
    /// +1); Fatal stops it.
    fn rhs(&mut self, t: f64, y: &[f64], ydot: &mut [f64]) -> CallbackResult;

    /// Called by CVODE before a batch of [`jac_times`](Self::jac_times) calls
    /// (CVLsJacTimesSetupFn), with fy = f(t, y). Registered only with
    /// `Spgmr { user_product: true, .. }`.
    fn jac_times_setup(&mut self, _t: f64, _y: &[f64], _fy: &[f64]) -> CallbackResult {
        Ok(())
    }

    /// jv = (∂f/∂y)(t, y) v (CVLsJacTimesVecFn). Registered only with
    /// `Spgmr { user_product: true, .. }`.
    fn jac_times(
        &mut self,
        _t: f64,
        _y: &[f64],
        _fy: &[f64],
        _v: &[f64],
        _jv: &mut [f64],
    ) -> CallbackResult {
        Err(CallbackError::Fatal("no Jacobian product".into()))
    }

    /// Left preconditioner setup (CVLsPrecSetupFn) for P ≈ I − γ ∂f/∂y: `jok` says the
    /// saved Jacobian data may be reused; return whether it was recomputed (jcur).
    /// Registered only with `Spgmr { preconditioned: true, .. }`.
    fn precond_setup(
        &mut self,
        _t: f64,
        _y: &[f64],
        _fy: &[f64],
        _jok: bool,
        _gamma: f64,
    ) -> Result<bool, CallbackError> {
        Ok(false)
    }

    /// Solve P z = r (CVLsPrecSolveFn); `delta` is the requested accuracy of the solve.
    /// The default is P = I.
    #[allow(clippy::too_many_arguments)] // mirrors CVLsPrecSolveFn
    fn precond_solve(
        &mut self,
        _t: f64,
        _y: &[f64],
        _fy: &[f64],
        r: &[f64],
        z: &mut [f64],
        _gamma: f64,
        _delta: f64,
    ) -> CallbackResult {
        z.copy_from_slice(r);
        Ok(())
    }

    /// Fill the structural entries of ∂f/∂y at (t, y) (CVLsJacFn); entries not set are zero
    /// (the layer zeroes the matrix first). Registered only with `user_jacobian: true`.
    fn jacobian(
        &mut self,
        _t: f64,
        _y: &[f64],
        _fy: &[f64],
        _jac: JacobianMatrix<'_>,
    ) -> CallbackResult {
        Err(CallbackError::Fatal("no Jacobian".into()))
    }
}

/// The linear solver inside CVODE's Newton iteration.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CvodeLinearSolver {
    /// Matrix-free GMRES (SUNLinSol_SPGMR, Krylov dimension `max_krylov` ≥ 1) with the user's
    /// [`OdeSystem::jac_times`] (`user_product`) or CVODE's difference quotient, and with or
    /// without the user's left preconditioner.
    Spgmr {
        max_krylov: usize,
        user_product: bool,
        preconditioned: bool,
    },
    /// Dense LU with the user's [`OdeSystem::jacobian`] or CVODE's difference quotients.
    Dense { user_jacobian: bool },
    /// Band LU (bandwidths clamped to n − 1) with the user's Jacobian or CVODE's band
    /// difference quotients.
    Band {
        upper: usize,
        lower: usize,
        user_jacobian: bool,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct CvodeOptions {
    pub rtol: f64,
    /// Scalar absolute tolerance, used unless `atol_vector` is given.
    pub atol: f64,
    /// Per-component absolute tolerances (length n, entries ≥ 0).
    pub atol_vector: Option<Vec<f64>>,
    pub max_steps: usize,
    /// 1 ..= 5 (BDF).
    pub max_order: usize,
    /// None = CVODE's estimate.
    pub initial_step: Option<f64>,
    /// None = no limit.
    pub max_step: Option<f64>,
    /// Do not step past this time (CVodeSetStopTime). CVODE 6.4 forgets it once reached
    /// (see [`Cvode::set_stop_time`]).
    pub stop_time: Option<f64>,
    /// Per step; None = CVODE's default (7).
    pub max_error_test_failures: Option<usize>,
    /// Per step; None = CVODE's default (10).
    pub max_convergence_failures: Option<usize>,
    /// CVodeSetEpsLin: Krylov tolerance as a fraction of the Newton tolerance;
    /// None = CVODE's default (0.05).
    pub linear_tolerance_factor: Option<f64>,
}

impl Default for CvodeOptions {
    fn default() -> Self {
        CvodeOptions {
            rtol: 1e-6,
            atol: 1e-8,
            atol_vector: None,
            max_steps: 10000,
            max_order: 5,
            initial_step: None,
            max_step: None,
            stop_time: None,
            max_error_test_failures: None,
            max_convergence_failures: None,
            linear_tolerance_factor: None,
        }
    }
}

/// CVODE's cumulative counters (since creation or the last [`Cvode::reinit`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CvodeStats {
    pub steps: usize,
    /// All calls of [`OdeSystem::rhs`]: CVODE's own (CVodeGetNumRhsEvals) plus those for
    /// difference-quotient Jacobians and products (CVodeGetNumLinRhsEvals).
    pub rhs_evaluations: usize,
    /// The part of `rhs_evaluations` spent on difference quotients.
    pub linear_solver_rhs_evaluations: usize,
    pub error_test_failures: usize,
    pub nonlinear_iterations: usize,
    pub nonlinear_convergence_failures: usize,
    /// Krylov iterations (0 for direct solvers).
    pub linear_iterations: usize,
    pub linear_convergence_failures: usize,
    /// Jacobian-vector products, the user's or difference quotients.
    pub jac_times_evaluations: usize,
    pub jac_times_setups: usize,
    pub preconditioner_evaluations: usize,
    pub preconditioner_solves: usize,
    /// Jacobian evaluations of a direct solver, the user's or difference quotients.
    pub jacobian_evaluations: usize,
    /// The order of the last successful step (0 before the first).
    pub last_order: i32,
    /// The size of the last successful step (0 before the first).
    pub last_step: f64,
    /// The time CVODE has reached (CVodeGetCurrentTime), also after a failure.
    pub current_time: f64,
}

/// The functions CVODE shares with IDA (see [`Api`]).
static CVODE: Api = Api {
    family: FlagFamily::Cv,
    create: "CVodeCreate",
    free: CVodeFree,
    set_err_handler_fn: named!(CVodeSetErrHandlerFn),
    set_user_data: named!(CVodeSetUserData),
    ss_tolerances: named!(CVodeSStolerances),
    sv_tolerances: named!(CVodeSVtolerances),
    set_max_num_steps: named!(CVodeSetMaxNumSteps),
    set_max_ord: named!(CVodeSetMaxOrd),
    set_init_step: named!(CVodeSetInitStep),
    set_max_step: named!(CVodeSetMaxStep),
    set_stop_time: named!(CVodeSetStopTime),
    set_max_err_test_fails: named!(CVodeSetMaxErrTestFails),
    set_max_conv_fails: named!(CVodeSetMaxConvFails),
    get_current_time: CVodeGetCurrentTime,
    get_dky: named!(CVodeGetDky),
};

/// A matrix-free SPGMR solver, freed on drop (after the CVODE memory that uses it).
struct Spgmr(SUNLinearSolver);

impl Drop for Spgmr {
    fn drop(&mut self) {
        // SAFETY: the pointer came from SUNLinSol_SPGMR and is freed once; the CVODE memory
        // that pointed at it was freed first (field order of Cvode).
        unsafe {
            SUNLinSolFree(self.0);
        }
    }
}

enum Linear {
    Direct(LinearSolver),
    Spgmr(Spgmr),
}

impl Linear {
    fn raw(&self) -> SUNLinearSolver {
        match self {
            Linear::Direct(ls) => ls.raw(),
            Linear::Spgmr(ls) => ls.0,
        }
    }
}

pub struct Cvode<S: OdeSystem> {
    // Drop order = declaration order. CVODE points at the linear solver, the matrix (in
    // `shared`), the error log and the user data, so it goes first.
    mem: Mem,
    linsol: Linear,
    shared: RawBox<Shared<S>>,
    log: RawBox<ErrorLog>,
    y: NVector,
    n: usize,
    _ctx: Rc<Context>,
}

impl<S: OdeSystem> Cvode<S> {
    /// BDF (CV_BDF) with CVODE's Newton solver, from y(t0) = y0.
    pub fn new(
        system: S,
        t0: f64,
        y0: &[f64],
        linear: CvodeLinearSolver,
        options: &CvodeOptions,
    ) -> Result<Self, SundialsError> {
        let n = y0.len();
        if n == 0 {
            return invalid("CVODE needs at least one unknown".into());
        }
        if !t0.is_finite() {
            return invalid(format!("t0 = {t0} is not finite"));
        }
        validate(n, options)?;
        let ctx = Context::new()?;
        let y = NVector::from_slice(&ctx, y0)?;
        let (matrix, linsol) = match &linear {
            CvodeLinearSolver::Spgmr {
                max_krylov,
                preconditioned,
                ..
            } => {
                if *max_krylov == 0 {
                    return invalid("Spgmr needs max_krylov ≥ 1".into());
                }
                let maxl = to_int("max_krylov", *max_krylov)?;
                let pretype = if *preconditioned {
                    SUN_PREC_LEFT
                } else {
                    SUN_PREC_NONE
                } as c_int;
                // SAFETY: y and ctx are live; the constructor only inspects y as a template.
                let raw = unsafe { SUNLinSol_SPGMR(y.raw(), pretype, maxl, ctx.raw()) };
                if raw.is_null() {
                    return Err(SundialsError::NullHandle("SUNLinSol_SPGMR"));
                }
                (None, Linear::Spgmr(Spgmr(raw)))
            }
            CvodeLinearSolver::Dense { .. } => {
                let (m, ls) = LinearSolver::for_spec(&ctx, n, &LinearSolverSpec::Dense)?;
                (Some(m), Linear::Direct(ls))
            }
            CvodeLinearSolver::Band { upper, lower, .. } => {
                let spec = LinearSolverSpec::Band {
                    upper: *upper,
                    lower: *lower,
                };
                let (m, ls) = LinearSolver::for_spec(&ctx, n, &spec)?;
                (Some(m), Linear::Direct(ls))
            }
        };
        let shared = RawBox::new(Shared::new(system, matrix, n));
        let log = RawBox::new(ErrorLog::default());
        // SAFETY: ctx is live; the new memory is CVODE's and owned by the Mem alone.
        let mem = unsafe { Mem::new(&CVODE, CVodeCreate(CV_BDF, ctx.raw()))? };
        let mut cv = Cvode {
            mem,
            linsol,
            shared,
            log,
            y,
            n,
            _ctx: ctx,
        };
        cv.init(t0, &linear, options)?;
        Ok(cv)
    }

    fn init(
        &mut self,
        t0: f64,
        linear: &CvodeLinearSolver,
        options: &CvodeOptions,
    ) -> Result<(), SundialsError> {
        use FlagFamily::CvLs;
        let mem = self.mem.raw();
        let y0 = self.y.raw();
        let ls = self.linsol.raw();
        // SAFETY: the matrix is only read for its handle.
        let a = unsafe { self.shared.get().matrix_raw() };
        let common = common_options!(options);
        // SAFETY: the error log and the user data outlive the CVODE memory (field order).
        unsafe { self.mem.attach(&mut self.log, self.shared.as_void())? };
        // SAFETY (all calls): `mem` is live CVODE memory; the user data the trampolines
        // reach, the vectors, linear solver and matrix all outlive it (field order). CVODE
        // copies y0.
        self.log.call("CVodeInit", FlagFamily::Cv, || unsafe {
            CVodeInit(mem, Some(rhs_trampoline::<S>), t0, y0)
        })?;
        self.mem
            .set_tolerances(&mut self.log, &self._ctx, &common)?;
        self.log.call("CVodeSetLinearSolver", CvLs, || unsafe {
            CVodeSetLinearSolver(mem, ls, a)
        })?;
        match *linear {
            CvodeLinearSolver::Spgmr {
                user_product,
                preconditioned,
                ..
            } => {
                if user_product {
                    self.log.call("CVodeSetJacTimes", CvLs, || unsafe {
                        CVodeSetJacTimes(
                            mem,
                            Some(jac_times_setup_trampoline::<S>),
                            Some(jac_times_trampoline::<S>),
                        )
                    })?;
                }
                if preconditioned {
                    self.log.call("CVodeSetPreconditioner", CvLs, || unsafe {
                        CVodeSetPreconditioner(
                            mem,
                            Some(precond_setup_trampoline::<S>),
                            Some(precond_solve_trampoline::<S>),
                        )
                    })?;
                }
            }
            CvodeLinearSolver::Dense { user_jacobian }
            | CvodeLinearSolver::Band { user_jacobian, .. } => {
                if user_jacobian {
                    self.log.call("CVodeSetJacFn", CvLs, || unsafe {
                        CVodeSetJacFn(mem, Some(jacobian_trampoline::<S>))
                    })?;
                }
            }
        }
        self.mem.set_step_controls(&mut self.log, &common)?;
        if let Some(eps) = options.linear_tolerance_factor {
            self.log.call("CVodeSetEpsLin", CvLs, || unsafe {
                CVodeSetEpsLin(mem, eps)
            })?;
        }
        Ok(())
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// Integrate to `tout` (CV_NORMAL: CVODE steps past it and interpolates); `y` gets the
    /// state at the returned time, which is `tout` unless a stop time came first.
    ///
    /// On failure `y` holds the state at the last successful step and
    /// [`stats`](Self::stats)`().current_time` says where that was.
    pub fn advance_to(&mut self, tout: f64, y: &mut [f64]) -> Result<f64, SundialsError> {
        self.run(tout, y, CV_NORMAL, "CVode")
    }

    /// One internal step towards `tout` (CV_ONE_STEP); returns the time reached, and `y`
    /// the state there.
    pub fn step(&mut self, tout: f64, y: &mut [f64]) -> Result<f64, SundialsError> {
        self.run(tout, y, CV_ONE_STEP, "CVode (one step)")
    }

    /// CVode with `itask`; `function` names the call in errors.
    fn run(
        &mut self,
        tout: f64,
        y: &mut [f64],
        itask: c_int,
        function: &'static str,
    ) -> Result<f64, SundialsError> {
        if y.len() != self.n {
            return invalid(format!("y has length {}, expected {}", y.len(), self.n));
        }
        if !tout.is_finite() {
            return invalid(format!("tout = {tout} is not finite"));
        }
        reset_reports(&mut self.shared, &mut self.log);
        let mut tret: realtype = f64::NAN;
        // SAFETY: every handle is live; during the call the only references to the shared
        // state and the log are the short-lived ones the trampolines create.
        let flag = unsafe { CVode(self.mem.raw(), tout, self.y.raw(), &mut tret, itask) };
        y.copy_from_slice(self.y.as_slice());
        self.mem
            .finish(&mut self.shared, &self.log, function, flag)?;
        Ok(tret)
    }

    /// Restart from y(t0) = y0 with the same system, solver and options (CVodeReInit); the
    /// counters restart from zero.
    pub fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SundialsError> {
        if y0.len() != self.n {
            return invalid(format!("y0 has length {}, expected {}", y0.len(), self.n));
        }
        if !t0.is_finite() {
            return invalid(format!("t0 = {t0} is not finite"));
        }
        self.y.as_mut_slice().copy_from_slice(y0);
        let (mem, y) = (self.mem.raw(), self.y.raw());
        // SAFETY: mem and y are live; CVODE copies y.
        self.log.call("CVodeReInit", FlagFamily::Cv, || unsafe {
            CVodeReInit(mem, t0, y)
        })
    }

    /// Do not step past `t` (CVodeSetStopTime): [`advance_to`](Self::advance_to) and
    /// [`step`](Self::step) return `t` when they reach it. CVODE 6.4 then forgets it (later
    /// calls integrate past it; there is no CVodeClearStopTime before 6.5), and keeps one not
    /// yet reached across [`reinit`](Self::reinit). A `t` behind the current time is
    /// CV_ILL_INPUT.
    pub fn set_stop_time(&mut self, t: f64) -> Result<(), SundialsError> {
        self.mem.set_stop_time(&mut self.log, t)
    }

    /// Dense output of the last step: y at any t within it (CVodeGetDky, k = 0).
    pub fn interpolate(&self, t: f64, y: &mut [f64]) -> Result<(), SundialsError> {
        if y.len() != self.n {
            return invalid(format!("y has length {}, expected {}", y.len(), self.n));
        }
        self.mem.get_dky(&self.log, &self._ctx, t, 0, y)
    }

    /// The counters so far (also after a failure).
    pub fn stats(&self) -> CvodeStats {
        let mem = self.mem.raw();
        // SAFETY: mem is live CVODE memory, and the getters are CVODE's.
        let count = |f: CountGetter| unsafe { counter(mem, f) };
        let real = |f: RealGetter| unsafe { callback::real(mem, f) };
        let mut last_order: c_int = 0;
        // SAFETY: mem is live; last_order is a valid out-pointer.
        unsafe { CVodeGetLastOrder(mem, &mut last_order) };
        let own = count(CVodeGetNumRhsEvals);
        let ls = count(CVodeGetNumLinRhsEvals);
        CvodeStats {
            steps: count(CVodeGetNumSteps),
            rhs_evaluations: own + ls,
            linear_solver_rhs_evaluations: ls,
            error_test_failures: count(CVodeGetNumErrTestFails),
            nonlinear_iterations: count(CVodeGetNumNonlinSolvIters),
            nonlinear_convergence_failures: count(CVodeGetNumNonlinSolvConvFails),
            linear_iterations: count(CVodeGetNumLinIters),
            linear_convergence_failures: count(CVodeGetNumLinConvFails),
            jac_times_evaluations: count(CVodeGetNumJtimesEvals),
            jac_times_setups: count(CVodeGetNumJTSetupEvals),
            preconditioner_evaluations: count(CVodeGetNumPrecEvals),
            preconditioner_solves: count(CVodeGetNumPrecSolves),
            jacobian_evaluations: count(CVodeGetNumJacEvals),
            last_order,
            last_step: real(CVodeGetLastStep),
            current_time: real(CVodeGetCurrentTime),
        }
    }

    pub fn system(&self) -> &S {
        // SAFETY: no callback is running while we hold &self (advance_to needs &mut self).
        unsafe { &self.shared.get().system }
    }

    pub fn system_mut(&mut self) -> &mut S {
        // SAFETY: as above, with exclusive access.
        unsafe { &mut self.shared.get_mut().system }
    }
}

fn validate(n: usize, o: &CvodeOptions) -> Result<(), SundialsError> {
    common_options!(o).validate(n)?;
    if o.max_error_test_failures == Some(0) || o.max_convergence_failures == Some(0) {
        return invalid("max_error_test_failures and max_convergence_failures must be ≥ 1".into());
    }
    if let Some(eps) = o.linear_tolerance_factor {
        if !(eps > 0.0 && eps.is_finite()) {
            return invalid(format!(
                "linear_tolerance_factor must be positive, got {eps}"
            ));
        }
    }
    Ok(())
}

/// CVRhsFn: ydot = f(t, y).
unsafe extern "C" fn rhs_trampoline<S: OdeSystem>(
    t: realtype,
    y: N_Vector,
    ydot: N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: `data` is the Shared<S> registered with CVodeSetUserData; CVODE calls us from
    // inside CVode, while no other reference to it exists; y and ydot are distinct live
    // serial vectors of length n.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, ydot) = unsafe { (nvector::slice(y), nvector::slice_mut(ydot)) };
    shared.guard("rhs", |system| system.rhs(t, y, ydot))
}

/// CVLsJacFn: zero J, let the system fill it, check nothing fell outside its structure.
unsafe extern "C" fn jacobian_trampoline<S: OdeSystem>(
    t: realtype,
    y: N_Vector,
    fy: N_Vector,
    jac: SUNMatrix,
    data: *mut c_void,
    _tmp1: N_Vector,
    _tmp2: N_Vector,
    _tmp3: N_Vector,
) -> c_int {
    // SAFETY: as in rhs_trampoline; y and fy are live and only read.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, fy) = unsafe { (nvector::slice(y), nvector::slice(fy)) };
    shared.jacobian("CVODE", jac, |system, jac| system.jacobian(t, y, fy, jac))
}

/// CVLsJacTimesSetupFn.
unsafe extern "C" fn jac_times_setup_trampoline<S: OdeSystem>(
    t: realtype,
    y: N_Vector,
    fy: N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: as in rhs_trampoline; y and fy are only read.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, fy) = unsafe { (nvector::slice(y), nvector::slice(fy)) };
    shared.guard("jac_times_setup", |system| system.jac_times_setup(t, y, fy))
}

/// CVLsJacTimesVecFn: jv = J v.
unsafe extern "C" fn jac_times_trampoline<S: OdeSystem>(
    v: N_Vector,
    jv: N_Vector,
    t: realtype,
    y: N_Vector,
    fy: N_Vector,
    data: *mut c_void,
    _tmp: N_Vector,
) -> c_int {
    // SAFETY: as in rhs_trampoline; y and fy are only read, v and jv are live vectors of
    // length n that only this call accesses (guard_in_out copies v if it is jv).
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, fy) = unsafe { (nvector::slice(y), nvector::slice(fy)) };
    unsafe {
        shared.guard_in_out("jac_times", v, jv, |system, v, jv| {
            system.jac_times(t, y, fy, v, jv)
        })
    }
}

/// CVLsPrecSetupFn.
unsafe extern "C" fn precond_setup_trampoline<S: OdeSystem>(
    t: realtype,
    y: N_Vector,
    fy: N_Vector,
    jok: c_int,
    jcur: *mut c_int,
    gamma: realtype,
    data: *mut c_void,
) -> c_int {
    // SAFETY: as in rhs_trampoline; jcur is a valid out-pointer.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, fy) = unsafe { (nvector::slice(y), nvector::slice(fy)) };
    let mut recomputed = false;
    let flag = shared.guard("precond_setup", |system| {
        recomputed = system.precond_setup(t, y, fy, jok != 0, gamma)?;
        Ok(())
    });
    if !jcur.is_null() {
        // SAFETY: CVODE passes a pointer to its jcur flag.
        unsafe { *jcur = c_int::from(recomputed) };
    }
    flag
}

/// CVLsPrecSolveFn: solve P z = r.
unsafe extern "C" fn precond_solve_trampoline<S: OdeSystem>(
    t: realtype,
    y: N_Vector,
    fy: N_Vector,
    r: N_Vector,
    z: N_Vector,
    gamma: realtype,
    delta: realtype,
    _lr: c_int,
    data: *mut c_void,
) -> c_int {
    // SAFETY: as in jac_times_trampoline, with r the input and z the output.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, fy) = unsafe { (nvector::slice(y), nvector::slice(fy)) };
    unsafe {
        shared.guard_in_out("precond_solve", r, z, |system, r, z| {
            system.precond_solve(t, y, fy, r, z, gamma, delta)
        })
    }
}
