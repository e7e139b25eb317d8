//! `eyeshell sweep --shard K/N` and `eyeshell sweep merge|status DIR`: shards run by hand,
//! one after the other or at once, merge to the table of a plain sweep; a shard killed
//! mid-way resumes; bad `--shard` values are refused; merge names missing and failed runs;
//! `--shard slurm` takes its shard from a job array's environment. (The real Slurm is
//! tests/cli/slurm.rs.)

use std::os::unix::ffi::OsStrExt;
use std::path::Path;
use std::process::{Command, Stdio};

use crate::support::*;

mod grids;
mod slurm;

/// A small growth scene (N = 21, CVODE rtol 1e-3): a run takes a few hundredths of a second.
pub(crate) const SMALL: &str = "name = \"small\"\n[fibres]\nD = 0.0\n[growth]\neta0 = 70.0\nt_end = 0.2\n[solver]\nnodes = 21\nrtol = 1e-3\n[output]\ntimes = [0.1]\nhistory_points = 10\n";
/// Six runs, as the paper's grow sweep: Γ × δ.
pub(crate) const GRID: &str =
    "[sweep.grid]\n\"growth.Gamma\" = [4, 8, 12]\n\"growth.delta\" = [2, 6]\n";

/// The cells of a CSV line (quoted cells unquoted).
fn cells(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(String::new()),
            (c, _) => out.last_mut().unwrap().push(c),
        }
    }
    out
}

/// sweep.csv of `dir` without its timing column (wall_seconds): what must not depend on how
/// the sweep was run.
pub(crate) fn table_without_timings(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let mut rows: Vec<Vec<String>> = text.lines().map(cells).collect();
    let col = rows[0].iter().position(|h| h == "wall_seconds").unwrap();
    for r in &mut rows {
        r.remove(col);
    }
    rows
}

/// summary.json of `dir` without the runs' wall_seconds.
fn summary_without_timings(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for run in v["runs"].as_array_mut().unwrap() {
        if let Some(r) = run["result"].as_object_mut() {
            r.remove("wall_seconds");
        }
    }
    v
}

fn scene_dir(text: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), text).unwrap();
    dir
}

fn spawn_shard(dir: &Path, shard: &str) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_eyeshell"))
        .args(["sweep", "s.toml", "--out", "out", "--jobs", "1", "-q"])
        .args(["--shard", shard])
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// `eyeshell sweep s.toml --out out -q --shard K/N` in `d`.
fn quiet_shard(d: &Path, k: usize, n: usize) -> Run {
    eyeshell_in(
        d,
        &[
            "sweep",
            "s.toml",
            "--out",
            "out",
            "-q",
            "--shard",
            &format!("{k}/{n}"),
        ],
    )
}

#[test]
fn shards_in_any_order_and_at_once_merge_to_the_plain_sweeps_table() {
    let dir = scene_dir(&format!("{SMALL}{GRID}"));
    let d = dir.path();
    let plain = eyeshell_in(d, &["sweep", "s.toml", "--out", "plain", "-q"]);
    assert_eq!(plain.code, Some(0), "{}", plain.stderr);

    // The last shard first, alone: two runs, its record, no table.
    let last = eyeshell_in(d, &["sweep", "s.toml", "--out", "out", "--shard", "3/3"]);
    assert_eq!(last.code, Some(0), "{}", last.stderr);
    assert!(
        last.stdout.contains("shard 3/3: 2 runs ok"),
        "{}",
        last.stdout
    );
    assert!(
        last.stdout.contains("eyeshell sweep merge out"),
        "{}",
        last.stdout
    );
    let out = d.join("out");
    assert!(out.join("shards/3.json").is_file());
    assert!(!out.join("sweep.csv").exists() && !out.join("summary.json").exists());
    let runs = std::fs::read_dir(out.join("runs")).unwrap().count();
    assert_eq!(runs, 2);

    // status: four runs missing, the command that runs them, exit 1, nothing written.
    let status = eyeshell_in(d, &["sweep", "status", "out"]);
    assert_fails(&status, 1, "4 of 6 runs of the sweep in out are not done");
    assert!(
        status
            .stdout
            .contains("2 of 6 runs ok, 0 failed, 4 missing"),
        "{}",
        status.stdout
    );
    assert!(
        status
            .stdout
            .contains("eyeshell sweep s.toml --out out --resume --shard K/3   for K = 1, 2"),
        "{}",
        status.stdout
    );
    assert!(!out.join("sweep.csv").exists());

    // The other two at once.
    let a = spawn_shard(d, "1/3");
    let b = spawn_shard(d, "2/3");
    for child in [a, b] {
        let r = Run::from(child.wait_with_output().unwrap());
        assert_eq!(r.code, Some(0), "{}", r.stderr);
    }
    // Every run in exactly one shard's record.
    let mut names: Vec<String> = (1..=3)
        .flat_map(|k| {
            let text = std::fs::read_to_string(out.join(format!("shards/{k}.json"))).unwrap();
            let v: serde_json::Value = serde_json::from_str(&text).unwrap();
            assert_eq!(v["status"], "ok");
            assert_eq!(v["shards"], 3);
            v["runs"]
                .as_array()
                .unwrap()
                .iter()
                .map(|r| r["name"].as_str().unwrap().to_string())
                .collect::<Vec<_>>()
        })
        .collect();
    names.sort();
    assert_eq!(names.len(), 6);
    names.dedup();
    assert_eq!(names.len(), 6);

    let merge = eyeshell_in(d, &["sweep", "merge", "out"]);
    assert_eq!(merge.code, Some(0), "{}{}", merge.stdout, merge.stderr);
    assert!(
        merge.stdout.contains("6 of 6 runs ok, 0 failed, 0 missing"),
        "{}",
        merge.stdout
    );
    assert_eq!(
        table_without_timings(&out),
        table_without_timings(&d.join("plain"))
    );
    assert_eq!(
        summary_without_timings(&out),
        summary_without_timings(&d.join("plain"))
    );
    // A merged sweep is an ordinary sweep: --resume reuses every run, a plain sweep replaces it.
    let resumed = eyeshell_in(d, &["sweep", "s.toml", "--out", "out", "--resume"]);
    assert_eq!(resumed.code, Some(0), "{}", resumed.stderr);
    assert!(resumed.stdout.contains("(6 reused"), "{}", resumed.stdout);
}

#[test]
fn merge_names_failed_and_missing_runs_and_matches_a_plain_sweep_with_failures() {
    // η0 = 1e4 with two Euler steps turns the shell inside out at the first step.
    let dir = scene_dir(&format!("{SMALL}[[sweep.runs]]\nname = \"good\"\n[[sweep.runs]]\nname = \"bad\"\n\"growth.eta0\" = 1e4\n\"solver.integrator\" = \"euler\"\n\"solver.steps\" = 2\n[[sweep.runs]]\nname = \"other\"\n\"growth.Gamma\" = 6\n"));
    let d = dir.path();
    let plain = eyeshell_in(d, &["sweep", "s.toml", "--out", "plain", "-q"]);
    assert_eq!(plain.code, Some(1), "{}", plain.stderr);
    // Which shard holds "bad"? Run every shard but the one with "other".
    let mut ran = Vec::new();
    for k in 1..=3 {
        let r = quiet_shard(d, k, 3);
        let record = std::fs::read_to_string(d.join(format!("out/shards/{k}.json"))).unwrap();
        if record.contains("\"name\": \"bad\"") {
            assert_fails(
                &r,
                1,
                &format!("1 of 1 runs shard {k}/3 failed: bad: growth failed"),
            );
        } else {
            assert_eq!(r.code, Some(0), "{}", r.stderr);
        }
        ran.push((k, record.contains("\"name\": \"other\"")));
    }
    // Remove "other"'s result: it is missing now, as if its shard had never run.
    std::fs::remove_file(d.join("out/runs/other/result.json")).unwrap();
    let merge = eyeshell_in(d, &["sweep", "merge", "out"]);
    assert_fails(
        &merge,
        1,
        "2 of 3 runs of the sweep in out are not done (1 failed, 1 missing)",
    );
    assert!(
        merge
            .stdout
            .contains("  failed          bad: growth failed at t = 0.02"),
        "{}",
        merge.stdout
    );
    assert!(
        merge.stdout.contains("  missing         other\n"),
        "{}",
        merge.stdout
    );
    let k_other = ran.iter().find(|(_, other)| *other).unwrap().0;
    assert!(
        merge
            .stdout
            .contains("  run the rest:   eyeshell sweep s.toml --out out --resume\n"),
        "{}",
        merge.stdout
    );
    assert!(merge.stdout.contains("for K = "), "{}", merge.stdout);
    let (_, rows) = csv_cells(&d.join("out/sweep.csv"));
    let status: Vec<(&str, &str)> = rows
        .iter()
        .map(|r| (r[0].as_str(), r[1].as_str()))
        .collect();
    assert_eq!(
        status,
        [("good", "ok"), ("bad", "failed"), ("other", "not run")]
    );
    // The missing run's shard again, with --resume: then the table is the plain sweep's.
    let again = eyeshell_in(
        d,
        &[
            "sweep",
            "s.toml",
            "--out",
            "out",
            "-q",
            "--resume",
            "--shard",
            &format!("{k_other}/3"),
        ],
    );
    assert!(
        again.code == Some(0) || again.code == Some(1),
        "{}",
        again.stderr
    );
    let merge = eyeshell_in(d, &["sweep", "merge", "out"]);
    assert_fails(
        &merge,
        1,
        "1 of 3 runs of the sweep in out are not done (1 failed, 0 missing)",
    );
    assert_eq!(
        table_without_timings(&d.join("out")),
        table_without_timings(&d.join("plain"))
    );
    assert_eq!(
        summary_without_timings(&d.join("out")),
        summary_without_timings(&d.join("plain"))
    );
}

/// Runs of about a second each (the published Euler's fixed work on 201 nodes), so that a
/// kill sent after the first run's line lands while the second runs.
fn slow_scene() -> String {
    let text = SMALL
        .replace("nodes = 21", "nodes = 201")
        .replace("t_end = 0.2", "t_end = 1.0")
        .replace("times = [0.1]", "times = [0.5]")
        .replace(
            "rtol = 1e-3",
            "rtol = 1e-6\nintegrator = \"euler\"\nsteps = 4000",
        );
    format!("{text}[sweep.grid]\n\"growth.Gamma\" = [4, 5, 6, 7]\n")
}

/// Shard 1/2 of [`slow_scene`] (two runs, one at a time) started in `d`, in a process
/// group of its own, once its first run has ended; with that run's name.
fn shard_one_of_two_after_its_first_run(
    d: &Path,
) -> (
    std::process::Child,
    std::io::BufReader<std::process::ChildStderr>,
    String,
) {
    let (child, stderr, first) = spawn_in_own_group(
        d,
        &[
            "sweep", "s.toml", "--out", "out", "--jobs", "1", "--shard", "1/2",
        ],
        "eyeshell: [1/2] ",
    );
    let done = first["eyeshell: [1/2] ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .to_string();
    (child, stderr, done)
}

/// SIGKILL to `child`'s process group (as a cluster ends a job out of time), then reap it.
fn kill_group(child: &mut std::process::Child) {
    let killed = Command::new("kill")
        .args(["-KILL", "--", &format!("-{}", child.id())])
        .status()
        .unwrap();
    assert!(killed.success());
    let _ = child.wait();
}

#[test]
fn a_shard_killed_mid_way_resumes_and_keeps_its_finished_runs() {
    let dir = scene_dir(&slow_scene());
    let d = dir.path();
    // Shard 1/2 (two runs), one at a time, in a process group of its own: SIGKILL to the
    // group once its first run has ended, as a cluster ends a job out of time.
    let (mut child, _stderr, done) = shard_one_of_two_after_its_first_run(d);
    kill_group(&mut child);
    // The record still says the shard was running, with one run done.
    let record = std::fs::read_to_string(d.join("out/shards/1.json")).unwrap();
    assert!(record.contains("\"status\": \"running\""), "{record}");
    let status = eyeshell_in(d, &["sweep", "status", "out"]);
    assert_fails(
        &status,
        1,
        "3 of 4 runs of the sweep in out are not done (0 failed, 3 missing)",
    );
    // ... but no process holds its lock: status says it was interrupted, not running.
    assert!(
        status.stdout.contains("1/2 interrupted"),
        "{}",
        status.stdout
    );
    assert!(!status.stdout.contains("running"), "{}", status.stdout);
    assert!(status.stdout.contains("for K = 1, 2"), "{}", status.stdout);

    // --resume: the finished run is reused, the other runs.
    let again = eyeshell_in(
        d,
        &[
            "sweep", "s.toml", "--out", "out", "--jobs", "1", "--shard", "1/2", "--resume",
        ],
    );
    assert_eq!(again.code, Some(0), "{}", again.stderr);
    assert!(
        again.stderr.contains(&format!("{done} reused: ")),
        "{}",
        again.stderr
    );
    assert!(
        again.stdout.contains("2 runs ok (1 reused"),
        "{}",
        again.stdout
    );
    let other = eyeshell_in(
        d,
        &[
            "sweep", "s.toml", "--out", "out", "--jobs", "1", "--shard", "2/2", "-q",
        ],
    );
    assert_eq!(other.code, Some(0), "{}", other.stderr);
    let merge = eyeshell_in(d, &["sweep", "merge", "out", "-q"]);
    assert_eq!(merge.code, Some(0), "{}{}", merge.stdout, merge.stderr);
    assert!(merge.stdout.is_empty(), "{}", merge.stdout);
    let (_, rows) = csv_cells(&d.join("out/sweep.csv"));
    assert!(rows.iter().all(|r| r[1] == "ok"), "{rows:?}");
}

#[test]
fn bad_shards_are_refused_with_one_line_and_nothing_written() {
    let dir = scene_dir(&format!("{SMALL}{GRID}"));
    let d = dir.path();
    let cases: [(&[&str], &str); 9] = [
        (
            &["--shard", "0/3"],
            "--shard 0/3: K must be 1 to N = 3, not 0",
        ),
        (
            &["--shard", "4/3"],
            "--shard 4/3: K must be 1 to N = 3, not 4",
        ),
        (&["--shard", "1/0"], "--shard 1/0: N must be 1 to"),
        (&["--shard", "2"], "--shard 2: give K/N with 1 <= K <= N"),
        (&["--shard", "a/b"], "--shard a/b: give K/N"),
        (&["--shard", "1/99999999"], "N must be 1 to 1000000"),
        (
            &["--shard", "slurm"],
            "--shard slurm: SLURM_ARRAY_TASK_ID is not set",
        ),
        (&["--shard", "1/2", "--jobs", "0"], "--jobs 0"),
        (
            &["--slurm-script", "--shards", "7"],
            "--shards 7: give 1 to 6 (the sweep has 6 runs)",
        ),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["sweep", "s.toml", "--out", "out"];
        args.extend_from_slice(extra);
        let r = Command::new(env!("CARGO_BIN_EXE_eyeshell"))
            .args(&args)
            .current_dir(d)
            .env_remove("SLURM_ARRAY_TASK_ID")
            .output()
            .unwrap();
        assert_bad(&Run::from(r), needle, &format!("{extra:?}"));
        assert!(!d.join("out").exists(), "{extra:?} wrote out/");
    }
    // Stepped arrays have no K/N: refused with the range to use.
    let stepped = eyeshell_with(
        d,
        &["sweep", "s.toml", "--out", "out", "--shard", "slurm"],
        &[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_MAX", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ],
    );
    assert_bad(
        &stepped,
        "must be a plain range (--array=1-5)",
        "stepped array",
    );
    // Usage errors (clap): exit 2 as well.
    for args in [
        &["sweep", "s.toml", "--out", "out", "--shards", "2"][..],
        &[
            "sweep",
            "s.toml",
            "--out",
            "out",
            "--shard",
            "1/2",
            "--slurm-script",
        ][..],
    ] {
        let r = eyeshell_in(d, args);
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
        assert!(!d.join("out").exists());
    }
    // merge of a directory no shard wrote.
    assert_bad(
        &eyeshell_in(d, &["sweep", "merge", "nowhere"]),
        "nowhere: no shard has run here",
        "merge of nothing",
    );
    // A shard never removes another output: a solve's directory is refused.
    std::fs::create_dir(d.join("mine")).unwrap();
    std::fs::write(d.join("mine/notes.txt"), "mine").unwrap();
    let r = eyeshell_in(d, &["sweep", "s.toml", "--out", "mine", "--shard", "1/2"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert_eq!(
        std::fs::read_to_string(d.join("mine/notes.txt")).unwrap(),
        "mine"
    );
    // Nor does merge or status touch it: one line, exit 2.
    for cmd in ["merge", "status"] {
        let r = eyeshell_in(d, &["sweep", cmd, "mine"]);
        assert_eq!(r.code, Some(2), "{cmd}: {}", r.stderr);
        assert_eq!(r.stderr.lines().count(), 1, "{cmd}: {}", r.stderr);
    }
    assert_eq!(std::fs::read_dir(d.join("mine")).unwrap().count(), 1);
}

/// The same shard twice at once: the second is refused while the first holds its record's
/// lock (held here by the test, as a running shard holds it), and runs once it is free.
#[test]
fn the_same_shard_twice_at_once_is_refused() {
    let dir = scene_dir(&format!("{SMALL}[sweep.grid]\n\"growth.Gamma\" = [4, 8]\n"));
    let d = dir.path();
    let first = quiet_shard(d, 1, 2);
    assert_eq!(first.code, Some(0), "{}", first.stderr);
    let lock = std::fs::File::create(d.join("out/shards/.1.json.lock")).unwrap();
    lock.try_lock().unwrap();
    let second = quiet_shard(d, 1, 2);
    assert_eq!(second.code, Some(2), "{}", second.stderr);
    assert!(
        second.stderr.contains("another eyeshell process"),
        "{}",
        second.stderr
    );
    lock.unlock().unwrap();
    drop(lock);
    let third = quiet_shard(d, 1, 2);
    assert_eq!(third.code, Some(0), "{}", third.stderr);
}

#[test]
fn shards_started_together_into_a_fresh_directory_all_succeed() {
    let dir = scene_dir(&format!(
        "{SMALL}[sweep.grid]\n\"growth.Gamma\" = [4, 8, 12]\n"
    ));
    let d = dir.path();
    for attempt in 0..3 {
        let _ = std::fs::remove_dir_all(d.join("out"));
        let children: Vec<_> = (1..=4).map(|k| spawn_shard(d, &format!("{k}/4"))).collect();
        for child in children {
            let r = Run::from(child.wait_with_output().unwrap());
            assert_eq!(r.code, Some(0), "attempt {attempt}: {}", r.stderr);
        }
        let merge = eyeshell_in(d, &["sweep", "merge", "out", "-q"]);
        assert_eq!(merge.code, Some(0), "attempt {attempt}: {}", merge.stderr);
    }
}

/// Many shards starting at once, many times: one may look at `out` while another writes
/// the marker (its temporary file there, the marker not yet renamed into place). That was
/// refused as "not an eyeshell output directory" (seen once in CI); it is retried now.
#[test]
fn shards_racing_for_a_fresh_directory_never_refuse_it() {
    let dir = scene_dir(&format!("{SMALL}[sweep.grid]\n\"growth.Gamma\" = [4, 8]\n"));
    let d = dir.path();
    for attempt in 0..25 {
        let _ = std::fs::remove_dir_all(d.join("out"));
        let children: Vec<_> = (1..=8).map(|k| spawn_shard(d, &format!("{k}/8"))).collect();
        for child in children {
            let r = Run::from(child.wait_with_output().unwrap());
            assert_eq!(r.code, Some(0), "attempt {attempt}: {}", r.stderr);
        }
    }
}

#[test]
fn more_shards_than_runs_leave_the_extra_shards_empty() {
    let dir = scene_dir(&format!("{SMALL}[sweep.grid]\n\"growth.Gamma\" = [4, 8]\n"));
    let d = dir.path();
    for k in 1..=4 {
        let r = quiet_shard(d, k, 4);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
    }
    let record = std::fs::read_to_string(d.join("out/shards/4.json")).unwrap();
    assert!(record.contains("\"runs_total\": 0"), "{record}");
    let merge = eyeshell_in(d, &["sweep", "merge", "out", "-q"]);
    assert_eq!(merge.code, Some(0), "{}", merge.stderr);
}

/// A plain sweep into a directory where a shard is running is refused (it would replace
/// the shard's runs, or run them twice at once), resuming or not; once the shard is gone
/// (killed: the kernel drops its lock), a plain --resume finishes the sweep.
#[test]
fn a_plain_sweep_is_refused_while_a_shard_runs_in_its_directory() {
    let dir = scene_dir(&slow_scene());
    let d = dir.path();
    let (mut child, _stderr, done) = shard_one_of_two_after_its_first_run(d);
    for extra in [&[][..], &["--resume"][..]] {
        let mut args = vec!["sweep", "s.toml", "--out", "out", "-q"];
        args.extend_from_slice(extra);
        let plain = eyeshell_in(d, &args);
        assert_bad(&plain, "shard 1 is running here", &format!("{extra:?}"));
        assert!(
            plain.stderr.contains(&format!("(pid {})", child.id())),
            "{}",
            plain.stderr
        );
    }
    kill_group(&mut child);
    // The shard's finished run and its record are still there (a fresh plain sweep would
    // have replaced the directory), and neither table was written.
    assert!(d.join("out/runs").join(&done).join("result.json").is_file());
    assert!(d.join("out/shards/1.json").is_file());
    assert!(!d.join("out/sweep.csv").exists());
    let resumed = eyeshell_in(d, &["sweep", "s.toml", "--out", "out", "--resume", "-q"]);
    assert_eq!(resumed.code, Some(0), "{}", resumed.stderr);
}

/// The environment variable that holds the canary path a hostile name tries to create.
pub(crate) const CANARY: &str = "EYESHELL_CANARY";

/// A file or directory name that runs commands if it reaches a shell unquoted, or ends a
/// comment line of a script early: line breaks (the second starting an `#SBATCH` line that
/// sbatch must not see), quotes of both kinds, `$(...)`, backticks, `;`, `#` and a
/// backslash. Each command it holds creates `$EYESHELL_CANARY-<how>`: a canary file that
/// must never appear.
pub(crate) fn hostile_name() -> String {
    format!("{} \\", hostile_slurm_name())
}

/// [`hostile_name`] without its backslash: Slurm takes a backslash in a job's working
/// directory as an escape of its `--output` pattern, and cannot open the file, so
/// `--slurm-script` refuses such a directory.
pub(crate) fn hostile_slurm_name() -> String {
    let c = format!("\"${CANARY}\"");
    format!(
        "it's \"a\" $(touch {c}-dollar)`touch {c}-tick`;touch {c}-semi #\n#SBATCH --array=1-99\ntouch {c}-line\r\n'$(touch {c}-quoted)'\t$HOME"
    )
}

/// The canary files that appeared under `root` (none may).
pub(crate) fn canaries(root: &Path) -> Vec<String> {
    let mut found = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with("canary") {
                found.push(e.path().display().to_string());
            }
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                stack.push(e.path());
            }
        }
    }
    found
}

/// The options sbatch takes from `script`, read as sbatch reads them: the `#SBATCH` lines
/// after the first line and before the first command (a line that is neither blank nor a
/// comment).
pub(crate) fn sbatch_options(script: &str) -> Vec<String> {
    let mut options = Vec::new();
    for line in script.lines().skip(1) {
        let line = line.trim_start();
        if let Some(option) = line.strip_prefix("#SBATCH") {
            options.push(option.trim().to_string());
        } else if !(line.is_empty() || line.starts_with('#')) {
            break;
        }
    }
    options
}

/// A copy of the eyeshell binary at `dir/name/eyeshell` (a hard link where it can be), so
/// that the script names the binary by a path that is hostile too.
pub(crate) fn eyeshell_at(dir: &Path, name: &str) -> std::path::PathBuf {
    let bin = dir.join(name);
    std::fs::create_dir_all(&bin).unwrap();
    let exe = bin.join("eyeshell");
    let real = env!("CARGO_BIN_EXE_eyeshell");
    if std::fs::hard_link(real, &exe).is_err() {
        std::fs::copy(real, &exe).unwrap();
    }
    exe
}
