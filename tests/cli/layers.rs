//! The numerics crate (crates/core, `eyeshell-core`) touches no file: it depends on no I/O
//! crate, no serialisation crate, and names no file API. Reading and writing files, and the
//! form of what they record, are the `eyeshell` crate's job (ARCHITECTURE.md); these checks
//! keep the line where it is drawn.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::repo;

/// The crates that read or write files, which the numerics must not depend on.
const IO_CRATES: [&str; 4] = ["csv", "toml", "zip", "flate2"];

/// The crates of a file's format (summary.json's records are the files crate's:
/// rundir/record.rs), which the numerics must not depend on either.
const FORMAT_CRATES: [&str; 2] = ["serde", "serde_json"];

/// The names of the crates `cargo tree -p PACKAGE -e normal` lists (normal dependencies,
/// transitively).
fn dependencies(package: &str) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(repo())
        .args([
            "tree",
            "--offline",
            "-e",
            "normal",
            "--prefix",
            "none",
            "-p",
            package,
        ])
        .output()
        .expect("cargo runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut names: Vec<String> = text
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect();
    names.sort();
    names.dedup();
    names
}

fn io_crates_in(names: &[String]) -> Vec<&'static str> {
    crates_in(&IO_CRATES, names)
}

fn crates_in(these: &[&'static str], names: &[String]) -> Vec<&'static str> {
    these
        .iter()
        .copied()
        .filter(|c| names.iter().any(|n| n == c))
        .collect()
}

#[test]
fn the_numerics_crate_depends_on_no_io_crate() {
    let core = dependencies("eyeshell-core");
    // Not vacuous: the tree was read, and holds what the numerics do use.
    for used in [
        "eyeshell-core",
        "eyeshell-sundials",
        "eyeshell-linalg",
        "nalgebra",
    ] {
        assert!(core.iter().any(|n| n == used), "{used} not in {core:?}");
    }
    assert_eq!(
        io_crates_in(&core),
        [] as [&str; 0],
        "eyeshell-core's dependencies: {core:?}"
    );
    assert_eq!(
        crates_in(&FORMAT_CRATES, &core),
        [] as [&str; 0],
        "eyeshell-core's dependencies: {core:?}"
    );
    // The same check sees them where they belong: the files crate above it.
    let files = dependencies("eyeshell");
    assert_eq!(
        io_crates_in(&files),
        IO_CRATES,
        "eyeshell's dependencies: {files:?}"
    );
    assert_eq!(
        crates_in(&FORMAT_CRATES, &files),
        FORMAT_CRATES,
        "eyeshell's dependencies: {files:?}"
    );
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The file APIs the numerics must not name (std::fs, and `File::` from anywhere).
const FILE_APIS: [&str; 2] = ["std::fs", "File::"];

fn file_api_uses(dir: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(dir, &mut files);
    assert!(!files.is_empty(), "no Rust files under {}", dir.display());
    let mut hits = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, line) in text.lines().enumerate() {
            if FILE_APIS.iter().any(|api| line.contains(api)) {
                hits.push(format!("{}:{}: {}", f.display(), i + 1, line.trim()));
            }
        }
    }
    hits
}

#[test]
fn the_numerics_crate_names_no_file_api() {
    let hits = file_api_uses(&repo().join("crates/core/src"));
    assert!(
        hits.is_empty(),
        "file I/O in eyeshell-core:\n{}",
        hits.join("\n")
    );
    // The same search finds them in the files crate, which writes run directories.
    assert!(!file_api_uses(&repo().join("crates/eyeshell/src/rundir")).is_empty());
}
