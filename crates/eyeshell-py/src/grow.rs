//! Growth runs: the series, snapshots and sensitivities as dicts of arrays, with the
//! progress callback and Ctrl-C between steps.

use eyeshell::growth::{
    GrowthParams, Observer, ObserverError, SensitivityRow, SeriesRow, Snapshot, GROWTH_COLUMNS,
};
use eyeshell::outputs::{Cell, Kind};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

use std::sync::Arc;

use eyeshell::model::rule::GrowthRule;

use super::convert::{column, fields_dict};
use super::errors::py_err;
use super::rule::PyRule;
use super::scene::PyScene;

/// Why a run stopped early on the caller's behalf.
#[derive(Debug)]
struct Stopped(&'static str);

impl std::fmt::Display for Stopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

impl std::error::Error for Stopped {}

/// The observer of a growth run from Python: after each step, with the GIL taken back
/// briefly, Python's pending signals (Ctrl-C) and the progress callback.
pub(super) struct Watch<'a> {
    pub(super) progress: Option<&'a Py<PyAny>>,
    /// The Python exception that stopped the run (KeyboardInterrupt, or the callback's).
    pub(super) raised: Option<PyErr>,
}

impl Observer for Watch<'_> {
    fn snapshot(&mut self, _s: &Snapshot) -> Result<(), ObserverError> {
        Ok(())
    }

    fn progress(&mut self, t: f64, t_end: f64) -> Result<(), ObserverError> {
        let outcome = Python::attach(|py| {
            py.check_signals()?;
            if let Some(f) = self.progress {
                f.call1(py, (t, t_end))?;
            }
            Ok::<(), PyErr>(())
        });
        if let Err(e) = outcome {
            self.raised = Some(e);
            return Err(Box::new(Stopped("interrupted")));
        }
        Ok(())
    }
}

/// Series rows as a dict of arrays: series.csv's columns, from the table of outputs, in
/// its order (a class as a list of str); `age` last when the scene counts in ages, `g`'s
/// time.unit, as series.csv.
fn series_dict<'py>(
    py: Python<'py>,
    rows: &[SeriesRow],
    g: Option<&GrowthParams>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for q in eyeshell::outputs::series_quantities() {
        match q.kind {
            Kind::Number => d.set_item(q.name, column(py, rows, |r| q.value(r).number()))?,
            Kind::Class => {
                let words: Vec<&str> = rows
                    .iter()
                    .map(|r| match q.value(r) {
                        Cell::Text(s) => s,
                        Cell::Number(_) => "",
                    })
                    .collect();
                d.set_item(q.name, PyList::new(py, words)?)?
            }
        }
    }
    add_age(py, &d, rows.iter().map(|r| r.t), g)?;
    Ok(d)
}

/// The `age` column of the times `t` in a scene that counts in ages (`g`'s time.unit), as
/// the command line's files end in it; nothing without a unit.
fn add_age(
    py: Python<'_>,
    d: &Bound<'_, PyDict>,
    t: impl Iterator<Item = f64>,
    g: Option<&GrowthParams>,
) -> PyResult<()> {
    let Some(g) = g.filter(|g| g.age_unit().is_some()) else {
        return Ok(());
    };
    let ages: Vec<f64> = t.map(|t| g.age_of(t).unwrap_or(f64::NAN)).collect();
    d.set_item("age", PyArray1::from_vec(py, ages))
}

/// The peripheral refraction of every snapshot (peripheral.csv's columns, `age` last when
/// the scene counts in ages, `g`'s time.unit) as arrays: with lenses worn, each snapshot's
/// naked rows and then its rows through each image of the lenses, with the columns that say
/// which (`through`, `image`, `image_power_D`, `share`), as peripheral.csv holds them.
fn peripheral_dict<'py>(
    py: Python<'py>,
    snapshots: &[Snapshot],
    g: Option<&GrowthParams>,
) -> PyResult<Bound<'py, PyDict>> {
    // (t, row, through: None for the naked eye, else (image, its power, its share)).
    type Row<'a> = (
        f64,
        &'a eyeshell::growth::PeripheralRow,
        Option<(usize, f64, f64)>,
    );
    let mut rows: Vec<Row> = Vec::new();
    for s in snapshots {
        rows.extend(s.peripheral.iter().map(|p| (s.t, p, None)));
        for (k, l) in s.through.iter().enumerate() {
            let power = l.image_power.unwrap_or(f64::NAN);
            rows.extend(l.peripheral.iter().enumerate().map(|(i, p)| {
                let share = l.share.get(i).copied().unwrap_or(f64::NAN);
                (s.t, p, Some((k, power, share)))
            }));
        }
    }
    let d = PyDict::new(py);
    d.set_item("t", column(py, &rows, |r| r.0))?;
    d.set_item("field_deg", column(py, &rows, |r| r.1.field_deg))?;
    d.set_item("refraction_D", column(py, &rows, |r| r.1.refraction_d))?;
    d.set_item("relative_D", column(py, &rows, |r| r.1.relative_d))?;
    if snapshots.iter().any(|s| !s.through.is_empty()) {
        let through: Vec<&str> = (rows.iter())
            .map(|r| if r.2.is_some() { "lenses" } else { "naked" })
            .collect();
        d.set_item("through", through)?;
        let image: Vec<i64> = rows.iter().map(|r| r.2.map_or(0, |x| x.0 as i64)).collect();
        d.set_item("image", PyArray1::from_vec(py, image))?;
        d.set_item(
            "image_power_D",
            column(py, &rows, |r| r.2.map_or(f64::NAN, |x| x.1)),
        )?;
        d.set_item("share", column(py, &rows, |r| r.2.map_or(1.0, |x| x.2)))?;
    }
    add_age(py, &d, rows.iter().map(|r| r.0), g)?;
    Ok(d)
}

/// One snapshot's fields (fields.csv's columns, then the growth columns) as arrays, and
/// its age on every node in a scene with time.unit, as the snapshot file has it.
fn snapshot_dict<'py>(
    py: Python<'py>,
    s: &Snapshot,
    g: Option<&GrowthParams>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = fields_dict(py, &s.fields)?;
    for (j, name) in GROWTH_COLUMNS.iter().enumerate() {
        d.set_item(*name, column(py, &s.growth, |g| g.values()[j]))?;
    }
    add_age(py, &d, s.fields.iter().map(|_| s.t), g)?;
    Ok(d)
}

/// sensitivities.csv's columns of `rows` (`parameter` as a list of str; the scaled column
/// computed as the command line computes it, so the values are the file's bit for bit).
fn sensitivities_dict<'py>(
    py: Python<'py>,
    rows: &[SensitivityRow],
    g: Option<&GrowthParams>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t", column(py, rows, |r| r.t))?;
    let names: Vec<&str> = rows.iter().map(|r| r.parameter).collect();
    d.set_item("parameter", PyList::new(py, names)?)?;
    d.set_item("d_axial_length", column(py, rows, |r| r.d_axial_length))?;
    d.set_item(
        "d_equatorial_radius",
        column(py, rows, |r| r.d_equatorial_radius),
    )?;
    d.set_item(
        "d_retina_minus_blue",
        column(py, rows, |r| r.d_retina_minus_blue),
    )?;
    d.set_item(
        "scaled_axial_length",
        column(py, rows, SensitivityRow::scaled_axial_length),
    )?;
    add_age(py, &d, rows.iter().map(|r| r.t), g)?;
    Ok(d)
}

/// Grow the eye of `scene` with the GIL released, calling `progress(t, t_end)` after each
/// step, with `stimulus(view)` as the growth rule if given (rule.rs); returns a dict:
/// series, history, snapshots (a list of (t, fields)), sensitivities (with
/// `sensitivities`: the keys, as `eyeshell grow --sensitivities`), summary_text, and with
/// a rule its name and cost (rule_name, rule_calls, rule_seconds).
#[pyfunction]
#[pyo3(signature = (scene, progress = None, sensitivities = Vec::new(), sensitivity_error_control = false, stimulus = None))]
pub(super) fn grow<'py>(
    py: Python<'py>,
    scene: PyScene,
    progress: Option<Py<PyAny>>,
    sensitivities: Vec<String>,
    sensitivity_error_control: bool,
    stimulus: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut scene = scene.inner;
    scene
        .set_sensitivities(&sensitivities, sensitivity_error_control)
        .map_err(py_err)?;
    scene.solver.threads = eyeshell::scene::jobs_from_env().map_err(py_err)?;
    let rule = match stimulus {
        Some(f) => {
            let rule = Arc::new(PyRule::new(py, f, scene.solver.max_seconds)?);
            scene.set_rule(rule.clone()).map_err(py_err)?;
            Some(rule)
        }
        None => None,
    };
    let (result, raised) = py.detach(|| {
        let mut watch = Watch {
            progress: progress.as_ref(),
            raised: None,
        };
        let result = scene.grow(&mut watch);
        (result, watch.raised)
    });
    // The rule's own exception first: the run's error only says that it failed.
    if let Some(e) = rule.as_ref().and_then(|r| r.take_failure()).or(raised) {
        return Err(e);
    }
    let growth = result.map_err(py_err)?;
    let d = PyDict::new(py);
    if let Some(rule) = &rule {
        let (calls, seconds) = rule.cost();
        d.set_item("rule_name", rule.name())?;
        d.set_item("rule_calls", calls)?;
        d.set_item("rule_seconds", seconds)?;
    }
    let g = scene.growth.as_ref();
    d.set_item("series", series_dict(py, &growth.series, g)?)?;
    d.set_item("history", series_dict(py, &growth.history, g)?)?;
    let snapshots = PyList::empty(py);
    for s in &growth.snapshots {
        snapshots.append(PyTuple::new(
            py,
            [
                s.t.into_pyobject(py)?.into_any(),
                snapshot_dict(py, s, g)?.into_any(),
            ],
        )?)?;
    }
    d.set_item("snapshots", snapshots)?;
    d.set_item("peripheral", peripheral_dict(py, &growth.snapshots, g)?)?;
    d.set_item(
        "sensitivities",
        sensitivities_dict(py, &growth.sensitivities, g)?,
    )?;
    d.set_item("summary_text", scene.grow_summary(&growth))?;
    Ok(d)
}
