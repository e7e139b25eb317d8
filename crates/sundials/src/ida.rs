//! IDA: variable-order, variable-step BDF for implicit DAEs F(t, y, y') = 0, with Newton's
//! method (IDA's default nonlinear solver) and a direct linear solver: dense or band LU (with
//! the caller's Jacobian or IDA's difference quotients), or the caller's own solver.
//!
//! Ownership: [`Ida`] owns the IDA memory, the linear solver, the matrix (a SUNDIALS one, or
//! the token matrix of the custom solver), the vectors and the user's system; its fields are
//! declared in the order they must be freed (IDA memory → linear solver → matrix → everything
//! else → context), as in [`Cvode`](super::Cvode).
//!
//! The custom solver ([`IdaLinearSolver::Custom`]) is a SUNLinearSolver of type DIRECT whose
//! `solve` calls [`DaeSystem::linear_solve`], paired with an empty "token" SUNMatrix, while the
//! Jacobian function registered with IDASetJacFn calls [`DaeSystem::linear_setup`]. Why not a
//! MATRIX_EMBEDDED solver, the type meant for solvers that keep their own matrix: IDA 6.4 then
//! sets its lsetup to NULL (idaLsInitialize), so the system would never be told to refresh
//! its Newton matrix, and drops the 2/(1 + cj/cj_old) scaling of the correction that keeps a
//! matrix built for an older cj usable. A DIRECT solver with a non-NULL matrix gets both:
//! idaLsSetup calls SUNMatZero on the matrix (the only matrix operation IDA 6.4 performs when
//! the Jacobian function is the user's), then the Jacobian function, then SUNLinSolSetup.
//!
//! Callbacks are registered only when the solver asks for them, so the trait's default
//! methods (which fail) are never called by a correctly configured solver.

use std::os::raw::{c_int, c_void};
use std::rc::Rc;

use sundials_sys::{
    realtype, IDACalcIC, IDACreate, IDAFree, IDAGetConsistentIC, IDAGetCurrentStep,
    IDAGetCurrentTime, IDAGetDky, IDAGetLastOrder, IDAGetLastStep, IDAGetNumErrTestFails,
    IDAGetNumJacEvals, IDAGetNumLinResEvals, IDAGetNumLinSolvSetups, IDAGetNumNonlinSolvConvFails,
    IDAGetNumNonlinSolvIters, IDAGetNumResEvals, IDAGetNumSteps, IDAInit, IDAReInit,
    IDASStolerances, IDASVtolerances, IDASetErrHandlerFn, IDASetId, IDASetInitStep, IDASetJacFn,
    IDASetLinearSolver, IDASetMaxConvFails, IDASetMaxErrTestFails, IDASetMaxNonlinIters,
    IDASetMaxNumSteps, IDASetMaxOrd, IDASetMaxStep, IDASetNonlinConvCoef, IDASetStopTime,
    IDASetSuppressAlg, IDASetUserData, IDASolve, N_Vector, SUNLinSolFree, SUNLinearSolver,
    SUNMatDestroy, SUNMatrix, IDA_NORMAL, IDA_ONE_STEP, IDA_YA_YDP_INIT, SUNLS_PACKAGE_FAIL_REC,
    SUNLS_PACKAGE_FAIL_UNREC, SUNLS_SUCCESS,
};

use super::callback::{
    self, counter, CallbackError, CallbackResult, CountGetter, ErrorLog, RawBox, RealGetter,
};
use super::context::Context;
use super::custom;
use super::error::{flag_error, FlagFamily, SundialsError};
use super::integrator::{common_options, invalid, named, reset_reports, to_int, Api, Mem, Shared};
use super::linsol::{LinearSolver, LinearSolverSpec};
use super::matrix::JacobianMatrix;
use super::nvector::{self, NVector};

/// F(t, y, y') = 0 and how its Newton systems are solved.
pub trait DaeSystem {
    /// r = F(t, y, y'). A Recoverable error makes IDA retry with a smaller step (the
    /// trampoline returns +1); Fatal stops it.
    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult;

    /// [`IdaLinearSolver::Custom`] only: prepare to solve M x = b with
    /// M = ∂F/∂y + cj ∂F/∂y' at (t, y, y'), r = F(t, y, y'). Called from IDA's Jacobian
    /// callback when IDA decides to refresh its Newton matrix. Recoverable makes IDA retry
    /// (a smaller step, or in [`Ida::calc_ic`] a smaller cj).
    fn linear_setup(
        &mut self,
        _t: f64,
        _cj: f64,
        _y: &[f64],
        _yp: &[f64],
        _r: &[f64],
    ) -> CallbackResult {
        Err(CallbackError::Fatal("no linear setup".into()))
    }

    /// [`IdaLinearSolver::Custom`] only: x = M⁻¹ b with the M of the last
    /// [`linear_setup`](Self::linear_setup). IDA may call it with a cj different from that
    /// of the setup; it rescales the result itself. Recoverable makes IDA set up again (if
    /// the matrix was old) or cut the step.
    fn linear_solve(&mut self, _b: &[f64], _x: &mut [f64]) -> CallbackResult {
        Err(CallbackError::Fatal("no linear solve".into()))
    }

    /// Dense/Band with `user_jacobian: true`: fill the structural entries of
    /// M = ∂F/∂y + cj ∂F/∂y' (IDALsJacFn); entries not set are zero (the layer zeroes the
    /// matrix first), and writes outside the band are an error.
    fn jacobian(
        &mut self,
        _t: f64,
        _cj: f64,
        _y: &[f64],
        _yp: &[f64],
        _r: &[f64],
        _jac: JacobianMatrix<'_>,
    ) -> CallbackResult {
        Err(CallbackError::Fatal("no Jacobian".into()))
    }

    /// Forward sensitivities only ([`Ida::init_sensitivities`]): for each parameter j,
    /// rs\[j\] = F_y ys\[j\] + F_y' yps\[j\] + ∂F/∂p_j at (t, y, y'), r = F(t, y, y')
    /// (IDASensResFn). Recoverable makes IDAS cut the step.
    #[allow(clippy::too_many_arguments)] // IDASensResFn's arguments, each distinct
    fn sensitivity_residual(
        &mut self,
        _t: f64,
        _y: &[f64],
        _yp: &[f64],
        _r: &[f64],
        _ys: &[&[f64]],
        _yps: &[&[f64]],
        _rs: &mut [&mut [f64]],
    ) -> CallbackResult {
        Err(CallbackError::Fatal("no sensitivity residual".into()))
    }
}

/// The linear solver inside IDA's Newton iteration.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum IdaLinearSolver {
    /// The system's own linear solver ([`DaeSystem::linear_setup`] /
    /// [`DaeSystem::linear_solve`]).
    Custom,
    /// Dense LU with the user's [`DaeSystem::jacobian`] or IDA's difference quotients.
    Dense { user_jacobian: bool },
    /// Band LU (bandwidths clamped to n − 1) with the user's Jacobian or IDA's band
    /// difference quotients.
    Band {
        upper: usize,
        lower: usize,
        user_jacobian: bool,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct IdaOptions {
    pub rtol: f64,
    /// Scalar absolute tolerance, used unless `atol_vector` is given.
    pub atol: f64,
    /// Per-component absolute tolerances (length n, entries ≥ 0).
    pub atol_vector: Option<Vec<f64>>,
    pub max_steps: usize,
    /// 1 ..= 5 (BDF).
    pub max_order: usize,
    /// None = IDA's estimate.
    pub initial_step: Option<f64>,
    /// None = no limit.
    pub max_step: Option<f64>,
    /// Do not step past this time (IDASetStopTime). IDA 6.4 forgets it once reached (see
    /// [`Ida::set_stop_time`]).
    pub stop_time: Option<f64>,
    /// Per component: 1.0 differential, 0.0 algebraic (IDASetId). Required when
    /// `suppress_algebraic` or [`Ida::calc_ic`] are used.
    pub id: Option<Vec<f64>>,
    /// IDASetSuppressAlg: leave the algebraic components out of the local error test.
    pub suppress_algebraic: bool,
    /// Per step; None = IDA's default (10).
    pub max_error_test_failures: Option<usize>,
    /// Per step; None = IDA's default (10).
    pub max_convergence_failures: Option<usize>,
    /// Newton iterations per step (IDASetMaxNonlinIters); None = IDA's default (4).
    pub max_nonlinear_iterations: Option<usize>,
    /// Safety factor of the Newton convergence test (IDASetNonlinConvCoef); None = IDA's
    /// default (0.33).
    pub nonlinear_convergence_coefficient: Option<f64>,
    /// How far c_j may drift from the one the Newton matrix was set up with before IDA sets
    /// it up again (IDASetDeltaCjLSetup: a new set-up when the ratio leaves
    /// [(1 − dcj)/(1 + dcj), (1 + dcj)/(1 − dcj)]); None = IDA's default (0.25). In (0, 1).
    pub delta_cj_setup: Option<f64>,
    /// The step-size ratios η ∈ [lo, hi] for which IDA keeps the step unchanged
    /// (IDASetEtaFixedStepBounds); None = IDA's default [0, 2]: a step grows only when it
    /// could at least double. 0 ≤ lo ≤ 1 ≤ hi.
    pub fixed_step_bounds: Option<(f64, f64)>,
}

impl Default for IdaOptions {
    fn default() -> Self {
        IdaOptions {
            rtol: 1e-6,
            atol: 1e-8,
            atol_vector: None,
            max_steps: 10000,
            max_order: 5,
            initial_step: None,
            max_step: None,
            stop_time: None,
            id: None,
            suppress_algebraic: false,
            max_error_test_failures: None,
            max_convergence_failures: None,
            max_nonlinear_iterations: None,
            nonlinear_convergence_coefficient: None,
            delta_cj_setup: None,
            fixed_step_bounds: None,
        }
    }
}

/// IDA's cumulative counters (since creation or the last [`Ida::reinit`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IdaStats {
    pub steps: usize,
    /// All calls of [`DaeSystem::residual`]: IDA's own (IDAGetNumResEvals, including those of
    /// [`Ida::calc_ic`]) plus those of difference-quotient Jacobians (IDAGetNumLinResEvals).
    pub residual_evaluations: usize,
    /// The part of `residual_evaluations` spent on difference quotients.
    pub linear_solver_residual_evaluations: usize,
    /// Jacobian evaluations (IDAGetNumJacEvals), the user's or difference quotients; for
    /// [`IdaLinearSolver::Custom`], the number of [`DaeSystem::linear_setup`] calls.
    pub jacobian_evaluations: usize,
    /// Linear solver setups (IDAGetNumLinSolvSetups).
    pub linear_setups: usize,
    pub error_test_failures: usize,
    pub nonlinear_iterations: usize,
    /// Failed Newton solves, including those caused by recoverable callback errors.
    pub nonlinear_convergence_failures: usize,
    /// The order of the last successful step (0 before the first).
    pub last_order: i32,
    /// The size of the last successful step (0 before the first; after [`Ida::calc_ic`],
    /// the pseudo-step it used).
    pub last_step: f64,
    /// The step IDA will try next.
    pub current_step: f64,
    /// The time IDA has reached (IDAGetCurrentTime), also after a failure.
    pub current_time: f64,
}

/// The functions IDA shares with CVODE (see [`Api`]).
static IDA: Api = Api {
    family: FlagFamily::Ida,
    create: "IDACreate",
    free: IDAFree,
    set_err_handler_fn: named!(IDASetErrHandlerFn),
    set_user_data: named!(IDASetUserData),
    ss_tolerances: named!(IDASStolerances),
    sv_tolerances: named!(IDASVtolerances),
    set_max_num_steps: named!(IDASetMaxNumSteps),
    set_max_ord: named!(IDASetMaxOrd),
    set_init_step: named!(IDASetInitStep),
    set_max_step: named!(IDASetMaxStep),
    set_stop_time: named!(IDASetStopTime),
    set_max_err_test_fails: named!(IDASetMaxErrTestFails),
    set_max_conv_fails: named!(IDASetMaxConvFails),
    get_current_time: IDAGetCurrentTime,
    get_dky: named!(IDAGetDky),
};

/// The custom solver's SUNLinearSolver (ops set by [`Linear::custom`]), freed on drop.
struct CustomSolver(SUNLinearSolver);

impl Drop for CustomSolver {
    fn drop(&mut self) {
        // SAFETY: the pointer came from SUNLinSolNewEmpty and is freed once, by its `free` op
        // (SUNLinSolFreeEmpty: the content is ours and not freed); the IDA memory that pointed
        // at it was freed first (field order of Ida).
        unsafe {
            SUNLinSolFree(self.0);
        }
    }
}

/// The custom solver's placeholder matrix, freed on drop.
struct TokenMatrix(SUNMatrix);

impl Drop for TokenMatrix {
    fn drop(&mut self) {
        // SAFETY: the pointer came from SUNMatNewEmpty and is freed once, by its `destroy` op
        // (SUNMatFreeEmpty; it has no content); IDA and the solver were freed first.
        unsafe { SUNMatDestroy(self.0) }
    }
}

enum Linear {
    Direct(LinearSolver),
    // Field order = drop order: the solver, then its matrix.
    Custom {
        solver: CustomSolver,
        token: TokenMatrix,
    },
}

impl Linear {
    fn raw(&self) -> SUNLinearSolver {
        match self {
            Linear::Direct(ls) => ls.raw(),
            Linear::Custom { solver, .. } => solver.0,
        }
    }
}

pub struct Ida<S: DaeSystem> {
    // Drop order = declaration order. IDA points at the linear solver, the matrix (the
    // token in `linsol`, or a SUNDIALS matrix in `shared`), the error log and the user data,
    // so it goes first; the custom solver points at `shared`, so it goes before it.
    mem: Mem,
    linsol: Linear,
    shared: RawBox<Shared<S>>,
    log: RawBox<ErrorLog>,
    y: NVector,
    yp: NVector,
    n: usize,
    /// Whether options.id was given (IDACalcIC needs it).
    has_id: bool,
    /// The number of sensitivities ([`Ida::init_sensitivities`]; 0 without).
    pub(crate) n_sens: usize,
    _ctx: Rc<Context>,
}

impl<S: DaeSystem> Ida<S> {
    /// BDF with IDA's Newton solver, from y(t0) = y0, y'(t0) = yp0 (which should be
    /// consistent, F(t0, y0, yp0) = 0, or be made so by [`calc_ic`](Self::calc_ic)).
    pub fn new(
        system: S,
        t0: f64,
        y0: &[f64],
        yp0: &[f64],
        linear: IdaLinearSolver,
        options: &IdaOptions,
    ) -> Result<Self, SundialsError> {
        let n = y0.len();
        if n == 0 {
            return invalid("IDA needs at least one unknown".into());
        }
        if yp0.len() != n {
            return invalid(format!(
                "yp0 has length {}, expected {n} (the length of y0)",
                yp0.len()
            ));
        }
        if !t0.is_finite() {
            return invalid(format!("t0 = {t0} is not finite"));
        }
        validate(n, options)?;
        let ctx = Context::new()?;
        let mut y = NVector::from_slice(&ctx, y0)?;
        let mut yp = NVector::from_slice(&ctx, yp0)?;
        // IDA clones its work vectors from y: fused operations halve its passes over them,
        // and our kernels run them several times faster than the library's (fastops.rs).
        y.enable_fused_ops()?;
        yp.enable_fused_ops()?;
        // SAFETY: y and yp are live serial vectors owned here, with their own op tables.
        unsafe {
            super::fastops::install(y.raw());
            super::fastops::install(yp.raw());
        }
        let (matrix, linsol) = match &linear {
            IdaLinearSolver::Custom => (None, Linear::custom::<S>(&ctx)?),
            IdaLinearSolver::Dense { .. } => {
                let (m, ls) = LinearSolver::for_spec(&ctx, n, &LinearSolverSpec::Dense)?;
                (Some(m), Linear::Direct(ls))
            }
            IdaLinearSolver::Band { upper, lower, .. } => {
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
        // SAFETY: ctx is live; the new memory is IDA's and owned by the Mem alone.
        let mem = unsafe { Mem::new(&IDA, IDACreate(ctx.raw()))? };
        let has_id = options.id.is_some();
        let mut ida = Ida {
            mem,
            linsol,
            shared,
            log,
            y,
            yp,
            n,
            has_id,
            n_sens: 0,
            _ctx: ctx,
        };
        if let Linear::Custom { solver, .. } = &ida.linsol {
            // SAFETY: the solver is live and ours; its content is read only by
            // custom_solve_trampoline, and `shared` outlives the solver (field order of Ida).
            unsafe { (*solver.0).content = ida.shared.as_void() };
        }
        ida.init(t0, &linear, options)?;
        Ok(ida)
    }

    fn init(
        &mut self,
        t0: f64,
        linear: &IdaLinearSolver,
        options: &IdaOptions,
    ) -> Result<(), SundialsError> {
        use FlagFamily::{Ida, IdaLs};
        let mem = self.mem.raw();
        let (y0, yp0) = (self.y.raw(), self.yp.raw());
        let ls = self.linsol.raw();
        let a = match &self.linsol {
            Linear::Custom { token, .. } => token.0,
            // SAFETY: the matrix is only read for its handle.
            Linear::Direct(_) => unsafe { self.shared.get().matrix_raw() },
        };
        let common = common_options!(options);
        // SAFETY: the error log and the user data outlive the IDA memory (field order).
        unsafe { self.mem.attach(&mut self.log, self.shared.as_void())? };
        // SAFETY (all calls): `mem` is live IDA memory; the user data the trampolines reach,
        // the vectors, linear solver and matrix all outlive it (field order). IDA copies y0,
        // yp0 and the id vector. The user data is set (attach) before the Jacobian function,
        // which IDASetJacFn binds to the user data current at the call.
        self.log.call("IDAInit", Ida, || unsafe {
            IDAInit(mem, Some(residual_trampoline::<S>), t0, y0, yp0)
        })?;
        self.mem
            .set_tolerances(&mut self.log, &self._ctx, &common)?;
        self.log.call("IDASetLinearSolver", IdaLs, || unsafe {
            IDASetLinearSolver(mem, ls, a)
        })?;
        let jac: sundials_sys::IDALsJacFn = match *linear {
            IdaLinearSolver::Custom => Some(linear_setup_trampoline::<S>),
            IdaLinearSolver::Dense {
                user_jacobian: true,
            }
            | IdaLinearSolver::Band {
                user_jacobian: true,
                ..
            } => Some(jacobian_trampoline::<S>),
            _ => None,
        };
        if jac.is_some() {
            self.log
                .call("IDASetJacFn", IdaLs, || unsafe { IDASetJacFn(mem, jac) })?;
        }
        if let Some(id) = &options.id {
            let id = NVector::from_slice(&self._ctx, id)?;
            self.log
                .call("IDASetId", Ida, || unsafe { IDASetId(mem, id.raw()) })?;
        }
        if options.suppress_algebraic {
            self.log.call("IDASetSuppressAlg", Ida, || unsafe {
                IDASetSuppressAlg(mem, 1)
            })?;
        }
        self.mem.set_step_controls(&mut self.log, &common)?;
        if let Some(k) = options.max_nonlinear_iterations {
            // Needs the nonlinear solver, which IDAInit creates.
            let k = to_int("max_nonlinear_iterations", k)?;
            self.log.call("IDASetMaxNonlinIters", Ida, || unsafe {
                IDASetMaxNonlinIters(mem, k)
            })?;
        }
        if let Some(c) = options.nonlinear_convergence_coefficient {
            self.log.call("IDASetNonlinConvCoef", Ida, || unsafe {
                IDASetNonlinConvCoef(mem, c)
            })?;
        }
        if let Some(d) = options.delta_cj_setup {
            // SAFETY: mem is live.
            self.log.call("IDASetDeltaCjLSetup", Ida, || unsafe {
                sundials_sys::IDASetDeltaCjLSetup(mem, d)
            })?;
        }
        if let Some((lo, hi)) = options.fixed_step_bounds {
            // SAFETY: mem is live.
            self.log.call("IDASetEtaFixedStepBounds", Ida, || unsafe {
                sundials_sys::IDASetEtaFixedStepBounds(mem, lo, hi)
            })?;
        }
        Ok(())
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// Integrate to `tout` (IDA_NORMAL: IDA steps past it and interpolates); `y` and `yp`
    /// get the state at the returned time, which is `tout` unless a stop time came first.
    ///
    /// On failure `y` and `yp` hold the state at the last successful step (the initial
    /// values if there was none) and [`stats`](Self::stats)`().current_time` says where that
    /// was.
    pub fn advance_to(
        &mut self,
        tout: f64,
        y: &mut [f64],
        yp: &mut [f64],
    ) -> Result<f64, SundialsError> {
        self.run(tout, y, yp, IDA_NORMAL, "IDASolve")
    }

    /// One internal step towards `tout` (IDA_ONE_STEP); returns the time reached, and `y`,
    /// `yp` the state there.
    pub fn step(&mut self, tout: f64, y: &mut [f64], yp: &mut [f64]) -> Result<f64, SundialsError> {
        self.run(tout, y, yp, IDA_ONE_STEP, "IDASolve (one step)")
    }

    fn check_lengths(&self, y: &[f64], yp: &[f64]) -> Result<(), SundialsError> {
        if y.len() != self.n || yp.len() != self.n {
            return invalid(format!(
                "y and yp have lengths {} and {}, expected {}",
                y.len(),
                yp.len(),
                self.n
            ));
        }
        Ok(())
    }

    /// IDASolve with `itask`; `function` names the call in errors.
    fn run(
        &mut self,
        tout: f64,
        y: &mut [f64],
        yp: &mut [f64],
        itask: c_int,
        function: &'static str,
    ) -> Result<f64, SundialsError> {
        self.check_lengths(y, yp)?;
        if !tout.is_finite() {
            return invalid(format!("tout = {tout} is not finite"));
        }
        reset_reports(&mut self.shared, &mut self.log);
        let mut tret: realtype = f64::NAN;
        // SAFETY: every handle is live; during the call the only references to the shared
        // state and the log are the short-lived ones the trampolines create.
        let flag = unsafe {
            IDASolve(
                self.mem.raw(),
                tout,
                &mut tret,
                self.y.raw(),
                self.yp.raw(),
                itask,
            )
        };
        if flag < 0 {
            // IDA_TOO_MUCH_WORK in IDA_NORMAL mode leaves the output vectors as they were;
            // interpolate the last step's end instead (exact there: the sum stops at phi[0]).
            self.load_current_state();
        }
        y.copy_from_slice(self.y.as_slice());
        yp.copy_from_slice(self.yp.as_slice());
        self.mem
            .finish(&mut self.shared, &self.log, function, flag)?;
        Ok(tret)
    }

    /// y, y' at the current time from the last step's polynomial, if a step was taken.
    fn load_current_state(&mut self) {
        let stats = self.stats();
        if stats.steps == 0 || stats.last_order < 1 {
            return;
        }
        let (mem, y, yp) = (self.mem.raw(), self.y.raw(), self.yp.raw());
        // SAFETY: mem, y and yp are live; IDAGetDky calls no user callback (a failure, which
        // cannot happen at t = tn with k ≤ the last order, would only reach the log).
        unsafe {
            IDAGetDky(mem, stats.current_time, 0, y);
            IDAGetDky(mem, stats.current_time, 1, yp);
        }
    }

    /// Make the initial state consistent (IDACalcIC with IDA_YA_YDP_INIT): keep the
    /// differential components of y (options.id = 1.0), compute the algebraic components of
    /// y and the differential components of y' so that F(t0, y, y') = 0; `tout1` is the
    /// first output time (IDA scales its pseudo-step, 0.001 (tout1 − t0) at most, by it).
    ///
    /// The guess is the y0, yp0 given to [`new`](Self::new) or [`reinit`](Self::reinit);
    /// `y` and `yp` are only written, with the corrected values (IDAGetConsistentIC), which
    /// the integration then starts from. The algebraic components of y' are left as given.
    /// Only before the first step, and only with options.id. IDA's Newton iteration here
    /// stops at 0.0033 in the weighted norm, so the result is consistent to a fraction of
    /// the tolerances, not to round-off.
    pub fn calc_ic(
        &mut self,
        tout1: f64,
        y: &mut [f64],
        yp: &mut [f64],
    ) -> Result<(), SundialsError> {
        self.check_lengths(y, yp)?;
        if !self.has_id {
            return invalid("calc_ic needs options.id (which components are differential)".into());
        }
        if !tout1.is_finite() {
            return invalid(format!("tout1 = {tout1} is not finite"));
        }
        if self.stats().steps > 0 {
            return invalid("calc_ic must come before the first step (after new or reinit)".into());
        }
        reset_reports(&mut self.shared, &mut self.log);
        // SAFETY: mem is live; as in run, the trampolines create the only references to the
        // shared state and the log.
        let flag = unsafe { IDACalcIC(self.mem.raw(), IDA_YA_YDP_INIT, tout1) };
        self.mem
            .finish(&mut self.shared, &self.log, "IDACalcIC", flag)?;
        let (mem, yv, ypv) = (self.mem.raw(), self.y.raw(), self.yp.raw());
        // SAFETY: mem, yv and ypv are live; IDAGetConsistentIC copies into them.
        self.log
            .call("IDAGetConsistentIC", FlagFamily::Ida, || unsafe {
                IDAGetConsistentIC(mem, yv, ypv)
            })?;
        y.copy_from_slice(self.y.as_slice());
        yp.copy_from_slice(self.yp.as_slice());
        Ok(())
    }

    /// Restart from y(t0) = y0, y'(t0) = yp0 with the same system, solver and options
    /// (IDAReInit). IDA's counters restart from zero at once, the linear solver's
    /// (`jacobian_evaluations`, `linear_solver_residual_evaluations`) at the next
    /// [`advance_to`](Self::advance_to), [`step`](Self::step) or [`calc_ic`](Self::calc_ic).
    pub fn reinit(&mut self, t0: f64, y0: &[f64], yp0: &[f64]) -> Result<(), SundialsError> {
        if y0.len() != self.n || yp0.len() != self.n {
            return invalid(format!(
                "y0 and yp0 have lengths {} and {}, expected {}",
                y0.len(),
                yp0.len(),
                self.n
            ));
        }
        if !t0.is_finite() {
            return invalid(format!("t0 = {t0} is not finite"));
        }
        self.y.as_mut_slice().copy_from_slice(y0);
        self.yp.as_mut_slice().copy_from_slice(yp0);
        let (mem, y, yp) = (self.mem.raw(), self.y.raw(), self.yp.raw());
        // SAFETY: mem, y and yp are live; IDA copies y and yp.
        self.log.call("IDAReInit", FlagFamily::Ida, || unsafe {
            IDAReInit(mem, t0, y, yp)
        })
    }

    /// Do not step past `t` (IDASetStopTime): [`advance_to`](Self::advance_to) and
    /// [`step`](Self::step) return `t` when they reach it. IDA 6.4 then forgets it (later
    /// calls integrate past it; there is no IDAClearStopTime before 6.5), and keeps one not
    /// yet reached across [`reinit`](Self::reinit). A `t` behind the current time is
    /// IDA_ILL_INPUT (once a step has been taken).
    pub fn set_stop_time(&mut self, t: f64) -> Result<(), SundialsError> {
        self.mem.set_stop_time(&mut self.log, t)
    }

    /// Dense output of the last step: y at any t within it (IDAGetDky, k = 0). A t outside
    /// it is IDA_BAD_T.
    pub fn interpolate(&self, t: f64, y: &mut [f64]) -> Result<(), SundialsError> {
        self.dky(t, 0, y)
    }

    /// Dense output of the last step: y' at any t within it (IDAGetDky, k = 1; IDA_BAD_K
    /// before the first step).
    pub fn interpolate_derivative(&self, t: f64, yp: &mut [f64]) -> Result<(), SundialsError> {
        self.dky(t, 1, yp)
    }

    /// The weighted local error estimate of the last step, component by component:
    /// |e_i| w_i (IDAGetEstLocalErrors times IDAGetErrWeights), where the step's error test
    /// asks for the WRMS norm of these to be at most 1. What limits the step shows here.
    pub fn weighted_local_errors(&self, out: &mut [f64]) -> Result<(), SundialsError> {
        if out.len() != self.n {
            return invalid(format!(
                "output has length {}, expected {}",
                out.len(),
                self.n
            ));
        }
        let ctx = &self._ctx;
        let mut w = NVector::new(ctx, self.n)?;
        let mut e = NVector::new(ctx, self.n)?;
        let mem = self.mem.raw();
        // SAFETY: mem, w and e are live; the getters only copy into the vectors.
        let flags = unsafe {
            (
                sundials_sys::IDAGetErrWeights(mem, w.raw()),
                sundials_sys::IDAGetEstLocalErrors(mem, e.raw()),
            )
        };
        for (name, flag) in [
            ("IDAGetErrWeights", flags.0),
            ("IDAGetEstLocalErrors", flags.1),
        ] {
            if flag != 0 {
                return Err(flag_error(name, flag, FlagFamily::Ida, None));
            }
        }
        for ((o, ei), wi) in out
            .iter_mut()
            .zip(e.as_mut_slice().iter())
            .zip(w.as_mut_slice().iter())
        {
            *o = (ei * wi).abs();
        }
        Ok(())
    }

    fn dky(&self, t: f64, k: c_int, out: &mut [f64]) -> Result<(), SundialsError> {
        if out.len() != self.n {
            return invalid(format!(
                "output has length {}, expected {}",
                out.len(),
                self.n
            ));
        }
        self.check_dense_output_time(t)?;
        self.mem.get_dky(&self.log, &self._ctx, t, k, out)
    }

    /// Refuse a t outside the last step (see [`Ida::dky`]).
    pub(crate) fn check_dense_output_time(&self, t: f64) -> Result<(), SundialsError> {
        // IDAGetDky 6.4 refuses only a t before the last step and extrapolates beyond its
        // end without complaint; refuse that too, as CVODE does, with IDA's fuzz and message.
        let s = self.stats();
        let (tn, hh) = (s.current_time, s.current_step);
        let fuzz = 100.0 * f64::EPSILON * (tn.abs() + hh.abs());
        if (t - tn) * hh.signum() > fuzz || t.is_nan() {
            let message = format!(
                "IDAGetDky: Illegal value for t. t = {t} is not between tcur - hu = {} and tcur = {tn}.",
                tn - s.last_step
            );
            return Err(flag_error(
                "IDAGetDky",
                sundials_sys::IDA_BAD_T,
                FlagFamily::Ida,
                Some(message),
            ));
        }
        Ok(())
    }

    /// The counters so far (also after a failure).
    pub fn stats(&self) -> IdaStats {
        let mem = self.mem.raw();
        // SAFETY: mem is live IDA memory, and the getters are IDA's.
        let count = |f: CountGetter| unsafe { counter(mem, f) };
        let real = |f: RealGetter| unsafe { callback::real(mem, f) };
        let mut last_order: c_int = 0;
        // SAFETY: mem is live; last_order is a valid out-pointer.
        unsafe { IDAGetLastOrder(mem, &mut last_order) };
        let own = count(IDAGetNumResEvals);
        let ls = count(IDAGetNumLinResEvals);
        IdaStats {
            steps: count(IDAGetNumSteps),
            residual_evaluations: own + ls,
            linear_solver_residual_evaluations: ls,
            jacobian_evaluations: count(IDAGetNumJacEvals),
            linear_setups: count(IDAGetNumLinSolvSetups),
            error_test_failures: count(IDAGetNumErrTestFails),
            nonlinear_iterations: count(IDAGetNumNonlinSolvIters),
            nonlinear_convergence_failures: count(IDAGetNumNonlinSolvConvFails),
            last_order,
            last_step: real(IDAGetLastStep),
            current_step: real(IDAGetCurrentStep),
            current_time: real(IDAGetCurrentTime),
        }
    }

    pub fn system(&self) -> &S {
        // SAFETY: no callback is running while we hold &self (advance_to needs &mut self).
        unsafe { &self.shared.get().system }
    }

    pub(crate) fn parts(&self) -> (&Mem, &RawBox<ErrorLog>, &Rc<Context>) {
        (&self.mem, &self.log, &self._ctx)
    }

    pub(crate) fn parts_mut(&mut self) -> (&Mem, &mut RawBox<ErrorLog>, &Rc<Context>) {
        (&self.mem, &mut self.log, &self._ctx)
    }

    pub fn system_mut(&mut self) -> &mut S {
        // SAFETY: as above, with exclusive access.
        unsafe { &mut self.shared.get_mut().system }
    }
}

impl Linear {
    /// The custom solver and its token matrix; the solver's content (the shared state) is set
    /// by the caller once that exists.
    fn custom<S: DaeSystem>(ctx: &Rc<Context>) -> Result<Self, SundialsError> {
        // Each owned (freed on drop) as soon as it exists. Of the matrix IDA 6.4 calls only
        // SUNMatZero (idaLsSetup, before each Jacobian evaluation): the token's does nothing.
        let solver = CustomSolver(custom::direct_solver(
            ctx,
            custom_setup,
            custom_solve_trampoline::<S>,
        )?);
        let token = TokenMatrix(custom::token_matrix(ctx, std::ptr::null_mut())?);
        Ok(Linear::Custom { solver, token })
    }
}

fn validate(n: usize, o: &IdaOptions) -> Result<(), SundialsError> {
    common_options!(o).validate(n)?;
    match &o.id {
        Some(id) => {
            if id.len() != n {
                return invalid(format!("id has length {}, expected {n}", id.len()));
            }
            // IDA itself only refuses negative entries (in IDACalcIC); anything but 0 and 1
            // would silently mean "differential" to some tests and not to others.
            if let Some(k) = id.iter().position(|&x| x != 0.0 && x != 1.0) {
                return invalid(format!(
                    "id[{k}] = {} must be 1.0 (differential) or 0.0 (algebraic)",
                    id[k]
                ));
            }
        }
        None if o.suppress_algebraic => {
            return invalid(
                "suppress_algebraic needs options.id (which components are algebraic)".into(),
            );
        }
        None => {}
    }
    if o.max_error_test_failures == Some(0)
        || o.max_convergence_failures == Some(0)
        || o.max_nonlinear_iterations == Some(0)
    {
        return invalid("max_error_test_failures, max_convergence_failures and max_nonlinear_iterations must be ≥ 1".into());
    }
    if let Some(c) = o.nonlinear_convergence_coefficient {
        if !(c > 0.0 && c.is_finite()) {
            return invalid(format!(
                "nonlinear_convergence_coefficient must be positive, got {c}"
            ));
        }
    }
    if let Some(d) = o.delta_cj_setup {
        if !(d > 0.0 && d < 1.0) {
            return invalid(format!("delta_cj_setup must lie in (0, 1), got {d}"));
        }
    }
    if let Some((lo, hi)) = o.fixed_step_bounds {
        if !((0.0..=1.0).contains(&lo) && hi >= 1.0 && hi.is_finite()) {
            return invalid(format!(
                "fixed_step_bounds must have 0 ≤ lo ≤ 1 ≤ hi < ∞, got ({lo}, {hi})"
            ));
        }
    }
    Ok(())
}

/// IDAResFn: r = F(t, y, y').
unsafe extern "C" fn residual_trampoline<S: DaeSystem>(
    t: realtype,
    y: N_Vector,
    yp: N_Vector,
    r: N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: `data` is the Shared<S> registered with IDASetUserData; IDA calls us from
    // inside IDASolve or IDACalcIC, while no other reference to it exists; y, yp and r are
    // distinct live serial vectors of length n, y and yp only read, r only written.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, yp, r) = unsafe { (nvector::slice(y), nvector::slice(yp), nvector::slice_mut(r)) };
    shared.guard("residual", |system| system.residual(t, y, yp, r))
}

/// IDALsJacFn for dense and band: zero M, let the system fill it, check nothing fell outside
/// its structure.
unsafe extern "C" fn jacobian_trampoline<S: DaeSystem>(
    t: realtype,
    cj: realtype,
    y: N_Vector,
    yp: N_Vector,
    r: N_Vector,
    jac: SUNMatrix,
    data: *mut c_void,
    _tmp1: N_Vector,
    _tmp2: N_Vector,
    _tmp3: N_Vector,
) -> c_int {
    // SAFETY: as in residual_trampoline; y, yp and r are live and only read.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, yp, r) = unsafe { (nvector::slice(y), nvector::slice(yp), nvector::slice(r)) };
    shared.jacobian("IDA", jac, |system, jac| {
        system.jacobian(t, cj, y, yp, r, jac)
    })
}

/// IDALsJacFn for the custom solver: the token matrix carries nothing; the system prepares
/// its own M = ∂F/∂y + cj ∂F/∂y'.
unsafe extern "C" fn linear_setup_trampoline<S: DaeSystem>(
    t: realtype,
    cj: realtype,
    y: N_Vector,
    yp: N_Vector,
    r: N_Vector,
    _jac: SUNMatrix,
    data: *mut c_void,
    _tmp1: N_Vector,
    _tmp2: N_Vector,
    _tmp3: N_Vector,
) -> c_int {
    // SAFETY: as in jacobian_trampoline.
    let shared = unsafe { Shared::<S>::from_raw(data) };
    let (y, yp, r) = unsafe { (nvector::slice(y), nvector::slice(yp), nvector::slice(r)) };
    shared.guard("linear_setup", |system| {
        system.linear_setup(t, cj, y, yp, r)
    })
}

/// SUNLinSolSolve of the custom solver: x = M⁻¹ b by the system. The flags are the ones
/// idaLsSolve understands: PACKAGE_FAIL_REC → recoverable, PACKAGE_FAIL_UNREC → fatal.
unsafe extern "C" fn custom_solve_trampoline<S: DaeSystem>(
    ls: SUNLinearSolver,
    _a: SUNMatrix,
    x: N_Vector,
    b: N_Vector,
    _tol: realtype,
) -> c_int {
    // SAFETY: the content is the Shared<S> set in Ida::new, alive as long as the solver; IDA
    // calls us from inside IDASolve or IDACalcIC, while no other reference to it exists.
    // b is only read and x only written, live vectors of length n that only this call
    // accesses (guard_in_out copies b if it is x).
    let shared = unsafe { Shared::<S>::from_raw((*ls).content) };
    let flag = unsafe {
        shared.guard_in_out("linear_solve", b, x, |system, b, x| {
            system.linear_solve(b, x)
        })
    };
    match flag {
        0 => SUNLS_SUCCESS as c_int,
        f if f > 0 => SUNLS_PACKAGE_FAIL_REC as c_int,
        _ => SUNLS_PACKAGE_FAIL_UNREC,
    }
}

/// The system's linear_setup already ran in the Jacobian function; nothing left to do.
unsafe extern "C" fn custom_setup(_ls: SUNLinearSolver, _a: SUNMatrix) -> c_int {
    SUNLS_SUCCESS as c_int
}
