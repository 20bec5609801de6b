//! Grid DEM to TIN within an error bound: greedy refinement by Delaunay insertion.
//!
//! Soomart & Paitoonwattanakij's incremental converter, in the form of Garland & Heckbert's
//! greedy insertion (as in fogleman's `hmm` and its port `delatin`):
//!
//! 1. start from the two triangles of the grid's four corner cells;
//! 2. for every triangle keep its *candidate*: the cell of largest vertical error among the cells
//!    whose centres lie in it (equation 4 of the paper with the vertical distance; only the cells
//!    inside the triangle are scanned, by exact integer rasterisation);
//! 3. keep the candidates in a priority queue; insert the worst with exact Delaunay insertion
//!    ([`crate::Tin`], Lawson flips, the crate's tie rule); rescan only the triangles the
//!    insertion created or flipped;
//! 4. stop when the worst error is within the bound, or at a point or triangle budget.
//!
//! The triangulation is built in cell-index space scaled to square cells (`x = col`, `y = -row`
//! for a north-up grid with square cells): exact small integers (the adaptive predicates' exact stage is then cheap), and since the map to world coordinates is a similarity the triangulation is Delaunay in
//! world coordinates too. Output vertices are the cell centres in world coordinates.
//!
//! # Missing cells (nodata)
//! A triangle that covers a missing cell (or has a missing corner: the grid's corners may be
//! missing; they are then *phantom* vertices) must be split first: its candidate is the valid
//! non-vertex cell nearest to the centroid of the missing cells it covers, with priority `+∞`. A
//! triangle over missing cells with no such cell left is dropped from the output. So no output
//! triangle covers a missing cell, and every valid cell either lies in an output triangle (and is
//! within the bound) or is a vertex; valid cells left in no output triangle (isolated cells, strips
//! one cell wide) are counted in [`SimplifyStats::uncovered_cells`]. Under a point or triangle
//! budget the splitting may stop early, and triangles still over missing cells are dropped.
//!
//! # Redundant points
//! With [`Stop::MaxError`], [`Options::decimate`] then visits every point (band by band, after
//! renumbering the TIN for locality) and removes it when the Delaunay triangles that would replace
//! its star keep every cell within the bound (checked on a preview, the point's own cell first).
//! Greedy insertion leaves many points that later points made redundant: this pass removes
//! 10–20 % of them at the same maximum error.
//!
//! # Memory: windows
//! [`simplify`] holds the whole grid (as `f32` when its values are exactly `f32`, else `f64`)
//! plus about 150 bytes per TIN point (TIN, candidates, queue; 256 bytes a cell at worst, every
//! cell a point). [`simplify_raster`] reads a grid file and keeps within a memory budget on
//! grids of any size:
//!
//! 1. the grid is cut evenly into *windows* of at most [`GridOptions::window`] ×
//!    [`GridOptions::window`] cell intervals ([`DEFAULT_WINDOW`]); neighbouring windows share
//!    their border line of cells. The window alone decides the output, never the memory budget
//!    or the threads; a grid of one window is simplified whole, by [`simplify`];
//! 2. the grid is read a band of windows at a time (full-width rows, strip or tile rows decoded
//!    once), and each border line of the band (every window side, corner to corner) is
//!    simplified in one dimension to the same bound (`border`: greedy insertion of the worst
//!    cell, then redundant points removed, missing cells as above), so the two windows on a side
//!    get the same vertices there;
//! 3. each window starts from the Delaunay triangulation of its border vertices (its rectangle
//!    is convex, so the border segments are hull edges and stay edges) and refines only its
//!    interior cells, then removes its redundant interior points. Border cells are within the
//!    bound through the border segments (checked in 1-D with a rounding margin, so that the
//!    windows' planes find them within it too), and the windows' TINs conform;
//! 4. windows run on every core (`threads` workers; the next band is read while the last windows
//!    of a band run) and are written strictly in order (`stitch`): each border vertex once, by the
//!    first window that uses it, its number kept for the next windows. So the bytes are the same
//!    whatever the budget and the threads.
//!
//! The budget covers one band of heights (12 bytes a cell at worst), the reader's buffer (a band
//! of 256 rows or one strip or tile), [`WINDOW_BYTES_PER_CELL`] per cell of each window in
//! flight, the writer's state and 16 MiB for the rest; a job whose band of windows cannot fit is
//! refused before anything is read ([`Error::Options`]). A larger budget lets more windows run at
//! once and the next band be read ahead. Point and triangle budgets ([`Stop::MaxPoints`],
//! [`Stop::MaxTriangles`]) are global, so they need one window. The border lines cost a few
//! points: on Big Tujunga at 1 m, 0.35 % more than one window with the default window (see
//! docs/BENCHMARKS.md).

use crate::error::{Error, Result};
use crate::input::raster::RasterSpec;
use refiner::Refiner;
use scan::Cells;
pub use scan::Height;

pub(crate) mod border;
mod queue;
mod refiner;
pub mod scan;
mod stitch;
mod windows;
pub use windows::{
    DEFAULT_WINDOW, GridOptions, GridProgress, GridProgressFn, WINDOW_BYTES_PER_CELL,
    simplify_raster,
};
pub mod thin;
pub(crate) mod thin_tiles;
pub use thin::{ThinLines, ThinOptions, ThinStats, Thinned, thin};

/// When to stop refining.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// When every valid cell is within this vertical distance of the TIN.
    MaxError(f64),
    /// Before the triangle count would exceed this.
    MaxTriangles(u64),
    /// When the TIN has this many points.
    MaxPoints(u64),
}

/// How to simplify.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Options {
    /// When to stop inserting points.
    pub stop: Stop,
    /// With [`Stop::MaxError`]: afterwards, remove every point (in insertion order) whose removal
    /// keeps all cells within the bound. Greedy insertion leaves many points that later points
    /// made redundant; this pass typically removes 15 % of them at the same maximum error.
    pub decimate: bool,
}

impl Options {
    /// Refine to `max_error`, then remove the redundant points.
    pub fn max_error(max_error: f64) -> Self {
        Options {
            stop: Stop::MaxError(max_error),
            decimate: true,
        }
    }
}

/// What the simplification did and how good the result is.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SimplifyStats {
    /// Cells in the grid.
    pub cells: u64,
    /// Valid (not missing) cells.
    pub valid_cells: u64,
    /// Points in the output TIN.
    pub points: u64,
    /// `points / valid_cells`.
    pub point_ratio: f64,
    /// Triangles in the output TIN.
    pub triangles: u64,
    /// `triangles / (2 · (cols - 1) · (rows - 1))`, the regular grid's triangle count.
    pub triangle_ratio: f64,
    /// Points inserted after the initial corners (Soomart's "split points").
    pub insertions: u64,
    /// Edge flips (Soomart's "swapped diagonals").
    pub flips: u64,
    /// Triangle scans (Soomart's "reorganized edges" counterpart).
    pub scans: u64,
    /// Points removed again by the redundancy pass ([`Options::decimate`]).
    pub removed: u64,
    /// Largest vertical error over the valid cells in output triangles.
    pub max_error: f64,
    /// Root-mean-square vertical error over the same cells.
    pub rms_error: f64,
    /// Valid cells in no output triangle (their points may still be vertices).
    pub uncovered_cells: u64,
    /// Wall-clock seconds of the refinement.
    pub seconds: f64,
    /// Windows the grid was cut into (1: simplified whole).
    pub windows: u64,
    /// Points on the windows' border lines (simplified in 1-D, shared by the windows).
    pub border_points: u64,
}

/// A simplified TIN in world coordinates.
#[derive(Clone, Debug, Default)]
pub struct Simplified {
    /// Vertices `[x, y, z]`: cell centres in world coordinates.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, counter-clockwise in world `(x, y)`.
    pub triangles: Vec<[u32; 3]>,
    /// For each vertex, its cell `(col, row)`.
    pub cells: Vec<[u32; 2]>,
    /// Numbers.
    pub stats: SimplifyStats,
}

/// Progress callback: `(points, current worst error)`, called now and then.
pub type Progress<'a> = &'a mut dyn FnMut(u64, f64);

/// Simplifies the grid `heights` (row-major, `spec.cols × spec.rows`, missing cells NaN) into a
/// TIN.
///
/// # Errors
/// [`Error::Invalid`] when `heights` has the wrong length, the grid has a single row or column,
/// or the error bound is negative or not finite; [`Error::TooManyPoints`] beyond 2³² cells.
pub fn simplify<T: Height>(
    spec: &RasterSpec,
    heights: &[T],
    options: &Options,
    progress: Option<Progress<'_>>,
) -> Result<Simplified> {
    let start = std::time::Instant::now();
    let (cols, rows) = (i64::from(spec.cols), i64::from(spec.rows));
    if heights.len() as u64 != spec.cells() {
        return Err(Error::Invalid(format!(
            "{} heights for a {}×{} grid",
            heights.len(),
            cols,
            rows
        )));
    }
    if cols < 2 || rows < 2 {
        return Err(Error::Invalid(format!(
            "a {cols}×{rows} grid has no triangle: it needs at least 2 rows and 2 columns"
        )));
    }
    if spec.cells() > u64::from(u32::MAX) {
        return Err(Error::TooManyPoints {
            count: spec.cells(),
            max: u64::from(u32::MAX),
        });
    }
    let corners = [[0, 0], [cols - 1, 0], [0, rows - 1], [cols - 1, rows - 1]];
    let cells = Cells::grid(heights, cols);
    let mut r = Refiner::new(spec, cells, [0, 0], &corners, false)?;
    r.run(options.stop, progress)?;
    let mut removed = 0;
    if let Stop::MaxError(e) = options.stop
        && options.decimate
    {
        removed = r.decimate(e)?;
    }
    let (kept, keep) = r.kept(spec);
    let errors = r.errors(&keep);
    let valid = heights.iter().filter(|&&h| !h.into().is_nan()).count() as u64;
    let points = kept.vertices.len() as u64;
    let triangles = kept.triangles.len() as u64;
    let grid_tris = 2.0 * (cols - 1) as f64 * (rows - 1) as f64;
    Ok(Simplified {
        vertices: kept.vertices,
        triangles: kept.triangles,
        cells: kept.cells,
        stats: SimplifyStats {
            cells: (cols * rows) as u64,
            valid_cells: valid,
            points,
            point_ratio: points as f64 / valid.max(1) as f64,
            triangles,
            triangle_ratio: triangles as f64 / grid_tris,
            insertions: r.insertions,
            flips: r.flips(),
            scans: r.scans,
            removed,
            max_error: errors.max,
            rms_error: (errors.sum_sq / errors.covered.max(1) as f64).sqrt(),
            uncovered_cells: valid - errors.covered,
            seconds: start.elapsed().as_secs_f64(),
            windows: 1,
            border_points: 0,
        },
    })
}

#[cfg(test)]
mod tests;
