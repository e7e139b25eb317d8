//! What CVODE and IDA share: both are variable-order BDF codes from the same family, and the
//! options, checks and calls that mean the same in both are written here once. What only
//! looks alike (the systems' callbacks, the linear solvers, the length checks that name
//! different vectors) stays in [`cvode`](super::cvode) and [`ida`](super::ida).

use std::os::raw::c_int;

use super::error::SundialsError;

pub(crate) fn invalid<T>(what: String) -> Result<T, SundialsError> {
    Err(SundialsError::Invalid(what))
}

pub(crate) fn to_int(what: &str, n: usize) -> Result<c_int, SundialsError> {
    c_int::try_from(n).map_err(|_| SundialsError::Invalid(format!("{what} = {n} is too large")))
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
