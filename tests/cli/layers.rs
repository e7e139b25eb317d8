//! The layers below the files crate, as ARCHITECTURE.md draws them: the numerics crate
//! (crates/core, `eyeshell-core`), the optics (crates/optics), the safe solvers
//! (crates/linalg) and the charts (crates/plot) each depend on what the document says and
//! on nothing else, and touch no file (the charts read their font, and write nothing).
//! Reading and writing files, and the form of what they record, are the `eyeshell` crate's
//! job; these checks keep the lines where they are drawn. The command line names
//! eyeshell-sundials in its benches only, so it is a dev-dependency.

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

/// The normal dependencies each lower crate has directly (`cargo tree -e normal --depth 1`),
/// as ARCHITECTURE.md lists them: a new one is a decision to write down there first.
const LAYERS: [(&str, &[&str]); 4] = [
    (
        "eyeshell-core",
        &[
            "eyeshell-linalg",
            "eyeshell-optics",
            "eyeshell-sundials",
            "nalgebra",
            "rustix",
            "thiserror",
        ],
    ),
    ("eyeshell-optics", &["rayon", "thiserror"]),
    ("eyeshell-linalg", &["thiserror"]),
    (
        "eyeshell-plot",
        &["plotters", "plotters-backend", "png", "thiserror"],
    ),
];

/// The names of the crates `package` depends on directly (normal dependencies).
fn direct_dependencies(package: &str) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(repo())
        .args([
            "tree",
            "--offline",
            "-e",
            "normal",
            "--depth",
            "1",
            "--prefix",
            "none",
            "-p",
            package,
        ])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let mut names: Vec<String> = text
        .lines()
        .skip(1) // the package itself
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect();
    names.sort();
    names.dedup();
    names
}

#[test]
fn each_lower_crate_depends_on_what_architecture_md_says() {
    for (package, expected) in LAYERS {
        assert_eq!(
            direct_dependencies(package),
            expected,
            "{package}'s direct dependencies (ARCHITECTURE.md lists them)"
        );
    }
    // The optics and the solvers hold no I/O or format crate anywhere below them either.
    for package in ["eyeshell-optics", "eyeshell-linalg"] {
        let all = dependencies(package);
        assert!(all.iter().any(|n| n == "thiserror"), "{all:?}");
        assert_eq!(io_crates_in(&all), [] as [&str; 0], "{package}: {all:?}");
        assert_eq!(
            crates_in(&FORMAT_CRATES, &all),
            [] as [&str; 0],
            "{package}: {all:?}"
        );
    }
}

#[test]
fn the_command_line_depends_on_sundials_only_to_bench_it() {
    let cli = direct_dependencies("eyeshell-cli");
    assert!(cli.iter().any(|n| n == "eyeshell"), "{cli:?}");
    for dev_only in ["eyeshell-sundials", "eyeshell-linalg"] {
        assert!(!cli.iter().any(|n| n == dev_only), "{dev_only} in {cli:?}");
    }
    // What names it: the benches alone.
    let mut named = Vec::new();
    for dir in ["src", "tests/cli", "examples"] {
        let mut files = Vec::new();
        rust_files(&repo().join(dir), &mut files);
        // This file names it only to search for it.
        for f in files
            .into_iter()
            .filter(|f| !f.ends_with("tests/cli/layers.rs"))
        {
            if std::fs::read_to_string(&f)
                .unwrap()
                .contains("eyeshell_sundials")
            {
                named.push(f.display().to_string());
            }
        }
    }
    assert_eq!(named, Vec::<String>::new());
}

/// The file APIs that write (the charts read their font, so std::fs itself is allowed there).
const WRITE_APIS: [&str; 6] = [
    "fs::write",
    "File::create",
    "OpenOptions",
    "create_dir",
    "remove_file",
    "fs::rename",
];

#[test]
fn the_optics_the_solvers_and_the_charts_touch_no_file() {
    for dir in ["crates/optics/src", "crates/linalg/src"] {
        let hits = file_api_uses(&repo().join(dir));
        assert!(hits.is_empty(), "file I/O in {dir}:\n{}", hits.join("\n"));
    }
    let mut files = Vec::new();
    rust_files(&repo().join("crates/plot/src"), &mut files);
    let (mut writes, mut reads) = (Vec::new(), 0);
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, line) in text.lines().enumerate() {
            if WRITE_APIS.iter().any(|api| line.contains(api)) {
                writes.push(format!("{}:{}: {}", f.display(), i + 1, line.trim()));
            }
            reads += line.contains("std::fs::read") as usize;
        }
    }
    assert!(
        writes.is_empty(),
        "crates/plot writes:\n{}",
        writes.join("\n")
    );
    // Not vacuous: the same search sees the font being read.
    assert!(reads > 0);
}
