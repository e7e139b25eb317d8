//! Canonical problems shared by the tests: the exact sphere of docs/MODEL.md §7 and the paper's
//! scenes, as diffsol keeps its test models.
#![allow(dead_code)]

use eyeshell_core::bvp::settings::{LinearSolverKind, Scheme, SolverSettings};
use eyeshell_core::bvp::{self, Solution};
use eyeshell_core::model::params::{Params, Thickness};

/// docs/MODEL.md §7: uniform H0, D = 0, cornea of the sclera's material and radius.
pub fn exact_sphere() -> Params {
    Params::default().exact_sphere()
}

/// The non-uniform shell with fibres, D = 200.
pub fn fibre_shell() -> Params {
    Params {
        thickness: Thickness::NonUniform,
        d: 200.0,
        ..Params::default()
    }
}

/// The tests' settings. `EYESHELL_TEST_LINEAR=band|klu|block` picks the linear solver of
/// every test that uses them (default: the scene default), so that the whole elastic suite
/// runs with each: `EYESHELL_TEST_LINEAR=block cargo test --release -p eyeshell-core --test numerics`.
pub fn settings(nodes: usize, scheme: Scheme) -> SolverSettings {
    SolverSettings {
        nodes,
        scheme,
        newton_tol: 1e-12,
        linear: test_linear(),
        ..SolverSettings::default()
    }
}

/// The linear solver `EYESHELL_TEST_LINEAR` names (the default one if unset).
pub fn test_linear() -> LinearSolverKind {
    match std::env::var("EYESHELL_TEST_LINEAR").as_deref() {
        Err(_) | Ok("") => SolverSettings::default().linear,
        Ok("band") => LinearSolverKind::Band,
        Ok("klu") => LinearSolverKind::Klu,
        Ok("block") => LinearSolverKind::Block,
        Ok(other) => panic!("EYESHELL_TEST_LINEAR={other}: expected band, klu or block"),
    }
}

pub fn solve(p: &Params, nodes: usize, scheme: Scheme) -> Solution {
    bvp::solve(p, &settings(nodes, scheme), None)
        .unwrap_or_else(|e| panic!("solve failed at N = {nodes}, {scheme:?}: {e}"))
}

/// The five fields of bvp4c's state at a node: κ, α_s, r, θ, Q.
pub fn five(row: &eyeshell_core::bvp::FieldRow) -> [f64; 5] {
    [row.kappa, row.alpha_s, row.r, row.theta, row.q]
}

/// Observed orders log2(e_k / e_{k+1}) of a ladder whose spacing halves.
pub fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// A list of numbers in short scientific notation, for the tables the tests print.
pub fn sci(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.2e}")).collect();
    format!("[{}]", parts.join(", "))
}

/// The exact solution (docs/MODEL.md §7) at material point Σ = x of the sphere `p` inflated
/// to stretch `a` (the cornea's α): κ, α_s, r, θ, Q.
pub fn exact_sphere_fields(p: &Params, a: f64, x: f64) -> [f64; 5] {
    [
        1.0 / (a * p.r0),
        a,
        a * p.r0 * (x / p.r0).sin(),
        x / p.r0,
        0.0,
    ]
}

/// [`eyeshell_core::growth::grow`] of the problem these parts make, checked by its builder (a
/// part the builder refuses is a mistake in the test).
pub fn grow(
    params: &Params,
    solver: &SolverSettings,
    growth: &eyeshell_core::growth::GrowthParams,
    settings: &eyeshell_core::growth::GrowthSettings,
    observer: &mut dyn eyeshell_core::growth::Observer,
) -> Result<eyeshell_core::growth::GrowthStats, eyeshell_core::growth::GrowthError> {
    let elastic = eyeshell_core::problem::ElasticProblem::builder()
        .params(*params)
        .solver(*solver)
        .build()
        .expect("the test's shell is a valid problem");
    let problem = eyeshell_core::problem::GrowthProblem::builder(elastic)
        .growth(growth.clone())
        .settings(settings.clone())
        .build()
        .expect("the test's growth is a valid problem");
    eyeshell_core::growth::grow(&problem, observer)
}

/// `base` with E_b, D and C set (C both the sclera's and the cornea's, as `eyeshell extremes`
/// pushes it), ΔP held below half the cornea's limit so that a soft shell stays admissible:
/// the shells of the parameter sweeps.
pub fn pushed(base: Params, e_b: f64, d: f64, c: f64) -> Params {
    let cornea = eyeshell_core::model::params::CorneaParams { c, ..base.cornea };
    Params {
        e_b,
        d,
        c,
        cornea,
        dp: base
            .dp
            .min(0.5 * eyeshell_core::model::cornea::max_pressure(&cornea)),
        ..base
    }
}
