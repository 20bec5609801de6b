//! `sweeptin._sweeptin`: the native half of the Python package `sweeptin` (the pure-Python
//! `sweeptin/__init__.py` wraps it with argument checks, docstrings and type hints).
//!
//! Everything here is glue: numpy arrays in and out, library errors mapped to the exceptions of
//! `sweeptin/_errors.py`, and the GIL released around every call into the library. The work
//! itself is the library's: `triangulate`/`triangulate_cdt` in memory, the streaming pipeline
//! (`pipeline::run`) with the products' sinks for files, and `plan` for tile plans.

use pyo3::prelude::*;

mod errors;
mod files;
mod ground;
mod interrupt;
mod memory;
mod plans;

pub(crate) use errors::to_py;

#[pymodule]
fn _sweeptin(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Built for x86-64-v2 (.cargo/config.toml): an ImportError on an older processor, before
    // anything could run an instruction it lacks.
    if let Some(missing) = sweeptin::cpu::missing_features() {
        return Err(pyo3::exceptions::PyImportError::new_err(
            sweeptin::cpu::message(&missing),
        ));
    }
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<memory::Tin>()?;
    m.add_function(wrap_pyfunction!(memory::triangulate, m)?)?;
    m.add_class::<files::TriangleStream>()?;
    m.add_function(wrap_pyfunction!(files::run_products, m)?)?;
    m.add_function(wrap_pyfunction!(files::run_tin, m)?)?;
    m.add_function(wrap_pyfunction!(files::stream_triangles, m)?)?;
    m.add_function(wrap_pyfunction!(files::parse_size, m)?)?;
    m.add_function(wrap_pyfunction!(files::parse_classes, m)?)?;
    m.add_function(wrap_pyfunction!(files::default_mem, m)?)?;
    m.add_function(wrap_pyfunction!(ground::ground_points, m)?)?;
    m.add_function(wrap_pyfunction!(ground::ground_files_native, m)?)?;
    m.add_function(wrap_pyfunction!(ground::height_files, m)?)?;
    m.add_function(wrap_pyfunction!(plans::make_plan, m)?)?;
    m.add_function(wrap_pyfunction!(plans::run_task, m)?)?;
    m.add_function(wrap_pyfunction!(plans::merge, m)?)?;
    m.add_function(wrap_pyfunction!(plans::task_count, m)?)?;
    Ok(())
}
