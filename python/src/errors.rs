//! The library's error kinds as Python exceptions (defined in `sweeptin/_errors.py`, where they
//! can inherit from both `SweeptinError` and the built-in class a Python user catches).

use pyo3::prelude::*;
use pyo3::types::PyDict;
use sweeptin::{Error, ErrorKind};

/// The exception class (by name in `sweeptin._errors`) of each library error: a finer class
/// where one fits, otherwise the class of its kind ([`Error::kind`], the command line's exit
/// status).
fn class_of(e: &Error) -> &'static str {
    match e {
        Error::TooFewPoints { .. } | Error::AllCollinear { .. } | Error::NothingLeft { .. } => {
            "NoTriangleError"
        }
        Error::NoInput | Error::Options(_) => "OptionsError",
        Error::Io { source, .. } | Error::Write { source, .. }
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            "MissingFileError"
        }
        Error::Io { .. } | Error::Write { .. } => "FileError",
        Error::OutOfMemory { .. } => "OutOfMemoryError",
        _ => match e.kind() {
            ErrorKind::Usage => "OptionsError",
            ErrorKind::Input => "InputError",
            ErrorKind::Output => "OutputError",
            ErrorKind::Interrupted => "Interrupted",
            _ => "InternalError",
        },
    }
}

/// The kind's name (`usage`, `input`, `output`, `internal`, `interrupted`) and exit status.
fn kind_of(e: &Error) -> (&'static str, u8) {
    let k = e.kind();
    let name = match k {
        ErrorKind::Usage => "usage",
        ErrorKind::Input => "input",
        ErrorKind::Output => "output",
        ErrorKind::Interrupted => "interrupted",
        _ => "internal",
    };
    (name, k.exit_code())
}

/// Attributes that locate the problem: `path`, `line`, `index`.
fn attributes<'py>(py: Python<'py>, e: &Error) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match e {
        Error::Io { path, .. }
        | Error::Write { path, .. }
        | Error::Format { path, .. }
        | Error::Output { path, .. } => {
            d.set_item("path", path)?;
        }
        Error::NothingLeft { files, .. } => {
            if let [one] = files.as_slice() {
                d.set_item("path", one)?;
            }
        }
        Error::Parse { path, line, .. } => {
            d.set_item("path", path)?;
            d.set_item("line", line)?;
        }
        Error::NonFinite { index, .. } | Error::CoordinateOutOfRange { index, .. } => {
            d.set_item("index", index)?;
        }
        _ => {}
    }
    let (kind, exit_code) = kind_of(e);
    d.set_item("kind", kind)?;
    d.set_item("exit_code", exit_code)?;
    Ok(d)
}

fn build(py: Python<'_>, e: &Error) -> PyResult<PyErr> {
    let module = py.import("sweeptin._errors")?;
    let name = class_of(e);
    if name == "Interrupted" {
        return Ok(pyo3::exceptions::PyKeyboardInterrupt::new_err(
            e.to_string(),
        ));
    }
    let class = module.getattr(name)?;
    let exc = class.call1((e.to_string(),))?;
    for (k, v) in attributes(py, e)?.iter() {
        exc.setattr(k.extract::<&str>()?, v)?;
    }
    Ok(PyErr::from_value(exc))
}

/// The Python exception for a library error.
pub(crate) fn to_py(e: Error) -> PyErr {
    Python::attach(|py| build(py, &e).unwrap_or_else(|failed| failed))
}

/// `ValueError` for a bad argument caught in the binding.
pub(crate) fn value_error(message: impl Into<String>) -> PyErr {
    to_py(Error::Options(message.into()))
}

/// Runs `work` with the GIL released, as `py.detach`, and turns a panic in it into
/// [`sweeptin::Error::Internal`] (raised as `InternalError`, exit code 5, as the command line
/// reports one), never pyo3's `PanicException`, which `except Exception` misses.
pub(crate) fn detach_guarded<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> sweeptin::Result<T> + Send,
) -> sweeptin::Result<T> {
    py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
            .unwrap_or_else(|p| Err(sweeptin::Error::panicked("binding's", &*p)))
    })
}
