//! Growth in time (docs/MODEL.md §5–6): the implicit-function Jacobian product, CVODE against
//! the published explicit Euler, monotone growth, and what a failed run keeps.

use crate::common::grow;
use eyeshell_core::bvp::settings::SolverSettings;
use eyeshell_core::growth::system::GrowthSystem;
use eyeshell_core::growth::*;
use eyeshell_core::model::params::Params;

/// Keeps every snapshot it is handed.
#[derive(Default)]
struct Keep(Vec<Snapshot>);

impl Observer for Keep {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), eyeshell_core::growth::ObserverError> {
        self.0.push(s.clone());
        Ok(())
    }
}

fn settings(nodes: usize) -> SolverSettings {
    SolverSettings {
        nodes,
        ..SolverSettings::default()
    }
}

fn run(
    nodes: usize,
    g: &GrowthParams,
    s: &GrowthSettings,
) -> (Vec<Snapshot>, Result<GrowthStats, GrowthError>) {
    let mut keep = Keep::default();
    let r = grow(&Params::default(), &settings(nodes), g, s, &mut keep);
    (keep.0, r)
}

fn cvode(rtol: f64) -> GrowthSettings {
    GrowthSettings {
        integrator: Integrator::Cvode,
        rtol,
        atol: rtol * 1e-2,
        ..GrowthSettings::default()
    }
}

fn euler(steps: usize) -> GrowthSettings {
    GrowthSettings {
        integrator: Integrator::Euler,
        steps,
        ..GrowthSettings::default()
    }
}

/// The axial lengths at the output times t = 0.1, 0.2, 0.4, 1.
fn axial(snaps: &[Snapshot]) -> Vec<f64> {
    snaps
        .iter()
        .skip(1)
        .map(|s| s.series.axial_length)
        .collect()
}

/// J v by the implicit-function theorem equals differences of G with full elastic re-solves.
#[test]
fn jacobian_product_matches_resolved_differences() {
    let mut sys =
        GrowthSystem::new(&Params::default(), &settings(101), &GrowthParams::default()).unwrap();
    let p0 = sys.points.initial_state();
    let n = p0.len();
    let mut fy = vec![0.0; n];
    sys.rhs(&p0, &mut fy).unwrap();
    // A smooth direction, scaled like the state (ρ ~ R(Σ), γ_s ~ 1).
    let v: Vec<f64> = (0..n)
        .map(|k| p0[k] * (1.0 + 0.5 * (0.01 * k as f64).sin()))
        .collect();
    let mut jv = vec![0.0; n];
    sys.jac_times(&p0, &fy, &v, &mut jv).unwrap();
    let size = jv.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let d = 1e-6;
    let q: Vec<f64> = p0.iter().zip(&v).map(|(a, b)| a + d * b).collect();
    let mut g1 = vec![0.0; n];
    sys.rhs(&q, &mut g1).unwrap();
    let err = g1
        .iter()
        .zip(&fy)
        .zip(&jv)
        .map(|((a, b), j)| ((a - b) / d - j).abs())
        .fold(0.0, f64::max);
    println!("J v: max |J v| {size:.3e}, max difference to re-solved differences {err:.3e}");
    assert!(
        size > 0.0 && err < 1e-4 * size,
        "J v off by {err:e} of {size:e}"
    );
}

/// CVODE at rtol 1e-8 and Euler at 200…1600 steps converge to the same axial lengths, and
/// Euler's error halves with its step (first order). Also: CVODE's large steps.
#[test]
fn cvode_and_euler_agree_and_euler_is_first_order() {
    let g = GrowthParams::default();
    let (reference, r) = run(501, &g, &cvode(1e-8));
    let reference = axial(&reference);
    let cv_stats = r.unwrap();
    let mut eulers = vec![];
    for steps in [200, 400, 800, 1600] {
        let (snaps, r) = run(501, &g, &euler(steps));
        r.unwrap();
        eulers.push(axial(&snaps));
    }
    let times = [0.1, 0.2, 0.4, 1.0];
    println!(
        "axial length, const scene, N = 501 (CVODE rtol 1e-8: {} steps, {} elastic solves)",
        cv_stats.steps, cv_stats.bvp_solves
    );
    println!("   t    CVODE 1e-8     Euler 200      Euler 400      Euler 800      Euler 1600     extrapolated   orders");
    for (k, t) in times.iter().enumerate() {
        let e: Vec<f64> = eulers.iter().map(|a| a[k]).collect();
        let extrapolated = 2.0 * e[3] - e[2];
        let errs: Vec<f64> = e.iter().map(|x| (x - reference[k]).abs()).collect();
        let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!(
            "  {t:.1}  {:.10}  {:.10}  {:.10}  {:.10}  {:.10}  {:.10}  {orders:.2?}",
            reference[k], e[0], e[1], e[2], e[3], extrapolated
        );
        assert!(
            (extrapolated - reference[k]).abs() < 0.05 * errs[3],
            "t = {t}: extrapolation {extrapolated} vs {}",
            reference[k]
        );
        for o in &orders {
            assert!((o - 1.0).abs() < 0.2, "t = {t}: Euler order {o}");
        }
    }
    // Large steps: rtol 1e-6 against Euler's 200 steps, both against the converged value.
    let (fast, r) = run(501, &g, &cvode(1e-6));
    let fast_stats = r.unwrap();
    let (e200, r) = run(501, &g, &euler(200));
    let e200_stats = r.unwrap();
    let err_cv = (axial(&fast)[3] - reference[3]).abs();
    let err_eu = (axial(&e200)[3] - reference[3]).abs();
    println!("rtol 1e-6: {} elastic solves, error {err_cv:.2e}; Euler 200: {} elastic solves, error {err_eu:.2e}", fast_stats.bvp_solves, e200_stats.bvp_solves);
    assert!(err_cv < err_eu / 100.0);
    // At Euler's accuracy CVODE needs a fraction of its elastic solves.
    let (loose, r) = run(501, &g, &cvode(1e-3));
    let loose_stats = r.unwrap();
    let err_loose = (axial(&loose)[3] - reference[3]).abs();
    println!(
        "rtol 1e-3: {} elastic solves, error {err_loose:.2e}",
        loose_stats.bvp_solves
    );
    assert!(err_loose < 1.5 * err_eu && 3 * loose_stats.bvp_solves < e200_stats.bvp_solves);
}

/// ρ and σ never decrease at any node, and growth stops where the retina is behind the
/// blue surface (within φ_max). The rates are never negative, so Euler's ρ and σ never fall
/// at all. BDF does not keep monotonicity at the kinks where a point stops growing (its
/// formula overshoots, then relaxes back): CVODE's ρ and σ may fall, but by no more than a
/// small multiple of its error tolerance (measured: 2 rtol).
#[test]
fn growth_never_shrinks_and_stops_behind_blue() {
    let g = GrowthParams::default();
    for s in [cvode(1e-5), euler(100)] {
        let (snaps, r) = run(101, &g, &s);
        r.unwrap();
        assert_eq!(snaps.len(), 5);
        let slack = |x: f64| {
            if s.integrator == Integrator::Euler {
                0.0
            } else {
                10.0 * (s.rtol * x.abs() + s.atol)
            }
        };
        for w in snaps.windows(2) {
            for (a, b) in w[0].growth.iter().zip(&w[1].growth) {
                assert!(
                    b.rho >= a.rho - slack(a.rho),
                    "ρ fell from {} to {} ({:?})",
                    a.rho,
                    b.rho,
                    s.integrator
                );
            }
            for (a, b) in w[0].fields.iter().zip(&w[1].fields) {
                assert!(
                    b.sigma >= a.sigma - slack(a.sigma),
                    "σ fell at Σ = {} ({:?})",
                    a.sigma_ref,
                    s.integrator
                );
            }
        }
        let last = snaps.last().unwrap();
        let blue = g.blue;
        let mut stopped = 0;
        for row in &last.growth {
            let behind = blue.depth(row.z_retina, row.r_retina) < 0.0
                && blue.angle(row.z_retina, row.r_retina) < blue.phi_max;
            if behind {
                assert_eq!(row.g_v, 0.0);
                assert_eq!(row.eta, 0.0);
                stopped += 1;
            }
        }
        // The const eye overshoots the blue surface at the back by t = 1 (the paper's account).
        assert!(stopped > 0 && last.series.retina_minus_blue > 0.0);
        assert!(last.series.axial_length > snaps[0].series.axial_length + 3.0);
    }
}

/// Every growth rate is non-negative, at the initial shell and at perturbed, grown states.
#[test]
fn rates_are_never_negative() {
    let mut sys =
        GrowthSystem::new(&Params::default(), &settings(101), &GrowthParams::default()).unwrap();
    let p0 = sys.points.initial_state();
    let mut rate = vec![0.0; p0.len()];
    for k in 0..6 {
        // Grow by up to 6 % with a wavy profile.
        let p: Vec<f64> = p0
            .iter()
            .enumerate()
            .map(|(j, x)| x * (1.0 + 0.01 * k as f64 * (1.0 + (0.05 * j as f64).sin())))
            .collect();
        sys.rhs(&p, &mut rate).unwrap();
        let min = rate.iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(min >= 0.0, "a rate of {min} at state {k}");
    }
}

/// A run whose elastic solve breaks down says when, and keeps the snapshots it had.
#[test]
fn a_failed_run_says_when_and_keeps_what_it_had() {
    let g = GrowthParams {
        eta0: 1e4,
        ..GrowthParams::default()
    };
    let s = GrowthSettings {
        integrator: Integrator::Euler,
        steps: 20,
        output_times: vec![0.05, 0.5, 1.0],
        ..GrowthSettings::default()
    };
    let (snaps, r) = run(51, &g, &s);
    let e = r.expect_err("explicit Euler at η0 = 1e4 with 20 steps must break down");
    println!("{e}; {} snapshots kept", snaps.len());
    assert!(e.t > 0.0 && e.t < 1.0, "failure time {}", e.t);
    assert!(!snaps.is_empty() && snaps.iter().all(|s| s.t <= e.t));
    assert!(e.stats.bvp_solves > 0);
}

/// The const scene's axial length and equatorial radius at t = 0, 0.1, 0.2, 0.4 and 1: IDA
/// on N = 3201 nodes at rtol 1e-10, atol 1e-12 (`eyeshell grow scenes/const.toml --set
/// solver.nodes=3201 --set solver.rtol=1e-10 --set solver.atol=1e-12`), within about 4e-8
/// mm of CVODE on 1601 nodes (BENCHMARKS.md, "Growth to a tolerance").
const CONST_REFERENCE: [(f64, f64); 5] = [
    (19.95611017073154, 9.81989331871984),
    (21.891446923090843, 9.995141307015858),
    (22.794106572533998, 10.234117658715363),
    (23.306945978802457, 10.679700176388609),
    (23.70145552064177, 11.239341883657993),
];

/// `solver.tol` in a growth run (the const scene, its output times): the axial length and
/// the equatorial radius lie within tol of the reference at every output time, the
/// estimate in the stats lies within [1/3, 30]× of that true error, and the choice is
/// recorded (the delivered mesh's nodes are the snapshots').
fn grows_to(tol: f64) {
    let solver = SolverSettings {
        tol: Some(tol),
        ..SolverSettings::default()
    };
    let mut keep = Keep::default();
    let stats = grow(
        &Params::default(),
        &solver,
        &GrowthParams::default(),
        &GrowthSettings::default(),
        &mut keep,
    )
    .unwrap();
    let accuracy = stats.accuracy.expect("solver.tol records its choice");
    let estimate = stats
        .error_estimate
        .expect("solver.tol estimates the error");
    assert_eq!(accuracy.nodes, keep.0[0].fields.len());
    assert_eq!(keep.0.len(), CONST_REFERENCE.len());
    let mut true_error: f64 = 0.0;
    for (snap, (l, r)) in keep.0.iter().zip(CONST_REFERENCE) {
        let e = (snap.series.axial_length - l)
            .abs()
            .max((snap.series.equatorial_radius - r).abs());
        assert!(e <= tol, "t {}: error {e:e} above tol {tol:e}", snap.t);
        true_error = true_error.max(e);
    }
    let est = estimate
        .largest
        .axial_length
        .total
        .max(estimate.largest.equatorial_radius.total);
    assert!(estimate.overall() <= tol, "{estimate:?}");
    assert!(
        est >= true_error / 3.0 && est <= 30.0 * true_error,
        "estimate {est:e} against the true error {true_error:e}"
    );
    println!("tol {tol:e}: {accuracy:?}, true error {true_error:e}, estimate {est:e}");
}

#[test]
fn solver_tol_bounds_the_growth_error_at_1e_4() {
    grows_to(1e-4);
}

#[test]
fn solver_tol_bounds_the_growth_error_at_1e_6() {
    grows_to(1e-6);
}
