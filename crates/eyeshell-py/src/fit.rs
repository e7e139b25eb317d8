//! Calibration: a fit of growth keys to axial lengths.

use pyo3::prelude::*;

use super::errors::{argument_err, py_err};
use super::grow::Watch;
use super::scene::PyScene;

/// Fit the parameters `keys` of `scene` to observations (the CSV file `path`, or the
/// columns `t` (or `age`, in the scene's time.unit), `axial_length` and `sigma`), with the
/// GIL released, as `eyeshell fit`:
/// returns (fit.json's text, the report's table and its notes, the fitted scene). Ctrl-C stops it within a step of its
/// current growth run, as it stops `grow`.
#[pyfunction]
#[pyo3(signature = (scene, keys, path = None, t = None, axial_length = None, sigma = None, max_iterations = 50, age = None))]
#[allow(clippy::too_many_arguments)]
pub(super) fn fit(
    py: Python<'_>,
    scene: PyScene,
    keys: Vec<String>,
    path: Option<std::path::PathBuf>,
    t: Option<Vec<f64>>,
    axial_length: Option<Vec<f64>>,
    sigma: Option<Vec<f64>>,
    max_iterations: usize,
    age: Option<Vec<f64>>,
) -> PyResult<(String, String, Vec<String>, PyScene)> {
    use eyeshell::fit::{FitOptions, Observations};
    if !(1..=1000).contains(&max_iterations) {
        return Err(argument_err(
            format!("max_iterations = {max_iterations}: must lie between 1 and 1000"),
            "max_iterations",
            Some(max_iterations.to_string()),
        ));
    }
    let scene = scene.inner;
    let data = match (path, t, age, axial_length) {
        (Some(p), None, None, None) => Observations::read(&p).map_err(py_err)?,
        (None, Some(t), None, Some(l)) => {
            Observations::from_columns(&t, &l, sigma.as_deref(), "data").map_err(py_err)?
        }
        (None, None, Some(a), Some(l)) => {
            Observations::from_age_columns(&a, &l, sigma.as_deref(), "data").map_err(py_err)?
        }
        _ => {
            return Err(argument_err(
                "data: give a CSV file's path, or the columns t (or age) and axial_length (and sigma), not both t and age",
                "data",
                None,
            ))
        }
    };
    let options = FitOptions {
        max_iterations,
        ..FitOptions::default()
    };
    let (result, raised) = py.detach(|| {
        let mut watch = Watch {
            progress: None,
            raised: None,
        };
        let result = scene.fit_observed(&data, &keys, &options, &mut watch);
        (result, watch.raised)
    });
    if let Some(e) = raised {
        return Err(e);
    }
    let done = result.map_err(py_err)?;
    let json = eyeshell::fit::report_json(&done.report);
    let text = eyeshell::fit::report::report_table(&scene, &done.report);
    let notes = eyeshell::fit::report::notes(&done.report);
    Ok((json, text, notes, PyScene { inner: done.scene }))
}
