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
        Error::TooFewPoints { .. }
        | Error::AllCollinear { .. }
        | Error::NothingLeft { .. }
        | Error::NoArea { .. } => "NoTriangleError",
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

/// The package's parameter for each command-line flag the library's messages name (`--class`
/// is `classes=`); a flag of a yes/no option reads as the value that turns it on.
const PARAMETERS: &[(&str, &str)] = &[
    ("--align", "align="),
    ("--base", "base="),
    ("--bbox", "bbox="),
    ("--bigtiff", "bigtiff=True"),
    ("--boundary", "boundary="),
    ("--breaklines", "breaklines="),
    ("--buffer", "buffer="),
    ("--cell", "cell="),
    ("--class", "classes="),
    ("--compress", "compress="),
    ("--contours", "contours="),
    ("--crs", "crs="),
    ("--duplicates", "duplicates="),
    ("--engine", "engine="),
    ("--format", "format="),
    ("--hillshade", "hillshade="),
    ("--holes", "holes="),
    ("--interval", "interval="),
    ("--keep-withheld", "keep_withheld=True"),
    ("--max-cells", "max_cells="),
    ("--max-edge", "max_edge="),
    ("--mem", "mem="),
    ("--nodata", "nodata="),
    ("--plane", "plane="),
    ("--predictor", "predictor="),
    ("--resume", "resume=True"),
    ("--returns", "returns="),
    ("--snap", "snap=True"),
    ("--threads", "threads="),
    ("--tile", "tile="),
    ("--tmp-dir", "tmp_dir="),
    ("--trim-boundary", "trim_boundary="),
    ("--volume-plane", "plane="),
];

/// `message` with the command-line flags it names (`--tile 0: must be …`, `dropped by
/// --class`) spelt as the package's parameters (`tile=0: must be …`, `dropped by classes=`),
/// so that a Python user is told what to change in the call. A flag's value (a number, or a
/// word ending a clause) joins it after `=`; flags the package has no parameter for, and
/// anything between backquotes (a command to run), stay as they are.
pub(crate) fn python_names(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut quoted = false;
    let mut rest = message;
    while let Some(c) = rest.chars().next() {
        let at_flag = !quoted
            && rest.starts_with("--")
            && out.chars().last().is_none_or(|p| " (,\"'".contains(p));
        if at_flag {
            let len = 2 + rest[2..]
                .find(|c: char| !(c.is_ascii_lowercase() || c == '-'))
                .unwrap_or(rest.len() - 2);
            if let Some((_, param)) = PARAMETERS.iter().find(|(f, _)| *f == &rest[..len]) {
                out.push_str(param);
                rest = &rest[len..];
                // `--tile 0:` → `tile=0:`, `--interval 0,` → `interval=0,`.
                if param.ends_with('=')
                    && let Some(value) = rest.strip_prefix(' ')
                {
                    let word = value.split(' ').next().unwrap_or("");
                    let numeric = word
                        .chars()
                        .next()
                        .is_some_and(|c| c.is_ascii_digit() || "-+.".contains(c))
                        || ["nan", "inf", "NaN"].iter().any(|w| word.starts_with(w));
                    let ends_clause = word.len() > 1 && word.ends_with([':', ',', ')', ';']);
                    if numeric || ends_clause {
                        rest = value;
                    }
                }
                continue;
            }
        }
        if c == '`' {
            quoted = !quoted;
        }
        out.push(c);
        rest = &rest[c.len_utf8()..];
    }
    out
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
    let exc = class.call1((python_names(&e.to_string()),))?;
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
