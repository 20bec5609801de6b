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
//! # Memory
//! The whole grid is held in memory, as `f32` when its values are exactly `f32` (see
//! [`crate::input::raster::RasterReader::read_heights`], which reads band by band) or `f64`, plus
//! about 150 bytes per TIN point (TIN, candidates, queue). Grids larger than memory are not
//! handled yet (they would need window-by-window refinement with shared border points).

use crate::error::{Error, Result};
use crate::input::raster::RasterSpec;
use crate::tin::{Tin, TriId};
use queue::TriangleQueue;
pub use scan::Height;
use scan::{CellTriangle, NO_CELL};

mod queue;
pub mod scan;
pub mod thin;
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
    let mut r = Refiner::new(spec, heights)?;
    r.run(options.stop, progress)?;
    let mut removed = 0;
    if let Stop::MaxError(e) = options.stop
        && options.decimate
    {
        removed = r.decimate(e)?;
    }
    let mut out = r.finish(spec);
    out.stats.removed = removed;
    out.stats.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// Per-triangle candidate.
#[derive(Clone, Copy, Debug)]
struct Cand {
    cell: u64,
    error: f64,
    key: u32,
}

/// The order key of an error: its `f32` bits, rounded up so that the key never ranks an error
/// below a smaller one (non-negative floats order like their bits).
fn error_key(e: f64) -> u32 {
    let f = e as f32;
    let f = if f64::from(f) < e { f.next_up() } else { f };
    f.to_bits()
}

struct Refiner<'a, T: Height> {
    heights: &'a [T],
    cols: i64,
    rows: i64,
    may_miss: bool,
    /// Map from cell index to internal coordinates.
    kx: f64,
    ky: f64,
    tin: Tin,
    /// Cell `(col, row)` and height of each TIN vertex.
    vdata: Vec<VData>,
    cand: Vec<Cand>,
    /// Queue keys: the candidate's error as `f32` bits rounded up, then the triangle.
    heap: TriangleQueue,
    /// Candidates with an error at or below this are never taken (the error bound), so they
    /// are not queued.
    floor: f64,
    scans: u64,
    insertions: u64,
    touched: Vec<TriId>,
}

impl<'a, T: Height> Refiner<'a, T> {
    fn new(spec: &RasterSpec, heights: &'a [T]) -> Result<Self> {
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
        let (kx, ky) = internal_scale(spec);
        let may_miss = heights.iter().any(|&h| h.into().is_nan());
        let corners = [[0, 0], [cols - 1, 0], [0, rows - 1], [cols - 1, rows - 1]];
        let pts: Vec<[f64; 3]> = corners
            .iter()
            .map(|&[c, r]| [c as f64 * kx, r as f64 * ky, 0.0])
            .collect();
        let t = crate::triangulate(&pts, &crate::Options::default())?;
        let tin = Tin::from_triangulation(&t)?;
        let vdata = t
            .input_index
            .iter()
            .map(|&i| {
                let [c, r] = corners[i as usize];
                VData::new(c, r, heights[(r * cols + c) as usize].into())
            })
            .collect();
        let mut r = Refiner {
            heights,
            cols,
            rows,
            may_miss,
            kx,
            ky,
            tin,
            vdata,
            cand: Vec::new(),
            heap: TriangleQueue::default(),
            floor: 0.0,
            scans: 0,
            insertions: 0,
            touched: Vec::new(),
        };
        r.tin.record_touched(true);
        // Pure insertion until the redundancy pass: no vertex → edge map upkeep.
        r.tin.set_vertex_tracking(false);
        Ok(r)
    }

    #[inline]
    fn cell_triangle(&self, t: TriId) -> CellTriangle {
        let d = self.tin.tri_vertices(t).map(|v| self.vdata[v.0 as usize]);
        CellTriangle {
            v: d.map(|d| [i64::from(d.col), i64::from(d.row)]),
            z: d.map(|d| d.z),
        }
        .ccw()
    }

    fn rescan(&mut self, t: TriId) {
        let s = self
            .cell_triangle(t)
            .scan(self.heights, self.cols, self.may_miss);
        self.scans += 1;
        let i = t.0 as usize;
        if i >= self.cand.len() {
            self.cand.resize(
                i + 1,
                Cand {
                    cell: NO_CELL,
                    error: 0.0,
                    key: 0,
                },
            );
        }
        let c = &mut self.cand[i];
        c.cell = s.cell;
        c.error = s.error;
        c.key = error_key(s.error);
        let queued = s.cell != NO_CELL && s.error > self.floor;
        self.heap.set(t.0, queued.then_some(c.key));
    }

    /// The worst candidate.
    fn peek(&mut self) -> Option<(f64, TriId)> {
        let t = self.heap.peek()?;
        Some((self.cand[t as usize].error, TriId(t)))
    }

    fn run(&mut self, stop: Stop, mut progress: Option<Progress<'_>>) -> Result<()> {
        match stop {
            Stop::MaxError(e) if !(e >= 0.0 && e.is_finite()) => {
                return Err(Error::Invalid(format!("--max-error {e} must be >= 0")));
            }
            _ => {}
        }
        if let Stop::MaxError(e) = stop {
            self.floor = e;
        }
        let all: Vec<TriId> = self.tin.triangles().collect();
        for t in all {
            self.rescan(t);
        }
        while let Some((error, t)) = self.peek() {
            let done = match stop {
                Stop::MaxError(e) => error <= e,
                Stop::MaxPoints(n) => self.tin.vertex_count() as u64 >= n,
                Stop::MaxTriangles(n) => self.tin.triangle_count() as u64 + 2 > n,
            };
            if done {
                break;
            }
            self.heap.pop();
            let cell = std::mem::replace(&mut self.cand[t.0 as usize].cell, NO_CELL);
            self.insert(t, cell)?;

            if self.insertions & 0x3FFF == 0
                && let Some(p) = progress.as_mut()
            {
                p(self.tin.vertex_count() as u64, error);
            }
        }
        Ok(())
    }

    fn insert(&mut self, t: TriId, cell: u64) -> Result<()> {
        let (col, row) = (
            (cell % self.cols as u64) as i64,
            (cell / self.cols as u64) as i64,
        );
        let z: f64 = self.heights[cell as usize].into();
        let p = [col as f64 * self.kx, row as f64 * self.ky, z];
        // With non-square cells the internal coordinates are rounded, so a cell on an edge in
        // index space may fall just outside the triangle: then the point is located by a walk.
        let v = match self.tin.insert_in_triangle(t, p) {
            Ok(v) => v,
            Err(_) => {
                self.tin.set_hint(t);
                self.tin.insert(p)?
            }
        };
        if v.0 as usize != self.vdata.len() {
            return Err(Error::Internal("vertex ids out of step".into()));
        }
        self.vdata.push(VData::new(col, row, z));
        self.insertions += 1;
        self.touched.clear();
        let mut touched = std::mem::take(&mut self.touched);
        self.tin.take_touched(&mut touched);
        // A handful of triangles: sorting beats a per-triangle stamp array (cache misses).
        touched.sort_unstable();
        touched.dedup();
        for &t in &touched {
            self.rescan(t);
        }
        self.touched = touched;
        Ok(())
    }

    /// Removes the vertices the bound does not need (a post-pass of the greedy insertion, which
    /// inserts points that later points make redundant): a vertex goes when every cell of the
    /// triangles that replace its star stays within `e` and no missing cell gets covered.
    fn decimate(&mut self, e: f64) -> Result<u64> {
        let mut removed = 0;
        let mut tris: Vec<CellTriangle> = Vec::new();
        self.tin.record_touched(false);
        self.relayout(16)?;
        for v in 0..self.vdata.len() as u32 {
            let d = self.vdata[v as usize];
            let corner = (d.col == 0 || i64::from(d.col) == self.cols - 1)
                && (d.row == 0 || i64::from(d.row) == self.rows - 1);
            if corner || d.z.is_nan() {
                continue;
            }
            let v = crate::tin::VertexId(v);
            // The triangles that would replace the star; the removed point's own cell is the
            // likeliest to fail, so it is checked as soon as its triangle is known.
            let own = [i64::from(d.col), i64::from(d.row)];
            tris.clear();
            let vdata = &self.vdata;
            let own_ok = self.tin.removal_preview_with(v, |tri| {
                let d3 = tri.map(|w| vdata[w.0 as usize]);
                let ct = CellTriangle {
                    v: d3.map(|d| [i64::from(d.col), i64::from(d.row)]),
                    z: d3.map(|d| d.z),
                }
                .ccw();
                tris.push(ct);
                !(ct.contains(own) && ct.error_at(own, d.z) > e)
            });
            if !matches!(own_ok, Ok(true)) {
                continue;
            }
            let ok = tris
                .iter()
                .all(|ct| !ct.exceeds(self.heights, self.cols, e));
            if ok {
                self.tin.remove(v)?;
                removed += 1;
            }
        }
        Ok(removed)
    }

    /// Renumbers the TIN's vertices band by band (`band` rows, then by column) and its triangles
    /// by their first vertex, so that neighbouring points are neighbours in memory: the
    /// redundant-point pass then visits the points in that order with the TIN and the grid in
    /// cache.
    fn relayout(&mut self, band: u32) -> Result<()> {
        let mut order: Vec<crate::tin::VertexId> = self.tin.vertices().collect();
        order.sort_unstable_by_key(|&v| {
            let d = self.vdata[v.0 as usize];
            (u64::from(d.row / band) << 42) | (u64::from(d.col) << 21) | u64::from(d.row % band)
        });
        self.tin.relayout(&order)?;
        self.vdata = order.iter().map(|&v| self.vdata[v.0 as usize]).collect();
        self.cand.clear();
        Ok(())
    }

    /// Output: the triangles over no missing cell, in world coordinates, with the statistics.
    fn finish(self, spec: &RasterSpec) -> Simplified {
        let keep: Vec<TriId> = self
            .tin
            .triangles()
            .filter(|&t| {
                !self.may_miss
                    || !self
                        .cell_triangle(t)
                        .exceeds(self.heights, self.cols, f64::INFINITY)
            })
            .collect();
        let mut remap = vec![u32::MAX; self.vdata.len()];
        let mut out = Simplified::default();
        let flip = (self.kx * self.ky < 0.0) != spec.flips_orientation();
        for &t in &keep {
            let tri = self.tin.tri_vertices(t).map(|v| {
                let i = v.0 as usize;
                if remap[i] == u32::MAX {
                    remap[i] = out.vertices.len() as u32;
                    let d = self.vdata[i];
                    let [x, y] = spec.cell_center(d.col, d.row);
                    out.vertices.push([x, y, d.z]);
                    out.cells.push([d.col, d.row]);
                }
                remap[i]
            });
            out.triangles
                .push(if flip { [tri[0], tri[2], tri[1]] } else { tri });
        }
        let valid = self.heights.iter().filter(|&&h| !h.into().is_nan()).count() as u64;
        let (max_error, rms_error, covered) = self.errors(&keep);
        let grid_tris = 2.0 * (self.cols - 1) as f64 * (self.rows - 1) as f64;
        out.stats = SimplifyStats {
            cells: (self.cols * self.rows) as u64,
            valid_cells: valid,
            points: out.vertices.len() as u64,
            point_ratio: out.vertices.len() as f64 / valid.max(1) as f64,
            triangles: out.triangles.len() as u64,
            triangle_ratio: out.triangles.len() as f64 / grid_tris,
            insertions: self.insertions,
            flips: self.tin.flips(),
            scans: self.scans,
            removed: 0,
            max_error,
            rms_error,
            uncovered_cells: valid - covered,
            seconds: 0.0,
        };
        out
    }

    /// Max and RMS error over the valid cells of the kept triangles, each cell counted once.
    fn errors(&self, keep: &[TriId]) -> (f64, f64, u64) {
        let mut seen = vec![0u64; (self.heights.len()).div_ceil(64)];
        let (mut max, mut sum, mut n) = (0.0f64, 0.0f64, 0u64);
        for &t in keep {
            let ct = self.cell_triangle(t);
            let (gx, gy) = ct.plane();
            let a = ct.v[0];
            ct.rows(self.cols, |r, lo, hi| {
                for c in lo..=hi {
                    let i = (r * self.cols + c) as usize;
                    let h: f64 = self.heights[i].into();
                    if h.is_nan() || seen[i / 64] & (1 << (i % 64)) != 0 {
                        continue;
                    }
                    seen[i / 64] |= 1 << (i % 64);
                    let z = (ct.z[0] + gy * (r - a[1]) as f64) + gx * (c - a[0]) as f64;
                    let e = (h - z).abs();
                    max = max.max(e);
                    sum += e * e;
                    n += 1;
                }
            });
        }
        let _ = self.rows;
        (max, (sum / n.max(1) as f64).sqrt(), n)
    }
}

/// A TIN vertex: its cell and height.
#[derive(Clone, Copy, Debug)]
struct VData {
    col: u32,
    row: u32,
    z: f64,
}

impl VData {
    fn new(col: i64, row: i64, z: f64) -> Self {
        VData {
            col: col as u32,
            row: row as u32,
            z,
        }
    }
}

/// Scale from cell indices to the internal frame: `x = col·kx`, `y = row·ky`, a similarity of
/// the world frame for axis-aligned grids (so Delaunay there is Delaunay in the world), with
/// `|kx| = 1`. Rotated or sheared grids are triangulated in index space (`x = col`, `y = -row`).
fn internal_scale(spec: &RasterSpec) -> (f64, f64) {
    let t = &spec.transform;
    if !spec.is_axis_aligned() {
        return (1.0, -1.0);
    }
    let kx = t[1].signum();
    let ky = t[5] / t[1].abs();
    // Cells square to 1e-9 (a non-round cell size stored with different roundings, such as
    // 33.365 m): integer coordinates, exact and fast.
    if (ky.abs() - 1.0).abs() < 1e-9 {
        return (kx, ky.signum());
    }
    (kx, ky)
}

#[cfg(test)]
mod tests;
