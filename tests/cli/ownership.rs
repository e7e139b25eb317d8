//! Hostile inputs, families 2–4 (TESTING.md): somebody else's folders and files, overwrites,
//! concurrency, kills mid-write and litter. Every case runs the binary under a memory limit
//! and a time limit ([`bounded`]) and asserts the exit code, one clean line of stderr, and
//! that no file outside the output changed ([`World`]).

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::support::*;

const SMALL: &str = "[solver]\nnodes = 21\n";
const SMALL_GROW: &str =
    "[solver]\nnodes = 21\nrtol = 1e-3\n[growth]\nt_end = 0.2\n[output]\ntimes = [0.1, 0.2]\n";
const SMALL_SWEEP: &str = "[solver]\nnodes = 21\n[sweep.grid]\n\"fibres.D\" = [0, 100]\n";

/// A scratch directory with the three small scenes and a solve and a grow to export.
fn scratch() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [
        ("s.toml", SMALL),
        ("g.toml", SMALL_GROW),
        ("w.toml", SMALL_SWEEP),
    ] {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    dir
}

/// The commands that write an output directory, as `--out DIR` argument lists.
fn writers() -> Vec<Vec<&'static str>> {
    vec![
        vec!["solve", "s.toml", "-q", "--out"],
        vec!["grow", "g.toml", "-q", "--out"],
        vec!["sweep", "w.toml", "-q", "--out"],
        vec!["converge", "s.toml", "--nodes", "11,21", "--out"],
        vec!["plot", "made", "-q", "--out"],
        vec!["export", "made-grow", "--mat"],
    ]
}

/// Family 2: a directory that merely looks like an output (summary.json, even a forged
/// marker) is nobody's to delete; an eyeshell output holding a user's file is not replaced.
#[test]
fn somebody_elses_folder_is_never_deleted() {
    let dir = scratch();
    let root = dir.path();
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", "made"]),
        "solve",
    );
    succeeded(
        &bounded(root, &["grow", "g.toml", "-q", "--out", "made-grow"]),
        "grow",
    );
    let plant = |name: &str, files: &[(&str, &str)]| {
        let d = root.join(name);
        std::fs::create_dir_all(&d).unwrap();
        for (f, text) in files {
            std::fs::write(d.join(f), text).unwrap();
        }
    };
    plant(
        "lookalike",
        &[("summary.json", "{}"), ("thesis.tex", "mine")],
    );
    plant(
        "forged",
        &[
            (".eyeshell", r#"{"written_by":"someone","kind":"solve"}"#),
            ("data.csv", "1,2"),
        ],
    );
    plant("bvp4c-results", &[("run1.mat", "MATLAB 5.0 MAT-file")]);
    let before = World::of(root);
    for target in ["lookalike", "forged", "bvp4c-results"] {
        for w in writers() {
            let mut args = w.clone();
            args.push(target);
            let r = bounded(root, &args);
            refused(&r, "not an eyeshell output directory", &format!("{args:?}"));
            assert_eq!(World::of(root), before, "{args:?} changed files");
        }
    }
    // An eyeshell output with a user's file in it: refused, naming the file.
    std::fs::write(root.join("made/notes.txt"), "my notes").unwrap();
    let before = World::of(root);
    let r = bounded(root, &["solve", "s.toml", "-q", "--out", "made"]);
    refused(
        &r,
        "\"notes.txt\", which eyeshell did not write",
        "user file",
    );
    assert_eq!(World::of(root), before);
    std::fs::remove_file(root.join("made/notes.txt")).unwrap();
    // Without it, the output is eyeshell's to replace, with its plots inside.
    succeeded(&bounded(root, &["plot", "made", "-q"]), "plot");
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", "made"]),
        "replace",
    );
    // Adding to an output of another kind is refused.
    let r = bounded(
        root,
        &["sweep", "w.toml", "-q", "--resume", "--out", "made-grow"],
    );
    refused(&r, "holds a grow output, not a sweep", "resume into a grow");
}

/// Family 3: files are replaced only if eyeshell wrote them, or with --force; never the
/// run's own files.
#[test]
fn files_are_not_overwritten_without_force() {
    let dir = scratch();
    let root = dir.path();
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", "run"]),
        "solve",
    );
    std::fs::write(root.join("theirs.mat"), "a user's file").unwrap();
    std::fs::write(root.join("theirs.npz"), "a user's file").unwrap();
    std::fs::write(root.join("TESTING.md"), "# my notes\n").unwrap();
    let before = World::of(root);
    for (args, needle) in [
        (
            vec!["export", "run", "--mat", "theirs.mat"],
            "not written by eyeshell",
        ),
        (
            vec!["export", "run", "--npz", "theirs.npz"],
            "not written by eyeshell",
        ),
        // Both formats: the second target is refused before the first is written.
        (
            vec!["export", "run", "--mat", "new.mat", "--npz", "theirs.npz"],
            "theirs.npz",
        ),
        (
            vec!["export", "run", "--mat", "x", "--npz", "x"],
            "two different outputs",
        ),
        (
            vec!["export", "run", "--npz", "run/fields.csv", "--force"],
            "a file of the run being exported",
        ),
        (
            vec!["export", "run", "--mat", "run/summary.json", "--force"],
            "a file of the run being exported",
        ),
        (
            vec!["export", "run", "--mat", "run/.eyeshell", "--force"],
            "a file of the run being exported",
        ),
        (
            vec!["extremes", "--out", "TESTING.md"],
            "not written by eyeshell",
        ),
        (vec!["extremes", "--out", "run"], "not a regular file"),
    ] {
        let r = bounded(root, &args);
        refused(&r, needle, &format!("{args:?}"));
        assert_eq!(World::of(root), before, "{args:?} changed files");
    }
    // What eyeshell wrote it replaces; a user's file only with --force.
    succeeded(
        &bounded(root, &["export", "run", "--mat", "ours.mat", "-q"]),
        "mat",
    );
    succeeded(
        &bounded(root, &["export", "run", "--npz", "ours.npz", "-q"]),
        "npz",
    );
    succeeded(
        &bounded(root, &["export", "run", "--mat", "ours.mat", "-q"]),
        "again",
    );
    succeeded(
        &bounded(root, &["export", "run", "--npz", "ours.npz", "-q"]),
        "again",
    );
    succeeded(
        &bounded(
            root,
            &["export", "run", "--mat", "theirs.mat", "-q", "--force"],
        ),
        "forced",
    );
    assert!(std::fs::read(root.join("theirs.mat"))
        .unwrap()
        .starts_with(b"MATLAB 5.0 MAT-file, Platform: eyeshell"));
    // plot --out into a folder of the user's with a same-named picture: refused.
    std::fs::create_dir(root.join("pictures")).unwrap();
    std::fs::write(root.join("pictures/fields.png"), "my picture").unwrap();
    let before = World::of(root);
    let r = bounded(root, &["plot", "run", "--out", "pictures"]);
    refused(
        &r,
        "not an eyeshell output directory",
        "plot into a user folder",
    );
    assert_eq!(World::of(root), before);
}

/// Start `eyeshell ARGS` in `dir` without waiting.
fn start(dir: &Path, args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_eyeshell"))
        .args(args)
        .current_dir(dir)
        .env("CI", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start eyeshell")
}

/// Wait until `path` exists (a process has reached a point), at most 30 s.
fn wait_for(path: &Path) {
    let start = Instant::now();
    while !path.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "{}",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Wait until `dir` holds an entry whose name starts with `prefix` (a writer's temporary,
/// `.NAME.tmp-<pid>-<nonce>`).
fn wait_for_entry(dir: &Path, prefix: &str) {
    let start = Instant::now();
    let present = || {
        std::fs::read_dir(dir)
            .unwrap()
            .any(|e| e.unwrap().file_name().to_string_lossy().starts_with(prefix))
    };
    while !present() {
        assert!(start.elapsed() < Duration::from_secs(30), "{prefix}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The hidden entries of a directory (litter, locks), sorted.
fn hidden(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    v.sort();
    v
}

/// A growth run long enough (seconds) to be caught in the middle.
const SLOW_GROW: [&str; 6] = [
    "--set",
    "solver.nodes=2001",
    "--set",
    "solver.rtol=1e-8",
    "-q",
    "--out",
];

/// Family 4: a second writer of one output is refused while the first runs, and says who
/// holds it; the first finishes unharmed.
#[test]
fn two_writers_of_one_output() {
    let dir = scratch();
    let root = dir.path();
    let scene = repo().join("scenes/const.toml");
    let mut args = vec!["grow", s(&scene)];
    args.extend(SLOW_GROW);
    args.push("out");
    let first = start(root, &args);
    wait_for(&root.join(".out.lock"));
    let r = bounded(root, &args);
    refused(&r, "another eyeshell process", "a second grow");
    assert!(
        r.stderr.contains(&format!("(pid {})", first.id())),
        "{}",
        r.stderr
    );
    // Writers of another kind are refused for what is there (a growth run, already
    // marked as one), which waiting would not change.
    for (second, kind) in [
        (vec!["solve", "s.toml", "-q", "--out", "out"], "solve"),
        (vec!["sweep", "w.toml", "-q", "--out", "out"], "sweep"),
    ] {
        let r = bounded(root, &second);
        refused(
            &r,
            &format!("out: holds a grow output; refusing to replace it with a {kind} output"),
            &format!("{second:?}"),
        );
    }
    let done = first.wait_with_output().unwrap();
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    assert!(hidden(root).is_empty(), "litter: {:?}", hidden(root));
    let summary = std::fs::read_to_string(root.join("out/summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"ok\""), "{summary}");
    // Many solves at once into one output: each succeeds or is refused cleanly, and what
    // is left is one whole output and no litter.
    let racers: Vec<Child> = (0..6)
        .map(|_| start(root, &["solve", "s.toml", "-q", "--out", "raced"]))
        .collect();
    for c in racers {
        let out = c.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        match out.status.code() {
            Some(0) => assert!(err.is_empty(), "{err}"),
            Some(2) => assert!(err.contains("another eyeshell process"), "{err}"),
            other => panic!("{other:?}: {err}"),
        }
    }
    assert!(hidden(root).is_empty(), "litter: {:?}", hidden(root));
    let (_, rows) = csv(&root.join("raced/fields.csv"));
    assert!(rows.len() >= 21, "{} rows", rows.len());
    assert!(root.join("raced/summary.json").is_file());
}

/// Family 4: a run killed mid-write leaves litter that the next run into the same output
/// removes; a killed commit's previous output is put back; nothing half-written remains.
#[test]
fn kills_mid_write_leave_nothing_the_next_run_cannot_clean() {
    let dir = scratch();
    let root = dir.path();
    // A solve killed during its computation: its temporary directory (created first) stays.
    let big = [
        "solve",
        "s.toml",
        "--set",
        "solver.nodes=200001",
        "-q",
        "--out",
        "out",
    ];
    let mut victim = start(root, &big);
    let pid = victim.id();
    wait_for_entry(root, &format!(".out.tmp-{pid}-"));
    victim.kill().unwrap();
    victim.wait().unwrap();
    assert!(!root.join("out").exists(), "solve is all or nothing");
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", "out"]),
        "after kill",
    );
    assert!(hidden(root).is_empty(), "litter: {:?}", hidden(root));
    // A grow killed mid-run is an eyeshell output: the next run replaces it.
    let scene = repo().join("scenes/const.toml");
    let mut args = vec!["grow", s(&scene)];
    args.extend(SLOW_GROW);
    args.push("grown");
    let mut victim = start(root, &args);
    wait_for(&root.join("grown/series.csv"));
    std::thread::sleep(Duration::from_millis(300));
    victim.kill().unwrap();
    victim.wait().unwrap();
    let summary = std::fs::read_to_string(root.join("grown/summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"running\""), "{summary}");
    succeeded(
        &bounded(root, &["grow", "g.toml", "-q", "--out", "grown"]),
        "regrow",
    );
    assert!(hidden(root).is_empty(), "litter: {:?}", hidden(root));
    // A commit cut short between its two renames: the previous output was moved aside.
    std::fs::rename(root.join("out"), root.join(".out.old-999999999")).unwrap();
    std::fs::create_dir(root.join(".out.tmp-999999998")).unwrap();
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", "out"]),
        "after a cut commit",
    );
    assert!(root.join("out/fields.csv").is_file());
    assert!(hidden(root).is_empty(), "litter: {:?}", hidden(root));
    // A killed export's temporary file (dead pid) goes with the next export to that name.
    std::fs::write(root.join(".x.mat.tmp-999999999"), "half").unwrap();
    succeeded(
        &bounded(root, &["export", "out", "--mat", "x.mat", "-q"]),
        "export",
    );
    assert!(hidden(root).is_empty(), "litter: {:?}", hidden(root));
}

/// Family 4: legal but awkward output paths.
#[test]
fn awkward_output_paths() {
    let dir = scratch();
    let root = dir.path();
    // A 250-byte name (legal): its hidden temporary and lock names are short.
    let long = "n".repeat(250);
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", &long]),
        "long",
    );
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", &long]),
        "long, again",
    );
    let long_grow = "g".repeat(250);
    for what in ["long grow", "long grow, again"] {
        succeeded(
            &bounded(root, &["grow", "g.toml", "-q", "--out", &long_grow]),
            what,
        );
    }
    assert!(root.join(&long_grow).join("series.csv").is_file());
    // A solve never replaces a growth run, nor a grow a solve.
    refused(
        &bounded(root, &["grow", "g.toml", "-q", "--out", &long]),
        "holds a solve output; refusing to replace it with a grow output",
        "grow over a solve",
    );
    assert!(root.join(&long).join("fields.csv").is_file());
    // prev/. is prev.
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", "prev"]),
        "prev",
    );
    succeeded(
        &bounded(root, &["solve", "s.toml", "-q", "--out", "prev/."]),
        "prev/.",
    );
    assert!(root.join("prev/fields.csv").is_file());
    assert!(hidden(root).is_empty(), "litter: {:?}", hidden(root));
    // Paths that name no directory of their own.
    for bad in [".", "..", "prev/..", "/"] {
        let r = bounded(root, &["solve", "s.toml", "-q", "--out", bad]);
        assert_eq!(r.code, Some(2), "{bad}: {}", r.stderr);
        assert_eq!(r.stderr.lines().count(), 1, "{bad}: {}", r.stderr);
    }
    // A symlink as the output is not followed.
    std::fs::create_dir(root.join("elsewhere")).unwrap();
    std::fs::write(root.join("elsewhere/keep"), "k").unwrap();
    std::os::unix::fs::symlink(root.join("elsewhere"), root.join("link")).unwrap();
    let before = World::of(root);
    for w in writers() {
        let mut args = w.clone();
        args.push("link");
        if args[0] == "plot" {
            args[1] = "prev";
        }
        if args[0] == "export" {
            continue; // exports a growth run; a solve exports to a file: checked below
        }
        let r = bounded(root, &args);
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
        assert_eq!(World::of(root), before, "{args:?}");
    }
    let r = bounded(root, &["export", "prev", "--mat", "link", "--force"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert_eq!(World::of(root), before);
}
