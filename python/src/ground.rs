//! The ground filter and heights above ground: `ground_points` on arrays
//! (`sweeptin::ground::classify`), `ground_files` and `height_files` on files
//! (`pipeline::ground::ground_files`, `pipeline::height::height`), each the library's own.

use crate::errors::{detach_guarded, value_error};
use crate::to_py;
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;
use sweeptin::ground::{GroundParams, Terrain};
use sweeptin::pipeline::height::{Ground, HeightJob, height};
use sweeptin::pipeline::{RunOptions, ground::ground_files};

/// The filter's parameters: the preset's (or the defaults), each value given over it.
#[derive(Clone, Debug, Default, FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct ParamsOpts {
    preset: Option<String>,
    step: Option<f64>,
    max_distance: Option<f64>,
    max_angle: Option<f64>,
    low_noise: Option<f64>,
    offset: Option<f64>,
    densify_cell: Option<f64>,
    mirror: bool,
    reset: bool,
}

impl ParamsOpts {
    pub(crate) fn params(&self) -> PyResult<GroundParams> {
        let mut p = match self.preset.as_deref() {
            None => GroundParams::default(),
            Some(name) => match name {
                "wilderness" => Terrain::Wilderness,
                "nature" => Terrain::Nature,
                "town" => Terrain::Town,
                "city" => Terrain::City,
                "metro" => Terrain::Metro,
                "forest" => Terrain::Forest,
                "mountains" => Terrain::Mountains,
                _ => {
                    return Err(value_error(format!(
                        "preset={name:?}: use 'wilderness', 'nature', 'town', 'city', 'metro', \
                         'forest' or 'mountains'"
                    )));
                }
            }
            .params(),
        };
        p.step = self.step.unwrap_or(p.step);
        p.max_distance = self.max_distance.unwrap_or(p.max_distance);
        p.max_angle = self.max_angle.unwrap_or(p.max_angle);
        p.low_noise = self.low_noise.unwrap_or(p.low_noise);
        p.offset = self.offset.unwrap_or(p.offset);
        p.densify_cell = self.densify_cell.unwrap_or(p.densify_cell);
        p.mirror = self.mirror;
        p.reset = self.reset;
        p.check().map_err(to_py)?;
        Ok(p)
    }
}

/// The classes of the points `xyz` (`(n, 3)`), given with their classes and withheld flags.
#[pyfunction]
#[pyo3(signature = (xyz, classes, withheld, params, mem))]
pub(crate) fn ground_points<'py>(
    py: Python<'py>,
    xyz: PyReadonlyArray2<'py, f64>,
    classes: PyReadonlyArray1<'py, u8>,
    withheld: PyReadonlyArray1<'py, bool>,
    params: ParamsOpts,
    mem: u64,
) -> PyResult<Bound<'py, PyArray1<u8>>> {
    if xyz.shape()[1] != 3 {
        return Err(value_error(format!(
            "xyz must have shape (n, 3), not {:?}",
            xyz.shape()
        )));
    }
    let flat = xyz
        .as_slice()
        .map_err(|_| value_error("xyz must be C-contiguous"))?;
    let points: &[[f64; 3]] = bytemuck::cast_slice(flat);
    let classes = classes
        .as_slice()
        .map_err(|_| value_error("classes must be contiguous"))?;
    let withheld = withheld
        .as_slice()
        .map_err(|_| value_error("withheld must be contiguous"))?;
    let params = params.params()?;
    let out = detach_guarded(py, || {
        sweeptin::ground::classify(points, classes, withheld, &params, mem)
    })
    .map_err(to_py)?;
    let a = PyArray1::from_vec(py, out);
    Ok(a)
}

/// `sweeptin ground`: each input written to its output with the new classes; the summary as
/// JSON.
#[pyfunction]
#[pyo3(name = "ground_files", signature = (files, outputs, params, mem, tmp_dir = None))]
pub(crate) fn ground_files_native(
    py: Python<'_>,
    files: Vec<PathBuf>,
    outputs: Vec<PathBuf>,
    params: ParamsOpts,
    mem: u64,
    tmp_dir: Option<PathBuf>,
) -> PyResult<String> {
    let params = params.params()?;
    let tmp = tmp_dir.unwrap_or_else(std::env::temp_dir);
    let done = detach_guarded(py, || {
        ground_files(&files, &outputs, &params, mem, &tmp, &mut |_, _, _| {})
    })
    .map_err(to_py)?;
    serde_json::to_string(&done).map_err(|e| value_error(e.to_string()))
}

/// `sweeptin height`: each input written with its heights above the ground (the class-2
/// points, `ground_class`, or the ground found with `params`); the summary as JSON.
#[pyfunction]
#[pyo3(signature = (files, outputs, params, ground_class, replace_z, mem, threads, tmp_dir = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn height_files(
    py: Python<'_>,
    files: Vec<PathBuf>,
    outputs: Vec<PathBuf>,
    params: Option<ParamsOpts>,
    ground_class: Vec<u8>,
    replace_z: bool,
    mem: u64,
    threads: usize,
    tmp_dir: Option<PathBuf>,
) -> PyResult<String> {
    let ground = match params {
        Some(p) => Ground::Classify(p.params()?),
        None => Ground::Classes(ground_class),
    };
    let job = HeightJob {
        inputs: files,
        outputs,
        ground,
        replace_z,
    };
    sweeptin::pipeline::check_threads(threads).map_err(to_py)?;
    sweeptin::pipeline::size_thread_pool(threads);
    let options = RunOptions {
        mem,
        tmp_dir,
        tiles: Some(sweeptin::TileOptions {
            threads,
            tile: None,
            base: None,
            scope: None,
        }),
        ..RunOptions::default()
    };
    let s = detach_guarded(py, || height(&job, &options)).map_err(to_py)?;
    let v = serde_json::json!({
        "points": s.points,
        "ground_points": s.ground_points,
        "outside": s.outside,
        "files": s.files,
    });
    Ok(v.to_string())
}
