//! `eyeshell sweep`: a grid and a list of runs, each in its own directory with the table
//! collecting them; a failed run kept beside the good ones; bad sweeps refused cleanly; an
//! interrupted sweep keeps its finished runs and `--resume` does only the rest, after
//! checking that the files of each run it reuses are those the run wrote.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::support::*;
use eyeshell::scene::sweep::Sweep;
use eyeshell::sweep::{run_sweep, RunStatus, SweepOptions};

/// A small growth scene (N = 21, CVODE rtol 1e-3): a run takes a few hundredths of a second.
const SMALL: &str = "name = \"small\"\n[fibres]\nD = 0.0\n[growth]\neta0 = 70.0\nt_end = 0.2\n[solver]\nnodes = 21\nrtol = 1e-3\n[output]\ntimes = [0.1]\nhistory_points = 10\n";

fn write_scene(dir: &Path, text: &str) {
    std::fs::write(dir.join("s.toml"), text).unwrap();
}

#[test]
fn a_grid_runs_every_combination_into_its_own_directory() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        &format!("{SMALL}[sweep.grid]\n\"growth.Gamma\" = [4, 12]\n\"growth.delta\" = [2, 6]\n"),
    );
    let run = eyeshell_in(
        dir.path(),
        &["sweep", "s.toml", "--out", "out", "--jobs", "2"],
    );
    assert_eq!(run.code, Some(0), "{}{}", run.stdout, run.stderr);
    let out = dir.path().join("out");
    let (header, rows) = csv_cells(&out.join("sweep.csv"));
    assert_eq!(
        &header[..4],
        ["run", "status", "growth.Gamma", "growth.delta"]
    );
    let names: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        names,
        [
            "Gamma=4_delta=2",
            "Gamma=4_delta=6",
            "Gamma=12_delta=2",
            "Gamma=12_delta=6"
        ]
    );
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    for r in &rows {
        assert_eq!(r[1], "ok");
        // The table's axial length is the run's own last series row.
        let (_, series) = csv_cells(&out.join("runs").join(&r[0]).join("series.csv"));
        assert_eq!(
            r[col("axial_length")],
            series.last().unwrap()[1],
            "{}",
            r[0]
        );
        // Each run is the base scene with its values: the run's scene.toml says so.
        let scene =
            std::fs::read_to_string(out.join("runs").join(&r[0]).join("scene.toml")).unwrap();
        assert!(
            scene.contains(&format!("growth.Gamma = {}.0", r[2])),
            "{scene}"
        );
        assert!(
            scene.contains(&format!("growth.delta = {}.0", r[3])),
            "{scene}"
        );
        assert!(scene.contains("solver.nodes = 21"));
        assert!(r[col("newton_iterations")].parse::<usize>().unwrap() > 0);
        assert!(!r[col("class")].is_empty());
    }
    // Different growth zones give different eyes.
    let lengths: Vec<f64> = rows
        .iter()
        .map(|r| r[col("axial_length")].parse().unwrap())
        .collect();
    assert!(lengths.windows(2).all(|w| w[0] != w[1]), "{lengths:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "ok");
    assert_eq!(summary["runs"].as_array().unwrap().len(), 4);
    // Each run directory is an ordinary run: export and plot read it.
    ok(&[
        "plot",
        s(&out),
        "--out",
        s(&dir.path().join("plots")),
        "--quiet",
    ]);
    assert!(dir
        .path()
        .join("plots/Gamma=4_delta=2/timeline.png")
        .is_file());
    assert!(dir.path().join("plots/axial_length.svg").is_file());
}

/// sweep.csv's refraction_D is each run's pole refraction at its end (its series.csv's last
/// refraction_D, byte for byte; summary.json the same number), for a sweep of spectacle
/// lenses, which move it by about their power; a result.json written before eyeshell
/// recorded it (no "refraction_D") still reads on --resume: the run is reused and its
/// refraction_D cell is NaN (what eyeshell writes for a value it does not have).
#[test]
fn the_sweep_table_has_each_runs_refraction_and_older_results_still_resume() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        &format!(
            "{SMALL}[stimulus]\nsource = \"optics\"\n[optics]\nfocus = \"sagittal\"\npupil = 1.0\n\
             [[sweep.runs]]\nname = \"none\"\n[[sweep.runs]]\nname = \"minus2\"\n\
             \"optics.lenses\" = [{{ kind = \"spectacle\", power = -2.0 }}]\n"
        ),
    );
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "-q"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let out = dir.path().join("out");
    let (header, rows) = quoted_cells(&out.join("sweep.csv"));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    // series.csv's order: the class, then the refraction.
    assert_eq!(col("refraction_D"), col("class") + 1);
    let mut refraction = vec![];
    for r in &rows {
        let (series_header, series) = csv_cells(&out.join("runs").join(&r[0]).join("series.csv"));
        let at = series_header
            .iter()
            .position(|h| h == "refraction_D")
            .unwrap();
        assert_eq!(
            r[col("refraction_D")],
            series.last().unwrap()[at],
            "{}",
            r[0]
        );
        refraction.push(r[col("refraction_D")].parse::<f64>().unwrap());
    }
    // Behind a −2 D lens the eye grows longer (the lens moves its focus back), and its naked
    // refraction ends less hyperopic.
    assert!(refraction.iter().all(|d| d.is_finite()), "{refraction:?}");
    assert!(refraction[1] < refraction[0], "{refraction:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["runs"][0]["result"]["refraction_D"]
            .as_f64()
            .unwrap(),
        refraction[0]
    );

    // An older eyeshell's result.json: the same without refraction_D.
    let first = out.join("runs").join(&rows[0][0]).join("result.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&first).unwrap()).unwrap();
    assert!(v.as_object_mut().unwrap().remove("refraction_D").is_some());
    std::fs::write(&first, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "--resume"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let (_, rows) = quoted_cells(&out.join("sweep.csv"));
    assert_eq!(rows[0][1], "reused", "{}", run.stderr);
    assert_eq!(rows[0][col("refraction_D")], "NaN");
    assert!(!rows[0][col("axial_length")].is_empty());
    assert_eq!(
        rows[1][col("refraction_D")].parse::<f64>().unwrap(),
        refraction[1]
    );
}

/// sweep.csv's header and rows, a quoted cell read as one (a swept lens table holds commas
/// and doubled quotes).
fn quoted_cells(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let cells = |line: &str| {
        let (mut out, mut cell, mut quoted) = (vec![], String::new(), false);
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '"' if quoted && chars.peek() == Some(&'"') => {
                    cell.push('"');
                    chars.next();
                }
                '"' => quoted = !quoted,
                ',' if !quoted => out.push(std::mem::take(&mut cell)),
                c => cell.push(c),
            }
        }
        out.push(cell);
        out
    };
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = cells(lines.next().unwrap());
    (header, lines.map(cells).collect())
}

#[test]
fn a_failed_run_is_reported_and_the_others_are_kept() {
    let dir = tempfile::tempdir().unwrap();
    // η0 = 1e4 with two Euler steps turns the shell inside out at the first step.
    write_scene(
        dir.path(),
        &format!("{SMALL}[[sweep.runs]]\nname = \"good\"\n[[sweep.runs]]\nname = \"bad\"\n\"growth.eta0\" = 1e4\n\"solver.integrator\" = \"euler\"\n\"solver.steps\" = 2\n"),
    );
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "-q"]);
    assert_fails(
        &run,
        1,
        "1 of 2 runs failed: bad: growth failed at t = 0.02",
    );
    let out = dir.path().join("out");
    let (header, rows) = csv_cells(&out.join("sweep.csv"));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    assert_eq!((rows[0][0].as_str(), rows[0][1].as_str()), ("good", "ok"));
    assert_eq!(
        (rows[1][0].as_str(), rows[1][1].as_str()),
        ("bad", "failed")
    );
    assert!(
        rows[1][col("error")].contains("passed through its axis"),
        "{:?}",
        rows[1]
    );
    // The failed run keeps what it wrote before it failed (t = 0), and says so.
    assert_eq!(rows[1][col("t")], "0.0");
    let summary = std::fs::read_to_string(out.join("runs/bad/summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"failed\""));
    assert!(out.join("runs/good/result.json").is_file());
    assert!(!out.join("runs/bad/result.json").exists());
}

#[test]
fn bad_sweeps_are_refused_before_anything_runs() {
    let cases = [
        ("[sweep.grid]\n\"fibres.D\" = [0, -1]\n", vec![], "run D=-1"),
        (
            "[sweep.grid]\n\"fibres.DD\" = [0]\n",
            vec![],
            "unknown key 'fibres.DD'",
        ),
        (
            "[sweep.grid]\n\"fibres.D\" = [0, 1]\n",
            vec!["--set", "fibres.D=3"],
            "sweeps fibres.D",
        ),
        ("[sweep]\n", vec![], "[sweep] is empty"),
    ];
    for (extra, sets, needle) in cases {
        let dir = tempfile::tempdir().unwrap();
        write_scene(dir.path(), &format!("{SMALL}{extra}"));
        let mut args = vec!["sweep", "s.toml", "--out", "out"];
        args.extend(sets);
        let run = eyeshell_in(dir.path(), &args);
        assert_bad(&run, needle, extra);
        assert!(!dir.path().join("out").exists(), "{extra}");
    }
    // A sweep is not a scene for solve or grow.
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        &format!("{SMALL}[sweep.grid]\n\"fibres.D\" = [0, 1]\n"),
    );
    for cmd in ["grow", "solve"] {
        let run = eyeshell_in(dir.path(), &[cmd, "s.toml", "--out", "out"]);
        assert_bad(&run, "run it with `eyeshell sweep s.toml --out DIR`", cmd);
    }
    let _ = foreign_dir_is_refused("sweep", SMALL);
}

#[test]
fn an_interrupted_sweep_keeps_its_finished_runs_and_resume_does_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let text = format!("{SMALL}[sweep.grid]\n\"growth.Gamma\" = [4, 6, 8, 10]\n");
    let sweep = Sweep::from_toml_str(&text, "s.toml", &[]).unwrap();
    // One run at a time; "Ctrl-C" as soon as the first run ends.
    let cancel = AtomicBool::new(false);
    let options = SweepOptions {
        jobs: 1,
        resume: false,
        cancel: &cancel,
        runner: &eyeshell::sweep::InProcess,
        inputs: &[],
    };
    let report = run_sweep(&sweep, &out, &options, &|_, _, _| {
        cancel.store(true, Ordering::SeqCst)
    })
    .unwrap();
    assert!(report.interrupted);
    assert_eq!(report.status(), "interrupted");
    let done: Vec<&str> = report
        .records
        .iter()
        .filter(|r| r.status == RunStatus::Ok)
        .map(|r| r.name.as_str())
        .collect();
    assert_eq!(done.len(), 1, "{:?}", report.records);
    let (_, rows) = csv_cells(&out.join("sweep.csv"));
    assert_eq!(rows.iter().filter(|r| r[1] == "not run").count(), 3);
    let first = out.join("runs").join(done[0]);
    let written = std::fs::read_to_string(first.join("series.csv")).unwrap();

    // --resume: the finished run is reused as it is, the others run.
    let cancel = AtomicBool::new(false);
    let options = SweepOptions {
        jobs: 2,
        resume: true,
        cancel: &cancel,
        runner: &eyeshell::sweep::InProcess,
        inputs: &[],
    };
    let report = run_sweep(&sweep, &out, &options, &|_, _, _| {}).unwrap();
    assert_eq!(report.status(), "ok");
    let statuses: Vec<RunStatus> = report.records.iter().map(|r| r.status.clone()).collect();
    assert_eq!(
        statuses.iter().filter(|s| **s == RunStatus::Reused).count(),
        1,
        "{statuses:?}"
    );
    assert_eq!(
        statuses.iter().filter(|s| **s == RunStatus::Ok).count(),
        3,
        "{statuses:?}"
    );
    assert_eq!(
        std::fs::read_to_string(first.join("series.csv")).unwrap(),
        written
    );

    // A changed scene is not reused.
    let other = Sweep::from_toml_str(&text, "s.toml", &["growth.eta0=60".into()]).unwrap();
    let report = run_sweep(&other, &out, &options, &|_, _, _| {}).unwrap();
    assert!(report.records.iter().all(|r| r.status == RunStatus::Ok));
}

#[test]
fn elastic_sweeps_solve_each_shell() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(dir.path(), "[material]\nthickness = \"nonuniform\"\n[solver]\nnodes = 51\n[sweep.grid]\n\"fibres.D\" = [0, 200]\n");
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "-q"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let (header, rows) = csv_cells(&dir.path().join("out/sweep.csv"));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    assert!(rows
        .iter()
        .all(|r| r[col("kind")] == "solve" && r[1] == "ok"));
    // The loaded, ungrown eye: shorter than 2 R0 and hyperopic; fibres stiffen it.
    let l: Vec<f64> = rows
        .iter()
        .map(|r| r[col("axial_length")].parse().unwrap())
        .collect();
    assert!(l.iter().all(|&x| x > 19.0 && x < 20.5), "{l:?}");
    assert!(l[1] < l[0], "{l:?}");
    assert!(rows.iter().all(|r| r[col("class")] == "hyperopic"));
    assert!(dir.path().join("out/runs/D=200/fields.csv").is_file());
    // Each run's summary names the physics its model contains: fibres only where D > 0.
    let summary = |run: &str| -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(dir.path().join(format!("out/runs/{run}/summary.json")))
                .unwrap(),
        )
        .unwrap()
    };
    let (free, fibres) = (summary("D=0"), summary("D=200"));
    assert_eq!(free["components"]["membrane"]["kind"], "neo_hookean");
    assert_eq!(fibres["components"]["membrane"]["kind"], "reinforced");
    assert_eq!(fibres["components"]["thickness"]["kind"], "profile");
    assert_eq!(free["components"]["growth"], false);
    assert!(
        free["model"].as_str().unwrap().contains("no fibres"),
        "{}",
        free["model"]
    );
}

#[test]
fn check_lists_the_runs_of_a_sweep() {
    let r = ok(&["check", "scenes/grow.toml"]);
    assert!(
        r.stdout.starts_with(
            "# scenes/grow.toml: valid sweep 'grow' of 6 runs over growth.Gamma, growth.delta"
        ),
        "{}",
        r.stdout
    );
    assert!(
        r.stdout
            .lines()
            .any(|l| l.starts_with("#   Gamma=12_delta=6 ")
                && l.ends_with(" growth.Gamma = 12, growth.delta = 6")),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("fibres.D = 100.0"), "{}", r.stdout);
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        &format!("{SMALL}[sweep.grid]\n\"fibres.D\" = [1, -1]\n"),
    );
    assert_bad(
        &eyeshell_in(dir.path(), &["check", "s.toml"]),
        "s.toml [sweep] run D=-1: fibres.D = -1 must be non-negative",
        "check",
    );
}

/// Runs of a few tenths of a second each: a signal sent after the first run's line
/// arrives while the second runs.
fn slow_sweep(dir: &Path) {
    let text = SMALL
        .replace("nodes = 21", "nodes = 201")
        .replace("t_end = 0.2", "t_end = 1.0")
        .replace("times = [0.1]", "times = [0.5]")
        // The published Euler's fixed work (12000 elastic solves, about 2.3 s a run here),
        // so that a run outlasts the tests' signals however fast the solves get and however
        // loaded the machine (at 4000 steps, 0.8 s, a run once ended between the two
        // Ctrl-Cs of `a_second_ctrl_c_ends_the_workers_too` at load 7).
        .replace(
            "rtol = 1e-3",
            "rtol = 1e-6\nintegrator = \"euler\"\nsteps = 12000",
        );
    write_scene(
        dir,
        &format!("{text}[sweep.grid]\n\"growth.Gamma\" = [4, 5, 6, 7, 8, 9]\n"),
    );
}

/// `eyeshell sweep` of [`slow_sweep`] in `dir`, one job, in a process group of its own (so
/// that a test can signal the group as a terminal does); its stderr, after the first line.
fn start_slow_sweep(dir: &Path) -> (std::process::Child, impl std::io::BufRead) {
    slow_sweep(dir);
    let (child, stderr, _) = spawn_in_own_group(
        dir,
        &["sweep", "s.toml", "--out", "out", "--jobs", "1"],
        "eyeshell: [1/6] ",
    );
    (child, stderr)
}

/// SIGINT to `pid`, or to its whole process group (as Ctrl-C at a terminal).
fn interrupt(pid: u32, group: bool) {
    let target = if group {
        format!("-{pid}")
    } else {
        pid.to_string()
    };
    let killed = std::process::Command::new("kill")
        .args(["-INT", "--", &target])
        .status()
        .unwrap();
    assert!(killed.success());
}

/// A real Ctrl-C (SIGINT) to `eyeshell sweep`: no new run starts, the running one finishes,
/// the table says which did not run, and the exit is 1 with one line saying how to resume.
/// Sent to the whole process group, as a terminal does, it reaches the run's worker process
/// too, which ignores it: the running run still finishes.
#[test]
fn ctrl_c_stops_starting_runs_and_keeps_the_table() {
    for group in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let (mut child, mut stderr) = start_slow_sweep(dir.path());
        interrupt(child.id(), group);
        let mut rest = String::new();
        std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(1), "group {group}: {rest}");
        assert!(
            rest.contains("interrupted: finishing the running runs"),
            "{rest}"
        );
        let last = rest.lines().last().unwrap();
        assert!(
            last.starts_with("eyeshell: error: sweep interrupted: ") && last.contains("--resume"),
            "{last}"
        );
        let (_, rows) = csv_cells(&dir.path().join("out/sweep.csv"));
        let ok = rows.iter().filter(|r| r[1] == "ok").count();
        let not_run = rows.iter().filter(|r| r[1] == "not run").count();
        assert!(
            (1..=5).contains(&ok) && ok + not_run == 6,
            "group {group}: {rows:?}"
        );
        let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
        assert!(summary.contains("\"status\": \"interrupted\""), "{summary}");
        // Every finished run is whole.
        for r in rows.iter().filter(|r| r[1] == "ok") {
            assert!(dir
                .path()
                .join("out/runs")
                .join(&r[0])
                .join("result.json")
                .is_file());
        }
    }
}

/// The processes of group `pgid` that have not ended (zombies aside), from /proc.
fn alive_in_group(pgid: u32) -> Vec<String> {
    let mut alive = Vec::new();
    for entry in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(stat) = std::fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // pid (comm) state ppid pgrp ...
        let Some((_, fields)) = stat.rsplit_once(')') else {
            continue;
        };
        let fields: Vec<&str> = fields.split_whitespace().collect();
        if fields.len() > 2 && fields[2] == pgid.to_string() && fields[0] != "Z" {
            alive.push(stat);
        }
    }
    alive
}

/// A second Ctrl-C exits at once (130), and the worker running a run ends with it
/// instead of finishing the run alone.
#[test]
fn a_second_ctrl_c_ends_the_workers_too() {
    let dir = tempfile::tempdir().unwrap();
    let (mut child, mut stderr) = start_slow_sweep(dir.path());
    let pgid = child.id();
    interrupt(pgid, true);
    std::thread::sleep(std::time::Duration::from_millis(50));
    interrupt(pgid, true);
    let status = child.wait().unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    assert_eq!(status.code(), Some(130), "{rest}");
    let start = std::time::Instant::now();
    while !alive_in_group(pgid).is_empty() {
        assert!(
            start.elapsed().as_secs() < 10,
            "still running: {:?}",
            alive_in_group(pgid)
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// `--jobs` is bounded (a typo of 100000 would spawn threads for seconds and then blame the
/// output directory): refused first, on one line, exit 2, nothing written.
#[test]
fn absurd_jobs_are_refused_before_anything_else() {
    let dir = tempfile::tempdir().unwrap();
    for jobs in ["0", "100000"] {
        for cmd in [
            vec!["sweep", "scenes/fibre.toml", "--jobs", jobs, "--out"],
            vec!["figures", "--jobs", jobs, "--out"],
        ] {
            let out = dir.path().join("out");
            let mut args = cmd.clone();
            args.push(s(&out));
            let r = eyeshell(&args);
            assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
            assert!(
                r.stderr.contains(&format!("--jobs {jobs}: give 1 to 1024")),
                "{}",
                r.stderr
            );
            assert_eq!(r.stderr.lines().count(), 1);
            assert!(!out.exists());
        }
    }
}

/// Each run's result.json lists its files (size, FNV-1a 64); --resume reuses a run only
/// if they are all there unchanged, runs the others again, and says why on the run's line.
#[test]
fn resume_runs_again_what_was_deleted_resized_or_edited() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        "[solver]\nnodes = 21\n[sweep.grid]\n\"fibres.D\" = [0, 100, 200, 300, 400, 500]\n",
    );
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "-q"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let runs = dir.path().join("out/runs");
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(runs.join("D=0/result.json")).unwrap())
            .unwrap();
    let listed: Vec<&str> = result["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["path"].as_str().unwrap())
        .collect();
    assert_eq!(listed, ["fields.csv", "scene.toml", "summary.json"]);
    let bytes = std::fs::metadata(runs.join("D=0/fields.csv"))
        .unwrap()
        .len();
    assert_eq!(result["files"][0]["bytes"], bytes);
    assert_eq!(result["files"][0]["fnv1a64"].as_str().unwrap().len(), 16);
    // The sweep's own summary does not repeat the lists.
    let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
    assert!(!summary.contains("fnv1a64"));

    let fields = runs.join("D=0/fields.csv");
    let original = std::fs::read(&fields).unwrap();
    let mut edited = original.clone();
    let last = edited.len() - 2;
    edited[last] = if edited[last] == b'1' { b'2' } else { b'1' };
    std::fs::write(&fields, &edited).unwrap();
    let mut longer = std::fs::read(runs.join("D=100/summary.json")).unwrap();
    longer.push(b' ');
    std::fs::write(runs.join("D=100/summary.json"), longer).unwrap();
    std::fs::remove_file(runs.join("D=200/fields.csv")).unwrap();
    // result.json as an earlier eyeshell wrote it: no list.
    let old = runs.join("D=300/result.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&old).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("files");
    std::fs::write(&old, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    std::fs::write(runs.join("D=400/result.json"), "{ not json").unwrap();

    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "--resume"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let line = |name: &str| {
        run.stderr
            .lines()
            .find(|l| l.contains(&format!("] {name} ")))
            .unwrap_or_else(|| panic!("no line for {name}: {}", run.stderr))
            .to_string()
    };
    for (name, why) in [
        ("D=0", "ok: axial length"),
        (
            "D=0",
            "; ran again: fields.csv was changed after the run wrote it",
        ),
        ("D=100", "; ran again: summary.json has "),
        ("D=200", "; ran again: fields.csv is missing"),
        ("D=300", "; ran again: its result.json lists no files"),
        ("D=400", "; ran again: its result.json is not valid"),
        ("D=500", "reused: axial length"),
    ] {
        assert!(
            line(name).contains(why),
            "{name}: {why:?} not in {}",
            line(name)
        );
    }
    assert!(!line("D=500").contains("ran again"));
    // Run again, the edited run is as it first was (the solve is deterministic).
    assert_eq!(std::fs::read(&fields).unwrap(), original);
    let (_, rows) = csv_cells(&dir.path().join("out/sweep.csv"));
    let status: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(status, ["ok", "ok", "ok", "ok", "ok", "reused"]);
}

/// However many runs fail, the error line names the first three and counts the rest (the
/// table has every message).
#[test]
fn many_failed_runs_make_one_short_line() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        &format!("{SMALL}[sweep.grid]\n\"growth.eta0\" = [1e4, 2e4, 3e4, 4e4, 5e4]\n\"solver.integrator\" = [\"euler\"]\n\"solver.steps\" = [2]\n"),
    );
    let run = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "out", "-q"]);
    assert_fails(&run, 1, "5 of 5 runs failed: ");
    assert_eq!(
        run.stderr.matches("growth failed at").count(),
        3,
        "{}",
        run.stderr
    );
    assert!(
        run.stderr
            .contains("; and 2 more (the other results are in "),
        "{}",
        run.stderr
    );
    let (_, rows) = csv_cells(&dir.path().join("out/sweep.csv"));
    assert!(rows.iter().all(|r| r[1] == "failed"), "{rows:?}");
}
