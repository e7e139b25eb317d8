//! Fuzz of the run-file readers (TESTING.md, family 6): the CSV files of a run directory
//! (fields.csv, at.csv, series.csv, history.csv, the snapshots) and summary.json of every
//! kind (elastic, growth running / ok / failed, sweep, study, figures), mutated from real
//! files written by a small solve, grow and sweep: bit flips, overwritten bytes,
//! truncations (inside a line and at a line end), splices of another file, numbers replaced
//! by huge, tiny and non-finite spellings, words replaced by hostile text, JSON nested deeper
//! than serde_json's limit, very long lines and invalid UTF-8.
//!
//! In process, each mutated file goes through the library's readers (`read_csv`,
//! `read_series`, `Summary::read`) and, placed in a copy of its run, through everything that
//! reads a run back: `read_run` (export, compare), `rundata::read` (plot, figures),
//! `compare::load`, `export` and, for a sweep, `sweep_runs`. Fewer cases run the binary:
//! `export`, `compare` and `plot` on a broken run. Every call must return without
//! panicking, within a time bound, and an error must be one clean line of bounded length
//! that names the run (and, when one CSV file was broken, no other CSV file).
//!
//! Seeded and counted like `fuzz_readers`: 2,000 CSV files, 3,000 summaries, 900 damaged
//! runs and 18 runs of the binary per command, a few seconds each in release;
//! `EYESHELL_FUZZ_SCALE=50 cargo test --release --test cli fuzz_run_files` multiplies every
//! case count for a longer hunt. What the hunts found is kept at the end, as named cases.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

use crate::fuzz_readers::{mutation, runner, Mutation};
use crate::support::*;
use eyeshell::interop::{compare, export};
use eyeshell::rundir::read::read_run;
use eyeshell::rundir::rundata::{self, read_series};
use eyeshell::rundir::summary::{
    FigureEntry, FiguresSummary, GrowthSummary, RunStatus, SnapshotEntry, StudySummary,
};
use eyeshell::rundir::table::read_csv;
use eyeshell::rundir::Summary;
use eyeshell::Scene;

/// The bound on one call in process (generous: a case may be a 50 MB file of megabyte
/// lines, read in about a second on a busy machine; a reader that is slower than linear
/// takes far longer).
const TIME_BOUND: Duration = Duration::from_secs(5);

/// The longest error message accepted: a path or two and a short excerpt, never a file.
const MESSAGE_BOUND: usize = 1000;

/// The bound on one run of the binary (it draws PNG files for `plot`).
const CLI_TIME_BOUND: Duration = Duration::from_secs(60);

// ---------------------------------------------------------------- the seeds

/// The runs the seeds come from: a solve with `--at`, a growth run with a history, and a
/// sweep of two elastic runs, all at N = 21.
struct Runs {
    _dir: tempfile::TempDir,
    solve: PathBuf,
    grow: PathBuf,
    sweep: PathBuf,
}

fn runs() -> &'static Runs {
    static RUNS: OnceLock<Runs> = OnceLock::new();
    RUNS.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let (solve, grow) = (dir.path().join("solve"), dir.path().join("grow"));
        ok(&[
            "solve",
            "scenes/default.toml",
            "--set",
            "solver.nodes=21",
            "--at",
            "0.5,1,2",
            "--out",
            s(&solve),
            "-q",
        ]);
        ok(&[
            "grow",
            "scenes/const.toml",
            "--set",
            "solver.nodes=21",
            "--set",
            "solver.rtol=1e-3",
            "--set",
            "output.history_points=4",
            "--out",
            s(&grow),
            "-q",
        ]);
        std::fs::write(
            dir.path().join("s.toml"),
            "[solver]\nnodes = 21\n[sweep.grid]\n\"fibres.D\" = [0, 100]\n",
        )
        .unwrap();
        let sweep = dir.path().join("sweep");
        let r = eyeshell_in(dir.path(), &["sweep", "s.toml", "--out", "sweep", "-q"]);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        Runs {
            _dir: dir,
            solve,
            grow,
            sweep,
        }
    })
}

/// Every file of `dir`, recursively, as (path relative to `dir`, bytes), in order.
fn files_of(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

/// The CSV files of the runs: (file name, bytes).
fn csv_seeds() -> Vec<(String, Vec<u8>)> {
    let r = runs();
    let mut seeds = Vec::new();
    for dir in [&r.solve, &r.grow, &r.sweep.join("runs/D=0")] {
        for (rel, bytes) in files_of(dir) {
            if rel.extension().is_some_and(|x| x == "csv") {
                let name = rel.file_name().unwrap().to_string_lossy().into_owned();
                seeds.push((name, bytes));
            }
        }
    }
    assert!(seeds.len() >= 9, "{} CSV seeds", seeds.len());
    seeds
}

/// summary.json of every kind: those the runs wrote, and those of the kinds no small run
/// writes (a running and a failed growth run, a study, figures), made by the library.
fn summary_seeds() -> Vec<Vec<u8>> {
    let r = runs();
    let mut seeds: Vec<Vec<u8>> = [&r.solve, &r.grow, &r.sweep, &r.sweep.join("runs/D=0")]
        .iter()
        .map(|d| std::fs::read(d.join("summary.json")).unwrap())
        .collect();
    let scene: Scene = "growth.eta0 = 70\nsolver.nodes = 21\noutput.history_points = 4"
        .parse()
        .unwrap();
    let snaps = [SnapshotEntry {
        t: 0.0,
        file: "snapshots/snapshot_00000_t0.000000.csv".into(),
    }];
    let error = eyeshell::growth::GrowthError {
        t: 0.25,
        reason: "the elastic solve failed".into(),
        stats: Box::default(),
    };
    for status in [RunStatus::Running, RunStatus::Failed(&error)] {
        let g = GrowthSummary::new(&scene, status, &snaps, None);
        seeds.push(Summary::Growth(g).to_text().into_bytes());
    }
    let study = StudySummary {
        study: "converge".into(),
        sundials_version: Some("6.4.1".into()),
        report: "N  error\n21  1e-3\n".into(),
    };
    seeds.push(Summary::Study(study).to_text().into_bytes());
    let figures = FiguresSummary {
        figures: vec![FigureEntry {
            id: "a".into(),
            title: "Growth".into(),
            caption: "C = 100 kPa".into(),
            png: "fig_a.png".into(),
            svg: "fig_a.svg".into(),
        }],
        data: Some("data".into()),
        index: Some("index.html".into()),
        status: "ok".into(),
        runs_solved: Some(11),
        runs_shared: Some(1),
    };
    seeds.push(Summary::Figures(figures).to_text().into_bytes());
    seeds
}

// ---------------------------------------------------------------- the mutations

/// Numbers a reader may meet: huge, tiny, non-finite in every spelling, and near-numbers.
const HOSTILE_NUMBERS: &[&str] = &[
    "1e308",
    "1.7976931348623157e308",
    "1e309",
    "-1e400",
    "4.9e-324",
    "1e-400",
    "NaN",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "+inf",
    "Infinity",
    "-Infinity",
    "0",
    "-0",
    "1e",
    "e5",
    ".",
    "-",
    "0x10",
    "1_0",
    "18446744073709551616",
    "-9223372036854775809",
    "99999999999999999999999999999999999999999",
    "1e999999999999",
    "null",
    "true",
    "\"1\"",
    "[]",
    "{}",
];

/// Text a reader may meet in place of a word (a key, a name, a status, a class, a path).
const HOSTILE_TEXT: &[&str] = &[
    "",
    ".",
    "..",
    "../..",
    "/",
    "/tmp",
    "runs/../..",
    "a\u{0}b",
    "line\nbreak",
    "cr\rhere",
    "\u{1b}[31mred",
    "ok",
    "running",
    "failed",
    "reused",
    "not run",
    "hyperopic",
    "myopic",
    "sweep",
    "status",
    "snapshots",
    "parameters",
    "t",
    "Sigma",
    "\"",
    "\\",
    "é",
    "\u{202e}",
];

const BAD_UTF8: &[&[u8]] = &[
    &[0xff],
    &[0xc3],
    &[0xed, 0xa0, 0x80],
    &[0xf4, 0x90, 0x80, 0x80],
    &[0xe2, 0x82],
    &[0xc0, 0xaf],
];

/// Depths of nesting: around serde_json's limit of 128, and far beyond it.
const DEPTHS: &[usize] = &[1, 2, 100, 127, 128, 129, 1000, 100_000];

/// Lengths of an inserted run of one byte: long lines.
const LONG: &[usize] = &[1000, 100_000, 1 << 20];

/// One edit of a text file.
#[derive(Clone, Debug)]
enum Edit {
    /// A byte-level mutation (bit flip, overwrite, 32-bit value, truncation, insertion, removal).
    Bytes(Mutation),
    /// The k-th number replaced by `HOSTILE_NUMBERS[i]`.
    Number(usize, usize),
    /// The k-th word (letters and `_`) replaced by `HOSTILE_TEXT[i]` (JSON-escaped in JSON).
    Word(usize, usize),
    /// The k-th number replaced by arrays (or objects) nested `DEPTHS[i]` deep.
    Nest(usize, usize, bool),
    /// `LONG[i]` copies of a byte inserted at a position.
    LongRun(usize, usize, u8),
    /// Invalid UTF-8 `BAD_UTF8[i]` inserted at a position.
    BadUtf8(usize, usize),
    /// Line k repeated n more times.
    RepeatLine(usize, usize),
    /// Line k removed.
    RemoveLine(usize),
    /// Lines j and k swapped.
    SwapLines(usize, usize),
    /// The file cut after line k (at a line end).
    CutAtLine(usize),
    /// Bytes of seed s (from an offset, a length) inserted at a position.
    Splice(usize, usize, usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        6 => mutation().prop_map(Edit::Bytes),
        4 => (any::<usize>(), 0..HOSTILE_NUMBERS.len()).prop_map(|(k, i)| Edit::Number(k, i)),
        3 => (any::<usize>(), 0..HOSTILE_TEXT.len()).prop_map(|(k, i)| Edit::Word(k, i)),
        1 => (any::<usize>(), 0..DEPTHS.len(), any::<bool>())
            .prop_map(|(k, i, o)| Edit::Nest(k, i, o)),
        1 => (any::<usize>(), 0..LONG.len(), prop_oneof![Just(b'1'), Just(b'x'), Just(b','), Just(b'"'), Just(b'[')])
            .prop_map(|(p, i, b)| Edit::LongRun(p, i, b)),
        1 => (any::<usize>(), 0..BAD_UTF8.len()).prop_map(|(p, i)| Edit::BadUtf8(p, i)),
        1 => (any::<usize>(), 1usize..50).prop_map(|(k, n)| Edit::RepeatLine(k, n)),
        1 => any::<usize>().prop_map(Edit::RemoveLine),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(j, k)| Edit::SwapLines(j, k)),
        2 => any::<usize>().prop_map(Edit::CutAtLine),
        1 => (any::<usize>(), any::<usize>(), 1usize..400, any::<usize>())
            .prop_map(|(s, o, n, p)| Edit::Splice(s, o, n, p)),
    ]
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    proptest::collection::vec(edit(), 1..4)
}

/// The byte ranges of the tokens `is_token` bytes make up, if `wanted` accepts them.
fn tokens(
    b: &[u8],
    is_token: impl Fn(u8) -> bool,
    wanted: impl Fn(&[u8]) -> bool,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if !is_token(b[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < b.len() && is_token(b[i]) {
            i += 1;
        }
        if wanted(&b[start..i]) {
            out.push((start, i));
        }
    }
    out
}

fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    tokens(
        b,
        |c| c.is_ascii_digit() || b".eE+-".contains(&c),
        |t| t.iter().any(u8::is_ascii_digit),
    )
}

fn words(b: &[u8]) -> Vec<(usize, usize)> {
    tokens(b, |c| c.is_ascii_alphabetic() || c == b'_', |_| true)
}

/// Replace the k-th token `find` finds (mod their number) by `with`.
fn replace(b: &mut Vec<u8>, find: fn(&[u8]) -> Vec<(usize, usize)>, k: usize, with: &[u8]) {
    let ranges = find(b);
    if let Some(&(start, end)) = ranges.get(k % ranges.len().max(1)) {
        b.splice(start..end, with.iter().copied());
    }
}

fn nested(depth: usize, object: bool) -> Vec<u8> {
    let (open, close): (&[u8], &[u8]) = if object {
        (b"{\"a\":", b"}")
    } else {
        (b"[", b"]")
    };
    let mut v = open.repeat(depth);
    v.extend_from_slice(if object { b"1" } else { b"" });
    v.extend(close.repeat(depth));
    v
}

/// Apply `edits` to `b` (a file of `seeds`); `json` says how words are escaped.
fn apply(mut b: Vec<u8>, edits: &[Edit], seeds: &[Vec<u8>], json: bool) -> Vec<u8> {
    for e in edits {
        let len = b.len();
        let at = |p: usize| p % (len + 1);
        let mut lines: Vec<Vec<u8>> = b
            .split_inclusive(|&c| c == b'\n')
            .map(<[u8]>::to_vec)
            .collect();
        let n_lines = lines.len().max(1);
        match e {
            Edit::Bytes(m) => b = crate::fuzz_readers::mutate(b, std::slice::from_ref(m)),
            Edit::Number(k, i) => replace(&mut b, numbers, *k, HOSTILE_NUMBERS[*i].as_bytes()),
            Edit::Word(k, i) => {
                let text = if json {
                    let quoted = serde_json::to_string(HOSTILE_TEXT[*i]).unwrap();
                    quoted[1..quoted.len() - 1].to_string()
                } else {
                    HOSTILE_TEXT[*i].to_string()
                };
                replace(&mut b, words, *k, text.as_bytes());
            }
            Edit::Nest(k, i, object) => replace(&mut b, numbers, *k, &nested(DEPTHS[*i], *object)),
            Edit::LongRun(p, i, c) => {
                let p = at(*p);
                b.splice(p..p, std::iter::repeat_n(*c, LONG[*i]));
            }
            Edit::BadUtf8(p, i) => {
                let p = at(*p);
                b.splice(p..p, BAD_UTF8[*i].iter().copied());
            }
            Edit::RepeatLine(k, n) if !lines.is_empty() => {
                let line = lines[k % n_lines].clone();
                for _ in 0..*n {
                    lines.insert(k % n_lines, line.clone());
                }
                b = lines.concat();
            }
            Edit::RemoveLine(k) if !lines.is_empty() => {
                lines.remove(k % n_lines);
                b = lines.concat();
            }
            Edit::SwapLines(j, k) if !lines.is_empty() => {
                lines.swap(j % n_lines, k % n_lines);
                b = lines.concat();
            }
            Edit::CutAtLine(k) => {
                lines.truncate(k % n_lines);
                b = lines.concat();
            }
            Edit::Splice(s, o, n, p) => {
                let src = &seeds[s % seeds.len()];
                let from = o % (src.len() + 1);
                let chunk = &src[from..(from + n).min(src.len())];
                let p = at(*p);
                b.splice(p..p, chunk.iter().copied());
            }
            _ => {}
        }
    }
    b
}

// ---------------------------------------------------------------- the checks

/// Run `read`: no panic, within `bound`, and an error is one clean line of bounded length
/// containing `names` (a path of the run).
fn check<T>(
    what: &str,
    names: &str,
    bound: Duration,
    read: impl FnOnce() -> Result<T, String>,
) -> Result<Option<String>, TestCaseError> {
    let start = Instant::now();
    let r = catch_unwind(AssertUnwindSafe(read));
    let took = start.elapsed();
    let r = r.map_err(|_| TestCaseError::fail(format!("{what}: panicked")))?;
    prop_assert!(took < bound, "{what}: took {took:?}");
    let Err(e) = r else { return Ok(None) };
    prop_assert!(!e.trim().is_empty(), "{what}: an empty message");
    prop_assert!(
        !e.chars().any(char::is_control),
        "{what}: not one clean line: {e:?}"
    );
    prop_assert!(
        e.len() <= MESSAGE_BOUND,
        "{what}: a message of {} bytes: {:?}",
        e.len(),
        e.chars().take(300).collect::<String>()
    );
    prop_assert!(e.contains(names), "{what}: {names:?} not named: {e:?}");
    Ok(Some(e))
}

/// When only the CSV file `broken` (relative to `dir`) was damaged, an error that names a
/// CSV file of the run names that one.
fn blames(dir: &Path, broken: &Path, e: &str) -> Result<(), TestCaseError> {
    let prefix = format!("{}/", dir.display());
    let Some(rest) = e.split(&prefix).nth(1) else {
        return Ok(());
    };
    let named = rest.split(':').next().unwrap_or_default();
    if named.ends_with(".csv") {
        prop_assert_eq!(
            named,
            broken.to_str().unwrap(),
            "blames the wrong file: {}",
            e
        );
    }
    Ok(())
}

// ---------------------------------------------------------------- in process

/// One CSV file through `read_csv` (and `read_series` for a time series).
#[test]
fn csv_files() {
    let seeds = csv_seeds();
    let bytes: Vec<Vec<u8>> = seeds.iter().map(|(_, b)| b.clone()).collect();
    let dir = tempfile::tempdir().unwrap();
    runner(2000, 21)
        .run(&(0..seeds.len(), edits()), |(k, edits)| {
            let (name, seed) = &seeds[k];
            let path = dir.path().join(name);
            std::fs::write(&path, apply(seed.clone(), &edits, &bytes, false)).unwrap();
            let p = s(&path);
            check("read_csv", p, TIME_BOUND, || {
                read_csv(&path).map_err(|e| e.to_string())
            })?;
            if name == "series.csv" || name == "history.csv" {
                check("read_series", p, TIME_BOUND, || {
                    read_series(&path).map_err(|e| e.to_string())
                })?;
            }
            Ok(())
        })
        .unwrap();
}

/// summary.json of every kind through `Summary::read`.
#[test]
fn summaries() {
    let seeds = summary_seeds();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("summary.json");
    runner(3000, 22)
        .run(&(0..seeds.len(), edits()), |(k, edits)| {
            std::fs::write(&path, apply(seeds[k].clone(), &edits, &seeds, true)).unwrap();
            check("Summary::read", s(dir.path()), TIME_BOUND, || {
                Summary::read(dir.path()).map_err(|e| e.to_string())
            })?;
            Ok(())
        })
        .unwrap();
}

/// A copy of a run in which one file is damaged at a time and put back afterwards.
struct Workbench {
    _dir: tempfile::TempDir,
    /// The copy, and the export target beside it.
    run: PathBuf,
    export: PathBuf,
    files: Vec<(PathBuf, Vec<u8>)>,
    sweep: bool,
}

impl Workbench {
    fn new(src: &Path) -> Workbench {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("run");
        let files = files_of(src);
        for (rel, bytes) in &files {
            let p = run.join(rel);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, bytes).unwrap();
        }
        let export = dir.path().join("export");
        Workbench {
            _dir: dir,
            run,
            export,
            files,
            sweep: src.join("sweep.csv").is_file(),
        }
    }

    /// Damage file `k` by `edits`, run `f`, and restore the file.
    fn with_damage<T>(&self, k: usize, edits: &[Edit], f: impl FnOnce(&Path) -> T) -> (PathBuf, T) {
        let (rel, bytes) = &self.files[k % self.files.len()];
        let seeds: Vec<Vec<u8>> = self.files.iter().map(|(_, b)| b.clone()).collect();
        let json = rel.extension().is_some_and(|x| x == "json");
        let path = self.run.join(rel);
        std::fs::write(&path, apply(bytes.clone(), edits, &seeds, json)).unwrap();
        let out = f(rel);
        std::fs::write(&path, bytes).unwrap();
        (rel.clone(), out)
    }
}

/// Everything that reads a run back, in process, on `bench.run` with one file damaged.
fn read_back(bench: &Workbench, broken: &Path) -> Result<(), TestCaseError> {
    let (run, names) = (&bench.run, s(&bench.run));
    let csv = broken.extension().is_some_and(|x| x == "csv");
    let mut errors = Vec::new();
    if bench.sweep {
        errors.push(check("sweep_runs", names, TIME_BOUND, || {
            eyeshell_cli::charts::sweep_runs(run)
                .map(|_| ())
                .map_err(|e| e.to_string())
        })?);
    } else {
        errors.push(check("read_run", names, TIME_BOUND, || {
            read_run(run).map(|_| ()).map_err(|e| e.to_string())
        })?);
        errors.push(check("rundata::read", names, TIME_BOUND, || {
            rundata::read(run).map(|_| ()).map_err(|e| e.to_string())
        })?);
        errors.push(check("export", names, TIME_BOUND, || {
            let done = export::export(run, &bench.export, export::Format::Npz, false);
            let _ = std::fs::remove_dir_all(&bench.export);
            let _ = std::fs::remove_file(&bench.export);
            done.map(|_| ()).map_err(|e| e.to_string())
        })?);
    }
    errors.push(check("compare::load", names, TIME_BOUND, || {
        compare::load(run).map(|_| ()).map_err(|e| e.to_string())
    })?);
    if csv {
        for e in errors.iter().flatten() {
            blames(run, broken, e)?;
        }
    }
    Ok(())
}

#[test]
fn run_directories() {
    let r = runs();
    for (k, src) in [&r.solve, &r.grow, &r.sweep].into_iter().enumerate() {
        let bench = Workbench::new(src);
        let strategy = (any::<usize>(), edits());
        runner(300, 23 + k as u8)
            .run(&strategy, |(file, edits)| {
                let (broken, result) =
                    bench.with_damage(file, &edits, |rel| read_back(&bench, rel));
                result
                    .map_err(|e| TestCaseError::fail(format!("{} damaged: {e}", broken.display())))
            })
            .unwrap();
    }
}

// ---------------------------------------------------------------- the binary

/// `eyeshell ARGS` on a broken run: exit 0, 1 or 2; on failure, one clean line on stderr.
fn cli(args: &[&str]) -> Result<(), TestCaseError> {
    let start = Instant::now();
    let r = eyeshell(args);
    let took = start.elapsed();
    prop_assert!(took < CLI_TIME_BOUND, "{args:?}: took {took:?}");
    prop_assert!(
        matches!(r.code, Some(0..=2)),
        "{args:?}: exit {:?}: {}",
        r.code,
        r.stderr
    );
    prop_assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
    if r.code != Some(0) {
        prop_assert_eq!(r.stderr.lines().count(), 1, "{:?}: {:?}", args, r.stderr);
        prop_assert!(
            r.stderr.starts_with("eyeshell: error: "),
            "{args:?}: {}",
            r.stderr
        );
        prop_assert!(
            r.stderr.len() <= MESSAGE_BOUND + 20,
            "{args:?}: {} bytes",
            r.stderr.len()
        );
    }
    Ok(())
}

#[test]
fn commands_on_broken_runs() {
    let r = runs();
    for (k, src) in [&r.solve, &r.grow, &r.sweep].into_iter().enumerate() {
        let bench = Workbench::new(src);
        let plots = bench.export.with_extension("plots");
        let reference = src.to_str().unwrap().to_string();
        runner(6, 26 + k as u8)
            .run(&(any::<usize>(), edits()), |(file, edits)| {
                let run = s(&bench.run).to_string();
                let (_, result) = bench.with_damage(file, &edits, |_| {
                    if k < 2 {
                        cli(&["export", &run, "--mat", s(&bench.export), "-q"])?;
                        let _ = std::fs::remove_dir_all(&bench.export);
                        let _ = std::fs::remove_file(&bench.export);
                        cli(&["compare", &run, &reference, "-q"])?;
                    }
                    cli(&["plot", &run, "--out", s(&plots), "-q"])
                });
                result
            })
            .unwrap();
    }
}

// ---------------------------------------------------------------- what the hunts found

/// The error of `read` on the run `dir` whose file `rel` is replaced by `bytes` (put back
/// afterwards): it must be one clean line of bounded length naming the run.
fn error_with(
    dir: &Path,
    rel: &str,
    bytes: &[u8],
    read: impl FnOnce(&Path) -> Result<(), String>,
) -> String {
    let bench = Workbench::new(dir);
    let path = bench.run.join(rel);
    std::fs::write(&path, bytes).unwrap();
    let start = Instant::now();
    let e = read(&bench.run).expect_err("an error");
    assert!(start.elapsed() < TIME_BOUND, "{:?}", start.elapsed());
    assert!(!e.chars().any(char::is_control), "{e:?}");
    assert!(e.len() <= MESSAGE_BOUND, "{} bytes", e.len());
    assert!(e.contains(s(&bench.run)), "{e}");
    e
}

fn rundata_read(dir: &Path) -> Result<(), String> {
    rundata::read(dir).map(|_| ()).map_err(|e| e.to_string())
}

/// A megabyte-long word is quoted in a few dozen characters wherever it lands: a CSV cell
/// (read_csv quoted the whole line), a value of summary.json (serde's message quotes it), a
/// parameter's name (the scene reader quoted it, and took seconds looking for the closest
/// key).
#[test]
fn found_a_megabyte_long_word_is_quoted_short() {
    let r = runs();
    let long = "1".repeat(1 << 20);
    let fields = std::fs::read_to_string(r.solve.join("fields.csv")).unwrap();
    let (header, rows) = fields.split_once('\n').unwrap();
    let cut = format!("{header}\n{}", rows.replacen(',', &format!(",{long}x"), 1));
    let e = error_with(&r.solve, "fields.csv", cut.as_bytes(), rundata_read);
    assert!(
        e.contains("fields.csv: line 2: value 2 (sigma) is not a number: \"111"),
        "{e}"
    );
    let summary = std::fs::read_to_string(r.grow.join("summary.json")).unwrap();
    let status = summary.replacen("\"status\": \"ok\"", &format!("\"status\": \"{long}\""), 1);
    let e = error_with(&r.grow, "summary.json", status.as_bytes(), rundata_read);
    assert!(
        e.contains("not a valid growth run summary: unknown variant"),
        "{e}"
    );
    let key = summary.replacen("\"solver.nodes\"", &format!("\"{long}\""), 1);
    let e = error_with(&r.grow, "summary.json", key.as_bytes(), rundata_read);
    assert!(e.contains("unknown key '111"), "{e}");
}

/// A sweep whose run directory holds a control character (a NUL here) is refused as not a
/// plain path below the sweep, before a message could quote it raw.
#[test]
fn found_a_control_character_in_a_sweeps_run_directory() {
    let r = runs();
    let summary = std::fs::read_to_string(r.sweep.join("summary.json")).unwrap();
    let nul = summary.replacen("\"runs/D=0\"", "\"a\\u0000b/D=0\"", 1);
    assert_ne!(nul, summary);
    let e = error_with(&r.sweep, "summary.json", nul.as_bytes(), |d| {
        eyeshell_cli::charts::sweep_runs(d)
            .map(|_| ())
            .map_err(|e| e.to_string())
    });
    assert!(e.contains("points outside the sweep's runs"), "{e}");
    assert!(e.contains(r#"("a\0b/D=0")"#), "{e}");
}

/// A sweep naming a run directory of a kilobyte (a megabyte-long word in a longer hunt) put
/// it whole in the message: a sweep names its runs `runs/<name>` in at most about 100 bytes,
/// and a longer directory is refused, quoted short.
#[test]
fn found_a_sweeps_run_directory_of_a_kilobyte() {
    let r = runs();
    let summary = std::fs::read_to_string(r.sweep.join("summary.json")).unwrap();
    let long = summary.replacen(
        "\"runs/D=0\"",
        &format!("\"runs/{}/D=0\"", "1".repeat(1000)),
        1,
    );
    let e = error_with(&r.sweep, "summary.json", long.as_bytes(), |d| {
        eyeshell_cli::charts::sweep_runs(d)
            .map(|_| ())
            .map_err(|e| e.to_string())
    });
    assert!(
        e.contains("points outside the sweep's runs (\"runs/111"),
        "{e}"
    );
}

/// Twenty-six megabyte-long lines of commas took seconds: read_csv parsed the whole file
/// before checking the first row, which was wrong. It now stops at that row.
#[test]
fn found_a_wrong_row_stops_the_reading_there() {
    let r = runs();
    let fields = std::fs::read_to_string(r.solve.join("fields.csv")).unwrap();
    let commas = format!("{}\n", ",".repeat(1 << 20)).repeat(26);
    let text = fields.replacen('\n', &format!("\n{commas}"), 1);
    let e = error_with(&r.solve, "fields.csv", text.as_bytes(), rundata_read);
    assert!(
        e.ends_with("fields.csv: line 2: 1048577 values for 14 columns"),
        "{e}"
    );
}

/// JSON nested past serde_json's limit of 128 is an error naming the file, however deep;
/// nested below it, a value of the wrong type (nothing of ours recurses further).
#[test]
fn deep_json_is_an_error_naming_the_file() {
    let r = runs();
    let summary = std::fs::read_to_string(r.solve.join("summary.json")).unwrap();
    for (depth, needle) in [
        (100_000, "not valid JSON: recursion limit exceeded"),
        (120, "solver.nodes must be an integer"),
    ] {
        let nested = format!("{}{}", "[".repeat(depth), "]".repeat(depth));
        let text = summary.replacen(
            "\"solver.nodes\": 21",
            &format!("\"solver.nodes\": {nested}"),
            1,
        );
        assert_ne!(text, summary);
        let e = error_with(&r.solve, "summary.json", text.as_bytes(), rundata_read);
        assert!(e.contains(needle), "{depth}: {e:?}");
    }
}

/// A file cut at a line end, or inside its last number, read as a shorter run or a wrong
/// value: both are refused now, naming the file and the line.
#[test]
fn found_a_file_cut_short_read_as_a_shorter_run() {
    let r = runs();
    let fields = std::fs::read_to_string(r.solve.join("fields.csv")).unwrap();
    let lines: Vec<&str> = fields.lines().collect();
    let at_line_end = lines[..10].join("\n") + "\n";
    let e = error_with(&r.solve, "fields.csv", at_line_end.as_bytes(), rundata_read);
    assert!(
        e.contains(
            "fields.csv: line 10: the file ends after 9 rows, where summary.json's nodes is"
        ),
        "{e}"
    );
    let in_a_number = &fields[..fields.len() - 3];
    let e = error_with(&r.solve, "fields.csv", in_a_number.as_bytes(), rundata_read);
    let last = lines.len();
    assert!(
        e.contains(&format!(
            "fields.csv: line {last}: the file ends inside this line (cut short?)"
        )),
        "{e}"
    );
    // A snapshot cut at a line end is named, not the snapshots beside it.
    let snap = "snapshots/snapshot_00002_t0.200000.csv";
    let text = std::fs::read_to_string(r.grow.join(snap)).unwrap();
    let short = text.lines().take(5).collect::<Vec<_>>().join("\n") + "\n";
    let e = error_with(&r.grow, snap, short.as_bytes(), |d| {
        read_run(d).map(|_| ()).map_err(|e| e.to_string())
    });
    assert!(
        e.contains(&format!(
            "{snap}: line 5: the file ends after 4 rows, where the other snapshots have"
        )),
        "{e}"
    );
}
