//! Scenes: `_Scene` (a validated scene read from a file or text, set by key) and the keys.

use eyeshell::scene::{Scene, KEYS};
use pyo3::exceptions::PyKeyError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use super::convert::{key_value, toml_value};
use super::errors::py_err;

/// The scene's own keys (`eyeshell keys`): every parameter and setting, checked.
#[pyclass(name = "_Scene", module = "eyeshell._eyeshell", from_py_object)]
#[derive(Clone)]
pub(super) struct PyScene {
    pub(super) inner: Scene,
}

#[pymethods]
impl PyScene {
    /// The default scene (the paper's shell).
    #[staticmethod]
    fn defaults() -> Self {
        PyScene {
            inner: Scene::default_scene(),
        }
    }

    /// Read and validate the scene file at `path`; `sweep=False` reads a sweep file's
    /// scene without its `[sweep]` table.
    #[staticmethod]
    #[pyo3(signature = (path, sweep = true))]
    fn from_file(path: std::path::PathBuf, sweep: bool) -> PyResult<Self> {
        let inner = if sweep {
            Scene::from_path(&path)
        } else {
            Scene::from_file_without_sweep(&path)
        };
        Ok(PyScene {
            inner: inner.map_err(|e| py_err(e.into()))?,
        })
    }

    /// Parse and validate a scene from TOML text; `origin` names it in messages.
    #[staticmethod]
    #[pyo3(signature = (text, origin = "<string>"))]
    fn from_toml(text: &str, origin: &str) -> PyResult<Self> {
        let inner = Scene::from_toml_str(text, origin, &[]).map_err(|e| py_err(e.into()))?;
        Ok(PyScene { inner })
    }

    /// Set `key` to `value` and validate (on an error the scene is left as it was).
    fn set(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = toml_value(value)?;
        self.inner.set(key, v).map_err(|e| py_err(e.into()))
    }

    /// Set every (key, value) of `items` in order, then validate once (keys valid only
    /// together, growth.t_end and output.times, are set together); on an error the scene is
    /// left as it was.
    fn set_all(&mut self, items: Vec<(String, Bound<'_, PyAny>)>) -> PyResult<()> {
        let values = items
            .iter()
            .map(|(k, v)| Ok((k.as_str(), toml_value(v)?)))
            .collect::<PyResult<Vec<_>>>()?;
        self.inner.set_all(values).map_err(|e| py_err(e.into()))
    }

    /// The effective value of `key` (None for an optional key left unset).
    fn get<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let spec = KEYS.iter().find(|k| k.key == key).ok_or_else(|| {
            PyKeyError::new_err(format!("{key:?} is not a scene key (see eyeshell.keys())"))
        })?;
        key_value(py, spec.get(&self.inner))
    }

    /// The keys in use and their effective values, in the order of `eyeshell keys`.
    fn entries<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in self.inner.entries() {
            d.set_item(k, key_value(py, v)?)?;
        }
        Ok(d)
    }

    /// The effective scene as TOML, which reads back to the same scene.
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    /// Does the scene grow (any growth key set)?
    #[getter]
    fn grows(&self) -> bool {
        self.inner.growth.is_some()
    }

    /// Where the scene came from (its file, or `<string>`).
    #[getter]
    fn origin(&self) -> String {
        self.inner.origin.clone()
    }

    /// The scene's name: `name` if given, else its file's stem.
    #[getter]
    fn name(&self) -> String {
        self.inner.display_name()
    }

    /// Σ's range [ε, L]: solver.epsilon and the shell's length.
    #[getter]
    fn span(&self) -> (f64, f64) {
        (self.inner.solver.epsilon, self.inner.params.length())
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .extract::<PyScene>()
            .is_ok_and(|o| o.inner.to_toml() == self.inner.to_toml())
    }
}

/// Every scene key: dicts of key, type, default, doc and range, in `eyeshell keys` order.
#[pyfunction]
pub(super) fn keys(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for k in KEYS.iter() {
        let d = PyDict::new(py);
        d.set_item("key", k.key)?;
        d.set_item("type", k.type_name())?;
        d.set_item("default", key_value(py, k.default_value())?)?;
        d.set_item("doc", k.doc)?;
        d.set_item("range", k.rule.describe())?;
        d.set_item("growth", k.growth)?;
        list.append(d)?;
    }
    Ok(list)
}
