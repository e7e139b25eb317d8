//! The almost-block-diagonal LU (`linalg::AbdLu`) against nalgebra's dense LU: random ABD
//! matrices of every boundary split (0..=5 rows at the start; the shell's schemes all use
//! 3, with 2 at the end), one node to hundreds, diagonal blocks that are zero and need rows
//! from the next block, singular matrices reported as such, non-finite entries, and a
//! proptest over sizes and structures.

use crate::sundials_support::{fill_from_dense, relative_residual};
use eyeshell_sundials::linalg::{AbdLu, LinalgError, ABD_NODE};
use eyeshell_sundials::MatrixSink;
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

/// A small deterministic generator (xorshift), values in [−1, 1).
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Whether (i, j) lies in the ABD structure of `nodes` nodes with `top` rows at the start.
fn in_structure(nodes: usize, top: usize, i: usize, j: usize) -> bool {
    let n = ABD_NODE * nodes;
    if i < top {
        j < ABD_NODE
    } else if i >= n - (ABD_NODE - top) {
        j >= n - ABD_NODE
    } else {
        let k = (i - top) / ABD_NODE;
        j >= ABD_NODE * k && j < ABD_NODE * (k + 2)
    }
}

/// How a random ABD matrix is made.
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// Like a BVP's finite differences on [0, 1]: interval k's rows are
    /// [−I − h R₁ | I − h R₂] (h = 1 / nodes, R random), so the conditioning does not grow
    /// with the number of nodes; the rows of each block in a random order (`shuffle`), so
    /// that the diagonal is not where the pivots are, and optionally with each left block's
    /// first column zero (k ≥ 1; only with top rows, without which the matrix is block
    /// triangular and that would make it singular), so that node k's first pivot must come from the rows carried
    /// from stage k − 1 (pivoting across blocks).
    Bvp { shuffle: bool, zero_first: bool },
    /// Every entry random, `diag` added where interval rows meet their left node's
    /// diagonal. Random blocks make a random dichotomy: conditioning grows exponentially
    /// with the nodes, so only for a few nodes.
    General { diag: f64 },
    /// Every interval block's left half zero (top = 5): node k's pivots come only from the
    /// rows of interval k − 1 (and node 0's from the top rows).
    ZeroLeft,
}

/// A random ABD matrix of `nodes` nodes with `top` rows at the start, dense.
fn random_abd(nodes: usize, top: usize, kind: Kind, seed: u64) -> DMatrix<f64> {
    let mut rng = Rng::new(seed);
    let n = ABD_NODE * nodes;
    let h = 1.0 / nodes as f64;
    let mut a = DMatrix::from_fn(n, n, |i, j| {
        if !in_structure(nodes, top, i, j) {
            return 0.0;
        }
        let v = rng.next();
        let interval = i >= top && i < n - (ABD_NODE - top);
        if !interval {
            return v;
        }
        let k = (i - top) / ABD_NODE;
        let (row, left) = ((i - top) % ABD_NODE, j < ABD_NODE * (k + 1));
        let col = j % ABD_NODE;
        match kind {
            Kind::Bvp { zero_first, .. } => {
                if zero_first && top > 0 && left && col == 0 && k > 0 {
                    0.0
                } else {
                    let id = if row == col { 1.0 } else { 0.0 };
                    if left {
                        -id - h * v
                    } else {
                        id - h * v
                    }
                }
            }
            Kind::General { diag } => v + if left && row == col { diag } else { 0.0 },
            Kind::ZeroLeft => {
                if left {
                    0.0
                } else {
                    v
                }
            }
        }
    });
    if let Kind::Bvp { shuffle: true, .. } = kind {
        for k in 0..nodes.saturating_sub(1) {
            for r in (1..ABD_NODE).rev() {
                let q = ((rng.next() + 1.0) * 0.5 * (r + 1) as f64) as usize;
                a.swap_rows(top + ABD_NODE * k + r, top + ABD_NODE * k + q.min(r));
            }
        }
    }
    a
}

fn abd_of(a: &DMatrix<f64>, top: usize) -> AbdLu {
    let nodes = a.nrows() / ABD_NODE;
    let mut lu = AbdLu::new(nodes, top).unwrap();
    fill_from_dense(&mut lu, a);
    assert_eq!(lu.take_outside(), 0);
    lu
}

/// Factor once, solve three right sides, compare with nalgebra's dense LU; returns the
/// largest relative residual.
fn check(a: &DMatrix<f64>, top: usize, what: &str) -> f64 {
    let n = a.nrows();
    let mut lu = abd_of(a, top);
    lu.factor().unwrap_or_else(|e| panic!("{what}: {e}"));
    let dense = a.clone().lu();
    let mut worst = 0.0f64;
    for r in 0..3 {
        let b: Vec<f64> = (0..n)
            .map(|i| ((i + 5 * r) as f64 * 0.7 + 1.0).sin())
            .collect();
        let mut x = vec![0.0; n];
        lu.solve(&b, &mut x).unwrap();
        let res = relative_residual(a, &x, &b);
        assert!(res <= 1e-13, "{what}: residual {res:e}");
        worst = worst.max(res);
        let expect = dense.solve(&DVector::from_column_slice(&b)).unwrap();
        let dense_res = relative_residual(a, expect.as_slice(), &b);
        let scale = expect.amax().max(1.0);
        for i in 0..n {
            // Both are backward stable; their forward difference is bounded by the
            // condition number, small for these matrices.
            assert!(
                (x[i] - expect[i]).abs() <= 1e-8 * scale,
                "{what} x[{i}]: {} vs {} (dense residual {dense_res:e})",
                x[i],
                expect[i]
            );
        }
    }
    worst
}

#[test]
fn random_abd_matrices_of_every_boundary_split() {
    for top in 0..=ABD_NODE {
        for &nodes in &[1, 2, 3, 7, 40, 201] {
            for seed in 0..3 {
                for kind in [
                    Kind::Bvp {
                        shuffle: false,
                        zero_first: false,
                    },
                    Kind::Bvp {
                        shuffle: true,
                        zero_first: false,
                    },
                    Kind::Bvp {
                        shuffle: true,
                        zero_first: true,
                    },
                ] {
                    check(
                        &random_abd(nodes, top, kind, seed),
                        top,
                        &format!("{kind:?}, top {top}, {nodes} nodes, seed {seed}"),
                    );
                }
            }
        }
        for &nodes in &[1, 2, 3, 4] {
            for seed in 0..4 {
                for diag in [0.0, 3.0] {
                    let kind = Kind::General { diag };
                    check(
                        &random_abd(nodes, top, kind, 50 + seed),
                        top,
                        &format!("{kind:?}, top {top}, {nodes} nodes, seed {seed}"),
                    );
                }
            }
        }
    }
}

/// The shell's shape (3 top rows, 2 bottom) at the sizes of the benches' meshes, with
/// shuffled rows: pivots are chosen among all eight rows of each stage.
#[test]
fn shell_shape_at_mesh_sizes() {
    for &nodes in &[108, 308] {
        for seed in 0..2 {
            let kind = Kind::Bvp {
                shuffle: true,
                zero_first: seed == 1,
            };
            let res = check(
                &random_abd(nodes, 3, kind, 100 + seed),
                3,
                &format!("{nodes} nodes, seed {seed}"),
            );
            assert!(
                res > 0.0,
                "an exact solve would mean the test checks nothing"
            );
        }
    }
}

/// Diagonal blocks that are zero: interval k's rows cannot pivot on node k, so its
/// pivots come from the rows of the block above (and, at node 0, from the top rows).
#[test]
fn zero_diagonal_blocks_need_pivoting_across_blocks() {
    for &nodes in &[1, 2, 6, 50] {
        for seed in 0..3 {
            check(
                &random_abd(nodes, 5, Kind::ZeroLeft, 200 + seed),
                5,
                &format!("zero left blocks, {nodes} nodes, seed {seed}"),
            );
        }
    }
    // A permutation-like matrix: the top rows 2 I, each interval block [0 | c I]: every
    // pivot of node k ≥ 1 sits in the block above.
    let nodes = 6;
    let n = ABD_NODE * nodes;
    let a = DMatrix::from_fn(n, n, |i, j| {
        if i < ABD_NODE {
            (i == j) as u8 as f64 * 2.0
        } else {
            (j == i) as u8 as f64 * (1.0 + i as f64)
        }
    });
    check(&a, 5, "permutation-like");
    // The shell's split with node k's first column zero in interval k's rows.
    let a = random_abd(
        20,
        3,
        Kind::Bvp {
            shuffle: false,
            zero_first: true,
        },
        7,
    );
    let mut lu = abd_of(&a, 3);
    lu.factor().unwrap();
    check(&a, 3, "zero first column in every left block");
}

#[test]
fn singular_matrices_are_reported_singular() {
    // A zero column at node 4, unknown 2.
    let mut a = random_abd(10, 3, Kind::General { diag: 3.0 }, 1);
    a.column_mut(22).fill(0.0);
    let mut lu = abd_of(&a, 3);
    match lu.factor() {
        Err(LinalgError::Singular(why)) => assert!(why.contains("column 22"), "{why}"),
        other => panic!("expected singular, got {other:?}"),
    }
    assert!(!lu.is_factored());
    let mut x = vec![0.0; 50];
    assert!(matches!(
        lu.solve(&vec![1.0; 50], &mut x),
        Err(LinalgError::NotFactored)
    ));
    // Two rows of one interval block equal: singular up to rounding, caught by the
    // pivot test (not by an exact zero).
    let mut a = random_abd(10, 3, Kind::General { diag: 3.0 }, 2);
    for j in 0..50 {
        a[(3 + 5 * 6 + 1, j)] = a[(3 + 5 * 6 + 3, j)];
    }
    let mut lu = abd_of(&a, 3);
    assert!(
        matches!(lu.factor(), Err(LinalgError::Singular(_))),
        "two equal rows"
    );
    // A row of interval 1 a combination of two others of its block, up to rounding.
    let mut a = random_abd(4, 3, Kind::General { diag: 3.0 }, 3);
    for j in 5..15 {
        a[(9, j)] = 0.5 * a[(10, j)] + 0.25 * a[(11, j)];
    }
    let mut lu = abd_of(&a, 3);
    assert!(
        matches!(lu.factor(), Err(LinalgError::Singular(_))),
        "a row that is a combination of two others"
    );
    // Non-finite entries.
    let mut a = random_abd(4, 3, Kind::General { diag: 3.0 }, 4);
    a[(10, 9)] = f64::NAN;
    let mut lu = abd_of(&a, 3);
    assert!(matches!(lu.factor(), Err(LinalgError::Singular(_))));
    // The bottom rows alone cannot fix the last node: the last stage is singular.
    let mut a = random_abd(3, 3, Kind::General { diag: 3.0 }, 5);
    for j in 0..15 {
        a[(14, j)] = a[(13, j)];
    }
    let mut lu = abd_of(&a, 3);
    assert!(matches!(lu.factor(), Err(LinalgError::Singular(_))));
}

#[test]
fn writes_outside_the_structure_are_counted() {
    let mut lu = AbdLu::new(4, 3).unwrap();
    // Row 0 (top) only reaches columns 0..5; row 3 (interval 0) columns 0..10.
    #[cfg(not(debug_assertions))]
    {
        lu.set(0, 5, 1.0);
        lu.set(3, 10, 1.0);
        lu.set(19, 14, 1.0);
        assert_eq!(lu.take_outside(), 3);
    }
    lu.set(0, 4, 1.0);
    lu.set(3, 9, 1.0);
    lu.set(19, 15, 1.0);
    assert_eq!(lu.take_outside(), 0);
    assert_eq!(lu.get(3, 9), 1.0);
    assert_eq!(lu.get(3, 10), 0.0);
    assert!(AbdLu::new(0, 3).is_err());
    assert!(AbdLu::new(3, 6).is_err());
}

/// Zeroing only the boundary rows is enough when the assembler rewrites every block entry;
/// an assembler that leaves one unwritten after `poison_blocks` is caught.
#[test]
fn poisoned_blocks_catch_an_unwritten_entry() {
    let a = random_abd(
        6,
        3,
        Kind::Bvp {
            shuffle: true,
            zero_first: false,
        },
        9,
    );
    let mut lu = abd_of(&a, 3);
    lu.factor().unwrap();
    lu.zero_boundary();
    lu.poison_blocks();
    for i in 0..30 {
        for j in 0..30 {
            if in_structure(6, 3, i, j) && (i, j) != (12, 14) {
                lu.set(i, j, a[(i, j)]);
            }
        }
    }
    assert!(matches!(lu.factor(), Err(LinalgError::Singular(_))));
    lu.set(12, 14, a[(12, 14)]);
    lu.factor().unwrap();
    assert!(
        lu.growth() >= 1.0 && lu.growth() < 1e3,
        "growth {}",
        lu.growth()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any split and 1–150 nodes, BVP-like blocks shuffled or not, with or without zero
    /// first columns, or fully random blocks on a few nodes, or zero left blocks:
    /// residual ≤ 1e-13 against the dense matrix.
    #[test]
    fn abd_solves_match_dense_lu(
        nodes in 1usize..150,
        top in 0usize..=5,
        which in 0usize..4,
        flags in any::<(bool, bool)>(),
        seed in 0u64..1_000_000,
    ) {
        let (kind, nodes, top) = match which {
            0 | 1 => (Kind::Bvp { shuffle: flags.0, zero_first: flags.1 }, nodes, top),
            2 => (Kind::General { diag: if flags.0 { 2.0 } else { 0.0 } }, 1 + nodes % 5, top),
            _ => (Kind::ZeroLeft, nodes, 5),
        };
        let a = random_abd(nodes, top, kind, seed);
        // Skip the rare random matrix dense LU itself cannot solve accurately.
        let dense = a.clone().lu();
        let b = DVector::from_fn(a.nrows(), |i, _| (i as f64 * 0.37).cos());
        let ok = dense
            .solve(&b)
            .is_some_and(|x| relative_residual(&a, x.as_slice(), b.as_slice()) <= 1e-14);
        prop_assume!(ok);
        let mut lu = abd_of(&a, top);
        lu.factor().unwrap();
        let mut x = b.as_slice().to_vec();
        lu.solve_in_place(&mut x);
        let res = relative_residual(&a, &x, b.as_slice());
        prop_assert!(res <= 1e-13, "residual {:e}", res);
    }
}
