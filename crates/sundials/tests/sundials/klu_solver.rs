//! SUNDIALS' KLU adapted to eyeshell-linalg (`KluSolver`): alone and as the Schur solver's
//! reduced matrix, against nalgebra's dense LU, and its errors as `LinalgError::Backend`.

use eyeshell_linalg::{Csr, DirectSolver, LinalgError, SchurSolver};
use eyeshell_sundials::{klu_available, KluSolver};
use nalgebra::{DMatrix, DVector};

/// A diagonally dominant matrix with the Schur solver's structure: 3 blocks of 2 unknowns
/// (each reading its own block, a window of the band unknowns, the border and, for the
/// last, the first block), 8 band unknowns (tridiagonal, each reading one block) and a
/// border row reading everything. As CSR and dense.
fn structured() -> (Csr, DMatrix<f64>, usize) {
    let (nb, n_w) = (3usize, 8usize);
    let n_p = 2 * nb;
    let n = n_p + n_w + 1;
    let d = n - 1;
    let mut rows: Vec<Vec<usize>> = vec![vec![]; n];
    for k in 0..nb {
        for r in 0..2 {
            let row = &mut rows[2 * k + r];
            row.extend([2 * k, 2 * k + 1, d]);
            row.extend((2 * k..(2 * k + 3).min(n_w)).map(|c| n_p + c));
            if k == nb - 1 {
                row.extend([0, 1]);
            }
        }
    }
    for j in 0..n_w {
        rows[n_p + j].extend((j.saturating_sub(1)..(j + 2).min(n_w)).map(|c| n_p + c));
        rows[n_p + j].extend([2 * (j / 2 % nb), 2 * (j / 2 % nb) + 1]);
    }
    rows[d] = (0..n).collect();
    let mut a = Csr::from_rows(rows.clone());
    let mut dense = DMatrix::zeros(n, n);
    for (i, cols) in rows.iter().enumerate() {
        for &j in cols {
            if dense[(i, j)] == 0.0 {
                let v = ((i * 31 + j * 17) as f64 * 0.37).sin() + if i == j { 6.0 } else { 0.0 };
                a.add(i, j, v);
                dense[(i, j)] = v;
            }
        }
    }
    (a, dense, n_p)
}

#[test]
fn klu_alone_and_for_the_schur_complement_match_dense() {
    if !klu_available() {
        eprintln!("KLU not built in: nothing to compare");
        return;
    }
    let (a, dense, n_p) = structured();
    let n = a.n();
    let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
    let expect = dense.lu().solve(&DVector::from_vec(b.clone())).unwrap();
    let mut x = vec![0.0; n];
    let mut klu = KluSolver::new(&a).unwrap();
    klu.factor(&a).unwrap();
    klu.solve(&b, &mut x).unwrap();
    let err = |x: &[f64]| {
        x.iter()
            .zip(expect.iter())
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max)
    };
    assert!(err(&x) < 1e-12, "KLU alone: {:e}", err(&x));
    let mut schur = SchurSolver::new(&a, n_p, true, KluSolver::REDUCED).unwrap();
    schur.factor(&a).unwrap();
    x.fill(0.0);
    schur.solve(&b, &mut x).unwrap();
    assert!(err(&x) < 1e-12, "Schur with KLU: {:e}", err(&x));
}

/// A singular matrix: KLU's failure reaches the caller as a backend error naming SUNDIALS'
/// flag, not as a panic.
#[test]
fn klu_failure_is_a_backend_error() {
    if !klu_available() {
        eprintln!("KLU not built in: nothing to check");
        return;
    }
    let a = Csr::from_rows(vec![vec![0, 1], vec![0, 1]]);
    let mut klu = KluSolver::new(&a).unwrap();
    match klu.factor(&a) {
        Err(LinalgError::Backend(e)) => assert!(!e.to_string().is_empty()),
        other => panic!("expected a backend error, got {other:?}"),
    }
}
