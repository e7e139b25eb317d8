//! KINSOL: Newton's method (optionally with a line search) for F(u) = 0 with a direct linear
//! solver and the caller's analytic Jacobian.
//!
//! Ownership: [`Kinsol`] owns the KINSOL memory, the linear solver, the Jacobian matrix, the
//! vectors and the user's system; its fields are declared in the order they must be freed
//! (KINSOL memory → linear solver → matrix → everything else → context).

use std::os::raw::{c_int, c_long, c_void};
use std::rc::Rc;

use sundials_sys::{
    KINCreate, KINFree, KINGetFuncNorm, KINGetNumBacktrackOps, KINGetNumFuncEvals,
    KINGetNumJacEvals, KINGetNumNonlinSolvIters, KINInit, KINSetErrHandlerFn, KINSetFuncNormTol,
    KINSetJacFn, KINSetLinearSolver, KINSetMaxNewtonStep, KINSetMaxSetupCalls, KINSetNoInitSetup,
    KINSetNumMaxIters, KINSetPrintLevel, KINSetScaledStepTol, KINSetUserData, KINSol, N_Vector,
    SUNLinSolSolve, SUNMatrix, KIN_LINESEARCH, KIN_LSETUP_FAIL, KIN_NONE,
};

use super::callback::{error_handler, CallbackResult, CallbackState, ErrorLog, RawBox};
use super::context::Context;
use super::error::{check, flag_error, FlagFamily, SundialsError};
use super::linsol::{LinearSolver, LinearSolverSpec};
use super::matrix::{JacobianMatrix, Matrix};
use super::nvector::{self, NVector};

/// F(u) = 0 and its Jacobian, as KINSOL calls them.
pub trait NonlinearSystem {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult;
    /// Fill every structural entry of the Jacobian dF/du at u (entries not set are zero:
    /// the layer zeroes the matrix first).
    fn jacobian(&mut self, u: &[f64], jac: JacobianMatrix<'_>) -> CallbackResult;
}

/// KINSOL's globalisation: a full Newton step, or a line search along it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    Newton,
    #[default]
    LineSearch,
}

#[derive(Clone, Debug, PartialEq)]
pub struct KinsolOptions {
    pub strategy: Strategy,
    /// Stop when the scaled max-norm of F is below this.
    pub fnorm_tol: f64,
    /// Stop (see [`Kinsol::solve`]) when the scaled step is below this.
    pub scaled_step_tol: f64,
    pub max_iterations: usize,
    /// Iterations between Jacobian re-evaluations; 1 = a fresh Jacobian every iteration.
    pub max_setup_calls: usize,
    /// Largest scaled Newton step; None = KINSOL's default (1000 ‖u₀ · u_scale‖).
    pub max_newton_step: Option<f64>,
    /// Start each solve with the factorisation of the previous one (KINSetNoInitSetup), when
    /// there is one: modified Newton across a sequence of nearby problems.
    pub reuse_factorization: bool,
}

impl Default for KinsolOptions {
    /// KINSOL's own defaults, with a line search.
    fn default() -> Self {
        KinsolOptions {
            strategy: Strategy::LineSearch,
            fnorm_tol: f64::EPSILON.cbrt(),
            scaled_step_tol: f64::EPSILON.powf(2.0 / 3.0),
            max_iterations: 200,
            max_setup_calls: 10,
            max_newton_step: None,
            reuse_factorization: false,
        }
    }
}

/// Counters of the last [`Kinsol::solve`] (KINSOL resets them at each call).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KinsolStats {
    pub iterations: usize,
    pub residual_evaluations: usize,
    /// Calls of [`NonlinearSystem::jacobian`].
    pub jacobian_evaluations: usize,
    /// Linear solver setups (each evaluates and factorises a Jacobian).
    pub linear_setups: usize,
    pub backtracks: usize,
    /// KINGetFuncNorm: the scaled max-norm of F at the last iterate.
    pub fnorm: f64,
}

/// What the trampolines reach through KINSOL's user-data pointer.
struct Shared<S> {
    system: S,
    matrix: Matrix,
    callbacks: CallbackState,
    jacobian_calls: usize,
    /// KINSOL began a linear setup during this solve: it zeroed the matrix (for dense and
    /// band, the old LU factors) before calling the Jacobian trampoline.
    setup_started: bool,
}

/// KINSOL memory, freed with KINFree.
struct KinMem(*mut c_void);

impl Drop for KinMem {
    fn drop(&mut self) {
        // SAFETY: the pointer came from KINCreate and is freed once (KINFree nulls it).
        unsafe { KINFree(&mut self.0) }
    }
}

pub struct Kinsol<S: NonlinearSystem> {
    // Drop order = declaration order. KINSOL points at the linear solver, the matrix (in
    // `shared`), the error log and the user data, so it goes first.
    mem: KinMem,
    linsol: LinearSolver,
    shared: RawBox<Shared<S>>,
    log: RawBox<ErrorLog>,
    u: NVector,
    u_scale: NVector,
    f_scale: NVector,
    /// Right-hand side and solution of [`solve_with_last_factorization`](Self::solve_with_last_factorization).
    lin_b: NVector,
    lin_x: NVector,
    /// Whether the linear solver holds the factorisation of KINSOL's last Jacobian setup.
    factored: bool,
    options: KinsolOptions,
    last_stats: KinsolStats,
    n: usize,
    _ctx: Rc<Context>,
}

impl<S: NonlinearSystem> Kinsol<S> {
    pub fn new(
        system: S,
        n: usize,
        linear: LinearSolverSpec,
        options: &KinsolOptions,
    ) -> Result<Self, SundialsError> {
        if n == 0 {
            return Err(SundialsError::Invalid(
                "KINSOL needs at least one unknown".into(),
            ));
        }
        let ctx = Context::new()?;
        let (matrix, linsol) = LinearSolver::for_spec(&ctx, n, &linear)?;
        let shared = RawBox::new(Shared {
            system,
            matrix,
            callbacks: CallbackState::default(),
            jacobian_calls: 0,
            setup_started: false,
        });
        let log = RawBox::new(ErrorLog::default());
        let u = NVector::new(&ctx, n)?;
        let u_scale = NVector::new(&ctx, n)?;
        let f_scale = NVector::new(&ctx, n)?;
        let lin_b = NVector::new(&ctx, n)?;
        let lin_x = NVector::new(&ctx, n)?;
        // SAFETY: ctx is live.
        let raw = unsafe { KINCreate(ctx.raw()) };
        if raw.is_null() {
            return Err(SundialsError::NullHandle("KINCreate"));
        }
        let mut kin = Kinsol {
            mem: KinMem(raw),
            linsol,
            shared,
            log,
            u,
            u_scale,
            f_scale,
            lin_b,
            lin_x,
            factored: false,
            options: options.clone(),
            last_stats: KinsolStats::default(),
            n,
            _ctx: ctx,
        };
        kin.init()?;
        kin.set_options(options)?;
        Ok(kin)
    }

    fn init(&mut self) -> Result<(), SundialsError> {
        let mem = self.mem.0;
        let log = self.log.as_void();
        let data = self.shared.as_void();
        let tmpl = self.u.raw();
        let ls = self.linsol.raw();
        // SAFETY: the matrix is only read for its handle.
        let a = unsafe { self.shared.get().matrix.raw() };
        // SAFETY (all calls): `mem` is live KINSOL memory; the error log, the user data, the
        // template vector, linear solver and matrix all outlive it (field order).
        self.log
            .call("KINSetErrHandlerFn", FlagFamily::Kin, || unsafe {
                KINSetErrHandlerFn(mem, Some(error_handler), log)
            })?;
        self.log
            .call("KINSetPrintLevel", FlagFamily::Kin, || unsafe {
                KINSetPrintLevel(mem, 0)
            })?;
        self.log
            .call("KINSetUserData", FlagFamily::Kin, || unsafe {
                KINSetUserData(mem, data)
            })?;
        self.log.call("KINInit", FlagFamily::Kin, || unsafe {
            KINInit(mem, Some(residual_trampoline::<S>), tmpl)
        })?;
        self.log
            .call("KINSetLinearSolver", FlagFamily::KinLs, || unsafe {
                KINSetLinearSolver(mem, ls, a)
            })?;
        self.log.call("KINSetJacFn", FlagFamily::KinLs, || unsafe {
            KINSetJacFn(mem, Some(jacobian_trampoline::<S>))
        })?;
        Ok(())
    }

    pub fn set_options(&mut self, options: &KinsolOptions) -> Result<(), SundialsError> {
        let invalid = |what: String| Err(SundialsError::Invalid(what));
        if !(options.fnorm_tol > 0.0 && options.fnorm_tol.is_finite()) {
            return invalid(format!(
                "fnorm_tol must be positive, got {}",
                options.fnorm_tol
            ));
        }
        if !(options.scaled_step_tol > 0.0 && options.scaled_step_tol.is_finite()) {
            return invalid(format!(
                "scaled_step_tol must be positive, got {}",
                options.scaled_step_tol
            ));
        }
        if options.max_iterations == 0 || options.max_setup_calls == 0 {
            return invalid("max_iterations and max_setup_calls must be ≥ 1".into());
        }
        if let Some(step) = options.max_newton_step {
            if !(step > 0.0 && step.is_finite()) {
                return invalid(format!("max_newton_step must be positive, got {step}"));
            }
        }
        let mem = self.mem.0;
        let long = |n: usize| c_long::try_from(n).unwrap_or(c_long::MAX);
        // SAFETY (all calls): `mem` is live KINSOL memory; the arguments are plain numbers.
        self.log
            .call("KINSetFuncNormTol", FlagFamily::Kin, || unsafe {
                KINSetFuncNormTol(mem, options.fnorm_tol)
            })?;
        self.log
            .call("KINSetScaledStepTol", FlagFamily::Kin, || unsafe {
                KINSetScaledStepTol(mem, options.scaled_step_tol)
            })?;
        self.log
            .call("KINSetNumMaxIters", FlagFamily::Kin, || unsafe {
                KINSetNumMaxIters(mem, long(options.max_iterations))
            })?;
        self.log
            .call("KINSetMaxSetupCalls", FlagFamily::Kin, || unsafe {
                KINSetMaxSetupCalls(mem, long(options.max_setup_calls))
            })?;
        // 0 asks KINSOL for its default.
        let step = options.max_newton_step.unwrap_or(0.0);
        self.log
            .call("KINSetMaxNewtonStep", FlagFamily::Kin, || unsafe {
                KINSetMaxNewtonStep(mem, step)
            })?;
        self.options = options.clone();
        Ok(())
    }

    pub fn options(&self) -> &KinsolOptions {
        &self.options
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// Solve F(u) = 0 from the guess in `u`; on success `u` holds the root. Scales are
    /// KINSOL's u_scale and f_scale (positive entries).
    ///
    /// KIN_SUCCESS and KIN_INITIAL_GUESS_OK are success; KIN_STEP_LT_STPTOL (the step
    /// stalled) is success only if ‖F‖ ≤ 100 · fnorm_tol. On failure `u` holds KINSOL's last
    /// iterate and [`last_stats`](Self::last_stats) the counters so far.
    pub fn solve(
        &mut self,
        u: &mut [f64],
        u_scale: &[f64],
        f_scale: &[f64],
    ) -> Result<KinsolStats, SundialsError> {
        let n = self.n;
        if u.len() != n || u_scale.len() != n || f_scale.len() != n {
            return Err(SundialsError::Invalid(format!(
                "solve needs u, u_scale and f_scale of length {n}, got {}, {}, {}",
                u.len(),
                u_scale.len(),
                f_scale.len()
            )));
        }
        for (name, s) in [("u_scale", u_scale), ("f_scale", f_scale)] {
            if let Some(k) = s.iter().position(|&x| !(x > 0.0 && x.is_finite())) {
                return Err(SundialsError::Invalid(format!(
                    "{name}[{k}] = {} is not positive",
                    s[k]
                )));
            }
        }
        self.u.as_mut_slice().copy_from_slice(u);
        self.u_scale.as_mut_slice().copy_from_slice(u_scale);
        self.f_scale.as_mut_slice().copy_from_slice(f_scale);
        // SAFETY: no callback is running.
        unsafe {
            let shared = self.shared.get_mut();
            shared.callbacks.reset();
            shared.jacobian_calls = 0;
            shared.setup_started = false;
            self.log.get_mut().clear();
        }
        let strategy = match self.options.strategy {
            Strategy::Newton => KIN_NONE,
            Strategy::LineSearch => KIN_LINESEARCH,
        };
        // Skip the first setup only when a factorisation exists to start from.
        let no_init_setup = self.options.reuse_factorization && self.factored;
        // SAFETY: `mem` is live KINSOL memory; the argument is a plain boolean.
        let mem = self.mem.0;
        self.log
            .call("KINSetNoInitSetup", FlagFamily::Kin, || unsafe {
                KINSetNoInitSetup(mem, no_init_setup as _)
            })?;
        // SAFETY: every handle is live; during the call the only references to the shared
        // state and the log are the short-lived ones the trampolines create.
        let flag = unsafe {
            KINSol(
                self.mem.0,
                self.u.raw(),
                strategy,
                self.u_scale.raw(),
                self.f_scale.raw(),
            )
        };
        u.copy_from_slice(self.u.as_slice());
        let stats = self.collect_stats();
        self.last_stats = stats;
        // SAFETY: KINSol has returned; no callback is running.
        let (fatal, recoverable, logged, setup_started, factor_error) = unsafe {
            let shared = self.shared.get_mut();
            let factor_error = match &shared.matrix {
                Matrix::Block(m) if flag == KIN_LSETUP_FAIL => m.last_error().map(str::to_string),
                _ => None,
            };
            (
                shared.callbacks.fatal.take(),
                shared.callbacks.last_recoverable.take(),
                self.log.get().last_message(),
                shared.setup_started,
                factor_error,
            )
        };
        // Every setup KINSOL begins zeroes and refills the matrix, which for dense and band
        // held the old LU factors. KINSOL stops with KIN_LSETUP_FAIL whenever a setup fails
        // (the Jacobian callback or SUNLinSolSetup), so any other outcome means the last
        // setup succeeded. With no setup in this call the previous factorisation is
        // untouched. (Not KINGetNumJacEvals: KINSOL does not reset it when the initial guess
        // is already a root, so it can be the previous call's count.)
        if setup_started {
            self.factored = flag != KIN_LSETUP_FAIL;
        }
        let name = FlagFamily::Kin.name(flag);
        match flag {
            0 | 1 => Ok(stats),
            2 if stats.fnorm <= 100.0 * self.options.fnorm_tol => Ok(stats),
            2 => Err(flag_error(
                "KINSol",
                flag,
                FlagFamily::Kin,
                Some(format!(
                    "the scaled step fell below scaled_step_tol = {:e} while the scaled ‖F‖ = {:e} > 100 · fnorm_tol = {:e}: stalled, not converged",
                    self.options.scaled_step_tol,
                    stats.fnorm,
                    100.0 * self.options.fnorm_tol
                )),
            )),
            _ => {
                if let Some(m) = fatal {
                    return Err(SundialsError::Callback(format!("{m} (KINSol stopped with {name})")));
                }
                let mut message = logged.unwrap_or_else(|| FlagFamily::Kin.describe(flag).1.to_string());
                if let Some(r) = recoverable {
                    message.push_str(&format!("; last recoverable callback error: {r}"));
                }
                if let Some(e) = factor_error {
                    message.push_str(&format!("; {e}"));
                }
                Err(flag_error("KINSol", flag, FlagFamily::Kin, Some(message)))
            }
        }
    }

    fn collect_stats(&self) -> KinsolStats {
        let mem = self.mem.0;
        // SAFETY: mem is live KINSOL memory, and the getters are KINSOL's.
        let count = |f: super::callback::CountGetter| unsafe { super::callback::counter(mem, f) };
        let mut fnorm = f64::NAN;
        // SAFETY: mem is live; fnorm is a valid out-pointer.
        unsafe { KINGetFuncNorm(mem, &mut fnorm) };
        KinsolStats {
            iterations: count(KINGetNumNonlinSolvIters),
            residual_evaluations: count(KINGetNumFuncEvals),
            // SAFETY: read of a plain counter; no callback is running.
            jacobian_evaluations: unsafe { self.shared.get().jacobian_calls },
            linear_setups: count(KINGetNumJacEvals),
            backtracks: count(KINGetNumBacktrackOps),
            fnorm,
        }
    }

    /// Solve J x = b with the factorisation KINSOL made at its last Jacobian setup (the
    /// linear solver's SUNLinSolSolve on the matrix KINSOL holds), without a new setup.
    ///
    /// J is the Jacobian at the iterate where KINSOL last set up: never the root itself
    /// (KINSOL stops as soon as F is small there), but with `max_setup_calls = 1` the iterate
    /// one Newton step before it, so after a successful [`solve`](Self::solve) this applies
    /// the inverse Jacobian at nearly the root cheaply (e.g. implicit-function-theorem
    /// products). The system's own record of its Jacobian calls says where exactly. A solve
    /// that makes no setup (initial guess already a root) keeps the previous factorisation.
    /// `Invalid` if no setup has succeeded since creation, or the last one failed.
    pub fn solve_with_last_factorization(
        &mut self,
        x: &mut [f64],
        b: &[f64],
    ) -> Result<(), SundialsError> {
        let n = self.n;
        if x.len() != n || b.len() != n {
            return Err(SundialsError::Invalid(format!(
                "solve_with_last_factorization needs x and b of length {n}, got {} and {}",
                x.len(),
                b.len()
            )));
        }
        if !self.factored {
            return Err(SundialsError::Invalid(
                "no factorisation to solve with: KINSOL has made no successful Jacobian setup (call solve first)".into(),
            ));
        }
        self.lin_b.as_mut_slice().copy_from_slice(b);
        // SAFETY: the matrix is only read for its handle; no callback is running.
        let a = unsafe { self.shared.get().matrix.raw() };
        // SAFETY: the linear solver, the matrix KINSOL factorised with it and both vectors
        // are live; direct solvers copy b into x and solve in place, leaving the matrix and
        // the factors as they are.
        let flag = unsafe {
            SUNLinSolSolve(
                self.linsol.raw(),
                a,
                self.lin_x.raw(),
                self.lin_b.raw(),
                0.0,
            )
        };
        check("SUNLinSolSolve", flag, FlagFamily::SunLs, None)?;
        x.copy_from_slice(self.lin_x.as_slice());
        Ok(())
    }

    /// The counters of the last solve, also after a failure.
    pub fn last_stats(&self) -> KinsolStats {
        self.last_stats
    }

    pub fn system(&self) -> &S {
        // SAFETY: no callback is running while we hold &self (solve needs &mut self).
        unsafe { &self.shared.get().system }
    }

    pub fn system_mut(&mut self) -> &mut S {
        // SAFETY: as above, with exclusive access.
        unsafe { &mut self.shared.get_mut().system }
    }
}

/// KINSysFn: F(u) into fval.
unsafe extern "C" fn residual_trampoline<S: NonlinearSystem>(
    uu: N_Vector,
    fval: N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: `data` is the Shared<S> registered with KINSetUserData; KINSOL calls us from
    // inside KINSol, while no other reference to it exists; uu and fval are distinct live
    // serial vectors of length n.
    let shared = unsafe { &mut *(data as *mut Shared<S>) };
    let (u, f) = unsafe { (nvector::slice(uu), nvector::slice_mut(fval)) };
    let Shared {
        system, callbacks, ..
    } = shared;
    callbacks.guard("residual", || system.residual(u, f))
}

/// KINLsJacFn: zero J, let the system fill it, check nothing fell outside its structure.
unsafe extern "C" fn jacobian_trampoline<S: NonlinearSystem>(
    uu: N_Vector,
    _fu: N_Vector,
    jac: SUNMatrix,
    data: *mut c_void,
    _tmp1: N_Vector,
    _tmp2: N_Vector,
) -> c_int {
    // SAFETY: as in residual_trampoline.
    let shared = unsafe { &mut *(data as *mut Shared<S>) };
    let u = unsafe { nvector::slice(uu) };
    let Shared {
        system,
        matrix,
        callbacks,
        jacobian_calls,
        setup_started,
    } = shared;
    *setup_started = true;
    if jac != matrix.raw() {
        return callbacks.fail("KINSOL passed a Jacobian matrix this layer did not create".into());
    }
    *jacobian_calls += 1;
    callbacks.guard("jacobian", || {
        // fill_jacobian zeroes first, which also rewrites a sparse matrix's pattern that
        // KINSOL's SUNMatZero cleared.
        matrix.fill_jacobian(|jac| system.jacobian(u, jac))
    })
}
