//! The eye's optics: the best-focus surfaces traced through the scene's schematic eye.

use eyeshell::Error;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::array1;
use super::errors::py_err;
use super::scene::PyScene;

/// The best-focus surfaces of the scene's schematic eye (its `optics.*` keys), traced with
/// the GIL released: a dict of arrays, one entry per (wavelength, field), and the run's facts.
#[pyfunction]
pub(super) fn optics<'py>(py: Python<'py>, scene: PyScene) -> PyResult<Bound<'py, PyDict>> {
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
    d.set_item("refraction", refraction(py, &scene)?)?;
    Ok(d)
}

/// The refraction without growing, as `eyeshell optics` writes it (refraction.csv,
/// peripheral.csv): of the loaded, ungrown retina, at t = 0 and each table time, naked and
/// through each image of the lenses; None for a scene with no optics to compute it with.
fn refraction<'py>(
    py: Python<'py>,
    scene: &eyeshell::Scene,
) -> PyResult<Option<Vec<Bound<'py, PyDict>>>> {
    if scene.refraction_optics().is_none() {
        return Ok(None);
    }
    let at = py
        .detach(|| {
            scene
                .solve()
                .and_then(|solution| scene.refraction(&solution))
        })
        .map_err(py_err)?;
    let peripheral = |rows: &[eyeshell::growth::PeripheralRow]| -> PyResult<Bound<'py, PyDict>> {
        let p = PyDict::new(py);
        p.set_item(
            "field_deg",
            array1(py, rows.iter().map(|r| r.field_deg).collect()),
        )?;
        p.set_item(
            "refraction_D",
            array1(py, rows.iter().map(|r| r.refraction_d).collect()),
        )?;
        p.set_item(
            "relative_D",
            array1(py, rows.iter().map(|r| r.relative_d).collect()),
        )?;
        Ok(p)
    };
    at.iter()
        .map(|a| {
            let d = PyDict::new(py);
            d.set_item("t", a.t)?;
            d.set_item("refraction_D", a.pole_d)?;
            d.set_item("peripheral", peripheral(&a.peripheral)?)?;
            let through = (a.through.iter())
                .map(|l| {
                    let e = PyDict::new(py);
                    e.set_item("image_power_D", l.image_power)?;
                    e.set_item("refraction_D", l.pole_d)?;
                    e.set_item("peripheral", peripheral(&l.peripheral)?)?;
                    Ok(e)
                })
                .collect::<PyResult<Vec<_>>>()?;
            d.set_item("through_lenses", through)?;
            Ok(d)
        })
        .collect::<PyResult<Vec<_>>>()
        .map(Some)
}
