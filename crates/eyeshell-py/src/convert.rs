//! Conversions: the library's rows as NumPy arrays, Python values as TOML values and back.

use eyeshell::bvp::{FieldRow, COLUMNS};
use eyeshell::scene::KeyValue;
use numpy::PyArray1;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyByteArray, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString};

use super::errors::input_err;

/// A 1-D NumPy array owning `values` (no copy).
pub(super) fn array1<'py>(py: Python<'py>, values: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, values)
}

/// Column `j` of `rows` (values given by `get`) as a NumPy array.
pub(super) fn column<'py, R>(
    py: Python<'py>,
    rows: &[R],
    get: impl Fn(&R) -> f64,
) -> Bound<'py, PyArray1<f64>> {
    array1(py, rows.iter().map(get).collect())
}

/// Every field of `rows` by its fields.csv name, as a dict of arrays.
pub(super) fn fields_dict<'py>(py: Python<'py>, rows: &[FieldRow]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (j, name) in COLUMNS.iter().enumerate() {
        d.set_item(*name, column(py, rows, |r| r.values()[j]))?;
    }
    Ok(d)
}

// ---------------------------------------------------------------------------------------
// Scenes

/// A Python value as the TOML value a scene key takes (one conversion for `Scene.set` and
/// the TOML of a sweep's grid, [`toml_literal`]):
/// - a NumPy scalar or 0-d array counts as the Python value it holds (`.item()`), so
///   `np.int64(301)` and `np.array(301)` are integers, `np.True_` is a bool;
/// - an integer is anything integral (`int`, or with `__index__`); a float is never taken
///   for an integer, even 301.0, as in a scene file and `--set`: the key then says it
///   wants an integer, and no computed value passes or fails on its last bit;
/// - a float is a `float` or anything with `__float__`; a string is a `str`; a list is
///   any other iterable (bytes are refused: their items would be taken for numbers).
pub(super) fn toml_value(v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return integer(v);
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    let type_name = || v.get_type().name().map(|n| n.to_string());
    if v.is_instance_of::<PyBytes>() || v.is_instance_of::<PyByteArray>() {
        return Err(PyTypeError::new_err(format!(
            "a scene value must be a number, a bool, a string or a list of numbers, not {} (decode it to a str)",
            type_name()?
        )));
    }
    if is_numpy_scalar(v)? {
        return toml_value(&v.call_method0("item")?);
    }
    // A dict is a table (a surface of optics.surfaces), not the list of its keys.
    if let Ok(d) = v.cast::<pyo3::types::PyDict>() {
        let mut table = toml::Table::new();
        for (k, x) in d.iter() {
            table.insert(k.extract::<String>()?, toml_value(&x)?);
        }
        return Ok(toml::Value::Table(table));
    }
    // Before __index__ and __float__, which NumPy's arrays have too (and refuse unless 0-d).
    if let Ok(items) = v.try_iter() {
        let values = items
            .map(|item| toml_value(&item?))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(values));
    }
    if v.get_type().hasattr("__index__")? {
        let operator = v.py().import("operator")?;
        return integer(&operator.getattr("index")?.call1((v,))?);
    }
    if v.get_type().hasattr("__float__")? {
        return Ok(toml::Value::Float(v.extract()?));
    }
    Err(PyTypeError::new_err(format!(
        "a scene value must be a number, a bool, a string or a list of numbers, not {}",
        type_name()?
    )))
}

/// A Python int as a TOML integer (64 bits, as TOML's).
fn integer(v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    v.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
        input_err(format!(
            "{}: an integer beyond TOML's 64 bits (±9223372036854775807)",
            v.str().map_or_else(|_| "?".into(), |s| s.to_string())
        ))
    })
}

/// A NumPy scalar (`np.int64(3)`, `np.True_`) or 0-d array, told apart without importing
/// NumPy: its type comes from the module `numpy` and it has no dimension.
fn is_numpy_scalar(v: &Bound<'_, PyAny>) -> PyResult<bool> {
    let module: String = v
        .get_type()
        .getattr("__module__")?
        .extract()
        .unwrap_or_default();
    if module != "numpy" {
        return Ok(false);
    }
    Ok(v.getattr("ndim").and_then(|n| n.extract::<usize>()).ok() == Some(0))
}

/// `value` as a TOML literal (`3`, `2.5`, `"text"`, `[1, 2]`), converted as
/// [`PyScene::set`] converts it: how the Python package writes a sweep's grid and runs.
#[pyfunction]
pub(super) fn toml_literal(value: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(toml_value(value)?.to_string())
}

/// A scene key's value as a Python object.
pub(super) fn key_value<'py>(py: Python<'py>, v: KeyValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        KeyValue::Float(x) => x.into_pyobject(py)?.into_any(),
        KeyValue::Count(n) => n.into_pyobject(py)?.into_any(),
        KeyValue::Bool(b) => PyBool::new(py, b).to_owned().into_any(),
        KeyValue::Choice(s) => s.into_pyobject(py)?.into_any(),
        KeyValue::Text(s) => s.into_pyobject(py)?.into_any(),
        KeyValue::Floats(xs) => PyList::new(py, xs)?.into_any(),
        // The lenses as their TOML text, which `set` reads back.
        KeyValue::Lenses(_) => v.to_string().into_pyobject(py)?.into_any(),
        KeyValue::Tables(ts) => {
            let items = ts
                .iter()
                .map(|t| toml_to_py(py, t))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        KeyValue::Unset => py.None().into_bound(py),
    })
}

/// A TOML value as Python lists, dicts and numbers: a surface table of `optics.surfaces`,
/// or a swept value that is no scene key's (such as a run's name).
pub(super) fn toml_to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::Float(x) => x.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| toml_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        toml::Value::Table(t) => {
            let d = pyo3::types::PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, toml_to_py(py, x)?)?;
            }
            d.into_any()
        }
        other => eyeshell::scene::sweep::show_value(other)
            .into_pyobject(py)?
            .into_any(),
    })
}
