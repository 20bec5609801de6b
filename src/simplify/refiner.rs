//! The greedy refinement of one grid, or of one window of a larger grid whose border lines are
//! fixed (see the [parent module](super)).

use super::queue::TriangleQueue;
use super::scan::{CellTriangle, Cells, Clip, Height, NO_CELL};
use super::{Progress, Stop};
use crate::error::{Error, Result};
use crate::input::raster::RasterSpec;
use crate::tin::{Tin, TriId, VertexId};

/// Per-triangle candidate.
#[derive(Clone, Copy, Debug)]
struct Cand {
    cell: u64,
    error: f64,
    key: u32,
}

/// The order key of an error: its `f32` bits, rounded up so that the key never ranks an error
/// below a smaller one (non-negative floats order like their bits).
pub(super) fn error_key(e: f64) -> u32 {
    let f = e as f32;
    let f = if f64::from(f) < e { f.next_up() } else { f };
    f.to_bits()
}

/// A TIN vertex: its cell (in the refined grid or window) and height.
#[derive(Clone, Copy, Debug)]
pub(super) struct VData {
    pub(super) col: u32,
    pub(super) row: u32,
    pub(super) z: f64,
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

/// Error statistics over a set of cells.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ErrorSums {
    /// Largest vertical error.
    pub(super) max: f64,
    /// Sum of the squared errors.
    pub(super) sum_sq: f64,
    /// Valid cells counted.
    pub(super) covered: u64,
}

impl ErrorSums {
    pub(super) fn add(&mut self, e: f64) {
        self.max = self.max.max(e);
        self.sum_sq += e * e;
        self.covered += 1;
    }

    pub(super) fn merge(&mut self, o: &ErrorSums) {
        self.max = self.max.max(o.max);
        self.sum_sq += o.sum_sq;
        self.covered += o.covered;
    }
}

/// The kept part of a refined TIN: triangles over no missing cell, their vertices in order of
/// first use.
pub(super) struct Kept {
    /// Vertices in world coordinates.
    pub(super) vertices: Vec<[f64; 3]>,
    /// Their cells, in the whole grid.
    pub(super) cells: Vec<[u32; 2]>,
    /// Triangles, counter-clockwise in world `(x, y)`.
    pub(super) triangles: Vec<[u32; 3]>,
}

/// The errors of the cells on a window's four sides: `NaN` for a cell in no kept triangle (or
/// missing). `top`/`bottom` run over the columns, `left`/`right` over the rows.
#[derive(Clone, Debug, Default)]
pub(super) struct SideErrors {
    pub(super) top: Vec<f64>,
    pub(super) bottom: Vec<f64>,
    pub(super) left: Vec<f64>,
    pub(super) right: Vec<f64>,
}

pub(super) struct Refiner<'a, T: Height> {
    cells: Cells<'a, T>,
    cols: i64,
    rows: i64,
    /// A window: its border vertices are fixed (never removed) and its border cells never
    /// candidates.
    window: bool,
    /// The first cell's place in the whole grid.
    origin: [u32; 2],
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
    pub(super) scans: u64,
    pub(super) insertions: u64,
    touched: Vec<TriId>,
}

impl<'a, T: Height> Refiner<'a, T> {
    /// A refiner of `cells` (`cols × rows`, at `origin` in the whole grid), starting from the
    /// Delaunay triangulation of the cells `start`. A `window`'s border cells are never
    /// candidates and its border vertices are never removed.
    pub(super) fn new(
        spec: &RasterSpec,
        cells: Cells<'a, T>,
        origin: [u32; 2],
        start: &[[i64; 2]],
        window: bool,
    ) -> Result<Self> {
        let (cols, rows) = (cells.all.c1 + 1, cells.all.r1 + 1);
        let (kx, ky) = internal_scale(spec);
        let pts: Vec<[f64; 3]> = start
            .iter()
            .map(|&[c, r]| [c as f64 * kx, r as f64 * ky, 0.0])
            .collect();
        let t = crate::triangulate(&pts, &crate::Options::default())?;
        let tin = Tin::from_triangulation(&t)?;
        let vdata = t
            .input_index
            .iter()
            .map(|&i| {
                let [c, r] = start[i as usize];
                VData::new(c, r, cells.at(c, r))
            })
            .collect();
        let mut r = Refiner {
            cells,
            cols,
            rows,
            window,
            origin,
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

    pub(super) fn flips(&self) -> u64 {
        self.tin.flips()
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
        let s = self.cell_triangle(t).scan(&self.cells);
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

    pub(super) fn run(&mut self, stop: Stop, mut progress: Option<Progress<'_>>) -> Result<()> {
        match stop {
            Stop::MaxError(e) if !(e >= 0.0 && e.is_finite()) => {
                return Err(Error::Options(format!(
                    "--max-error {e} must be a finite number >= 0"
                )));
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
        let stride = self.cells.stride as u64;
        let (col, row) = ((cell % stride) as i64, (cell / stride) as i64);
        let z: f64 = self.cells.heights[cell as usize].into();
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

    /// May vertex `d` be removed? Not a grid's corner, nor any border vertex of a window.
    fn fixed(&self, d: VData) -> bool {
        let (c, r) = (i64::from(d.col), i64::from(d.row));
        let on_col = c == 0 || c == self.cols - 1;
        let on_row = r == 0 || r == self.rows - 1;
        if self.window {
            on_col || on_row
        } else {
            on_col && on_row
        }
    }

    /// Removes the vertices the bound does not need (a post-pass of the greedy insertion, which
    /// inserts points that later points make redundant): a vertex goes when every cell of the
    /// triangles that replace its star stays within `e` and no missing cell gets covered.
    pub(super) fn decimate(&mut self, e: f64) -> Result<u64> {
        let mut removed = 0;
        let mut tris: Vec<CellTriangle> = Vec::new();
        self.tin.record_touched(false);
        self.relayout(16)?;
        for v in 0..self.vdata.len() as u32 {
            let d = self.vdata[v as usize];
            if self.fixed(d) || d.z.is_nan() {
                continue;
            }
            let v = VertexId(v);
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
            let ok = tris.iter().all(|ct| !ct.exceeds(&self.cells, e));
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
        let mut order: Vec<VertexId> = self.tin.vertices().collect();
        order.sort_unstable_by_key(|&v| {
            let d = self.vdata[v.0 as usize];
            (u64::from(d.row / band) << 42) | (u64::from(d.col) << 21) | u64::from(d.row % band)
        });
        self.tin.relayout(&order)?;
        self.vdata = order.iter().map(|&v| self.vdata[v.0 as usize]).collect();
        self.cand.clear();
        Ok(())
    }

    /// The triangles over no missing cell, with their vertices in world coordinates (in order
    /// of first use).
    pub(super) fn kept(&self, spec: &RasterSpec) -> (Kept, Vec<TriId>) {
        let keep: Vec<TriId> = self
            .tin
            .triangles()
            .filter(|&t| {
                !self.cells.may_miss || !self.cell_triangle(t).exceeds(&self.cells, f64::INFINITY)
            })
            .collect();
        let mut remap = vec![u32::MAX; self.vdata.len()];
        let mut out = Kept {
            vertices: Vec::new(),
            cells: Vec::new(),
            triangles: Vec::with_capacity(keep.len()),
        };
        let flip = (self.kx * self.ky < 0.0) != spec.flips_orientation();
        let [c0, r0] = self.origin;
        for &t in &keep {
            let tri = self.tin.tri_vertices(t).map(|v| {
                let i = v.0 as usize;
                if remap[i] == u32::MAX {
                    remap[i] = out.vertices.len() as u32;
                    let d = self.vdata[i];
                    let [x, y] = spec.cell_center(c0 + d.col, r0 + d.row);
                    out.vertices.push([x, y, d.z]);
                    out.cells.push([c0 + d.col, r0 + d.row]);
                }
                remap[i]
            });
            out.triangles
                .push(if flip { [tri[0], tri[2], tri[1]] } else { tri });
        }
        (out, keep)
    }

    /// Calls `f(col, row, error)` once for every valid cell of the kept triangles.
    fn covered_cells(&self, keep: &[TriId], mut f: impl FnMut(i64, i64, f64)) {
        let n = self.cells.heights.len();
        let mut seen = vec![0u64; n.div_ceil(64)];
        for &t in keep {
            let ct = self.cell_triangle(t);
            let (gx, gy) = ct.plane();
            let a = ct.v[0];
            ct.rows(self.cells.all, |r, lo, hi| {
                for c in lo..=hi {
                    let i = (r * self.cells.stride + c) as usize;
                    let h: f64 = self.cells.heights[i].into();
                    if h.is_nan() || seen[i / 64] & (1 << (i % 64)) != 0 {
                        continue;
                    }
                    seen[i / 64] |= 1 << (i % 64);
                    let z = (ct.z[0] + gy * (r - a[1]) as f64) + gx * (c - a[0]) as f64;
                    f(c, r, (h - z).abs());
                }
            });
        }
    }

    /// Max and RMS error over the valid cells of the kept triangles, each cell counted once.
    pub(super) fn errors(&self, keep: &[TriId]) -> ErrorSums {
        let mut s = ErrorSums::default();
        self.covered_cells(keep, |_, _, e| s.add(e));
        s
    }

    /// A window's errors: the sums over its interior cells, and each border cell's error.
    pub(super) fn window_errors(&self, keep: &[TriId]) -> (ErrorSums, SideErrors) {
        let (w, h) = (self.cols as usize, self.rows as usize);
        let mut sides = SideErrors {
            top: vec![f64::NAN; w],
            bottom: vec![f64::NAN; w],
            left: vec![f64::NAN; h],
            right: vec![f64::NAN; h],
        };
        let inner = Clip {
            c0: 1,
            c1: self.cols - 2,
            r0: 1,
            r1: self.rows - 2,
        };
        let mut s = ErrorSums::default();
        self.covered_cells(keep, |c, r, e| {
            if inner.holds(c, r) {
                s.add(e);
                return;
            }
            let (c, r) = (c as usize, r as usize);
            if r == 0 {
                sides.top[c] = e;
            }
            if r == h - 1 {
                sides.bottom[c] = e;
            }
            if c == 0 {
                sides.left[r] = e;
            }
            if c == w - 1 {
                sides.right[r] = e;
            }
        });
        (s, sides)
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
