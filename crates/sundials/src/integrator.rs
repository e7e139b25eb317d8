//! What CVODE and IDA share: both are variable-order BDF codes of the same suite, and the
//! options, checks and calls that mean the same in both are written here once. What only
//! looks alike (the systems' callbacks, the linear solvers, the counters each reports, the
//! length checks that name different vectors) stays in [`cvode`](super::cvode) and
//! [`ida`](super::ida).
//!
//! The C functions differ only by prefix (CVodeSetMaxOrd, IDASetMaxOrd); each integrator
//! lists its own in an [`Api`] table, and [`Mem`], the integrator memory, calls them through
//! it.

use std::os::raw::{c_int, c_long, c_void};
use std::rc::Rc;

use sundials_sys::{realtype, N_Vector, SUNMatrix};

use super::callback::{
    self, error_handler, CallbackResult, CallbackState, ErrorLog, RawBox, RealGetter,
};
use super::context::Context;
use super::error::{flag_error, FlagFamily, SundialsError};
use super::matrix::{JacobianMatrix, Matrix};
use super::nvector::{self, NVector};

pub(crate) fn invalid<T>(what: String) -> Result<T, SundialsError> {
    Err(SundialsError::Invalid(what))
}

pub(crate) fn to_int(what: &str, n: usize) -> Result<c_int, SundialsError> {
    c_int::try_from(n).map_err(|_| SundialsError::Invalid(format!("{what} = {n} is too large")))
}

/// What the trampolines reach through the integrator's user-data pointer (and, for IDA's
/// custom solver, through the linear solver's content pointer).
pub(crate) struct Shared<S> {
    pub(crate) system: S,
    /// The matrix of a direct solver.
    matrix: Option<Matrix>,
    callbacks: CallbackState,
    /// Input copy for a callback whose input and output vectors coincide.
    scratch: Vec<f64>,
}

impl<S> Shared<S> {
    /// The state of a system of n unknowns.
    pub(crate) fn new(system: S, matrix: Option<Matrix>, n: usize) -> Self {
        Shared {
            system,
            matrix,
            callbacks: CallbackState::default(),
            scratch: vec![0.0; n],
        }
    }

    /// The shared state behind the pointer a trampoline was given.
    ///
    /// # Safety
    /// `data` must be the address of a live `Shared<S>` (the user data, or the custom
    /// solver's content) to which no other reference exists while the result lives: true
    /// inside a callback, which CVODE and IDA make only from inside the call that solves.
    pub(crate) unsafe fn from_raw<'a>(data: *mut c_void) -> &'a mut Self {
        &mut *(data as *mut Self)
    }

    /// The matrix's handle, NULL for a solver without one.
    pub(crate) fn matrix_raw(&self) -> SUNMatrix {
        self.matrix
            .as_ref()
            .map_or(std::ptr::null_mut(), |m| m.raw())
    }

    /// Run a callback of the system under the guard (see [`CallbackState::guard`]).
    pub(crate) fn guard(
        &mut self,
        what: &'static str,
        f: impl FnOnce(&mut S) -> CallbackResult,
    ) -> c_int {
        let Shared {
            system, callbacks, ..
        } = self;
        callbacks.guard(what, || f(system))
    }

    /// A Jacobian callback of a direct solver: check that `jac` is the matrix this layer
    /// created (`solver` names the integrator in the error), then let `f` fill it (see
    /// [`Matrix::fill_jacobian`]).
    pub(crate) fn jacobian(
        &mut self,
        solver: &str,
        jac: SUNMatrix,
        f: impl FnOnce(&mut S, JacobianMatrix<'_>) -> CallbackResult,
    ) -> c_int {
        let Shared {
            system,
            matrix,
            callbacks,
            ..
        } = self;
        let Some(matrix) = matrix.as_mut().filter(|m| m.raw() == jac) else {
            return callbacks.fail(format!(
                "{solver} passed a Jacobian matrix this layer did not create"
            ));
        };
        callbacks.guard("jacobian", || matrix.fill_jacobian(|jac| f(system, jac)))
    }

    /// Run a callback that reads `input` and writes `output` under the guard. SUNDIALS may
    /// pass the same vector as both: the input is then copied to the scratch buffer first,
    /// so that the slices never alias.
    ///
    /// # Safety
    /// `input` and `output` must be live serial vectors of length n that nothing else
    /// accesses during the call.
    pub(crate) unsafe fn guard_in_out(
        &mut self,
        what: &'static str,
        input: N_Vector,
        output: N_Vector,
        f: impl FnOnce(&mut S, &[f64], &mut [f64]) -> CallbackResult,
    ) -> c_int {
        let Shared {
            system,
            callbacks,
            scratch,
            ..
        } = self;
        let out = nvector::slice_mut(output);
        let input: &[f64] = if input == output {
            scratch.copy_from_slice(out);
            &scratch[..]
        } else {
            nvector::slice(input)
        };
        callbacks.guard(what, || f(system, input, out))
    }
}

/// The options [`CvodeOptions`](super::CvodeOptions) and [`IdaOptions`](super::IdaOptions)
/// both have, with the same meaning, borrowed from either by [`common_options!`].
pub(crate) struct CommonOptions<'a> {
    pub(crate) rtol: f64,
    pub(crate) atol: f64,
    pub(crate) atol_vector: Option<&'a [f64]>,
    pub(crate) max_steps: usize,
    pub(crate) max_order: usize,
    pub(crate) initial_step: Option<f64>,
    pub(crate) max_step: Option<f64>,
    pub(crate) stop_time: Option<f64>,
    pub(crate) max_error_test_failures: Option<usize>,
    pub(crate) max_convergence_failures: Option<usize>,
}

/// The [`CommonOptions`] of a `CvodeOptions` or an `IdaOptions` (the two name these fields
/// alike; a macro rather than two `From` impls that would repeat the list).
macro_rules! common_options {
    ($o:expr) => {{
        let o = $o;
        $crate::integrator::CommonOptions {
            rtol: o.rtol,
            atol: o.atol,
            atol_vector: o.atol_vector.as_deref(),
            max_steps: o.max_steps,
            max_order: o.max_order,
            initial_step: o.initial_step,
            max_step: o.max_step,
            stop_time: o.stop_time,
            max_error_test_failures: o.max_error_test_failures,
            max_convergence_failures: o.max_convergence_failures,
        }
    }};
}
pub(crate) use common_options;

impl CommonOptions<'_> {
    /// The checks of the shared options for n unknowns, in the order both integrators make
    /// them, before their own (the failure limits are left to each: their messages differ,
    /// as IDA checks a third limit with them).
    pub(crate) fn validate(&self, n: usize) -> Result<(), SundialsError> {
        let o = self;
        let nonneg = |x: f64| x >= 0.0 && x.is_finite();
        if !nonneg(o.rtol) || !nonneg(o.atol) {
            return invalid(format!(
                "rtol and atol must be finite and ≥ 0, got {} and {}",
                o.rtol, o.atol
            ));
        }
        if let Some(v) = o.atol_vector {
            if v.len() != n {
                return invalid(format!("atol_vector has length {}, expected {n}", v.len()));
            }
            if let Some(k) = v.iter().position(|&x| !nonneg(x)) {
                return invalid(format!("atol_vector[{k}] = {} is not finite and ≥ 0", v[k]));
            }
        }
        if o.max_steps == 0 {
            return invalid("max_steps must be ≥ 1".into());
        }
        if !(1..=5).contains(&o.max_order) {
            return invalid(format!(
                "max_order must be 1 ..= 5 for BDF, got {}",
                o.max_order
            ));
        }
        if let Some(h) = o.initial_step {
            if !(h.is_finite() && h != 0.0) {
                return invalid(format!("initial_step must be finite and nonzero, got {h}"));
            }
        }
        if let Some(h) = o.max_step {
            if !(h > 0.0 && h.is_finite()) {
                return invalid(format!("max_step must be positive, got {h}"));
            }
        }
        if let Some(t) = o.stop_time {
            if !t.is_finite() {
                return invalid(format!("stop_time {t} is not finite"));
            }
        }
        Ok(())
    }
}

/// A C function of an integrator with its name, for errors.
pub(crate) type Named<F> = (&'static str, F);

/// `(name, function)` for a table entry.
macro_rules! named {
    ($f:ident) => {
        (stringify!($f), $f)
    };
}
pub(crate) use named;

type Setter<T> = unsafe extern "C" fn(*mut c_void, T) -> c_int;

/// The functions of CVODE's or IDA's C API that do the same thing in both.
pub(crate) struct Api {
    /// The flags of the integrator's own functions (CV_*, IDA_*).
    pub(crate) family: FlagFamily,
    /// The name of the function that creates the memory, for [`Mem::new`].
    pub(crate) create: &'static str,
    pub(crate) free: unsafe extern "C" fn(*mut *mut c_void),
    pub(crate) set_err_handler_fn: Named<
        unsafe extern "C" fn(*mut c_void, sundials_sys::CVErrHandlerFn, *mut c_void) -> c_int,
    >,
    pub(crate) set_user_data: Named<Setter<*mut c_void>>,
    pub(crate) ss_tolerances: Named<unsafe extern "C" fn(*mut c_void, realtype, realtype) -> c_int>,
    pub(crate) sv_tolerances: Named<unsafe extern "C" fn(*mut c_void, realtype, N_Vector) -> c_int>,
    pub(crate) set_max_num_steps: Named<Setter<c_long>>,
    pub(crate) set_max_ord: Named<Setter<c_int>>,
    pub(crate) set_init_step: Named<Setter<realtype>>,
    pub(crate) set_max_step: Named<Setter<realtype>>,
    pub(crate) set_stop_time: Named<Setter<realtype>>,
    pub(crate) set_max_err_test_fails: Named<Setter<c_int>>,
    pub(crate) set_max_conv_fails: Named<Setter<c_int>>,
    pub(crate) get_current_time: RealGetter,
    pub(crate) get_dky:
        Named<unsafe extern "C" fn(*mut c_void, realtype, c_int, N_Vector) -> c_int>,
}

/// CVODE or IDA memory, freed on drop with the integrator's own function.
///
/// Invariant: `raw` is live memory of the integrator `api` describes, owned by this value.
pub(crate) struct Mem {
    raw: *mut c_void,
    api: &'static Api,
}

impl Mem {
    /// Own the memory `raw` just returned by `api.create` (NULL is an error).
    ///
    /// # Safety
    /// `raw` must be NULL or memory of the integrator `api` describes that nothing else
    /// owns.
    pub(crate) unsafe fn new(api: &'static Api, raw: *mut c_void) -> Result<Self, SundialsError> {
        if raw.is_null() {
            return Err(SundialsError::NullHandle(api.create));
        }
        Ok(Mem { raw, api })
    }

    pub(crate) fn raw(&self) -> *mut c_void {
        self.raw
    }

    /// Call the setter `f` of this memory's integrator with `value`.
    ///
    /// # Safety
    /// `f` must come from `self.api`, and `value` must stay valid for as long as the
    /// integrator keeps it (plain numbers: no condition).
    unsafe fn set<T>(
        &self,
        log: &mut RawBox<ErrorLog>,
        (name, f): Named<Setter<T>>,
        value: T,
    ) -> Result<(), SundialsError> {
        let mem = self.raw;
        // SAFETY: `mem` is live memory of the integrator `f` belongs to (invariant and
        // contract); the value is valid (contract).
        log.call(name, self.api.family, || unsafe { f(mem, value) })
    }

    /// Send the integrator's messages to `log` and hand `user_data` to the callbacks: the
    /// first calls after creation.
    ///
    /// # Safety
    /// `log` and `user_data` must outlive this memory (the owner frees the memory first).
    pub(crate) unsafe fn attach(
        &self,
        log: &mut RawBox<ErrorLog>,
        user_data: *mut c_void,
    ) -> Result<(), SundialsError> {
        let (mem, log_data) = (self.raw, log.as_void());
        let (name, set_err_handler_fn) = self.api.set_err_handler_fn;
        // SAFETY: `mem` is live (invariant); the log outlives it (contract).
        log.call(name, self.api.family, || unsafe {
            set_err_handler_fn(mem, Some(error_handler), log_data)
        })?;
        // SAFETY: the user data outlives the memory (contract).
        unsafe { self.set(log, self.api.set_user_data, user_data) }
    }

    /// The relative and absolute tolerances: scalar, or per component (the integrator
    /// copies the vector).
    pub(crate) fn set_tolerances(
        &self,
        log: &mut RawBox<ErrorLog>,
        ctx: &Rc<Context>,
        o: &CommonOptions,
    ) -> Result<(), SundialsError> {
        let mem = self.raw;
        match o.atol_vector {
            None => {
                let (name, ss_tolerances) = self.api.ss_tolerances;
                // SAFETY: `mem` is live (invariant).
                log.call(name, self.api.family, || unsafe {
                    ss_tolerances(mem, o.rtol, o.atol)
                })
            }
            Some(atol) => {
                let atol = NVector::from_slice(ctx, atol)?;
                let (name, sv_tolerances) = self.api.sv_tolerances;
                // SAFETY: `mem` and `atol` are live; the integrator copies `atol`.
                log.call(name, self.api.family, || unsafe {
                    sv_tolerances(mem, o.rtol, atol.raw())
                })
            }
        }
    }

    /// The shared options that steer the stepping: step count, order, step sizes, stop
    /// time, failure limits (checked by [`CommonOptions::validate`] before).
    pub(crate) fn set_step_controls(
        &self,
        log: &mut RawBox<ErrorLog>,
        o: &CommonOptions,
    ) -> Result<(), SundialsError> {
        let api = self.api;
        let long = |n: usize| c_long::try_from(n).unwrap_or(c_long::MAX);
        // SAFETY (all calls): the setters are this integrator's and take plain numbers.
        unsafe {
            self.set(log, api.set_max_num_steps, long(o.max_steps))?;
            self.set(log, api.set_max_ord, to_int("max_order", o.max_order)?)?;
            if let Some(h) = o.initial_step {
                self.set(log, api.set_init_step, h)?;
            }
            if let Some(h) = o.max_step {
                self.set(log, api.set_max_step, h)?;
            }
            if let Some(t) = o.stop_time {
                self.set(log, api.set_stop_time, t)?;
            }
            if let Some(k) = o.max_error_test_failures {
                let k = to_int("max_error_test_failures", k)?;
                self.set(log, api.set_max_err_test_fails, k)?;
            }
            if let Some(k) = o.max_convergence_failures {
                let k = to_int("max_convergence_failures", k)?;
                self.set(log, api.set_max_conv_fails, k)?;
            }
        }
        Ok(())
    }

    /// Do not step past `t` (SetStopTime), which must be finite.
    pub(crate) fn set_stop_time(
        &self,
        log: &mut RawBox<ErrorLog>,
        t: f64,
    ) -> Result<(), SundialsError> {
        if !t.is_finite() {
            return invalid(format!("stop time {t} is not finite"));
        }
        // SAFETY: the setter is this integrator's and takes a plain number.
        unsafe { self.set(log, self.api.set_stop_time, t) }
    }

    /// The time the integrator has reached (GetCurrentTime); NaN if it cannot say.
    pub(crate) fn current_time(&self) -> f64 {
        // SAFETY: `raw` is live memory of the integrator the getter belongs to (invariant).
        unsafe { callback::real(self.raw, self.api.get_current_time) }
    }

    /// Dense output of the last step (GetDky): the k-th derivative of the interpolating
    /// polynomial at `t` into `out`, whose length the caller has checked.
    pub(crate) fn get_dky(
        &self,
        log: &RawBox<ErrorLog>,
        ctx: &Context,
        t: f64,
        k: c_int,
        out: &mut [f64],
    ) -> Result<(), SundialsError> {
        let (mem, (name, get_dky)) = (self.raw, self.api.get_dky);
        // SAFETY: mem and the borrowed vector are live; GetDky calls no user callback.
        // The error handler may write to the log through its raw pointer; no reference to
        // the log is alive.
        let flag = NVector::with_borrowed(ctx, out, |v| unsafe { get_dky(mem, t, k, v) })?;
        if flag == 0 {
            return Ok(());
        }
        // The log is not cleared here (that needs &mut self); GetDky reports every failure
        // to the handler, so the last message is this call's.
        // SAFETY: GetDky has returned.
        let message = unsafe { log.get().last_message() };
        Err(flag_error(name, flag, self.api.family, message))
    }

    /// Turn the flag of a call that ran the callbacks (CVode, IDASolve, IDACalcIC) into a
    /// Result carrying what the callbacks (whose reports it takes) and the integrator
    /// reported. A fatal callback error or panic wins, with the flag and the time reached;
    /// otherwise the integrator's message (or the flag's description), with the last
    /// recoverable callback error.
    pub(crate) fn finish<S>(
        &self,
        shared: &mut RawBox<Shared<S>>,
        log: &RawBox<ErrorLog>,
        function: &'static str,
        flag: c_int,
    ) -> Result<(), SundialsError> {
        let family = self.api.family;
        // SAFETY: the integrator has returned; no callback is running.
        let (fatal, recoverable, logged) = unsafe {
            let shared = shared.get_mut();
            (
                shared.callbacks.fatal.take(),
                shared.callbacks.last_recoverable.take(),
                log.get().last_message(),
            )
        };
        if flag >= 0 {
            return Ok(());
        }
        let name = family.name(flag);
        if let Some(m) = fatal {
            let t = self.current_time();
            return Err(SundialsError::Callback(format!(
                "{m} ({function} stopped with {name} at t = {t:e})"
            )));
        }
        let mut message = logged.unwrap_or_else(|| family.describe(flag).1.to_string());
        if let Some(r) = recoverable {
            message.push_str(crate::error::RECOVERABLE_NOTE);
            message.push_str(&r);
        }
        Err(flag_error(function, flag, family, Some(message)))
    }
}

impl Drop for Mem {
    fn drop(&mut self) {
        // SAFETY: the memory is live and ours (invariant) and freed once (the free function
        // nulls the pointer).
        unsafe { (self.api.free)(&mut self.raw) }
    }
}

/// Forget what the callbacks and the integrator reported during an earlier call.
pub(crate) fn reset_reports<S>(shared: &mut RawBox<Shared<S>>, log: &mut RawBox<ErrorLog>) {
    // SAFETY: no callback is running.
    unsafe {
        shared.get_mut().callbacks.reset();
        log.get_mut().clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CvodeOptions, IdaOptions};

    /// The messages of the shared checks, word for word as CVODE's and IDA's validation
    /// gave them before they were written once.
    #[test]
    fn shared_checks_report_the_same_messages_for_both_integrators() {
        type Case = (&'static str, fn(&mut CvodeOptions), fn(&mut IdaOptions));
        let cases: [Case; 9] = [
            (
                "rtol and atol must be finite and ≥ 0, got -1 and 0.00000001",
                |o| o.rtol = -1.0,
                |o| o.rtol = -1.0,
            ),
            (
                "rtol and atol must be finite and ≥ 0, got 0.000001 and NaN",
                |o| o.atol = f64::NAN,
                |o| o.atol = f64::NAN,
            ),
            (
                "atol_vector has length 1, expected 2",
                |o| o.atol_vector = Some(vec![1.0]),
                |o| o.atol_vector = Some(vec![1.0]),
            ),
            (
                "atol_vector[1] = -1 is not finite and ≥ 0",
                |o| o.atol_vector = Some(vec![1.0, -1.0]),
                |o| o.atol_vector = Some(vec![1.0, -1.0]),
            ),
            (
                "max_steps must be ≥ 1",
                |o| o.max_steps = 0,
                |o| o.max_steps = 0,
            ),
            (
                "max_order must be 1 ..= 5 for BDF, got 6",
                |o| o.max_order = 6,
                |o| o.max_order = 6,
            ),
            (
                "initial_step must be finite and nonzero, got 0",
                |o| o.initial_step = Some(0.0),
                |o| o.initial_step = Some(0.0),
            ),
            (
                "max_step must be positive, got -1",
                |o| o.max_step = Some(-1.0),
                |o| o.max_step = Some(-1.0),
            ),
            (
                "stop_time inf is not finite",
                |o| o.stop_time = Some(f64::INFINITY),
                |o| o.stop_time = Some(f64::INFINITY),
            ),
        ];
        for (expected, cvode, ida) in cases {
            let mut cv = CvodeOptions::default();
            cvode(&mut cv);
            let mut id = IdaOptions::default();
            ida(&mut id);
            for e in [
                common_options!(&cv).validate(2),
                common_options!(&id).validate(2),
            ] {
                match e {
                    Err(SundialsError::Invalid(m)) => assert_eq!(m, expected),
                    other => panic!("{expected}: got {other:?}"),
                }
            }
        }
        let (cv, id) = (CvodeOptions::default(), IdaOptions::default());
        assert!(common_options!(&cv).validate(2).is_ok());
        assert!(common_options!(&id).validate(2).is_ok());
    }
}
