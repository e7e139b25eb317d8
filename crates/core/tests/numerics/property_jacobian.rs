//! The analytic Jacobian equals central differences at random states AND random parameters:
//! ΔP, C, D ∈ {0} ∪ [1, 1e4], E_b, H0, thickness uniform/non-uniform, R0, fraction, the
//! cornea, ε ∈ [1e-5, 1e-1] and N = 9..15, for both schemes. jacobian.rs (beside this file) covers random
//! states at the default parameters; the comparison (steps and the round-off-aware
//! tolerance) is the same.

use eyeshell_core::bvp::discretisation::DenseSink;
use eyeshell_core::bvp::settings::{Scheme, SolverSettings};
use eyeshell_core::bvp::solve::{discretise, sphere_guess};
use eyeshell_core::model::cornea;
use eyeshell_core::model::params::{CorneaParams, Params, Thickness};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

#[derive(Clone, Debug)]
struct Case {
    p: Params,
    nodes: usize,
    epsilon: f64,
    noise: Vec<f64>,
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.log10()..hi.log10()).prop_map(|e| 10f64.powf(e))
}

fn case() -> impl Strategy<Value = Case> {
    let material = (
        log_uniform(10.0, 1e4),                        // C
        prop_oneof![Just(0.0), log_uniform(1.0, 1e4)], // D
        log_uniform(0.1, 1e3),                         // E_b
        0.05f64..2.0,                                  // H0
        prop_oneof![Just(Thickness::Uniform), Just(Thickness::NonUniform)],
    );
    let geometry = (
        5.0f64..20.0,            // R0
        0.5f64..0.9,             // fraction
        log_uniform(10.0, 1e4),  // cornea C_c
        0.3f64..1.0,             // ΔP as a fraction of the limit (see below)
        log_uniform(1e-5, 1e-1), // ε
        9usize..=15,             // N
    );
    (material, geometry, prop::collection::vec(-1.0f64..1.0, 7)).prop_map(
        |((c, d, e_b, h0, thickness), (r0, fraction, c_c, dp_frac, epsilon, nodes), noise)| {
            let cornea = CorneaParams { c: c_c, h: h0, r0 };
            // ΔP below the cornea's limit, and below the limit pressure of a neo-Hookean
            // sphere of the sclera's C, H0, R0: past that the shell has no inflated state
            // near the sphere, α_s runs to 10–100 and the terms of the equations outgrow
            // their typical sizes (the scales of the round-off tolerance) by as much.
            let sclera = CorneaParams { c, h: h0, r0 };
            let dp = dp_frac * cornea::max_pressure(&cornea).min(cornea::max_pressure(&sclera));
            let p = Params {
                dp,
                c,
                e_b,
                thickness,
                h0,
                d,
                cornea,
                r0,
                fraction,
                cornea_follows_radius: true,
            };
            Case {
                p,
                nodes,
                epsilon,
                noise,
            }
        },
    )
}

/// jacobian.rs's comparison, at the case's parameters, mesh and perturbed state.
fn check(case: &Case, scheme: Scheme) -> Result<(), TestCaseError> {
    let p = &case.p;
    let s = SolverSettings {
        nodes: case.nodes,
        epsilon: case.epsilon,
        scheme,
        ..SolverSettings::default()
    };
    let mut disc = discretise(p, &s).map_err(|e| TestCaseError::fail(format!("{case:?}: {e}")))?;
    let n = disc.len();
    let typ = disc.typical(p.r0);
    let mut u = sphere_guess(&disc, p.r0);
    // Relative noise of up to 2 % on every unknown (q_s, zero on the sphere, gets 2 % of t_s).
    for k in 0..n {
        let size = if k % 5 == 3 { typ[3] } else { u[k].abs() };
        u[k] += 0.02 * size * case.noise[k % case.noise.len()] * (1.0 + (k as f64).sin()) / 2.0;
    }
    let (_, f_scale) = disc.scales(p.r0);
    let mut jac = DenseSink::new(n);
    disc.jacobian(&u, &mut jac)
        .map_err(|e| TestCaseError::fail(format!("{case:?}: {e:?}")))?;
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    let mut differences = |u: &[f64], j: usize, h: f64| -> Vec<f64> {
        let mut up = u.to_vec();
        up[j] += h;
        let mut um = u.to_vec();
        um[j] -= h;
        disc.residual(&up, &mut fp).unwrap();
        disc.residual(&um, &mut fm).unwrap();
        (0..n).map(|i| (fp[i] - fm[i]) / (2.0 * h)).collect()
    };
    for j in 0..n {
        // Steps relative to κ, r, t_s (never near zero) and absolute for θ and q_s, which
        // vanish at the pole.
        let floor = if matches!(j % 5, 2 | 3) {
            typ[j % 5]
        } else {
            0.0
        };
        let h = 1e-6 * u[j].abs().max(floor);
        let fd = differences(&u, j, h);
        let fd2 = differences(&u, j, 2.0 * h);
        for i in 0..n {
            let a = jac.get(i, j);
            // Round-off of central differences: ε |terms of row i| / h, the terms being of
            // the typical size 1 / f_scale[i] (jacobian.rs) ...
            let noise = 64.0 * f64::EPSILON / (f_scale[i] * h);
            // ... which they outgrow at these parameters (C H0 ≫ ΔP R0, D ≫ C, ε ≪ 1e-3: a
            // stiff sclera's t_φ and the fibres' terms cancel in the t_s and κ rows), so the
            // differences' own spread between steps h and 2h bounds their error too. A wrong
            // analytic entry shows as differences that agree with each other, not with it.
            let spread = 4.0 * (fd[i] - fd2[i]).abs();
            let err = (a - fd[i]).abs() / (1e-5 * a.abs() + noise + spread);
            prop_assert!(
                err < 1.0,
                "{scheme:?} {case:?}: J[{i}][{j}] ({:?}) = {a} but differences give {} (step h) and {} (2h)",
                disc.locate_row(i),
                fd[i],
                fd2[i]
            );
        }
    }
    // Entries outside the pattern are zero.
    let (row_ptr, col_idx) = disc.pattern();
    for i in 0..n {
        let cols = &col_idx[row_ptr[i]..row_ptr[i + 1]];
        for j in 0..n {
            if !cols.contains(&j) {
                prop_assert_eq!(jac.get(i, j), 0.0, "J[{}][{}] outside the pattern", i, j);
            }
        }
    }
    Ok(())
}

fn run(scheme: Scheme) {
    let config = Config {
        cases: 16,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..Config::default()
    };
    let seed = [0x1a; 32];
    let mut runner =
        TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
    runner.run(&case(), |c| check(&c, scheme)).unwrap();
}

#[test]
fn trapezoid_jacobian_matches_differences_at_random_parameters() {
    run(Scheme::Trapezoid);
}

#[test]
fn hermite_simpson_jacobian_matches_differences_at_random_parameters() {
    run(Scheme::HermiteSimpson);
}
