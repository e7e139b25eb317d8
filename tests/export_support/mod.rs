//! Shared by the export_* tests: run the binary, make small runs, read CSV files back.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

/// Run `eyeshell ARGS` in the repository (so `scenes/` resolves).
pub fn eyeshell(args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_eyeshell"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("CI", "1")
        .output()
        .expect("run eyeshell");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Run `eyeshell ARGS` and insist that it succeeds.
pub fn ok(args: &[&str]) -> Run {
    let r = eyeshell(args);
    assert_eq!(r.code, Some(0), "eyeshell {args:?}: {}{}", r.stdout, r.stderr);
    r
}

/// Assert a clean failure: `code`, one stderr line `eyeshell: error: ...` containing `needle`.
pub fn assert_fails(r: &Run, code: i32, needle: &str) {
    assert_eq!(r.code, Some(code), "stdout: {} stderr: {}", r.stdout, r.stderr);
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {:?}", r.stderr);
    assert!(lines[0].starts_with("eyeshell: error: "), "{}", lines[0]);
    assert!(lines[0].contains(needle), "{needle:?} not in {}", lines[0]);
}

/// The small runs of the brief: an elastic solve (N = 21) and the const growth scene (N = 21,
/// rtol 1e-3), in `dir/solve` and `dir/grow`.
pub fn small_runs(dir: &Path) -> (PathBuf, PathBuf) {
    let solve = dir.join("solve");
    let grow = dir.join("grow");
    ok(&["solve", "scenes/default.toml", "--set", "solver.nodes=21", "--out", s(&solve), "--quiet"]);
    ok(&[
        "grow", "scenes/const.toml", "--set", "solver.nodes=21", "--set", "solver.rtol=1e-3",
        "--out", s(&grow), "--quiet",
    ]);
    (solve, grow)
}

/// A CSV file: header and rows of f64 (every value parsed exactly).
pub fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// Column `name` of a CSV file.
pub fn column(path: &Path, name: &str) -> Vec<f64> {
    let (h, rows) = csv(path);
    let j = h.iter().position(|c| c == name).unwrap_or_else(|| panic!("no {name} in {}", path.display()));
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
        .map(|s| (run.join(s["file"].as_str().unwrap()), s["t"].as_f64().unwrap()))
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
    "h", "s", "z", "r", "sigma", "rho", "zeta", "alpha_s", "alpha_phi", "alpha_n", "eta",
    "z_retina", "r_retina", "Sigma",
];
pub const Y_ROWS: [&str; 5] = ["kappa", "alpha_s", "r", "theta", "Q"];
pub const ELASTIC_EXTRA: [&str; 8] = ["sigma", "z", "s", "alpha_phi", "alpha_n", "h", "t_s", "t_phi"];
