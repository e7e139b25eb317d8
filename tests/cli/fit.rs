//! `eyeshell fit` (calibration): the command end to end on a small case, and the
//! inputs it refuses (exit 2, one line, nothing written): hostile data files, bad keys, an
//! unidentifiable parameter, a foreign output directory.

use crate::support::*;

const DATA: &str = "examples/fit/const_synthetic.csv";

fn fit_args<'a>(data: &'a str, keys: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "fit",
        "scenes/const.toml",
        "--set",
        "solver.nodes=101",
        "--data",
        data,
        "--fit",
        keys,
        "--out",
        out,
    ]
}

#[test]
fn fit_writes_the_report_the_fitted_scene_and_the_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut args = fit_args(DATA, "growth.Gamma,growth.delta", s(&out));
    args.extend(["--set", "growth.Gamma=9", "--set", "growth.delta=3"]);
    let run = ok(&args);
    // The table on stdout.
    for needle in [
        "eyeshell: fitted scenes/const.toml (const) to examples/fit/const_synthetic.csv (10 observations, σ given)",
        "parameter",
        "growth.Gamma",
        "(2) growth.delta",
        "χ²",
        "converged",
    ] {
        assert!(run.stdout.contains(needle), "{needle:?} not in {}", run.stdout);
    }
    // The correlation table's rows line up with its header; Γ and δ are not a valley.
    let table: Vec<usize> = run
        .stdout
        .lines()
        .filter(|l| l.starts_with("  correlation") || l.starts_with("  ("))
        .map(|l| l.chars().count())
        .collect();
    assert_eq!(table.len(), 3, "{}", run.stdout);
    assert!(table.iter().all(|&w| w == table[0]), "{}", run.stdout);
    assert!(
        !run.stdout.contains("strongly correlated"),
        "{}",
        run.stdout
    );
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            ".eyeshell",
            "curve.csv",
            "fit.json",
            "fit.png",
            "fit.svg",
            "residuals.csv",
            "scene.toml"
        ]
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap();
    let p = &report["parameters"];
    assert_eq!(p[0]["key"], "growth.Gamma");
    assert_eq!(p[0]["initial"], 9.0);
    let (gamma, se) = (
        p[0]["estimate"].as_f64().unwrap(),
        p[0]["standard_error"].as_f64().unwrap(),
    );
    assert!((gamma - 8.0).abs() < 2.0 * se, "Γ = {gamma} ± {se}");
    assert_eq!(report["data"]["observations"], 10);
    assert_eq!(report["data"]["fnv1a64"].as_str().unwrap().len(), 16);
    assert_eq!(report["covariance_scaling"], "sigma");
    assert!(report["iterations"].as_u64().unwrap() >= 1);
    assert_eq!(report["residuals"].as_array().unwrap().len(), 10);
    assert!(report["convergence_reason"]
        .as_str()
        .unwrap()
        .starts_with("converged"));
    // The fitted scene reads back with the estimate, and `check` accepts it.
    let scene = std::fs::read_to_string(out.join("scene.toml")).unwrap();
    assert!(scene.contains(&format!("Gamma = {gamma:?}")), "{scene}");
    ok(&["check", s(&out.join("scene.toml"))]);
    let (header, rows) = csv(&out.join("residuals.csv"));
    assert_eq!(
        header,
        [
            "t",
            "axial_length",
            "sigma",
            "model",
            "residual",
            "weighted_residual"
        ]
    );
    assert_eq!(rows.len(), 10);
    assert!(rows.iter().all(|r| (r[4] - (r[3] - r[1])).abs() < 1e-12));
    assert_eq!(column(&out.join("curve.csv"), "t").len(), 201);
    assert!(std::fs::metadata(out.join("fit.png")).unwrap().len() > 1000);
    // A second fit replaces the first (an eyeshell output).
    ok(&args);
}

/// Every hostile data file: exit 2, one line naming the file (and the line and column), and
/// nothing written.
#[test]
fn hostile_data_files_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let huge = format!("t,axial_length\n{}", "0.5,23.0\n".repeat(100_001));
    let cases: Vec<(&str, String, &str)> = vec![
        ("empty", String::new(), "empty file"),
        (
            "header only",
            "t,axial_length,sigma\n".into(),
            "no observations after the header",
        ),
        (
            "wrong header",
            "time,length\n0.1,22\n".into(),
            "line 1: the header must be",
        ),
        (
            "non-numeric",
            "t,axial_length\n0.1,22\n0.2,long\n".into(),
            "line 3: column 2 (axial_length): \"long\" is not a number",
        ),
        (
            "NaN",
            "t,axial_length\n0.1,NaN\n".into(),
            "line 2: column 2 (axial_length) = NaN must be a finite number",
        ),
        (
            "negative sigma",
            "t,axial_length,sigma\n0.1,22,-0.05\n".into(),
            "line 2: column 3 (sigma) = -0.05 must be positive",
        ),
        (
            "negative t",
            "t,axial_length\n-1,22\n".into(),
            "line 2: column 1 (t) = -1 must be ≥ 0",
        ),
        (
            "ragged",
            "t,axial_length,sigma\n0.1,22\n".into(),
            "line 2: 2 values for 3 columns",
        ),
        (
            "after t_end",
            "t,axial_length\n0.5,23\n1.5,24\n".into(),
            "observation 2 (t = 1.5) is after the scene's run ends",
        ),
        (
            "too few",
            "t,axial_length\n0.5,23\n".into(),
            "1 observation for 2 parameters",
        ),
        ("huge", huge, "line 100002: more than 100000 observations"),
        (
            "binary",
            "t,axial_length\n0.1,\u{0}\u{1}\n".into(),
            "is not a number",
        ),
        // Finite values whose weighted squares overflow: the cause named, not "converged"
        // with χ² = inf, nor "does not depend on growth.delta".
        (
            "overflow",
            "t,axial_length\n0.5,23\n0.6,1e308\n0.7,24\n".into(),
            "observation 2 (t = 0.6, axial_length = 1e308 mm, σ = 1 (none given)) gives the weighted residual",
        ),
        (
            "tiny sigma",
            "t,axial_length,sigma\n0.5,23,1e-170\n0.6,24,1e-170\n".into(),
            "σ = 1e-170 mm) gives the weighted residual",
        ),
    ];
    for (what, text, needle) in cases {
        let data = dir.path().join(format!("{}.csv", what.replace(' ', "_")));
        std::fs::write(&data, text).unwrap();
        let out = dir.path().join("out");
        let run = eyeshell(&fit_args(s(&data), "growth.Gamma,growth.delta", s(&out)));
        assert_bad(&run, needle, what);
        assert!(
            run.stderr.contains(s(&data)),
            "{what}: the file is named: {}",
            run.stderr
        );
        assert!(!out.exists(), "{what}: nothing may be written");
    }
    // Beyond the size limit (16 MiB), before any parsing.
    let big = dir.path().join("big.csv");
    std::fs::write(&big, vec![b'9'; (1 << 24) + 1]).unwrap();
    let out = dir.path().join("out");
    assert_bad(
        &eyeshell(&fit_args(s(&big), "growth.Gamma", s(&out))),
        "more than 16777216 bytes",
        "big",
    );
    assert!(!out.exists());
    let missing = dir.path().join("none.csv");
    assert_bad(
        &eyeshell(&fit_args(s(&missing), "growth.Gamma", s(&out))),
        "none.csv",
        "missing",
    );
    assert!(!out.exists());
}

#[test]
fn bad_keys_and_unidentifiable_parameters_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    for (keys, needle) in [
        ("growth.Gama", "--fit: \"growth.Gama\" is not a scene key"),
        (
            "growth.eta0,growth.eta0",
            "--fit: growth.eta0 is listed twice",
        ),
        ("stimulus.red.offset", "only affects the classification"),
        (
            "solver.nodes",
            "--fit: solver.nodes is a setting of the solver, not a parameter of the model",
        ),
        (
            "growth.schedule",
            "--fit: growth.schedule is not a real-valued key",
        ),
        // The check `grow --sensitivities` makes, before any run (exit 2, not 1 at t = 0).
        (
            "fibres.D",
            "fibres.D = 0: the scene has no fibres, so there is no sensitivity to their stiffness",
        ),
    ] {
        assert_bad(&eyeshell(&fit_args(DATA, keys, s(&out))), needle, keys);
        assert!(!out.exists(), "{keys}: nothing may be written");
    }
    // Γ far beyond the shell with a narrow fall: the growth does not depend on Γ.
    let mut args = fit_args(DATA, "growth.eta0,growth.Gamma", s(&out));
    args.extend(["--set", "growth.Gamma=80", "--set", "growth.delta=1"]);
    assert_bad(
        &eyeshell(&args),
        "the data cannot identify growth.Gamma:",
        "Γ beyond the shell",
    );
    // With the data that would identify it.
    assert_bad(
        &eyeshell(&args),
        "; data that would identify growth.Gamma: axial lengths late in the growth",
        "Γ beyond the shell, advice",
    );
    assert!(!out.exists());
    let mut args = fit_args(DATA, "growth.eta0", s(&out));
    args.extend(["--set", "solver.integrator=cvode"]);
    assert_bad(
        &eyeshell(&args),
        "a fit needs solver.integrator = \"ida\"",
        "cvode",
    );
    assert!(!out.exists());
}

#[test]
fn a_foreign_output_directory_is_refused_before_the_fit() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "keep").unwrap();
    let run = eyeshell(&fit_args(DATA, "growth.Gamma", s(&out)));
    assert_bad(&run, "refusing to overwrite", "foreign");
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "keep"
    );
}

/// η0 and Γ from plateau data are a valley (correlation −0.99): the report says which pair,
/// and what to do about it, under the correlation table.
#[test]
fn a_strongly_correlated_pair_is_pointed_out() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut args = fit_args(DATA, "growth.eta0,growth.Gamma,growth.delta", s(&out));
    args.extend([
        "--set",
        "growth.eta0=60",
        "--set",
        "growth.Gamma=9",
        "--set",
        "growth.delta=3.5",
    ]);
    let run = ok(&args);
    let note = run
        .stdout
        .lines()
        .find(|l| l.trim_start().starts_with("note"))
        .unwrap_or_else(|| panic!("no note in {}", run.stdout));
    assert!(
        note.contains("strongly correlated (|ρ| ≥ 0.99): growth.eta0 and growth.Gamma at -0.99"),
        "{note}"
    );
    assert!(!note.contains("growth.delta"), "{note}");
    assert!(
        note.contains("leave growth.Gamma, say, out of the fit and give its value with --set"),
        "{note}"
    );
}

/// What the scene's own surfaces and rule cannot differentiate is an input error naming the
/// key before anything runs, in a fit and in `grow --sensitivities`: the blue surface's
/// centre z_B of surfaces computed from the optics, and under a rule that reads dioptres.
#[test]
fn a_key_the_scenes_stimulus_cannot_use_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("data.csv"),
        "age,axial_length,sigma\n9,24.4,0.05\n10,24.6,0.05\n11,24.8,0.05\n",
    )
    .unwrap();
    let scene = repo().join("scenes/myopia/single-vision.toml");
    let scene = s(&scene);
    let fit = |sets: &[&str]| {
        let mut args = vec![
            "fit",
            scene,
            "--data",
            "data.csv",
            "--fit",
            "stimulus.blue.z_B",
            "--out",
            "out",
        ];
        for set in sets {
            args.extend(["--set", set]);
        }
        eyeshell_in(d, &args)
    };
    assert_bad(
        &fit(&[]),
        "fit: the sensitivity to stimulus.blue.z_B needs stimulus.source = \"polynomial\"",
        "z_B of computed surfaces",
    );
    assert_bad(
        &fit(&["stimulus.source=polynomial", "optics.lenses=[]"]),
        "needs a growth rule that reads the surfaces alone (the defocus rule",
        "z_B under the defocus rule",
    );
    let grow = eyeshell_in(
        d,
        &[
            "grow",
            scene,
            "--sensitivities",
            "stimulus.blue.z_B",
            "--out",
            "out",
        ],
    );
    assert_bad(
        &grow,
        "--sensitivities: the sensitivity to stimulus.blue.z_B",
        "grow",
    );
    assert_only_entry(d, "data.csv", "nothing written");
}

/// The joint fit of two arms (the guide's): each arm's scene, data and values in the
/// report; residuals.csv and curve.csv name the arm; a data path holding ':' and a scene
/// path holding '=' are split where the files are.
#[test]
fn a_joint_fit_of_two_arms_reports_each_arms_values() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ex = repo().join("examples/fit");
    std::fs::copy(ex.join("joint_none.csv"), d.join("a:none.csv")).unwrap();
    std::fs::copy(ex.join("joint_single-vision.csv"), d.join("sv.csv")).unwrap();
    std::fs::copy(
        repo().join("scenes/eyewear/single-vision.toml"),
        d.join("lens=-2.toml"),
    )
    .unwrap();
    let none = format!(
        "none={}:a:none.csv",
        s(&repo().join("scenes/eyewear/none.toml"))
    );
    let run = eyeshell_in(
        d,
        &[
            "fit",
            "--set",
            "solver.nodes=61",
            "--set",
            "output.history_points=0",
            "--arm",
            &none,
            "--arm",
            "single-vision=lens=-2.toml:sv.csv",
            "--fit",
            "growth.Gamma",
            "--per-arm",
            "growth.eta0",
            "--out",
            "out",
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    for needle in [
        "eyeshell: fitted 2 arms jointly (20 observations, σ given)",
        "  arm              single-vision: lens=-2.toml to sv.csv (10 observations of axial_length and refraction_D)",
        "growth.eta0[none]",
        "growth.eta0[single-vision]",
    ] {
        assert!(run.stdout.contains(needle), "{needle:?} not in {}", run.stdout);
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/fit.json")).unwrap()).unwrap();
    let p = json["parameters"].as_array().unwrap();
    assert_eq!(p.len(), 3);
    assert_eq!(p[2]["arm"], "single-vision");
    assert_eq!(
        p[1]["jacobian"],
        "IDAS sensitivity (axial length), finite differences (refraction)"
    );
    // The data were grown at η0 = 75, Γ = 7.5 in both arms.
    for q in p {
        let truth = if q["key"] == "growth.Gamma" {
            7.5
        } else {
            75.0
        };
        let z = (q["estimate"].as_f64().unwrap() - truth) / q["standard_error"].as_f64().unwrap();
        assert!(z.abs() < 2.0, "{q}");
    }
    assert_eq!(json["arms"][0]["data"]["file"], "a:none.csv");
    let residuals = std::fs::read_to_string(d.join("out/residuals.csv")).unwrap();
    let lines: Vec<&str> = residuals.lines().collect();
    assert_eq!(
        lines[0],
        "arm,t,measured,value,sigma,model,residual,weighted_residual"
    );
    assert_eq!(lines.len(), 1 + 2 * 2 * 10);
    assert!(
        lines[2].starts_with("none,0.1,refraction_D,5.47,0.15,"),
        "{}",
        lines[2]
    );
    assert!(
        lines[40].starts_with("single-vision,1.0,refraction_D,"),
        "{}",
        lines[40]
    );
    let curve = std::fs::read_to_string(d.join("out/curve.csv")).unwrap();
    assert!(curve.starts_with("arm,t,fitted_axial_length,initial_axial_length\nnone,0.0,"));
    for f in [
        "scene-none.toml",
        "scene-single-vision.toml",
        "fit-none.png",
        "fit-single-vision.svg",
    ] {
        assert!(d.join("out").join(f).is_file(), "{f}");
    }
}

/// Bad arms, keys and data of a joint fit: each exit 2 with one line, nothing written.
#[test]
fn bad_arms_keys_and_refraction_data_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ex = repo().join("examples/fit");
    std::fs::copy(ex.join("joint_none.csv"), d.join("j.csv")).unwrap();
    std::fs::copy(repo().join(DATA), d.join("l.csv")).unwrap();
    let none = s(&repo().join("scenes/eyewear/none.toml")).to_string();
    let konst = s(&repo().join("scenes/const.toml")).to_string();
    let arm = |name: &str, scene: &str, data: &str| format!("{name}={scene}:{data}");
    let cases: Vec<(Vec<String>, &str, &str)> = vec![
        (vec![format!("a={none}:missing.csv"), arm("b", &none, "j.csv")], "growth.eta0", "the data file \"missing.csv\" does not exist"),
        (vec![format!("a={none}"), arm("b", &none, "j.csv")], "growth.eta0", "no ':' between the scene and the data file"),
        (vec![format!("{none}:j.csv"), arm("b", &none, "j.csv")], "growth.eta0", "no '=' after the arm's name"),
        (vec![arm("a", &none, "j.csv"), arm("a", &none, "j.csv")], "growth.eta0", "--arm a: two arms have this name"),
        (vec![arm("a b", &none, "j.csv"), arm("b", &none, "j.csv")], "growth.eta0", "the arm's name \"a b\" must be letters"),
        (vec![arm("a", &none, "j.csv")], "growth.eta0", "a joint fit needs two arms or more"),
        (vec![arm("a", &none, "j.csv"), arm("b", &none, "j.csv")], "growth.Gama", "--fit: \"growth.Gama\" is not a scene key"),
        (vec![arm("a", &none, "j.csv"), arm("b", &none, "j.csv")], "growth.schedule", "--fit: growth.schedule is not a real-valued key"),
        (vec![arm("a", &none, "j.csv"), arm("b", &konst, "j.csv")], "growth.eta0", "j.csv: the data give refraction_D, but the scene computes no refraction: its stimulus is not from the optics"),
        (vec![arm("a", &konst, "l.csv"), arm("b", &konst, "l.csv")], "optics.surfaces[0].radius", "fit: optics.surfaces[0].radius is not used by the run of"),
    ];
    for (arms, key, needle) in cases {
        let mut args = vec![
            "fit",
            "--set",
            "solver.nodes=61",
            "--fit",
            key,
            "--out",
            "out",
        ];
        for a in &arms {
            args.extend(["--arm", a.as_str()]);
        }
        assert_bad(&eyeshell_in(d, &args), needle, &arms.join(" "));
        assert!(!d.join("out").exists(), "{needle}: nothing may be written");
    }
    // One scene: refraction data of a scene without optics, and --per-arm without arms.
    let one = |data: &str, extra: &[&str]| {
        let mut args = vec![
            "fit",
            konst.as_str(),
            "--data",
            data,
            "--fit",
            "growth.eta0",
            "--out",
            "out",
        ];
        args.extend(extra);
        eyeshell_in(d, &args)
    };
    assert_bad(
        &one("j.csv", &[]),
        "(stimulus.source = \"polynomial\" in",
        "refraction of const",
    );
    assert_bad(
        &one("l.csv", &["--per-arm", "growth.Gamma"]),
        "--per-arm growth.Gamma: a key of each arm's own needs arms",
        "per-arm alone",
    );
    assert!(!d.join("out").exists());
}
