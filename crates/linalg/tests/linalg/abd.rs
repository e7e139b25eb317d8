//! The almost-block-diagonal LU (`linalg::Abd`) against nalgebra's dense LU, with 5-wide
//! node blocks (`AbdLu`, the elastic Jacobian) and 6-wide ones (`AbdLu6`, the growth DAE's
//! reduced matrix): random ABD matrices of every boundary split (0..=N rows at the start;
//! the shell's schemes all use 3, with N − 3 at the end), one node to hundreds, diagonal blocks that are zero and need rows
//! from the next block, singular matrices reported as such, non-finite entries, and a
//! proptest over sizes and structures.

use crate::support::{fill_from_dense, relative_residual};
use eyeshell_linalg::MatrixSink;
use eyeshell_linalg::{Abd, AbdLu, AbdLu6, LinalgError, ABD_NODE};
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
fn in_structure<const N: usize>(nodes: usize, top: usize, i: usize, j: usize) -> bool {
    let n = N * nodes;
    if i < top {
        j < N
    } else if i >= n - (N - top) {
        j >= n - N
    } else {
        let k = (i - top) / N;
        j >= N * k && j < N * (k + 2)
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
fn random_abd<const N: usize>(nodes: usize, top: usize, kind: Kind, seed: u64) -> DMatrix<f64> {
    let mut rng = Rng::new(seed);
    let n = N * nodes;
    let h = 1.0 / nodes as f64;
    let mut a = DMatrix::from_fn(n, n, |i, j| {
        if !in_structure::<N>(nodes, top, i, j) {
            return 0.0;
        }
        let v = rng.next();
        let interval = i >= top && i < n - (N - top);
        if !interval {
            return v;
        }
        let k = (i - top) / N;
        let (row, left) = ((i - top) % N, j < N * (k + 1));
        let col = j % N;
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
            for r in (1..N).rev() {
                let q = ((rng.next() + 1.0) * 0.5 * (r + 1) as f64) as usize;
                a.swap_rows(top + N * k + r, top + N * k + q.min(r));
            }
        }
    }
    a
}

fn abd_of<const N: usize, const W: usize>(a: &DMatrix<f64>, top: usize) -> Abd<N, W> {
    let nodes = a.nrows() / N;
    let mut lu = Abd::<N, W>::new(nodes, top).unwrap();
    fill_from_dense(&mut lu, a);
    assert_eq!(lu.take_outside(), 0);
    lu
}

/// Factor once, solve three right sides, compare with nalgebra's dense LU; returns the
/// largest relative residual.
fn check<const N: usize, const W: usize>(a: &DMatrix<f64>, top: usize, what: &str) -> f64 {
    let n = a.nrows();
    let lu = abd_of::<N, W>(a, top)
        .factor()
        .unwrap_or_else(|e| panic!("{what}: {e}"));
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

/// Every split 0..=N of the boundary rows, for both block widths in use: 5 (the elastic
/// BVP's Jacobian, split 3 + 2) and 6 (the growth DAE's reduced matrix, split 3 + 3).
fn every_boundary_split<const N: usize, const W: usize>() {
    for top in 0..=N {
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
                    check::<N, W>(
                        &random_abd::<N>(nodes, top, kind, seed),
                        top,
                        &format!("{N}-wide, {kind:?}, top {top}, {nodes} nodes, seed {seed}"),
                    );
                }
            }
        }
        for &nodes in &[1, 2, 3, 4] {
            for seed in 0..4 {
                for diag in [0.0, 3.0] {
                    let kind = Kind::General { diag };
                    check::<N, W>(
                        &random_abd::<N>(nodes, top, kind, 50 + seed),
                        top,
                        &format!("{N}-wide, {kind:?}, top {top}, {nodes} nodes, seed {seed}"),
                    );
                }
            }
        }
    }
}

#[test]
fn random_abd_matrices_of_every_boundary_split() {
    every_boundary_split::<5, 10>();
    every_boundary_split::<6, 12>();
}

/// 6-wide blocks with zero diagonal blocks (pivots from the block above), and a singular
/// matrix (a zero column at node 4) reported with its column.
#[test]
fn six_wide_blocks_pivot_across_blocks_and_report_singular() {
    for &nodes in &[1, 2, 6, 50] {
        for seed in 0..3 {
            check::<6, 12>(
                &random_abd::<6>(nodes, 6, Kind::ZeroLeft, 300 + seed),
                6,
                &format!("6-wide zero left blocks, {nodes} nodes, seed {seed}"),
            );
        }
    }
    // The reduced matrix's split, 3 pole and 3 cornea rows, node k's first column zero in
    // interval k's rows: its first pivot comes from the rows carried from node k − 1.
    let a = random_abd::<6>(
        30,
        3,
        Kind::Bvp {
            shuffle: true,
            zero_first: true,
        },
        11,
    );
    check::<6, 12>(&a, 3, "6-wide, zero first columns");
    let mut a = random_abd::<6>(10, 3, Kind::General { diag: 3.0 }, 1);
    a.column_mut(26).fill(0.0);
    let lu: AbdLu6 = abd_of::<6, 12>(&a, 3);
    match lu.factor() {
        Err(LinalgError::Singular(why)) => assert!(why.contains("column 26"), "{why}"),
        other => panic!("expected singular, got {other:?}"),
    }
    // Two equal rows of interval 2's block: singular up to rounding.
    let mut a = random_abd::<6>(10, 3, Kind::General { diag: 3.0 }, 2);
    for j in 0..60 {
        a[(3 + 6 * 2 + 1, j)] = a[(3 + 6 * 2 + 4, j)];
    }
    let lu = abd_of::<6, 12>(&a, 3);
    assert!(
        matches!(lu.factor(), Err(LinalgError::Singular(_))),
        "two equal rows"
    );
}

/// Rows written whole through `set_row` make the same matrix as entry by entry.
#[test]
fn set_row_writes_a_rows_span() {
    let a = random_abd::<6>(5, 3, Kind::General { diag: 2.0 }, 8);
    let entrywise = abd_of::<6, 12>(&a, 3);
    let mut rowwise = AbdLu6::new(5, 3).unwrap();
    for i in 0..30 {
        let (first, len) = rowwise.row_span(i).unwrap();
        let row: Vec<f64> = (first..first + len).map(|j| a[(i, j)]).collect();
        rowwise.set_row(i, &row).unwrap();
    }
    for i in 0..30 {
        for j in 0..30 {
            assert_eq!(rowwise.get(i, j), entrywise.get(i, j), "({i}, {j})");
        }
    }
    assert_eq!(rowwise.row_span(2).unwrap(), (0, 6));
    assert_eq!(rowwise.row_span(3 + 6 * 2 + 5).unwrap(), (12, 12));
    assert_eq!(rowwise.row_span(27).unwrap(), (24, 6));
}

/// A row that is not there, a row of the wrong length and a right side of the wrong
/// length are errors that leave the matrix and the vector as they were, not panics.
#[test]
fn wrong_lengths_are_errors() {
    let a = random_abd::<5>(4, 3, Kind::General { diag: 3.0 }, 3);
    let mut lu = abd_of::<5, 10>(&a, 3);
    let before = lu.clone();
    assert!(matches!(lu.row_span(20), Err(LinalgError::Length(_))));
    // A top row (5 columns), an interval's (10) and a bottom row (5), each one short and
    // one long, and a row past the end.
    for (i, len) in [(0, 4), (0, 10), (4, 9), (4, 11), (19, 4), (19, 10), (20, 5)] {
        match lu.set_row(i, &vec![7.0; len]) {
            Err(LinalgError::Length(why)) => assert!(why.contains(&format!("row {i}")), "{why}"),
            other => panic!("row {i} of {len} values: {other:?}"),
        }
    }
    for i in 0..20 {
        for j in 0..20 {
            assert_eq!(lu.get(i, j), before.get(i, j), "({i}, {j})");
        }
    }
    let f = lu.factor().unwrap();
    assert_eq!(f.size(), 20);
    for len in [0, 19, 21] {
        let mut b = vec![1.0; len];
        match f.solve_in_place(&mut b) {
            Err(LinalgError::Length(why)) => assert!(why.contains("size 20"), "{why}"),
            other => panic!("right side of {len}: {other:?}"),
        }
        assert!(b.iter().all(|&v| v == 1.0));
        let mut x = vec![0.0; 20];
        assert!(matches!(f.solve(&b, &mut x), Err(LinalgError::Length(_))));
        let mut x = vec![0.0; len];
        assert!(matches!(
            f.solve(&[1.0; 20], &mut x),
            Err(LinalgError::Length(_))
        ));
    }
}

/// The factors are of the matrix as it was factored: rewriting the matrix leaves them
/// solving the old one, and factoring again into their storage solves the new one.
#[test]
fn factors_outlive_a_rewrite_and_are_reused() {
    let a = random_abd::<5>(
        6,
        3,
        Kind::Bvp {
            shuffle: true,
            zero_first: false,
        },
        4,
    );
    let mut lu = abd_of::<5, 10>(&a, 3);
    let f = lu.factor().unwrap();
    let b: Vec<f64> = (0..30).map(|i| (i as f64 * 0.3).cos()).collect();
    let mut x = vec![0.0; 30];
    f.solve(&b, &mut x).unwrap();
    assert!(relative_residual(&a, &x, &b) <= 1e-13);
    let a2 = a.map(|v| 2.0 * v);
    fill_from_dense(&mut lu, &a2);
    let mut y = vec![0.0; 30];
    f.solve(&b, &mut y).unwrap();
    assert_eq!(x, y, "the factors changed with the matrix");
    let f2 = lu.factor_reusing(Some(f)).unwrap();
    f2.solve(&b, &mut y).unwrap();
    assert!(relative_residual(&a2, &y, &b) <= 1e-13);
    // Factors of another shape are not reused but replaced.
    let other = abd_of::<5, 10>(&random_abd::<5>(3, 3, Kind::General { diag: 3.0 }, 5), 3);
    let f3 = other.factor_reusing(Some(f2)).unwrap();
    assert_eq!(f3.size(), 15);
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
            let res = check::<5, 10>(
                &random_abd::<5>(nodes, 3, kind, 100 + seed),
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
            check::<5, 10>(
                &random_abd::<5>(nodes, 5, Kind::ZeroLeft, 200 + seed),
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
    check::<5, 10>(&a, 5, "permutation-like");
    // The shell's split with node k's first column zero in interval k's rows.
    let a = random_abd::<5>(
        20,
        3,
        Kind::Bvp {
            shuffle: false,
            zero_first: true,
        },
        7,
    );
    let lu = abd_of::<5, 10>(&a, 3);
    lu.factor().unwrap();
    check::<5, 10>(&a, 3, "zero first column in every left block");
}

#[test]
fn singular_matrices_are_reported_singular() {
    // A zero column at node 4, unknown 2.
    let mut a = random_abd::<5>(10, 3, Kind::General { diag: 3.0 }, 1);
    a.column_mut(22).fill(0.0);
    let lu = abd_of::<5, 10>(&a, 3);
    match lu.factor() {
        Err(LinalgError::Singular(why)) => assert!(why.contains("column 22"), "{why}"),
        other => panic!("expected singular, got {other:?}"),
    }
    // Two rows of one interval block equal: singular up to rounding, caught by the
    // pivot test (not by an exact zero).
    let mut a = random_abd::<5>(10, 3, Kind::General { diag: 3.0 }, 2);
    for j in 0..50 {
        a[(3 + 5 * 6 + 1, j)] = a[(3 + 5 * 6 + 3, j)];
    }
    let lu = abd_of::<5, 10>(&a, 3);
    assert!(
        matches!(lu.factor(), Err(LinalgError::Singular(_))),
        "two equal rows"
    );
    // A row of interval 1 a combination of two others of its block, up to rounding.
    let mut a = random_abd::<5>(4, 3, Kind::General { diag: 3.0 }, 3);
    for j in 5..15 {
        a[(9, j)] = 0.5 * a[(10, j)] + 0.25 * a[(11, j)];
    }
    let lu = abd_of::<5, 10>(&a, 3);
    assert!(
        matches!(lu.factor(), Err(LinalgError::Singular(_))),
        "a row that is a combination of two others"
    );
    // Non-finite entries.
    let mut a = random_abd::<5>(4, 3, Kind::General { diag: 3.0 }, 4);
    a[(10, 9)] = f64::NAN;
    let lu = abd_of::<5, 10>(&a, 3);
    assert!(matches!(lu.factor(), Err(LinalgError::Singular(_))));
    // The bottom rows alone cannot fix the last node: the last stage is singular.
    let mut a = random_abd::<5>(3, 3, Kind::General { diag: 3.0 }, 5);
    for j in 0..15 {
        a[(14, j)] = a[(13, j)];
    }
    let lu = abd_of::<5, 10>(&a, 3);
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
    let a = random_abd::<5>(
        6,
        3,
        Kind::Bvp {
            shuffle: true,
            zero_first: false,
        },
        9,
    );
    let mut lu = abd_of::<5, 10>(&a, 3);
    lu.factor().unwrap();
    lu.zero_boundary();
    lu.poison_blocks();
    for i in 0..30 {
        for j in 0..30 {
            if in_structure::<5>(6, 3, i, j) && (i, j) != (12, 14) {
                lu.set(i, j, a[(i, j)]);
            }
        }
    }
    assert!(matches!(lu.factor(), Err(LinalgError::Singular(_))));
    lu.set(12, 14, a[(12, 14)]);
    let f = lu.factor().unwrap();
    assert!(
        f.growth() >= 1.0 && f.growth() < 1e3,
        "growth {}",
        f.growth()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Either block width, any split and 1–150 nodes, BVP-like blocks shuffled or not, with
    /// or without zero first columns, or fully random blocks on a few nodes, or zero left
    /// blocks: residual ≤ 1e-13 against the dense matrix.
    #[test]
    fn abd_solves_match_dense_lu(
        nodes in 1usize..150,
        top in 0usize..=6,
        which in 0usize..4,
        flags in any::<(bool, bool)>(),
        seed in 0u64..1_000_000,
        six in any::<bool>(),
    ) {
        let node = if six { 6 } else { 5 };
        let top = top.min(node);
        let (kind, nodes, top) = match which {
            0 | 1 => (Kind::Bvp { shuffle: flags.0, zero_first: flags.1 }, nodes, top),
            2 => (Kind::General { diag: if flags.0 { 2.0 } else { 0.0 } }, 1 + nodes % 5, top),
            _ => (Kind::ZeroLeft, nodes, node),
        };
        let a = if six {
            random_abd::<6>(nodes, top, kind, seed)
        } else {
            random_abd::<5>(nodes, top, kind, seed)
        };
        // Skip the rare random matrix dense LU itself cannot solve accurately.
        let dense = a.clone().lu();
        let b = DVector::from_fn(a.nrows(), |i, _| (i as f64 * 0.37).cos());
        let ok = dense
            .solve(&b)
            .is_some_and(|x| relative_residual(&a, x.as_slice(), b.as_slice()) <= 1e-14);
        prop_assume!(ok);
        let mut x = b.as_slice().to_vec();
        if six {
            abd_of::<6, 12>(&a, top).factor().unwrap().solve_in_place(&mut x).unwrap();
        } else {
            abd_of::<5, 10>(&a, top).factor().unwrap().solve_in_place(&mut x).unwrap();
        }
        let res = relative_residual(&a, &x, b.as_slice());
        prop_assert!(res <= 1e-13, "residual {:e}", res);
    }
}
