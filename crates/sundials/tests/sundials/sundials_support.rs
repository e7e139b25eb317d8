//! Shared by the test modules: tight KINSOL options, every linear solver for a band matrix,
//! and the parts of a SUNDIALS flag error.

#![allow(dead_code)]

use eyeshell_sundials::{klu_available, KinsolOptions, LinearSolverSpec, Strategy, SundialsError};

/// A line search with tight tolerances and one Jacobian setup per iteration.
pub fn tight() -> KinsolOptions {
    KinsolOptions {
        strategy: Strategy::LineSearch,
        fnorm_tol: 1e-11,
        scaled_step_tol: 1e-15,
        max_iterations: 100,
        max_setup_calls: 1,
        max_newton_step: None,
        reuse_factorization: false,
    }
}

/// Full CSR pattern of a matrix with bandwidths (upper, lower).
pub fn band_pattern(n: usize, upper: usize, lower: usize) -> (Vec<usize>, Vec<usize>) {
    let mut row_ptr = vec![0];
    let mut col_idx = Vec::new();
    for i in 0..n {
        col_idx.extend(i.saturating_sub(lower)..(i + upper + 1).min(n));
        row_ptr.push(col_idx.len());
    }
    (row_ptr, col_idx)
}

/// Dense, band and (when built with it) KLU, for an n × n matrix with bandwidths (upper, lower).
pub fn specs(n: usize, upper: usize, lower: usize) -> Vec<(&'static str, LinearSolverSpec)> {
    let mut v = vec![
        ("dense", LinearSolverSpec::Dense),
        ("band", LinearSolverSpec::Band { upper, lower }),
    ];
    if klu_available() {
        let (row_ptr, col_idx) = band_pattern(n, upper, lower);
        v.push(("klu", LinearSolverSpec::Klu { row_ptr, col_idx }));
    }
    v
}

/// The function, flag, symbolic name and message of a [`SundialsError::Flag`]; any other
/// error fails the test.
pub fn flag_parts(e: &SundialsError) -> (&'static str, i32, &'static str, &str) {
    match e {
        SundialsError::Flag {
            function,
            flag,
            name,
            message,
        } => (function, *flag, name, message),
        other => panic!("expected a flag, got {other}"),
    }
}

/// The largest |a_i − b_i|.
pub fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}
