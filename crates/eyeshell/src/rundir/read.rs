//! Reading a run directory back: its CSV tables, and whether it is an elastic solve or a
//! growth run (with the output time of every snapshot).

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use super::growth::{SERIES_FILE, SNAPSHOT_DIR};
use super::summary::Summary;
use super::{FIELDS_FILE, SUMMARY_FILE};

pub use super::table::{read_csv, Table};

/// The row vectors of a growth export (the published scripts' variables, then Σ); `time`
/// is written after `eta`.
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

/// A run directory that cannot be read (or, for the exporters, written): one line naming the file. `bad_input`
/// for the user's mistakes (exit 2), otherwise a failure to write (exit 1).
#[derive(Clone, Debug)]
pub struct ReadError {
    pub bad_input: bool,
    pub message: String,
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for ReadError {}

pub fn bad(message: impl Into<String>) -> ReadError {
    ReadError {
        bad_input: true,
        message: message.into(),
    }
}

/// The most bytes a CSV run file may have: a snapshot at `mesh::MAX_NODES` nodes is about
/// 500 MB, history.csv at its most rows about 120 MB.
pub const MAX_CSV_BYTES: u64 = 1 << 30;
/// The most bytes summary.json may have: a sweep of `MAX_RUNS` runs is about 10 MB.
pub const MAX_SUMMARY_BYTES: u64 = 1 << 28;

/// The text of the file `path`, refused beyond `limit` bytes (a file that is not what it
/// says, or a link to a device that never ends, must not fill the memory). Errors name it.
pub fn read_text(path: &Path, limit: u64) -> Result<String, ReadError> {
    use std::io::Read;
    let fail = |e: std::io::Error| bad(format!("{}: {e}", path.display()));
    let mut bytes = Vec::new();
    fs::File::open(path)
        .and_then(|f| f.take(limit + 1).read_to_end(&mut bytes))
        .map_err(fail)?;
    if bytes.len() as u64 > limit {
        return Err(bad(format!(
            "{}: more than {limit} bytes, larger than any file eyeshell writes",
            path.display()
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        bad(format!(
            "{}: not UTF-8 text (an invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })
}

/// One row of sensitivities.csv read back: at time `t`, the derivatives of the run's
/// measures with respect to `parameter` (a scene key), in the order of
/// [`super::growth::SENSITIVITY_COLUMNS`] after the first two.
#[derive(Clone, Debug, PartialEq)]
pub struct SensitivityRecord {
    pub t: f64,
    pub parameter: String,
    pub values: [f64; 4],
}

/// sensitivities.csv of the growth run `dir` (`grow --sensitivities`), None without the
/// file. Read with the size bound of every CSV run file; the header must be eyeshell's and
/// every row as many cells, numbers where numbers belong. Errors (bad input) name the file and
/// the line.
pub fn read_sensitivities(dir: &Path) -> Result<Option<Vec<SensitivityRecord>>, ReadError> {
    use super::growth::{with_age_column, SENSITIVITIES_FILE, SENSITIVITY_COLUMNS};
    let path = dir.join(SENSITIVITIES_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let records = super::table::read_records(&path)?;
    // A scene with ages ends the file in an age column: read it too (the age follows from t
    // and the scene, so it is not kept).
    let columns = records.header.as_ref().and_then(|h| {
        [false, true]
            .into_iter()
            .map(|ages| with_age_column(&SENSITIVITY_COLUMNS, ages))
            .find(|c| h.iter().map(String::as_str).eq(c.iter().copied()))
    });
    let Some(columns) = columns else {
        return Err(bad(format!(
            "{}: the header is not {} (with a final age column in a scene with time.unit)",
            path.display(),
            SENSITIVITY_COLUMNS.join(",")
        )));
    };
    let mut rows = Vec::new();
    for r in records.iter() {
        let at = |what: String| bad(format!("{}: line {}: {what}", path.display(), r.line));
        if r.cells.len() != columns.len() {
            return Err(at(format!(
                "{} cells, not {}",
                r.cells.len(),
                columns.len()
            )));
        }
        let num = |c: usize| {
            r.cells[c].parse::<f64>().map_err(|_| {
                at(format!(
                    "{:?} is not a number",
                    crate::text::excerpt(&r.cells[c], 40)
                ))
            })
        };
        rows.push(SensitivityRecord {
            t: num(0)?,
            parameter: r.cells[1].to_string(),
            values: [num(2)?, num(3)?, num(4)?, num(5)?],
        });
    }
    Ok(Some(rows))
}

/// One output time of a growth run, read back.
#[derive(Clone, Debug)]
pub struct RunSnapshot {
    /// Output time.
    pub t: f64,
    /// The snapshot CSV file.
    pub file: PathBuf,
    pub table: Table,
}

/// A run directory read back.
#[derive(Clone, Debug)]
pub enum Run {
    /// `eyeshell solve`: fields.csv.
    Elastic { file: PathBuf, table: Table },
    /// `eyeshell grow`: the snapshots written so far, in time order.
    Growth(Vec<RunSnapshot>),
}

/// Does `dir` look like an eyeshell run directory (it holds summary.json)?
pub fn is_run_dir(dir: &Path) -> bool {
    dir.join(SUMMARY_FILE).is_file()
}

/// Read the run directory `dir`: summary.json says whether it is a growth run.
pub fn read_run(dir: &Path) -> Result<Run, ReadError> {
    if !dir.is_dir() {
        return Err(bad(format!("{}: not a directory", dir.display())));
    }
    read_run_with(dir, &Summary::read(dir)?)
}

/// Read the run directory `dir` whose summary.json is `summary`.
pub fn read_run_with(dir: &Path, summary: &Summary) -> Result<Run, ReadError> {
    let growth = match summary {
        Summary::Elastic(_) => None,
        Summary::Growth(g) => Some(g),
        other => {
            return Err(bad(format!(
                "{}: an eyeshell {} directory, not a run directory (of `eyeshell solve` or `eyeshell grow`)",
                dir.display(),
                other.kind()
            )))
        }
    };
    let Some(growth) = growth else {
        let file = dir.join(FIELDS_FILE);
        let table = read_csv(&file)?;
        check_columns(&file, &table, &crate::bvp::COLUMNS)?;
        if let Summary::Elastic(e) = summary {
            check_nodes(&file, &table, e.stats.nodes, "summary.json's nodes is")?;
        }
        return Ok(Run::Elastic { file, table });
    };
    // The times: summary.json's list (exact), else series.csv row k, else the file name.
    let mut times: BTreeMap<String, f64> = BTreeMap::new();
    for s in growth
        .snapshots
        .iter()
        .filter(|s| !s.file.is_empty() && !s.t.is_nan())
    {
        let name = Path::new(&s.file)
            .file_name()
            .unwrap_or_default()
            .to_string_lossy();
        times.insert(name.into_owned(), s.t);
    }
    let series: Vec<f64> = read_csv(&dir.join(SERIES_FILE))
        .ok()
        .and_then(|t| t.column("t"))
        .unwrap_or_default();
    let snap_dir = dir.join(SNAPSHOT_DIR);
    let entries =
        fs::read_dir(&snap_dir).map_err(|e| bad(format!("{}: {e}", snap_dir.display())))?;
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("snapshot_") && n.ends_with(".csv"))
        .collect();
    names.sort();
    if names.is_empty() {
        return Err(bad(format!(
            "{}: the growth run has no snapshot yet",
            snap_dir.display()
        )));
    }
    let mut snapshots = Vec::with_capacity(names.len());
    for name in names {
        let file = snap_dir.join(&name);
        let k: Option<usize> = name
            .strip_prefix("snapshot_")
            .and_then(|r| r.split('_').next())
            .and_then(|k| k.parse().ok());
        let from_name = name
            .rsplit_once("_t")
            .and_then(|(_, t)| t.strip_suffix(".csv"))
            .and_then(|t| t.parse::<f64>().ok());
        let t = times
            .get(&name)
            .copied()
            .or_else(|| k.and_then(|k| series.get(k).copied()))
            .or(from_name)
            .ok_or_else(|| bad(format!("{}: cannot tell its output time", file.display())))?;
        let table = read_csv(&file)?;
        check_columns(&file, &table, &GROWTH_VARS)?;
        snapshots.push(RunSnapshot { t, file, table });
    }
    check_snapshot_nodes(&snapshots)?;
    Ok(Run::Growth(snapshots))
}

fn check_columns(file: &Path, table: &Table, needed: &[&str]) -> Result<(), ReadError> {
    for c in needed {
        if !table.columns.iter().any(|x| x == c) {
            return Err(bad(format!("{}: no column {c:?}", file.display())));
        }
    }
    Ok(())
}

/// A table of one row per node has `nodes` rows (0: not known), as `expected` says ("the
/// other snapshots have"): with fewer the file was cut short (at a line end, or a line
/// would be broken), with more it was added to. Line numbers count the header as line 1.
fn check_nodes(file: &Path, table: &Table, nodes: usize, expected: &str) -> Result<(), ReadError> {
    let rows = table.rows.len();
    let problem = if nodes == 0 || rows == nodes {
        return Ok(());
    } else if rows < nodes {
        format!("line {}: the file ends after {rows} rows, where {expected} {nodes} (one row per node): cut short?", rows + 1)
    } else {
        format!(
            "line {}: {rows} rows, where {expected} {nodes} (one row per node)",
            nodes + 2
        )
    };
    Err(bad(format!("{}: {problem}", file.display())))
}

/// Every snapshot of a growth run has one row per node of its one mesh: a snapshot with
/// another number of rows than most of them (than the first, when no count is the most
/// common) was cut short or added to, and is named.
fn check_snapshot_nodes(snapshots: &[RunSnapshot]) -> Result<(), ReadError> {
    let Some(first) = snapshots.first() else {
        return Ok(());
    };
    let mut counts: BTreeMap<usize, usize> = BTreeMap::new();
    for s in snapshots {
        *counts.entry(s.table.rows.len()).or_default() += 1;
    }
    let first_rows = first.table.rows.len();
    let nodes = counts
        .iter()
        .max_by_key(|&(&rows, &n)| (n, rows == first_rows))
        .map_or(first_rows, |(&rows, _)| rows);
    for s in snapshots {
        check_nodes(&s.file, &s.table, nodes, "the other snapshots have")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rundir::summary::{StudySummary, SweepSummary};

    /// sensitivities.csv read back: the rows as written, None without the file, and a
    /// header, a row's width or a cell that is not eyeshell's refused naming file and line.
    #[test]
    fn sensitivities_read_back_and_bad_ones_refused() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(read_sensitivities(dir.path()).unwrap(), None);
        let path = dir.path().join("sensitivities.csv");
        let header = "t,parameter,d_axial_length,d_equatorial_radius,d_retina_minus_blue,scaled_axial_length\n";
        fs::write(&path, format!("{header}0.5,growth.eta0,1.5,-2,3e-3,0.25\n")).unwrap();
        assert_eq!(
            read_sensitivities(dir.path()).unwrap(),
            Some(vec![SensitivityRecord {
                t: 0.5,
                parameter: "growth.eta0".into(),
                values: [1.5, -2.0, 3e-3, 0.25],
            }])
        );
        for (text, says) in [
            (
                "t,parameter\n".to_string(),
                "the header is not t,parameter,",
            ),
            (
                format!("{header}0.5,growth.eta0,1,2,3\n"),
                "line 2: 5 cells, not 6",
            ),
            (
                format!("{header}0.5,growth.eta0,1,2,3,x\n"),
                "line 2: \"x\" is not a number",
            ),
        ] {
            fs::write(&path, text).unwrap();
            let e = read_sensitivities(dir.path()).unwrap_err().to_string();
            assert!(e.contains("sensitivities.csv") && e.contains(says), "{e}");
        }
    }

    #[test]
    fn only_runs_read_as_runs() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_run(&dir.path().join("none")).unwrap_err();
        assert!(
            e.bad_input && e.message.ends_with("none: not a directory"),
            "{e}"
        );
        let e = read_run(dir.path()).unwrap_err();
        assert!(e.message.contains("not an eyeshell run directory"), "{e}");
        // A sweep has a status too, but it is not a growth run; nor is a study a solve.
        for summary in [
            Summary::Sweep(SweepSummary {
                sweep: "s".into(),
                status: "ok".into(),
                ..SweepSummary::default()
            }),
            Summary::Study(StudySummary::default()),
        ] {
            summary.write(dir.path()).unwrap();
            let e = read_run(dir.path()).unwrap_err();
            assert!(
                e.bad_input && e.message.contains("not a run directory"),
                "{e}"
            );
        }
        // A growth run that has no snapshot yet says so.
        fs::write(dir.path().join(SUMMARY_FILE), "{\"status\": \"running\"}").unwrap();
        fs::create_dir(dir.path().join(SNAPSHOT_DIR)).unwrap();
        let e = read_run(dir.path()).unwrap_err();
        assert!(e.message.contains("has no snapshot yet"), "{e}");
    }
}
