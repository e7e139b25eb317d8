//! Elastic solves: `_Solved`, the solution's fields and its .mat variables.

use eyeshell::bvp::{Solution, COLUMNS};
use eyeshell::interop::export::{elastic_mat_vars, ElasticExtras, Table};
use eyeshell::interop::mat::MatValue;
use eyeshell::scene::Scene;
use numpy::ndarray::{Array2, ShapeBuilder};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{array1, fields_dict};
use super::errors::{argument_err, py_err, SolverError};
use super::scene::PyScene;

/// A solved shell: the library's [`Solution`] and the scene it solves.
#[pyclass(name = "_Solved", module = "eyeshell._eyeshell", frozen)]
pub(super) struct Solved {
    scene: Scene,
    solution: Solution,
}

/// Solve the loaded shell of `scene`, with the GIL released.
#[pyfunction]
pub(super) fn solve(py: Python<'_>, scene: PyScene) -> PyResult<Solved> {
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
                    return Err(argument_err(
                        format!("at: Σ = {x} is outside the shell [ε, L] = [{lo}, {hi}] (solver.epsilon, π·geometry.fraction·geometry.R0)"),
                        "at",
                        Some(x.to_string()),
                    ));
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

    /// The eye of the loaded, ungrown shell as a sweep's table measures it: the measures of
    /// the table of outputs that an elastic solve computes (axial_length,
    /// equatorial_radius, retina_minus_blue, retina_minus_red, class, and refraction_D for a
    /// scene with optics to compute it with; a NaN is left out).
    fn eye<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        use eyeshell::outputs::{Measures, Value};
        let eye = eyeshell::sweep::run::unloaded_eye(&self.scene, &self.solution.rows);
        let d = PyDict::new(py);
        for (name, value) in Measures::of(&eyeshell::growth::SeriesRow::new(0.0, eye)).0 {
            match value {
                Value::Number(x) if x.is_nan() => {}
                Value::Number(x) => d.set_item(name, x)?,
                Value::Text(s) => d.set_item(name, s)?,
            }
        }
        Ok(d)
    }

    /// The refraction (D) at the pole of the loaded, ungrown shell through the naked eye, as
    /// summary.json's `refraction_D`: None for a scene with no optics to compute it with,
    /// NaN beyond the ±25 D the optics are traced over.
    fn refraction_d(&self) -> Option<f64> {
        self.scene.refraction_of(&self.solution.rows)
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
