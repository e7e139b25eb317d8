//! Sweeps too large to build: million- and ten-million-run grids planned and sharded without
//! building their scenes.

use super::*;

/// A grid of 10⁶ solves (100 × 100 × 100 values), N = 11.
fn million_run_grid() -> String {
    let values = |a: f64, b: f64| {
        let v: Vec<String> = (0..100)
            .map(|i| format!("{:?}", a + (b - a) * i as f64 / 99.0))
            .collect();
        format!("[{}]", v.join(", "))
    };
    format!(
        "name = \"million\"\n[solver]\nnodes = 11\n[sweep.grid]\n\"pressure.dP\" = {}\n\"material.C\" = {}\n\"fibres.D\" = {}\n",
        values(1.0, 3.0),
        values(50.0, 150.0),
        values(0.0, 400.0)
    )
}

/// A 10⁶-run grid is validated and partitioned without per-run work (milliseconds), run
/// in shards of at most MAX_RUNS, and its status read, one run at a time (under `bounded`'s
/// 4 GiB of address space and 60 s; measured: 7 s of CPU); a plain sweep of it, or a shard
/// too large for one process, is refused before anything is written.
#[test]
fn a_million_run_grid_is_planned_and_sharded_without_building_its_scenes() {
    let d = scene_dir(&million_run_grid());
    let dir = d.path();
    let script = bounded(dir, &["sweep", "s.toml", "--out", "out", "--slurm-script"]);
    assert_eq!(script.code, Some(0), "{}", script.stderr);
    assert!(
        script.stdout.contains("(1000000 runs)"),
        "{}",
        script.stdout
    );
    assert!(
        script.stdout.contains("#SBATCH --array=1-100\n"),
        "{}",
        script.stdout
    );

    let plain = bounded(dir, &["sweep", "s.toml", "--out", "out"]);
    assert_fails(
        &plain,
        2,
        "1000000 runs, more than the 10000 allowed in one process",
    );
    let big_shard = bounded(dir, &["sweep", "s.toml", "--out", "out", "--shard", "1/10"]);
    assert_fails(
        &big_shard,
        2,
        "shard 1/10 would hold 100000 of the sweep's 1000000 runs",
    );
    assert!(
        big_shard.stderr.contains("N of at least 100"),
        "{}",
        big_shard.stderr
    );
    assert!(
        !dir.join("out").exists(),
        "nothing written before the refusals"
    );

    // Equal costs: round-robin, so shard 7 of 100000 holds runs 7, 100007, ... (1-based).
    let shard = bounded(
        dir,
        &[
            "sweep", "s.toml", "--out", "out", "--shard", "7/100000", "-q",
        ],
    );
    assert_eq!(shard.code, Some(0), "{}", shard.stderr);
    let record: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/shards/7.json")).unwrap()).unwrap();
    let runs = record["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 10);
    assert!(runs.iter().all(|r| r["status"] == "ok"), "{record}");
    assert_eq!(std::fs::read_dir(dir.join("out/runs")).unwrap().count(), 10);

    let status = bounded(dir, &["sweep", "status", "out"]);
    assert_fails(&status, 1, "999990 of 1000000 runs of the sweep");
    assert!(
        status.stdout.contains("10 of 1000000 runs ok"),
        "{}",
        status.stdout
    );
    // Only shards can run the rest: no plain --resume is offered.
    assert!(
        status
            .stdout
            .contains("run the rest:   eyeshell sweep s.toml --out out --resume --shard K/100000"),
        "{}",
        status.stdout
    );
}

/// A grid of 10⁷ solves (100 × 100 × 100 × 10 values), N = 11: the million-run grid and
/// ten Newton tolerances.
fn ten_million_run_grid() -> String {
    let tols: Vec<String> = (1..=10).map(|i| format!("{i}e-10")).collect();
    format!(
        "{}\"solver.newton_tol\" = [{}]\n",
        million_run_grid().replace("name = \"million\"", "name = \"ten-million\""),
        tols.join(", ")
    )
}

/// `eyeshell ARGS` in `dir`, timed: it must end in well under a second.
fn within_a_second(dir: &Path, args: &[&str]) -> Run {
    let start = std::time::Instant::now();
    let r = bounded(dir, args);
    let took = start.elapsed();
    assert!(took.as_secs_f64() < 1.0, "{args:?} took {took:?}");
    r
}

/// A grid of 10⁷ runs (the most a sweep may plan) is counted, planned and partitioned
/// without making a run's name or scene per run: a plain sweep of it is refused, its
/// --slurm-script printed, and shard 1/1000 starts running, each in well under a second
/// (they took 30 s and 1.9 GB, 100 s, and more than 60 s). What stands for its validation
/// is each grid value once ([`SweepPlan::representatives`]), and each shard validates all
/// of its own runs before it runs any.
#[test]
fn a_ten_million_run_grid_is_planned_in_well_under_a_second() {
    let d = scene_dir(&ten_million_run_grid());
    let dir = d.path();
    let plain = within_a_second(dir, &["sweep", "s.toml", "--out", "out"]);
    assert_fails(
        &plain,
        2,
        "10000000 runs, more than the 10000 allowed in one process",
    );
    let script = within_a_second(dir, &["sweep", "s.toml", "--out", "out", "--slurm-script"]);
    assert_eq!(script.code, Some(0), "{}", script.stderr);
    assert!(
        script.stdout.contains("(10000000 runs)"),
        "{}",
        script.stdout
    );
    assert!(
        sbatch_options(&script.stdout).contains(&"--array=1-1000".to_string()),
        "{}",
        script.stdout
    );
    let too_few = within_a_second(
        dir,
        &[
            "sweep",
            "s.toml",
            "--out",
            "out",
            "--slurm-script",
            "--shards",
            "999",
        ],
    );
    assert_fails(
        &too_few,
        2,
        "a shard would hold 10011 of the sweep's 10000000 runs",
    );
    assert!(
        !dir.join("out").exists(),
        "nothing written before the shard"
    );

    // Shard 1/1000: planned, its 10 000 runs built and validated, and its first run done,
    // within a second; then stopped.
    let start = std::time::Instant::now();
    let (mut child, _stderr, first) = spawn_in_own_group(
        dir,
        &[
            "sweep", "s.toml", "--out", "out", "--shard", "1/1000", "--jobs", "1",
        ],
        "eyeshell: [1/10000] ",
    );
    let took = start.elapsed();
    kill_group(&mut child);
    assert!(
        took.as_secs_f64() < 1.0,
        "shard 1/1000 took {took:?} to its first run: {first}"
    );
    let record: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/shards/1.json")).unwrap()).unwrap();
    assert_eq!(record["runs_total"], 10_000, "{record}");
    // Round-robin (every run costs the same): shard 1 holds runs 1, 1001, 2001, ...
    let runs = record["runs"].as_array().unwrap();
    assert_eq!(
        runs[0]["name"], "dP=1_C=50_D=0_newton_tol=1e-10",
        "{}",
        runs[0]
    );
    assert_eq!(
        runs[1]["name"], "dP=1_C=51.01010101010101_D=0_newton_tol=1e-10",
        "{}",
        runs[1]
    );
}
