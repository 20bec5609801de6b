//! The file API: the library's streaming pipeline over LAS/LAZ/XYZ files into the products'
//! sinks (`dem`, `contours`, `volume`), a mesh (`tin`), or chunks of triangles handed to Python
//! (`stream_triangles`), with the same bounded memory as the command line.

use crate::errors::value_error;
use crate::interrupt::{Cancel, CancelMesh, CancelSink, interruptible};
use crate::memory::{align, duplicates};
use crate::to_py;
use numpy::PyArray3;
use numpy::ndarray::Array3;
use pyo3::exceptions::PyStopIteration;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Mutex;
use sweeptin::crs::Crs;
use sweeptin::ground::GroundParams;
use sweeptin::input::las::{BBox, Filter, Returns};
use sweeptin::output::raster::{Compression, Predictor, RasterFormat, RasterOptions};
use sweeptin::pipeline::{self, Input, LineOptions, RunConfig, RunOptions, RunSummary, SweepAxis};
use sweeptin::products::contours::{ContourOptions, ContourSink};
use sweeptin::products::dem::{DemOptions, DemSink};
use sweeptin::products::volume::VolumeSink;
use sweeptin::raster::{GridExtent, GridPlan};
use sweeptin::sink::{Fanout, ProductSummary, StreamInfo, TriangleSink};

/// The input and run options every file function takes (a dict built by the package).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct InputOpts {
    files: Vec<PathBuf>,
    classes: Option<Vec<u8>>,
    returns: String,
    keep_withheld: bool,
    bbox: Option<[f64; 4]>,
    duplicates: String,
    breaklines: Vec<PathBuf>,
    trim_boundary: Option<PathBuf>,
    holes: Option<PathBuf>,
    max_edge: Option<f64>,
    mem: u64,
    tmp_dir: Option<PathBuf>,
    engine: String,
    threads: i64,
    tile: Option<f64>,
    crs: Option<String>,
    progress: bool,
    /// `ground=True`: the filter's parameters (the command line's `--ground`).
    ground: Option<crate::ground::ParamsOpts>,
}

impl InputOpts {
    /// As the command line, before any work: the `outputs` are distinct from each other and
    /// from every file the run reads (points, breaklines, boundary, holes), and each can be
    /// created where asked.
    fn check_outputs(&self, outputs: &[(&str, &std::path::Path)]) -> PyResult<()> {
        let mut inputs = self.files.clone();
        inputs.extend(self.breaklines.iter().cloned());
        inputs.extend(self.trim_boundary.iter().chain(&self.holes).cloned());
        sweeptin::output::distinct_outputs(outputs, &inputs, "the run").map_err(to_py)?;
        for (_, o) in outputs {
            sweeptin::output::check_output(o).map_err(to_py)?;
        }
        Ok(())
    }

    /// The ground filter's parameters, with `ground=True`.
    fn ground_params(&self) -> PyResult<Option<GroundParams>> {
        self.ground.as_ref().map(|g| g.params()).transpose()
    }

    fn bbox(&self) -> PyResult<Option<BBox>> {
        self.bbox
            .map(|[x0, y0, x1, y1]| {
                BBox::new(x0, y0, x1, y1).ok_or_else(|| {
                    value_error(format!(
                        "bbox={:?}: expected (xmin, ymin, xmax, ymax), finite, min <= max",
                        self.bbox
                    ))
                })
            })
            .transpose()
    }

    /// The run's configuration, checked by the library, and the CRS given.
    fn config(&self) -> PyResult<(RunConfig, Option<Crs>)> {
        let returns = match self.returns.as_str() {
            "all" => Returns::All,
            "first" => Returns::First,
            "last" => Returns::Last,
            r => {
                return Err(value_error(format!(
                    "returns={r:?}: use 'all', 'first' or 'last'"
                )));
            }
        };
        let input = Input {
            paths: self.files.clone(),
            filter: Filter {
                classes: self.classes.clone(),
                returns,
                drop_withheld: !self.keep_withheld,
                bbox: self.bbox()?,
                z_from: None,
                classes_from: None,
            },
            duplicates: duplicates(&self.duplicates)?,
            lines: LineOptions {
                breaklines: self.breaklines.clone(),
                boundary: self.trim_boundary.clone(),
                holes: self.holes.clone(),
                max_edge: self.max_edge,
                ..LineOptions::default()
            },
        };
        // As `--engine`: `auto` (the default) and `tiles` run exact tiles where the input
        // allows it (LAS/LAZ points without breaklines or trimming polygons), one sweep
        // otherwise; `sweep` always runs one streaming sweep.
        if let Some(t) = self.tile {
            sweeptin::pipeline::check_tile_side(t).map_err(to_py)?;
        }
        let threads = count(self.threads, "threads", 0)?;
        let tiles = match self.engine.as_str() {
            "sweep" => None,
            "auto" | "tiles" => Some(sweeptin::TileOptions {
                threads,
                tile: self.tile,
                base: None,
                scope: None,
            }),
            e => {
                return Err(value_error(format!(
                    "engine={e:?}: use 'auto', 'tiles' or 'sweep'"
                )));
            }
        };
        let options = RunOptions {
            mem: self.mem,
            tmp_dir: self.tmp_dir.clone(),
            progress: self.progress,
            sweep_axis: SweepAxis::Auto,
            tiles,
        };
        let crs = self
            .crs
            .as_deref()
            .map(Crs::parse)
            .transpose()
            .map_err(to_py)?;
        Ok((RunConfig::new(input, options).map_err(to_py)?, crs))
    }
}

/// With the ground filter's parameters (`ground=True`), the run of `config` on the ground
/// found first, as the command line's `--ground` (`pipeline::ground::ground_input`: the same
/// bytes); its summary carries the filter's. `None` without.
fn grounded(
    config: &RunConfig,
    params: Option<GroundParams>,
) -> sweeptin::Result<Option<RunConfig>> {
    let Some(p) = params else {
        return Ok(None);
    };
    let g =
        pipeline::ground::ground_input(config.input(), &p, config.options(), &mut |_, _, _| {})?;
    let run = RunConfig::new(g.input, g.options)?.with_ground(Some(g.summary));
    Ok(Some(run))
}

/// A raster's format and compression, as the command line's `--format`, `--compress`,
/// `--predictor` and `--bigtiff` name them (`None`: the default).
pub(crate) fn raster_options(
    format: Option<&str>,
    compress: Option<&str>,
    predictor: Option<&str>,
    bigtiff: bool,
) -> PyResult<RasterOptions> {
    let format = match format {
        None => None,
        Some("tif" | "tiff" | "gtiff") => Some(RasterFormat::GeoTiff),
        Some("cog") => Some(RasterFormat::Cog),
        Some("asc") => Some(RasterFormat::Ascii),
        Some(f) => {
            return Err(value_error(format!(
                "format={f:?}: use 'tif' (GeoTIFF), 'cog' (Cloud Optimized GeoTIFF) or 'asc' \
                 (ESRI ASCII grid)"
            )));
        }
    };
    let compress = match compress {
        None => None,
        Some("none") => Some(Compression::None),
        Some("deflate") => Some(Compression::Deflate),
        Some("zstd") => Some(Compression::Zstd),
        Some("lzw") => Some(Compression::Lzw),
        Some(c) => {
            return Err(value_error(format!(
                "compress={c:?}: use 'none', 'deflate', 'zstd' or 'lzw'"
            )));
        }
    };
    let predictor = match predictor {
        None => None,
        Some("none" | "1") => Some(Predictor::None),
        Some("horizontal" | "2") => Some(Predictor::Horizontal),
        Some("float" | "3") => Some(Predictor::Float),
        Some(p) => {
            return Err(value_error(format!(
                "predictor={p:?}: use 'none', 'horizontal' or 'float'"
            )));
        }
    };
    Ok(RasterOptions {
        format,
        compress,
        predictor,
        bigtiff,
    })
}

/// A DEM's options (a dict built by the package).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct DemOpts {
    out: PathBuf,
    cell: f64,
    nodata: f32,
    snap: bool,
    align: String,
    format: Option<String>,
    compress: Option<String>,
    predictor: Option<String>,
    bigtiff: bool,
    max_cells: i64,
}

/// `{"run": …, "products": …}` as JSON text.
fn summary_json(run: &RunSummary, products: serde_json::Value) -> PyResult<String> {
    serde_json::to_string(&serde_json::json!({ "run": run, "products": products }))
        .map_err(|e| value_error(e.to_string()))
}

/// One pass over the files into the DEM, contours and volume sinks given (each `None` or a
/// dict); returns the JSON summary.
#[pyfunction]
#[pyo3(signature = (opts, dem = None, contours = None, volume = None))]
pub(crate) fn run_products(
    py: Python<'_>,
    opts: InputOpts,
    dem: Option<DemOpts>,
    contours: Option<(PathBuf, f64, f64)>,
    volume: Option<(f64, Option<PathBuf>)>,
) -> PyResult<String> {
    let (config, crs) = opts.config()?;
    let ground = opts.ground_params()?;
    let mut outputs: Vec<(&str, &std::path::Path)> = Vec::new();
    if let Some(d) = &dem {
        outputs.push(("out", &d.out));
    }
    if let Some(c) = &contours {
        outputs.push(("contours", &c.0));
    }
    opts.check_outputs(&outputs)?;
    let bbox = opts.bbox()?;
    let mut sinks: Vec<(String, Box<dyn TriangleSink>)> = Vec::new();
    if let Some(d) = dem {
        let extent = match bbox {
            Some(b) => GridExtent::BBox {
                bbox: b.corners(),
                snap: d.snap,
            },
            None => GridExtent::Auto,
        };
        let max_cells = count(d.max_cells, "max_cells", 1)? as u64;
        let grid = GridPlan::new(d.cell, extent, align(&d.align)?)
            .and_then(|g| g.limit(max_cells))
            .map_err(to_py)?;
        let options = DemOptions {
            grid,
            nodata: d.nodata,
            output: raster_options(
                d.format.as_deref(),
                d.compress.as_deref(),
                d.predictor.as_deref(),
                d.bigtiff,
            )?,
            // As the command line: the raster's rows hold at most a quarter of `mem`.
            memory: opts.mem / 4,
        };
        let sink = DemSink::new(&d.out, options).map_err(to_py)?;
        // Its size against `max_cells` and the memory, before any work: from the box, or
        // from the LAS/LAZ headers.
        match (extent, config.header_bounds()) {
            (GridExtent::Auto, Some(b)) => sink.check_size(b),
            (GridExtent::Auto, None) => Ok(()),
            _ => sink.check_size([0.0; 4]),
        }
        .map_err(to_py)?;
        sinks.push(("dem".into(), Box::new(sink)));
    }
    if let Some((path, interval, base)) = contours {
        // The decimals the command line writes by default (the LAS/LAZ scale's).
        let options = ContourOptions {
            interval,
            base,
            decimals: Some(sweeptin::pipeline::contour_decimals(&opts.files)),
            ..ContourOptions::default()
        }
        .within(opts.mem);
        let sink = ContourSink::new(&path, options).map_err(to_py)?;
        sinks.push(("contours".into(), Box::new(sink)));
    }
    if let Some((plane, boundary)) = volume {
        let boundary = boundary
            .as_deref()
            .map(sweeptin::products::boundary::Boundary::read)
            .transpose()
            .map_err(to_py)?;
        let sink = VolumeSink::new(plane, boundary).map_err(to_py)?;
        sinks.push(("volume".into(), Box::new(sink)));
    }
    let cancel = Cancel::default();
    let (mut run, products) = interruptible(py, &cancel, || {
        let grounded = grounded(&config, ground)?;
        let config = grounded.as_ref().unwrap_or(&config);
        let mut fanout = Fanout::new(sinks).with_crs(crs);
        let mut stop = CancelSink(&cancel);
        let mut run = pipeline::run(config, None, &mut [&mut fanout, &mut stop])?;
        run.products.truncate(1);
        let products = run.products.pop();
        Ok((run, products))
    })?;
    run.peak_rss_bytes = pipeline::peak_rss();
    match products {
        Some(ProductSummary::Fanout(p)) => summary_json(
            &run,
            serde_json::to_value(p).map_err(|e| value_error(e.to_string()))?,
        ),
        other => Err(to_py(sweeptin::Error::Internal(format!(
            "the products' summary is {other:?}"
        )))),
    }
}

/// Triangulates the files into the mesh file `out`; returns the JSON summary.
#[pyfunction]
#[pyo3(signature = (opts, out))]
pub(crate) fn run_tin(py: Python<'_>, opts: InputOpts, out: PathBuf) -> PyResult<String> {
    let (config, crs) = opts.config()?;
    let ground = opts.ground_params()?;
    opts.check_outputs(&[("out", &out)])?;
    let cancel = Cancel::default();
    let (mut run, mesh) = interruptible(py, &cancel, || {
        let grounded = grounded(&config, ground)?;
        let config = grounded.as_ref().unwrap_or(&config);
        let crs = match crs {
            Some(c) => c.definition(),
            None => config.input_crs()?,
        };
        let names: Vec<String> = opts.files.iter().map(|p| p.display().to_string()).collect();
        let meta = sweeptin::output::MeshMeta {
            crs,
            comments: vec![format!(
                "sweeptin {} Delaunay TIN of {}",
                env!("CARGO_PKG_VERSION"),
                names.join(", ")
            )],
        };
        let mut sink = sweeptin::output::create_mesh_sink(&out, None, &meta)?;
        let mut guarded = CancelMesh {
            inner: &mut *sink,
            cancel: &cancel,
        };
        let run = pipeline::run(config, Some(&mut guarded), &mut [])?;
        let mesh = sink.finish()?;
        Ok((run, mesh))
    })?;
    run.peak_rss_bytes = pipeline::peak_rss();
    let mesh = serde_json::json!({
        "path": out, "vertices": mesh.vertices, "triangles": mesh.triangles, "bytes": mesh.bytes
    });
    summary_json(&run, serde_json::json!({ "mesh": mesh }))
}

/// Bytes of a triangle in a chunk: three corners of three doubles.
const TRIANGLE_BYTES: u64 = 72;

/// Triangles a chunk holds by default, when a quarter of the memory budget holds them.
const DEFAULT_CHUNK: u64 = 1_000_000;

/// A [`TriangleSink`] handing chunks of triangles to the Python iterator through a bounded
/// channel (two chunks in flight at most: memory stays bounded whatever the input).
struct ChunkSink {
    tx: crossbeam_channel::Sender<Vec<[[f64; 3]; 3]>>,
    chunk: usize,
    buf: Vec<[[f64; 3]; 3]>,
}

impl ChunkSink {
    /// An empty buffer for the next chunk: room for a small one at first (a chunk of a large
    /// size holds a small run's few triangles), growing with the triangles.
    fn fresh(&self) -> Vec<[[f64; 3]; 3]> {
        Vec::with_capacity(self.chunk.min(1 << 16))
    }

    fn send(&mut self) -> sweeptin::Result<()> {
        let fresh = self.fresh();
        let full = std::mem::replace(&mut self.buf, fresh);
        // The iterator was dropped: stop the run.
        self.tx.send(full).map_err(|_| sweeptin::Error::Interrupted)
    }
}

impl TriangleSink for ChunkSink {
    fn begin(&mut self, _info: &StreamInfo) -> sweeptin::Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> sweeptin::Result<()> {
        if self.buf.len() == self.buf.capacity() {
            // Grown by doubling up to the chunk, never beyond it; a failure is an error, not an
            // abort of the interpreter.
            let more = self.buf.len().clamp(1, self.chunk - self.buf.len());
            self.buf
                .try_reserve_exact(more)
                .map_err(|_| sweeptin::Error::OutOfMemory {
                    what: "a chunk of triangles for stream_triangles".into(),
                    bytes: (self.buf.len() + more) as u64 * TRIANGLE_BYTES,
                    hint: "give a smaller chunk=".into(),
                })?;
        }
        self.buf.push(*t);
        if self.buf.len() >= self.chunk {
            self.send()?;
        }
        Ok(())
    }

    fn finish(&mut self) -> sweeptin::Result<ProductSummary> {
        if !self.buf.is_empty() {
            self.send()?;
        }
        Ok(ProductSummary::None)
    }
}

/// The triangles a chunk holds: `chunk` (`None`: [`DEFAULT_CHUNK`]), at least 1 and within a
/// quarter of the memory budget `mem` (as a DEM's rows: three chunks live at once, one filling,
/// one in the pipe and one handed to Python). `chunk=10**9` allocated 72 GB up front and
/// aborted the interpreter.
fn chunk_size(chunk: Option<i64>, mem: u64) -> PyResult<usize> {
    let most = (mem / 4 / TRIANGLE_BYTES).max(1);
    let n = match chunk {
        None => return Ok(DEFAULT_CHUNK.min(most) as usize),
        Some(n) => count(n, "chunk", 1)? as u64,
    };
    if n > most {
        return Err(value_error(format!(
            "chunk={n}: {n} triangles of {TRIANGLE_BYTES} bytes are more than a quarter of \
             mem= ({mem} bytes) holds: give chunk={most} or less, or a larger mem="
        )));
    }
    Ok(n as usize)
}

/// `value` as a count of at least `least`, named `name` in the error.
pub(crate) fn count(value: i64, name: &str, least: u64) -> PyResult<usize> {
    match u64::try_from(value) {
        Ok(v) if v >= least => {
            usize::try_from(v).map_err(|_| value_error(format!("{name}={value}: too large")))
        }
        _ => Err(value_error(format!(
            "{name}={value}: must be a whole number, {least} or more"
        ))),
    }
}

enum StreamState {
    Running {
        rx: crossbeam_channel::Receiver<Vec<[[f64; 3]; 3]>>,
        run: std::thread::JoinHandle<sweeptin::Result<RunSummary>>,
    },
    Done(Option<String>),
}

/// An iterator over chunks of final triangles, `(k, 3, 3)` float64 arrays of `[x, y, z]`
/// corners (counter-clockwise), as the streaming run releases them.
#[pyclass(module = "sweeptin._sweeptin")]
pub struct TriangleStream {
    state: Mutex<StreamState>,
}

#[pyfunction]
#[pyo3(signature = (opts, chunk = None))]
pub(crate) fn stream_triangles(opts: InputOpts, chunk: Option<i64>) -> PyResult<TriangleStream> {
    let chunk = chunk_size(chunk, opts.mem)?;
    let (config, _) = opts.config()?;
    let ground = opts.ground_params()?;
    let (tx, rx) = crossbeam_channel::bounded(1);
    let run = std::thread::Builder::new()
        .name("sweeptin-stream".into())
        .spawn(move || {
            let mut sink = ChunkSink {
                tx,
                chunk,
                buf: Vec::new(),
            };
            sink.buf = sink.fresh();
            let grounded = grounded(&config, ground)?;
            pipeline::run(grounded.as_ref().unwrap_or(&config), None, &mut [&mut sink])
        })
        .map_err(|e| value_error(format!("cannot start the run: {e}")))?;
    Ok(TriangleStream {
        state: Mutex::new(StreamState::Running { rx, run }),
    })
}

#[pymethods]
impl TriangleStream {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let next = match &*state {
            StreamState::Running { rx, .. } => loop {
                let r = py.detach(|| rx.recv_timeout(std::time::Duration::from_millis(100)));
                match r {
                    Ok(tris) => break Some(tris),
                    Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break None,
                    // Ctrl-C while waiting: raised here; dropping the iterator stops the run.
                    Err(crossbeam_channel::RecvTimeoutError::Timeout) => py.check_signals()?,
                }
            },
            StreamState::Done(_) => return Err(PyStopIteration::new_err(())),
        };
        if let Some(tris) = next {
            let k = tris.len();
            let flat: Vec<f64> = bytemuck::cast_vec(tris);
            let a =
                Array3::from_shape_vec((k, 3, 3), flat).map_err(|e| value_error(e.to_string()))?;
            return Ok(PyArray3::from_owned_array(py, a));
        }
        // The run ended: its summary, or its error.
        let StreamState::Running { run, .. } =
            std::mem::replace(&mut *state, StreamState::Done(None))
        else {
            unreachable!("matched above")
        };
        let result = py.detach(|| run.join());
        match result {
            Ok(Ok(mut s)) => {
                s.peak_rss_bytes = pipeline::peak_rss();
                *state = StreamState::Done(serde_json::to_string(&s).ok());
                Err(PyStopIteration::new_err(()))
            }
            Ok(Err(e)) => Err(to_py(e)),
            Err(p) => Err(to_py(sweeptin::Error::Internal(format!(
                "the run panicked: {:?}",
                p.downcast_ref::<&str>()
            )))),
        }
    }

    /// The run's summary as JSON text, once the iterator is exhausted (else `None`).
    fn summary_json(&self) -> Option<String> {
        match &*self.state.lock().unwrap_or_else(|e| e.into_inner()) {
            StreamState::Done(s) => s.clone(),
            StreamState::Running { .. } => None,
        }
    }
}

/// The default memory budget, as `--mem`'s: 1 GiB, or what an address-space limit leaves.
#[pyfunction]
pub(crate) fn default_mem() -> u64 {
    pipeline::default_mem()
}

/// Parses a memory size (`"512M"`, `"4G"`) as `--mem` does.
#[pyfunction]
pub(crate) fn parse_size(s: &str) -> PyResult<u64> {
    pipeline::parse_size(s).map_err(crate::to_py)
}

/// Parses a classification list (`"2,9"`, `"29"`) as `--class` does.
#[pyfunction]
pub(crate) fn parse_classes(s: &str) -> PyResult<Vec<u8>> {
    sweeptin::input::las::parse_classes(s).map_err(crate::to_py)
}
