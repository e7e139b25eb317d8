//! The table of outputs (`eyeshell::outputs`) for the Python package: the frames' columns
//! come from it, as the command line's files do.

use eyeshell::outputs::{self, Cell, Kind, Quantity};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The measures of the eye in their columns' order: name, unit, description, how it is
/// computed and kind ("number" or "class") of each.
#[pyfunction]
pub(super) fn output_quantities(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    outputs::quantities()
        .iter()
        .map(|q| {
            let d = PyDict::new(py);
            d.set_item("name", q.name)?;
            d.set_item("unit", q.unit)?;
            d.set_item("description", q.description)?;
            d.set_item("computed", q.computed)?;
            d.set_item(
                "kind",
                match q.kind {
                    Kind::Number => "number",
                    Kind::Class => "class",
                },
            )?;
            Ok(d)
        })
        .collect()
}

/// Add a column to the table for this process, for the test that finds it in the frames
/// (crates/eyeshell-py/tests/test_outputs.py, in a process of its own): the axial length
/// in micrometres. Nothing else calls it.
#[pyfunction]
pub(super) fn _register_output_for_tests() {
    outputs::register_for_tests(Quantity {
        name: "axial_length_um",
        unit: "µm",
        description: "axial length in micrometres",
        computed: "1000 × axial_length (a column only the tests add)",
        kind: Kind::Number,
        added_later: true,
        of: |r| Cell::Number(r.axial_length * 1000.0),
    });
}
