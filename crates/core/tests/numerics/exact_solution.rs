//! docs/MODEL.md §7: the uniformly inflated sphere solves the continuous problem exactly, so the
//! discrete solutions must converge to it at the schemes' orders, down to round-off.

use crate::common::*;
use eyeshell_core::bvp::settings::Scheme;

/// Largest absolute error over all nodes and the five fields (κ, α_s, r, θ, Q). (t_s at the
/// pole carries the O(ε²) truncation of the pole conditions, 2e-7 at ε = 1e-3: see
/// `pole_truncation_is_order_epsilon_squared`.)
fn max_error(nodes: usize, scheme: Scheme) -> f64 {
    let p = exact_sphere();
    let sol = solve(&p, nodes, scheme);
    let a = sol.stats.cornea_alpha;
    let mut worst: f64 = 0.0;
    for row in &sol.rows {
        let x = row.sigma_ref;
        let exact = exact_sphere_fields(&p, a, x);
        for (v, e) in five(row).iter().zip(exact) {
            worst = worst.max((v - e).abs());
        }
    }
    worst
}

fn check_order(scheme: Scheme, ladder: &[usize]) -> Vec<f64> {
    let errors: Vec<f64> = ladder.iter().map(|&n| max_error(n, scheme)).collect();
    let orders = orders(&errors);
    println!(
        "{scheme:?}: N = {ladder:?}\n  errors = {}\n  orders = {orders:.3?}",
        sci(&errors)
    );
    for (k, q) in orders.iter().enumerate() {
        let p = scheme.order() as f64;
        assert!(
            (q - p).abs() <= 0.3,
            "{scheme:?}: order {q:.3} between N = {} and {}",
            ladder[k],
            ladder[k + 1]
        );
    }
    errors
}

#[test]
fn trapezoid_converges_at_order_2() {
    check_order(Scheme::Trapezoid, &[101, 201, 401, 801, 1601]);
}

#[test]
fn hermite_simpson_converges_at_order_4() {
    check_order(Scheme::HermiteSimpson, &[51, 101, 201, 401]);
}

#[test]
fn hermite_simpson_at_1601_is_within_1e_9() {
    let e = max_error(1601, Scheme::HermiteSimpson);
    println!("HS N = 1601: max error {e:.3e}");
    assert!(e < 1e-9, "error {e:e}");
}

#[test]
fn first_integral_holds_to_discretisation_error() {
    let p = exact_sphere();
    for (n, scheme) in [(201, Scheme::Trapezoid), (201, Scheme::HermiteSimpson)] {
        let sol = solve(&p, n, scheme);
        let e = max_error(n, scheme);
        let fi = sol.stats.first_integral_max;
        println!("{scheme:?} N = {n}: first integral {fi:.3e}, error {e:.3e}");
        // Q cos θ + r t_s sin θ − r²ΔP/2 is O(r t_s) times the error of the fields.
        assert!(
            fi < 10.0 * p.r0 * 13.0 * e.max(1e-13),
            "first integral {fi:e} vs error {e:e}"
        );
    }
}
