//! The safe-Rust band LU (`linalg::BandLu`) against nalgebra's dense LU: random band
//! matrices of several shapes (kl ≠ ku, n smaller than the band), matrices that need row
//! interchanges, singular matrices reported as such, writes outside the band, and the
//! bordered band built on it.

use crate::support::{fill_from_dense, relative_residual};
use eyeshell_linalg::MatrixSink;
use eyeshell_linalg::{BandLu, BorderedBand, Csr, DirectSolver, InterleavedBand, LinalgError};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

/// A small deterministic generator (xorshift), values in [−1, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// A random band matrix, dense; `diag` is added to the diagonal (0: pivoting needed).
fn random_band(n: usize, kl: usize, ku: usize, diag: f64, seed: u64) -> DMatrix<f64> {
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    DMatrix::from_fn(n, n, |i, j| {
        if i > j + kl || j > i + ku {
            0.0
        } else {
            rng.next() + if i == j { diag } else { 0.0 }
        }
    })
}

fn band_lu_of(a: &DMatrix<f64>, kl: usize, ku: usize) -> BandLu {
    let mut lu = BandLu::new(a.nrows(), kl, ku).unwrap();
    fill_from_dense(&mut lu, a);
    assert_eq!(lu.take_outside(), 0);
    lu
}

/// Factor, solve two right sides with one factorisation, and compare with nalgebra.
fn check(n: usize, kl: usize, ku: usize, diag: f64, seed: u64) {
    let a = random_band(n, kl, ku, diag, seed);
    let lu = band_lu_of(&a, kl, ku).factor().unwrap();
    let dense = a.clone().lu();
    for r in 0..2 {
        let b: Vec<f64> = (0..n)
            .map(|i| ((i + 3 * r) as f64 * 0.7 + 1.0).sin())
            .collect();
        let mut x = b.clone();
        lu.solve_in_place(&mut x).unwrap();
        let res = relative_residual(&a, &x, &b);
        assert!(res <= 1e-13, "n {n} kl {kl} ku {ku}: residual {res:e}");
        let expect = dense.solve(&DVector::from_column_slice(&b)).unwrap();
        let scale = expect.amax().max(1.0);
        for i in 0..n {
            assert!(
                (x[i] - expect[i]).abs() <= 1e-9 * scale,
                "n {n} kl {kl} ku {ku} x[{i}]: {} vs {}",
                x[i],
                expect[i]
            );
        }
    }
}

#[test]
fn random_band_matrices_of_several_shapes() {
    for &(n, kl, ku) in &[
        (1, 0, 0),
        (5, 0, 0),
        (10, 1, 1),
        (30, 2, 5),
        (30, 5, 2),
        (40, 0, 3),
        (40, 3, 0),
        (200, 8, 8),
        (3, 8, 8),
        (6, 4, 9),
        (9, 8, 2),
    ] {
        for seed in 0..3 {
            check(n, kl, ku, 4.0, seed);
        }
    }
}

/// A zero diagonal forces interchanges at every step.
#[test]
fn zero_diagonal_needs_pivoting() {
    for &(n, kl, ku) in &[(12, 1, 1), (40, 3, 2), (40, 2, 3), (7, 6, 6), (100, 8, 8)] {
        for seed in 0..3 {
            check(n, kl, ku, 0.0, seed + 10);
        }
    }
    // Explicitly zero: [[0, 1], [1, 0]]-like blocks down the diagonal.
    let n = 10;
    let a = DMatrix::from_fn(n, n, |i, j| match (i % 2, j as isize - i as isize) {
        (0, 1) | (1, -1) => 1.0 + i as f64,
        _ => 0.0,
    });
    let lu = band_lu_of(&a, 1, 1).factor().unwrap();
    let b: Vec<f64> = (0..n).map(|i| i as f64 - 2.5).collect();
    let mut x = b.clone();
    lu.solve_in_place(&mut x).unwrap();
    assert!(relative_residual(&a, &x, &b) <= 1e-15);
}

#[test]
fn singular_matrices_are_reported_with_their_column() {
    // A zero column: exactly singular at column 3.
    let n = 8;
    let mut a = random_band(n, 2, 2, 4.0, 1);
    a.column_mut(3).fill(0.0);
    let lu = band_lu_of(&a, 2, 2);
    match lu.factor() {
        Err(LinalgError::Singular(why)) => assert!(why.contains("column 3"), "{why}"),
        other => panic!("expected singular, got {other:?}"),
    }
    // Two equal rows, 4 and 5, on the columns both can hold (3..=6): singular up to
    // rounding.
    let mut a = random_band(n, 2, 2, 4.0, 2);
    a[(4, 2)] = 0.0;
    a[(5, 7)] = 0.0;
    for j in 3..=6 {
        a[(5, j)] = a[(4, j)];
    }
    let lu = band_lu_of(&a, 2, 2);
    assert!(matches!(lu.factor(), Err(LinalgError::Singular(_))));
    // All zero.
    let lu = BandLu::new(4, 1, 1).unwrap();
    assert!(matches!(lu.factor(), Err(LinalgError::Singular(_))));
}

#[test]
fn rows_written_in_place_and_refactored() {
    let (n, kl, ku) = (50, 3, 4);
    let mut lu = BandLu::new(n, kl, ku).unwrap();
    for seed in 0..3 {
        let a = random_band(n, kl, ku, 0.5, seed + 20);
        // row_mut holds columns i − kl ..= i + ku; entries for columns outside 0..n are
        // ignored, so write garbage there.
        for i in 0..n {
            for (t, v) in lu.row_mut(i).unwrap().iter_mut().enumerate() {
                let j = (i + t) as isize - kl as isize;
                *v = if (0..n as isize).contains(&j) {
                    a[(i, j as usize)]
                } else {
                    1e300
                };
            }
        }
        let f = lu.factor().unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let mut x = b.clone();
        f.solve_in_place(&mut x).unwrap();
        assert!(relative_residual(&a, &x, &b) <= 1e-13);
    }
    assert!(matches!(lu.row_mut(n), Err(LinalgError::Length(_))));
}

/// Right sides of the wrong length are errors that leave them as they were, not panics;
/// the factors are of the matrix as factored, whatever is written to it after.
#[test]
fn wrong_lengths_are_errors_and_factors_are_a_snapshot() {
    let (n, kl, ku) = (12, 2, 3);
    let a = random_band(n, kl, ku, 4.0, 11);
    let mut lu = band_lu_of(&a, kl, ku);
    let f = lu.factor().unwrap();
    assert_eq!(f.size(), n);
    for len in [0, n - 1, n + 1] {
        let mut b = vec![1.0; len];
        match f.solve_in_place(&mut b) {
            Err(LinalgError::Length(why)) => assert!(why.contains("size 12"), "{why}"),
            other => panic!("right side of {len}: {other:?}"),
        }
        assert!(b.iter().all(|&v| v == 1.0));
    }
    let b: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let mut x = b.clone();
    f.solve_in_place(&mut x).unwrap();
    lu.zero();
    let mut y = b.clone();
    f.solve_in_place(&mut y).unwrap();
    assert_eq!(x, y);
    assert!(relative_residual(&a, &x, &b) <= 1e-13);
    // Refactoring a zeroed matrix into the old storage fails, and takes the old factors.
    assert!(matches!(
        lu.factor_reusing(Some(f)),
        Err(LinalgError::Singular(_))
    ));
}

#[test]
fn absurd_sizes_are_refused() {
    assert!(BandLu::new(usize::MAX / 2, 8, 8).is_err());
    assert!(BandLu::new(10, usize::MAX / 2, 8).is_err());
    assert!(BandLu::new(10, 2, usize::MAX).is_err());
    assert!(BandLu::new(0, 3, 3).is_ok());
}

#[test]
#[cfg(not(debug_assertions))]
fn writes_outside_the_band_are_counted() {
    let mut lu = BandLu::new(5, 1, 2).unwrap();
    lu.set(0, 3, 1.0);
    lu.add(3, 1, 1.0);
    lu.set(5, 0, 1.0);
    lu.set(0, 2, 1.0);
    assert_eq!(lu.take_outside(), 3);
    assert_eq!(lu.take_outside(), 0);
    let mut bb = BorderedBand::new(5, 1, 1, true).unwrap();
    let r = bb.fill(|m, _, _, _| m.set(0, 4, 1.0));
    assert!(matches!(r, Err(LinalgError::OutsidePattern(1))));
}

/// A bordered band with a zero band diagonal (pivoting inside the band) against dense.
#[test]
fn bordered_band_with_pivoting_against_dense() {
    let (n, kl, ku) = (40, 3, 2);
    let a = random_band(n, kl, ku, 0.0, 7);
    let mut bb = BorderedBand::new(n, kl, ku, true).unwrap();
    let c = |i: usize| 0.3 * (i as f64 * 1.3).sin();
    let r = |j: usize| 0.2 * (j as f64 * 0.4).cos();
    bb.fill(|m, col, row, corner| {
        for i in 0..n {
            for j in 0..n {
                if a[(i, j)] != 0.0 {
                    m.set(i, j, a[(i, j)]);
                }
            }
            col[i] = c(i);
            row[i] = r(i);
        }
        *corner = 2.0;
    })
    .unwrap();
    let f = bb.factor().unwrap();
    let full = DMatrix::from_fn(n + 1, n + 1, |i, j| match (i < n, j < n) {
        (true, true) => a[(i, j)],
        (true, false) => c(i),
        (false, true) => r(j),
        (false, false) => 2.0,
    });
    let b: Vec<f64> = (0..=n).map(|i| (i as f64 * 0.3).sin()).collect();
    let mut x = vec![0.0; n + 1];
    f.solve(&b, &mut x).unwrap();
    assert_eq!(f.len(), n + 1);
    for len in [n, n + 2] {
        let mut y = vec![1.0; len];
        assert!(matches!(
            f.solve_in_place(&mut y),
            Err(LinalgError::Length(_))
        ));
        assert!(matches!(
            f.solve(&vec![1.0; len], &mut y),
            Err(LinalgError::Length(_))
        ));
    }
    assert!(relative_residual(&full, &x, &b) <= 1e-13);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any shape, with or without a dominant diagonal: a small relative residual, or a
    /// singular report that the dense LU agrees with (a tiny pivot somewhere).
    #[test]
    fn band_lu_solves_any_shape(
        n in 1usize..60,
        kl in 0usize..10,
        ku in 0usize..10,
        dominant in any::<bool>(),
        seed in any::<u64>(),
    ) {
        let a = random_band(n, kl, ku, if dominant { 4.0 } else { 0.0 }, seed);
        let lu = band_lu_of(&a, kl, ku);
        match lu.factor() {
            Ok(f) => {
                let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.9).cos()).collect();
                let mut x = b.clone();
                f.solve_in_place(&mut x).unwrap();
                let res = relative_residual(&a, &x, &b);
                // Random unstructured matrices can be badly conditioned; the backward
                // error of partial pivoting stays small regardless.
                prop_assert!(res <= 1e-13, "residual {:e}", res);
            }
            Err(LinalgError::Singular(_)) => {
                let sv = a.clone().singular_values();
                let ratio = sv.min() / sv.max();
                prop_assert!(ratio < 1e-8, "reported singular, σ_min/σ_max {:e}", ratio);
            }
            Err(e) => prop_assert!(false, "{e}"),
        }
    }
}

/// No answer from a solver that was not factored, or whose last factorisation failed
/// (the bordered matrix's own factors cannot be had without one).
#[test]
fn a_solver_refuses_to_solve_without_a_factorisation() {
    // [I c; cᵀ s] with the border last: nonsingular for s = 4, singular for s = 3.
    let m = |s: f64| {
        let mut a = Csr::from_rows(
            (0..4)
                .map(|i| if i < 3 { vec![i, 3] } else { vec![0, 1, 2, 3] })
                .collect(),
        );
        for i in 0..3 {
            a.add(i, i, 1.0);
            a.add(i, 3, 1.0);
            a.add(3, i, 1.0);
        }
        a.add(3, 3, s);
        a
    };
    let mut solver = InterleavedBand::new(&m(4.0), vec![0, 1, 2, 0], Some(3)).unwrap();
    let mut x = vec![0.0; 4];
    assert!(matches!(
        solver.solve(&[1.0; 4], &mut x),
        Err(LinalgError::NotFactored)
    ));
    solver.factor(&m(4.0)).unwrap();
    solver.solve(&[1.0; 4], &mut x).unwrap();
    // x_i + x_3 = 1 and Σ x_i + 4 x_3 = 1: x_3 = −2, x_i = 3.
    assert_eq!(x, [3.0, 3.0, 3.0, -2.0]);
    assert!(matches!(
        solver.solve(&[1.0; 3], &mut x),
        Err(LinalgError::Length(_))
    ));
    assert!(matches!(
        solver.factor(&m(3.0)),
        Err(LinalgError::Singular(_))
    ));
    assert!(matches!(
        solver.solve(&[1.0; 4], &mut x),
        Err(LinalgError::NotFactored)
    ));
    // An order that does not fit the pattern is refused when the solver is made.
    assert!(matches!(
        InterleavedBand::new(&m(4.0), vec![0, 1, 2], Some(3)),
        Err(LinalgError::Structure(_))
    ));
    assert!(matches!(
        InterleavedBand::new(&m(4.0), vec![0, 1, 5, 0], Some(3)),
        Err(LinalgError::Structure(_))
    ));
}
