//! Plumbing shared by every integrator's `extern "C"` trampolines: the callback result
//! type, the guard that stops panics at the C boundary, the captured error log, and the
//! heap box whose address SUNDIALS holds as user data.
//!
//! Why: unwinding through C frames is undefined behaviour, and SUNDIALS's default error
//! handler prints to stderr. Every trampoline runs the Rust code under `catch_unwind` and
//! returns a SUNDIALS flag (0 ok, > 0 recoverable, < 0 unrecoverable), remembering what went
//! wrong so that the final error can say it; the error handler stores messages instead of
//! printing them.

use std::any::Any;
use std::ffi::CStr;
use std::fmt;
use std::os::raw::{c_char, c_int, c_void};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr::NonNull;

use super::error::{flag_error, FlagFamily, SundialsError};

/// How a user callback failed.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CallbackError {
    /// SUNDIALS may retry (e.g. KINSOL's line search shortens the step).
    Recoverable(String),
    /// Stop the solver now.
    Fatal(String),
}

impl fmt::Display for CallbackError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CallbackError::Recoverable(m) => write!(f, "recoverable: {m}"),
            CallbackError::Fatal(m) => write!(f, "fatal: {m}"),
        }
    }
}

impl std::error::Error for CallbackError {}

pub type CallbackResult = Result<(), CallbackError>;

/// What the callbacks of one solve reported.
#[derive(Debug, Default)]
pub(crate) struct CallbackState {
    /// The first fatal error or panic, e.g. "residual panicked: index out of bounds".
    pub(crate) fatal: Option<String>,
    /// The last recoverable error, e.g. "residual: negative thickness".
    pub(crate) last_recoverable: Option<String>,
}

impl CallbackState {
    pub(crate) fn reset(&mut self) {
        *self = CallbackState::default();
    }

    /// Run `f` without letting a panic escape; map its result to a SUNDIALS flag.
    pub(crate) fn guard(
        &mut self,
        what: &'static str,
        f: impl FnOnce() -> CallbackResult,
    ) -> c_int {
        match catch_unwind(AssertUnwindSafe(f)) {
            Ok(Ok(())) => 0,
            Ok(Err(CallbackError::Recoverable(m))) => {
                self.last_recoverable = Some(format!("{what}: {m}"));
                1
            }
            Ok(Err(CallbackError::Fatal(m))) => self.fail(format!("{what}: {m}")),
            Err(payload) => self.fail(format!(
                "{what} panicked: {}",
                panic_message(payload.as_ref())
            )),
        }
    }

    /// Record an unrecoverable failure (the first one wins) and return -1.
    pub(crate) fn fail(&mut self, message: String) -> c_int {
        self.fatal.get_or_insert(message);
        -1
    }
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "non-string panic payload".to_string()
    }
}

/// A heap value whose address is handed to C (user data, error-handler data).
///
/// Why not `Box`: a `Box` asserts unique access whenever it is used, while SUNDIALS writes
/// through the raw pointer we gave it. Keeping only the raw pointer and creating short-lived
/// references to it (never across a call into SUNDIALS) avoids that aliasing.
pub(crate) struct RawBox<T>(NonNull<T>);

impl<T> RawBox<T> {
    pub(crate) fn new(value: T) -> Self {
        RawBox(NonNull::from(Box::leak(Box::new(value))))
    }

    pub(crate) fn as_void(&self) -> *mut c_void {
        self.0.as_ptr().cast()
    }

    /// # Safety
    /// No reference obtained from the raw pointer (e.g. inside a callback) may be alive.
    pub(crate) unsafe fn get(&self) -> &T {
        self.0.as_ref()
    }

    /// # Safety
    /// As for `get`.
    pub(crate) unsafe fn get_mut(&mut self) -> &mut T {
        self.0.as_mut()
    }
}

impl<T> Drop for RawBox<T> {
    fn drop(&mut self) {
        // SAFETY: the pointer came from Box::leak and is reclaimed once; owners drop the C
        // object holding the address before this box.
        drop(unsafe { Box::from_raw(self.0.as_ptr()) });
    }
}

/// Messages SUNDIALS sent to the error handler during one call.
#[derive(Debug, Default)]
pub(crate) struct ErrorLog {
    entries: Vec<(c_int, String)>,
}

impl ErrorLog {
    pub(crate) fn clear(&mut self) {
        self.entries.clear();
    }

    /// The last error message (negative code), else the last message of any kind.
    pub(crate) fn last_message(&self) -> Option<String> {
        self.entries
            .iter()
            .rev()
            .find(|(code, _)| *code < 0)
            .or_else(|| self.entries.last())
            .map(|(_, m)| m.clone())
    }
}

impl RawBox<ErrorLog> {
    /// Call a SUNDIALS function with this log as its error handler's data, and turn its flag
    /// (with the captured message) into a Result.
    pub(crate) fn call(
        &mut self,
        function: &'static str,
        family: FlagFamily,
        f: impl FnOnce() -> c_int,
    ) -> Result<(), SundialsError> {
        // SAFETY: no callback is running, so no other reference to the log exists.
        unsafe { self.get_mut().clear() };
        let flag = f();
        if flag == 0 {
            return Ok(());
        }
        // SAFETY: as above.
        let message = unsafe { self.get().last_message() };
        Err(flag_error(function, flag, family, message))
    }
}

/// A getter of a solver's counters (CVodeGetNumSteps, IDAGetNumResEvals, ...).
pub(crate) type CountGetter = unsafe extern "C" fn(*mut c_void, *mut std::os::raw::c_long) -> c_int;
/// A getter of a solver's real outputs (CVodeGetLastStep, ...).
pub(crate) type RealGetter = unsafe extern "C" fn(*mut c_void, *mut f64) -> c_int;

/// One counter of a solver's memory; 0 if the getter fails (the stats of every solver are
/// read this way, also after a failure).
///
/// # Safety
/// `mem` must be live memory of the solver the getter belongs to.
pub(crate) unsafe fn counter(mem: *mut c_void, get: CountGetter) -> usize {
    let mut v: std::os::raw::c_long = 0;
    if get(mem, &mut v) == 0 {
        v.max(0) as usize
    } else {
        0
    }
}

/// One real output of a solver's memory; NaN if the getter fails.
///
/// # Safety
/// As for [`counter`].
pub(crate) unsafe fn real(mem: *mut c_void, get: RealGetter) -> f64 {
    let mut v = f64::NAN;
    if get(mem, &mut v) == 0 {
        v
    } else {
        f64::NAN
    }
}

/// The error handler for KINSOL (and CVODE/IDA, whose handler type is the same): store the
/// message in the `ErrorLog` passed as `data` instead of printing it.
///
/// # Safety
/// `data` must point to a live `ErrorLog` that no reference is alive to.
pub(crate) unsafe extern "C" fn error_handler(
    code: c_int,
    _module: *const c_char,
    function: *const c_char,
    message: *mut c_char,
    data: *mut c_void,
) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        let text = |p: *const c_char| {
            if p.is_null() {
                String::new()
            } else {
                // SAFETY: SUNDIALS passes NUL-terminated strings.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        let (function, message) = (text(function), text(message));
        let line = if function.is_empty() {
            message
        } else {
            format!("{function}: {message}")
        };
        if let Some(log) = (data as *mut ErrorLog).as_mut() {
            log.entries.push((code, super::error::one_line(&line)));
        }
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guard_maps_results_and_catches_panics() {
        let mut s = CallbackState::default();
        assert_eq!(s.guard("f", || Ok(())), 0);
        assert_eq!(
            s.guard("f", || Err(CallbackError::Recoverable("soft".into()))),
            1
        );
        assert_eq!(s.last_recoverable.as_deref(), Some("f: soft"));
        assert!(s.guard("residual", || panic!("boom {}", 7)) < 0);
        assert_eq!(s.fatal.as_deref(), Some("residual panicked: boom 7"));
        assert!(s.guard("g", || Err(CallbackError::Fatal("later".into()))) < 0);
        assert_eq!(
            s.fatal.as_deref(),
            Some("residual panicked: boom 7"),
            "first failure wins"
        );
    }
}
