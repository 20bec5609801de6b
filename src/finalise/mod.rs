//! Streaming mode: triangles leave memory as soon as nothing later can change them
//! (Isenburg et al. 2006, "Streaming computation of Delaunay triangulations", done with a sweep).
//!
//! # When is a triangle final?
//!
//! Every point still to come lies on or above the sweep line, and the triangulated region is the
//! area under the advancing front. A triangle is final when its circumdisk lies strictly under the
//! front over the disk's x-span (only the part of the span inside the front's real x-range counts:
//! no point exists or will arrive left or right of it below the sweep line). Then:
//! * no later point can be inside the circle (later points are on or above the sweep line, the disk is
//!   strictly below the front, which never rises above the sweep line; a later point exactly on the
//!   circle counts as outside under the tie-breaking rule of [`crate::geom::predicates`]);
//! * no current point is inside either: the disk lies in the triangulated region, so every point in it
//!   is visible from the triangle, and the triangulation of the region is (constrained) Delaunay.
//!
//! "The circumcircle is entirely below the sweep line" is *not* enough: a circle can reach across a
//! basin of the front, above the triangulated region, to a vertex on the basin's other side.
//!
//! The disk is bounded conservatively ([`crate::geom::predicates::circumdisk_bounds`]): floating-point
//! error only ever enlarges it, so it can delay a finalisation, never hasten one.
//!
//! # Scheduling
//!
//! Each live triangle slot has exactly one entry in a bucket queue keyed by `y` (bucket width ≈ the
//! point spacing). A new triangle is checked a couple of buckets after it appears; when the sweep line
//! passes a bucket, its triangles are re-checked with their *current* vertices (flips change a slot's
//! triangle in place, so nothing is tracked at flip time) and either finalised or re-scheduled, at
//! their circle's top or after the basin that blocks them has had time to fill.
//!
//! # Output
//!
//! Finalised triangles and their vertices leave as [`Event`]s: a vertex is announced just before the
//! first triangle that uses it and released ([`Event::VertexDone`]) after its last one, so a consumer
//! also needs only bounded memory. The event order depends only on the input.

use crate::error::{Error, Result};
use crate::geom::predicates::{self, FIRST_REAL, is_artificial};
use crate::mesh::{Across, EdgeId, Mesh, TriId, VertexId};
use crate::sweep::Sweep;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// One point for the streaming sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamPoint {
    /// Position in the local frame.
    pub xy: [f64; 2],
    /// Height, carried along.
    pub z: f64,
    /// Index of the point in the input.
    pub index: u64,
    /// The breakline vertex this point is, or [`crate::sweep::NO_CONSTRAINT`].
    pub constraint: u32,
}

/// What the streaming sweep knows up front.
#[derive(Clone, Debug)]
pub struct StreamConfig {
    /// A sample of the points' x (any order, a few thousand values): spreads the front's
    /// search index over the data (speed only; empty is fine).
    pub x_sample: Vec<f64>,
    /// Extent of the data in the local frame: `[xmin, ymin, xmax, ymax]`.
    pub bounds: [f64; 4],
    /// Number of points expected (sizes the finalisation queue; need not be exact).
    pub expected_points: u64,
}

/// Output of the streaming sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A vertex; vertices are numbered 0, 1, 2, … in the order of these events.
    Vertex {
        /// Position in the local frame.
        xy: [f64; 2],
        /// Height.
        z: f64,
        /// Index of the input point.
        index: u64,
    },
    /// A final triangle, counter-clockwise, by vertex number.
    Triangle([u64; 3]),
    /// No later triangle uses this vertex.
    VertexDone(u64),
    /// Progress hint: later triangles normally lie at `y >=` this (local frame); see
    /// [`Sweep::emit_watermark`].
    Watermark(f64),
}

const NOT_OUT: u64 = u64::MAX;
const RING: usize = 1024;
/// Capacity a processed ring bucket keeps for reuse.
const RING_KEEP: usize = 256;
/// Buckets between a triangle's creation and its first check.
const FIRST_CHECK: u64 = 3;
/// Buckets between checks of a triangle that uses an artificial point or is too flat to bound.
const PARKED: u64 = 64;

/// Per-vertex data needed only when streaming.
#[derive(Debug, Clone, Default)]
pub(crate) struct VertexTable {
    pub z: Vec<f64>,
    pub index: Vec<u64>,
    pub out: Vec<u64>,
    /// Live triangles using the vertex.
    pub refs: Vec<u32>,
    free: Vec<u32>,
}

/// Peak sizes of the streaming sweep's working set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct StreamStats {
    /// Most triangles in memory at once (artificial ones included).
    pub peak_live_triangles: u64,
    /// Most vertices in memory at once.
    pub peak_live_vertices: u64,
    /// Most breakline segments pending at once.
    pub peak_pending_segments: u64,
    /// Finalisation checks that had to be repeated.
    pub rechecks: u64,
    /// Triangles emitted.
    pub triangles: u64,
    /// Vertices emitted.
    pub vertices: u64,
}

/// The finalisation queue and streaming state.
#[derive(Debug, Clone)]
pub(crate) struct Finalizer {
    pub vertices: VertexTable,
    pub free_triangles: Vec<u32>,
    ring: Vec<Vec<u32>>,
    /// Entries in `ring`.
    in_ring: usize,
    far: BinaryHeap<Reverse<(u64, u32)>>,
    /// First bucket not yet processed.
    cur: u64,
    /// Bucket of the sweep line.
    sweep_bucket: u64,
    base: f64,
    inv_h: f64,
    next_out: u64,
    events: Vec<Event>,
    last: [f64; 2],
    live_triangles: u64,
    live_vertices: u64,
    stats: StreamStats,
    /// Set once all points are in: everything left is final.
    ending: bool,
    /// Breaklines whose earlier end is swept and later end is not.
    pub pending: PendingSegments,
    /// The data's x range (watermark heuristic).
    x_range: (f64, f64),
    /// The bucket at which each triangle slot is due for its next check: queue entries for any
    /// other bucket are stale (the slot was rescheduled, flipped or refilled since) and skipped,
    /// so each slot has one live entry.
    due: Vec<u64>,
}

/// Pending breakline segments, indexed by x, to keep triangles they may still cross in memory.
#[derive(Debug, Clone, Default)]
pub(crate) struct PendingSegments {
    segs: Vec<Option<PendingSeg>>,
    /// Generation of each slot, bumped when its segment is removed: bucket entries of an earlier
    /// generation are stale (slots are reused) and pruned when met.
    gen_of: Vec<u32>,
    free: Vec<u32>,
    by_ends: std::collections::HashMap<(u32, u32), u32>,
    /// Slot and generation of the segments over each x range.
    buckets: Vec<Vec<(u32, u32)>>,
    x0: f64,
    inv_w: f64,
    live: usize,
    peak: usize,
}

#[derive(Debug, Clone, Copy)]
struct PendingSeg {
    a: [f64; 2],
    b: [f64; 2],
}

impl PendingSegments {
    fn new(x_range: (f64, f64)) -> Self {
        let n = 1024;
        let w = x_range.1 - x_range.0;
        PendingSegments {
            buckets: vec![Vec::new(); n],
            x0: x_range.0,
            inv_w: if w > 0.0 && w.is_finite() {
                n as f64 / w
            } else {
                0.0
            },
            ..Default::default()
        }
    }

    #[inline]
    fn bucket(&self, x: f64) -> usize {
        (((x - self.x0) * self.inv_w) as usize).min(self.buckets.len() - 1)
    }

    /// Adds the pending segment between constraint vertices `lo` and `hi`.
    pub fn add(&mut self, lo: u32, hi: u32, a: [f64; 2], b: [f64; 2]) {
        let id = match self.free.pop() {
            Some(id) => {
                self.segs[id as usize] = Some(PendingSeg { a, b });
                id
            }
            None => {
                self.segs.push(Some(PendingSeg { a, b }));
                self.gen_of.push(0);
                (self.segs.len() - 1) as u32
            }
        };
        self.by_ends.insert((lo, hi), id);
        let g = self.gen_of[id as usize];
        let (k0, k1) = (self.bucket(a[0].min(b[0])), self.bucket(a[0].max(b[0])));
        for k in k0..=k1 {
            self.buckets[k].push((id, g));
        }
        self.live += 1;
        self.peak = self.peak.max(self.live);
    }

    /// Removes the segment between `lo` and `hi` (inserted now).
    pub fn remove(&mut self, lo: u32, hi: u32) {
        if let Some(id) = self.by_ends.remove(&(lo, hi)) {
            self.segs[id as usize] = None;
            self.gen_of[id as usize] = self.gen_of[id as usize].wrapping_add(1);
            self.free.push(id);
            self.live -= 1;
        }
    }

    /// Could a pending segment pass within `r` of `c` (conservatively: floating-point error only
    /// makes this say yes more often)? Prunes dead entries from the buckets it scans.
    pub fn near(&mut self, c: [f64; 2], r: f64) -> bool {
        if self.live == 0 {
            return false;
        }
        let (k0, k1) = (self.bucket(c[0] - r), self.bucket(c[0] + r));
        for k in k0..=k1 {
            let mut i = 0;
            while i < self.buckets[k].len() {
                let (id, g) = self.buckets[k][i];
                match self.segs[id as usize] {
                    Some(s) if self.gen_of[id as usize] == g => {
                        if segment_within(s.a, s.b, c, r) {
                            return true;
                        }
                    }
                    _ => {
                        self.buckets[k].swap_remove(i);
                        continue;
                    }
                }
                i += 1;
            }
        }
        false
    }
}

/// Is the circumcircle of `a b c` narrower than `limit` in radius and inside the x range of the
/// data? (Floating point: a heuristic for watermarks only, never a topological decision.)
fn ordinary(a: [f64; 2], b: [f64; 2], c: [f64; 2], limit: f64, x_range: (f64, f64)) -> bool {
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    if d == 0.0 {
        return false;
    }
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    let r = (ux * ux + uy * uy).sqrt();
    let x = a[0] + ux;
    r < limit && x - r >= x_range.0 && x + r <= x_range.1
}

/// Is segment `a`–`b` within distance `r` of `c`? Floating point with a relative margin of 1e-9
/// of the magnitudes involved, so a true "yes" is never missed.
fn segment_within(a: [f64; 2], b: [f64; 2], c: [f64; 2], r: f64) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (px, py) = (c[0] - a[0], c[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        ((px * dx + py * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (px - t * dx, py - t * dy);
    let d = (qx * qx + qy * qy).sqrt();
    let scale = dx.abs() + dy.abs() + px.abs() + py.abs() + r;
    d <= r + 1e-9 * scale
}

impl Finalizer {
    fn new(cfg: &StreamConfig) -> Self {
        let [x0, y0, x1, y1] = cfg.bounds;
        let (w, h) = ((x1 - x0).max(0.0), (y1 - y0).max(0.0));
        let (x0, x1) = (x0, x1);
        let n = cfg.expected_points.max(1) as f64;
        // Typical spacing between points: sqrt(area / n), or the 1-D spacing for a thin strip.
        let area = w * h;
        let spacing = if area > 0.0 {
            (area / n).sqrt()
        } else {
            w.max(h) / n
        };
        let inv_h = if spacing > 0.0 && spacing.is_finite() {
            1.0 / spacing
        } else {
            1.0
        };
        Finalizer {
            vertices: VertexTable::default(),
            free_triangles: Vec::new(),
            ring: vec![Vec::new(); RING],
            in_ring: 0,
            far: BinaryHeap::new(),
            cur: 0,
            sweep_bucket: 0,
            base: if y0.is_finite() { y0 } else { 0.0 },
            inv_h,
            next_out: 0,
            events: Vec::new(),
            last: [f64::NEG_INFINITY; 2],
            live_triangles: 0,
            live_vertices: 0,
            stats: StreamStats::default(),
            ending: false,
            pending: PendingSegments::new((x0, x1)),
            x_range: (x0, x1),
            due: Vec::new(),
        }
    }

    #[inline(always)]
    fn bucket(&self, y: f64) -> u64 {
        let k = (y - self.base) * self.inv_h;
        // Saturating cast: negative and NaN go to 0, huge values to u64::MAX.
        k as u64
    }

    #[inline]
    fn schedule(&mut self, t: u32, k: u64) {
        let k = k.max(self.cur);
        let i = t as usize;
        if i >= self.due.len() {
            self.due.resize(i + 1, u64::MAX);
        }
        self.due[i] = k;
        self.push_entry(t, k);
    }

    /// Queues slot `t` for bucket `k` (already recorded in `due`).
    #[inline]
    fn push_entry(&mut self, t: u32, k: u64) {
        if k < self.cur + RING as u64 {
            self.ring[(k % RING as u64) as usize].push(t);
            self.in_ring += 1;
        } else {
            self.far.push(Reverse((k, t)));
        }
    }

    /// Vertex `v` is used by nothing any more: announce it (if it was ever output) and free its
    /// slot.
    pub fn release_vertex(&mut self, v: VertexId) {
        let i = v.0 as usize;
        if self.vertices.out[i] != NOT_OUT {
            self.events.push(Event::VertexDone(self.vertices.out[i]));
        }
        self.vertices.free.push(v.0);
        self.live_vertices -= 1;
    }

    /// Triangle slot `t` was changed in place (an edge flip): check it again soon, whatever it
    /// was waiting for before.
    #[inline(always)]
    pub fn changed(&mut self, t: u32) {
        self.schedule(t, self.sweep_bucket.saturating_add(FIRST_CHECK));
    }

    /// A triangle slot was (re)filled.
    #[inline(always)]
    pub fn created(&mut self, t: u32) {
        self.live_triangles += 1;
        if self.live_triangles > self.stats.peak_live_triangles {
            self.stats.peak_live_triangles = self.live_triangles;
        }
        self.schedule(t, self.sweep_bucket.saturating_add(FIRST_CHECK));
    }
}

impl Sweep {
    /// Starts a streaming sweep with its first point (see the [module docs](self)).
    pub fn streaming(first: StreamPoint, cfg: &StreamConfig) -> Self {
        let mut fin = Box::new(Finalizer::new(cfg));
        let v = &mut fin.vertices;
        for _ in 0..FIRST_REAL {
            v.z.push(f64::NAN);
            v.index.push(u64::MAX);
            v.out.push(NOT_OUT);
            v.refs.push(0);
        }
        v.z.push(first.z);
        v.index.push(first.index);
        v.out.push(NOT_OUT);
        v.refs.push(0);
        fin.last = first.xy;
        fin.live_vertices = 1;
        fin.stats.peak_live_vertices = 1;
        let pts = vec![[f64::NAN; 2], [f64::NAN; 2], first.xy];
        let [x0, _, x1, _] = cfg.bounds;
        let xmap = if cfg.x_sample.is_empty() {
            crate::sweep::front::XMap::linear(x0, x1)
        } else {
            crate::sweep::front::XMap::from_sample(cfg.x_sample.clone())
        };
        Self::start(pts, Mesh::with_capacity(1024), xmap, Some(fin))
    }

    /// Adds the next point of a streaming sweep.
    ///
    /// # Errors
    /// [`Error::OutOfOrder`] unless `p` comes strictly after the previous point in sweep order (by
    /// `y`, then `x`); duplicates must be merged before.
    ///
    /// # Panics
    /// If the sweep was not started with [`Sweep::streaming`].
    pub fn push(&mut self, p: StreamPoint) -> Result<()> {
        let fin = self.fin.as_mut().expect("push needs a streaming sweep");
        if predicates::sweep_cmp(fin.last, p.xy) != std::cmp::Ordering::Less {
            return Err(Error::OutOfOrder {
                index: self.stats.points,
            });
        }
        fin.last = p.xy;
        self.finalize_due(p.xy[1]);
        let fin = self.fin.as_mut().expect("streaming");
        let vt = &mut fin.vertices;
        let v = match vt.free.pop() {
            Some(v) => {
                let i = v as usize;
                self.pts[i] = p.xy;
                vt.z[i] = p.z;
                vt.index[i] = p.index;
                vt.out[i] = NOT_OUT;
                vt.refs[i] = 0;
                v
            }
            None => {
                self.pts.push(p.xy);
                vt.z.push(p.z);
                vt.index.push(p.index);
                vt.out.push(NOT_OUT);
                vt.refs.push(0);
                (self.pts.len() - 1) as u32
            }
        };
        fin.live_vertices += 1;
        fin.stats.peak_live_vertices = fin.stats.peak_live_vertices.max(fin.live_vertices);
        let n = self.insert(VertexId(v));
        if p.constraint != crate::sweep::NO_CONSTRAINT {
            self.constraint_vertex(VertexId(v), n, p.constraint);
        }
        Ok(())
    }

    /// Moves the events produced so far into `out` (appending).
    pub fn take_events(&mut self, out: &mut Vec<Event>) {
        if let Some(f) = self.fin.as_mut() {
            out.append(&mut f.events);
        }
    }

    /// Appends a watermark event: no live triangle of ordinary size has a vertex below the
    /// returned `y`, and every later point is above it. Triangles whose finalisation waits for
    /// the end or for a long time are left out — wider than 100 point spacings, or with a
    /// circumcircle wider than that or reaching beyond the data's x range (the triangles along the
    /// left and right sides of the convex hull, whose disks the front never covers), or with a
    /// vertex more than 100 spacings below the sweep line (the rim of an empty area such as a lake,
    /// which waits until the sweep has crossed it) — so they may arrive later below the watermark
    /// ("late"), which every sink handles. The watermark therefore trails the sweep line by at
    /// most 100 spacings, whatever the data's holes. O(live triangles); call it every few
    /// thousand points.
    pub fn emit_watermark(&mut self) -> f64 {
        let Some(fin) = self.fin.as_ref() else {
            return f64::NEG_INFINITY;
        };
        let wide = 100.0 / fin.inv_h;
        let mut w = fin.last[1];
        let stuck = fin.last[1] - wide;
        let o = &self.mesh.origin;
        for t in (0..o.len()).step_by(3) {
            let [a, b, c] = [o[t], o[t + 1], o[t + 2]];
            if a == super::mesh::DEAD
                || is_artificial(a.0)
                || is_artificial(b.0)
                || is_artificial(c.0)
            {
                continue;
            }
            let (pa, pb, pc) = (
                self.pts[a.0 as usize],
                self.pts[b.0 as usize],
                self.pts[c.0 as usize],
            );
            let low = pa[1].min(pb[1]).min(pc[1]);
            if low < w && low >= stuck {
                let span = pa[0].max(pb[0]).max(pc[0]) - pa[0].min(pb[0]).min(pc[0]);
                if span < wide && ordinary(pa, pb, pc, wide, fin.x_range) {
                    w = low;
                }
            }
        }
        let fin = self.fin.as_mut().expect("streaming");
        fin.events.push(Event::Watermark(w));
        w
    }

    /// Number of events waiting in [`Sweep::take_events`].
    pub fn pending_events(&self) -> usize {
        self.fin.as_ref().map_or(0, |f| f.events.len())
    }

    /// Working-set statistics of a streaming sweep.
    pub fn stream_stats(&self) -> StreamStats {
        self.fin.as_ref().map_or(StreamStats::default(), |f| {
            let mut s = f.stats;
            s.peak_pending_segments = f.pending.peak as u64;
            s
        })
    }

    /// Ends a streaming sweep: closes the hull and emits everything still in memory, in a fixed
    /// order (triangle slot order, then vertex slot order for the releases).
    pub fn finish_streaming(&mut self) {
        self.close_hull();
        self.fin.as_mut().expect("streaming").ending = true;
        let slots = self.mesh.triangle_count() as u32;
        for t in 0..slots {
            if self.mesh.is_live(TriId(t)) && !self.has_artificial(t) {
                self.finalize(t);
            }
        }
        let fin = self.fin.as_mut().expect("streaming");
        let vt = &fin.vertices;
        for v in FIRST_REAL as usize..vt.out.len() {
            if vt.out[v] != NOT_OUT && vt.refs[v] > 0 {
                fin.events.push(Event::VertexDone(vt.out[v]));
            }
        }
    }

    #[inline]
    fn has_artificial(&self, t: u32) -> bool {
        self.mesh
            .tri_vertices(TriId(t))
            .iter()
            .any(|v| is_artificial(v.0))
    }

    /// Processes every queue bucket the sweep line (now at `y`) has passed.
    fn finalize_due(&mut self, y: f64) {
        let ks = {
            let fin = self.fin.as_mut().expect("streaming");
            let ks = fin.bucket(y);
            fin.sweep_bucket = fin.sweep_bucket.max(ks);
            ks
        };
        loop {
            let fin = self.fin.as_mut().expect("streaming");
            if fin.cur >= ks {
                return;
            }
            if fin.in_ring == 0 {
                // Nothing in the ring: jump straight to the sweep line or the next far entry.
                let next_far = fin.far.peek().map_or(u64::MAX, |r| r.0.0);
                fin.cur = ks.min(next_far.max(fin.cur + 1));
                Self::pull_far(fin);
                continue;
            }
            let bucket = fin.cur;
            let slot = (bucket % RING as u64) as usize;
            fin.cur += 1;
            let mut list = std::mem::take(&mut fin.ring[slot]);
            fin.in_ring -= list.len();
            Self::pull_far(fin);
            for &t in &list {
                let fin = self.fin.as_ref().expect("streaming");
                if fin.due[t as usize] == bucket && self.mesh.is_live(TriId(t)) {
                    self.check_final(t, y, ks);
                }
            }
            list.clear();
            // Do not let each of the RING buckets keep the capacity of its busiest moment: that
            // would hold RING x (entries per bucket), which grows with the front.
            list.shrink_to(RING_KEEP);
            let fin = self.fin.as_mut().expect("streaming");
            if fin.ring[slot].is_empty() {
                fin.ring[slot] = list;
            }
        }
    }

    fn pull_far(fin: &mut Finalizer) {
        while let Some(&Reverse((k, t))) = fin.far.peek() {
            if k >= fin.cur + RING as u64 {
                break;
            }
            fin.far.pop();
            if fin.due[t as usize] == k {
                fin.push_entry(t, k);
            }
        }
    }

    /// Finalises triangle slot `t` if its circumdisk is under the front; otherwise re-schedules it.
    fn check_final(&mut self, t: u32, y: f64, ks: u64) {
        let [a, b, c] = self.mesh.tri_vertices(TriId(t));
        let fin = self.fin.as_mut().expect("streaming");
        if is_artificial(a.0) || is_artificial(b.0) || is_artificial(c.0) {
            fin.schedule(t, ks + PARKED);
            return;
        }
        let p = &self.pts;
        let Some(d) =
            predicates::circumdisk_bounds(p[a.0 as usize], p[b.0 as usize], p[c.0 as usize])
        else {
            fin.stats.rechecks += 1;
            fin.schedule(t, ks + PARKED);
            return;
        };
        if d.top >= y {
            fin.stats.rechecks += 1;
            let k = fin.bucket(d.top);
            fin.schedule(t, k.max(ks));
            return;
        }
        let low = self.front.min_y_over(d.x_min, d.x_max);
        let fin = self.fin.as_mut().expect("streaming");
        if d.top < low && fin.pending.near(d.center, d.radius) {
            // A breakline still to come may cross it.
            fin.stats.rechecks += 1;
            fin.schedule(t, ks + FIRST_CHECK);
        } else if d.top < low {
            self.finalize(t);
        } else {
            let fin = self.fin.as_mut().expect("streaming");
            fin.stats.rechecks += 1;
            // The front under the disk must rise by (top - low): wait about that long.
            let k = fin.bucket(y + (d.top - low));
            fin.schedule(t, k.max(ks + 1));
        }
    }

    /// Emits triangle slot `t` (and any vertex not yet emitted), releases what it no longer needs
    /// and frees the slot. Its neighbours see a hull edge from now on: the shared edge is a final
    /// Delaunay edge and will never be tested again.
    fn finalize(&mut self, t: u32) {
        for k in 0..3 {
            let e = EdgeId(3 * t + k);
            match self.mesh.across(e) {
                Across::Twin(f) => self.mesh.detach(f),
                // During the sweep a final triangle is never under the front; at the end the
                // front is the upper hull.
                Across::Front(_) => debug_assert!(self.fin.as_ref().is_some_and(|f| f.ending)),
                Across::Hull => {}
            }
        }
        let tri = self.mesh.tri_vertices(TriId(t));
        let fin = self.fin.as_mut().expect("streaming");
        let mut ids = [0u64; 3];
        for (k, v) in tri.iter().enumerate() {
            let i = v.0 as usize;
            let vt = &mut fin.vertices;
            if vt.out[i] == NOT_OUT {
                vt.out[i] = fin.next_out;
                fin.next_out += 1;
                fin.stats.vertices += 1;
                fin.events.push(Event::Vertex {
                    xy: self.pts[i],
                    z: vt.z[i],
                    index: vt.index[i],
                });
            }
            ids[k] = fin.vertices.out[i];
        }
        fin.events.push(Event::Triangle(ids));
        fin.stats.triangles += 1;
        for v in tri {
            let i = v.0 as usize;
            fin.vertices.refs[i] -= 1;
            if fin.vertices.refs[i] == 0 {
                fin.release_vertex(v);
            }
        }
        fin.live_triangles -= 1;
        self.mesh.free_triangle(TriId(t));
        fin.free_triangles.push(t);
    }
}
