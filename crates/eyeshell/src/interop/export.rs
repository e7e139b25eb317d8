//! `eyeshell export`: a finished (or partial) run directory as MATLAB v5 .mat or NumPy .npz.
//!
//! The run is read back from its files, so any run directory will do, including one that
//! failed or is still going: summary.json says what it is (a growth run has `status` /
//! `snapshots`), fields.csv or `snapshots/*.csv` give the values (every value in the CSV
//! files reads back to the same f64, so an export is bit-for-bit the run's values).
//!
//! Layouts:
//! - elastic solve: `OUT` is one file. In .mat, the struct `sol` shaped like bvp4c's
//!   solution: `sol.solver` ('bvp4c'), `sol.x` (1×N, the material coordinate Σ of the
//!   nodes, each interface twice, as bvp4c holds a multipoint problem's), `sol.y` (5×N,
//!   rows κ, α_s, r, θ, Q), `sol.yp` (5×N, their d/dΣ: f(x, y) on the differential rows,
//!   α_s's derivative along the same flow: [`bvp4c_form`]), `sol.stats` (nmeshpoints, maxres, nODEevals, nBCevals: [`stats_struct`]), plus the other
//!   columns of fields.csv as further fields (`sol.sigma`, `sol.z`, `sol.s`,
//!   `sol.alpha_phi`, `sol.alpha_n`, `sol.h`, `sol.t_s`, `sol.t_phi`, 1×N each). In .npz the
//!   same names as arrays: `x` (N,), `y` and `yp` (5, N) and the others (N,).
//! - growth run: `OUT` is a directory with one file per output time, named after its
//!   snapshot (`snapshot_00002_t0.200000.mat` / `.npz`). Each holds the row vectors (1×N)
//!   h, s, z, r, sigma, rho, zeta, alpha_s, alpha_phi, alpha_n, eta, z_retina, r_retina,
//!   `time` (1×1) and, beyond the published scripts' variables, `Sigma` (1×N, the material
//!   coordinate). In .npz the vectors are 1-D and `time` is 0-D. A .mat export also holds
//!   `series.mat` and, when the run has history.csv, `history.mat`: series.csv's and
//!   history.csv's columns (the table of outputs', [`crate::outputs`]), each numeric one a
//!   row vector (1×R) named after its column, and `class` a char row of the rows' classes
//!   separated by commas (MATLAB: `strsplit(class, ',')`).

use std::path::{Path, PathBuf};

use super::mat::{self, MatValue};
use super::npz::{self, NpyArray};
pub use crate::rundir::read::{
    bad, is_run_dir, read_csv, read_run, ReadError as ExportError, Run, RunSnapshot, Table,
    GROWTH_VARS,
};
use crate::rundir::{self, Marker, OutputDir, OutputError, MARKER_FILE};

/// The rows of `sol.y`, in order (bvp4c's unknowns of the published scripts).
pub use crate::bvp::bvp4c::Y_ROWS;
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

/// What an elastic export needs beyond fields.csv: the scene's parameters (yp = f(x, y)
/// and the interfaces come from its equations and data) and the solver's statistics (for
/// `sol.stats`), from the run's summary.json.
#[derive(Clone, Debug, Default)]
pub struct ElasticExtras {
    /// The scene solved, or why it cannot be read (then nothing is exported: without it
    /// yp would not be f).
    pub params: Option<Result<crate::model::params::Params, ExportError>>,
    pub stats: Option<crate::bvp::SolveStats>,
    /// The file the fields come from, named when they cannot be evaluated.
    pub fields_file: Option<PathBuf>,
}

impl ElasticExtras {
    /// Read from the run directory; an old or partial summary gives no stats.
    pub fn of(run_dir: &Path) -> ElasticExtras {
        let stats = match rundir::Summary::read(run_dir) {
            Ok(rundir::Summary::Elastic(e)) => Some(e.stats),
            _ => None,
        };
        let params = crate::rundir::rundata::scene(run_dir).map(|s| s.params);
        ElasticExtras {
            params: Some(params),
            stats,
            fields_file: Some(run_dir.join(rundir::FIELDS_FILE)),
        }
    }

    /// The extras of a solution in memory: its scene's parameters and its statistics.
    pub fn of_solution(solution: &crate::bvp::Solution) -> ElasticExtras {
        ElasticExtras {
            params: Some(Ok(solution.params)),
            stats: Some(solution.stats.clone()),
            fields_file: None,
        }
    }
}

/// fields.csv's `table` in bvp4c's form ([`crate::bvp::bvp4c`]): x with each interface
/// twice, y, and yp = f(x, y) at every point of x.
pub fn bvp4c_form(
    table: &Table,
    extras: &ElasticExtras,
) -> Result<crate::bvp::bvp4c::Bvp4cForm, ExportError> {
    let params = match &extras.params {
        Some(Ok(p)) => p,
        Some(Err(why)) => {
            return Err(bad(format!(
                "the run's scene cannot be read, and sol.yp = f(x, y) needs its equations: {}",
                crate::text::excerpt(&why.message, 200)
            )))
        }
        None => {
            return Err(bad(
                "the run's scene is not known; sol.yp = f(x, y) needs it",
            ))
        }
    };
    let columns = crate::bvp::COLUMNS
        .iter()
        .map(|&c| {
            table
                .column(c)
                .ok_or_else(|| bad(format!("fields.csv has no column {c}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let rows: Vec<crate::bvp::FieldRow> = (0..table.rows.len())
        .map(|i| crate::bvp::FieldRow::from_values(std::array::from_fn(|j| columns[j][i])))
        .collect();
    // The fields are what was given: a value the equations cannot take is the file's.
    crate::bvp::bvp4c::bvp4c_form(params, &rows).map_err(|e| {
        let file = extras
            .fields_file
            .as_ref()
            .map_or(String::new(), |f| format!("{}: ", f.display()));
        bad(format!(
            "{file}sol.yp = f(x, y) cannot be evaluated on these fields: {e}"
        ))
    })
}

/// A field of fields.csv (a name of [`crate::bvp::COLUMNS`]) over the form's x.
fn form_column(form: &crate::bvp::bvp4c::Bvp4cForm, name: &str) -> Vec<f64> {
    let j = crate::bvp::COLUMNS
        .iter()
        .position(|&c| c == name)
        .unwrap_or(0);
    form.rows.iter().map(|r| r.values()[j]).collect()
}

/// bvp4c's `sol.stats`: nmeshpoints (nodes), maxres (the final Newton residual's max
/// norm: eyeshell's measure, not bvp4c's residual control), nODEevals (residual
/// evaluations × nodes: each evaluates the equations at every node), nBCevals (residual
/// evaluations).
fn stats_struct(nodes: usize, stats: &crate::bvp::SolveStats) -> MatValue {
    let evals = stats.residual_evaluations as f64;
    MatValue::Struct(vec![
        ("nmeshpoints".to_string(), MatValue::scalar(nodes as f64)),
        ("maxres".to_string(), MatValue::scalar(stats.residual_norm)),
        (
            "nODEevals".to_string(),
            MatValue::scalar(evals * nodes as f64),
        ),
        ("nBCevals".to_string(), MatValue::scalar(evals)),
    ])
}

/// The variables of an elastic export as a .mat file: the struct `sol`, shaped like
/// bvp4c's solution (`solver`, `x`, `y`, `yp`, `stats`) so that MATLAB's `deval(sol, xi)`
/// and `bvpinit(sol, ...)` take it, plus the other columns as further fields.
pub fn elastic_mat_vars(
    table: &Table,
    extras: &ElasticExtras,
) -> Result<Vec<(String, MatValue)>, ExportError> {
    let form = bvp4c_form(table, extras)?;
    let mut fields = vec![
        ("solver".to_string(), MatValue::Char("bvp4c".to_string())),
        ("x".to_string(), MatValue::row(&form.x)),
        (
            "y".to_string(),
            MatValue::from_rows(&std::array::from_fn::<_, 5, _>(|k| form.y_row(k))),
        ),
        (
            "yp".to_string(),
            MatValue::from_rows(&std::array::from_fn::<_, 5, _>(|k| form.yp_row(k))),
        ),
    ];
    if let Some(stats) = &extras.stats {
        fields.push(("stats".to_string(), stats_struct(form.x.len(), stats)));
    }
    for c in ELASTIC_EXTRA {
        fields.push((c.to_string(), MatValue::row(&form_column(&form, c))));
    }
    Ok(vec![("sol".to_string(), MatValue::Struct(fields))])
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

/// The arrays of an elastic export as a .npz file: x, y, yp as in .mat, and the others.
pub fn elastic_npz_arrays(
    table: &Table,
    extras: &ElasticExtras,
) -> Result<Vec<(String, NpyArray)>, ExportError> {
    let form = bvp4c_form(table, extras)?;
    let mut arrays = vec![
        ("x".to_string(), NpyArray::vector(&form.x)),
        (
            "y".to_string(),
            NpyArray::from_rows(&std::array::from_fn::<_, 5, _>(|k| form.y_row(k))),
        ),
        (
            "yp".to_string(),
            NpyArray::from_rows(&std::array::from_fn::<_, 5, _>(|k| form.yp_row(k))),
        ),
    ];
    for c in ELASTIC_EXTRA {
        arrays.push((c.to_string(), NpyArray::vector(&form_column(&form, c))));
    }
    Ok(arrays)
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

    /// Did eyeshell write the file at `path`? Its .mat header names eyeshell as the
    /// platform; its .npz archive ends with eyeshell's comment.
    fn wrote(self, path: &Path) -> bool {
        match self {
            Format::Mat { .. } => rundir::owner::head(path, 128).starts_with(mat::SIGNATURE),
            Format::Npz => npz::has_signature(path),
        }
    }
}

/// An output error as an export error: a refusal is the user's.
fn output_error(e: OutputError) -> ExportError {
    ExportError {
        bad_input: e.is_refusal(),
        message: e.to_string(),
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
    mat_vars: impl FnOnce() -> Result<Vec<(String, MatValue)>, ExportError>,
    npz_arrays: impl FnOnce() -> Result<Vec<(String, NpyArray)>, ExportError>,
) -> Result<(), ExportError> {
    match format {
        Format::Mat { compress } => {
            mat::write(path, &mat_vars()?, compress).map_err(|e| failed(e.to_string()))
        }
        Format::Npz => npz::write(path, &npz_arrays()?).map_err(|e| failed(e.to_string())),
    }
}

/// May the one-file export `out` of the run in `run_dir` be written? A new file, or one
/// eyeshell exported, or any file with `force`, but never one of the run's own files.
pub fn check_file_target(
    run_dir: &Path,
    out: &Path,
    format: Format,
    force: bool,
) -> Result<(), ExportError> {
    if is_file_of_run(run_dir, out) {
        return Err(bad(format!(
            "{}: is a file of the run being exported; refusing to overwrite it, even with {}",
            out.display(),
            crate::text::advice(&crate::text::Advice::Force)
        )));
    }
    rundir::check_file(out, force, |p| format.wrote(p)).map_err(output_error)
}

/// Check the target `out` as [`export`] will, before any export is written: a directory
/// for a growth run, a file otherwise (a run whose summary cannot be read is checked by
/// [`export`] itself, which refuses it before writing).
pub fn precheck(
    run_dir: &Path,
    out: &Path,
    format: Format,
    force: bool,
) -> Result<(), ExportError> {
    match rundir::Summary::read(run_dir) {
        Ok(rundir::Summary::Growth(_)) => {
            rundir::check_target(out, "export", &[run_dir]).map_err(output_error)
        }
        Ok(_) if !out.is_dir() => check_file_target(run_dir, out, format, force),
        _ => Ok(()),
    }
}

/// Is `path` one of the files of the run directory `run_dir` (its marker lists it)?
fn is_file_of_run(run_dir: &Path, path: &Path) -> bool {
    let (Ok(dir), Some(name)) = (run_dir.canonicalize(), path.file_name()) else {
        return false;
    };
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    let Ok(parent) = parent.unwrap_or(Path::new(".")).canonicalize() else {
        return false;
    };
    let name = name.to_string_lossy();
    parent == dir
        && (name == MARKER_FILE
            || Marker::read(&dir).is_none_or(|m| m.entries.iter().any(|e| *e == name)))
}

/// Export the run in `run_dir` to `out` (a file for an elastic solve, a directory for a
/// growth run); nothing is half-written. An existing file is replaced only if eyeshell
/// wrote it, or with `force`; a directory only if it is an earlier eyeshell export.
pub fn export(
    run_dir: &Path,
    out: &Path,
    format: Format,
    force: bool,
) -> Result<Exported, ExportError> {
    let run = read_run(run_dir)?;
    match run {
        Run::Elastic { table, file } => {
            if !out.is_dir() {
                check_file_target(run_dir, out, format, force)?;
            }
            let extras = ElasticExtras {
                fields_file: Some(file),
                ..ElasticExtras::of(run_dir)
            };
            export_table(&table, &extras, out, format, force)
        }
        Run::Growth(snapshots) => {
            let tables = match format {
                Format::Mat { .. } => read_series_tables(run_dir)?,
                Format::Npz => Vec::new(),
            };
            export_growth(&snapshots, &tables, out, format, &[run_dir])
        }
    }
}

/// Write an elastic solve's fields.csv `table` (with its `extras`) to the one file `out`;
/// nothing is half-written. An existing file is replaced only if eyeshell wrote it, or
/// with `force`.
pub fn export_table(
    table: &Table,
    extras: &ElasticExtras,
    out: &Path,
    format: Format,
    force: bool,
) -> Result<Exported, ExportError> {
    if out.is_dir() {
        return Err(bad(format!(
            "{}: is a directory; an elastic solve exports to one file (e.g. out.{})",
            out.display(),
            format.extension()
        )));
    }
    rundir::check_file(out, force, |p| format.wrote(p)).map_err(output_error)?;
    write_one(
        out,
        format,
        || elastic_mat_vars(table, extras),
        || elastic_npz_arrays(table, extras),
    )?;
    Ok(Exported {
        path: out.to_path_buf(),
        files: vec![out.to_path_buf()],
        nodes: table.rows.len(),
        growth: false,
    })
}

/// Write `snapshots` (a growth run's output times, each named after its snapshot file) to
/// the directory `out`, one file per output time in the published scripts' layout (the
/// module's doc); nothing is half-written. `inputs` are the directories the snapshots come
/// from, which `out` may not replace; an existing `out` is replaced only if it is an earlier
/// eyeshell export.
pub fn export_snapshots(
    snapshots: &[RunSnapshot],
    out: &Path,
    format: Format,
    inputs: &[&Path],
) -> Result<Exported, ExportError> {
    export_growth(snapshots, &[], out, format, inputs)
}

/// The stems of the tables a .mat export of a growth run holds beside its snapshots.
pub const SERIES_TABLES: [&str; 2] = ["series", "history"];

/// series.csv or history.csv as an export writes it: its stem ([`SERIES_TABLES`]), its
/// columns and each row's cells as text.
#[derive(Clone, Debug, PartialEq)]
pub struct SeriesTable {
    pub stem: &'static str,
    pub columns: Vec<String>,
    pub cells: Vec<Vec<String>>,
}

/// The series.csv and history.csv of the run in `run_dir` (those it has).
pub fn read_series_tables(run_dir: &Path) -> Result<Vec<SeriesTable>, ExportError> {
    let mut out = Vec::new();
    for stem in SERIES_TABLES {
        let path = run_dir.join(format!("{stem}.csv"));
        if !path.is_file() {
            continue;
        }
        let records = crate::rundir::table::read_records(&path)?;
        out.push(SeriesTable {
            stem,
            columns: records.header.clone().unwrap_or_default(),
            cells: records
                .iter()
                .map(|r| r.cells.iter().map(str::to_string).collect())
                .collect(),
        });
    }
    Ok(out)
}

/// The variables of `table` as a .mat file: each column a row vector named after it, the
/// numbers as they read back (exactly the file's), a class column a char row of its
/// words separated by commas.
pub fn series_mat_vars(table: &SeriesTable) -> Result<Vec<(String, MatValue)>, ExportError> {
    let file = format!("{}.csv", table.stem);
    let mut vars = Vec::with_capacity(table.columns.len());
    for (j, name) in table.columns.iter().enumerate() {
        let cell = |row: &Vec<String>| row.get(j).cloned().unwrap_or_default();
        let class =
            crate::outputs::quantity(name).is_some_and(|q| q.kind == crate::outputs::Kind::Class);
        if class {
            let words: Vec<String> = table.cells.iter().map(cell).collect();
            vars.push((name.clone(), MatValue::Char(words.join(","))));
            continue;
        }
        let mut values = Vec::with_capacity(table.cells.len());
        for (i, row) in table.cells.iter().enumerate() {
            let text = cell(row);
            values.push(text.parse::<f64>().map_err(|_| {
                bad(format!(
                    "{file}: row {}: {name} is not a number: {:?}",
                    i + 1,
                    crate::text::excerpt(&text, 40)
                ))
            })?);
        }
        vars.push((name.clone(), MatValue::row(&values)));
    }
    Ok(vars)
}

/// [`export_snapshots`], and with a .mat format each of `tables` as `<stem>.mat`
/// ([`series_mat_vars`]).
pub fn export_growth(
    snapshots: &[RunSnapshot],
    tables: &[SeriesTable],
    out: &Path,
    format: Format,
    inputs: &[&Path],
) -> Result<Exported, ExportError> {
    let dir = OutputDir::create(out, "export", inputs).map_err(output_error)?;
    let mut files = Vec::new();
    for s in snapshots {
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
            || Ok(growth_mat_vars(s)),
            || Ok(growth_npz_arrays(s)),
        )?;
        files.push(out.join(name));
    }
    if let Format::Mat { compress } = format {
        for table in tables {
            let name = format!("{}.mat", table.stem);
            mat::write(&dir.file(&name), &series_mat_vars(table)?, compress)
                .map_err(|e| failed(e.to_string()))?;
            files.push(out.join(name));
        }
    }
    let path = dir.commit().map_err(output_error)?;
    Ok(Exported {
        path,
        files,
        nodes: snapshots.first().map_or(0, |s| s.table.rows.len()),
        growth: true,
    })
}
