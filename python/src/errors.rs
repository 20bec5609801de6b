//! The library's error kinds as Python exceptions (defined in `sweeptin/_errors.py`, where they
//! can inherit from both `SweeptinError` and the built-in class a Python user catches).

use pyo3::prelude::*;
use pyo3::types::PyDict;
use sweeptin::Error;

/// The exception class (by name in `sweeptin._errors`) of each library error.
fn class_of(e: &Error) -> &'static str {
    match e {
        Error::TooFewPoints { .. } | Error::AllCollinear { .. } => "NoTriangleError",
        Error::NonFinite { .. }
        | Error::CoordinateOutOfRange { .. }
        | Error::TooManyPoints { .. }
        | Error::OutOfOrder { .. }
        | Error::Parse { .. }
        | Error::Format { .. }
        | Error::BadLine { .. }
        | Error::Invalid(_) => "InputError",
        Error::NoInput | Error::Options(_) => "OptionsError",
        Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            "MissingFileError"
        }
        Error::Io { .. } => "FileError",
        Error::Output { .. } => "OutputError",
        Error::BufferTooSmall { .. } | Error::Internal(_) => "InternalError",
        Error::Interrupted => "Interrupted",
        _ => "SweeptinError",
    }
}

/// Attributes that locate the problem: `path`, `line`, `index`.
fn attributes<'py>(py: Python<'py>, e: &Error) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match e {
        Error::Io { path, .. } | Error::Format { path, .. } | Error::Output { path, .. } => {
            d.set_item("path", path)?;
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
