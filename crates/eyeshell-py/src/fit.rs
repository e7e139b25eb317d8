//! Calibration: a fit of scene keys to axial lengths and refractions, of one scene or of
//! several arms jointly.

use pyo3::prelude::*;

use super::errors::{argument_err, py_err};
use super::grow::Watch;
use super::scene::PyScene;

/// One arm as the Python layer hands it: its name (None for the fit of one scene), its
/// scene, and its data: a CSV file's path, or the first column's name ("t" or "age"), its
/// values and the other columns by name.
type ArmData = (
    Option<String>,
    PyScene,
    Option<std::path::PathBuf>,
    String,
    Vec<f64>,
    Vec<(String, Vec<f64>)>,
);

/// Fit the keys `keys` (shared by every arm) and `per_arm` (each arm's own) of the arms'
/// scenes to their observations, with the GIL released, as `eyeshell fit`: returns
/// (fit.json's text, the report's table, its notes, each arm's fitted scene). Ctrl-C stops
/// it within a step of its current growth run, as it stops `grow`.
#[pyfunction]
#[pyo3(signature = (arms, keys, per_arm = vec![], max_iterations = 50))]
pub(super) fn fit(
    py: Python<'_>,
    arms: Vec<ArmData>,
    keys: Vec<String>,
    per_arm: Vec<String>,
    max_iterations: usize,
) -> PyResult<(String, String, Vec<String>, Vec<PyScene>)> {
    use eyeshell::fit::{Arm, FitOptions, Observations};
    if !(1..=1000).contains(&max_iterations) {
        return Err(argument_err(
            format!("max_iterations = {max_iterations}: must lie between 1 and 1000"),
            "max_iterations",
            Some(max_iterations.to_string()),
        ));
    }
    let shared = eyeshell::fit::parse_fit_keys(&keys, "fit").map_err(py_err)?;
    let per_arm = match per_arm.is_empty() {
        true => vec![],
        false => eyeshell::fit::parse_fit_keys(&per_arm, "per_arm").map_err(py_err)?,
    };
    let mut built = Vec::with_capacity(arms.len());
    for (name, scene, path, first, times, columns) in arms {
        let origin = name
            .as_deref()
            .map_or("data".to_string(), |n| format!("arms[{n:?}]"));
        let data = match path {
            Some(p) => Observations::read(&p),
            None => {
                let cols: Vec<(&str, &[f64])> = (columns.iter())
                    .map(|(n, c)| (n.as_str(), c.as_slice()))
                    .collect();
                Observations::from_table(&first, &times, &cols, &origin)
            }
        }
        .map_err(py_err)?;
        built.push(Arm {
            name,
            scene: scene.inner,
            data,
        });
    }
    let first = built.first().map(|a| a.scene.clone());
    let options = FitOptions {
        max_iterations,
        ..FitOptions::default()
    };
    let t_end = first
        .as_ref()
        .and_then(|s| s.growth.as_ref())
        .map_or(f64::NAN, |g| g.t_end);
    let (result, raised) = py.detach(|| {
        let mut watch = Watch {
            progress: None,
            raised: None,
        };
        let result =
            eyeshell::fit::fit_arms(built, &shared, &per_arm, &options, &mut |_| {}, &mut |t| {
                eyeshell::growth::Observer::progress(&mut watch, t, t_end)
            });
        (result, watch.raised)
    });
    if let Some(e) = raised {
        return Err(e);
    }
    let done = result.map_err(py_err)?;
    let json = eyeshell::fit::report_json(&done.report);
    let text = eyeshell::fit::report::report_table(&done.scene, &done.report);
    let notes = eyeshell::fit::report::notes(&done.report);
    let scenes = done
        .scenes
        .into_iter()
        .map(|inner| PyScene { inner })
        .collect();
    Ok((json, text, notes, scenes))
}
