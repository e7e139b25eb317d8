//! Run directories: `fields.csv`, `at.csv` and `summary.json` in an output directory that
//! appears whole or not at all, and reading them back.
//!
//! - [`atomic`]: the one atomic writer of files and directories;
//! - [`summary`]: summary.json, typed ([`Summary`]);
//! - [`table`]: the CSV files, written and read through the `csv` crate;
//! - [`number`]: one number in them, as Python's `repr` writes it;
//! - [`growth`]: a growth run's directory, written as the results come;
//! - [`read`], [`rundata`]: a run directory read back, for export and for figures.
//!
//! - [`owner`]: which targets eyeshell may replace (its `.eyeshell` marker), and the two
//!   writers of output directories, [`OutputDir`] (whole or not at all) and [`OwnedDir`]
//!   (in place, as results come);
//! - [`lock`]: one writer per target.
//!
//! A run writes into a temporary sibling of the target (`.NAME.tmp-<pid>`), then renames it
//! into place. An existing target is replaced only if it is an eyeshell output (it holds
//! eyeshell's marker, and nothing eyeshell did not write) or an empty directory; anything
//! else is refused. On any error, and when an [`OutputDir`] is dropped without
//! [`OutputDir::commit`], the temporary directory is removed.
//!
//! A growth run ([`growth::GrowthWriter`]) writes in place instead, as its results come.

pub mod atomic;
pub mod growth;
pub mod lock;
pub use crate::number;
pub mod owner;
pub mod read;
pub mod record;
pub mod run;
pub mod rundata;
pub mod summary;
pub mod table;

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::bvp::{FieldRow, COLUMNS};

pub use crate::number::{format_value, push_value};
pub use atomic::{write_atomic, write_atomic_unsynced, AtomicDir};
pub use growth::GrowthWriter;
pub use owner::{check_file, check_target, Marker, OutputDir, OwnedDir, MARKER_FILE};
pub use summary::Summary;

/// The summary of a run, sweep or study.
pub const SUMMARY_FILE: &str = "summary.json";
/// Every field on every node.
pub const FIELDS_FILE: &str = "fields.csv";
/// Every field at the material points asked for with `--at`.
pub const AT_FILE: &str = "at.csv";

/// Failure to write results. Display is one line naming the path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: exists and is not an eyeshell output directory (it has no {MARKER_FILE} marker); refusing to overwrite it", path.display())]
    Refused { path: PathBuf },
    #[error("{}: holds {entry:?}, which eyeshell did not write; refusing to replace the directory (move that out first)", path.display())]
    Foreign { path: PathBuf, entry: String },
    #[error("{}: holds a {found} output, not a {wanted}; refusing to add to it", path.display())]
    OtherKind {
        path: PathBuf,
        found: String,
        wanted: String,
    },
    #[error("{}: holds {} {found} output; refusing to replace it with {} {wanted} output, which replaces only an earlier {wanted} output or an empty directory (choose another output)", path.display(), article(found), article(wanted))]
    NotItsKind {
        path: PathBuf,
        found: String,
        wanted: String,
    },
    #[error("{}: {how} {}, which this {kind} is made from; refusing to write there (choose an output outside it)", path.display(), input.display())]
    Input {
        path: PathBuf,
        /// "is", "holds" or "is inside".
        how: &'static str,
        input: PathBuf,
        kind: String,
    },
    #[error("{}: another eyeshell process{} is writing it; wait for it to finish or choose another output", path.display(), pid.map(|p| format!(" (pid {p})")).unwrap_or_default())]
    Busy { path: PathBuf, pid: Option<u32> },
    #[error("{}: exists and was not written by eyeshell; refusing to overwrite it ({} replaces it)", path.display(), crate::text::advice(&crate::text::Advice::Force))]
    NotOurFile { path: PathBuf },
    #[error("{}: is a file of the eyeshell output {}; refusing to overwrite it, even with {} (choose another file)", path.display(), dir.display(), crate::text::advice(&crate::text::Advice::Force))]
    PartOfOutput { path: PathBuf, dir: PathBuf },
    #[error("{}: exists and is not a regular file; refusing to overwrite it", path.display())]
    NotAFile { path: PathBuf },
    #[error("{}: the output path has no file name", path.display())]
    NoName { path: PathBuf },
    #[error("{}: a parent of the output path is not a directory", path.display())]
    NoParent { path: PathBuf },
    #[error("{}: the output path climbs (..) out of a directory that does not exist; give it without the ..", path.display())]
    Unresolved { path: PathBuf },
}

/// "a" or "an", for a kind of output in a message.
fn article(word: &str) -> &'static str {
    match word.chars().next() {
        Some('a' | 'e' | 'i' | 'o' | 'u') => "an",
        _ => "a",
    }
}

impl OutputError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// True when the error is the user's (a target that may not be overwritten), not I/O.
    pub fn is_refusal(&self) -> bool {
        !matches!(self, OutputError::Io { .. })
    }
}

/// A CSV table of numbers: the header, then one line per row of [`push_value`]s (numbers
/// never need quoting), as the csv writer would write it, without a String per value.
pub fn numeric_csv<'a, R, C>(header: impl IntoIterator<Item = &'a str>, rows: R) -> Vec<u8>
where
    R: IntoIterator<Item = C>,
    C: IntoIterator<Item = f64>,
{
    let mut out = Vec::new();
    for (k, name) in header.into_iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        out.extend_from_slice(name.as_bytes());
    }
    out.push(b'\n');
    for row in rows {
        for (k, x) in row.into_iter().enumerate() {
            if k > 0 {
                out.push(b',');
            }
            push_value(&mut out, x);
        }
        out.push(b'\n');
    }
    out
}

/// The CSV header: the [`COLUMNS`] joined by commas.
pub fn csv_header() -> String {
    COLUMNS.join(",")
}

/// Write `rows` as CSV: the header, then one line per row, every value round-trip exact.
pub fn write_fields_csv(path: &Path, rows: &[FieldRow]) -> Result<(), OutputError> {
    let write = || -> std::io::Result<()> {
        let file = fs::File::create(path)?;
        let mut w = BufWriter::new(file);
        w.write_all(&numeric_csv(COLUMNS, rows.iter().map(|r| r.values())))?;
        w.flush()
    };
    write().map_err(|e| OutputError::io(path, e))
}

/// The SUNDIALS version the binary is linked against, if the sundials layer reports it.
pub fn sundials_version() -> Option<String> {
    Some(eyeshell_sundials::version())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvp::SolveStats;

    use crate::scene::Scene;

    /// The time of writing a cohort's tables: 2,000 eyes' sweep.csv rows (14 cells, 8 of
    /// them numbers, through `format_value` and the csv writer, as sweep.csv is written)
    /// and 2,000 × 5 rows of series (7 numbers each, through `numeric_csv`), best of 20.
    /// `cargo test --release -p eyeshell --lib -- --ignored --nocapture cohort_tables`
    #[test]
    #[ignore = "a timing, run by hand"]
    fn cohort_tables_write_time() {
        let value =
            |i: usize, j: usize| (i as f64 * 0.731 + j as f64).sin() * 10f64.powi(j as i32 % 5);
        let mut best = (f64::INFINITY, f64::INFINITY);
        for _ in 0..20 {
            let start = std::time::Instant::now();
            let rows = (0..2000).map(|i| {
                let mut cells = vec![format!("run_{i:04}"), "ok".to_string(), "grow".to_string()];
                cells.extend((0..8).map(|j| format_value(value(i, j))));
                cells.extend(["myopic".to_string(), "12".to_string(), String::new()]);
                cells
            });
            let table = table::csv_bytes(["h"; 14], rows, table::QuoteStyle::Necessary).unwrap();
            let a = start.elapsed().as_secs_f64();
            let start = std::time::Instant::now();
            let series = numeric_csv(
                ["h"; 7],
                (0..10_000).map(|i| (0..7).map(move |j| value(i, j))),
            );
            let b = start.elapsed().as_secs_f64();
            assert!(table.len() > 100_000 && series.len() > 500_000);
            best = (best.0.min(a), best.1.min(b));
        }
        eprintln!(
            "cohort tables: sweep.csv of 2,000 eyes {:.2} ms, 10,000 series rows {:.2} ms",
            best.0 * 1e3,
            best.1 * 1e3
        );
    }

    fn row(k: f64) -> FieldRow {
        FieldRow {
            sigma_ref: k,
            sigma: k / 3.0,
            kappa: 0.1 + k,
            alpha_s: 1.0136216901111,
            r: 1e-300,
            theta: -2.5e17,
            ..FieldRow::default()
        }
    }

    #[test]
    fn csv_has_the_header_and_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.csv");
        let rows: Vec<FieldRow> = (0..5).map(|k| row(k as f64 * 0.7)).collect();
        write_fields_csv(&path, &rows).unwrap();
        let text = fs::read_to_string(&path).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), COLUMNS.join(","));
        for r in &rows {
            let back: Vec<f64> = lines
                .next()
                .unwrap()
                .split(',')
                .map(|v| v.parse().unwrap())
                .collect();
            assert_eq!(back, r.values().to_vec());
        }
        assert!(lines.next().is_none());
    }

    #[test]
    fn summary_has_every_stat_and_parameter() {
        let stats = SolveStats {
            newton_iterations: 7,
            nodes: 509,
            residual_norm: 1e-12,
            ..SolveStats::default()
        };
        let v = serde_json::to_value(Summary::Elastic(summary::ElasticSummary::new(
            &Scene::default(),
            &stats,
        )))
        .unwrap();
        for k in [
            "newton_iterations",
            "residual_evaluations",
            "jacobian_evaluations",
            "residual_norm",
            "first_integral_max",
            "nodes",
            "uniform_nodes",
            "breakpoint_nodes",
            "pole_nodes",
            "cornea_alpha",
            "continuation_stages",
            "wall_seconds",
            "scheme",
            "linear_solver",
            "epsilon",
            "sundials_version",
        ] {
            assert!(v.get(k).is_some(), "missing {k}");
        }
        assert_eq!(v["newton_iterations"], 7);
        assert_eq!(v["scheme"], "hermite-simpson");
        assert_eq!(v["parameters"]["pressure.dP"], 2.0);
        assert_eq!(v["parameters"]["solver.nodes"], 501);
        // Every elastic parameter that has a value; the growth keys only when the scene grows.
        let n = v["parameters"].as_object().unwrap().len();
        let unset = crate::scene::KeyValue::Unset;
        assert_eq!(
            n,
            crate::scene::KEYS
                .iter()
                .filter(|k| k.is_parameter() && !k.growth)
                .filter(|k| k.get(&Scene::default()) != unset)
                .count()
        );
        assert!(v["parameters"].get("solver.max_seconds").is_none());
        assert!(v["parameters"].get("growth.eta0").is_none());
    }

    #[test]
    fn output_appears_whole_and_replaces_previous_outputs_only() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        // Fresh target.
        let out = OutputDir::create(&target, "solve", &[]).unwrap();
        fs::write(out.file(SUMMARY_FILE), "{}").unwrap();
        fs::write(out.file("old-only"), "x").unwrap();
        assert!(!target.exists());
        out.commit().unwrap();
        assert!(target.join(SUMMARY_FILE).is_file());
        // A previous output is replaced wholesale.
        let out = OutputDir::create(&target, "solve", &[]).unwrap();
        fs::write(out.file(SUMMARY_FILE), "{\"new\":1}").unwrap();
        out.commit().unwrap();
        assert!(!target.join("old-only").exists());
        assert_eq!(
            fs::read_to_string(target.join(SUMMARY_FILE)).unwrap(),
            "{\"new\":1}"
        );
        // Nothing is left next to it.
        let names: Vec<_> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("out")]);
    }

    #[test]
    fn dropped_output_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        {
            let out = OutputDir::create(&target, "solve", &[]).unwrap();
            fs::write(out.file(FIELDS_FILE), "partial").unwrap();
        }
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn foreign_directories_and_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("data");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("precious.txt"), "keep").unwrap();
        let e = OutputDir::create(&target, "solve", &[]).unwrap_err();
        assert!(e.is_refusal());
        assert!(
            e.to_string().contains("data") && e.to_string().contains("refusing"),
            "{e}"
        );
        assert_eq!(
            fs::read_to_string(target.join("precious.txt")).unwrap(),
            "keep"
        );
        let file = dir.path().join("file");
        fs::write(&file, "x").unwrap();
        assert!(OutputDir::create(&file, "solve", &[])
            .unwrap_err()
            .is_refusal());
        // A parent that is a file is refused; missing parents are created, and removed
        // again when the run does not commit.
        assert!(OutputDir::create(&file.join("out"), "solve", &[])
            .unwrap_err()
            .is_refusal());
        let nested = OutputDir::create(&dir.path().join("no/such/out"), "solve", &[]).unwrap();
        assert!(dir.path().join("no/such").is_dir());
        drop(nested);
        assert!(!dir.path().join("no").exists());
        // An empty directory is fine.
        let empty = dir.path().join("empty");
        fs::create_dir(&empty).unwrap();
        let out = OutputDir::create(&empty, "solve", &[]).unwrap();
        fs::write(out.file(SUMMARY_FILE), "{}").unwrap();
        out.commit().unwrap();
        assert!(empty.join(SUMMARY_FILE).is_file());
    }
}
