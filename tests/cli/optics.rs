//! `eyeshell optics`: the best-focus surfaces of a scene's schematic eye, written whole, and
//! bad optics keys refused in one line naming the key, leaving nothing behind.

use crate::support::*;

/// The const scene's eye (Atchison 2006) at 400 and 600 nm: 41 fields each, the foci in
/// the shell's frame, the paraxial figures of docs/optics.md, the polar fits, the figure, and
/// the ownership marker (so a second run replaces the first).
#[test]
fn optics_writes_surfaces_json_and_a_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("eye");
    for _ in 0..2 {
        ok(&[
            "optics",
            "scenes/const.toml",
            "--set",
            "optics.focus=sagittal",
            "--set",
            "optics.pupil=1",
            "--out",
            s(&out),
            "--quiet",
        ]);
    }
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            ".eyeshell",
            "optics.json",
            "optics.png",
            "optics.svg",
            "peripheral.csv",
            "published.csv",
            "published.png",
            "published.svg",
            "refraction.csv",
            "surfaces.csv"
        ]
    );
    // Against the published blue surface (docs/optics.md's table): the sagittal surface of a
    // 1 mm pupil 0.090 mm in front of it on the axis, 0.070 mm at the 40° field (φ ≈ 0.45).
    let (header, published) = csv_cells(&out.join("published.csv"));
    assert_eq!(header[3], "criterion_minus_polynomial");
    assert_eq!(published.len(), 41);
    let at = |row: usize, col: usize| published[row][col].parse::<f64>().unwrap();
    assert!((at(0, 2) - 23.635).abs() < 1e-3 && at(0, 1) == 0.0);
    assert!((at(0, 3) + 0.090).abs() < 2e-3, "{:?}", published[0]);
    assert!((at(40, 4) + 0.065).abs() < 0.02, "{:?}", published[40]);
    assert!(at(40, 5) < -1.0, "{:?}", published[40]);
    let (header, rows) = csv_cells(&out.join("surfaces.csv"));
    assert_eq!(
        header,
        [
            "wavelength_nm",
            "field_deg",
            "z",
            "r",
            "criterion",
            "strehl",
            "image",
            "share"
        ]
    );
    assert_eq!(rows.len(), 82);
    // No lens: one image carrying all the light.
    assert!(rows.iter().all(|r| r[6] == "0" && r[7] == "1.0"));
    assert!(rows.iter().all(|r| r[4] == "sagittal"));
    let num = |r: &Vec<String>, i: usize| r[i].parse::<f64>().unwrap();
    // On the axis at 400 nm, 1 mm pupil: 23.038 mm (docs/optics.md), 0.09 mm in front of
    // the published blue surface's 23.1285 mm.
    assert_eq!(
        (num(&rows[0], 0), num(&rows[0], 1), num(&rows[0], 3)),
        (400.0, 0.0, 0.0)
    );
    assert!((num(&rows[0], 2) - 23.038).abs() < 2e-3, "{:?}", rows[0]);
    assert_eq!(num(&rows[81], 1), 40.0);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("optics.json")).unwrap()).unwrap();
    assert_eq!(j["eye"], "atchison-2006");
    let lca = &j["chromatic_aberration"];
    // docs/optics.md's table: F(400) − F(600) = 2.370 D, focus(600) − focus(400) = 0.6049 mm.
    assert!((lca["power_difference_dioptres"].as_f64().unwrap() - 2.370).abs() < 1e-3);
    assert!((lca["focus_difference_mm"].as_f64().unwrap() - 0.6049).abs() < 1e-4);
    let fit = &j["surfaces"][0]["polar_fit"];
    assert_eq!(fit["z_B"].as_f64().unwrap(), -0.5064886748669879);
    assert!(fit["rms_residual_mm"].as_f64().unwrap() < 1e-2);
    // 4 rays across the 1 mm pupil suffice (their foci agree with 8 rays' to 1e-5 mm): 8
    // traced and mirrored, and the chief ray, at each of the 82 foci.
    assert_eq!(j["rays_traced"].as_u64().unwrap(), 82 * 9);
}

/// Bad optics keys: one line naming the key (a trace failure names the surface, the field
/// and the wavelength too), exit 2, no directory.
#[test]
fn bad_optics_keys_are_refused_and_nothing_is_written() {
    let scene = "growth.eta0 = 70\n";
    fails(
        "optics",
        scene,
        &["optics.pupil=12"],
        "optics.pupil = 12 must lie in (0, 10] mm",
        "--set optics.pupil=12",
    );
    fails(
        "optics",
        scene,
        &["optics.eye=gullstrand"],
        "optics.eye",
        "--set optics.eye=gullstrand",
    );
    fails(
        "optics",
        scene,
        &["optics.wavelengths=[400, 1500]"],
        "(1500 does not)",
        "--set optics.wavelengths=[400, 1500]",
    );
    // A key given by --set is named with its --set, also when the error is found by tracing.
    fails(
        "optics",
        scene,
        &["optics.pupil=8", "optics.max_field=80"],
        "optics.max_field = 80 cannot be traced in the atchison-2006 eye: the ray at 80° and 400 nm fails at 'posterior lens'",
        "--set optics.max_field=80",
    );
    fails(
        "optics",
        "optics.max_field = 80\noptics.pupil = 8\n",
        &[],
        "optics.max_field = 80 cannot be traced",
        "scene.toml",
    );
    fails(
        "optics",
        scene,
        &["optics.surfaces[0].radius=0.1"],
        "optics.surfaces[0].radius = 0.1 must be between 0.5 and 10000 mm",
        "--set optics.surfaces[0].radius=0.1",
    );
    fails(
        "optics",
        scene,
        &["optics.eye=custom"],
        "optics.surfaces = (0 surface tables) must describe 2 to 16 surfaces",
        "scene.toml",
    );
    // The same keys refuse a growth run that would use them.
    fails(
        "grow",
        "growth.eta0 = 70\nstimulus.source = \"optics\"\n",
        &["optics.pupil=8", "optics.max_field=80"],
        "optics.max_field = 80 cannot be traced",
        "--set optics.max_field=80",
    );
}

/// An eye whose keys are tables over t is drawn as it is at `--at T`: at t = 1 the surfaces
/// of scenes/optics-age.toml are those of the same eye with its t = 1 values fixed, at 0
/// (the default) those of its t = 0 values; a time outside [0, growth.t_end] is refused in
/// one line and nothing is written.
#[test]
fn optics_at_a_growth_time_draws_the_eye_of_that_time() {
    let dir = tempfile::tempdir().unwrap();
    let quick = [
        "--set",
        "optics.max_field=10",
        "--set",
        "optics.wavelengths=[450, 600]",
    ];
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["optics", "scenes/optics-age.toml"];
        args.extend_from_slice(&quick);
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", s(&out), "--quiet"]);
        ok(&args);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("optics.json")).unwrap())
                .unwrap();
        (std::fs::read(out.join("surfaces.csv")).unwrap(), json)
    };
    let fixed_at = |radius: &str, thickness: &str| {
        [
            "--set".to_string(),
            format!("optics.surfaces=[{{ radius = {radius} }}, {{ thickness = {thickness} }}]"),
        ]
    };
    let (default, json0) = run("default", &[]);
    let (at0, _) = run("at0", &["--at", "0"]);
    let (at1, json1) = run("at1", &["--at", "1"]);
    let f0 = fixed_at("7.472", "2.512");
    let f1 = fixed_at("7.77", "3.15");
    let (fixed0, _) = run("fixed0", &[&f0[0], &f0[1]]);
    let (fixed1, _) = run("fixed1", &[&f1[0], &f1[1]]);
    assert_eq!(default, at0);
    assert_eq!(at0, fixed0);
    assert_eq!(at1, fixed1);
    assert_ne!(at0, at1);
    assert_eq!(json0["t"], 0.0);
    assert_eq!(json1["t"], 1.0);
    // The flatter cornea and deeper chamber of t = 1 move the axial focus back.
    let axial = |j: &serde_json::Value| j["surfaces"][0]["axial_focus_mm"].as_f64().unwrap();
    assert!(
        axial(&json1) > axial(&json0) + 0.1,
        "{} {}",
        axial(&json0),
        axial(&json1)
    );
    for bad in ["1.5", "-0.1", "nan"] {
        let out = dir.path().join(format!("bad{bad}"));
        let at = format!("--at={bad}");
        let r = eyeshell(&["optics", "scenes/optics-age.toml", &at, "--out", s(&out)]);
        assert_fails(&r, 2, "--at");
        assert!(!out.exists());
    }
}

/// A scene is checked over its whole run, not only at its tables' points: a table whose end
/// slope carries a surface through a plane before its first time (−6 mm at t = 0.9, −100 mm
/// at 1: +840 mm at t = 0) is refused naming the key, the time and the value, and so is a
/// thickness whose cubic dips below zero between its points.
#[test]
fn tables_over_time_are_checked_over_the_whole_run() {
    let scene = "growth.eta0 = 70\nstimulus.source = \"optics\"\n";
    fails(
        "grow",
        scene,
        &["optics.surfaces[4].radius={ t = [0.9, 1.0], value = [-6, -100] }"],
        "optics.surfaces[4].radius = { t = [0.9, … reaches 840 at t = 0 (its spline between or beyond its points): it must stay between 0.5 and 10000 mm in magnitude, of one sign for all t in [0, 1]",
        "--set optics.surfaces[4].radius=",
    );
    // Beyond the last point, up to growth.t_end = 2.
    fails(
        "grow",
        "growth.eta0 = 70\ngrowth.t_end = 2\nstimulus.source = \"optics\"\n",
        &["optics.surfaces[1].thickness={ t = [0, 1], value = [3.15, 0.2] }"],
        "reaches -2.75 at t = 2",
        "--set optics.surfaces[1].thickness=",
    );
    // Between points: 0.2 at 0.5 and 1, far larger at 0.7; the natural cubic overshoots
    // below zero between 0.5 and 0.7.
    fails(
        "optics",
        "optics.max_field = 10\n",
        &["optics.surfaces[1].thickness={ t = [0, 0.5, 0.7, 1], value = [3.15, 0.2, 6, 0.2] }"],
        "optics.surfaces[1].thickness = { t = [0, 0.… reaches -1.85162 at t = 0.336661",
        "--set optics.surfaces[1].thickness=",
    );
}

/// A wavelength outside the range the eye's source gives its dispersion for is refused
/// naming the eye and the key (the Liou & Brennan eye's power rises again beyond 757 nm), and
/// so is red given before blue.
#[test]
fn wavelengths_outside_the_eyes_dispersion_or_reversed_are_refused() {
    let scene =
        "growth.eta0 = 70\nstimulus.source = \"optics\"\noptics.eye = \"liou-brennan-1997\"\n";
    fails(
        "grow",
        scene,
        &["optics.wavelengths=[400, 1200]"],
        "optics.wavelengths = [400, 1200] must lie between 380 and 750 nm for the liou-brennan-1997 eye: Liou & Brennan (1997) give their dispersion for 380-750 nm (1200 does not)",
        "--set optics.wavelengths=[400, 1200]",
    );
    fails(
        "grow",
        scene,
        &["optics.refraction_wavelength=1000"],
        "optics.refraction_wavelength = 1000 must lie between 380 and 750 nm for the liou-brennan-1997 eye",
        "--set optics.refraction_wavelength=1000",
    );
    fails(
        "optics",
        "",
        &["optics.wavelengths=[600, 400]"],
        "optics.wavelengths = [600, 400] must list the blue wavelength first, then a longer red one (600 nm is not shorter than 400 nm)",
        "--set optics.wavelengths=[600, 400]",
    );
}

/// A ray that fails because of a surface key given by --set is that key's failure, from its
/// --set, not the pupil's from the scene file: the Atchison eye traces a 6 mm pupil, but not
/// with a cornea of 2.9 mm, which the pupil's rays miss.
#[test]
fn a_trace_failure_names_the_surface_key_that_caused_it() {
    fails(
        "optics",
        "optics.pupil = 6\noptics.max_field = 10\n",
        &["optics.surfaces[0].radius=2.9"],
        "optics.surfaces[0].radius = 2.9 cannot be traced in the atchison-2006 eye: the ray at 0° and 400 nm fails at 'anterior cornea': the ray misses the surface",
        "--set optics.surfaces[0].radius=2.9",
    );
    // The pupil itself, when the eye's own surfaces are not to blame.
    fails(
        "optics",
        "optics.pupil = 10\noptics.max_field = 80\n",
        &[],
        "cannot be traced in the atchison-2006 eye",
        "scene.toml",
    );
}

/// One wavelength: `eyeshell optics` writes that wavelength's surface (41 fields, no
/// chromatic aberration); growth, which reads a red surface too, refuses it naming growth.
/// With two, optics.json's chromatic difference of refraction of the Atchison eye, 400–600 nm,
/// at the corneal apex for the eye's own retina: 1.767 D, the Indiana chromatic eye's
/// Rx(600) − Rx(400) = 1.766 D (Thibos et al. 1992, docs/optics.md), distinct from the
/// 2.370 D difference of equivalent power.
#[test]
fn one_wavelength_draws_its_surface_and_two_give_the_chromatic_difference_of_refraction() {
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("one");
    ok(&[
        "optics",
        "scenes/const.toml",
        "--set",
        "optics.wavelengths=[450]",
        "--out",
        s(&one),
        "--quiet",
    ]);
    let (_, rows) = csv_cells(&one.join("surfaces.csv"));
    assert_eq!(rows.len(), 41);
    assert!(rows.iter().all(|r| r[0] == "450.0"), "{:?}", rows[0]);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(one.join("optics.json")).unwrap()).unwrap();
    assert_eq!(j["wavelengths_nm"], serde_json::json!([450.0]));
    assert!(j["chromatic_aberration"].is_null());
    fails(
        "grow",
        "growth.eta0 = 70\nstimulus.source = \"optics\"\n",
        &["optics.wavelengths=[400]"],
        "optics.wavelengths = [400] must list at least two wavelengths (nm) for growth: blue (the stimulus), then red (it classifies the eye)",
        "--set optics.wavelengths=[400]",
    );
    let two = dir.path().join("two");
    ok(&[
        "optics",
        "scenes/const.toml",
        "--set",
        "optics.eye=atchison-2006",
        "--set",
        "optics.wavelengths=[400, 600]",
        "--out",
        s(&two),
        "--quiet",
    ]);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(two.join("optics.json")).unwrap()).unwrap();
    let lca = &j["chromatic_aberration"];
    let rx = lca["refraction_difference_dioptres"].as_f64().unwrap();
    assert!((1.6..=1.9).contains(&rx), "{rx}");
    // The Indiana eye: Rx(λ) = 1.68524 − 0.63346/(λ − 0.21410), λ in µm.
    let indiana = |l: f64| 1.68524 - 0.63346 / (l - 0.21410);
    assert!((rx - (indiana(0.6) - indiana(0.4))).abs() < 0.01, "{rx}");
    assert!((lca["power_difference_dioptres"].as_f64().unwrap() - 2.370).abs() < 1e-3);
    assert!((lca["refraction_retina_mm"].as_f64().unwrap() - 23.58).abs() < 1e-9);
}

/// scenes/optics-age-schedule.toml (the eye of scenes/optics-age.toml beside a growth rate
/// falling as exp(−t/0.5)) grows from the CLI: its records are at the scene's own times, it
/// starts from the same eye as the unscheduled scene and ends shorter (it grows 0.43 of the
/// time), with η0's sensitivity beside it. The sensitivity to the schedule's own parameter
/// is refused, by `grow --sensitivities` and by `fit`, in one line naming the key, exit 2,
/// nothing written, and so is a table that reaches 0 inside the window.
#[test]
fn a_schedule_beside_optics_that_change_with_age_grows_and_refuses_its_own_sensitivity() {
    let dir = tempfile::tempdir().unwrap();
    let grow = |scene: &str, out: &str, more: &[&str]| {
        let scene = repo().join(scene);
        let mut args = vec!["grow", s(&scene), "--set", "solver.nodes=51", "--quiet"];
        args.extend_from_slice(more);
        args.extend_from_slice(&["--out", out]);
        eyeshell_in(dir.path(), &args)
    };
    let r = grow(
        "scenes/optics-age-schedule.toml",
        "scheduled",
        &["--sensitivities", "growth.eta0"],
    );
    succeeded(&r, "the scheduled scene");
    succeeded(
        &grow("scenes/optics-age.toml", "plain", &[]),
        "the plain scene",
    );
    // A numeric column of a file with text columns (series.csv's class, the parameter).
    let numbers = |file: &str, name: &str| -> Vec<f64> {
        let (h, rows) = csv_cells(&dir.path().join(file));
        let j = h.iter().position(|c| c == name).unwrap();
        rows.iter().map(|r| r[j].parse().unwrap()).collect()
    };
    let series = |run: &str, name: &str| numbers(&format!("{run}/series.csv"), name);
    let (t, scheduled) = (
        series("scheduled", "t"),
        series("scheduled", "axial_length"),
    );
    let plain = series("plain", "axial_length");
    assert_eq!(t, [0.0, 0.1, 0.2, 0.4, 1.0]);
    assert_eq!(scheduled[0], plain[0]);
    println!(
        "t = 1: scheduled {} mm, unscheduled {} mm",
        scheduled[4], plain[4]
    );
    assert!(plain[4] - scheduled[4] > 0.2, "{scheduled:?} vs {plain:?}");
    let d = numbers("scheduled/sensitivities.csv", "d_axial_length");
    assert!(d.iter().skip(1).all(|&x| x > 0.0), "{d:?}");

    let needle = "the sensitivity to growth.schedule_tau needs optics that do not change with age (optics.surfaces has tables over time)";
    let r = grow(
        "scenes/optics-age-schedule.toml",
        "refused",
        &["--sensitivities", "growth.eta0,growth.schedule_tau"],
    );
    assert_bad(&r, needle, "grow --sensitivities growth.schedule_tau");
    assert!(!dir.path().join("refused").exists());
    std::fs::write(
        dir.path().join("data.csv"),
        "t,axial_length\n0.5,22.5\n1,23\n",
    )
    .unwrap();
    let scene = repo().join("scenes/optics-age-schedule.toml");
    let r = eyeshell_in(
        dir.path(),
        &[
            "fit",
            s(&scene),
            "--data",
            "data.csv",
            "--fit",
            "growth.schedule_tau",
            "--out",
            "fit",
        ],
    );
    assert_bad(&r, needle, "fit --fit growth.schedule_tau");
    assert!(!dir.path().join("fit").exists());
    // A schedule that vanishes inside the window is refused beside such optics (the clock's
    // inverse is infinitely steep there), and runs with the eye fixed.
    let zero = [
        "--set",
        "growth.schedule=table",
        "--set",
        "growth.schedule_times=[0, 0.5, 1]",
        "--set",
        "growth.schedule_factors=[1, 0, 1]",
        "--set",
        "output.history_points=0",
    ];
    let r = grow("scenes/optics-age.toml", "zero", &zero);
    assert_bad(
        &r,
        "growth.schedule_factors = [1, 0, 1] item 2 is 0 (at 0.5 in growth.schedule_times): beside optics that change with age",
        "a zero factor",
    );
    assert!(!dir.path().join("zero").exists());
    let mut fixed = zero.to_vec();
    fixed.extend_from_slice(&["--set", "optics.surfaces=[{}, {}]"]);
    succeeded(
        &grow("scenes/optics-age.toml", "zero-fixed", &fixed),
        "a zero factor, fixed eye",
    );
}
