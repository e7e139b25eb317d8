//! `eyeshell grow`: bad input (exit 2, one line naming the key, no output directory), scenes
//! without growth, `check` and `keys` for the growth keys, and a run end to end.

use crate::support::*;

/// Every bad growth value, from the file and from --set, for `grow` and for `solve`.
#[test]
fn bad_growth_values() {
    for (line, key) in [
        ("growth.eta0 = -1", "growth.eta0 = -1 must be non-negative"),
        ("growth.delta = 0", "growth.delta = 0 must be positive"),
        (
            "growth.t_end = -1",
            "growth.t_end = -1 must be at least 1e-100",
        ),
        ("growth.t_end = 0", "growth.t_end"),
        (
            "growth.Gamma = nan",
            "growth.Gamma = nan must be a finite number",
        ),
        ("growth.Gamma = inf", "growth.Gamma"),
        ("growth.thickness_law = \"volume\"", "growth.thickness_law"),
        ("solver.integrator = \"rk4\"", "solver.integrator"),
        ("solver.dae_linear = \"lu\"", "solver.dae_linear"),
        (
            "growth.kink_width = -1",
            "growth.kink_width = -1 must lie in [0, 1)",
        ),
        (
            "growth.kink_width = 1e300",
            "growth.kink_width = 1e300 must lie in [0, 1)",
        ),
        ("solver.rtol = 0", "solver.rtol"),
        ("solver.rtol = 1.5", "solver.rtol"),
        ("solver.atol = 0", "solver.atol"),
        ("solver.atol = -1e-8", "solver.atol"),
        ("solver.steps = 0", "solver.steps"),
        ("solver.steps = 2.5", "solver.steps"),
        ("output.times = []", "output.times"),
        ("output.times = [0.2, 0.1]", "strictly increasing"),
        ("output.times = [0, 1]", "output.times"),
        ("output.times = [0.5, 2]", "growth.t_end"),
        ("output.times = [0.5, \"x\"]", "output.times[2]"),
        ("output.times = \"soon\"", "output.times"),
        ("stimulus.blue.phi_max = 0", "stimulus.blue.phi_max"),
        ("stimulus.blue.phi_max = 4", "stimulus.blue.phi_max"),
        ("stimulus.red.phi_max = -1", "stimulus.red.phi_max"),
        ("stimulus.red.offset = nan", "stimulus.red.offset"),
        ("stimulus.blue.P3 = inf", "stimulus.blue.P3"),
        ("growth.gamma = 8", "did you mean 'growth.Gamma'"),
    ] {
        // A growth key of its own turns growth on (one that `line` does not give).
        let base = if line.starts_with("growth.thickness_law") {
            "growth.Gamma = 8\n"
        } else {
            "growth.thickness_law = \"none\"\n"
        };
        let scene = format!("{base}{line}\n");
        fails("grow", &scene, &[], key, "scene.toml: ");
        fails("solve", &scene, &[], key, "scene.toml: ");
        let set = line.replace(" = ", "=");
        fails("grow", base, &[&set], key, &format!("--set {set}: "));
    }
}

#[test]
fn a_scene_without_growth_is_refused_by_grow() {
    fails(
        "grow",
        "[pressure]\ndP = 2\n[solver]\nrtol = 1e-4\n",
        &[],
        "scene has no [growth] section: use `eyeshell solve`, or add growth keys",
        "scene.toml: ",
    );
    let run = eyeshell_in(
        repo(),
        &["grow", "scenes/default.toml", "--out", "/nonexistent/never"],
    );
    assert_bad(&run, "scene has no [growth] section", "default.toml");
}

#[test]
fn grow_refuses_a_foreign_directory_and_leaves_it_alone() {
    let dir = foreign_dir_is_refused("grow", "growth.eta0 = 70\n");
    let run = eyeshell_in(dir.path(), &["grow", "s.toml"]);
    assert_bad(&run, "--out", "no --out");
}

#[test]
fn check_says_whether_growth_is_on() {
    let run = eyeshell_in(repo(), &["check", "scenes/const.toml"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(run.stdout.contains("# growth: on"), "{}", run.stdout);
    for line in [
        "growth.eta0 = 70.0\n",
        "growth.Gamma = 8.0\n",
        "growth.delta = 4.0\n",
        "growth.thickness_law = \"none\"\n",
        "solver.integrator = \"ida\"\n",
        "output.times = [0.1, 0.2, 0.4, 1.0]\n",
        "# stimulus.red.offset = 0.655  (follows blue)\n",
    ] {
        assert!(
            run.stdout.contains(line),
            "{line:?} missing:\n{}",
            run.stdout
        );
    }
    // The listing reads back to the same scene.
    let back = eyeshell::scene::Scene::from_toml_str(&run.stdout, "check", &[]).unwrap();
    let direct = eyeshell::scene::Scene::from_file(&repo().join("scenes/const.toml"), &[]).unwrap();
    assert_eq!(back.growth, direct.growth);
    assert_eq!(back.growth_settings, direct.growth_settings);
    for s in [
        "scenes/default.toml",
        "scenes/fibres-nonuniform.toml",
        "scenes/exact-sphere.toml",
    ] {
        let run = eyeshell_in(repo(), &["check", s]);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        assert!(run.stdout.contains("# growth: off"), "{s}: {}", run.stdout);
        assert!(!run.stdout.contains("growth.eta0"), "{s}: {}", run.stdout);
    }
    let run = eyeshell_in(
        repo(),
        &["check", "scenes/default.toml", "--set", "growth.delta=2"],
    );
    assert!(run.stdout.contains("# growth: on") && run.stdout.contains("growth.delta = 2.0"));
}

#[test]
fn keys_lists_the_growth_keys() {
    let run = eyeshell_in(repo(), &["keys"]);
    assert_eq!(run.code, Some(0));
    for key in [
        "growth.eta0",
        "growth.Gamma",
        "growth.delta",
        "growth.t_end",
        "growth.thickness_law",
        "solver.integrator",
        "solver.rtol",
        "solver.atol",
        "solver.steps",
        "output.times",
        "stimulus.blue.P1",
        "stimulus.blue.P2",
        "stimulus.blue.P3",
        "stimulus.blue.z_B",
        "stimulus.blue.phi_max",
        "stimulus.red.P1",
        "stimulus.red.P2",
        "stimulus.red.P3",
        "stimulus.red.z_B",
        "stimulus.red.phi_max",
        "stimulus.red.offset",
    ] {
        assert!(
            run.stdout
                .lines()
                .any(|l| l.split_whitespace().next() == Some(key)),
            "{key} missing"
        );
    }
    assert!(run.stdout.contains("[0.1, 0.2, 0.4, 1.0]"));
    let run = eyeshell_in(repo(), &["--help"]);
    assert!(run.stdout.contains("grow"), "{}", run.stdout);
    let run = eyeshell_in(repo(), &["grow", "--help"]);
    assert!(
        run.stdout.contains("--out")
            && run.stdout.contains("--quiet")
            && run.stdout.contains("--set")
    );
}

/// `solve` on a growing scene solves the initial shell and ignores growth.
#[test]
fn solve_ignores_growth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("elastic");
    let run = eyeshell_in(
        repo(),
        &[
            "solve",
            "scenes/const.toml",
            "--set",
            "solver.nodes=101",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(out.join("fields.csv").is_file());
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["parameters"]["growth.eta0"], 70.0);
}

/// The const scene end to end, on a coarse mesh with loose tolerances.
#[test]
fn grow_const_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("const");
    let out_s = out.to_str().unwrap();
    let run = eyeshell_in(
        repo(),
        &[
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.nodes=101",
            "--set",
            "solver.rtol=1e-4",
            "--out",
            out_s,
        ],
    );
    assert_eq!(
        run.code,
        Some(0),
        "stderr: {}\nstdout: {}",
        run.stderr,
        run.stdout
    );
    assert!(
        run.stderr.is_empty(),
        "no progress bar off a terminal: {:?}",
        run.stderr
    );
    assert!(
        run.stdout.contains("axial length") && run.stdout.contains(out_s),
        "{}",
        run.stdout
    );

    let (h, series) = csv_cells(&out.join("series.csv"));
    assert_eq!(
        h.join(","),
        "t,axial_length,equatorial_radius,retina_minus_blue,retina_minus_red,class,refraction_D,drive,defocus_D"
    );
    let times: Vec<f64> = series.iter().map(|r| r[0].parse().unwrap()).collect();
    assert_eq!(times, vec![0.0, 0.1, 0.2, 0.4, 1.0]);
    let axial: Vec<f64> = series.iter().map(|r| r[1].parse().unwrap()).collect();
    assert!(axial.iter().all(|a| a.is_finite() && *a > 0.0), "{axial:?}");
    // Growth never shrinks: the axial length does not fall.
    assert!(axial.windows(2).all(|w| w[1] >= w[0] - 1e-9), "{axial:?}");
    for r in &series {
        assert!(
            ["hyperopic", "emmetropic", "myopic"].contains(&r[5].as_str()),
            "{r:?}"
        );
    }

    let mut snaps: Vec<_> = std::fs::read_dir(out.join("snapshots"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    snaps.sort();
    assert_eq!(snaps.len(), 5);
    let header = eyeshell::bvp::COLUMNS
        .iter()
        .chain(eyeshell::growth::GROWTH_COLUMNS.iter())
        .copied()
        .collect::<Vec<_>>()
        .join(",");
    let mut nodes = None;
    for p in &snaps {
        let (h, rows) = csv_cells(p);
        assert_eq!(h.join(","), header, "{}", p.display());
        assert!(rows.len() >= 101, "{}: {} rows", p.display(), rows.len());
        assert_eq!(*nodes.get_or_insert(rows.len()), rows.len());
        for r in &rows {
            assert_eq!(r.len(), 22);
            // Every field finite but defocus_D, NaN where the rule reads no defocus.
            let (fields, defocus) = r.split_at(21);
            assert!(fields.iter().all(|v| v.parse::<f64>().unwrap().is_finite()));
            assert!(defocus[0].parse::<f64>().unwrap().is_nan());
        }
    }

    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["status"], "ok");
    assert_eq!(v["integrator"], "ida");
    assert_eq!(v["rtol"], 1e-4);
    let steps = v["steps"].as_u64().unwrap();
    assert!(steps > 0);
    // IDA: one residual per Newton iteration, a few Newton-matrix set-ups, no right sides.
    assert!(v["residual_evaluations"].as_u64().unwrap() >= steps);
    assert!((1..steps).contains(&v["jacobian_evaluations"].as_u64().unwrap()));
    assert_eq!(v["rhs_evaluations"], 0);
    assert!(v["bvp_solves"].as_u64().unwrap() > 0);
    assert_eq!(v["parameters"]["growth.eta0"], 70.0);
    assert_eq!(v["parameters"]["solver.nodes"], 101);
    assert!(v["sundials_version"].as_str().unwrap().starts_with('6'));

    // A second run replaces the first.
    let run = eyeshell_in(
        repo(),
        &[
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.nodes=101",
            "--set",
            "solver.rtol=1e-4",
            "--set",
            "output.times=[1.0]",
            "--quiet",
            "--out",
            out_s,
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(run.stdout.is_empty());
    assert_eq!(std::fs::read_dir(out.join("snapshots")).unwrap().count(), 2);
}

/// A run that fails (two explicit Euler steps with a huge growth rate turn the shell inside
/// out) exits 1 with one line, and keeps what it wrote: series.csv from t = 0 and a
/// summary.json that says where and why it failed.
#[test]
fn a_failed_run_keeps_its_results() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad");
    let run = eyeshell_in(
        repo(),
        &[
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.nodes=51",
            "--set",
            "solver.integrator=euler",
            "--set",
            "solver.steps=2",
            "--set",
            "growth.eta0=2000",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(run.code, Some(1), "{}", run.stderr);
    assert!(run.stdout.is_empty(), "{}", run.stdout);
    let lines: Vec<&str> = run.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{:?}", run.stderr);
    assert!(
        lines[0].starts_with("eyeshell: error: growth failed at t = "),
        "{}",
        lines[0]
    );
    let (_, series) = csv_cells(&out.join("series.csv"));
    assert!(!series.is_empty());
    assert_eq!(series[0][0].parse::<f64>().unwrap(), 0.0);
    let snaps = std::fs::read_dir(out.join("snapshots")).unwrap().count();
    assert_eq!(snaps, series.len());
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["status"], "failed");
    assert!(v["failed_at_t"].as_f64().unwrap() > 0.0, "{v}");
    assert!(
        v["error"].as_str().unwrap().starts_with("growth failed"),
        "{v}"
    );
    assert!(v.get("steps").is_some() && v.get("rhs_evaluations").is_some());
}

/// solver.tol out of reach in growth: with solver.max_nodes = 30 no mesh of at most 15 nodes
/// (M) can bring the space error of the const scene to 1e-4, so after the first round's
/// estimate the run stops, exit 1 (a failure, not bad input), one line giving the estimate,
/// its split and why; summary.json records that one round, and no snapshot is written.
#[test]
fn solver_tol_out_of_reach_in_growth_stops_after_the_round_that_shows_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("far");
    let run = eyeshell_in(
        repo(),
        &[
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.tol=1e-4",
            "--set",
            "solver.max_nodes=30",
            "--out",
            s(&out),
        ],
    );
    assert_fails(&run, 1, "solver.tol = 0.0001 cannot be reached in growth");
    assert!(
        run.stderr.contains(
            "and neither more nodes (solver.max_nodes = 30) nor a tighter rtol (down to 1e-10) is predicted to reach it"
        ),
        "{}",
        run.stderr
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let rounds = v["accuracy"]["rounds"].as_array().unwrap();
    assert_eq!(rounds.len(), 1, "{rounds:?}");
    assert_eq!(rounds[0]["nodes"], 15);
    assert!(rounds[0]["space"].as_f64().unwrap() > 1e-4, "{rounds:?}");
    assert!(snapshots(&out).is_empty());
}

/// Under solver.tol the report says what the run chose and what it estimates (the mesh, the
/// integrator's rtol and atol, the error and its split), the numbers summary.json records,
/// not the scene's rtol and atol, which solver.tol overrides.
#[test]
fn a_run_to_a_tolerance_reports_the_mesh_tolerances_and_error_it_chose() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tol");
    let run = eyeshell_in(
        repo(),
        &[
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.tol=1e-3",
            "--set",
            "solver.rtol=1e-3",
            "--out",
            s(&out),
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let acc = &v["accuracy"];
    let rounds = acc["rounds"].as_array().unwrap().len();
    let nodes = format!(
        "  nodes           {} (chosen for solver.tol = 1e-3 in {rounds} round{})",
        acc["nodes"],
        if rounds == 1 { "" } else { "s" }
    );
    assert!(run.stdout.contains(&nodes), "{nodes}\n{}", run.stdout);
    let (rtol, atol) = (acc["rtol"].as_f64().unwrap(), acc["atol"].as_f64().unwrap());
    assert!(rtol != 1e-3, "solver.tol chooses rtol, not the scene's");
    let line = format!("  integrator      ida (rtol {rtol:.3e}, atol {atol:.3e}), ");
    assert!(run.stdout.contains(&line), "{line}\n{}", run.stdout);
    let est = run
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("  error estimate  "))
        .expect("an error estimate line");
    let total: f64 = est.split(' ').next().unwrap().parse().unwrap();
    assert!(total > 0.0 && total <= 1e-3, "{est}");
    assert!(
        est.contains(" mm (the largest over the lengths and times; their largest space part ")
            && est.contains(", time part "),
        "{est}"
    );
}

/// Growth under solver.tol takes its thread count from `--jobs`, else from EYESHELL_JOBS:
/// the summary says how many threads the rounds used, the results are the same bit for
/// bit, and a count that is not one is refused in one line before anything is written.
#[test]
fn growth_to_a_tolerance_takes_a_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, jobs: Option<&str>, env: &[(&str, &str)]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.tol=1e-3",
            "--out",
            s(&out),
            "--quiet",
        ];
        if let Some(j) = jobs {
            args.extend(["--jobs", j]);
        }
        (eyeshell_with(repo(), &args, env), out)
    };
    let threads = |out: &std::path::Path| {
        let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["accuracy"]["threads"].as_u64()
    };
    let (r, one) = run("one", Some("1"), &[("EYESHELL_JOBS", "2")]);
    succeeded(&r, "--jobs 1");
    assert_eq!(threads(&one), Some(1), "--jobs wins over the environment");
    let (r, two) = run("two", None, &[("EYESHELL_JOBS", "2")]);
    succeeded(&r, "EYESHELL_JOBS=2");
    assert_eq!(threads(&two), Some(2));
    let (r, env_one) = run("env-one", None, &[("EYESHELL_JOBS", "1")]);
    succeeded(&r, "EYESHELL_JOBS=1");
    assert_eq!(threads(&env_one), Some(1));
    for file in ["series.csv", "history.csv"] {
        let a = std::fs::read(one.join(file)).unwrap();
        assert_eq!(a, std::fs::read(two.join(file)).unwrap(), "{file}");
    }
    for bad in ["0", "two", "1025", "-1"] {
        let (r, out) = run("bad", None, &[("EYESHELL_JOBS", bad)]);
        assert_fails(&r, 2, "EYESHELL_JOBS");
        one_clean_line(&r, bad);
        assert!(!out.exists(), "EYESHELL_JOBS={bad} wrote {}", out.display());
    }
    let (r, _) = run("bad", Some("0"), &[]);
    assert_fails(&r, 2, "--jobs");
}
