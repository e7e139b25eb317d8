//! Sweeps: a sweep scene expanded into its runs' scenes.

use eyeshell::scene::KEYS;
use eyeshell::Sweep;
use pyo3::prelude::*;

use super::convert::{key_value, toml_to_py};
use super::errors::py_err;
use super::scene::PyScene;

/// One run of a sweep: its name, its swept (key, value), its scene.
type PlannedRun<'py> = (String, Vec<(String, Bound<'py, PyAny>)>, PyScene);

/// The runs of the sweep in TOML `text` (`origin` names it), each as (name, values, scene),
/// values being (key, value) in the order of the swept keys: a scene key's value as the
/// run's scene holds it (fibres.D = 0 is the float 0.0, solver.nodes an int), as
/// `Scene.get` gives it, so that a sweep's values are the numbers its runs used.
#[pyfunction]
#[pyo3(signature = (text, origin, overrides = Vec::new()))]
pub(super) fn expand_sweep<'py>(
    py: Python<'py>,
    text: &str,
    origin: &str,
    overrides: Vec<String>,
) -> PyResult<Vec<PlannedRun<'py>>> {
    let sweep = Sweep::from_toml_str(text, origin, &overrides).map_err(|e| py_err(e.into()))?;
    sweep
        .runs
        .into_iter()
        .map(|r| {
            let values = r
                .values
                .iter()
                .map(|(k, v)| {
                    let value = match KEYS.iter().find(|spec| spec.key == k) {
                        Some(spec) => key_value(py, spec.get(&r.scene))?,
                        None => toml_to_py(py, v)?,
                    };
                    Ok((k.clone(), value))
                })
                .collect::<PyResult<Vec<_>>>()?;
            Ok((r.name, values, PyScene { inner: r.scene }))
        })
        .collect()
}
