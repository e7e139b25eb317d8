//! `solver.max_seconds` on the command line: a bound reached is exit 1 with one
//! clean line naming the key and where it was reached; a growth run keeps what it wrote; a
//! bound not reached changes no result; bad bounds are bad input.

use std::time::Instant;

use crate::support::*;

#[test]
fn a_solve_out_of_time_fails_cleanly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let r = eyeshell(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "solver.nodes=20001",
        "--set",
        "solver.max_seconds=1e-6",
        "--out",
        s(&out),
    ]);
    assert_fails(
        &r,
        1,
        "solver.max_seconds = 1e-6 s reached in the elastic solve, after 0 Newton iterations",
    );
    assert!(!out.exists());
}

#[test]
fn a_growth_run_out_of_time_keeps_what_it_wrote() {
    let dir = tempfile::tempdir().unwrap();
    // At t = 0: the first elastic solve is stopped; the summary says so.
    let out = dir.path().join("early");
    let r = eyeshell(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=20001",
        "--set",
        "solver.max_seconds=1e-6",
        "--out",
        s(&out),
        "-q",
    ]);
    assert_fails(
        &r,
        1,
        "solver.max_seconds = 1e-6 s reached in the elastic solve",
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"failed\""), "{summary}");
    assert!(
        summary.contains("solver.max_seconds = 1e-6 s reached"),
        "{summary}"
    );
    // Later: a million Euler steps take minutes; the bound stops them after a second, and
    // the snapshot at t = 0 and its series row stay.
    let out = dir.path().join("late");
    let start = Instant::now();
    let r = eyeshell(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=21",
        "--set",
        "solver.integrator=euler",
        "--set",
        "solver.steps=1000000",
        "--set",
        "solver.max_seconds=1",
        "--out",
        s(&out),
        "-q",
    ]);
    let took = start.elapsed().as_secs_f64();
    assert_fails(&r, 1, "solver.max_seconds = 1 s reached");
    assert!(took < 30.0, "{took} s");
    assert!(out.join("snapshots/snapshot_00000_t0.000000.csv").is_file());
    let (_, series) = csv_cells(&out.join("series.csv"));
    assert_eq!(series.len(), 1, "the row at t = 0");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["status"], "failed");
    assert!(v["failed_at_t"].as_f64().unwrap() > 0.0, "{v}");
    assert!(
        v["error"]
            .as_str()
            .unwrap()
            .contains("solver.max_seconds = 1 s reached"),
        "{v}"
    );
    assert_eq!(v["parameters"]["solver.max_seconds"], 1.0);
}

/// The files of a run that hold results (not summary.json, whose wall times and parameters
/// differ), as bytes.
fn results(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    for sub in ["", "snapshots"] {
        let Ok(entries) = std::fs::read_dir(dir.join(sub)) else {
            continue;
        };
        for e in entries {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "csv") {
                files.push((p.display().to_string(), std::fs::read(&p).unwrap()));
            }
        }
    }
    files.sort();
    files
        .into_iter()
        .map(|(p, b)| (p.rsplit('/').next().unwrap().to_string(), b))
        .collect()
}

#[test]
fn a_bound_not_reached_changes_no_result() {
    let dir = tempfile::tempdir().unwrap();
    for (cmd, scene) in [
        ("solve", "scenes/default.toml"),
        ("grow", "scenes/const.toml"),
    ] {
        let run = |name: &str, extra: &[&str]| {
            let out = dir.path().join(name);
            let mut args = vec![
                cmd,
                scene,
                "--set",
                "solver.nodes=51",
                "--out",
                s(&out),
                "-q",
            ];
            args.extend_from_slice(extra);
            ok(&args);
            out
        };
        let free = run(&format!("{cmd}-free"), &[]);
        let bound = run(
            &format!("{cmd}-bound"),
            &["--set", "solver.max_seconds=1e6"],
        );
        let (a, b) = (results(&free), results(&bound));
        assert!(!a.is_empty(), "{cmd}");
        assert!(a == b, "{cmd}: the results differ");
        // The bound is recorded only where it was given.
        let parameters = |d: &std::path::Path| {
            let v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap())
                    .unwrap();
            v["parameters"].clone()
        };
        assert!(parameters(&free).get("solver.max_seconds").is_none());
        assert_eq!(parameters(&bound)["solver.max_seconds"], 1e6);
    }
}

#[test]
fn a_bound_must_be_a_positive_finite_number() {
    for bad in ["0", "-1", "nan", "inf", "-0.0"] {
        let set = format!("solver.max_seconds={bad}");
        let r = eyeshell(&["check", "scenes/default.toml", "--set", &set]);
        assert_bad(&r, "solver.max_seconds", &set);
    }
    let r = eyeshell(&[
        "check",
        "scenes/default.toml",
        "--set",
        "solver.max_seconds=\"soon\"",
    ]);
    assert_bad(&r, "solver.max_seconds must be a number", "a string");
    // Shown by check when given, and not when not (it has no value then).
    let r = ok(&[
        "check",
        "scenes/default.toml",
        "--set",
        "solver.max_seconds=90",
    ]);
    assert!(
        r.stdout.contains("solver.max_seconds = 90.0\n"),
        "{}",
        r.stdout
    );
    let r = ok(&["check", "scenes/default.toml"]);
    assert!(!r.stdout.contains("max_seconds"), "{}", r.stdout);
    let keys = ok(&["keys"]).stdout;
    let line = keys
        .lines()
        .find(|l| l.starts_with("solver.max_seconds "))
        .expect("listed");
    assert!(
        line.contains("float") && line.contains("(none)") && line.contains("[> 0]"),
        "{line}"
    );
}
