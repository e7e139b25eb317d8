//! The almost-block-diagonal linear solver (`solver.linear = "block"`) against band LU on
//! the shell's own Jacobians: the assembly straight into the blocks holds the same matrix
//! as the dense assembly; Newton with it reaches the band solution to 1e-12 on every scheme
//! and scene shape (trapezoid and Hermite–Simpson, uniform and non-uniform thickness with
//! its jump node, fibres or not, pole and cornea grading); and the exact sphere converges at
//! the schemes' orders with it. (The whole numerics suite runs with it too:
//! `EYESHELL_TEST_LINEAR=block`, see common.rs.)

use crate::common::*;
use eyeshell_core::bvp;
use eyeshell_core::bvp::discretisation::{DenseSink, NY, POLE_ROWS};
use eyeshell_core::bvp::settings::{LinearSolverKind, Scheme, SolverSettings};
use eyeshell_core::bvp::solve::{discretise, sphere_guess};
use eyeshell_core::model::params::{Params, Thickness};
use eyeshell_linalg::AbdLu;
use nalgebra::{DMatrix, DVector};

fn scenes() -> Vec<(&'static str, Params)> {
    vec![
        ("exact sphere", exact_sphere()),
        ("uniform, D = 0", Params::default()),
        (
            "non-uniform, D = 0",
            Params {
                thickness: Thickness::NonUniform,
                ..Params::default()
            },
        ),
        ("non-uniform, D = 200", fibre_shell()),
    ]
}

fn solve_with(p: &Params, nodes: usize, scheme: Scheme, linear: LinearSolverKind) -> bvp::Solution {
    let s = SolverSettings {
        linear,
        ..settings(nodes, scheme)
    };
    bvp::solve(p, &s, None).unwrap_or_else(|e| panic!("{linear:?}, N = {nodes}, {scheme:?}: {e}"))
}

/// The Jacobian written into the blocks (interval blocks whole, through `set_block`) is the
/// dense one entry for entry, and the block LU solves it to a relative residual ≤ 1e-13.
#[test]
fn assembly_into_blocks_is_the_jacobian_and_solves_it() {
    for (name, p) in scenes() {
        for scheme in [Scheme::Trapezoid, Scheme::HermiteSimpson] {
            let mut disc = discretise(&p, &settings(61, scheme)).unwrap();
            let n = disc.len();
            let mut u = sphere_guess(&disc, p.r0);
            for (k, v) in u.iter_mut().enumerate() {
                *v *= 1.0 + 1e-3 * ((k % 7) as f64 - 3.0); // off the solution: every term counts
            }
            let mut dense = DenseSink::new(n);
            disc.jacobian(&u, &mut dense).unwrap();
            let mut lu = AbdLu::new(n / NY, POLE_ROWS).unwrap();
            lu.poison_blocks(); // every block entry must be written
            disc.jacobian(&u, &mut lu).unwrap();
            assert_eq!(lu.take_outside(), 0);
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(
                        lu.get(i, j),
                        dense.get(i, j),
                        "{name}, {scheme:?}: ({i},{j})"
                    );
                }
            }
            let f = lu.factor().unwrap();
            let a = DMatrix::from_row_slice(n, n, &dense.data);
            let b: Vec<f64> = (0..n).map(|i| (0.3 * i as f64).sin()).collect();
            let mut x = b.clone();
            f.solve_in_place(&mut x).unwrap();
            let r = &a * DVector::from_column_slice(&x) - DVector::from_column_slice(&b);
            let norm_a = a.row_iter().map(|r| r.abs().sum()).fold(0.0, f64::max);
            let x_max = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let b_max = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let res = r.amax() / (norm_a * x_max + b_max);
            println!(
                "{name}, {scheme:?}: residual {res:.2e}, growth {:.2}",
                f.growth()
            );
            assert!(res <= 1e-13, "{name}, {scheme:?}: residual {res:e}");
        }
    }
}

/// Newton with the block solver and with band LU: same solution to 1e-12 (relative to each
/// unknown's size), on every scene shape and both schemes.
#[test]
fn block_and_band_give_the_same_solution() {
    for (name, p) in scenes() {
        for (nodes, scheme) in [(201, Scheme::Trapezoid), (401, Scheme::HermiteSimpson)] {
            let band = solve_with(&p, nodes, scheme, LinearSolverKind::Band);
            let block = solve_with(&p, nodes, scheme, LinearSolverKind::Block);
            assert_eq!(band.u.len(), block.u.len());
            let diff = band
                .u
                .iter()
                .zip(&block.u)
                .map(|(a, b)| (a - b).abs() / a.abs().max(1.0))
                .fold(0.0, f64::max);
            println!(
                "{name}, {scheme:?}, N = {nodes}: block vs band {diff:.2e}, Newton {} vs {}",
                block.stats.newton_iterations, band.stats.newton_iterations
            );
            assert!(
                diff <= 1e-12,
                "{name}, {scheme:?}: block and band differ by {diff:e}"
            );
        }
    }
}

/// The exact sphere (docs/MODEL.md §7) with the block solver: order 4 for Hermite–Simpson.
#[test]
fn exact_sphere_converges_at_order_4_with_the_block_solver() {
    let p = exact_sphere();
    let ladder = [51, 101, 201, 401];
    let errors: Vec<f64> = ladder
        .iter()
        .map(|&n| {
            let sol = solve_with(&p, n, Scheme::HermiteSimpson, LinearSolverKind::Block);
            let a = sol.stats.cornea_alpha;
            sol.rows
                .iter()
                .flat_map(|row| {
                    let x = row.sigma_ref;
                    let exact = exact_sphere_fields(&p, a, x);
                    five(row).into_iter().zip(exact).map(|(v, e)| (v - e).abs())
                })
                .fold(0.0, f64::max)
        })
        .collect();
    let q = orders(&errors);
    println!("block, HS: errors {} orders {q:.3?}", sci(&errors));
    for o in q {
        assert!((o - 4.0).abs() <= 0.3, "order {o}");
    }
}
