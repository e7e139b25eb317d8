//! Hostile inputs, family 1 (TESTING.md): finite but absurd numbers, through the binary, under
//! a memory limit and a time limit ([`bounded`]). Each is refused on one line before any
//! output exists, or (where the scene is legal but the solve cannot succeed) fails cleanly
//! within the time limit, saying where. The scene-level checks behind them are unit-tested
//! in `crates/eyeshell/src/scene/tests/`.

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

/// Growth rates too fast for the integrators (growth.eta0 = 1e150, 1e300, where IDA itself
/// says "IDASolve … IDA_ILL_INPUT … tstop = 1 is behind current t = 0"): a clean failure
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

/// `eyeshell ARGS` in `dir` must be refused (exit 2, one line naming `needle`) in well
/// under a second, within the memory limit, leaving `dir` as it was: no output, and no
/// `.out.tmp` or `.out.lock` beside it.
fn refused_at_once(dir: &std::path::Path, args: &[&str], needle: &str) {
    let before = World::of(dir);
    let start = std::time::Instant::now();
    let r = bounded(dir, args);
    let took = start.elapsed();
    refused(&r, needle, &format!("{args:?}"));
    assert!(took.as_secs_f64() < 1.0, "{args:?} took {took:?}");
    assert_eq!(World::of(dir), before, "{args:?} left something");
}

/// Sizes legal one key at a time whose run would allocate or write too much are counted
/// before the run starts and refused with the limit in the message: solver.richardson
/// solves on the mesh halved twice (300 000 nodes became 1.2 million: "memory allocation
/// failed", SIGABRT, `.out.tmp` and `.out.lock` left behind); output.times is a file a
/// time (20 000 times wrote 20 001 files, 319 MB), and the bytes of all the snapshots are
/// bounded too. In a sweep, the run that would is named and nothing runs.
#[test]
fn what_a_run_would_allocate_or_write_is_refused_before_it_starts() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("e.toml"), "").unwrap();
    let richardson = |nodes: &str| {
        [
            "solve",
            "e.toml",
            "--out",
            "out",
            "--set",
            "solver.richardson=true",
            "--set",
            nodes,
        ]
        .map(String::from)
    };
    for (nodes, needle) in [
        (
            "solver.nodes=300000",
            "solver.nodes = 300000 is too large with solver.richardson: its solve on the mesh halved twice would lay 120",
        ),
        ("solver.nodes=1000000", "more than the 1000000 nodes (2.4 GB) a solve may"),
        ("solver.nodes=250000", "give solver.nodes at most about 2499"),
    ] {
        let args = richardson(nodes);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused_at_once(d, &args, needle);
    }
    // With solver.tol, the adapted mesh halved twice: up to 2·max_nodes + 1.
    refused_at_once(
        d,
        &[
            "solve", "e.toml", "--out", "out", "--set", "solver.richardson=true", "--set",
            "solver.tol=1e-8", "--set", "solver.max_nodes=600000",
        ],
        "solver.max_nodes = 600000 is too large with solver.richardson: its solve on the mesh halved twice would lay 1200001 nodes",
    );
    // Just inside the bound: accepted (checked, not solved).
    let r = bounded(
        d,
        &[
            "check",
            "e.toml",
            "--set",
            "solver.richardson=true",
            "--set",
            "solver.nodes=240000",
        ],
    );
    succeeded(&r, "richardson at 240000 nodes");

    // output.times: a file a time, at most 1000 of them.
    let times = |n: usize| {
        (1..=n)
            .map(|i| format!("{}", i as f64 / n as f64 * 0.2))
            .collect::<Vec<_>>()
            .join(", ")
    };
    std::fs::write(
        d.join("g.toml"),
        format!(
            "[solver]\nnodes = 21\n[growth]\nt_end = 0.2\n[output]\ntimes = [{}]\n",
            times(20_000)
        ),
    )
    .unwrap();
    refused_at_once(
        d,
        &["grow", "g.toml", "--out", "out"],
        "lists 20000 times, more than the 1000 allowed (each time is a snapshot file",
    );
    let r = bounded(d, &["grow", "g.toml", "--out", "out"]);
    assert!(
        r.stderr.contains("(20000 values)"),
        "shown short: {}",
        r.stderr
    );
    assert!(r.stderr.len() < 600, "{}", r.stderr);
    // 1000 times are legal, but not on a million nodes: 1001 snapshots of 520 bytes a node.
    std::fs::write(
        d.join("g.toml"),
        format!(
            "[growth]\nt_end = 0.2\n[output]\ntimes = [{}]\n",
            times(1000)
        ),
    )
    .unwrap();
    refused_at_once(
        d,
        &[
            "grow",
            "g.toml",
            "--out",
            "out",
            "--set",
            "solver.nodes=100000",
        ],
        "would have the run write about 59.9 GB (1001 snapshot files of up to 100",
    );
    refused_at_once(
        d,
        &[
            "grow",
            "g.toml",
            "--out",
            "out",
            "--set",
            "solver.nodes=100000",
        ],
        "more than the 8.6 GB a growth run may write",
    );
    let r = bounded(d, &["check", "g.toml", "--set", "solver.nodes=101"]);
    succeeded(&r, "1000 times at 101 nodes");

    // In a sweep: the run that would is named, before anything runs.
    std::fs::write(
        d.join("s.toml"),
        "[solver]\nrichardson = true\n[sweep.grid]\n\"solver.nodes\" = [101, 300000]\n",
    )
    .unwrap();
    refused_at_once(d, &["sweep", "s.toml", "--out", "out"], "run nodes=300000");
}
