//! Files of other programs: a growth run written as .mat or .npz, and runs compared.

use eyeshell::bvp::COLUMNS;
use eyeshell::growth::GROWTH_COLUMNS;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::errors::{argument_err, input_err, py_err};

/// A table of a growth run from Python: its stem, its columns and each row's cells.
type TableCells = (String, Vec<String>, Vec<Vec<String>>);

/// Write a growth run's `snapshots` ((t, {column: values}), in time order, each with every
/// column of a snapshot file) to the directory `out` as `eyeshell export --mat` writes a
/// growth run: one .mat file per output time in the published scripts' layout, named by
/// `ages` (one per snapshot) in a scene with `time.unit` as its snapshot files are, and
/// `tables` (stem "series" or "history", columns, each row's cells as text) as
/// series.mat and history.mat. Returns the files written.
#[pyfunction]
#[pyo3(signature = (out, snapshots, compress = false, ages = None, tables = None))]
pub(super) fn export_growth(
    py: Python<'_>,
    out: std::path::PathBuf,
    snapshots: Vec<(f64, std::collections::HashMap<String, Vec<f64>>)>,
    compress: bool,
    ages: Option<Vec<f64>>,
    tables: Option<Vec<TableCells>>,
) -> PyResult<Vec<std::path::PathBuf>> {
    use eyeshell::interop::export::{SeriesTable, SERIES_TABLES};
    let tables = tables
        .unwrap_or_default()
        .into_iter()
        .map(|(stem, columns, cells)| {
            let stem = SERIES_TABLES
                .into_iter()
                .find(|s| *s == stem)
                .ok_or_else(|| input_err(format!("to_mat: no table {stem:?}")))?;
            Ok(SeriesTable {
                stem,
                columns,
                cells,
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    if let Some(ages) = &ages {
        if ages.len() != snapshots.len() {
            return Err(argument_err(
                format!(
                    "to_mat: {} ages for {} snapshots",
                    ages.len(),
                    snapshots.len()
                ),
                "ages",
                Some(format!("{} ages", ages.len())),
            ));
        }
    }
    use eyeshell::interop::export::{export_growth, Format, RunSnapshot, Table};
    let columns: Vec<String> = COLUMNS
        .iter()
        .chain(GROWTH_COLUMNS.iter())
        .map(|c| c.to_string())
        .collect();
    let mut runs = Vec::with_capacity(snapshots.len());
    for (k, (t, fields)) in snapshots.iter().enumerate() {
        let age = ages.as_ref().map(|a| a[k]);
        let name = eyeshell::rundir::growth::snapshot_name_at(k, *t, age);
        let values = columns
            .iter()
            .map(|c| {
                fields.get(c).ok_or_else(|| {
                    input_err(format!(
                        "to_mat: the snapshot at t = {} has no column {c}",
                        eyeshell::text::number(*t)
                    ))
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        let nodes = values[0].len();
        if let Some(c) = values.iter().position(|v| v.len() != nodes) {
            return Err(input_err(format!(
                "to_mat: the snapshot at t = {} has {} values of {} but {nodes} of {}",
                eyeshell::text::number(*t),
                values[c].len(),
                columns[c],
                columns[0]
            )));
        }
        let rows = (0..nodes)
            .map(|i| values.iter().map(|v| v[i]).collect())
            .collect();
        runs.push(RunSnapshot {
            t: *t,
            file: std::path::PathBuf::from(name),
            table: Table {
                columns: columns.clone(),
                rows,
            },
        });
    }
    let done = py
        .detach(|| export_growth(&runs, &tables, &out, Format::Mat { compress }, &[]))
        .map_err(|e| py_err(e.into()))?;
    Ok(done.files)
}

/// `eyeshell compare RUN REFERENCE --tol --rtol [--field]`: the reports, one dict per
/// pair, and the text the command prints.
#[pyfunction]
#[pyo3(signature = (run, reference, tol, rtol, field = None))]
pub(super) fn compare<'py>(
    py: Python<'py>,
    run: std::path::PathBuf,
    reference: std::path::PathBuf,
    tol: f64,
    rtol: f64,
    field: Option<String>,
) -> PyResult<(Bound<'py, PyList>, String)> {
    use eyeshell::interop::compare::{compare_paths, format_reports, FieldSpec};
    for (name, v) in [("tol", tol), ("rtol", rtol)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(argument_err(
                format!("{name} = {v}: must be a finite number ≥ 0"),
                name,
                Some(v.to_string()),
            ));
        }
    }
    let field = field
        .map(|f| {
            f.parse::<FieldSpec>()
                .map_err(|e| argument_err(format!("field: {e}"), "field", Some(f.to_string())))
        })
        .transpose()?;
    let reports = py
        .detach(|| compare_paths(&run, &[reference], tol, rtol, field.as_ref()))
        .map_err(|e| py_err(e.into()))?;
    let list = PyList::empty(py);
    for r in &reports {
        let d = PyDict::new(py);
        d.set_item("reference", &r.reference)?;
        d.set_item("run", &r.run)?;
        d.set_item("time", r.time)?;
        d.set_item("coordinate", &r.coordinate)?;
        d.set_item("points", r.points)?;
        d.set_item("outside", r.outside)?;
        let not_compared = PyDict::new(py);
        for (name, why) in &r.not_compared {
            not_compared.set_item(name, why)?;
        }
        d.set_item("not_compared", not_compared)?;
        d.set_item("passed", !r.failed())?;
        let fields = PyDict::new(py);
        for f in &r.fields {
            let fd = PyDict::new(py);
            fd.set_item("max_abs", f.max_abs)?;
            fd.set_item("at_abs", f.at_abs)?;
            fd.set_item("max_rel", f.max_rel)?;
            fd.set_item("at_rel", f.at_rel)?;
            fd.set_item("failures", f.failures)?;
            fd.set_item("worst_ratio", f.worst_ratio)?;
            fd.set_item("interpolation", f.interpolation)?;
            fd.set_item("allowed", f.allowed)?;
            fields.set_item(&f.field, fd)?;
        }
        d.set_item("fields", fields)?;
        list.append(d)?;
    }
    Ok((list, format_reports(&reports, tol, rtol)))
}
