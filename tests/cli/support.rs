//! Shared by the integration tests that run the binary: run it, assert clean failures, make
//! small runs, read CSV files back.

#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

impl From<std::process::Output> for Run {
    fn from(out: std::process::Output) -> Run {
        Run {
            code: out.status.code(),
            stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        }
    }
}

/// Whether `python3` can import SciPy and NumPy, for the tests that check eyeshell against
/// them (`what` names the test in the note). Without them a test skips with a note on
/// stderr, unless `EYESHELL_REQUIRE_SCIPY=1` (set by `.ci/run`, which installs them): then a
/// skip would hide a check CI promises, so it is a failure.
pub fn scipy_available(what: &str) -> bool {
    let found = Command::new("python3")
        .args(["-c", "import scipy.io, scipy.integrate, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        if std::env::var_os("EYESHELL_REQUIRE_SCIPY").is_some_and(|v| v == "1") {
            panic!("{what} needs python3 with scipy and numpy, and EYESHELL_REQUIRE_SCIPY=1");
        }
        eprintln!(
            "SKIPPED: {what}: python3 with scipy and numpy not found (.ci/run installs them)"
        );
    }
    found
}

/// The repository root (where `scenes/` lives).
pub fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Run `eyeshell ARGS` in `dir`.
pub fn eyeshell_in(dir: &Path, args: &[&str]) -> Run {
    eyeshell_with(dir, args, &[])
}

/// Run `eyeshell ARGS` in `dir` with the environment variables `envs` set.
pub fn eyeshell_with(dir: &Path, args: &[&str], envs: &[(&str, &str)]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_eyeshell"))
        .args(args)
        .current_dir(dir)
        .env("CI", "1")
        .envs(envs.iter().copied())
        .output()
        .expect("run eyeshell");
    Run::from(out)
}

/// Run `eyeshell ARGS` in the repository (so `scenes/` resolves).
pub fn eyeshell(args: &[&str]) -> Run {
    eyeshell_in(repo(), args)
}

pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Run `eyeshell ARGS` and insist that it succeeds.
pub fn ok(args: &[&str]) -> Run {
    let r = eyeshell(args);
    assert_eq!(
        r.code,
        Some(0),
        "eyeshell {args:?}: {}{}",
        r.stdout,
        r.stderr
    );
    r
}

/// Assert a clean failure: `code`, one stderr line `eyeshell: error: ...` containing `needle`.
pub fn assert_fails(r: &Run, code: i32, needle: &str) {
    assert_eq!(
        r.code,
        Some(code),
        "stdout: {} stderr: {}",
        r.stdout,
        r.stderr
    );
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {:?}", r.stderr);
    assert!(lines[0].starts_with("eyeshell: error: "), "{}", lines[0]);
    assert!(lines[0].contains(needle), "{needle:?} not in {}", lines[0]);
}

/// Assert a clean bad-input failure (`what` says which): exit 2, one newline-terminated stderr
/// line `eyeshell: error: ...` naming `needle`, no panic, no stdout.
pub fn assert_bad(run: &Run, needle: &str, what: &str) {
    assert_eq!(
        run.code,
        Some(2),
        "{what}: exit code, stderr: {}",
        run.stderr
    );
    assert!(
        !run.stderr.contains("panicked"),
        "{what}: panic: {}",
        run.stderr
    );
    let lines: Vec<&str> = run.stderr.lines().collect();
    assert_eq!(
        lines.len(),
        1,
        "{what}: stderr must be one line: {:?}",
        run.stderr
    );
    assert!(run.stderr.ends_with('\n'), "{what}: {:?}", run.stderr);
    assert!(
        lines[0].starts_with("eyeshell: error: "),
        "{what}: {}",
        lines[0]
    );
    assert!(
        lines[0].contains(needle),
        "{what}: {needle:?} not named in: {}",
        lines[0]
    );
    assert!(run.stdout.is_empty(), "{what}: stdout: {}", run.stdout);
}

/// Assert that `dir` holds exactly one entry, `name`.
pub fn assert_only_entry(dir: &Path, name: &str, what: &str) {
    let names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        names,
        vec![std::ffi::OsString::from(name)],
        "{what}: leftovers"
    );
}

/// `eyeshell CMD scene.toml --set ... --out out`, with `scene` written to a fresh directory,
/// must fail cleanly naming `needle` (and `origin` first), and leave the directory as it was.
pub fn fails(cmd: &str, scene: &str, sets: &[&str], needle: &str, origin: &str) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    let mut args = vec![cmd, "scene.toml", "--out", "out"];
    for s in sets {
        args.push("--set");
        args.push(s);
    }
    let what = format!("{cmd} {scene:?} --set {sets:?}");
    let run = eyeshell_in(dir.path(), &args);
    assert_bad(&run, needle, &what);
    assert!(
        run.stderr
            .starts_with(&format!("eyeshell: error: {origin}")),
        "{what}: {}",
        run.stderr
    );
    assert!(!dir.path().join("out").exists(), "{what}: out/ was created");
    assert_only_entry(dir.path(), "scene.toml", &what);
}

/// In a fresh directory holding `s.toml` (with `scene`) and a foreign `data/precious.txt`,
/// `eyeshell CMD s.toml --out data` must be refused and leave `data/` as it was. Returns the
/// directory for further runs.
pub fn foreign_dir_is_refused(cmd: &str, scene: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), scene).unwrap();
    std::fs::create_dir(dir.path().join("data")).unwrap();
    std::fs::write(dir.path().join("data/precious.txt"), "keep").unwrap();
    let run = eyeshell_in(dir.path(), &[cmd, "s.toml", "--out", "data"]);
    assert_bad(
        &run,
        "data: exists and is not an eyeshell output directory",
        "foreign dir",
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("data/precious.txt")).unwrap(),
        "keep"
    );
    assert_eq!(
        std::fs::read_dir(dir.path().join("data")).unwrap().count(),
        1
    );
    dir
}

/// The small runs of the brief: an elastic solve (N = 21) and the const growth scene (N = 21,
/// rtol 1e-3), in `dir/solve` and `dir/grow`.
pub fn small_runs(dir: &Path) -> (PathBuf, PathBuf) {
    let solve = dir.join("solve");
    let grow = dir.join("grow");
    ok(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "solver.nodes=21",
        "--out",
        s(&solve),
        "--quiet",
    ]);
    ok(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=21",
        "--set",
        "solver.rtol=1e-3",
        "--out",
        s(&grow),
        "--quiet",
    ]);
    (solve, grow)
}

/// A CSV file as text: header cells and rows of cells.
pub fn csv_cells(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

/// A CSV file: header and rows of f64 (every value parsed exactly).
pub fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let (header, cells) = csv_cells(path);
    let rows = cells
        .iter()
        .map(|r| r.iter().map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// Column `name` of a CSV file.
pub fn column(path: &Path, name: &str) -> Vec<f64> {
    let (h, rows) = csv(path);
    let j = h
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no {name} in {}", path.display()));
    rows.iter().map(|r| r[j]).collect()
}

/// The snapshot CSV files of a growth run and their times (from summary.json), in order.
pub fn snapshots(run: &Path) -> Vec<(PathBuf, f64)> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    v["snapshots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            (
                run.join(s["file"].as_str().unwrap()),
                s["t"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// Bit-for-bit equality of two f64 slices.
pub fn assert_bits(a: &[f64], b: &[f64], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "{what}[{i}]: {x:e} != {y:e}");
    }
}

/// The growth variables written per snapshot (as row vectors), beside `time`.
pub const GROWTH_VARS: [&str; 14] = [
    "h",
    "s",
    "z",
    "r",
    "sigma",
    "rho",
    "zeta",
    "alpha_s",
    "alpha_phi",
    "alpha_n",
    "eta",
    "z_retina",
    "r_retina",
    "Sigma",
];
pub const Y_ROWS: [&str; 5] = ["kappa", "alpha_s", "r", "theta", "Q"];
pub const ELASTIC_EXTRA: [&str; 8] = [
    "sigma",
    "z",
    "s",
    "alpha_phi",
    "alpha_n",
    "h",
    "t_s",
    "t_phi",
];

// ------------------------------------------------ hostile inputs: bounded runs

/// Virtual memory allowed to one eyeshell process (KiB), and its wall-clock limit.
pub const MEMORY_KIB: u64 = 4 << 20;
pub const SECONDS: u64 = 60;

/// Run `eyeshell ARGS` in `dir` under `ulimit -v` and `timeout -s KILL`; the run must end
/// by itself, well inside the limit.
pub fn bounded(dir: &Path, args: &[&str]) -> Run {
    bounded_with(dir, args, &[])
}

/// [`bounded`], with the environment variables `envs` set.
pub fn bounded_with(dir: &Path, args: &[&str], envs: &[(&str, &str)]) -> Run {
    let start = Instant::now();
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {MEMORY_KIB}; exec timeout -s KILL {SECONDS} \"$0\" \"$@\""
        ))
        .arg(env!("CARGO_BIN_EXE_eyeshell"))
        .args(args)
        .current_dir(dir)
        .env("CI", "1")
        .envs(envs.iter().copied())
        .output()
        .expect("run eyeshell");
    let took = start.elapsed();
    assert!(
        took < Duration::from_secs(SECONDS - 5),
        "{args:?} took {took:?}"
    );
    Run::from(out)
}

/// Every file under a directory and its bytes, to show that nothing changed.
#[derive(Debug, PartialEq)]
pub struct World(BTreeMap<PathBuf, Vec<u8>>);

impl World {
    pub fn of(root: &Path) -> World {
        let mut files = BTreeMap::new();
        let mut stack = vec![root.to_path_buf()];
        while let Some(dir) = stack.pop() {
            for e in std::fs::read_dir(&dir).unwrap() {
                let p = e.unwrap().path();
                let meta = std::fs::symlink_metadata(&p).unwrap();
                let rel = p.strip_prefix(root).unwrap().to_path_buf();
                if meta.is_dir() {
                    files.insert(rel, b"<dir>".to_vec());
                    stack.push(p);
                } else if meta.is_symlink() {
                    let to = std::fs::read_link(&p).unwrap();
                    files.insert(rel, to.to_string_lossy().as_bytes().to_vec());
                } else {
                    files.insert(rel, std::fs::read(&p).unwrap());
                }
            }
        }
        World(files)
    }
}

/// stderr is one line, an eyeshell error, with no panic text.
pub fn one_clean_line(r: &Run, what: &str) {
    assert_eq!(r.stderr.lines().count(), 1, "{what}: {:?}", r.stderr);
    assert!(
        r.stderr.starts_with("eyeshell: error: "),
        "{what}: {}",
        r.stderr
    );
    assert!(!r.stderr.contains("panicked"), "{what}: {}", r.stderr);
}

/// A clean refusal: exit 2, one `eyeshell: error:` line naming `needle`, no panic.
pub fn refused(r: &Run, needle: &str, what: &str) {
    assert_eq!(r.code, Some(2), "{what}: {}", r.stderr);
    one_clean_line(r, what);
    assert!(
        r.stderr.contains(needle),
        "{what}: {needle:?} not in {}",
        r.stderr
    );
}

pub fn succeeded(r: &Run, what: &str) {
    assert_eq!(r.code, Some(0), "{what}: {}", r.stderr);
}

/// `eyeshell ARGS` in `dir`, started in a process group of its own (so that a test can
/// signal the group as a terminal or a cluster does), stdout discarded; its stderr after
/// the first line, which must start with `first` (the first run's report).
pub fn spawn_in_own_group(
    dir: &Path,
    args: &[&str],
    first: &str,
) -> (
    std::process::Child,
    std::io::BufReader<std::process::ChildStderr>,
    String,
) {
    use std::io::BufRead;
    use std::os::unix::process::CommandExt;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_eyeshell"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .process_group(0)
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    assert!(line.starts_with(first), "{line}");
    (child, stderr, line)
}
