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

mod convert;
mod discrete;
mod errors;
mod fit;
mod grow;
mod interop;
mod optics;
mod outputs;
mod rule;
mod scene;
mod solve;
mod sweep;

use pyo3::prelude::*;

use errors::{python_wording, EyeshellError, InputError, SolverError};
use scene::PyScene;
use solve::Solved;

/// The SUNDIALS version the module loads, as summary.json names it.
#[pyfunction]
fn sundials_version() -> Option<String> {
    eyeshell::rundir::sundials_version()
}

// ---------------------------------------------------------------------------------------
// The eye's optics

#[pymodule]
fn _eyeshell(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // Only the first wording counts; a second import in this process finds it set.
    eyeshell::text::set_wording(python_wording);
    errors::register_defaults(py)?;
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
    m.add_function(wrap_pyfunction!(scene::keys, m)?)?;
    m.add_function(wrap_pyfunction!(convert::toml_literal, m)?)?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_function(wrap_pyfunction!(discrete::residual, m)?)?;
    m.add_function(wrap_pyfunction!(discrete::jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(grow::grow, m)?)?;
    m.add_function(wrap_pyfunction!(optics::optics, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::expand_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(interop::compare, m)?)?;
    m.add_function(wrap_pyfunction!(interop::export_growth, m)?)?;
    m.add_function(wrap_pyfunction!(sundials_version, m)?)?;
    m.add_function(wrap_pyfunction!(outputs::output_quantities, m)?)?;
    m.add_function(wrap_pyfunction!(outputs::_register_output_for_tests, m)?)?;
    Ok(())
}
