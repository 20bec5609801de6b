//! From input files to final triangles, delivered to sinks, with memory bounded by the budget and
//! the advancing front, never by the number of points.
//!
//! ```text
//! LAS/LAZ/XYZ ─► read (filters) ─► ExternalSorter (chunks sorted with rayon, spilled, mmapped)
//!   ─► k-way merge ─► duplicates merged ──[channel]──► streaming sweep (finalisation)
//!   ──[channel]──► writer thread: MeshSink (PLY/OBJ/LandXML/.stin) + TriangleSinks (DEM, …)
//! ```
//!
//! A run is described by an [`Input`] and [`RunOptions`], checked once into a [`RunConfig`]
//! that every stage reads. A streaming mesh (`.stin`) given as input is replayed into the sinks
//! instead (see the `replay` module).
//!
//! Geometry is in the binary doubles that the outputs get: the XYZ file's values as parsed, and
//! for LAS/LAZ the real-world values `offset + scale × N`, computed once when reading
//! (docs/ARCHITECTURE.md, "Coordinates"). The only change on the way out is the sweep axis: a
//! sweep along x works on the points with x and y exchanged, which [`Frame`] undoes.

mod clip;
mod config;
mod drive;
mod emit;
pub mod ground;
pub mod height;
mod line_feed;
mod lines;
mod read;
mod replay;
mod thin;
mod thin_tiles;
mod tiled;

use crate::error::{Error, Result};
use crate::input::las::Filter;
use crate::sink::{MeshSink, ProductSummary, StreamInfo, TriangleSink};
use crate::sort::memory::DuplicatePolicy;
pub(crate) use config::Source;
use std::path::{Path, PathBuf};

pub use config::{RunConfig, check_tile_side};
pub use lines::{ClipSummary, FarHeights, LineOptions, LineSummary, PLAN_REFUSES_CLIP};
pub(crate) use lines::{ReadLines, prepare, trim};
pub use read::read_points;
pub use thin::{THIN_BYTES_PER_POINT, ThinSummary, thin};
pub use thin_tiles::{TILE_BYTES_PER_POINT, ThinTileSummary, thin_tiled};

/// What to triangulate.
#[derive(Clone, Debug)]
pub struct Input {
    /// Point files: LAS/LAZ (by extension `.las`/`.laz`), a streaming mesh (`.stin`, alone), or
    /// XYZ text; several point files form one set.
    pub paths: Vec<PathBuf>,
    /// LAS/LAZ filters (ignored for XYZ).
    pub filter: Filter,
    /// Which point survives among exact (x, y) duplicates.
    pub duplicates: DuplicatePolicy,
    /// Breaklines and trimming (none by default).
    pub lines: LineOptions,
}

/// How to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Memory budget in bytes for the sort's chunks and the pipeline's buffers.
    pub mem: u64,
    /// Where spill files go (anonymous temporary files); default: the system temp directory.
    pub tmp_dir: Option<PathBuf>,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// The axis the sweep advances along.
    pub sweep_axis: SweepAxis,
    /// Run in exact tiles on several threads when the input allows it (LAS/LAZ points, no
    /// breaklines or trimming polygons); `None`: one streaming sweep.
    pub tiles: Option<crate::tiles::TileOptions>,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            mem: default_mem(),
            tmp_dir: None,
            progress: false,
            sweep_axis: SweepAxis::Auto,
            tiles: None,
        }
    }
}

/// The axis the streaming sweep advances along. Memory is proportional to the number of points
/// *across* the sweep (the advancing front), so a long strip should be swept lengthwise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SweepAxis {
    /// `x` when the LAS/LAZ headers' extent is more than 4 times wider than tall
    /// and nothing needs `y` order (no breaklines, no terrain products); `y` otherwise (and
    /// always for XYZ text, whose extent is not known before reading).
    #[default]
    Auto,
    /// Along `x` (the points are swept by `x`, then `y`).
    X,
    /// Along `y` (the points are swept by `y`, then `x`), as the in-memory core does.
    Y,
}

/// How much wider than tall (from the LAS/LAZ headers) an input must be for
/// [`SweepAxis::Auto`] to sweep along `x`.
pub const STRIP_RATIO: f64 = 4.0;

/// Default memory budget: 1 GiB (less under an address-space limit: [`default_mem`]).
pub const DEFAULT_MEM: u64 = 1 << 30;

/// The default memory budget: [`DEFAULT_MEM`], or, under an address-space limit (`ulimit -v`,
/// a batch job's `h_vmem`), what the limit leaves beside the process's own mappings with a
/// worker per core, in whole MiB (at least 16 MiB; a limit below that is refused when the job
/// starts).
pub fn default_mem() -> u64 {
    crate::limits::fit_address_space(DEFAULT_MEM, 0)
}

/// Parses a human memory size: `1048576`, `512K`, `128M`, `4G`, `1T`, optionally with `B`,
/// `iB` or a space (binary multiples: 1K = 1024), as `--mem` and the Python package take it.
///
/// # Errors
/// [`Error::Options`] saying what is wrong with `s`.
pub fn parse_size(s: &str) -> Result<u64> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let v: f64 = num
        .parse()
        .map_err(|_| Error::Options(format!("'{s}' is not a size like 512M or 4G")))?;
    let mult: u64 = match unit.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 1,
        "K" | "KB" | "KIB" => 1 << 10,
        "M" | "MB" | "MIB" => 1 << 20,
        "G" | "GB" | "GIB" => 1 << 30,
        "T" | "TB" | "TIB" => 1 << 40,
        _ => {
            return Err(Error::Options(format!(
                "'{s}': unknown size unit '{unit}' (use K, M, G or T)"
            )));
        }
    };
    let bytes = v * mult as f64;
    if !(1.0..=1e18).contains(&bytes) {
        return Err(Error::Options(format!(
            "'{s}' is not a sensible memory size"
        )));
    }
    Ok(bytes as u64)
}

/// The sweep's frame: the world's coordinates, with x and y exchanged for a sweep along x.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Frame {
    /// The sweep's frame has x and y exchanged (a sweep along the world's x): a mirror image,
    /// so triangles change orientation on the way out.
    pub swap: bool,
}

impl Frame {
    /// World coordinates of a point of the sweep's frame.
    #[inline]
    pub fn world(&self, xy: [f64; 2], z: f64) -> [f64; 3] {
        let [x, y] = if self.swap { [xy[1], xy[0]] } else { xy };
        [x, y, z]
    }
}

/// Seconds spent per phase.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Timings {
    /// Reading, filtering, sorting chunks and spilling.
    pub read_sort: f64,
    /// Merging, sweeping and writing (overlapped in three threads).
    pub triangulate_write: f64,
    /// Closing outputs (PLY assembly, renames).
    pub finish: f64,
}

/// What a run did (the `--json` summary of `sweeptin tin`).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunSummary {
    /// Points read (after filters).
    pub points_read: u64,
    /// Points triangulated (after merging duplicates).
    pub points_kept: u64,
    /// Exact (x, y) duplicates merged away.
    pub duplicates: u64,
    /// Triangles delivered.
    pub triangles: u64,
    /// Vertices delivered.
    pub vertices: u64,
    /// Seconds per phase.
    pub seconds: Timings,
    /// Peak resident memory of the process (VmHWM), in bytes, when the OS reports it. Includes
    /// pages of memory-mapped spill files, which the kernel can drop at any time.
    pub peak_rss_bytes: Option<u64>,
    /// Largest anonymous resident memory (RssAnon: heap and stacks, no file pages) seen when
    /// sampled: after reading, at every watermark, and at the end.
    pub peak_anon_bytes: Option<u64>,
    /// External sort.
    pub sort: crate::sort::external::SortStats,
    /// Sweep counters (front peak, flips, …).
    pub sweep: crate::sweep::SweepStats,
    /// Streaming working set.
    pub stream: crate::finalise::StreamStats,
    /// What each triangle sink reported, in the order of the sinks.
    pub products: Vec<ProductSummary>,
    /// The CRS, when known.
    pub crs: Option<String>,
    /// Breaklines and trimming, when given.
    pub breaklines: Option<LineSummary>,
    /// The axis the sweep went along (`x` or `y`).
    pub sweep_axis: SweepAxis,
    /// The tiles, for a tiled run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tiles: Option<crate::tiles::TileStats>,
    /// What the input files' headers say that did not stop the run, each `FILE: warning` (a
    /// point count that disagrees with the file…).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// What the ground filter found first, with `--ground` ([`RunConfig::with_ground`]): the
    /// summary `sweeptin ground --json` prints.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground: Option<crate::ground::GroundSummary>,
}

pub use crate::limits::{MAX_THREADS, anon_rss, check_threads, peak_rss, size_thread_pool};

/// Running maximum of [`anon_rss`] samples.
#[derive(Debug, Default)]
pub(crate) struct AnonPeak(std::sync::atomic::AtomicU64);

impl AnonPeak {
    pub(crate) fn sample(&self) {
        if let Some(a) = anon_rss() {
            self.0.fetch_max(a, std::sync::atomic::Ordering::Relaxed);
        }
    }
    pub(crate) fn get(&self) -> Option<u64> {
        let v = self.0.load(std::sync::atomic::Ordering::Relaxed);
        (v > 0).then_some(v)
    }
}

/// When the tiled engine finds fewer than three points: [`Error::NothingLeft`] naming what each
/// filter dropped, as the streaming sweep reports it. The engine does not hand its filter counts
/// out, so they are counted here by a read of the points (on this failure path only; a COPC
/// file read with `--bbox` decodes only the nodes the box meets). `e` when no filter dropped any
/// point, or when the count fails.
fn nothing_left(config: &RunConfig, distinct: u64, e: Error) -> Error {
    let input = config.input();
    let count = || -> Result<crate::input::las::FilterStats> {
        let mut r = config.open_lidar(crate::input::las::ReadOptions::default())?;
        let mut chunk = Vec::new();
        while r.read_chunk(&mut chunk, 1 << 16)? > 0 {
            chunk.clear();
        }
        Ok(*r.stats())
    };
    match count() {
        Ok(stats) if stats.read == 0 || stats.read > stats.kept || stats.skipped > 0 => {
            Error::NothingLeft {
                files: input.paths.clone(),
                what: stats.describe(distinct),
            }
        }
        _ => e,
    }
}

/// Triangulates the input of `config` and delivers the result to `mesh` (if any) and every
/// sink, streaming.
///
/// # Errors
/// Any reader, triangulation, sink or output error; [`crate::Error::TooFewPoints`] and
/// [`crate::Error::AllCollinear`] when no triangle exists.
pub fn run(
    config: &RunConfig,
    mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<RunSummary> {
    let mut summary = run_engine(config, mesh, sinks)?;
    summary.ground = config.ground().cloned();
    Ok(summary)
}

/// [`run`] on the engine that fits.
fn run_engine(
    config: &RunConfig,
    mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<RunSummary> {
    let mut mesh = mesh;
    if let Some(m) = mesh.as_mut() {
        // What the mesh is (a replayed mesh adds its own kind, `replay`).
        m.declare(config.input().lines.mesh_kind())?;
    }
    if config.source() == Source::Stream {
        return replay::replay(config, mesh, sinks);
    }
    if let Some(t) = config
        .options()
        .tiles
        .as_ref()
        .filter(|_| tiled::applies(config))
    {
        let task = t.scope.is_some();
        return tiled::run(config, t, mesh, sinks).map_err(|e| match e {
            // A plan's task reports an empty tile as it is (it records "empty").
            Error::TooFewPoints { distinct, .. } if !task => nothing_left(config, distinct, e),
            e => e,
        });
    }
    if config
        .options()
        .tiles
        .as_ref()
        .is_some_and(|t| t.scope.is_some())
    {
        return Err(Error::Options(
            "a task of a plan runs in exact tiles, which need LAS/LAZ points without \
             --no-flat-triangles, swept along y"
                .into(),
        ));
    }
    let lines = &config.input().lines;
    if lines.is_empty() && !lines.no_flat_triangles {
        return drive::run(config, None, mesh, sinks);
    }
    let points_only = config.points_only();
    let prepared = lines::prepare_with(
        lines,
        config.read_lines(),
        Some(&mut |sink| {
            if let Some(s) = config.stream_input() {
                return Err(Error::Options(format!(
                    "{}: lines without z take their heights from a first pass over the points, but \
                 this input is a pipe or a device, which can be read only once: give the points \
                 as a file, or the lines with z",
                    s.display()
                )));
            }
            drive::run(&points_only, None, None, &mut [sink]).map(|_| ())
        }),
        Some(config.line_budget()),
    )?;
    drive::run(config, Some(&prepared), mesh, sinks)
}

/// The decimals contour coordinates of the points in `inputs` are written with by default:
/// those of the finest horizontal scale of LAS/LAZ inputs (`0.01` gives 2: no finer than the
/// points themselves; [`crate::input::las::LidarReader::header_xy_decimals`]), else
/// [`crate::products::contours::DEFAULT_DECIMALS`].
pub fn contour_decimals(inputs: &[PathBuf]) -> u32 {
    match Source::of(inputs) {
        Ok(Source::Lidar) => crate::input::las::LidarReader::header_xy_decimals(inputs),
        _ => None,
    }
    .unwrap_or(crate::products::contours::DEFAULT_DECIMALS)
}

/// Phase 1 whole: the reference surface of a volume, the TIN of `paths` read as `config` reads
/// its own input (duplicates, breaklines, `--mem`, the box) but with the point filter `filter`
/// (a DSM of first returns against a DTM of ground points from the same file: one filter per
/// surface), filed into about `bands` bands in a scratch file under `dir`.
///
/// # Errors
/// As [`crate::pipeline::run`] for the reference's files; [`Error::Write`] for the scratch file.
pub fn reference_surface(
    config: &RunConfig,
    paths: &[PathBuf],
    filter: crate::input::las::Filter,
    dir: &Path,
    bands: usize,
) -> Result<crate::products::overlay::BandReader> {
    if filter.classes_from.is_some() && paths != config.input().paths.as_slice() {
        return Err(Error::Options(
            "--ground classifies the points of the run's own files, not those of another \
             surface: classify the surface first (`sweeptin ground`) and give it with its \
             classes (--surface-class 2)"
                .into(),
        ));
    }
    let reference = RunConfig::new(
        Input {
            paths: paths.to_vec(),
            filter,
            ..config.input().clone()
        },
        config.options().clone(),
    )?;
    let mut store = crate::products::overlay::BandStore::new(dir, bands);
    run(&reference, None, &mut [&mut store])?;
    store.into_reader()
}
