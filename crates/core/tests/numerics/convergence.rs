//! Observed orders on the non-uniform shell with fibres (D = 200): the largest nodal error,
//! against a Richardson extrapolation of the finest pair, must fall at order 2 (trapezoid)
//! and 4 (Hermite–Simpson), including the nodes next to the pole (docs/MODEL.md §3, trap).

use crate::common::*;
use eyeshell_core::bvp::settings::Scheme;
use eyeshell_core::bvp::Solution;

const LADDER: [usize; 6] = [101, 201, 401, 801, 1601, 3201];

/// Field values at the 101 uniform nodes shared by every mesh of the ladder.
fn coarse_values(sol: &Solution) -> Vec<[f64; 5]> {
    let l = sol.params.length();
    let eps = sol.mesh.nodes[0];
    (0..101)
        .map(|k| {
            let x = if k == 100 {
                l
            } else {
                eps + k as f64 * (l - eps) / 100.0
            };
            let i = sol
                .mesh
                .nodes
                .iter()
                .position(|&y| (y - x).abs() < 1e-9)
                .expect("nested node");
            five(&sol.rows[i])
        })
        .collect()
}

struct Study {
    /// Largest error over all fields and shared nodes, per N.
    all: Vec<f64>,
    /// Errors of κ and α_s at Σ = ε, per N.
    pole_kappa: Vec<f64>,
    pole_alpha: Vec<f64>,
    /// Largest error of each field, per N.
    fields: Vec<[f64; 5]>,
}

fn study(scheme: Scheme) -> Study {
    let p = fibre_shell();
    let vals: Vec<Vec<[f64; 5]>> = LADDER
        .iter()
        .map(|&n| coarse_values(&solve(&p, n, scheme)))
        .collect();
    let q = 2f64.powi(scheme.order() as i32);
    let (fine, finer) = (&vals[LADDER.len() - 2], &vals[LADDER.len() - 1]);
    let reference: Vec<[f64; 5]> = fine
        .iter()
        .zip(finer)
        .map(|(a, b)| std::array::from_fn(|c| b[c] + (b[c] - a[c]) / (q - 1.0)))
        .collect();
    let mut s = Study {
        all: vec![],
        pole_kappa: vec![],
        pole_alpha: vec![],
        fields: vec![],
    };
    for v in &vals[..LADDER.len() - 1] {
        let mut f = [0.0f64; 5];
        for (a, b) in v.iter().zip(&reference) {
            for c in 0..5 {
                f[c] = f[c].max((a[c] - b[c]).abs());
            }
        }
        s.all.push(f.iter().cloned().fold(0.0, f64::max));
        s.fields.push(f);
        s.pole_kappa.push((v[0][0] - reference[0][0]).abs());
        s.pole_alpha.push((v[0][1] - reference[0][1]).abs());
    }
    println!(
        "{scheme:?} on the fibre shell (D = 200, non-uniform), N = {:?}",
        &LADDER[..5]
    );
    println!(
        "  max error      {}  orders {:.2?}",
        sci(&s.all),
        orders(&s.all)
    );
    println!(
        "  κ at Σ = ε     {}  orders {:.2?}",
        sci(&s.pole_kappa),
        orders(&s.pole_kappa)
    );
    println!(
        "  α_s at Σ = ε   {}  orders {:.2?}",
        sci(&s.pole_alpha),
        orders(&s.pole_alpha)
    );
    for (k, f) in s.fields.iter().enumerate() {
        println!(
            "  N = {:5}: κ {:.2e} α_s {:.2e} r {:.2e} θ {:.2e} Q {:.2e}",
            LADDER[k], f[0], f[1], f[2], f[3], f[4]
        );
    }
    s
}

/// Orders of the pairs whose errors stand clear of round-off (above `floor`).
fn assert_orders(name: &str, errors: &[f64], order: f64, floor: f64) {
    let mut checked = 0;
    for (k, q) in orders(errors).iter().enumerate() {
        if errors[k + 1] > floor {
            assert!(
                (q - order).abs() <= 0.3,
                "{name}: order {q:.3} between N = {} and {}",
                LADDER[k],
                LADDER[k + 1]
            );
            checked += 1;
        }
    }
    assert!(
        checked >= 2,
        "{name}: too few pairs above round-off ({})",
        sci(errors)
    );
}

/// The pole nodes on their own: over the rungs whose error stands above `floor`, the error
/// falls at an average order of at least p − 0.5. Without the pole grading a uniform mesh
/// gives order ~1 here for Hermite–Simpson (docs/MODEL.md §3, trap), which this rejects.
fn assert_pole_order(name: &str, errors: &[f64], order: f64, floor: f64) {
    let last = errors
        .iter()
        .rposition(|&e| e > floor)
        .expect("an error above round-off");
    assert!(
        last >= 1,
        "{name}: too few rungs above round-off ({})",
        sci(errors)
    );
    let average = (errors[0] / errors[last]).log2() / last as f64;
    println!(
        "  {name}: average order {average:.2} over N = {}..{}",
        LADDER[0], LADDER[last]
    );
    assert!(
        average >= order - 0.5,
        "{name}: average order {average:.2} ({})",
        sci(errors)
    );
}

#[test]
fn trapezoid_is_order_2_everywhere() {
    let s = study(Scheme::Trapezoid);
    assert_orders("max error", &s.all, 2.0, 1e-12);
    assert_pole_order("κ at the pole", &s.pole_kappa, 2.0, 1e-12);
    assert_pole_order("α_s at the pole", &s.pole_alpha, 2.0, 1e-12);
}

#[test]
fn hermite_simpson_is_order_4_everywhere() {
    let s = study(Scheme::HermiteSimpson);
    assert_orders("max error", &s.all, 4.0, 1e-11);
    assert_pole_order("κ at the pole", &s.pole_kappa, 4.0, 4e-12);
    assert_pole_order("α_s at the pole", &s.pole_alpha, 4.0, 4e-12);
    // N = 1601 is the fifth rung.
    let e1601 = s.all[4];
    assert!(e1601 < 1e-9, "N = 1601 error {e1601:e}");
}
