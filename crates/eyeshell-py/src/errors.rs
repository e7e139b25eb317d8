//! The exceptions: the library's errors as InputError or SolverError, and its advice in a
//! Python caller's terms.

use eyeshell::text::Advice;
use eyeshell::Error;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

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
pub(super) fn python_wording(a: &Advice<'_>) -> String {
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
pub(super) fn py_err(e: Error) -> PyErr {
    let line = eyeshell::text::one_line(&e.to_string().replace(['\n', '\r'], " "));
    if e.is_user_error() {
        InputError::new_err(line)
    } else {
        SolverError::new_err(line)
    }
}

pub(super) fn input_err(message: impl Into<String>) -> PyErr {
    InputError::new_err(message.into())
}
