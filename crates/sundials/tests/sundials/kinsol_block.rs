//! KINSOL with the almost-block-diagonal solver (`LinearSolverSpec::Block`): a nonlinear
//! two-point BVP with five unknowns per node (trapezoid rule, three conditions at the start
//! and two at the end, the shell's shape) has the same root as with band LU and dense LU;
//! the factorisation is reused by `solve_with_last_factorization`; a singular Jacobian
//! stops KINSOL with the block LU's own message; a panicking Jacobian is a callback error;
//! the standalone solver reports a singular matrix; many create/drop cycles.

use crate::sundials_support::*;

use eyeshell_sundials::{
    CallbackResult, Context, JacobianMatrix, Kinsol, LinearSolver, LinearSolverSpec, MatrixSink,
    NVector, NonlinearSystem, SundialsError,
};

/// y' = f(y) on [0, 1], y ∈ R⁵, by the trapezoid rule on `nodes` nodes:
/// f = (y₁, −sin y₀ + y₃/10, y₄ − y₂, cos(y₀)/5 − y₃, y₀ y₁ / 10),
/// y₀(0) = 1, y₁(0) = 0.5, y₂(0) = 0 at the start, y₃(1) = 0.1, y₄(1) = −0.2 at the end.
struct FiveBvp {
    nodes: usize,
    /// Zero column 5 (node 1, unknown 0) of the Jacobian: singular.
    singular: bool,
    panic: bool,
}

fn f(y: &[f64]) -> [f64; 5] {
    [
        y[1],
        -y[0].sin() + 0.1 * y[3],
        y[4] - y[2],
        0.2 * y[0].cos() - y[3],
        0.1 * y[0] * y[1],
    ]
}

fn df(y: &[f64]) -> [[f64; 5]; 5] {
    [
        [0.0, 1.0, 0.0, 0.0, 0.0],
        [-y[0].cos(), 0.0, 0.0, 0.1, 0.0],
        [0.0, 0.0, -1.0, 0.0, 1.0],
        [-0.2 * y[0].sin(), 0.0, 0.0, -1.0, 0.0],
        [0.1 * y[1], 0.1 * y[0], 0.0, 0.0, 0.0],
    ]
}

impl NonlinearSystem for FiveBvp {
    fn residual(&mut self, u: &[f64], r: &mut [f64]) -> CallbackResult {
        let (m, h) = (self.nodes, 1.0 / (self.nodes - 1) as f64);
        r[0] = u[0] - 1.0;
        r[1] = u[1] - 0.5;
        r[2] = u[2];
        for k in 0..m - 1 {
            let (a, b) = (&u[5 * k..5 * k + 5], &u[5 * k + 5..5 * k + 10]);
            let (fa, fb) = (f(a), f(b));
            for e in 0..5 {
                r[3 + 5 * k + e] = b[e] - a[e] - 0.5 * h * (fa[e] + fb[e]);
            }
        }
        let n = 5 * m;
        r[n - 2] = u[n - 2] - 0.1;
        r[n - 1] = u[n - 1] + 0.2;
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        assert!(!self.panic, "a bug in the Jacobian");
        let (m, h) = (self.nodes, 1.0 / (self.nodes - 1) as f64);
        for e in 0..3 {
            jac.set(e, e, 1.0);
        }
        for k in 0..m - 1 {
            let (ja, jb) = (df(&u[5 * k..5 * k + 5]), df(&u[5 * k + 5..5 * k + 10]));
            for e in 0..5 {
                for c in 0..5 {
                    let id = if e == c { 1.0 } else { 0.0 };
                    let (mut left, right) = (-id - 0.5 * h * ja[e][c], id - 0.5 * h * jb[e][c]);
                    if self.singular && k == 1 && c == 0 {
                        left = 0.0;
                    }
                    jac.set(3 + 5 * k + e, 5 * k + c, left);
                    let right = if self.singular && k == 0 && c == 0 {
                        0.0
                    } else {
                        right
                    };
                    jac.set(3 + 5 * k + e, 5 * k + 5 + c, right);
                }
            }
        }
        let n = 5 * m;
        jac.set(n - 2, n - 2, 1.0);
        jac.set(n - 1, n - 1, 1.0);
        Ok(())
    }
}

/// The boundary values at every node: a guess Newton converges from (zero does not: its
/// steps hit KINSOL's largest step, with any linear solver).
fn guess(nodes: usize) -> Vec<f64> {
    [1.0, 0.5, 0.0, 0.1, -0.2].repeat(nodes)
}

fn bvp(nodes: usize) -> FiveBvp {
    FiveBvp {
        nodes,
        singular: false,
        panic: false,
    }
}

fn solve(nodes: usize, spec: LinearSolverSpec) -> Result<Vec<f64>, SundialsError> {
    let n = 5 * nodes;
    let mut kin = Kinsol::new(bvp(nodes), n, spec, &tight())?;
    let mut u = guess(nodes);
    let stats = kin.solve(&mut u, &vec![1.0; n], &vec![1.0; n])?;
    assert!(stats.iterations >= 2 && stats.fnorm <= 1e-11, "{stats:?}");
    Ok(u)
}

#[test]
fn block_band_and_dense_find_the_same_root() {
    for nodes in [2, 3, 40, 401] {
        let band = solve(nodes, LinearSolverSpec::Band { upper: 6, lower: 7 })
            .unwrap_or_else(|e| panic!("band, {nodes} nodes: {e}"));
        let block = solve(nodes, LinearSolverSpec::Block { nodes, top: 3 })
            .unwrap_or_else(|e| panic!("block, {nodes} nodes: {e}"));
        let d = max_diff(&block, &band);
        assert!(d <= 1e-12, "{nodes} nodes: block and band differ by {d:e}");
        assert!((block[0] - 1.0).abs() < 1e-14 && (block[5 * nodes - 1] + 0.2).abs() < 1e-14);
        if nodes <= 40 {
            let dense = solve(nodes, LinearSolverSpec::Dense).unwrap();
            let d = max_diff(&block, &dense);
            assert!(d <= 1e-12, "{nodes} nodes: block and dense differ by {d:e}");
        }
    }
}

#[test]
fn the_last_factorization_solves_again() {
    let nodes = 30;
    let n = 5 * nodes;
    let by = |spec| {
        let mut kin = Kinsol::new(bvp(nodes), n, spec, &tight()).unwrap();
        let mut u = guess(nodes);
        kin.solve(&mut u, &vec![1.0; n], &vec![1.0; n]).unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).cos()).collect();
        let mut x = vec![0.0; n];
        kin.solve_with_last_factorization(&mut x, &b).unwrap();
        let mut x2 = vec![0.0; n];
        kin.solve_with_last_factorization(&mut x2, &b).unwrap();
        assert_eq!(x, x2, "the factors are not changed by a solve");
        x
    };
    let block = by(LinearSolverSpec::Block { nodes, top: 3 });
    let band = by(LinearSolverSpec::Band { upper: 6, lower: 7 });
    let scale = band.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    assert!(max_diff(&block, &band) <= 1e-12 * scale);
}

#[test]
fn a_singular_jacobian_stops_kinsol_with_the_block_message() {
    let nodes = 10;
    let n = 5 * nodes;
    let sys = FiveBvp {
        singular: true,
        ..bvp(nodes)
    };
    let mut kin = Kinsol::new(sys, n, LinearSolverSpec::Block { nodes, top: 3 }, &tight()).unwrap();
    let mut u = vec![0.0; n];
    let err = kin.solve(&mut u, &vec![1.0; n], &vec![1.0; n]).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("block LU") && text.contains("column 5"),
        "{text}"
    );
}

#[test]
fn a_panicking_jacobian_is_a_callback_error() {
    let nodes = 5;
    let n = 5 * nodes;
    let sys = FiveBvp {
        panic: true,
        ..bvp(nodes)
    };
    let mut kin = Kinsol::new(sys, n, LinearSolverSpec::Block { nodes, top: 3 }, &tight()).unwrap();
    let mut u = vec![0.0; n];
    match kin.solve(&mut u, &vec![1.0; n], &vec![1.0; n]) {
        Err(SundialsError::Callback(m)) => assert!(m.contains("a bug in the Jacobian"), "{m}"),
        other => panic!("expected a callback error, got {other:?}"),
    }
}

#[test]
fn standalone_block_solver_and_its_misuse() {
    let ctx = Context::new().unwrap();
    // The size must be 5 · nodes.
    assert!(
        LinearSolver::for_spec(&ctx, 11, &LinearSolverSpec::Block { nodes: 2, top: 3 }).is_err()
    );
    assert!(
        LinearSolver::for_spec(&ctx, 10, &LinearSolverSpec::Block { nodes: 2, top: 6 }).is_err()
    );
    let (mut a, mut ls) =
        LinearSolver::for_spec(&ctx, 10, &LinearSolverSpec::Block { nodes: 2, top: 3 }).unwrap();
    let b = NVector::from_slice(&ctx, &[1.0; 10]).unwrap();
    let mut x = NVector::new(&ctx, 10).unwrap();
    // All zero: singular, with the block LU's reason in the error.
    let err = ls.setup(&mut a).unwrap_err().to_string();
    assert!(
        err.contains("block LU") && err.contains("column 0"),
        "{err}"
    );
    // Top rows 2 x_i = 1 (i < 3); interval rows x_{5+e} + 4 x_e [e ≥ 3] = 1; bottom rows
    // x_8 = x_9 = 1: the solution (½, ½, ½, 0, 0, 1, 1, 1, 1, 1), with pivots off the diagonal.
    {
        let mut v = a.view_mut();
        for i in 0..3 {
            v.set(i, i, 2.0);
        }
        for e in 0..5 {
            v.set(3 + e, 5 + e, 1.0);
            if e >= 3 {
                v.set(3 + e, e, 4.0);
            }
        }
        v.set(8, 8, 1.0);
        v.set(9, 9, 1.0);
    }
    ls.setup(&mut a).unwrap();
    ls.solve(&mut a, &mut x, &b).unwrap();
    let want = [0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0];
    assert!(max_diff(x.as_slice(), &want) < 1e-15, "{:?}", x.as_slice());
    // The assembled matrix survives its factorisation and copies whole.
    let (mut a2, _) =
        LinearSolver::for_spec(&ctx, 10, &LinearSolverSpec::Block { nodes: 2, top: 3 }).unwrap();
    a2.copy_from(&a).unwrap();
    let v = a2.view_mut();
    assert_eq!(
        (v.get(6, 3), v.get(3, 5), v.get(9, 9), v.get(3, 0)),
        (4.0, 1.0, 1.0, 0.0)
    );
}

#[test]
fn many_create_and_drop_cycles() {
    for k in 0..200 {
        let nodes = 2 + k % 7;
        let u = solve(nodes, LinearSolverSpec::Block { nodes, top: 3 }).unwrap();
        assert!((u[0] - 1.0).abs() < 1e-14);
    }
}
