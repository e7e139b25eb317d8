//! `eyeshell._eyeshell`: the library's facade (crates/eyeshell/src/api.rs) as a Python
//! extension module. The Python package around it (python/eyeshell/) shapes the results
//! into `Solution`, `Growth` and sweep results; this module only converts.
//!
//! - Every computation runs with the GIL released ([`Python::detach`]); a growth run, and
//!   each growth run of a fit, takes the GIL back briefly after each step to call the
//!   progress callback and to let Python handle a pending signal (Ctrl-C stops the run
//!   there and raises KeyboardInterrupt). A sweep's runs are in worker processes
//!   (python/eyeshell/_worker.py), which Ctrl-C ends.
//! - Arrays are handed to NumPy without a copy: each column is gathered once from the
//!   library's rows (which are per node, not per field) into a `Vec`, whose buffer NumPy
//!   then owns (`PyArray1::from_vec`, `PyArray2::from_owned_array`).
//! - Errors keep the library's class: bad input (exit 2 on the command line) is
//!   `InputError`, everything else (exit 1) `SolverError`, with the same one-line message.

use eyeshell::bvp::{FieldRow, Solution, COLUMNS};
use eyeshell::growth::{
    GrowthParams, Observer, ObserverError, SensitivityRow, SeriesRow, Snapshot, GROWTH_COLUMNS,
};
use eyeshell::interop::export::{elastic_mat_vars, ElasticExtras, Table};
use eyeshell::interop::mat::MatValue;
use eyeshell::scene::{KeyValue, Scene, KEYS};
use eyeshell::text::Advice;
use eyeshell::{Error, Sweep};
use numpy::ndarray::{Array2, ShapeBuilder};
use numpy::{PyArray1, PyArray2};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{
    PyBool, PyByteArray, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple,
};

create_exception!(
    eyeshell,
    EyeshellError,
    PyException,
    "Any error of eyeshell: an InputError or a SolverError."
);
create_exception!(
    eyeshell,
    InputError,
    EyeshellError,
    "Bad input: a scene or key that does not validate, a value out of range, a file that is not what it should be (what `eyeshell` exits 2 for)."
);
create_exception!(
    eyeshell,
    SolverError,
    EyeshellError,
    "A computation that failed: Newton did not converge, a growth run stopped, a file could not be written (what `eyeshell` exits 1 for)."
);

/// The advice in the library's messages in a Python caller's terms (keyword arguments, not
/// the command line's flags), registered when the module is imported.
fn python_wording(a: &Advice<'_>) -> String {
    use eyeshell::text::one_line;
    match *a {
        Advice::Override { text } => format!("set {}", one_line(text)),
        Advice::RunSweep { .. } => "run it with eyeshell.sweep(), or read the scene without its sweep with eyeshell.Scene.from_file(path, sweep=False)".into(),
        Advice::RemoveOverride { text } => format!(
            "drop {} from the keyword overrides, or give its values in grid= or runs=",
            one_line(text)
        ),
        Advice::Shards { max } => {
            format!("split it into eyeshell.sweep() calls of at most {max} runs each")
        }
        Advice::Force => "force=True".into(),
        Advice::SetKey => "a keyword override (growth__Gamma=8)".into(),
        Advice::ListKeys => "eyeshell.keys()".into(),
        Advice::Field { name: None } => "field=\"NAME\"".into(),
        Advice::Field { name: Some(name) } => format!("field={:?}", one_line(name)),
    }
}

/// The library's error as its Python exception, with the library's one-line message.
fn py_err(e: Error) -> PyErr {
    let line = eyeshell::text::one_line(&e.to_string().replace(['\n', '\r'], " "));
    if e.is_user_error() {
        InputError::new_err(line)
    } else {
        SolverError::new_err(line)
    }
}

fn input_err(message: impl Into<String>) -> PyErr {
    InputError::new_err(message.into())
}

/// A 1-D NumPy array owning `values` (no copy).
fn array1<'py>(py: Python<'py>, values: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, values)
}

/// Column `j` of `rows` (values given by `get`) as a NumPy array.
fn column<'py, R>(
    py: Python<'py>,
    rows: &[R],
    get: impl Fn(&R) -> f64,
) -> Bound<'py, PyArray1<f64>> {
    array1(py, rows.iter().map(get).collect())
}

/// Every field of `rows` by its fields.csv name, as a dict of arrays.
fn fields_dict<'py>(py: Python<'py>, rows: &[FieldRow]) -> PyResult<Bound<'py, PyDict>> {
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
fn toml_value(v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
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
fn toml_literal(value: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(toml_value(value)?.to_string())
}

/// A scene key's value as a Python object.
fn key_value<'py>(py: Python<'py>, v: KeyValue) -> PyResult<Bound<'py, PyAny>> {
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
fn toml_to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
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

/// The scene's own keys (`eyeshell keys`): every parameter and setting, checked.
#[pyclass(name = "_Scene", module = "eyeshell._eyeshell", from_py_object)]
#[derive(Clone)]
struct PyScene {
    inner: Scene,
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
fn keys(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
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

// ---------------------------------------------------------------------------------------
// Elastic solves

/// A solved shell: the library's [`Solution`] and the scene it solves.
#[pyclass(name = "_Solved", module = "eyeshell._eyeshell", frozen)]
struct Solved {
    scene: Scene,
    solution: Solution,
}

/// Solve the loaded shell of `scene`, with the GIL released.
#[pyfunction]
fn solve(py: Python<'_>, scene: PyScene) -> PyResult<Solved> {
    let scene = scene.inner;
    let solution = py.detach(|| scene.solve()).map_err(py_err)?;
    Ok(Solved { scene, solution })
}

/// fields.csv's table of `solution`, for the command line's export functions.
fn table_of(solution: &Solution) -> Table {
    Table {
        columns: COLUMNS.iter().map(|c| c.to_string()).collect(),
        rows: solution.rows.iter().map(|r| r.values().to_vec()).collect(),
    }
}

/// A MATLAB value as Python: a 1×1 double as a float, a row or column as a 1-D array, a
/// matrix as a 2-D array (Fortran order, as MATLAB keeps it; no copy), a struct as a dict.
fn mat_to_py<'py>(py: Python<'py>, v: MatValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        MatValue::Double { dims, data } => match dims.as_slice() {
            [1, 1] => data[0].into_pyobject(py)?.into_any(),
            [1, _] | [_, 1] => array1(py, data).into_any(),
            &[r, c] => {
                let a = Array2::from_shape_vec((r, c).f(), data)
                    .map_err(|e| SolverError::new_err(e.to_string()))?;
                PyArray2::from_owned_array(py, a).into_any()
            }
            _ => array1(py, data).into_any(),
        },
        MatValue::Struct(fields) => {
            let d = PyDict::new(py);
            for (name, value) in fields {
                d.set_item(name, mat_to_py(py, value)?)?;
            }
            d.into_any()
        }
        MatValue::Char(s) => s.into_pyobject(py)?.into_any(),
        other => {
            return Err(SolverError::new_err(format!(
                "unexpected value in the bvp4c export: {other:?}"
            )))
        }
    })
}

#[pymethods]
impl Solved {
    /// Every field at every node: a dict of arrays named as fields.csv's columns.
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        fields_dict(py, &self.solution.rows)
    }

    /// Every field at the material points `sigma` (continuous interpolant), a dict of arrays.
    fn at<'py>(&self, py: Python<'py>, sigma: Vec<f64>) -> PyResult<Bound<'py, PyDict>> {
        let (lo, hi) = (self.scene.solver.epsilon, self.scene.params.length());
        let rows = sigma
            .iter()
            .map(|&x| {
                if !(x >= lo && x <= hi) {
                    return Err(input_err(format!(
                        "at: Σ = {x} is outside the shell [ε, L] = [{lo}, {hi}] (solver.epsilon, π·geometry.fraction·geometry.R0)"
                    )));
                }
                self.solution.at(x).map_err(|e| py_err(e.into()))
            })
            .collect::<PyResult<Vec<_>>>()?;
        fields_dict(py, &rows)
    }

    /// The unknowns at the nodes, (κ, r, θ, q_s, t_s) node by node: what `residual` and
    /// `jacobian` take.
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.solution.u.clone())
    }

    /// The sol struct `eyeshell export --mat` writes, shaped like bvp4c's solution.
    fn bvp4c<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let extras = ElasticExtras::of_solution(&self.solution);
        let mut vars =
            elastic_mat_vars(&table_of(&self.solution), &extras).map_err(|e| py_err(e.into()))?;
        let (_, sol) = vars.remove(0);
        mat_to_py(py, sol)
    }

    /// The eye of the loaded, ungrown shell as a sweep's table measures it: axial_length,
    /// equatorial_radius, retina_minus_blue, retina_minus_red, class.
    fn eye<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let eye = eyeshell::sweep::run::unloaded_eye(&self.scene, &self.solution.rows);
        let d = PyDict::new(py);
        d.set_item("axial_length", eye.axial_length)?;
        d.set_item("equatorial_radius", eye.equatorial_radius)?;
        d.set_item("retina_minus_blue", eye.retina_minus_blue)?;
        d.set_item("retina_minus_red", eye.retina_minus_red)?;
        d.set_item("class", eye.class.as_str())?;
        Ok(d)
    }

    /// Write the .mat file `eyeshell export --mat` writes of the run to `path` (over a file
    /// eyeshell did not write only with `force`); returns the path.
    fn write_mat(&self, py: Python<'_>, path: std::path::PathBuf, force: bool) -> PyResult<String> {
        use eyeshell::interop::export::{export_table, Format};
        let extras = ElasticExtras::of_solution(&self.solution);
        let table = table_of(&self.solution);
        let format = Format::Mat { compress: false };
        py.detach(|| export_table(&table, &extras, &path, format, force))
            .map_err(|e| py_err(e.into()))?;
        Ok(path.to_string_lossy().into_owned())
    }

    /// The text of the summary.json `eyeshell solve` writes.
    fn summary_text(&self) -> String {
        self.scene.solve_summary(&self.solution)
    }

    /// The scene solved.
    fn scene(&self) -> PyScene {
        PyScene {
            inner: self.scene.clone(),
        }
    }
}

// ---------------------------------------------------------------------------------------
// The discrete equations

/// The discrete problem of `scene` and the state checked against it.
fn discrete(scene: &Scene) -> PyResult<eyeshell::discrete::DiscreteProblem> {
    scene.discrete_problem().map_err(py_err)
}

/// F(state) of the scene's discrete elastic problem (scaled as Newton's test scales it
/// when `scaled`), with the GIL released.
#[pyfunction]
fn residual<'py>(
    py: Python<'py>,
    scene: PyScene,
    state: Vec<f64>,
    scaled: bool,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let scene = scene.inner;
    let f = py
        .detach(|| {
            let mut d = scene.discrete_problem()?;
            let mut f = d.residual(&state)?;
            if scaled {
                f.iter_mut().zip(d.scales()).for_each(|(v, s)| *v *= s);
            }
            Ok::<_, eyeshell::Error>(f)
        })
        .map_err(py_err)?;
    Ok(array1(py, f))
}

/// ∂F/∂u at `state` in compressed rows: (values, column indices, row pointers, n).
#[pyfunction]
fn jacobian<'py>(
    py: Python<'py>,
    scene: PyScene,
    state: Vec<f64>,
) -> PyResult<Bound<'py, PyTuple>> {
    let scene = scene.inner;
    let mut d = discrete(&scene)?;
    let m = py.detach(|| d.jacobian(&state)).map_err(py_err)?;
    let idx = |v: Vec<usize>| v.into_iter().map(|k| k as i64).collect::<Vec<i64>>();
    PyTuple::new(
        py,
        [
            array1(py, m.values).into_any(),
            PyArray1::from_vec(py, idx(m.col_idx)).into_any(),
            PyArray1::from_vec(py, idx(m.row_ptr)).into_any(),
            m.n.into_pyobject(py)?.into_any(),
        ],
    )
}

// ---------------------------------------------------------------------------------------
// Growth

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
struct Watch<'a> {
    progress: Option<&'a Py<PyAny>>,
    /// The Python exception that stopped the run (KeyboardInterrupt, or the callback's).
    raised: Option<PyErr>,
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

const SERIES_NAMES: [&str; 5] = [
    "t",
    "axial_length",
    "equatorial_radius",
    "retina_minus_blue",
    "retina_minus_red",
];

/// Series rows as a dict of arrays (series.csv's columns, in its order; `class` as a list
/// of str; `age` last when the scene counts in ages, `g`'s time.unit, as series.csv).
fn series_dict<'py>(
    py: Python<'py>,
    rows: &[SeriesRow],
    g: Option<&GrowthParams>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let getters: [fn(&SeriesRow) -> f64; 5] = [
        |r| r.t,
        |r| r.axial_length,
        |r| r.equatorial_radius,
        |r| r.retina_minus_blue,
        |r| r.retina_minus_red,
    ];
    for (name, get) in SERIES_NAMES.iter().zip(getters) {
        d.set_item(*name, column(py, rows, get))?;
    }
    let classes: Vec<&str> = rows.iter().map(|r| r.class.as_str()).collect();
    d.set_item("class", PyList::new(py, classes)?)?;
    d.set_item("refraction_D", column(py, rows, |r| r.refraction_d))?;
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
/// the scene counts in ages, `g`'s time.unit) as arrays.
fn peripheral_dict<'py>(
    py: Python<'py>,
    snapshots: &[Snapshot],
    g: Option<&GrowthParams>,
) -> PyResult<Bound<'py, PyDict>> {
    let rows: Vec<(f64, &eyeshell::growth::PeripheralRow)> = snapshots
        .iter()
        .flat_map(|s| s.peripheral.iter().map(move |p| (s.t, p)))
        .collect();
    let d = PyDict::new(py);
    d.set_item("t", column(py, &rows, |r| r.0))?;
    d.set_item("field_deg", column(py, &rows, |r| r.1.field_deg))?;
    d.set_item("refraction_D", column(py, &rows, |r| r.1.refraction_d))?;
    d.set_item("relative_D", column(py, &rows, |r| r.1.relative_d))?;
    add_age(py, &d, rows.iter().map(|r| r.0), g)?;
    Ok(d)
}

/// One snapshot's fields (fields.csv's columns, then the growth columns) as arrays.
fn snapshot_dict<'py>(py: Python<'py>, s: &Snapshot) -> PyResult<Bound<'py, PyDict>> {
    let d = fields_dict(py, &s.fields)?;
    for (j, name) in GROWTH_COLUMNS.iter().enumerate() {
        d.set_item(*name, column(py, &s.growth, |g| g.values()[j]))?;
    }
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
/// step; returns a dict: series, history, snapshots (a list of (t, fields)), sensitivities
/// (with `sensitivities`: the keys, as `eyeshell grow --sensitivities`), summary_text.
#[pyfunction]
#[pyo3(signature = (scene, progress = None, sensitivities = Vec::new(), sensitivity_error_control = false))]
fn grow<'py>(
    py: Python<'py>,
    scene: PyScene,
    progress: Option<Py<PyAny>>,
    sensitivities: Vec<String>,
    sensitivity_error_control: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let mut scene = scene.inner;
    scene
        .set_sensitivities(&sensitivities, sensitivity_error_control)
        .map_err(py_err)?;
    scene.solver.threads = eyeshell::scene::jobs_from_env().map_err(py_err)?;
    let (result, raised) = py.detach(|| {
        let mut watch = Watch {
            progress: progress.as_ref(),
            raised: None,
        };
        let result = scene.grow(&mut watch);
        (result, watch.raised)
    });
    if let Some(e) = raised {
        return Err(e);
    }
    let growth = result.map_err(py_err)?;
    let d = PyDict::new(py);
    let g = scene.growth.as_ref();
    d.set_item("series", series_dict(py, &growth.series, g)?)?;
    d.set_item("history", series_dict(py, &growth.history, g)?)?;
    let snapshots = PyList::empty(py);
    for s in &growth.snapshots {
        snapshots.append(PyTuple::new(
            py,
            [
                s.t.into_pyobject(py)?.into_any(),
                snapshot_dict(py, s)?.into_any(),
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

// ---------------------------------------------------------------------------------------
// Calibration

/// Fit the parameters `keys` of `scene` to observations (the CSV file `path`, or the
/// columns `t` (or `age`, in the scene's time.unit), `axial_length` and `sigma`), with the
/// GIL released, as `eyeshell fit`:
/// returns (fit.json's text, the report's table and its notes, the fitted scene). Ctrl-C stops it within a step of its
/// current growth run, as it stops `grow`.
#[pyfunction]
#[pyo3(signature = (scene, keys, path = None, t = None, axial_length = None, sigma = None, max_iterations = 50, age = None))]
#[allow(clippy::too_many_arguments)]
fn fit(
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
        return Err(input_err(format!(
            "max_iterations = {max_iterations}: must lie between 1 and 1000"
        )));
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
            return Err(input_err(
                "data: give a CSV file's path, or the columns t (or age) and axial_length (and sigma), not both t and age",
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

// ---------------------------------------------------------------------------------------
// Sweeps and comparisons

/// One run of a sweep: its name, its swept (key, value), its scene.
type PlannedRun<'py> = (String, Vec<(String, Bound<'py, PyAny>)>, PyScene);

/// The runs of the sweep in TOML `text` (`origin` names it), each as (name, values, scene),
/// values being (key, value) in the order of the swept keys: a scene key's value as the
/// run's scene holds it (fibres.D = 0 is the float 0.0, solver.nodes an int), as
/// `Scene.get` gives it, so that a sweep's values are the numbers its runs used.
#[pyfunction]
#[pyo3(signature = (text, origin, overrides = Vec::new()))]
fn expand_sweep<'py>(
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

/// Write a growth run's `snapshots` ((t, {column: values}), in time order, each with every
/// column of a snapshot file) to the directory `out` as `eyeshell export --mat` writes a
/// growth run: one .mat file per output time in the published scripts' layout, named by
/// `ages` (one per snapshot) in a scene with `time.unit` as its snapshot files are. Returns
/// the files written.
#[pyfunction]
#[pyo3(signature = (out, snapshots, compress = false, ages = None))]
fn export_growth(
    py: Python<'_>,
    out: std::path::PathBuf,
    snapshots: Vec<(f64, std::collections::HashMap<String, Vec<f64>>)>,
    compress: bool,
    ages: Option<Vec<f64>>,
) -> PyResult<Vec<std::path::PathBuf>> {
    if let Some(ages) = &ages {
        if ages.len() != snapshots.len() {
            return Err(input_err(format!(
                "to_mat: {} ages for {} snapshots",
                ages.len(),
                snapshots.len()
            )));
        }
    }
    use eyeshell::interop::export::{export_snapshots, Format, RunSnapshot, Table};
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
        .detach(|| export_snapshots(&runs, &out, Format::Mat { compress }, &[]))
        .map_err(|e| py_err(e.into()))?;
    Ok(done.files)
}

/// `eyeshell compare RUN REFERENCE --tol --rtol [--field]`: the reports, one dict per
/// pair, and the text the command prints.
#[pyfunction]
#[pyo3(signature = (run, reference, tol, rtol, field = None))]
fn compare<'py>(
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
            return Err(input_err(format!(
                "{name} = {v}: must be a finite number ≥ 0"
            )));
        }
    }
    let field = field
        .map(|f| {
            f.parse::<FieldSpec>()
                .map_err(|e| input_err(format!("field: {e}")))
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

/// The SUNDIALS version the module loads, as summary.json names it.
#[pyfunction]
fn sundials_version() -> Option<String> {
    eyeshell::rundir::sundials_version()
}

// ---------------------------------------------------------------------------------------
// The eye's optics

/// The best-focus surfaces of the scene's schematic eye (its `optics.*` keys), traced with
/// the GIL released: a dict of arrays, one entry per (wavelength, field), and the run's facts.
#[pyfunction]
fn optics<'py>(py: Python<'py>, scene: PyScene) -> PyResult<Bound<'py, PyDict>> {
    let scene = scene.inner;
    let spec = scene.optics().clone();
    let z_c = scene.blue().z_b;
    let computed = py.detach(|| spec.compute(z_c)).map_err(|e| {
        py_err(Error::from(eyeshell::scene::SceneError::Invalid {
            origin: scene.origin.clone(),
            key: e.key.to_string(),
            value: e.value,
            problem: e.problem,
        }))
    })?;
    let points: Vec<_> = computed
        .surfaces
        .surfaces
        .iter()
        .flat_map(|s| s.points.iter())
        .collect();
    let column = |f: &dyn Fn(&eyeshell_optics::Focus) -> f64| {
        points.iter().map(|p| f(p)).collect::<Vec<f64>>()
    };
    let d = PyDict::new(py);
    d.set_item("wavelength_nm", array1(py, column(&|p| p.wavelength_nm)))?;
    d.set_item("field_deg", array1(py, column(&|p| p.field_deg)))?;
    d.set_item("z", array1(py, column(&|p| p.z)))?;
    d.set_item("r", array1(py, column(&|p| p.r)))?;
    d.set_item("strehl", array1(py, column(&|p| p.strehl)))?;
    d.set_item("sagittal", array1(py, column(&|p| p.sagittal)))?;
    d.set_item("tangential", array1(py, column(&|p| p.tangential)))?;
    d.set_item("criterion", spec.criterion().name())?;
    d.set_item("eye", spec.eye_name())?;
    d.set_item("pupil", spec.pupil)?;
    d.set_item("z_B", z_c)?;
    d.set_item("phi_max", (computed.blue.phi_max(), computed.red.phi_max()))?;
    d.set_item("rays_traced", computed.surfaces.rays_traced)?;
    d.set_item("wall_seconds", computed.wall_seconds)?;
    Ok(d)
}

#[pymodule]
fn _eyeshell(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // Only the first wording counts; a second import in this process finds it set.
    eyeshell::text::set_wording(python_wording);
    m.add("EyeshellError", py.get_type::<EyeshellError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "MAX_HISTORY_POINTS",
        eyeshell::scene::keys::MAX_HISTORY_POINTS,
    )?;
    m.add_class::<PyScene>()?;
    m.add_class::<Solved>()?;
    m.add_function(wrap_pyfunction!(keys, m)?)?;
    m.add_function(wrap_pyfunction!(toml_literal, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(residual, m)?)?;
    m.add_function(wrap_pyfunction!(jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(grow, m)?)?;
    m.add_function(wrap_pyfunction!(optics, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(expand_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(export_growth, m)?)?;
    m.add_function(wrap_pyfunction!(sundials_version, m)?)?;
    Ok(())
}
