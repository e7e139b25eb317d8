//! The discrete equations: the residual and Jacobian of a scene's BVP.

use eyeshell::scene::Scene;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use super::convert::array1;
use super::errors::py_err;
use super::scene::PyScene;

/// The discrete problem of `scene` and the state checked against it.
fn discrete(scene: &Scene) -> PyResult<eyeshell::discrete::DiscreteProblem> {
    scene.discrete_problem().map_err(py_err)
}

/// F(state) of the scene's discrete elastic problem (scaled as Newton's test scales it
/// when `scaled`), with the GIL released.
#[pyfunction]
pub(super) fn residual<'py>(
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
pub(super) fn jacobian<'py>(
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
