//! Hostile inputs, family 1 (issue 13): finite but absurd numbers, through the binary, under
//! a memory limit and a time limit ([`bounded`]). Each is refused on one line before any
//! output exists, or (where the scene is legal but the solve cannot succeed) fails cleanly
//! within the time limit, saying where. The scene-level checks behind them are unit-tested
//! in `crates/eyeshell/src/scene/tests.rs`.

use crate::support::*;

/// `eyeshell CMD s.toml --set SETS... --out out` must be refused (exit 2, one line naming
/// `needle`), quickly, within the memory limit, writing nothing.
fn refused_before_output(cmd: &[&str], sets: &[&str], needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        "[growth]\nt_end = 0.2\n[output]\ntimes = [0.1, 0.2]\n",
    )
    .unwrap();
    let mut args: Vec<&str> = cmd.to_vec();
    args.push("s.toml");
    for s in sets {
        args.extend(["--set", s]);
    }
    args.extend(["--out", "out"]);
    let r = bounded(dir.path(), &args);
    refused(&r, needle, &format!("{args:?}"));
    assert_only_entry(dir.path(), "s.toml", &format!("{args:?}"));
}

#[test]
fn sizes_that_would_exhaust_memory_are_refused_first() {
    for cmd in [&["solve"][..], &["grow"], &["converge"]] {
        for (set, needle) in [
            ("solver.nodes=100000000000", "solver.nodes"),
            ("solver.nodes=18446744073709551615", "solver.nodes"),
            ("solver.max_newton=99999999999", "solver.max_newton"),
            ("geometry.R0=1e308", "geometry.R0"),
            ("geometry.fraction=1e300", "geometry.fraction"),
            ("material.bending=1e-300", "material.bending"),
            ("material.bending=5e-324", "material.bending"),
        ] {
            refused_before_output(cmd, &[set], needle);
        }
    }
    for (set, needle) in [
        (
            "output.history_points=100000000000",
            "output.history_points",
        ),
        ("solver.steps=100000000000", "solver.steps"),
    ] {
        refused_before_output(&["grow"], &[set], needle);
    }
    // converge's own ladder is bounded too.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), "").unwrap();
    for nodes in ["5,100000000000", "3,5", "51"] {
        let r = bounded(
            dir.path(),
            &["converge", "s.toml", "--nodes", nodes, "--out", "out"],
        );
        refused(&r, "--nodes", nodes);
    }
    assert_only_entry(dir.path(), "s.toml", "converge");
}

/// Legal scenes at the edge of what double precision can solve end within the time limit:
/// solved, or failed on one line that says where, never a hang.
#[test]
fn legal_extremes_end_in_bounded_time() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), "").unwrap();
    for sets in [
        &["material.bending=1e-200", "solver.cornea_grading=false"][..],
        &["material.bending=1e-300", "solver.cornea_grading=false"],
        &["fibres.D=1e12"],
        &["material.C=1e-300"],
        &["pressure.dP=1e300"],
        &["solver.epsilon=1e-320"],
        &["solver.nodes=1000000", "solver.max_newton=2"],
    ] {
        let mut args = vec!["solve", "s.toml", "-q", "--out", "out"];
        for s in sets {
            args.extend(["--set", s]);
        }
        let r = bounded(dir.path(), &args);
        match r.code {
            Some(0) => assert!(dir.path().join("out/fields.csv").is_file()),
            Some(1) | Some(2) => {
                assert_eq!(r.stderr.lines().count(), 1, "{sets:?}: {}", r.stderr);
                assert!(r.stderr.starts_with("eyeshell: error: "), "{}", r.stderr);
                assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
                assert!(r.stderr.len() < 600, "a short line: {}", r.stderr);
                assert!(!dir.path().join("out").exists(), "{sets:?}: half-written");
            }
            other => panic!("{sets:?}: exit {other:?}: {}", r.stderr),
        }
        let _ = std::fs::remove_dir_all(dir.path().join("out"));
    }
}

/// A growth run to the float maximum's neighbourhood ends in bounded time with short file
/// names (a snapshot at t = 1e300 was named with 300 digits and failed).
#[test]
fn growth_to_absurd_times_keeps_short_names() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("g.toml"),
        "[solver]\nnodes = 21\nrtol = 1e-3\n[growth]\nt_end = 1e300\n[output]\ntimes = [0.1]\n",
    )
    .unwrap();
    let r = bounded(dir.path(), &["grow", "g.toml", "-q", "--out", "out"]);
    succeeded(&r, "t_end = 1e300");
    let names: Vec<String> = std::fs::read_dir(dir.path().join("out/snapshots"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| n.len() < 40), "{names:?}");
    let r = bounded(dir.path(), &["export", "out", "--npz", "x", "-q"]);
    succeeded(&r, "export");
}

/// growth.t_end too short for the integrators to step (their time × step products
/// underflow below about 1e-160) is refused with the limit, before any output; every
/// number in the message is short (1e-250 was printed with 250 digits).
#[test]
fn growth_too_short_to_step_is_refused_with_the_limit() {
    for t in ["1e-101", "1e-200", "5e-324"] {
        refused_before_output(
            &["grow"],
            &[&format!("growth.t_end={t}"), &format!("output.times=[{t}]")],
            &format!("growth.t_end = {t} must be at least 1e-100"),
        );
    }
    // Output times after a tiny t_end: named in short numbers.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        "[growth]\nt_end = 1e-50\n[output]\ntimes = [0.1, 0.2]\n",
    )
    .unwrap();
    let r = bounded(dir.path(), &["grow", "s.toml", "--out", "out"]);
    refused(&r, "0.2 is after growth.t_end = 1e-50", "output.times");
    assert!(r.stderr.len() < 200, "{}", r.stderr);
}

/// Growth rates too fast for the integrators (growth.eta0 = 1e150, 1e300: IDA used to stop
/// with "IDASolve … IDA_ILL_INPUT … tstop = 1 is behind current t = 0"): a clean failure
/// at t = 0 in the scene's terms, with every integrator, in bounded time.
#[test]
fn growth_rates_too_fast_fail_in_the_scenes_terms() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("g.toml"),
        "[solver]\nnodes = 21\n[growth]\nt_end = 1\n[output]\ntimes = [0.5]\n",
    )
    .unwrap();
    for integrator in ["ida", "cvode", "euler"] {
        for eta0 in ["1e150", "1e300"] {
            let what = format!("{integrator}, η0 = {eta0}");
            let r = bounded(
                dir.path(),
                &[
                    "grow",
                    "g.toml",
                    "-q",
                    "--set",
                    &format!("solver.integrator={integrator}"),
                    "--set",
                    &format!("growth.eta0={eta0}"),
                    "--out",
                    "out",
                ],
            );
            assert_eq!(r.code, Some(1), "{what}: {}", r.stderr);
            one_clean_line(&r, &what);
            for needle in [
                "growth failed at t = 0",
                "the growth rates at t = 0 are too fast for the integrators",
                &format!("growth.eta0 = {eta0}"),
            ] {
                assert!(
                    r.stderr.contains(needle),
                    "{what}: {needle:?} not in {}",
                    r.stderr
                );
            }
            for raw in ["IDA", "CVode", "tstop", "ILL_INPUT"] {
                assert!(!r.stderr.contains(raw), "{what}: {}", r.stderr);
            }
            assert!(r.stderr.len() < 500, "{what}: {}", r.stderr);
            let _ = std::fs::remove_dir_all(dir.path().join("out"));
        }
    }
}
