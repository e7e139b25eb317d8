//! The analytic Jacobian of the discrete equations equals central differences at random
//! states, for fibres on/off × thickness uniform/non-uniform and both schemes.

use crate::common::*;
use eyeshell_core::bvp::discretisation::DenseSink;
use eyeshell_core::bvp::settings::Scheme;
use eyeshell_core::bvp::solve::{discretise, sphere_guess};
use eyeshell_core::model::params::{Params, Thickness};
use proptest::prelude::*;

fn check(p: &Params, scheme: Scheme, noise: &[f64]) -> Result<(), TestCaseError> {
    // Few nodes, but with the pole grading and every breakpoint.
    let s = settings(9, scheme);
    let mut disc = discretise(p, &s).unwrap();
    let n = disc.len();
    let typ = disc.typical(p.r0);
    let mut u = sphere_guess(&disc, p.r0);
    // Relative noise of up to 2 % on every unknown (q_s, zero on the sphere, gets 2 % of t_s).
    for k in 0..n {
        let size = if k % 5 == 3 { typ[3] } else { u[k].abs() };
        u[k] += 0.02 * size * noise[k % noise.len()] * (1.0 + (k as f64).sin()) / 2.0;
    }
    let (_, f_scale) = disc.scales(p.r0);
    let mut jac = DenseSink::new(n);
    disc.jacobian(&u, &mut jac).unwrap();
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    for j in 0..n {
        // Steps relative to κ, r, t_s (never near zero) and absolute for θ and q_s, which
        // vanish at the pole.
        let floor = if matches!(j % 5, 2 | 3) {
            typ[j % 5]
        } else {
            0.0
        };
        let h = 1e-6 * u[j].abs().max(floor);
        let mut up = u.clone();
        up[j] += h;
        let mut um = u.clone();
        um[j] -= h;
        disc.residual(&up, &mut fp).unwrap();
        disc.residual(&um, &mut fm).unwrap();
        for i in 0..n {
            let fd = (fp[i] - fm[i]) / (2.0 * h);
            let a = jac.get(i, j);
            // Central differences carry round-off of about ε |F terms| / h: the terms of row i
            // are of the size 1 / f_scale[i] (the typical size of its unknown).
            let noise = 64.0 * f64::EPSILON / (f_scale[i] * h);
            let err = (a - fd).abs() / (1e-5 * a.abs() + noise);
            prop_assert!(
                err < 1.0,
                "{scheme:?} D={} {:?}: J[{i}][{j}] = {a} but differences give {fd}",
                p.d,
                p.thickness
            );
        }
    }
    // Entries outside the pattern are zero, so the band holds the whole Jacobian.
    let (row_ptr, col_idx) = disc.pattern();
    for i in 0..n {
        let cols = &col_idx[row_ptr[i]..row_ptr[i + 1]];
        for j in 0..n {
            if !cols.contains(&j) {
                prop_assert_eq!(jac.get(i, j), 0.0);
            } else {
                prop_assert!(i <= j + 7 && j <= i + 6, "entry ({i},{j}) outside the band");
            }
        }
    }
    Ok(())
}

fn variants() -> Vec<Params> {
    let mut out = vec![];
    for d in [0.0, 200.0] {
        for thickness in [Thickness::Uniform, Thickness::NonUniform] {
            out.push(Params {
                d,
                thickness,
                ..Params::default()
            });
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    #[test]
    fn analytic_jacobian_matches_differences(noise in prop::collection::vec(-1.0f64..1.0, 7)) {
        for p in variants() {
            for scheme in [Scheme::Trapezoid, Scheme::HermiteSimpson] {
                check(&p, scheme, &noise)?;
            }
        }
    }
}
