//! What a sweep says about itself after a fault: `sweep status` never calls a killed shard
//! "running", says "done" only where `sweep merge` succeeds (the same checks: links in
//! place of runs, of `runs/` or of `shards/`, missing markers, files the runs name but no
//! longer record), de-duplicated run names never take a name a run was given, `--resume`
//! reruns a run whose files were deleted with their record, and a failed run's message,
//! however many lines it has, is printed as one bounded line.

use std::path::Path;

use crate::shards::SMALL;
use crate::support::*;

/// Two runs, `a` and `b`, run as two shards into `dir/out` and merged.
fn sharded(dir: &Path) {
    std::fs::write(
        dir.join("s.toml"),
        format!("{SMALL}[[sweep.runs]]\nname = \"a\"\n\"growth.Gamma\" = 4\n[[sweep.runs]]\nname = \"b\"\n\"growth.Gamma\" = 8\n"),
    )
    .unwrap();
    for k in ["1/2", "2/2"] {
        let r = eyeshell_in(
            dir,
            &["sweep", "s.toml", "--out", "out", "--shard", k, "-q"],
        );
        succeeded(&r, k);
    }
    succeeded(&eyeshell_in(dir, &["sweep", "merge", "out", "-q"]), "merge");
}

/// Edit shard `k`'s record in `dir/out/shards` with `edit`.
fn edit_record(dir: &Path, k: usize, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join(format!("out/shards/{k}.json"));
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut v);
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

#[test]
fn a_shard_whose_process_is_gone_is_interrupted_not_running() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sharded(d);
    // What SIGKILL leaves: the record still says "running", and the kernel has released
    // the lock.
    edit_record(d, 1, |v| v["status"] = "running".into());
    let status = eyeshell_in(d, &["sweep", "status", "out"]);
    succeeded(&status, "status");
    assert!(
        status.stdout.contains("1/2 interrupted, 2/2 ok"),
        "{}",
        status.stdout
    );
    // A live holder of the shard's lock (as a shard that runs holds it): running.
    let lock = std::fs::File::create(d.join("out/shards/.1.json.lock")).unwrap();
    lock.lock().unwrap();
    let status = eyeshell_in(d, &["sweep", "status", "out"]);
    assert!(
        status.stdout.contains("1/2 running, 2/2 ok"),
        "{}",
        status.stdout
    );
    drop(lock);
    let status = eyeshell_in(d, &["sweep", "status", "out"]);
    assert!(
        status.stdout.contains("1/2 interrupted"),
        "{}",
        status.stdout
    );
}

/// status and merge on the same directory: the same verdict, the same line.
fn agree(d: &Path, what: &str) -> Run {
    let status = eyeshell_in(d, &["sweep", "status", "out"]);
    let merge = eyeshell_in(d, &["sweep", "merge", "out"]);
    assert_eq!(
        status.code, merge.code,
        "{what}: {}{}",
        status.stderr, merge.stderr
    );
    assert_eq!(status.stderr, merge.stderr, "{what}");
    assert_ne!(
        status.code,
        Some(0),
        "{what}: status says done: {}",
        status.stdout
    );
    status
}

#[test]
fn status_says_done_only_where_merge_succeeds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sharded(d);
    let elsewhere = d.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();

    // A run folder replaced by a symlink to its copy.
    std::fs::rename(d.join("out/runs/a"), elsewhere.join("a")).unwrap();
    std::os::unix::fs::symlink(elsewhere.join("a"), d.join("out/runs/a")).unwrap();
    let r = agree(d, "a run replaced by a link");
    refused(&r, "out/runs/a: is a symbolic link", "run link");
    std::fs::remove_file(d.join("out/runs/a")).unwrap();
    std::fs::rename(elsewhere.join("a"), d.join("out/runs/a")).unwrap();
    succeeded(&eyeshell_in(d, &["sweep", "status", "out"]), "restored");

    // runs/ replaced by a symlink.
    std::fs::rename(d.join("out/runs"), elsewhere.join("runs")).unwrap();
    std::os::unix::fs::symlink(elsewhere.join("runs"), d.join("out/runs")).unwrap();
    let r = agree(d, "runs replaced by a link");
    refused(&r, "is a symbolic link", "runs link");
    std::fs::remove_file(d.join("out/runs")).unwrap();
    std::fs::rename(elsewhere.join("runs"), d.join("out/runs")).unwrap();

    // The sweep's marker missing: not an eyeshell output any more.
    std::fs::rename(d.join("out/.eyeshell"), elsewhere.join("marker")).unwrap();
    let r = agree(d, "no marker");
    refused(&r, "not an eyeshell output directory", "no marker");
    std::fs::rename(elsewhere.join("marker"), d.join("out/.eyeshell")).unwrap();

    // A run's marker missing: that run is not done.
    std::fs::rename(d.join("out/runs/b/.eyeshell"), elsewhere.join("marker")).unwrap();
    let r = agree(d, "no run marker");
    assert_fails(&r, 1, "1 of 2 runs of the sweep in out are not done");
    assert!(
        r.stdout
            .contains("b (its results cannot be trusted: its .eyeshell marker is missing)"),
        "{}",
        r.stdout
    );
    std::fs::rename(elsewhere.join("marker"), d.join("out/runs/b/.eyeshell")).unwrap();
    succeeded(
        &eyeshell_in(d, &["sweep", "merge", "out", "-q"]),
        "restored",
    );

    // shards/ a link into another sweep: neither reads it.
    let other = tempfile::tempdir().unwrap();
    sharded(other.path());
    std::fs::rename(d.join("out/shards"), elsewhere.join("shards")).unwrap();
    std::os::unix::fs::symlink(other.path().join("out/shards"), d.join("out/shards")).unwrap();
    let r = agree(d, "shards link");
    refused(&r, "out/shards: is a symbolic link", "shards link");
}

#[test]
fn a_run_whose_file_was_deleted_with_its_record_is_not_reused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sharded(d);
    // history.csv deleted, and dropped from result.json's list of files; summary.json
    // still names it.
    let run = d.join("out/runs/a");
    std::fs::remove_file(run.join("history.csv")).unwrap();
    let path = run.join("result.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let files = v["files"].as_array_mut().unwrap();
    let before = files.len();
    files.retain(|f| f["path"] != "history.csv");
    assert_eq!(files.len(), before - 1);
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let why = "a (its results cannot be trusted: history.csv is named by the run but not recorded in its result.json)";
    let r = agree(d, "history.csv gone");
    assert!(r.stdout.contains(why), "{}", r.stdout);
    // --resume runs it again, and says why; the file is back.
    let again = eyeshell_in(d, &["sweep", "s.toml", "--out", "out", "--resume"]);
    succeeded(&again, "resume");
    assert!(
        again
            .stderr
            .contains("ran again: history.csv is named by the run but not recorded"),
        "{}",
        again.stderr
    );
    assert!(run.join("history.csv").is_file());
    assert!(again.stderr.contains("b reused"), "{}", again.stderr);
}

#[test]
fn deduplicated_names_never_take_a_name_the_user_gave() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("s.toml"),
        format!("{SMALL}[[sweep.runs]]\nname = \"a\"\n\"growth.Gamma\" = 4\n[[sweep.runs]]\nname = \"a\"\n\"growth.Gamma\" = 6\n[[sweep.runs]]\nname = \"a-2\"\n\"growth.Gamma\" = 8\n"),
    )
    .unwrap();
    succeeded(
        &eyeshell_in(d, &["sweep", "s.toml", "--out", "out", "-q"]),
        "sweep",
    );
    let gamma = |run: &str| {
        let text =
            std::fs::read_to_string(d.join("out/runs").join(run).join("scene.toml")).unwrap();
        let v: toml::Value = toml::from_str(&text).unwrap();
        v["growth"]["Gamma"].as_float().unwrap()
    };
    assert_eq!(gamma("a"), 4.0);
    assert_eq!(gamma("a-2"), 8.0, "the user's a-2 is the third run");
    assert_eq!(gamma("a-3"), 6.0, "the second a");
    let (_, rows) = csv_cells(&d.join("out/sweep.csv"));
    let names: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(names, ["a", "a-3", "a-2"]);
    // The same names again on resume: every run reused.
    let again = eyeshell_in(d, &["sweep", "s.toml", "--out", "out", "--resume"]);
    succeeded(&again, "resume");
    assert!(
        again.stdout.contains("3 runs ok (3 reused"),
        "{}",
        again.stdout
    );
}

#[test]
fn a_failed_runs_message_of_a_thousand_lines_is_one_bounded_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sharded(d);
    let message = format!("growth failed{}\u{1b}[31m", "\nline".repeat(1000));
    std::fs::remove_dir_all(d.join("out/runs/a")).unwrap();
    edit_record(d, 1, |v| {
        for run in v["runs"].as_array_mut().unwrap() {
            if run["name"] == "a" {
                run["status"] = "failed".into();
                run["error"] = message.clone().into();
            }
        }
    });
    for cmd in ["status", "merge"] {
        let r = eyeshell_in(d, &["sweep", cmd, "out"]);
        assert_fails(
            &r,
            1,
            "1 of 2 runs of the sweep in out are not done (1 failed",
        );
        let failed: Vec<&str> = r
            .stdout
            .lines()
            .filter(|l| l.trim_start().starts_with("failed"))
            .collect();
        assert_eq!(failed.len(), 1, "{cmd}: {}", r.stdout);
        assert!(
            failed[0].contains("a: growth failed\\nline"),
            "{}",
            failed[0]
        );
        assert!(
            failed[0].chars().count() < 800,
            "{cmd}: {}",
            failed[0].len()
        );
        assert!(!r.stdout.contains('\u{1b}'), "{cmd}");
        assert!(r.stdout.lines().count() < 12, "{cmd}: {}", r.stdout);
    }
}
