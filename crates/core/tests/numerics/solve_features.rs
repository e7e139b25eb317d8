//! The solve's other promises: KLU gives the band answer, warm starts save Newton work,
//! the interpolant keeps the scheme's order between nodes, and the first integral holds to
//! the size of the discretisation error on the fibre shell.

use crate::common::*;
use eyeshell_core::bvp;
use eyeshell_core::bvp::settings::{LinearSolverKind, Scheme, SolverSettings};
use eyeshell_core::model::params::Params;

#[test]
fn klu_and_band_give_the_same_solution() {
    assert!(
        eyeshell_sundials::klu_available(),
        "KLU is not built in: install libsuitesparse-dev"
    );
    let p = fibre_shell();
    let band = solve(&p, 401, Scheme::HermiteSimpson);
    let s = SolverSettings {
        linear: LinearSolverKind::Klu,
        ..settings(401, Scheme::HermiteSimpson)
    };
    let klu = bvp::solve(&p, &s, None).unwrap();
    let diff = band
        .u
        .iter()
        .zip(&klu.u)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!(
        "KLU vs band: max difference {diff:.2e}, Newton {} vs {}",
        klu.stats.newton_iterations, band.stats.newton_iterations
    );
    assert!(diff < 1e-11, "KLU and band differ by {diff:e}");
}

#[test]
fn warm_start_from_a_nearby_pressure_saves_newton_work() {
    let p = fibre_shell();
    let s = settings(501, Scheme::HermiteSimpson);
    let near = bvp::solve(&Params { dp: 2.02, ..p }, &s, None).unwrap();
    let cold = bvp::solve(&p, &s, None).unwrap();
    let warm = bvp::solve(&p, &s, Some(&near)).unwrap();
    let diff = cold
        .u
        .iter()
        .zip(&warm.u)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!(
        "cold {} iterations, warm {}; difference {diff:.2e}",
        cold.stats.newton_iterations, warm.stats.newton_iterations
    );
    assert!(warm.stats.newton_iterations < cold.stats.newton_iterations);
    assert!(diff < 1e-10);
    // From a different mesh the warm start interpolates and still converges to the same answer.
    let coarse = bvp::solve(&p, &settings(201, Scheme::HermiteSimpson), None).unwrap();
    let from_coarse = bvp::solve(&p, &s, Some(&coarse)).unwrap();
    let diff = cold
        .u
        .iter()
        .zip(&from_coarse.u)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-10, "warm start from another mesh: {diff:e}");
}

/// Between nodes the interpolant's error on the exact sphere falls at order 4.
#[test]
fn interpolant_keeps_order_4_between_nodes() {
    let p = exact_sphere();
    let mut errors = vec![];
    for n in [51, 101, 201] {
        let sol = solve(&p, n, Scheme::HermiteSimpson);
        let a = sol.stats.cornea_alpha;
        let mut worst: f64 = 0.0;
        for w in sol.mesh.nodes.windows(2).skip(sol.mesh.pole_nodes + 1) {
            let x = 0.5 * (w[0] + w[1]);
            let row = sol.at(x).unwrap();
            let exact = [
                1.0 / (a * p.r0),
                a,
                a * p.r0 * (x / p.r0).sin(),
                x / p.r0,
                0.0,
            ];
            for (v, e) in five(&row).iter().zip(exact) {
                worst = worst.max((v - e).abs());
            }
        }
        errors.push(worst);
        // At a node the interpolant returns the node's row.
        let k = sol.mesh.len() / 2;
        assert_eq!(sol.at(sol.mesh.nodes[k]).unwrap(), sol.rows[k]);
    }
    let q = orders(&errors);
    println!("midpoint errors {} orders {q:.2?}", sci(&errors));
    assert!(q.iter().all(|&o| (o - 4.0).abs() < 0.3), "orders {q:?}");
    let sol = solve(&p, 51, Scheme::HermiteSimpson);
    assert!(sol.at(0.0).is_err() && sol.at(p.length() + 1e-9).is_err());
}

/// max |Q cos θ + r t_s sin θ − r²ΔP/2| falls with the mesh at the scheme's order.
#[test]
fn first_integral_falls_at_the_scheme_order() {
    let p = fibre_shell();
    for (scheme, ladder) in [
        (Scheme::Trapezoid, [101, 201, 401]),
        (Scheme::HermiteSimpson, [101, 201, 401]),
    ] {
        let fi: Vec<f64> = ladder
            .iter()
            .map(|&n| solve(&p, n, scheme).stats.first_integral_max)
            .collect();
        let q = orders(&fi);
        println!("{scheme:?}: first integral {} orders {q:.2?}", sci(&fi));
        let p_ = scheme.order() as f64;
        assert!(
            q.iter().all(|&o| (o - p_).abs() < 0.3),
            "{scheme:?}: orders {q:?}"
        );
    }
}

/// A hopeless shell (E_b = 1e-200: a coefficient 1/E_b of 1e200) can keep KINSOL's line
/// search evaluating the residual for minutes inside one call. Each Newton solve may
/// make at most 20 residual evaluations per allowed iteration, so the whole continuation
/// fails, saying where, in a bounded number of evaluations (well under a second here; the
/// limit below only guards against a hang).
#[test]
fn a_hopeless_shell_fails_within_a_bounded_effort() {
    for grading in [true, false] {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let p = Params {
                e_b: 1e-200,
                ..Params::default()
            };
            let s = SolverSettings {
                cornea_grading: grading,
                ..SolverSettings::default()
            };
            let _ = tx.send(
                bvp::solve(&p, &s, None)
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
            );
        });
        let outcome = rx
            .recv_timeout(std::time::Duration::from_secs(120))
            .expect("the solve of E_b = 1e-200 must end (it used to run for minutes)");
        let message = outcome.expect_err("E_b = 1e-200 has no solution to find");
        if grading {
            // Its bending layer (1e-100 mm) cannot be graded in double precision: refused
            // before the mesh is laid.
            assert!(
                message.contains("thinner than double precision"),
                "{message}"
            );
        } else {
            // Ungraded, Newton stalls: its residual (terms of 1e200) cannot fall, while its
            // correction is within newton_tol, so it is named a precision limit, with the
            // mesh's nodes.
            assert!(
                message.starts_with("Newton stalled at a scaled residual of ")
                    && message.contains(" nodes")
                    && message.contains("below what double precision reaches"),
                "{message}"
            );
        }
    }
}
