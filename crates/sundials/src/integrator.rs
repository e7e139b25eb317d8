//! What CVODE and IDA share: both are variable-order BDF codes from the same family, and the
//! options, checks and calls that mean the same in both are written here once. What only
//! looks alike (the systems' callbacks, the linear solvers, the length checks that name
//! different vectors) stays in [`cvode`](super::cvode) and [`ida`](super::ida).

use std::os::raw::{c_int, c_void};

use sundials_sys::{N_Vector, SUNMatrix};

use super::callback::{CallbackResult, CallbackState};
use super::error::SundialsError;
use super::matrix::{JacobianMatrix, Matrix};
use super::nvector;

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
    pub(crate) callbacks: CallbackState,
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
        }
    }};
}
pub(crate) use common_options;

impl CommonOptions<'_> {
    /// The checks of the shared options for n unknowns, in the order both integrators make
    /// them, before their own.
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
