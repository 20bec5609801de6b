//! Points to TIN within a vertical tolerance: greedy insertion over the points themselves
//! (`sweeptin thin`).
//!
//! The grid simplifier's method ([`super::simplify`], Garland & Heckbert's greedy insertion) with
//! lidar points in place of grid cells, by the classic *bucket* method: every point not yet in the
//! TIN is kept in the bucket of the triangle that contains it (a linked list through the points),
//! and each triangle's candidate is the point of largest vertical error in its bucket among those
//! not within the tolerance. The worst candidate of all (the grid simplifier's `TriangleQueue`,
//! the same indexed heap) is inserted with exact Delaunay insertion ([`Tin::insert_in_triangle`], Lawson
//! flips, the crate's tie rule); the points of the triangles the insertion created or flipped are
//! moved to the new triangles (located exactly with `orient`) and those triangles rescanned.
//! It stops when every point is within the tolerance. A redundancy pass
//! ([`ThinOptions::decimate`]) then removes every vertex whose removal keeps all points within
//! (Herva 2009, §5.6: both insertion and removal, exact).
//!
//! # Start, hull and breaklines
//! The start is the Delaunay triangulation of the points' convex hull vertices (exactly: a
//! monotone chain with `orient`) and the breakline vertices, with the breakline segments
//! inserted as constrained edges ([`Tin::insert_segment`]); so every point lies in the TIN and the
//! breaklines stay edges (a point inserted on one splits it into two constrained pieces). Hull and
//! breakline vertices are never removed.
//!
//! # "Within", exactly
//! A point is within when its vertical distance to the plane of the triangle containing it (in
//! the closed sense: on a shared edge both planes agree) is at most the tolerance, decided by
//! `VerticalPlane::check`: a certified floating-point bound, and exact `orient3d` signs when the
//! bound cannot decide. A point is accepted only when it provably lies within; a point closer than
//! one unit in the last place of its `z` to the tolerance may be treated as beyond (and kept),
//! never the reverse. Errors reported ([`ThinStats::max_error`], `rms_error`) are the
//! floating-point distances.
//!
//! # Memory: one global greedy insertion, bounded by the budget
//! Every point is held once with its bucket link ([`NODE_BYTES`]), plus the TIN of the kept
//! points with buckets, candidates and queue ([`KEPT_BYTES`] per kept point): 9 M ground points
//! and 1.25 M kept take about 0.8 GB. [`ThinOptions::mem`] stops a run whose kept TIN outgrows
//! the budget. A global run, rather than greedy insertion per tile of a fixed grid, because it keeps
//! the fewest points (no seam vertices shared by tiles, whose borders the greedy cannot place
//! well: a border of kept points is about as dense as the tolerance allows along every seam), it
//! is exact and seamless by construction, and its order (and so its output) depends only on the
//! point set. Its memory is linear in the points, with a small constant; the caller
//! (`pipeline::thin`) checks the points against the memory budget before reading, from the
//! files' headers, and refuses jobs that do not fit; the kept TIN is checked as it grows.
//! `sweeptin thin --tile` is the bounded alternative, at the price of a few more points:
//! `simplify::thin_tiles` runs this thinning per tile (`thin_in_domain`) from borders cut from
//! the exact TIN.
//!
//! # Determinism
//! Ties in the queue go to the highest triangle slot; slots, vertex ids and walks depend only on
//! the order of operations, which depends only on the input (points sorted by `y`, then `x`). The
//! output is the unique (constrained) Delaunay triangulation of the kept points under the crate's
//! tie rule.

use super::queue::TriangleQueue;
use super::refiner::error_key;
use crate::error::{Error, Result};
use crate::geom::predicates::{Orientation, Vertical, VerticalPlane, orient};
use crate::tin::{PointLocation, Tin, TriId, VertexId, in_closed_triangle as contains};
use rayon::prelude::*;

const NONE: u32 = u32::MAX;

/// How to thin.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ThinOptions {
    /// Every point ends within this vertical distance of the TIN (z units).
    pub max_error: f64,
    /// Afterwards, remove every vertex whose removal keeps all points within the bound.
    pub decimate: bool,
    /// Memory budget in bytes: the run stops with [`Error::Options`] when the points and the
    /// kept TIN would outgrow it (estimated: [`NODE_BYTES`] per point, [`KEPT_BYTES`] per kept
    /// point). `None`: no limit.
    pub mem: Option<u64>,
}

/// Bytes per input point held by the thinning (the point and its bucket link).
pub const NODE_BYTES: u64 = 32;

/// Bytes per kept point (TIN vertex and its two triangles' slots, buckets, candidates, queue,
/// with the growth slack of their vectors, and the output): measured, ARSO ground at 0.05 m
/// peaks at 836 MiB for 9.0 M points and 1.25 M kept.
pub const KEPT_BYTES: u64 = 448;

impl ThinOptions {
    /// Thin to `max_error`, then remove the redundant points.
    pub fn max_error(max_error: f64) -> Self {
        ThinOptions {
            max_error,
            decimate: true,
            mem: None,
        }
    }
}

/// What the thinning did and how good the result is.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ThinStats {
    /// Distinct input points (after filters and de-duplication).
    pub points: u64,
    /// Input points kept as TIN vertices.
    pub kept: u64,
    /// `kept / points`.
    pub kept_ratio: f64,
    /// Vertices of the TIN that are not input points: breakline vertices, and with
    /// `thin --tile` the border vertices on the grid lines.
    pub line_vertices: u64,
    /// Vertices in the output TIN (`kept + line_vertices`): what is written.
    pub vertices: u64,
    /// `vertices / points`: the output's size against the input's (above 1 when the vertices
    /// that are not points outnumber the points left out).
    pub vertex_ratio: f64,
    /// Triangles in the output TIN.
    pub triangles: u64,
    /// Constrained (breakline) segments inserted.
    pub segments: u64,
    /// Points inserted by the greedy pass (hull vertices not counted).
    pub insertions: u64,
    /// Points removed again by the redundancy pass.
    pub removed: u64,
    /// Edge flips.
    pub flips: u64,
    /// Largest vertical distance of a point from the TIN (kept points count 0).
    pub max_error: f64,
    /// Root-mean-square vertical distance over all points.
    pub rms_error: f64,
    /// Points decided by exact `orient3d` (the floating-point bound could not decide).
    pub exact_tests: u64,
    /// Wall-clock seconds of the thinning.
    pub seconds: f64,
}

/// A thinned TIN.
#[derive(Clone, Debug, Default)]
pub struct Thinned {
    /// Vertices `[x, y, z]`: kept input points and breakline vertices.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
    /// For each vertex: is it an input point (`false`: a breakline vertex)?
    pub is_point: Vec<bool>,
    /// Numbers.
    pub stats: ThinStats,
}

/// Breaklines for [`thin`]: vertices with heights and segments between them (a cleaned planar
/// graph: segments meet only at vertices).
#[derive(Clone, Copy, Debug, Default)]
pub struct ThinLines<'a> {
    /// Vertices `[x, y, z]`.
    pub vertices: &'a [[f64; 3]],
    /// Segments, as pairs of indices into `vertices`.
    pub segments: &'a [[u32; 2]],
}

/// Thins `points` (distinct `(x, y)` positions, none at a breakline vertex; any order, though
/// sorted by `y` then `x` is fastest; taken, so that their memory is given back once they are in
/// the buckets) into a TIN that keeps every point within
/// `options.max_error` vertically and has every breakline segment as edges.
///
/// # Errors
/// [`Error::Invalid`] for a negative or non-finite bound or a point at a breakline vertex;
/// [`Error::TooFewPoints`] / [`Error::AllCollinear`] when no triangle exists; breakline errors of
/// [`Tin::insert_segment`]; coordinate errors of the predicates' range checks.
pub fn thin(points: Vec<[f64; 3]>, lines: ThinLines<'_>, options: &ThinOptions) -> Result<Thinned> {
    let start = std::time::Instant::now();
    let tol = options.max_error;
    if !(tol >= 0.0 && tol.is_finite()) {
        return Err(Error::Invalid(format!(
            "--max-error {tol} must be a finite distance >= 0"
        )));
    }
    fits_ids(&points)?;
    let h = hull(&points);
    finish(Thinner::new(points, h, lines, tol)?, options, start)
}

/// Are there few enough points for the thinning's 32-bit ids?
fn fits_ids(points: &[[f64; 3]]) -> Result<()> {
    if points.len() as u64 >= u64::from(NONE) {
        return Err(Error::TooManyPoints {
            count: points.len() as u64,
            max: u64::from(NONE) - 1,
        });
    }
    Ok(())
}

/// Runs the greedy insertion of `t` (and the decimation when asked) and times the thinning from
/// `start`.
fn finish(mut t: Thinner, options: &ThinOptions, start: std::time::Instant) -> Result<Thinned> {
    t.run(options.mem.unwrap_or(u64::MAX))?;
    if options.decimate {
        t.decimate()?;
    }
    let mut out = t.finish()?;
    out.stats.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// Thins the points of one tile of `sweeptin thin --tile` (`pipeline::thin_tiles`): the start
/// is the Delaunay triangulation of `fixed` (the tile's border vertices, not input points) and
/// the points `hull` names (the other vertices of the tile's domain), all never removed; every
/// point must lie in it and none at a `fixed` position. Otherwise as [`thin()`].
///
/// # Errors
/// As [`thin()`]; [`Error::TooFewPoints`] / [`Error::AllCollinear`] when the start has no
/// triangle.
pub(crate) fn thin_in_domain(
    points: Vec<[f64; 3]>,
    hull: Vec<u32>,
    fixed: &[[f64; 3]],
    options: &ThinOptions,
) -> Result<Thinned> {
    let start = std::time::Instant::now();
    fits_ids(&points)?;
    let lines = ThinLines {
        vertices: fixed,
        segments: &[],
    };
    finish(
        Thinner::new(points, hull, lines, options.max_error)?,
        options,
        start,
    )
}

/// The exact convex hull of `points` (strictly convex vertices only), by Andrew's monotone chain
/// over the points in `(y, x)` order; indices into `points`.
pub(crate) fn hull(points: &[[f64; 3]]) -> Vec<u32> {
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    let cmp = |a: &u32, b: &u32| {
        let (p, q) = (points[*a as usize], points[*b as usize]);
        p[1].total_cmp(&q[1]).then(p[0].total_cmp(&q[0]))
    };
    if !order.is_sorted_by(|a, b| cmp(a, b).is_le()) {
        order.sort_by(cmp);
    }
    let xy = |i: u32| {
        let p = points[i as usize];
        [p[0], p[1]]
    };
    let chain = |iter: &mut dyn Iterator<Item = u32>| {
        let mut h: Vec<u32> = Vec::new();
        for i in iter {
            while h.len() >= 2
                && orient(xy(h[h.len() - 2]), xy(h[h.len() - 1]), xy(i))
                    != Orientation::CounterClockwise
            {
                h.pop();
            }
            h.push(i);
        }
        h.pop();
        h
    };
    let mut lower = chain(&mut order.iter().copied());
    let upper = chain(&mut order.iter().rev().copied());
    lower.extend(upper);
    lower
}

/// Per-triangle candidate: the worst point not within, and its error.
#[derive(Clone, Copy, Debug)]
struct Cand {
    point: u32,
    error: f64,
}

const NO_CAND: Cand = Cand {
    point: NONE,
    error: 0.0,
};

/// A point and its bucket link (the next point in the same triangle): one cache line holds
/// both, and the buckets are walked by these links.
#[derive(Clone, Copy, Debug)]
struct Node {
    p: [f64; 3],
    next: u32,
    /// Morton key of the position (see [`Thinner::new`]).
    key: u32,
}

/// `next` of a hull vertex while the nodes are reordered.
const HULL_MARK: u32 = NONE - 1;

/// Interleaves the bits of two 16-bit values (Morton / Z order).
fn morton(x: u32, y: u32) -> u32 {
    fn spread(mut v: u32) -> u32 {
        v &= 0xFFFF;
        v = (v | (v << 8)) & 0x00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    }
    spread(x) | (spread(y) << 1)
}

struct Thinner {
    tol: f64,
    tin: Tin,
    nodes: Vec<Node>,
    /// First point of each triangle slot's bucket.
    head: Vec<u32>,
    cand: Vec<Cand>,
    /// Input point of each vertex id ([`NONE`] for breakline vertices).
    vpoint: Vec<u32>,
    /// Vertices that are never removed (hull and breakline vertices).
    fixed: Vec<bool>,
    heap: TriangleQueue,
    touched: Vec<TriId>,
    gathered: Vec<(u32, [f64; 3])>,
    segments: u64,
    insertions: u64,
    removed: u64,
    exact_tests: u64,
}

impl Thinner {
    /// The start: the Delaunay triangulation of the points `h` names and the line vertices,
    /// with the line segments as constraints; every point bucketed.
    fn new(pts: Vec<[f64; 3]>, h: Vec<u32>, lines: ThinLines<'_>, tol: f64) -> Result<Self> {
        if h.len() < 3 && lines.vertices.is_empty() {
            // The core's own error: too few points, or all collinear.
            crate::triangulate(&pts, &crate::Options::default())?;
        }
        let mut start: Vec<[f64; 3]> = h.iter().map(|&i| pts[i as usize]).collect();
        start.extend_from_slice(lines.vertices);
        let tri = crate::triangulate(&start, &crate::Options::default())?;
        if tri.duplicates > 0 {
            return Err(Error::Invalid(
                "a point lies exactly at a breakline vertex (merge it with the line first)".into(),
            ));
        }
        let mut tin = Tin::from_triangulation(&tri)?;
        let mut vpoint = vec![NONE; tri.vertices.len()];
        let mut line_vertex = vec![VertexId(NONE); lines.vertices.len()];
        for (v, &i) in tri.input_index.iter().enumerate() {
            match h.get(i as usize) {
                Some(&p) => vpoint[v] = p,
                None => line_vertex[i as usize - h.len()] = VertexId(v as u32),
            }
        }
        for s in lines.segments {
            let (a, b) = (line_vertex[s[0] as usize], line_vertex[s[1] as usize]);
            if a.0 == NONE || b.0 == NONE {
                return Err(Error::Invalid("breakline segment with a bad vertex".into()));
            }
            tin.insert_segment(a, b)?;
        }
        let fixed = vec![true; vpoint.len()];
        let mut t = Thinner {
            tol,
            tin,
            nodes: Self::spatial_order(pts, &h),
            head: Vec::new(),
            cand: Vec::new(),
            vpoint,
            fixed,
            heap: TriangleQueue::default(),
            touched: Vec::new(),
            gathered: Vec::new(),
            segments: lines.segments.len() as u64,
            insertions: 0,
            removed: 0,
            exact_tests: 0,
        };
        t.bucket_all()?;
        Ok(t)
    }

    /// The points in Morton order of their position on a 2^16 × 2^16 lattice over their extent
    /// (ties by `y`, then `x`: a total order of distinct positions, so the order depends only on
    /// the point set), hull vertices marked. The buckets are linked lists through this array:
    /// in this order the points of a small triangle sit close together in memory, which makes
    /// walking them several times faster than in sweep order, where they are spread over every
    /// point of the same `y` range.
    fn spatial_order(pts: Vec<[f64; 3]>, hull: &[u32]) -> Vec<Node> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &pts {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let scale = [0, 1].map(|k| {
            let w = hi[k] - lo[k];
            if w > 0.0 { 65535.0 / w } else { 0.0 }
        });
        let mut nodes: Vec<Node> = pts
            .iter()
            .map(|&p| {
                let q = [0, 1].map(|k| (((p[k] - lo[k]) * scale[k]) as u32).min(65535));
                Node {
                    p,
                    next: NONE,
                    key: morton(q[0], q[1]),
                }
            })
            .collect();
        drop(pts);
        for &i in hull {
            nodes[i as usize].next = HULL_MARK;
        }
        nodes.par_sort_unstable_by(|a, b| {
            a.key
                .cmp(&b.key)
                .then(a.p[1].total_cmp(&b.p[1]))
                .then(a.p[0].total_cmp(&b.p[0]))
        });
        nodes
    }

    fn grow(&mut self) {
        let n = self.tin.triangle_slots();
        if self.head.len() < n {
            self.head.resize(n, NONE);
            self.cand.resize(n, NO_CAND);
        }
    }

    /// Puts every point that is not a vertex in the bucket of its triangle, and scans them all.
    fn bucket_all(&mut self) -> Result<()> {
        self.grow();
        // Walk locations from the last point's triangle; the buckets are filled in reverse so
        // that each list ends in input order (any order would do; this one is fixed).
        for i in (0..self.nodes.len() as u32).rev() {
            if self.nodes[i as usize].next == HULL_MARK {
                self.nodes[i as usize].next = NONE;
                let p = self.nodes[i as usize].p;
                match self.tin.locate([p[0], p[1]]) {
                    PointLocation::OnVertex(v) => self.vpoint[v.0 as usize] = i,
                    _ => return Err(Error::Internal("thin: a hull vertex got lost".into())),
                }
                continue;
            }
            let p = self.nodes[i as usize].p;
            let t = match self.tin.locate([p[0], p[1]]) {
                PointLocation::Inside(t) => t,
                PointLocation::OnEdge(e) => e.tri(),
                PointLocation::OnVertex(_) => {
                    return Err(Error::Invalid(format!(
                        "point {i} ({}, {}) lies exactly at a breakline vertex",
                        p[0], p[1]
                    )));
                }
                PointLocation::Outside(_) => {
                    return Err(Error::Internal(format!(
                        "thin: point {i} outside the hull of the points"
                    )));
                }
            };
            self.nodes[i as usize].next = self.head[t.0 as usize];
            self.head[t.0 as usize] = i;
        }
        let all: Vec<TriId> = self.tin.triangles().collect();
        for t in all {
            self.rescan(t);
        }
        Ok(())
    }

    fn plane(&self, t: TriId) -> VerticalPlane {
        let [a, b, c] = self.tin.tri_vertices(t).map(|v| self.tin.point(v));
        VerticalPlane::new(a, b, c)
    }

    /// Recomputes the candidate of `t` from its bucket and queues it.
    fn rescan(&mut self, t: TriId) {
        let plane = self.plane(t);
        let mut c = NO_CAND;
        let mut i = self.head[t.0 as usize];
        while i != NONE {
            let n = self.nodes[i as usize];
            let v = self.check(&plane, n.p);
            if !v.within && (c.point == NONE || v.error > c.error) {
                c = Cand {
                    point: i,
                    error: v.error,
                };
            }
            i = n.next;
        }
        self.cand[t.0 as usize] = c;
        self.heap
            .set(t.0, (c.point != NONE).then(|| error_key(c.error)));
    }

    fn run(&mut self, mem: u64) -> Result<()> {
        self.tin.record_touched(true);
        // Pure insertion: no vertex → edge map upkeep until the redundancy pass.
        self.tin.set_vertex_tracking(false);
        while let Some(t) = self.heap.pop() {
            if self.insertions.is_multiple_of(1 << 14) {
                let need = NODE_BYTES * self.nodes.len() as u64
                    + KEPT_BYTES * self.tin.vertex_slots() as u64;
                if need > mem {
                    return Err(Error::Options(format!(
                        "thin: {} points kept so far for {} points need about {} MiB, more \
                         than --mem {} MiB: raise --mem, give a larger --max-error, or thin \
                         smaller areas with --bbox",
                        self.tin.vertex_slots(),
                        self.nodes.len(),
                        need >> 20,
                        mem >> 20
                    )));
                }
            }
            let t = TriId(t);
            let q = self.cand[t.0 as usize].point;
            let v = self.tin.insert_in_triangle(t, self.nodes[q as usize].p)?;
            self.register(v, q);
            self.insertions += 1;
            self.redistribute(Some(q))?;
        }
        Ok(())
    }

    fn register(&mut self, v: VertexId, q: u32) {
        let i = v.0 as usize;
        if self.vpoint.len() <= i {
            self.vpoint.resize(i + 1, NONE);
            self.fixed.resize(i + 1, false);
        }
        self.vpoint[i] = q;
        self.fixed[i] = false;
    }

    /// Moves the points of the triangles touched since the last call (except `skip`, just
    /// inserted) into the live ones among them, and rescans those.
    fn redistribute(&mut self, skip: Option<u32>) -> Result<()> {
        self.grow();
        let mut touched = std::mem::take(&mut self.touched);
        touched.clear();
        self.tin.take_touched(&mut touched);
        touched.sort_unstable();
        touched.dedup();
        let mut gathered = std::mem::take(&mut self.gathered);
        for &t in &touched {
            let mut i = std::mem::replace(&mut self.head[t.0 as usize], NONE);
            while i != NONE {
                let n = self.nodes[i as usize];
                if Some(i) != skip {
                    gathered.push((i, n.p));
                }
                i = n.next;
            }
        }
        touched.retain(|&t| self.tin.is_live(t));
        self.place(&gathered, &touched)?;
        gathered.clear();
        self.gathered = gathered;
        self.touched = touched;
        Ok(())
    }

    /// Puts each of `points` in the bucket of the first of `tris` that contains it (closed),
    /// and rescans `tris` on the way (their buckets must have been emptied first). Returns whether
    /// every point is within the bound.
    fn place(&mut self, points: &[(u32, [f64; 3])], tris: &[TriId]) -> Result<bool> {
        let geo: Vec<([[f64; 2]; 3], VerticalPlane)> = tris
            .iter()
            .map(|&t| {
                let p = self.tin.tri_vertices(t).map(|v| self.tin.point(v));
                (
                    p.map(|q| [q[0], q[1]]),
                    VerticalPlane::new(p[0], p[1], p[2]),
                )
            })
            .collect();
        for &t in tris {
            self.cand[t.0 as usize] = NO_CAND;
        }
        let mut last = 0;
        for &(i, p) in points {
            let q = [p[0], p[1]];
            let k = (0..tris.len())
                .map(|k| (k + last) % tris.len())
                .find(|&k| contains(&geo[k].0, q))
                .ok_or_else(|| {
                    Error::Internal(format!(
                        "thin: point {i} ({}, {}) left the triangles that replaced its own",
                        p[0], p[1]
                    ))
                })?;
            last = k;
            let t = tris[k].0 as usize;
            self.nodes[i as usize].next = self.head[t];
            self.head[t] = i;
            let v = self.check(&geo[k].1, p);
            let c = &mut self.cand[t];
            if !v.within && (c.point == NONE || v.error > c.error) {
                *c = Cand {
                    point: i,
                    error: v.error,
                };
            }
        }
        let mut ok = true;
        for &t in tris {
            let c = self.cand[t.0 as usize];
            ok &= c.point == NONE;
            self.heap
                .set(t.0, (c.point != NONE).then(|| error_key(c.error)));
        }
        Ok(ok)
    }

    #[inline]
    fn check(&mut self, plane: &VerticalPlane, p: [f64; 3]) -> Vertical {
        let v = plane.check(p, self.tol);
        self.exact_tests += u64::from(v.exact);
        v
    }

    /// The redundancy pass: removes, in vertex order, every vertex (not on the hull or a
    /// breakline) whose removal keeps every point within the bound.
    fn decimate(&mut self) -> Result<()> {
        self.tin.set_vertex_tracking(true);
        self.tin.record_touched(false);
        let mut points: Vec<(u32, [f64; 3])> = Vec::new();
        let mut tris: Vec<[VertexId; 3]> = Vec::new();
        for v in 0..self.vpoint.len() as u32 {
            let v = VertexId(v);
            if self.fixed[v.0 as usize] || !self.tin.contains_vertex(v) {
                continue;
            }
            // The points of the star, and the vertex's own point.
            points.clear();
            let own = self.vpoint[v.0 as usize];
            points.push((own, self.tin.point(v)));
            let spokes = self.tin.out_edges(v);
            if self.tin.twin(spokes[0]).is_none() {
                self.fixed[v.0 as usize] = true;
                continue;
            }
            for &e in &spokes {
                let mut i = self.head[e.tri().0 as usize];
                while i != NONE {
                    let n = self.nodes[i as usize];
                    points.push((i, n.p));
                    i = n.next;
                }
            }
            // Preview: the triangles that would fill the hole.
            tris.clear();
            if !matches!(
                self.tin.removal_preview_with(v, |t| {
                    tris.push(t);
                    true
                }),
                Ok(true)
            ) {
                continue;
            }
            if !self.preview_ok(&points, &tris) {
                continue;
            }
            // Remove it for real and check in the real triangles (near breaklines the hole's
            // triangulation may differ from the preview); put it back if any point fails.
            for &e in &spokes {
                self.head[e.tri().0 as usize] = NONE;
            }
            self.tin.record_touched(true);
            self.tin.remove(v)?;
            self.grow();
            let mut fresh = Vec::new();
            self.tin.take_touched(&mut fresh);
            fresh.sort_unstable();
            fresh.dedup();
            fresh.retain(|&t| self.tin.is_live(t));
            if self.place(&points, &fresh)? {
                self.removed += 1;
                self.vpoint[v.0 as usize] = NONE;
            } else {
                // The constrained Delaunay triangulation of the same points is unique: restoring
                // the vertex restores the triangles its points were within.
                self.tin.record_touched(false);
                self.tin.record_touched(true);
                self.tin.restore(v)?;
                self.redistribute(Some(own))?;
            }
            self.tin.record_touched(false);
        }
        Ok(())
    }

    fn preview_ok(&mut self, points: &[(u32, [f64; 3])], tris: &[[VertexId; 3]]) -> bool {
        let geo: Vec<([[f64; 2]; 3], VerticalPlane)> = tris
            .iter()
            .map(|t| {
                let p = t.map(|v| self.tin.point(v));
                (
                    p.map(|q| [q[0], q[1]]),
                    VerticalPlane::new(p[0], p[1], p[2]),
                )
            })
            .collect();
        let mut last = 0;
        for &(_, p) in points {
            let Some(k) = (0..geo.len())
                .map(|k| (k + last) % geo.len())
                .find(|&k| contains(&geo[k].0, [p[0], p[1]]))
            else {
                return false;
            };
            last = k;
            let c = geo[k].1.check(p, self.tol);
            self.exact_tests += u64::from(c.exact);
            if !c.within {
                return false;
            }
        }
        true
    }

    /// The output and its statistics; every point is checked once more against its triangle.
    fn finish(self) -> Result<Thinned> {
        let (mut max, mut sum, mut beyond) = (0.0f64, 0.0f64, 0u64);
        let tris: Vec<TriId> = self.tin.triangles().collect();
        for &t in &tris {
            let plane = self.plane(t);
            let mut i = self.head[t.0 as usize];
            while i != NONE {
                let n = self.nodes[i as usize];
                let c = plane.check(n.p, self.tol);
                if !c.within {
                    beyond += 1;
                }
                max = max.max(c.error);
                sum += c.error * c.error;
                i = n.next;
            }
        }
        if beyond > 0 {
            return Err(Error::Internal(format!(
                "thin: {beyond} points beyond the bound after thinning"
            )));
        }
        let mut remap = vec![NONE; self.tin.vertex_slots()];
        let mut out = Thinned::default();
        for v in self.tin.vertices() {
            remap[v.0 as usize] = out.vertices.len() as u32;
            out.vertices.push(self.tin.point(v));
            out.is_point.push(self.vpoint[v.0 as usize] != NONE);
        }
        out.triangles = tris
            .iter()
            .map(|&t| self.tin.tri_vertices(t).map(|v| remap[v.0 as usize]))
            .collect();
        let n = self.nodes.len() as u64;
        let kept = out.is_point.iter().filter(|&&p| p).count() as u64;
        out.stats = ThinStats {
            points: n,
            kept,
            kept_ratio: kept as f64 / n.max(1) as f64,
            line_vertices: out.vertices.len() as u64 - kept,
            vertices: out.vertices.len() as u64,
            vertex_ratio: out.vertices.len() as f64 / n.max(1) as f64,
            triangles: out.triangles.len() as u64,
            segments: self.segments,
            insertions: self.insertions,
            removed: self.removed,
            flips: self.tin.flips(),
            max_error: max,
            rms_error: (sum / n.max(1) as f64).sqrt(),
            exact_tests: self.exact_tests,
            seconds: 0.0,
        };
        Ok(out)
    }
}
