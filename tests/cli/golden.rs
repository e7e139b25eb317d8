//! Golden outputs: the files written by `eyeshell solve`, `grow`, `export`, `figures` and
//! `plot` must stay byte-identical (timings and versions aside) across refactors. The test
//! drives only the built binary (`CARGO_BIN_EXE_eyeshell`), never the library, whose
//! module paths a refactor moves.
//!
//! In a temporary directory (holding copies of the scene files it needs, so that every path
//! it passes and every path the outputs record is relative) it runs [`COMMANDS`], then
//! hashes every file produced (FNV-1a 64 of the normalised bytes, relative paths sorted) and
//! compares the hashes with `tests/golden/outputs.txt`, reporting every changed, missing
//! and extra file at once. On a mismatch the directory is kept and its path printed, so the
//! files can be inspected or diffed against a run of the old binary.
//!
//! What is normalised, and nothing else (two identical runs, including `figures` at
//! `-j 1`, `-j 2` and `-j 4`, differ in exactly these spans; no output holds a date, and
//! none holds an absolute path today):
//! - `*.json`: the values of `"wall_seconds"` (run time) and of `"eyeshell_version"` /
//!   `"sundials_version"`; in a sweep run's `result.json`, the `bytes` and `fnv1a64` of
//!   its `summary.json` entry (that file holds the run time) and of its `.csv` entries
//!   (their text follows the number format; their values are compared below);
//! - `*.csv`: the `wall_seconds` column (sweep.csv of the figures' sweeps), found by its
//!   header; every other cell that reads as a number is hashed by its value (the bits of
//!   the f64 it parses to), so `2.263564555774848e1` and `22.63564555774848` hash the
//!   same and a change of the number format is not a change of the outputs; every other
//!   byte (headers, text cells, quoting, line ends) as it is;
//! - `index.html`: the version text `eyeshell <v> (SUNDIALS <v>)`;
//! - `.eyeshell` (the ownership marker): the version in `"written_by"`;
//! - `*.mat`: the version in the 116-byte text header (`Platform: eyeshell <v>,`) and the
//!   header's padding spaces, which follow the version's length; the header holds no date.
//!   The data elements (plain and `--compress`ed) are compared raw;
//! - every text file: the temporary directory's absolute path, should one ever appear.
//!
//! PNG, SVG and `.npz` files are compared raw: the PNGs carry no text or time chunks, and
//! the `.npz` zip entries are stamped 1980-01-01 00:00 with fixed attributes.
//!
//! Re-bless (after an intended change of the outputs, or on another machine):
//!
//! ```text
//! EYESHELL_BLESS=1 cargo test --release --test cli golden
//! ```
//!
//! rewrites the manifest; review its diff before committing it.
//!
//! Caveat: the hashes are bit-level, so they assume the same numerical platform as the
//! blessing: SUNDIALS 6.x as Debian packages it (6.4.1+dfsg1, linked dynamically), the
//! x86-64 libm of glibc, the same `Cargo.lock` (the PNG/`.npz` deflate streams come from
//! the locked png/flate2/zip crates) and the same PNG font: the first one the binary finds
//! on its font list, here Debian's fonts-dejavu-core 2.37
//! /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf (the test unsets `EYESHELL_PLOT_FONT`).
//! On another machine, bless first on the old commit, then compare.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The manifest: one `<hash> <relative path>` line per file, sorted by path.
const MANIFEST: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/outputs.txt");
/// Set (to anything but empty or `0`) to rewrite [`MANIFEST`] instead of comparing.
const BLESS_ENV: &str = "EYESHELL_BLESS";
/// eyeshell's version, as written into summary.json, index.html and .mat headers.
const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The scenes the commands read, copied into the temporary directory's `scenes/`.
/// `fibre.toml` and `grow.toml` have [sweep] (not solve/grow scenes); `figures` has the
/// scenes it runs built in.
const SCENES: [&str; 5] = [
    "default",
    "exact-sphere",
    "fibres-nonuniform",
    "const",
    "thick",
];

/// Every command, run in this order in the temporary directory (which they alone fill,
/// apart from `scenes/`). Release build: about 4.5 s on 2 cores, 3.5 of them `figures`.
const COMMANDS: &[&[&str]] = &[
    // The elastic scenes (no [growth], no [sweep]); one with at.csv.
    &[
        "solve",
        "scenes/default.toml",
        "--out",
        "solve-default",
        "-q",
    ],
    &[
        "solve",
        "scenes/exact-sphere.toml",
        "--out",
        "solve-exact-sphere",
        "-q",
    ],
    &[
        "solve",
        "scenes/fibres-nonuniform.toml",
        "--at",
        "1,5,10",
        "--out",
        "solve-fibres-nonuniform",
        "-q",
    ],
    // The growth scenes without [sweep], at their full settings (0.3 s each).
    &["grow", "scenes/const.toml", "--out", "grow-const", "-q"],
    &["grow", "scenes/thick.toml", "--out", "grow-thick", "-q"],
    // Export: an elastic solve (files) and a growth run (directories), then both again
    // with every .mat variable miCOMPRESSED.
    &[
        "export",
        "solve-default",
        "--mat",
        "export-solve-default.mat",
        "--npz",
        "export-solve-default.npz",
        "-q",
    ],
    &[
        "export",
        "grow-const",
        "--mat",
        "export-grow-const-mat",
        "--npz",
        "export-grow-const-npz",
        "-q",
    ],
    &[
        "export",
        "solve-default",
        "--mat",
        "export-compress-solve-default.mat",
        "--npz",
        "export-compress-solve-default.npz",
        "--compress",
        "-q",
    ],
    &[
        "export",
        "grow-const",
        "--mat",
        "export-compress-grow-const-mat",
        "--npz",
        "export-compress-grow-const-npz",
        "--compress",
        "-q",
    ],
    // The paper's figures (a)-(f): PNG, SVG, index.html, summary.json and the runs in data/.
    &["figures", "--out", "fig", "-q"],
    // Plots of a growth run, an elastic run and a sweep (one of the figures' sweeps).
    &["plot", "grow-thick", "--out", "plot-grow-thick", "-q"],
    &["plot", "solve-default", "--out", "plot-solve-default", "-q"],
    &["plot", "fig/data/fibre", "--out", "plot-sweep-fibre", "-q"],
];

#[test]
fn outputs_match_the_golden_manifest() {
    let started = std::time::Instant::now();
    let tmp = tempfile::tempdir().expect("temporary directory");
    let dir = tmp.path();
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    fs::create_dir(dir.join("scenes")).unwrap();
    for s in SCENES {
        let file = format!("{s}.toml");
        fs::copy(scenes.join(&file), dir.join("scenes").join(&file))
            .unwrap_or_else(|e| panic!("copy scenes/{file}: {e}"));
    }

    for args in COMMANDS {
        let out = Command::new(env!("CARGO_BIN_EXE_eyeshell"))
            .args(*args)
            .current_dir(dir)
            .env_remove("EYESHELL_PLOT_FONT")
            .output()
            .expect("run eyeshell");
        if !out.status.success() {
            let kept = tmp.keep();
            panic!(
                "`eyeshell {}` failed ({}) in {}:\n{}{}",
                args.join(" "),
                out.status,
                kept.display(),
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }

    let ctx = Normaliser::new(dir);
    let mut files = Vec::new();
    walk(dir, dir, &mut files);
    files.retain(|rel| !rel.starts_with("scenes/"));
    files.sort();
    assert!(!files.is_empty(), "the commands wrote no files");
    let actual: BTreeMap<String, String> = files
        .iter()
        .map(|rel| {
            let bytes = fs::read(dir.join(rel)).unwrap_or_else(|e| panic!("read {rel}: {e}"));
            (
                rel.clone(),
                format!("{:016x}", fnv1a64(&ctx.normalise(rel, bytes))),
            )
        })
        .collect();

    let bless = std::env::var(BLESS_ENV).is_ok_and(|v| !v.is_empty() && v != "0");
    if bless {
        let mut text = String::from(
            "# Golden outputs of tests/golden.rs: FNV-1a 64 of each file's normalised bytes.\n\
             # Rewrite with: EYESHELL_BLESS=1 cargo test --release --test cli golden\n",
        );
        for (rel, hash) in &actual {
            writeln!(text, "{hash} {rel}").unwrap();
        }
        fs::create_dir_all(Path::new(MANIFEST).parent().unwrap()).unwrap();
        fs::write(MANIFEST, text).unwrap_or_else(|e| panic!("write {MANIFEST}: {e}"));
        eprintln!(
            "golden: blessed {} files into {MANIFEST} in {:.1} s",
            actual.len(),
            started.elapsed().as_secs_f64()
        );
        return;
    }

    let manifest = fs::read_to_string(MANIFEST).unwrap_or_else(|e| {
        panic!(
            "{MANIFEST}: {e}\nwrite it with: {BLESS_ENV}=1 cargo test --release --test cli golden"
        )
    });
    let mut expected = BTreeMap::new();
    for (i, line) in manifest.lines().enumerate() {
        if line.trim().is_empty() || line.starts_with('#') {
            continue;
        }
        let (hash, rel) = line
            .split_once(' ')
            .unwrap_or_else(|| panic!("{MANIFEST}:{}: not `<hash> <path>`: {line:?}", i + 1));
        expected.insert(rel.to_string(), hash.to_string());
    }

    let mut report = String::new();
    let (mut changed, mut missing, mut extra) = (0, 0, 0);
    for (rel, hash) in &expected {
        match actual.get(rel) {
            Some(h) if h == hash => {}
            Some(h) => {
                changed += 1;
                writeln!(report, "  changed  {rel} (expected {hash}, got {h})").unwrap();
            }
            None => {
                missing += 1;
                writeln!(report, "  missing  {rel}").unwrap();
            }
        }
    }
    for (rel, h) in &actual {
        if !expected.contains_key(rel) {
            extra += 1;
            writeln!(report, "  extra    {rel} ({h})").unwrap();
        }
    }
    if !report.is_empty() {
        let kept = tmp.keep();
        panic!(
            "the outputs differ from {MANIFEST}: {changed} changed, {missing} missing, {extra} \
             extra (of {} expected, {} produced):\n{report}\
             The outputs are kept in {} for inspection.\n\
             If the change is intended, re-bless with: {BLESS_ENV}=1 cargo test --release --test cli golden",
            expected.len(),
            actual.len(),
            kept.display()
        );
    }
    eprintln!(
        "golden: {} files match in {:.1} s",
        actual.len(),
        started.elapsed().as_secs_f64()
    );
}

/// Every file under `dir`, as `/`-separated paths relative to `root`.
fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
    for entry in fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path: PathBuf = entry.unwrap().path();
        if path.is_dir() {
            walk(root, &path, out);
        } else {
            let rel = path.strip_prefix(root).unwrap();
            let parts: Vec<_> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy())
                .collect();
            out.push(parts.join("/"));
        }
    }
}

/// FNV-1a, 64 bits (eyeshell's own, tested against the reference values there).
use eyeshell::hash::fnv1a64;

/// What varies between identical runs, replaced by fixed text (see the module doc).
struct Normaliser {
    /// The temporary directory's absolute path(s), as given and canonical.
    tmp: Vec<String>,
    /// The SUNDIALS version the binary reports (from solve-default/summary.json).
    sundials: String,
}

impl Normaliser {
    fn new(dir: &Path) -> Self {
        let summary = fs::read_to_string(dir.join("solve-default/summary.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&summary).unwrap();
        let sundials = v["sundials_version"]
            .as_str()
            .expect("solve-default/summary.json: sundials_version")
            .to_string();
        let mut tmp = vec![dir.to_string_lossy().into_owned()];
        if let Ok(c) = dir.canonicalize() {
            tmp.push(c.to_string_lossy().into_owned());
        }
        tmp.sort_by_key(|s| std::cmp::Reverse(s.len()));
        tmp.dedup();
        Normaliser { tmp, sundials }
    }

    fn normalise(&self, rel: &str, bytes: Vec<u8>) -> Vec<u8> {
        let ext = rel.rsplit_once('.').map_or("", |(_, e)| e);
        match ext {
            "mat" => mat_header(bytes),
            "json" | "csv" | "html" | "svg" | "toml" | "txt" | "eyeshell" => {
                let mut text =
                    String::from_utf8(bytes).unwrap_or_else(|e| panic!("{rel}: not UTF-8: {e}"));
                for t in &self.tmp {
                    text = text.replace(t.as_str(), "<tmp>");
                }
                match ext {
                    "json" => {
                        if rel.ends_with("/result.json") {
                            text = file_entries(&text);
                        }
                        text = json_value(&text, "wall_seconds", "\"<timing>\"");
                        text = json_value(&text, "eyeshell_version", "\"<version>\"");
                        text = json_value(&text, "sundials_version", "\"<version>\"");
                    }
                    "csv" => text = csv_numbers(&csv_column(&text, "wall_seconds", "<timing>")),
                    // The ownership marker `.eyeshell` names the version that wrote it.
                    "eyeshell" => text = json_value(&text, "written_by", "\"<version>\""),
                    "html" => {
                        text = text.replace(
                            &format!("eyeshell {VERSION} (SUNDIALS {})", self.sundials),
                            "eyeshell <version> (SUNDIALS <version>)",
                        )
                    }
                    _ => {}
                }
                text.into_bytes()
            }
            // png, npz: raw.
            _ => bytes,
        }
    }
}

/// A MAT v5 file with its 116-byte text header's version replaced and its padding spaces
/// dropped; the rest (subsystem offset, version, endian mark, data) raw.
fn mat_header(bytes: Vec<u8>) -> Vec<u8> {
    const TEXT: usize = 116;
    assert!(
        bytes.len() >= 128 && bytes.starts_with(b"MATLAB 5.0 MAT-file"),
        "not a MAT v5 file"
    );
    let text = String::from_utf8_lossy(&bytes[..TEXT]);
    let text = text.trim_end_matches(' ').replace(
        &format!("Platform: eyeshell {VERSION},"),
        "Platform: eyeshell <version>,",
    );
    let mut out = text.into_bytes();
    out.extend_from_slice(&bytes[TEXT..]);
    out
}

/// `text` with the value of every `"key":` (a number, null, bool or string) replaced.
fn json_value(text: &str, key: &str, with: &str) -> String {
    let needle = format!("\"{key}\":");
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find(&needle) {
        let (head, tail) = rest.split_at(i + needle.len());
        out.push_str(head);
        let value = tail.trim_start_matches([' ', '\t', '\n', '\r']);
        out.push_str(&tail[..tail.len() - value.len()]);
        let end = if let Some(s) = value.strip_prefix('"') {
            // A string: to its closing quote (skipping escapes).
            let mut escaped = false;
            let close = s
                .char_indices()
                .find(|&(_, c)| {
                    let hit = !escaped && c == '"';
                    escaped = !escaped && c == '\\';
                    hit
                })
                .map(|(j, _)| j)
                .expect("unterminated JSON string");
            1 + close + 1
        } else {
            value
                .find([',', '}', ']', ' ', '\t', '\n', '\r'])
                .unwrap_or(value.len())
        };
        out.push_str(with);
        rest = &value[end..];
    }
    out.push_str(rest);
    out
}

/// A sweep run's result.json with the size and checksum of its summary.json (which holds
/// the run time) and of its CSV files (whose text follows the number format, their values
/// being compared by [`csv_numbers`]) replaced; the other files' kept.
fn file_entries(text: &str) -> String {
    const PATH: &str = "\"path\": \"";
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find(PATH) {
        let start = i + PATH.len();
        let Some(close) = rest[start..].find('"') else {
            break;
        };
        let path = &rest[start..start + close];
        let end = rest[i..].find('}').map_or(rest.len(), |j| i + j);
        out.push_str(&rest[..i]);
        if path == "summary.json" || path.ends_with(".csv") {
            let entry = json_value(&rest[i..end], "bytes", "\"<size>\"");
            out.push_str(&json_value(&entry, "fnv1a64", "\"<checksum>\""));
        } else {
            out.push_str(&rest[i..end]);
        }
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// The (start, end) byte spans of the fields of each record of `text` (CSV as eyeshell
/// writes it: fields quoted when they hold `,`, `"` or a line break; `\r\n` or `\n`).
fn csv_spans(text: &str) -> Vec<Vec<(usize, usize)>> {
    let bytes = text.as_bytes();
    let mut records: Vec<Vec<(usize, usize)>> = vec![Vec::new()];
    let (mut start, mut quoted) = (0, false);
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'"' => quoted = !quoted,
            b',' if !quoted => {
                records.last_mut().unwrap().push((start, i));
                start = i + 1;
            }
            b'\n' if !quoted => {
                let end = if i > start && bytes[i - 1] == b'\r' {
                    i - 1
                } else {
                    i
                };
                records.last_mut().unwrap().push((start, end));
                records.push(Vec::new());
                start = i + 1;
            }
            _ => {}
        }
    }
    if start < bytes.len() {
        records.last_mut().unwrap().push((start, bytes.len()));
    }
    records
}

/// `text` (CSV) with every data cell that reads as a number (Rust's f64 parser: `8e0`,
/// `8.0`, `1e-05`, `NaN`, `inf`) replaced by the 16 hex digits of its f64's bits: the value
/// exactly, whatever its spelling. Header and text cells are kept byte for byte.
fn csv_numbers(text: &str) -> String {
    let records = csv_spans(text);
    let mut out = String::with_capacity(text.len());
    let mut at = 0;
    for record in records.iter().skip(1) {
        for &(a, b) in record {
            if let Ok(x) = text[a..b].parse::<f64>() {
                out.push_str(&text[at..a]);
                write!(out, "#{:016x}", x.to_bits()).unwrap();
                at = b;
            }
        }
    }
    out.push_str(&text[at..]);
    out
}

/// `text` (CSV as eyeshell writes it: fields quoted when they hold `,`, `"` or a line
/// break) with every data cell of the column headed `column` replaced; every other byte
/// kept.
fn csv_column(text: &str, column: &str, with: &str) -> String {
    let records = csv_spans(text);
    let Some(col) = records[0].iter().position(|&(a, b)| &text[a..b] == column) else {
        return text.to_string();
    };
    let mut out = String::with_capacity(text.len());
    let mut at = 0;
    for record in &records[1..] {
        if let Some(&(a, b)) = record.get(col) {
            out.push_str(&text[at..a]);
            out.push_str(with);
            at = b;
        }
    }
    out.push_str(&text[at..]);
    out
}

#[test]
fn normalisers_touch_only_their_spans() {
    let json = "{\n  \"a\": 1,\n  \"wall_seconds\": 0.0123,\n  \"s\": \"x\\\"y\",\n  \"sundials_version\": \"6.4.1\"\n}\n";
    let j = json_value(
        &json_value(json, "wall_seconds", "T"),
        "sundials_version",
        "V",
    );
    assert_eq!(j, "{\n  \"a\": 1,\n  \"wall_seconds\": T,\n  \"s\": \"x\\\"y\",\n  \"sundials_version\": V\n}\n");
    assert_eq!(
        json_value("{\"wall_seconds\":1e-3}", "wall_seconds", "T"),
        "{\"wall_seconds\":T}"
    );

    let csv = "run,wall_seconds,error\na,1.5e0,\nb,2e0,\"x,\ny\"\n";
    assert_eq!(
        csv_column(csv, "wall_seconds", "T"),
        "run,wall_seconds,error\na,T,\nb,T,\"x,\ny\"\n"
    );
    assert_eq!(csv_column("t,x\n1,2\n", "wall_seconds", "T"), "t,x\n1,2\n");
    // Numbers by value: old and new spellings of one f64 normalise alike, text cells and
    // the header stay, and a different value stays different.
    let old = csv_numbers("t,class,x\n2.263564555774848e1,myopic,8e0\n1e-5,\"a,b\",NaN\n");
    let new = csv_numbers("t,class,x\n22.63564555774848,myopic,8.0\n1e-05,\"a,b\",NaN\n");
    assert_eq!(old, new);
    assert!(old.starts_with("t,class,x\n#4036a2"), "{old}");
    assert!(old.contains(",myopic,#4020000000000000\n"), "{old}");
    assert!(old.contains(",\"a,b\",#7ff8000000000000\n"), "{old}");
    assert_ne!(
        csv_numbers("x\n1.5\n"),
        csv_numbers("x\n1.5000000000000002\n")
    );
    let result = "{\"files\": [\n {\"path\": \"series.csv\", \"bytes\": 12, \"fnv1a64\": \"ab\"},\n {\"path\": \"summary.json\", \"bytes\": 3, \"fnv1a64\": \"cd\"},\n {\"path\": \"snapshots/a.mat\", \"bytes\": 4, \"fnv1a64\": \"ef\"}]}";
    let n = file_entries(result);
    assert_eq!(n.matches("<checksum>").count(), 2, "{n}");
    assert!(n.contains("\"bytes\": 4, \"fnv1a64\": \"ef\""), "{n}");

    let mut mat =
        format!("MATLAB 5.0 MAT-file, Platform: eyeshell {VERSION}, Created by: eyeshell export")
            .into_bytes();
    mat.resize(116, b' ');
    mat.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0, 0, 1, b'I', b'M', 7]);
    let n = mat_header(mat);
    assert_eq!(
        n,
        b"MATLAB 5.0 MAT-file, Platform: eyeshell <version>, Created by: eyeshell export\0\0\0\0\0\0\0\0\0\x01IM\x07"
    );
}
