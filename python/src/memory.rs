//! The in-memory API: `triangulate(xyz)` → `Tin`, and what a `Tin` answers (heights at points,
//! a raster, contours, a mesh file), each through the library's own code.

use crate::errors::value_error;
use crate::to_py;
use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::sync::Mutex;
use sweeptin::products::contours::{ContourOptions, ContourSink};
use sweeptin::products::dem::{DemOptions, DemSink};
use sweeptin::raster::{Align, GridExtent, GridPlan};
use sweeptin::sink::{StreamInfo, TriangleSink};
use sweeptin::{DuplicatePolicy, Options};

/// The duplicate policy named `s`.
pub(crate) fn duplicates(s: &str) -> PyResult<DuplicatePolicy> {
    Ok(match s {
        "first" => DuplicatePolicy::First,
        "last" => DuplicatePolicy::Last,
        "lowest" => DuplicatePolicy::Lowest,
        "highest" => DuplicatePolicy::Highest,
        _ => {
            return Err(value_error(format!(
                "duplicates={s:?}: use 'first', 'last', 'lowest' or 'highest'"
            )));
        }
    })
}

/// The cell alignment named `s` (`--align`).
pub(crate) fn align(s: &str) -> PyResult<Align> {
    match s {
        "edges" => Ok(Align::Edges),
        "centres" | "centers" => Ok(Align::Centres),
        _ => Err(value_error(format!(
            "align={s:?}: use 'edges' (cell edges on multiples of the cell, GDAL's -tap) or \
             'centres' (cell centres on multiples)"
        ))),
    }
}

/// The rows of a C-contiguous `(n, k)` array as `[T; K]`s, without a copy.
fn rows<'a, T: numpy::Element + bytemuck::Pod, const K: usize>(
    a: &'a PyReadonlyArray2<'_, T>,
    what: &str,
) -> PyResult<&'a [[T; K]]> {
    if a.shape()[1] != K {
        return Err(value_error(format!(
            "{what} must have shape (n, {K}), not {:?}",
            a.shape()
        )));
    }
    let flat = a
        .as_slice()
        .map_err(|_| value_error(format!("{what} must be C-contiguous")))?;
    Ok(bytemuck::cast_slice(flat))
}

/// A read-only numpy array that owns `rows` (moved, not copied).
fn to_array<'py, T: numpy::Element + bytemuck::Pod, const K: usize>(
    py: Python<'py>,
    rows: Vec<[T; K]>,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let n = rows.len();
    let flat: Vec<T> = bytemuck::cast_vec(rows);
    let a = Array2::from_shape_vec((n, K), flat).map_err(|e| value_error(e.to_string()))?;
    let a = numpy::PyArray2::from_owned_array(py, a);
    a.getattr("flags")?.setattr("writeable", false)?;
    Ok(a)
}

/// A Delaunay TIN in memory (see `sweeptin.Tin` in the package for the documentation).
#[pyclass(frozen, module = "sweeptin._sweeptin")]
pub struct Tin {
    vertices: Py<PyArray2<f64>>,
    triangles: Py<PyArray2<u32>>,
    input_index: Py<PyArray1<u32>>,
    #[pyo3(get)]
    duplicates: u64,
    #[pyo3(get)]
    crossing_skipped: u64,
    /// The sweep's adjacency (`twins[3t + k]`), 12 bytes per triangle, for `interpolate`.
    twins: Vec<u32>,
    /// The walkable TIN for `interpolate`, built from `twins` on first use.
    walk: Mutex<Option<sweeptin::Tin>>,
}

#[pyfunction]
#[pyo3(signature = (xyz, duplicates = "first", segments = None))]
pub(crate) fn triangulate(
    py: Python<'_>,
    xyz: PyReadonlyArray2<'_, f64>,
    duplicates: &str,
    segments: Option<PyReadonlyArray2<'_, u32>>,
) -> PyResult<Tin> {
    let options = Options {
        duplicates: self::duplicates(duplicates)?,
    };
    let points: &[[f64; 3]] = rows(&xyz, "xyz")?;
    let segs: &[[u32; 2]] = match &segments {
        Some(s) => rows(s, "segments")?,
        None => &[],
    };
    let (t, twins) = crate::errors::detach_guarded(py, || {
        sweeptin::triangulation::triangulate_with_twins(points, segs, &options)
    })
    .map_err(to_py)?;
    let index = numpy::PyArray1::from_vec(py, t.input_index);
    index.getattr("flags")?.setattr("writeable", false)?;
    Ok(Tin {
        vertices: to_array(py, t.vertices)?.unbind(),
        triangles: to_array(py, t.triangles)?.unbind(),
        input_index: index.unbind(),
        duplicates: t.duplicates,
        crossing_skipped: t.constraint_stats.crossing_skipped,
        twins,
        walk: Mutex::new(None),
    })
}

/// The bounds `[xmin, ymin, xmax, ymax]` of `v`.
fn bounds(v: &[[f64; 3]]) -> [f64; 4] {
    v.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ]
        },
    )
}

/// Feeds every triangle of `(vertices, triangles)` to `sink`, from begin to finish.
fn feed(
    sink: &mut dyn TriangleSink,
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> sweeptin::Result<()> {
    sink.begin(&StreamInfo {
        crs: None,
        bounds: bounds(vertices),
    })?;
    for t in triangles {
        sink.triangle(&t.map(|i| vertices[i as usize]))?;
    }
    sink.finish()?;
    Ok(())
}

impl Tin {
    fn arrays<'py>(
        &self,
        py: Python<'py>,
    ) -> (PyReadonlyArray2<'py, f64>, PyReadonlyArray2<'py, u32>) {
        (
            self.vertices.bind(py).readonly(),
            self.triangles.bind(py).readonly(),
        )
    }
}

#[pymethods]
impl Tin {
    #[getter]
    fn vertices(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.vertices.clone_ref(py)
    }

    #[getter]
    fn triangles(&self, py: Python<'_>) -> Py<PyArray2<u32>> {
        self.triangles.clone_ref(py)
    }

    #[getter]
    fn input_index(&self, py: Python<'_>) -> Py<PyArray1<u32>> {
        self.input_index.clone_ref(py)
    }

    /// Heights at `xy` ((n, 2) float64), NaN outside the TIN.
    fn interpolate<'py>(
        &self,
        py: Python<'py>,
        xy: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let q: &[[f64; 2]] = rows(&xy, "xy")?;
        let (v, t) = self.arrays(py);
        let (v, t): (&[[f64; 3]], &[[u32; 3]]) = (rows(&v, "vertices")?, rows(&t, "triangles")?);
        let (walk, twins) = (&self.walk, &self.twins);
        let z = crate::errors::detach_guarded(py, || {
            // A walk that panicked may have left its state half-updated: build it again.
            let mut guard = walk.lock().unwrap_or_else(|e| {
                let mut g = e.into_inner();
                *g = None;
                g
            });
            if guard.is_none() {
                *guard = Some(sweeptin::Tin::from_twins(v, t, twins)?);
            }
            let tin = guard.as_mut().expect("built above");
            Ok(sweeptin::products::sample::heights(tin, q))
        })
        .map_err(to_py)?;
        Ok(PyArray1::from_vec(py, z))
    }

    /// `(values, (a, b, c, d, e, f))`: the DEM raster of the TIN (float32, row 0 north) and
    /// its affine transform.
    #[pyo3(signature = (cell, bbox = None, align = "edges", nodata = f32::NAN, snap = false,
                        max_cells = sweeptin::raster::DEFAULT_MAX_CELLS as i64))]
    #[allow(clippy::too_many_arguments)] // Python's keyword arguments
    fn rasterize<'py>(
        &self,
        py: Python<'py>,
        cell: f64,
        bbox: Option<[f64; 4]>,
        align: &str,
        nodata: f32,
        snap: bool,
        max_cells: i64,
    ) -> PyResult<(Bound<'py, PyArray2<f32>>, [f64; 6])> {
        let max_cells = crate::files::count(max_cells, "max_cells", 1)? as u64;
        let (v, t) = self.arrays(py);
        let (v, t): (&[[f64; 3]], &[[u32; 3]]) = (rows(&v, "vertices")?, rows(&t, "triangles")?);
        let align = self::align(align)?;
        let (cols, rows_, values, transform) =
            crate::errors::detach_guarded(py, || -> sweeptin::Result<_> {
                let extent = bbox.map_or(GridExtent::Auto, |b| GridExtent::BBox { bbox: b, snap });
                let mut sink = DemSink::in_memory(DemOptions {
                    grid: GridPlan::new(cell, extent, align)?.limit(max_cells)?,
                    nodata,
                    ..DemOptions::default()
                });
                feed(&mut sink, v, t)?;
                let (spec, values) = sink
                    .take_grid()
                    .ok_or_else(|| sweeptin::Error::Internal("no raster in memory".into()))?;
                let o = spec.origin();
                let tr = [spec.cell, 0.0, o[0], 0.0, -spec.cell, o[1]];
                Ok((spec.cols as usize, spec.rows as usize, values, tr))
            })
            .map_err(to_py)?;
        let a = Array2::from_shape_vec((rows_, cols), values)
            .map_err(|e| value_error(e.to_string()))?;
        Ok((PyArray2::from_owned_array(py, a), transform))
    }

    /// Contour lines as GeoJSON text (a FeatureCollection of LineStrings with `elevation`).
    #[pyo3(signature = (interval = 1.0, base = 0.0))]
    fn contours_geojson(&self, py: Python<'_>, interval: f64, base: f64) -> PyResult<String> {
        let (v, t) = self.arrays(py);
        let (v, t): (&[[f64; 3]], &[[u32; 3]]) = (rows(&v, "vertices")?, rows(&t, "triangles")?);
        crate::errors::detach_guarded(py, || -> sweeptin::Result<String> {
            let dir =
                tempfile::tempdir().map_err(|e| sweeptin::Error::write(std::env::temp_dir(), e))?;
            let path = dir.path().join("contours.geojson");
            let mut sink = ContourSink::new(
                &path,
                ContourOptions {
                    interval,
                    base,
                    // As the command line writes the contours of points without a LAS scale.
                    decimals: Some(sweeptin::products::contours::DEFAULT_DECIMALS),
                    ..ContourOptions::default()
                },
            )?;
            feed(&mut sink, v, t)?;
            std::fs::read_to_string(&path).map_err(|e| sweeptin::Error::io(&path, e))
        })
        .map_err(to_py)
    }

    /// Writes the mesh (.ply, .obj, .xml LandXML, .stin); returns (vertices, triangles, bytes).
    #[pyo3(signature = (path, crs = None))]
    fn write(
        &self,
        py: Python<'_>,
        path: std::path::PathBuf,
        crs: Option<String>,
    ) -> PyResult<(u64, u64, u64)> {
        let (v, t) = self.arrays(py);
        let (v, t): (&[[f64; 3]], &[[u32; 3]]) = (rows(&v, "vertices")?, rows(&t, "triangles")?);
        crate::errors::detach_guarded(py, || -> sweeptin::Result<_> {
            let meta = sweeptin::output::MeshMeta {
                crs,
                comments: vec![format!(
                    "sweeptin {} Delaunay TIN (Python)",
                    env!("CARGO_PKG_VERSION")
                )],
            };
            let mut sink = sweeptin::output::create_mesh_sink(&path, None, &meta)?;
            for p in v {
                sink.vertex(*p)?;
            }
            for tri in t {
                sink.triangle(tri.map(u64::from))?;
            }
            let s = sink.finish()?;
            Ok((s.vertices, s.triangles, s.bytes))
        })
        .map_err(to_py)
    }
}
