//! `eyeshell export`: a finished (or partial) run directory as MATLAB v5 .mat or NumPy .npz.
//!
//! The run is read back from its files, so any run directory will do, including one that
//! failed or is still going: summary.json says what it is (a growth run has `status` /
//! `snapshots`), fields.csv or `snapshots/*.csv` give the values (every value in the CSV
//! files reads back to the same f64, so an export is bit-for-bit the run's values).
//!
//! Layouts:
//! - elastic solve: `OUT` is one file. In .mat, the struct `sol` like bvp4c's solution:
//!   `sol.x` (1×N, the material coordinate Σ of the nodes) and `sol.y` (5×N, rows κ, α_s,
//!   r, θ, Q), plus the other columns of fields.csv as further fields (`sol.sigma`, `sol.z`,
//!   `sol.s`, `sol.alpha_phi`, `sol.alpha_n`, `sol.h`, `sol.t_s`, `sol.t_phi`, 1×N each).
//!   In .npz the same names as arrays: `x` (N,), `y` (5, N) and the others (N,).
//! - growth run: `OUT` is a directory with one file per output time, named after its
//!   snapshot (`snapshot_00002_t0.200000.mat` / `.npz`). Each holds the row vectors (1×N)
//!   h, s, z, r, sigma, rho, zeta, alpha_s, alpha_phi, alpha_n, eta, z_retina, r_retina,
//!   `time` (1×1) and, beyond the published scripts' variables, `Sigma` (1×N, the material
//!   coordinate). In .npz the vectors are 1-D and `time` is 0-D.

use std::fs;
use std::path::{Path, PathBuf};

use super::mat::{self, MatValue};
use super::npz::{self, NpyArray};
pub use eyeshell::rundir::read::{
    bad, is_run_dir, read_csv, read_run, ReadError as ExportError, Run, RunSnapshot, Table,
    GROWTH_VARS,
};
use eyeshell::rundir::AtomicDir;

/// The rows of `sol.y`, in order (bvp4c's unknowns of the published scripts).
pub const Y_ROWS: [&str; 5] = ["kappa", "alpha_s", "r", "theta", "Q"];
/// The further fields of an elastic export, beside `x` and `y`.
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

fn failed(message: impl Into<String>) -> ExportError {
    ExportError {
        bad_input: false,
        message: message.into(),
    }
}

fn col(table: &Table, name: &str) -> Vec<f64> {
    table.column(name).unwrap_or_default()
}

/// The variables of an elastic export as a .mat file: the struct `sol`.
pub fn elastic_mat_vars(table: &Table) -> Vec<(String, MatValue)> {
    let mut fields = vec![
        ("x".to_string(), MatValue::row(&col(table, "Sigma"))),
        (
            "y".to_string(),
            MatValue::from_rows(&Y_ROWS.map(|c| col(table, c))),
        ),
    ];
    for c in ELASTIC_EXTRA {
        if let Some(v) = table.column(c) {
            fields.push((c.to_string(), MatValue::row(&v)));
        }
    }
    vec![("sol".to_string(), MatValue::Struct(fields))]
}

/// The variables of one growth snapshot as a .mat file.
pub fn growth_mat_vars(s: &RunSnapshot) -> Vec<(String, MatValue)> {
    let mut vars = Vec::new();
    for c in GROWTH_VARS {
        vars.push((c.to_string(), MatValue::row(&col(&s.table, c))));
        if c == "eta" {
            vars.push(("time".to_string(), MatValue::scalar(s.t)));
        }
    }
    vars
}

/// The arrays of an elastic export as a .npz file.
pub fn elastic_npz_arrays(table: &Table) -> Vec<(String, NpyArray)> {
    let mut arrays = vec![
        ("x".to_string(), NpyArray::vector(&col(table, "Sigma"))),
        (
            "y".to_string(),
            NpyArray::from_rows(&Y_ROWS.map(|c| col(table, c))),
        ),
    ];
    for c in ELASTIC_EXTRA {
        if let Some(v) = table.column(c) {
            arrays.push((c.to_string(), NpyArray::vector(&v)));
        }
    }
    arrays
}

/// The arrays of one growth snapshot as a .npz file.
pub fn growth_npz_arrays(s: &RunSnapshot) -> Vec<(String, NpyArray)> {
    let mut arrays = Vec::new();
    for c in GROWTH_VARS {
        arrays.push((c.to_string(), NpyArray::vector(&col(&s.table, c))));
        if c == "eta" {
            arrays.push(("time".to_string(), NpyArray::scalar(s.t)));
        }
    }
    arrays
}

/// The export formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// MATLAB v5 .mat, each variable `miCOMPRESSED` with `compress`.
    Mat { compress: bool },
    /// NumPy .npz.
    Npz,
}

impl Format {
    fn extension(self) -> &'static str {
        match self {
            Format::Mat { .. } => "mat",
            Format::Npz => "npz",
        }
    }
}

/// What an export wrote.
#[derive(Clone, Debug)]
pub struct Exported {
    /// The file (elastic) or directory (growth) written.
    pub path: PathBuf,
    /// The files written, in order.
    pub files: Vec<PathBuf>,
    /// Number of nodes.
    pub nodes: usize,
    pub growth: bool,
}

fn write_one(
    path: &Path,
    format: Format,
    mat_vars: impl FnOnce() -> Vec<(String, MatValue)>,
    npz_arrays: impl FnOnce() -> Vec<(String, NpyArray)>,
) -> Result<(), ExportError> {
    match format {
        Format::Mat { compress } => {
            mat::write(path, &mat_vars(), compress).map_err(|e| failed(e.to_string()))
        }
        Format::Npz => npz::write(path, &npz_arrays()).map_err(|e| failed(e.to_string())),
    }
}

/// Export the run in `run_dir` to `out` (a file for an elastic solve, a directory for a
/// growth run); nothing is half-written.
pub fn export(run_dir: &Path, out: &Path, format: Format) -> Result<Exported, ExportError> {
    let run = read_run(run_dir)?;
    match run {
        Run::Elastic { table, .. } => {
            if out.is_dir() {
                return Err(bad(format!(
                    "{}: is a directory; an elastic solve exports to one file (e.g. out.{})",
                    out.display(),
                    format.extension()
                )));
            }
            if out.file_name().is_none() {
                return Err(bad(format!(
                    "{}: the output path has no file name",
                    out.display()
                )));
            }
            if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
                if !parent.is_dir() {
                    return Err(bad(format!(
                        "{}: the directory {} does not exist",
                        out.display(),
                        parent.display()
                    )));
                }
            }
            write_one(
                out,
                format,
                || elastic_mat_vars(&table),
                || elastic_npz_arrays(&table),
            )?;
            Ok(Exported {
                path: out.to_path_buf(),
                files: vec![out.to_path_buf()],
                nodes: table.rows.len(),
                growth: false,
            })
        }
        Run::Growth(snapshots) => {
            let dir = ExportDir::create(out, format.extension())?;
            let mut files = Vec::new();
            for s in &snapshots {
                let stem = s
                    .file
                    .file_stem()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned();
                let name = format!("{stem}.{}", format.extension());
                write_one(
                    &dir.file(&name),
                    format,
                    || growth_mat_vars(s),
                    || growth_npz_arrays(s),
                )?;
                files.push(out.join(name));
            }
            let path = dir.commit()?;
            Ok(Exported {
                path,
                files,
                nodes: snapshots.first().map_or(0, |s| s.table.rows.len()),
                growth: true,
            })
        }
    }
}

/// An export directory written into a temporary sibling and renamed into place (the
/// mechanism is [`AtomicDir`]'s). The target may be absent, an empty directory or a
/// previous export (a directory of `.EXT` files only); anything else is refused.
struct ExportDir {
    dir: AtomicDir,
}

impl ExportDir {
    fn create(target: &Path, ext: &str) -> Result<ExportDir, ExportError> {
        if target.file_name().is_none() {
            return Err(bad(format!(
                "{}: the output path has no file name",
                target.display()
            )));
        }
        Self::check(target, ext)?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !parent.is_dir() {
            return Err(bad(format!(
                "{}: the directory {} does not exist",
                target.display(),
                parent.display()
            )));
        }
        let dir = AtomicDir::create(target).map_err(|e| failed(e.to_string()))?;
        Ok(ExportDir { dir })
    }

    /// The path of `name` in the directory being written.
    fn file(&self, name: &str) -> PathBuf {
        self.dir.file(name)
    }

    /// Absent, empty or a previous export: fine. Anything else: refused.
    fn check(target: &Path, ext: &str) -> Result<(), ExportError> {
        if !target.exists() {
            return Ok(());
        }
        if !target.is_dir() {
            return Err(bad(format!(
                "{}: exists and is not a directory; a growth run exports to a directory of .{ext} files",
                target.display()
            )));
        }
        let entries =
            fs::read_dir(target).map_err(|e| bad(format!("{}: {e}", target.display())))?;
        for e in entries.filter_map(|e| e.ok()) {
            let p = e.path();
            if !(p.is_file() && p.extension().is_some_and(|x| x == ext)) {
                return Err(bad(format!(
                    "{}: exists and holds more than .{ext} files ({}); refusing to replace it",
                    target.display(),
                    e.file_name().to_string_lossy()
                )));
            }
        }
        Ok(())
    }

    /// Check the target again (it may have changed meanwhile), then move the export into
    /// place.
    fn commit(self) -> Result<PathBuf, ExportError> {
        if self.dir.target().exists() {
            let ext = self
                .dir
                .path()
                .read_dir()
                .ok()
                .and_then(|mut d| d.next())
                .and_then(|e| e.ok())
                .and_then(|e| {
                    e.path()
                        .extension()
                        .map(|x| x.to_string_lossy().into_owned())
                })
                .unwrap_or_default();
            if !ext.is_empty() {
                Self::check(self.dir.target(), &ext)?;
            }
        }
        self.dir.commit().map_err(|e| failed(e.to_string()))
    }
}
