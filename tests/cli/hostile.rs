//! Hostile files and values (TESTING.md): each case runs the binary under a memory and a time
//! limit ([`bounded`]) and asserts the exit code, one line of stderr with no panic text,
//! and that nothing was written or lost. The families this
//! module covers so far: broken run files (6), sweeps that point outside themselves
//! (5, 6), a sweep run that aborts its process, and `--resume` into directories that are
//! not the sweep's: planted symbolic links, other outputs, other sweeps (5). Finite but
//! absurd values (1) are in `crates/eyeshell/src/scene/tests/`, the mesh and solver
//! tests; names with control characters (7) in `keys_check.rs`; foreign .mat/.npz files in
//! `readers.rs` and `fuzz_readers.rs`; run files (CSV and summary.json) mutated at random in
//! `fuzz_run_files.rs`; `solver.max_seconds` in `max_seconds.rs`.

use std::path::Path;

use crate::support::*;

/// Three small elastic runs (N = 21, a few milliseconds each): D=0, D=100, D=200.
const THREE: &str = "[solver]\nnodes = 21\n[sweep.grid]\n\"fibres.D\" = [0, 100, 200]\n";

/// `s.toml` holding [`THREE`] in a fresh directory, swept once into `out`.
fn swept_three() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), THREE).unwrap();
    let r = bounded(dir.path(), &["sweep", "s.toml", "--out", "out", "-q"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    dir
}

/// `eyeshell sweep s.toml --out out --resume` in `dir` must be refused (exit 2, one clean
/// line naming `needle`), changing nothing in `dir`.
fn resume_is_refused(dir: &Path, needle: &str, what: &str) {
    let before = World::of(dir);
    let r = bounded(dir, &["sweep", "s.toml", "--out", "out", "--resume"]);
    assert_eq!(r.code, Some(2), "{what}: {}", r.stderr);
    one_clean_line(&r, what);
    assert!(r.stderr.contains(needle), "{what}: {}", r.stderr);
    assert!(World::of(dir) == before, "{what}: something changed");
}

/// A fields.csv that lost a column is refused by export, not written as a .mat with a short
/// `y` and an .npz with a missing row, as if nothing were wrong.
#[test]
fn a_run_missing_a_column_is_not_exported() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, _) = small_runs(dir.path());
    let fields = solve.join("fields.csv");
    let text = std::fs::read_to_string(&fields).unwrap();
    let cut: String = text
        .lines()
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(j, _)| *j != 2)
                .map(|(_, c)| c)
                .collect::<Vec<_>>()
                .join(",")
        })
        .map(|l| l + "\n")
        .collect();
    std::fs::write(&fields, cut).unwrap();
    for format in ["--mat", "--npz"] {
        let target = dir.path().join(format!("x{format}"));
        let r = bounded(repo(), &["export", s(&solve), format, s(&target)]);
        assert_eq!(r.code, Some(2), "{format}: {}", r.stderr);
        one_clean_line(&r, format);
        assert!(r.stderr.contains("no column \"kappa\""), "{}", r.stderr);
        assert!(!target.exists(), "{format}: nothing written");
    }
}

/// A sweep's summary.json whose run names the sweep itself (or a path out of it) is
/// refused by plot, which would otherwise recurse until the stack overflowed.
#[test]
fn a_sweep_run_pointing_outside_the_sweep_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        "[solver]\nnodes = 21\n[sweep.grid]\n\"fibres.D\" = [0, 100]\n",
    )
    .unwrap();
    let sweep = dir.path().join("sweep");
    let r = bounded(dir.path(), &["sweep", "s.toml", "--out", "sweep", "-q"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let summary = sweep.join("summary.json");
    let original = std::fs::read_to_string(&summary).unwrap();
    for bad in [".", "..", "../sweep", "/tmp", ""] {
        let planted = original.replacen("\"runs/D=0\"", &format!("{:?}", bad), 1);
        assert_ne!(planted, original, "the run's dir is in summary.json");
        std::fs::write(&summary, planted).unwrap();
        let plots = dir.path().join("plots");
        let r = bounded(repo(), &["plot", s(&sweep), "--out", s(&plots)]);
        assert_eq!(r.code, Some(2), "{bad:?}: {}", r.stderr);
        one_clean_line(&r, bad);
        assert!(
            r.stderr.contains("points outside the sweep"),
            "{}",
            r.stderr
        );
    }
    std::fs::write(&summary, original).unwrap();
    let plots = dir.path().join("plots");
    assert_eq!(
        bounded(repo(), &["plot", s(&sweep), "--out", s(&plots), "-q"]).code,
        Some(0)
    );
}

/// A run whose process aborts (as on a failed allocation or a stack overflow, which no
/// catch_unwind can stop) fails alone: the runs before and after it (in the same worker
/// slot, `--jobs 1`) finish, the table says which failed and how, the command exits 1
/// with one line. The abort is the worker's fault-injection hook, EYESHELL_TEST_ABORT_RUN.
#[test]
fn a_run_that_aborts_fails_alone() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), THREE).unwrap();
    let abort = ("EYESHELL_TEST_ABORT_RUN", "D=100");
    let args = ["sweep", "s.toml", "--out", "out", "--jobs", "1"];
    let r = bounded_with(dir.path(), &args, &[abort]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    let how = "D=100: the run's process ended abnormally (killed by signal 6: SIGABRT; out of memory or a stack overflow?)";
    // One line per run, then the error: nothing of the worker's reaches the terminal.
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 4, "{}", r.stderr);
    assert!(
        lines[1].contains("FAILED: the run's process ended abnormally"),
        "{}",
        lines[1]
    );
    assert!(
        lines[3].starts_with("eyeshell: error: 1 of 3 runs failed: ") && lines[3].contains(how),
        "{}",
        lines[3]
    );
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    let out = dir.path().join("out");
    let (header, rows) = csv_cells(&out.join("sweep.csv"));
    let error = header.iter().position(|h| h == "error").unwrap();
    let status: Vec<(&str, &str)> = rows
        .iter()
        .map(|r| (r[0].as_str(), r[1].as_str()))
        .collect();
    assert_eq!(
        status,
        [("D=0", "ok"), ("D=100", "failed"), ("D=200", "ok")]
    );
    assert_eq!(format!("D=100: {}", rows[1][error]), how);
    for ok in ["D=0", "D=200"] {
        for file in ["fields.csv", "summary.json", "scene.toml", "result.json"] {
            assert!(
                out.join("runs").join(ok).join(file).is_file(),
                "{ok}/{file}"
            );
        }
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "partial");
    assert_eq!(summary["runs_failed"], 1);
    assert!(summary["runs"][1]["error"]
        .as_str()
        .unwrap()
        .contains("SIGABRT"));

    // Resumed with the hook still set: the two good runs are reused, the third aborts
    // again; with -q the only line is the error.
    let mut quiet = args.to_vec();
    quiet.extend(["--resume", "-q"]);
    let r = bounded_with(dir.path(), &quiet, &[abort]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    one_clean_line(&r, "resumed");
    assert!(r.stderr.contains(how), "{}", r.stderr);
    let (_, rows) = csv_cells(&out.join("sweep.csv"));
    let status: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(status, ["reused", "failed", "reused"]);
    // Without the hook, the resumed sweep completes.
    let r = bounded(dir.path(), &quiet);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}

/// A `runs` link planted in a sweep's directory, pointing elsewhere: --resume refuses it
/// and touches neither side; a fresh sweep replaces the link, never writing through it.
#[test]
fn resume_never_follows_a_planted_runs_link() {
    let dir = swept_three();
    let out = dir.path().join("out");
    let elsewhere = dir.path().join("elsewhere");
    std::fs::rename(out.join("runs"), &elsewhere).unwrap();
    std::fs::write(elsewhere.join("precious.txt"), "keep").unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("runs")).unwrap();
    resume_is_refused(dir.path(), "out/runs: is a symbolic link", "runs link");
    // Without --resume the old output goes, link and all; what it pointed at stays.
    let before = World::of(&elsewhere);
    let r = bounded(dir.path(), &["sweep", "s.toml", "--out", "out", "-q"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(World::of(&elsewhere) == before, "written through the link");
    assert!(!std::fs::symlink_metadata(out.join("runs"))
        .unwrap()
        .file_type()
        .is_symlink());
}

/// A run directory, or a run's result.json or scene.toml, that is a link out of the sweep:
/// refused, nothing read or written on either side.
#[test]
fn resume_never_follows_a_planted_run_link() {
    for (planted, needle) in [
        ("D=100", "out/runs/D=100: is a symbolic link"),
        ("D=100/result.json", "result.json: is a symbolic link"),
        ("D=100/scene.toml", "scene.toml: is a symbolic link"),
        ("D=300", "out/runs/D=300: is a symbolic link"),
    ] {
        let dir = swept_three();
        let runs = dir.path().join("out/runs");
        let elsewhere = dir.path().join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        let target = elsewhere.join("target");
        match std::fs::symlink_metadata(runs.join(planted)) {
            Ok(_) => std::fs::rename(runs.join(planted), &target).unwrap(),
            Err(_) => std::fs::create_dir(&target).unwrap(),
        }
        std::os::unix::fs::symlink(&target, runs.join(planted)).unwrap();
        resume_is_refused(dir.path(), needle, planted);
    }
}

/// --resume into the output of something else than a sweep: refused, nothing changed.
#[test]
fn resume_into_another_output_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), THREE).unwrap();
    let (solve, grow) = small_runs(dir.path());
    let study = dir.path().join("study");
    ok(&[
        "converge",
        "scenes/default.toml",
        "--nodes",
        "11,21",
        "--out",
        s(&study),
    ]);
    // An eyeshell output (it has the marker) whose summary.json was damaged.
    let broken = dir.path().join("broken");
    ok(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "solver.nodes=11",
        "--out",
        s(&broken),
        "-q",
    ]);
    std::fs::write(broken.join("summary.json"), "{ not json").unwrap();
    for (target, needle) in [
        (&solve, "holds a solve output, not a sweep"),
        (&grow, "holds a grow output, not a sweep"),
        (
            &study,
            "holds the output of a study (converge), not a sweep",
        ),
        (&broken, "not valid JSON"),
    ] {
        let before = World::of(dir.path());
        let r = bounded(
            dir.path(),
            &["sweep", "s.toml", "--out", s(target), "--resume"],
        );
        assert_eq!(r.code, Some(2), "{needle}: {}", r.stderr);
        one_clean_line(&r, needle);
        assert!(r.stderr.contains(needle), "{}", r.stderr);
        assert!(
            World::of(dir.path()) == before,
            "{needle}: something changed"
        );
    }
}

/// --resume with a sweep that lacks some of the runs in the directory: refused (the old
/// runs would sit beside the new ones as if part of them). A sweep that adds runs, or
/// changes the scene, resumes: new runs run, changed ones run again and say why.
#[test]
fn resume_into_another_sweep() {
    let dir = swept_three();
    std::fs::write(dir.path().join("s.toml"), THREE.replace(", 200]", "]")).unwrap();
    resume_is_refused(
        dir.path(),
        "holds 1 run that is not in this sweep (D=200)",
        "fewer runs",
    );
    std::fs::write(
        dir.path().join("s.toml"),
        THREE.replace("200]", "200, 300]"),
    )
    .unwrap();
    let r = bounded(dir.path(), &["sweep", "s.toml", "--out", "out", "--resume"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let (_, rows) = csv_cells(&dir.path().join("out/sweep.csv"));
    let status: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(status, ["reused", "reused", "reused", "ok"]);
    let args = [
        "sweep",
        "s.toml",
        "--out",
        "out",
        "--resume",
        "--set",
        "pressure.dP=2.5",
    ];
    let r = bounded(dir.path(), &args);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_eq!(
        r.stderr.matches("ok: axial length").count(),
        4,
        "{}",
        r.stderr
    );
    assert_eq!(
        r.stderr.matches("; ran again: its scene changed").count(),
        4,
        "{}",
        r.stderr
    );
}

/// A scene file longer than 64 MB, or a device that never ends, is refused on one line
/// before it is read into memory, for every command that reads a scene.
#[test]
fn an_endless_or_huge_scene_file_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let huge = dir.path().join("huge.toml");
    let mut text = String::from("name = \"huge\"\n");
    let comment = format!("# {}\n", "x".repeat(1000));
    while text.len() <= 64 << 20 {
        text.push_str(&comment);
    }
    std::fs::write(&huge, text).unwrap();
    for scene in [s(&huge), "/dev/zero"] {
        for cmd in ["solve", "sweep"] {
            let run = bounded(dir.path(), &[cmd, scene, "--out", "out"]);
            assert_bad(&run, "too long for a scene", &format!("{cmd} {scene}"));
            assert!(run.stderr.contains(scene), "{}", run.stderr);
            assert!(!dir.path().join("out").exists());
        }
    }
    let run = bounded(
        dir.path(),
        &["sweep", "/dev/zero", "--out", "out", "--shard", "1/2"],
    );
    assert_bad(&run, "too long for a scene", "a shard of /dev/zero");
}
