//! Shared by the KINSOL tests: tight solver options and every linear solver for a band matrix.

#![allow(dead_code)]

use eyeshell_sundials::{klu_available, KinsolOptions, LinearSolverSpec, Strategy};

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
