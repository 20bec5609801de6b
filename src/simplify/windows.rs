//! Grids larger than memory: the grid cut into fixed windows with shared border lines, read band
//! of windows by band, refined on every core, written in a fixed order (see the parent module's
//! "# Memory").

use super::border::simplify_line;
use super::refiner::{ErrorSums, Kept, Refiner, SideErrors};
use super::scan::{Cells, Clip, Height};
use super::stitch::Stitch;
use super::{Options, SimplifyStats, Stop};
use crate::error::{Error, Result};
use crate::input::raster::{Heights, RasterReader, RasterSpec};
use crate::sink::MeshSink;
use crate::validate::MeshKind;
use std::collections::BTreeMap;
use std::sync::{Arc, Condvar, Mutex};

/// The default window: 128 × 128 cell intervals (129 × 129 cells with the shared borders).
pub const DEFAULT_WINDOW: u32 = 128;

/// Bytes a window's refinement may hold per cell of the window, at worst (every cell a vertex):
/// the TIN, the candidates and the queue, then the kept triangles waiting to be written.
pub const WINDOW_BYTES_PER_CELL: u64 = 256;

/// Bytes a band of heights holds per cell at worst (`f32`, then widened to `f64`).
const BAND_BYTES_PER_CELL: u64 = 12;

/// Bytes of the output writer's buffers and the rest of the process, whatever the grid.
const FIXED_BYTES: u64 = 16 << 20;

/// Progress of [`simplify_raster`], now and then.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridProgress {
    /// A grid of one window: points so far and the current worst error.
    Refining {
        /// Points in the TIN.
        points: u64,
        /// The worst error left.
        error: f64,
    },
    /// Windows written and points written.
    Windows {
        /// Windows written.
        done: u64,
        /// Windows in all.
        total: u64,
        /// Points written.
        points: u64,
    },
}

/// A [`simplify_raster`] progress callback.
pub type GridProgressFn<'a> = &'a mut dyn FnMut(GridProgress);

/// How to simplify a grid read from a file.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GridOptions {
    /// The bound and the redundancy pass.
    pub options: Options,
    /// Window side in cell intervals: windows of at most `window × window` intervals
    /// (`(window + 1)²` cells), the grid split evenly. It alone decides the output, never
    /// `mem` or `threads`. A grid of one window is simplified whole ([`super::simplify`]).
    pub window: u32,
    /// Memory budget in bytes.
    pub mem: u64,
    /// Worker threads (0: every core).
    pub threads: usize,
}

impl GridOptions {
    /// `options` within `mem` bytes, with the default window, on every core.
    pub fn new(options: Options, mem: u64) -> Self {
        GridOptions {
            options,
            window: DEFAULT_WINDOW,
            mem,
            threads: 0,
        }
    }
}

/// The cuts of `n` cells into windows of at most `window` intervals, evenly: the first and last
/// cells and the shared border lines between.
pub(super) fn cuts(n: u32, window: u32) -> Vec<u32> {
    let intervals = u64::from(n.max(2) - 1);
    let k = intervals.div_ceil(u64::from(window.max(1)));
    (0..=k).map(|i| (i * intervals / k) as u32).collect()
}

/// How a run is laid out and what it may hold.
#[derive(Debug)]
struct Layout {
    cols: Vec<u32>,
    rows: Vec<u32>,
    /// Windows refined at once.
    in_flight: usize,
    /// Bands held at once (2: the next band is read while the last windows of one run).
    bands: usize,
    threads: usize,
}

impl Layout {
    fn across(&self) -> usize {
        self.cols.len() - 1
    }

    fn windows(&self) -> usize {
        self.across() * (self.rows.len() - 1)
    }
}

/// Simplifies the grid of `reader` to `sink` window by window within `grid.mem`, and returns
/// the statistics. With a [`Stop::MaxError`] bound the output is the same for any `mem` and
/// `threads`; a grid of one window gives [`super::simplify`]'s output.
///
/// # Errors
/// [`Error::Options`] when the job cannot fit `grid.mem` (before anything is read), for a
/// window under 4 cells or a point or triangle budget on a grid of several windows;
/// [`Error::Format`] naming the file for a grid that gives no triangle (every cell missing, or
/// the valid cells standing alone), the sink left unfinished; the reader's and the sink's
/// errors; [`super::simplify`]'s.
pub fn simplify_raster(
    reader: &mut RasterReader,
    grid: &GridOptions,
    sink: &mut dyn MeshSink,
    progress: Option<GridProgressFn<'_>>,
) -> Result<SimplifyStats> {
    let start = std::time::Instant::now();
    let spec = reader.spec().clone();
    if grid.window < 4 {
        return Err(Error::Options(format!(
            "--window {}: give at least 4 cells",
            grid.window
        )));
    }
    if spec.cols < 2 || spec.rows < 2 {
        return Err(Error::Invalid(format!(
            "a {}×{} grid has no triangle: it needs at least 2 rows and 2 columns",
            spec.cols, spec.rows
        )));
    }
    let layout = plan(reader, grid)?;
    if layout.windows() == 1 {
        let stats = whole(reader, grid, sink, progress)?;
        return not_empty(reader, stats);
    }
    let Stop::MaxError(bound) = grid.options.stop else {
        return Err(Error::Options(format!(
            "a point or triangle budget needs the whole grid in one window: this {}×{} grid \
             makes {} windows of --window {}; give --max-error, or --window {} (within --mem)",
            spec.cols,
            spec.rows,
            layout.windows(),
            grid.window,
            spec.cols.max(spec.rows) - 1
        )));
    };
    if !(bound >= 0.0 && bound.is_finite()) {
        return Err(Error::Options(format!(
            "--max-error {bound} must be a finite number >= 0"
        )));
    }
    let mut stitch = Stitch::new(&layout.cols, &layout.rows);
    // Windows joined along their borders; missing cells are known only once read.
    sink.declare(MeshKind {
        trimmed: true,
        not_delaunay: true,
        ..MeshKind::default()
    })?;
    run(reader, &spec, grid, &layout, &mut stitch, sink, progress)?;
    let mut stats = stitch.finish(&spec);
    stats.seconds = start.elapsed().as_secs_f64();
    not_empty(reader, stats)
}

/// `stats`, or the refusal of a TIN without a triangle (its mesh is never finished): a grid
/// whose every cell is nodata, or whose valid cells stand alone.
fn not_empty(reader: &RasterReader, stats: SimplifyStats) -> Result<SimplifyStats> {
    if stats.triangles > 0 {
        return Ok(stats);
    }
    let spec = reader.spec();
    let message = if stats.valid_cells == 0 {
        format!(
            "every one of its {}×{} cells is missing ({}): there is no height to make a TIN \
             of; check the nodata value and the band",
            spec.cols,
            spec.rows,
            match spec.nodata {
                Some(v) => format!("the nodata value {v}, or NaN"),
                None => "NaN".into(),
            }
        )
    } else {
        format!(
            "its {} valid cells (of {}×{}) make no triangle: each stands alone or in a strip \
             one cell wide between missing cells",
            stats.valid_cells, spec.cols, spec.rows
        )
    };
    Err(Error::Format {
        path: reader.path().to_path_buf(),
        message,
    })
}

/// The windows and what may be held at once, or the refusal when one band of windows cannot
/// fit `grid.mem`.
fn plan(reader: &RasterReader, grid: &GridOptions) -> Result<Layout> {
    let spec = reader.spec();
    let cols = cuts(spec.cols, grid.window);
    let rows = cuts(spec.rows, grid.window);
    crate::limits::check_threads(grid.threads)?;
    let threads = match grid.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    let mib = |b: u64| b.div_ceil(1 << 20);
    if cols.len() == 2 && rows.len() == 2 {
        let read = reader.read_bytes(spec.rows);
        let cells = spec.cells();
        let need = FIXED_BYTES + read + cells * (BAND_BYTES_PER_CELL + WINDOW_BYTES_PER_CELL);
        if need > grid.mem {
            return Err(Error::Options(format!(
                "this {}×{} grid in one window needs up to {} MiB, more than --mem {} MiB: give \
                 a smaller --window (default {DEFAULT_WINDOW}) or a larger --mem",
                spec.cols,
                spec.rows,
                mib(need),
                mib(grid.mem)
            )));
        }
        return Ok(Layout {
            cols,
            rows,
            in_flight: 1,
            bands: 1,
            threads: 1,
        });
    }
    let tallest = rows.windows(2).map(|w| w[1] - w[0] + 1).max().unwrap_or(2);
    let widest = cols.windows(2).map(|w| w[1] - w[0] + 1).max().unwrap_or(2);
    let band = u64::from(spec.cols) * u64::from(tallest) * BAND_BYTES_PER_CELL;
    let read = reader.read_bytes(tallest);
    let window = u64::from(widest) * u64::from(tallest) * WINDOW_BYTES_PER_CELL;
    let stitch = Stitch::bytes(&cols, tallest);
    let base = FIXED_BYTES + read + stitch;
    let across = cols.len() - 1;
    if base + band + window > grid.mem {
        return Err(Error::Options(format!(
            "one band of windows of this {}×{} grid needs {} MiB (its {}×{} heights {} MiB, \
             reading {} MiB, one window's TIN up to {} MiB), more than --mem {} MiB: give a \
             larger --mem or a smaller --window (now {}){}",
            spec.cols,
            spec.rows,
            mib(base + band + window),
            spec.cols,
            tallest,
            mib(band),
            mib(read),
            mib(window),
            mib(grid.mem),
            grid.window,
            if reader.chunk_bytes() > band {
                "; the file's strips or tiles are large: retile it (gdal_translate -co TILED=YES)"
            } else {
                ""
            }
        )));
    }
    let bands = if base + 2 * band + window <= grid.mem {
        2
    } else {
        1
    };
    let room = grid.mem - base - bands as u64 * band;
    let in_flight = ((room / window) as usize)
        .clamp(1, threads.max(1) * 2)
        .min(across * 2);
    Ok(Layout {
        cols,
        rows,
        in_flight,
        bands,
        threads: threads.min(in_flight).max(1),
    })
}

/// A grid of one window: read whole and simplified as [`super::simplify`] does.
fn whole(
    reader: &mut RasterReader,
    grid: &GridOptions,
    sink: &mut dyn MeshSink,
    mut progress: Option<GridProgressFn<'_>>,
) -> Result<SimplifyStats> {
    let spec = reader.spec().clone();
    let heights = reader.read_heights()?;
    let mut each = |points: u64, error: f64| {
        if let Some(p) = progress.as_mut() {
            p(GridProgress::Refining { points, error });
        }
    };
    let tin = match &heights {
        Heights::F32(h) => super::simplify(&spec, h, &grid.options, Some(&mut each)),
        Heights::F64(h) => super::simplify(&spec, h, &grid.options, Some(&mut each)),
    }?;
    drop(heights);
    // Delaunay in the grid's index space, not exactly in world coordinates (the cell centres
    // are rounded there, and a grid is full of cocircular cells); the boundary is the hull
    // unless missing cells cut it or the grid is rotated.
    sink.declare(MeshKind {
        trimmed: tin.stats.valid_cells < spec.cells() || !spec.is_axis_aligned(),
        not_delaunay: true,
        ..MeshKind::default()
    })?;
    for &v in &tin.vertices {
        sink.vertex(v)?;
    }
    for t in &tin.triangles {
        sink.triangle(t.map(u64::from))?;
    }
    let mut stats = tin.stats;
    stats.windows = 1;
    Ok(stats)
}

/// A band of windows in memory: rows `rows[b] ..= rows[b + 1]`, full width, and the border
/// vertices of its windows.
struct Band {
    heights: Heights,
    /// Vertex columns of each window's top and bottom sides (offsets from the window's left).
    top: Vec<Vec<usize>>,
    bottom: Vec<Vec<usize>>,
    /// Vertex rows (offsets from the band's top) of each vertical line `cols[j]`.
    sides: Vec<Vec<usize>>,
    /// Valid cells of the rows the band owns (its last row belongs to the next band).
    valid: u64,
}

/// What one window gives the writer.
pub(super) struct WindowOut {
    pub(super) kept: Kept,
    pub(super) interior: ErrorSums,
    pub(super) sides: SideErrors,
    pub(super) insertions: u64,
    pub(super) flips: u64,
    pub(super) scans: u64,
    pub(super) removed: u64,
    /// Valid cells of the band (given with the band's first window).
    pub(super) valid: u64,
}

fn read_band(
    reader: &mut RasterReader,
    layout: &Layout,
    b: usize,
    bound: f64,
    decimate: bool,
) -> Result<Band> {
    let (r0, r1) = (layout.rows[b], layout.rows[b + 1]);
    let last = b + 2 == layout.rows.len();
    let heights = reader.read_rows(r0, r1 - r0 + 1)?;
    let cols = reader.spec().cols as usize;
    let at = |c: usize, r: usize| -> f64 {
        match &heights {
            Heights::F32(h) => f64::from(h[r * cols + c]),
            Heights::F64(h) => h[r * cols + c],
        }
    };
    let rows = (r1 - r0) as usize;
    let line = |range: std::ops::RangeInclusive<usize>, r: Option<usize>, c: Option<usize>| {
        let h: Vec<f64> = range.map(|k| at(c.unwrap_or(k), r.unwrap_or(k))).collect();
        simplify_line(&h, bound, decimate)
    };
    let mut top = Vec::new();
    let mut bottom = Vec::new();
    for w in layout.cols.windows(2) {
        let (c0, c1) = (w[0] as usize, w[1] as usize);
        top.push(line(c0..=c1, Some(0), None));
        bottom.push(line(c0..=c1, Some(rows), None));
    }
    let sides = layout
        .cols
        .iter()
        .map(|&c| line(0..=rows, None, Some(c as usize)))
        .collect();
    let owned = if last { rows + 1 } else { rows } * cols;
    let valid = match &heights {
        Heights::F32(h) => h[..owned].iter().filter(|v| !v.is_nan()).count(),
        Heights::F64(h) => h[..owned].iter().filter(|v| !v.is_nan()).count(),
    } as u64;
    Ok(Band {
        heights,
        top,
        bottom,
        sides,
        valid,
    })
}

/// Refines window `j` of `band` (band index `b`).
fn refine_window(
    spec: &RasterSpec,
    layout: &Layout,
    band: &Band,
    b: usize,
    j: usize,
    options: &Options,
) -> Result<WindowOut> {
    match &band.heights {
        Heights::F32(h) => refine_window_in(spec, layout, band, h, b, j, options),
        Heights::F64(h) => refine_window_in(spec, layout, band, h, b, j, options),
    }
}

fn refine_window_in<T: Height>(
    spec: &RasterSpec,
    layout: &Layout,
    band: &Band,
    h: &[T],
    b: usize,
    j: usize,
    options: &Options,
) -> Result<WindowOut> {
    let (c0, c1) = (layout.cols[j], layout.cols[j + 1]);
    let (r0, r1) = (layout.rows[b], layout.rows[b + 1]);
    let (w, hh) = (i64::from(c1 - c0 + 1), i64::from(r1 - r0 + 1));
    let stride = i64::from(spec.cols);
    let heights = &h[c0 as usize..];
    let all = Clip::all(w, hh);
    let may_miss = (0..hh).any(|r| {
        let s = (r * stride) as usize;
        heights[s..s + w as usize]
            .iter()
            .any(|&v| v.into().is_nan())
    });
    let cells = Cells {
        heights,
        stride,
        all,
        cand: Clip {
            c0: 1,
            c1: w - 2,
            r0: 1,
            r1: hh - 2,
        },
        may_miss,
    };
    let mut start: Vec<[i64; 2]> = Vec::new();
    start.extend(band.top[j].iter().map(|&c| [c as i64, 0]));
    start.extend(band.bottom[j].iter().map(|&c| [c as i64, hh - 1]));
    let inner = |v: &&usize| **v > 0 && (**v as i64) < hh - 1;
    start.extend(band.sides[j].iter().filter(inner).map(|&r| [0, r as i64]));
    start.extend(
        band.sides[j + 1]
            .iter()
            .filter(inner)
            .map(|&r| [w - 1, r as i64]),
    );
    let mut r = Refiner::new(spec, cells, [c0, r0], &start, true)?;
    r.run(options.stop, None)?;
    let removed = match options.stop {
        Stop::MaxError(e) if options.decimate => r.decimate(e)?,
        _ => 0,
    };
    let (kept, keep) = r.kept(spec);
    let (interior, sides) = r.window_errors(&keep);
    Ok(WindowOut {
        kept,
        interior,
        sides,
        insertions: r.insertions,
        flips: r.flips(),
        scans: r.scans,
        removed,
        valid: if j == 0 { band.valid } else { 0 },
    })
}

/// What the workers and the writer share.
struct State {
    /// The next window to start.
    next: usize,
    /// Windows written.
    written: usize,
    bands: BTreeMap<usize, Arc<Band>>,
    loading: bool,
    results: BTreeMap<usize, Result<WindowOut>>,
    stop: bool,
}

fn run(
    reader: &mut RasterReader,
    spec: &RasterSpec,
    grid: &GridOptions,
    layout: &Layout,
    stitch: &mut Stitch,
    sink: &mut dyn MeshSink,
    mut progress: Option<GridProgressFn<'_>>,
) -> Result<()> {
    let Stop::MaxError(bound) = grid.options.stop else {
        return Err(Error::Internal("windows need an error bound".into()));
    };
    let total = layout.windows();
    let across = layout.across();
    let state = Mutex::new(State {
        next: 0,
        written: 0,
        bands: BTreeMap::new(),
        loading: false,
        results: BTreeMap::new(),
        stop: false,
    });
    let cv = Condvar::new();
    let reader = Mutex::new(reader);
    let lock = || state.lock().unwrap_or_else(|e| e.into_inner());
    let work = || {
        loop {
            let mut s = lock();
            let (w, band) = loop {
                if s.stop || s.next >= total {
                    return;
                }
                let w = s.next;
                let b = w / across;
                if w < s.written + layout.in_flight {
                    if let Some(band) = s.bands.get(&b).cloned() {
                        s.next += 1;
                        break (w, band);
                    }
                    if !s.loading && s.bands.len() < layout.bands {
                        s.loading = true;
                        drop(s);
                        let mut rd = reader.lock().unwrap_or_else(|e| e.into_inner());
                        let r = read_band(&mut rd, layout, b, bound, grid.options.decimate);
                        drop(rd);
                        s = lock();
                        s.loading = false;
                        match r {
                            Ok(band) => {
                                s.bands.insert(b, Arc::new(band));
                            }
                            Err(e) => {
                                s.results.insert(w, Err(e));
                                s.stop = true;
                            }
                        }
                        cv.notify_all();
                        continue;
                    }
                }
                s = cv.wait(s).unwrap_or_else(|e| e.into_inner());
            };
            drop(s);
            let (b, j) = (w / across, w % across);
            let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                refine_window(spec, layout, &band, b, j, &grid.options)
            }))
            .unwrap_or_else(|p| {
                let what = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                Err(Error::Internal(format!("window {w}: {what}")))
            });
            drop(band);
            let mut s = lock();
            s.results.insert(w, out);
            cv.notify_all();
        }
    };
    std::thread::scope(|scope| {
        for _ in 0..layout.threads {
            scope.spawn(work);
        }
        let result = (|| {
            for w in 0..total {
                let out = {
                    let mut s = lock();
                    loop {
                        if let Some(r) = s.results.remove(&w) {
                            break r;
                        }
                        s = cv.wait(s).unwrap_or_else(|e| e.into_inner());
                    }
                };
                stitch.window(w / across, w % across, out?, sink)?;
                let mut s = lock();
                s.written = w + 1;
                if (w + 1) % across == 0 {
                    s.bands.remove(&(w / across));
                }
                cv.notify_all();
                drop(s);
                if let Some(p) = progress.as_mut() {
                    p(GridProgress::Windows {
                        done: (w + 1) as u64,
                        total: total as u64,
                        points: stitch.points(),
                    });
                }
            }
            Ok(())
        })();
        if result.is_err() {
            lock().stop = true;
            cv.notify_all();
        }
        result
    })
}
