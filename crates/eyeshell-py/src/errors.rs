//! The exceptions: the library's errors as InputError or SolverError, each with the key,
//! value and origin the error is about (`None` where it names none), and the library's
//! advice in a Python caller's terms.

use eyeshell::text::Advice;
use eyeshell::Error;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    eyeshell,
    EyeshellError,
    PyException,
    "Any error of eyeshell: an InputError or a SolverError. Besides the one-line message, every one carries `key` (the scene key, argument, column or file it is about), `value` (the value at fault as it was given, shortened) and `origin` (where it came from: the scene file's path, `set KEY=VALUE` for a keyword argument, a data file), each None where the error names none, and `stage` (a SolverError's: solve, growth, optics, fit, sweep, file, plot or study; None for an InputError)."
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
        Advice::SetKey => "a keyword override (section__key=value)".into(),
        Advice::ListKeys => "eyeshell.keys()".into(),
        Advice::Field { name: None } => "field=\"NAME\"".into(),
        Advice::Field { name: Some(name) } => format!("field={:?}", one_line(name)),
    }
}

/// The attributes every exception of eyeshell has, set on the classes to None (an exception
/// raised without them, by the Python layer, has them too) and on each instance made here.
pub(super) const ATTRIBUTES: [&str; 4] = ["key", "value", "origin", "stage"];

/// The library's error as its Python exception, with the library's one-line message and
/// what the error is about.
pub(super) fn py_err(e: Error) -> PyErr {
    let line = eyeshell::text::one_line(&e.to_string().replace(['\n', '\r'], " "));
    let err = if e.is_user_error() {
        InputError::new_err(line)
    } else {
        SolverError::new_err(line)
    };
    let stage = e.stage().map(|s| s.name().to_string());
    with_attributes(err, [e.key(), e.value(), e.origin(), stage])
}

/// Bad input found by the binding itself about no one argument (its key, value and origin
/// None).
pub(super) fn input_err(message: impl Into<String>) -> PyErr {
    InputError::new_err(message.into())
}

/// [`input_err`] naming the argument `key` and its `value`, given in the call.
pub(super) fn argument_err(message: impl Into<String>, key: &str, value: Option<String>) -> PyErr {
    let err = InputError::new_err(message.into());
    with_attributes(
        err,
        [Some(key.into()), value, Some("argument".into()), None],
    )
}

fn with_attributes(err: PyErr, values: [Option<String>; 4]) -> PyErr {
    Python::attach(|py| {
        let v = err.value(py);
        for (name, value) in ATTRIBUTES.iter().zip(values) {
            // Setting an attribute on a fresh exception cannot fail but for memory; the
            // class's None stands in then.
            let _ = v.setattr(*name, value);
        }
    });
    err
}

/// Set the attributes' defaults (None) on the base class, which the others inherit.
pub(super) fn register_defaults(py: Python<'_>) -> PyResult<()> {
    let base = py.get_type::<EyeshellError>();
    for name in ATTRIBUTES {
        base.setattr(name, py.None())?;
    }
    Ok(())
}
