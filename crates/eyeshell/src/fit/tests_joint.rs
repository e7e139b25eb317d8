//! Joint fits: refraction with axial length, keys without a sensitivity (finite
//! differences), several arms; on synthetic data from the model at known values.

use super::tests::Normal;
use super::*;

/// A scene of `scenes/eyewear/` on 61 nodes over t ∈ [0, 0.5] (a run of a second or so).
pub(crate) fn eyewear(name: &str) -> Scene {
    let path = format!(
        "{}/../../scenes/eyewear/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut s = Scene::from_path(path).unwrap();
    s.set_all([
        ("solver.nodes", "61"),
        ("output.history_points", "0"),
        ("growth.t_end", "0.5"),
        ("output.times", "[0.5]"),
    ])
    .unwrap();
    s
}

/// The model of `scene` at `times`: axial lengths and refractions, with no derivatives.
fn model_at(scene: &Scene, times: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let m = joint::run_model(scene, &[], times, true, &mut |_| Ok(())).unwrap();
    (m.axial_length, m.refraction_d)
}

/// Synthetic data of both quantities from `scene` at `times`, noise N(0, σ²) (seed `seed`).
fn synthetic_joint(
    scene: &Scene,
    times: &[f64],
    sigma: (f64, f64),
    seed: u64,
    origin: &str,
) -> Observations {
    let (l, d) = model_at(scene, times);
    let mut noise = Normal(seed);
    let l: Vec<f64> = l.iter().map(|x| x + sigma.0 * noise.sample()).collect();
    let d: Vec<f64> = d.iter().map(|x| x + sigma.1 * noise.sample()).collect();
    let n = times.len();
    Observations::from_table(
        "t",
        times,
        &[
            ("axial_length", &l),
            ("sigma_axial_length", &vec![sigma.0; n]),
            ("refraction_D", &d),
            ("sigma_refraction_D", &vec![sigma.1; n]),
        ],
        origin,
    )
    .unwrap()
}

#[test]
fn one_run_of_a_small_optics_scene_is_quick() {
    let s = eyewear("none");
    let t = std::time::Instant::now();
    let (l, d) = model_at(&s, &[0.1, 0.25, 0.5]);
    println!("L {l:?} D {d:?} in {:.3} s", t.elapsed().as_secs_f64());
    assert!(d.iter().all(|x| x.is_finite()));
}

/// The finite-difference column of a key with an IDAS sensitivity against IDAS's: η0 and
/// δ of the const scene on 101 nodes at its tolerances, h = FD_STEP·|p|, agree to 1e-2 of
/// the column's largest value (measured: 2.3e-3 for η0, 6.1e-3 for δ).
#[test]
fn finite_differences_agree_with_idas_sensitivities() {
    let scene = super::tests::const_scene();
    let times = [0.1, 0.3, 0.5, 0.8, 1.0];
    let data = Observations::from_columns(&times, &[20.0; 5], None, "times").unwrap();
    let params = parse_fit_keys(&["growth.eta0", "growth.delta"], "test").unwrap();
    let fd: Vec<FitParam> = params.iter().map(FitParam::by_differences).collect();
    let values = values_in(&scene, &params).unwrap();
    let step = &mut |_| Ok(());
    let idas = joint::arm_values(&scene, &params, &values, &data, step).unwrap();
    let diff = joint::arm_values(&scene, &fd, &values, &data, step).unwrap();
    assert_eq!((idas.runs, diff.runs), (1, 5));
    for c in 0..2 {
        let top = idas.d_axial_length.column(c).amax();
        let worst = (0..times.len())
            .map(|i| (idas.d_axial_length[(i, c)] - diff.d_axial_length[(i, c)]).abs())
            .fold(0.0, f64::max);
        println!(
            "{}: largest ∂L/∂p {top:.6e}, |IDAS − FD| ≤ {worst:.3e} ({:.2e} relative)",
            params[c].key(),
            worst / top
        );
        assert!(
            top > 1e-3 && worst < 1e-2 * top,
            "{}: {worst} of {top}",
            params[c].key()
        );
    }
}

/// The cornea's radius of a computed-optics eye from refractions alone (σ = 0.1 D at five
/// times): recovered within two standard errors on each of three seeds, its column by
/// finite differences.
#[test]
fn the_corneas_radius_is_recovered_from_refractions() {
    let truth = eyewear("none");
    let key = "optics.surfaces[0].radius";
    let params = parse_fit_keys(&[key], "--fit").unwrap();
    let r0 = params[0].value_in(&truth).unwrap();
    assert!((r0 - 7.77).abs() < 0.5, "the Atchison cornea: {r0}");
    let times = [0.05, 0.15, 0.25, 0.35, 0.5];
    let (_, d) = model_at(&truth, &times);
    let mut start = truth.clone();
    start.set(key, r0 + 0.15).unwrap();
    for seed in [1, 2, 3] {
        let mut noise = Normal(seed);
        let y: Vec<f64> = d.iter().map(|x| x + 0.1 * noise.sample()).collect();
        let data = Observations::from_table(
            "t",
            &times,
            &[("refraction_D", &y), ("sigma_refraction_D", &[0.1; 5])],
            "refraction.csv",
        )
        .unwrap();
        let done = fit(&start, &data, &params, &FitOptions::default(), &mut |_| {}).unwrap();
        let p = &done.report.parameters[0];
        let z = (p.estimate - r0) / p.standard_error;
        println!(
            "seed {seed}: {key} = {:.5} ± {:.5} (truth {r0}, z = {z:+.2}), {} iterations, {} runs, χ² {:.3}",
            p.estimate, p.standard_error, done.report.iterations, done.report.model_runs, done.report.chi2
        );
        assert!(
            done.report.convergence.converged(),
            "{}",
            done.report.convergence_reason
        );
        assert_eq!(p.jacobian, "finite differences");
        assert!(z.abs() < 2.0, "seed {seed}: z = {z}");
        assert!(p.standard_error < 0.05, "{}", p.standard_error);
        let row = &done.report.residuals[0];
        assert_eq!((row.axial_length, row.refraction_d), (None, Some(y[0])));
    }
}

/// The arms of the joint tests: the eye without eyewear and through a −2 D spectacle lens,
/// over t ∈ [0, 1], each from `start` (key, value) with data of both quantities at six
/// times from its truth (σ 0.03 mm, 0.15 D; seed `seed`).
fn two_arms(truths: &[Scene; 2], start: &[(&str, &str)], seed: u64) -> Vec<Arm> {
    let times = [0.1, 0.25, 0.4, 0.6, 0.8, 1.0];
    ["none", "single-vision"]
        .iter()
        .zip(truths)
        .enumerate()
        .map(|(a, (name, t))| {
            let mut s = t.clone();
            s.set_all(start.iter().copied()).unwrap();
            Arm {
                name: Some(name.to_string()),
                data: synthetic_joint(t, &times, (0.03, 0.15), 100 * seed + a as u64, name),
                scene: s,
            }
        })
        .collect()
}

fn long_eyewear(name: &str) -> Scene {
    let mut s = eyewear(name);
    s.set_all([("growth.t_end", "1"), ("output.times", "[1.0]")])
        .unwrap();
    s
}

/// Two arms (no eyewear, a −2 D lens), axial lengths and refractions, η0 and Γ shared: on
/// five seeds both estimates lie within two standard errors of their truth (70, 8).
#[test]
fn a_joint_fit_of_two_arms_recovers_the_shared_keys() {
    let truths = [long_eyewear("none"), long_eyewear("single-vision")];
    let shared = parse_fit_keys(&["growth.eta0", "growth.Gamma"], "--fit").unwrap();
    let started = std::time::Instant::now();
    for seed in 11..16 {
        let arms = two_arms(
            &truths,
            &[("growth.eta0", "62"), ("growth.Gamma", "8.8")],
            seed,
        );
        let done = fit_arms(
            arms,
            &shared,
            &[],
            &FitOptions::default(),
            &mut |_| {},
            &mut |_| Ok(()),
        )
        .unwrap();
        let r = &done.report;
        println!(
            "seed {seed}: {} iterations, {} runs, χ² {:.3} for {} dof; {}",
            r.iterations, r.model_runs, r.chi2, r.degrees_of_freedom, r.convergence_reason
        );
        assert!(r.convergence.converged(), "{}", r.convergence_reason);
        assert_eq!(r.residuals.len(), 2 * 2 * 6);
        assert_eq!(r.arms.len(), 2);
        for (p, t) in r.parameters.iter().zip([70.0, 8.0]) {
            let z = (p.estimate - t) / p.standard_error;
            println!(
                "  {} = {:.4} ± {:.4} (truth {t}, z = {z:+.2})",
                p.label(),
                p.estimate,
                p.standard_error
            );
            assert!(z.abs() < 2.0, "seed {seed}: {} z = {z}", p.label());
        }
        assert_eq!(
            done.scenes[1].growth.as_ref().unwrap().eta0,
            r.parameters[0].estimate
        );
    }
    println!(
        "five joint fits in {:.2} s",
        started.elapsed().as_secs_f64()
    );
}

/// Γ shared, η0 each arm's own (70 and 60): each arm's estimate is its own truth's within
/// two standard errors, and the report and the fitted scenes carry each arm's value.
#[test]
fn a_per_arm_key_takes_each_arms_own_value() {
    let mut truths = [long_eyewear("none"), long_eyewear("single-vision")];
    truths[1].set("growth.eta0", 60).unwrap();
    let shared = parse_fit_keys(&["growth.Gamma"], "--fit").unwrap();
    let per_arm = parse_fit_keys(&["growth.eta0"], "--per-arm").unwrap();
    let arms = two_arms(
        &truths,
        &[("growth.eta0", "65"), ("growth.Gamma", "8.5")],
        3,
    );
    let done = fit_arms(
        arms,
        &shared,
        &per_arm,
        &FitOptions::default(),
        &mut |_| {},
        &mut |_| Ok(()),
    )
    .unwrap();
    let r = &done.report;
    assert!(r.convergence.converged(), "{}", r.convergence_reason);
    let labels: Vec<String> = r.parameters.iter().map(|p| p.label()).collect();
    assert_eq!(
        labels,
        [
            "growth.Gamma",
            "growth.eta0[none]",
            "growth.eta0[single-vision]"
        ]
    );
    for (p, t) in r.parameters.iter().zip([8.0, 70.0, 60.0]) {
        let z = (p.estimate - t) / p.standard_error;
        println!(
            "{} = {:.4} ± {:.4} (truth {t}, z = {z:+.2})",
            p.label(),
            p.estimate,
            p.standard_error
        );
        assert!(z.abs() < 2.0, "{} z = {z}", p.label());
    }
    for (a, scene) in done.scenes.iter().enumerate() {
        assert_eq!(
            scene.growth.as_ref().unwrap().eta0,
            r.parameters[1 + a].estimate
        );
        assert_eq!(
            scene.growth.as_ref().unwrap().gamma,
            r.parameters[0].estimate
        );
    }
    let json = report_json(r);
    assert!(json.contains("\"arm\": \"single-vision\""), "{json}");
    let table = report::report_table(&done.scenes[0], r);
    assert!(
        table.contains("growth.eta0[single-vision]") && table.contains("fitted 2 arms jointly"),
        "{table}"
    );
    println!("{table}");
}

#[test]
fn what_a_run_cannot_use_is_refused_before_any_run() {
    let polynomial = super::tests::const_scene();
    let data = Observations::parse("t,refraction_D\n0.5,1\n0.8,0.5\n", "r.csv").unwrap();
    let eta0 = parse_fit_keys(&["growth.eta0"], "--fit").unwrap();
    let e = fit(
        &polynomial,
        &data,
        &eta0,
        &FitOptions::default(),
        &mut |_| {},
    )
    .unwrap_err();
    let text = e.to_string();
    assert!(e.is_user_error(), "{text}");
    assert!(
        text.starts_with("r.csv: the data give refraction_D, but the scene computes no refraction"),
        "{text}"
    );
    assert!(text.contains("stimulus.source"), "{text}");
    let axial = Observations::parse("t,axial_length\n0.5,22\n0.8,23\n", "l.csv").unwrap();
    let radius = parse_fit_keys(&["optics.surfaces[0].radius"], "--fit").unwrap();
    let e = fit(
        &polynomial,
        &axial,
        &radius,
        &FitOptions::default(),
        &mut |_| {},
    )
    .unwrap_err();
    assert!(
        e.is_user_error()
            && e.to_string()
                .contains("optics.surfaces[0].radius is not used by the run"),
        "{e}"
    );
    // No arm, a per-arm key of one arm, a key both shared and per arm.
    let step = &mut |_| Ok(());
    let one = || Arm {
        name: None,
        scene: polynomial.clone(),
        data: axial.clone(),
    };
    let o = FitOptions::default();
    let none: &[FitParam] = &[];
    let eta0: &[FitParam] = &eta0;
    for (arms, shared, per_arm, want) in [
        (vec![], eta0, none, "no arm to fit"),
        (
            vec![one()],
            none,
            eta0,
            "growth.eta0 is fitted per arm: a key of each arm's own needs two arms",
        ),
        (
            vec![one(), one()],
            eta0,
            eta0,
            "growth.eta0 is both fitted in common and per arm",
        ),
    ] {
        let e = fit_arms(arms, shared, per_arm, &o, &mut |_| {}, step).unwrap_err();
        assert!(e.is_user_error() && e.to_string().contains(want), "{e}");
    }
    for (key, want) in [
        ("solver.nodes", "solver.nodes is a setting of the solver"),
        ("growth.schedule", "is not a real-valued key"),
        ("optics.lenses[0].power", "not a lens's keys"),
        ("optics.surfaces[0].colour", "is not a surface's key"),
        ("growth.nope", "\"growth.nope\" is not a scene key"),
    ] {
        let e = parse_fit_keys(&[key], "--fit").unwrap_err();
        assert!(
            e.is_user_error() && e.to_string().contains(want),
            "{key}: {e}"
        );
    }
}
