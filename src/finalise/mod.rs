//! The streaming sweep ([`StreamingSweep`]): triangles leave memory as soon as nothing later can
//! change them (Isenburg et al. 2006, "Streaming computation of Delaunay triangulations", done
//! with a sweep).
//!
//! A [`StreamingSweep`] owns the sweep core ([`crate::sweep::Sweep`]) monomorphised over its
//! finaliser: the core calls the finaliser's hooks ([`crate::sweep::Mode`]) whenever it creates,
//! flips or removes a triangle, and the streaming sweep drives the finalisation queue between
//! points.
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
//! passes a bucket, its triangles are re-checked with their *current* vertices (a flip changes two
//! slots' triangles in place and re-schedules both a few buckets ahead; queue entries for any other
//! bucket are stale and skipped) and either finalised or re-scheduled, at their circle's top or
//! after the basin that blocks them has had time to fill. A slot re-scheduled for the bucket it
//! already waits for queues nothing new (one insertion can flip the same slot thousands of times).
//! A triangle the front has blocked more than a few times in a row waits twice as long each time
//! after: the front under it may never rise (the upper side of a diagonal strip), and checking it
//! every few buckets until the end made such data quadratic.
//!
//! # Output
//!
//! Finalised triangles and their vertices leave as [`Event`]s: a vertex is announced just before the
//! first triangle that uses it and released ([`Event::VertexDone`]) after its last one, so a consumer
//! also needs only bounded memory. The event order depends only on the input.

mod check;
mod end;
mod far;
mod pending;
mod ring;
mod tables;
mod watermark;

use crate::error::{Error, Result};
use crate::geom::predicates::{self, FIRST_REAL};
use crate::mesh::{Mesh, TriId, VertexId};
use crate::sort::mmap::SpillVec;
use crate::sweep::front::XMap;
use crate::sweep::hooks::sealed::Hooks;
use crate::sweep::{ConstraintGraph, ConstraintStats, Sweep, SweepStats};
use pending::PendingSegments;
use tables::{Spill, VertexTable};
pub use tables::SpillPolicy;
use far::FarQueue;
use ring::{NearRing, RING};

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
    /// Where the tables of held triangles go past a threshold (`None`: they stay on the heap).
    pub spill: Option<SpillPolicy>,
    /// Precede every [`Event::Triangle`] with its three corners' positions ([`Event::Corner`]),
    /// so a consumer that needs positions holds no table of the vertices still in use (on a
    /// ring of points nearly all of them are, to the end).
    pub corners: bool,
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
    /// A corner of the next [`Event::Triangle`], in its order (three of them before each
    /// triangle, only when [`StreamConfig::corners`] asks for them).
    Corner {
        /// Position in the local frame.
        xy: [f64; 2],
        /// Height.
        z: f64,
    },
    /// A final triangle, counter-clockwise, by vertex number.
    Triangle([u64; 3]),
    /// No later triangle uses this vertex.
    VertexDone(u64),
    /// Progress hint: later triangles normally lie at `y >=` this (local frame); see
    /// [`StreamingSweep::emit_watermark`].
    Watermark(f64),
}

const NOT_OUT: u64 = u64::MAX;
/// Buckets between a triangle's creation and its first check.
const FIRST_CHECK: u64 = 3;
/// Checks a triangle may fail on the front before the waits between its checks double.
const PATIENT_CHECKS: u8 = 4;
/// Buckets between checks of a triangle that uses an artificial point or is too flat to bound.
const PARKED: u64 = 64;
/// Front nodes scanned under a disk before a vertex of its triangle on the front is looked for.
const SHORT_SCAN: usize = 64;
/// Fewest points between two estimates of the bucket height (see [`Finalizer::adapt`]).
const WINDOW: u64 = 1024;
/// Rows of points the front holds, about (measured on uniform data: its nodes zigzag over two
/// rows below the sweep line).
const FRONT_ROWS: f64 = 2.0;
/// Most buckets the whole `y` range of the data may span (bucket numbers stay far from overflow).
const MAX_BUCKETS: f64 = (1u64 << 40) as f64;

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
    /// Most entries in the finalisation queue at once, stale ones (for a bucket the triangle no
    /// longer waits for) included.
    pub peak_queued: u64,
    /// Triangles emitted.
    pub triangles: u64,
    /// Vertices emitted.
    pub vertices: u64,
    /// Most bytes of the held triangles' tables in temporary files at once (0: they stayed on
    /// the heap: they move past a quarter of `--mem`).
    pub peak_spilled_bytes: u64,
    /// Times their pages were dropped from the resident set.
    pub spill_releases: u64,
    /// Front nodes scanned under circumdisks to decide whether their triangles are final.
    pub front_scans: u64,
}

/// The finalisation queue and streaming state: the [`crate::sweep::Mode`] of the core inside a
/// [`StreamingSweep`].
#[derive(Debug, Clone)]
pub(crate) struct Finalizer {
    vertices: VertexTable,
    free_triangles: Vec<u32>,
    /// The queue's buckets from `cur` on, [`RING`] of them; later ones wait in `far`.
    ring: NearRing,
    /// The entries of the bucket being processed, a block at a time.
    batch: Vec<u32>,
    far: FarQueue,
    /// First bucket not yet processed.
    cur: u64,
    /// Bucket of the sweep line.
    sweep_bucket: u64,
    /// Buckets are `k_ref + (y − base) · inv_h` at and above `base`: the bucket height `1 /
    /// inv_h` follows the rows of points the sweep line meets ([`Finalizer::adapt`]).
    base: f64,
    k_ref: u64,
    inv_h: f64,
    /// Largest `inv_h` allowed ([`MAX_BUCKETS`] over the data's `y` range).
    max_inv_h: f64,
    /// Points pushed so far, and the count and sweep-line `y` when the current estimate window
    /// of the bucket height began.
    points: u64,
    window_points: u64,
    window_y: f64,
    next_out: u64,
    events: Vec<Event>,
    last: [f64; 2],
    live_triangles: u64,
    live_vertices: u64,
    stats: StreamStats,
    /// Set once all points are in: everything left is final.
    ending: bool,
    /// Send each triangle's corners before it ([`StreamConfig::corners`]).
    corners: bool,
    /// Breaklines whose earlier end is swept and later end is not.
    pending: PendingSegments,
    /// The data's x range (watermark heuristic).
    x_range: (f64, f64),
    /// The bucket at which each triangle slot is due for its next check: queue entries for any
    /// other bucket are stale (the slot was rescheduled, flipped or refilled since) and skipped,
    /// so each slot has one live entry.
    due: SpillVec<u64>,
    /// How many times in a row each slot's triangle was found blocked by the front since it was
    /// made or changed (saturating): past `PATIENT_CHECKS` its waits double.
    blocked: SpillVec<u8>,
    /// Where the tables go when they outgrow their share of `--mem`.
    spill: Spill,
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
        let max_inv_h = if h > 0.0 && h.is_finite() {
            MAX_BUCKETS / h
        } else {
            MAX_BUCKETS
        };
        let inv_h = if spacing > 0.0 && spacing.is_finite() {
            (1.0 / spacing).min(max_inv_h)
        } else {
            1.0
        };
        Finalizer {
            vertices: VertexTable::default(),
            free_triangles: Vec::new(),
            ring: NearRing::default(),
            batch: Vec::new(),
            far: FarQueue::default(),
            cur: 0,
            sweep_bucket: 0,
            base: if y0.is_finite() { y0 } else { 0.0 },
            k_ref: 0,
            inv_h,
            max_inv_h,
            points: 0,
            window_points: 0,
            window_y: f64::NAN,
            next_out: 0,
            events: Vec::new(),
            last: [f64::NEG_INFINITY; 2],
            live_triangles: 0,
            live_vertices: 0,
            stats: StreamStats::default(),
            ending: false,
            corners: cfg.corners,
            pending: PendingSegments::new((x0, x1)),
            x_range: (x0, x1),
            due: SpillVec::default(),
            blocked: SpillVec::default(),
            spill: Spill::new(cfg.spill.clone()),
        }
    }

    #[inline(always)]
    fn bucket(&self, y: f64) -> u64 {
        let k = (y - self.base) * self.inv_h;
        // Saturating cast: negative and NaN go to 0, huge values to u64::MAX.
        self.k_ref.saturating_add(k as u64)
    }

    /// Counts a point pushed at sweep-line height `y` with `front` nodes on the front, and
    /// re-estimates the bucket height once a window of points has passed.
    ///
    /// A bucket should be about one row of points (the height the sweep line climbs while half
    /// as many points as the front has nodes arrive, [`FRONT_ROWS`]): a triangle is first checked a few rows after
    /// it appears and re-checked when the sweep line reaches its circle's top. The height cannot
    /// be known up front: the bounding box of data with a far outlier (or Kuzmin's heavy tail)
    /// is a million times taller than its dense part, and buckets from the box then hold the
    /// whole data set, so nothing is checked, let alone finalised, before the end (every
    /// triangle held). So the height is measured: over each window of at least [`WINDOW`] and
    /// two fronts' worth of points, the climb per row. The bucket numbers stay
    /// continuous and increasing (a new scale starts at the current sweep line), so a change
    /// only moves when triangles are checked, never what is decided; and the windows depend
    /// only on the input, so the output does too.
    #[inline]
    fn adapt(&mut self, y: f64, front: usize) {
        self.points += 1;
        let n = self.points - self.window_points;
        if n < WINDOW.max(2 * front as u64) {
            return;
        }
        let climb = y - self.window_y;
        if climb > 0.0 && climb.is_finite() {
            let row = climb * front.max(1) as f64 / (FRONT_ROWS * n as f64);
            let inv = (1.0 / row).min(self.max_inv_h);
            if inv.is_finite() && inv > 0.0 {
                self.k_ref = self.bucket(y);
                self.base = y;
                self.inv_h = inv;
            }
        }
        self.window_points = self.points;
        self.window_y = y;
    }

    #[inline]
    fn schedule(&mut self, t: u32, k: u64) {
        let k = k.max(self.cur);
        let i = t as usize;
        if i >= self.due.len() {
            self.due.resize(i + 1, u64::MAX);
            self.blocked.resize(i + 1, 0);
        }
        if self.due[i] == k {
            // Its entry for bucket `k` is still queued (an entry is consumed only once `cur`
            // has passed its bucket, and `k >= cur`): a second one would only be skipped later.
            // A slot flipped again and again while one point is inserted would otherwise queue
            // one entry a flip (two long rows far apart: O(n^2) entries).
            return;
        }
        self.due[i] = k;
        self.push_entry(t, k);
    }

    /// Queues slot `t` for bucket `k` (already recorded in `due`).
    #[inline]
    fn push_entry(&mut self, t: u32, k: u64) {
        if k < self.cur + RING as u64 {
            self.ring.push(k, t);
        } else {
            self.far.push(k, t);
        }
    }

    /// Vertex `v` is used by nothing any more: announce it (if it was ever output) and free its
    /// slot.
    fn release_vertex(&mut self, v: VertexId) {
        let i = v.0 as usize;
        if self.vertices.out[i] != NOT_OUT {
            self.events.push(Event::VertexDone(self.vertices.out[i]));
        }
        if !self.ending {
            self.vertices.free.push(v.0);
        }
        self.live_vertices -= 1;
    }

    /// Triangle slot `t` was changed in place (an edge flip): check it again soon, whatever it
    /// was waiting for before.
    #[inline(always)]
    fn changed(&mut self, t: u32) {
        if self.ending {
            // Every triangle left is emitted in slot order: a queue entry would never be read
            // (the closing of a ring's hull changes millions of slots).
            return;
        }
        self.schedule(t, self.sweep_bucket.saturating_add(FIRST_CHECK));
        self.blocked[t as usize] = 0;
    }

    /// A triangle slot was (re)filled.
    #[inline(always)]
    fn created_slot(&mut self, t: u32) {
        self.live_triangles += 1;
        if self.live_triangles > self.stats.peak_live_triangles {
            self.stats.peak_live_triangles = self.live_triangles;
        }
        if self.ending {
            return;
        }
        self.schedule(t, self.sweep_bucket.saturating_add(FIRST_CHECK));
        self.blocked[t as usize] = 0;
    }

    /// Moves the far-queue entries that now fall within the ring into it.
    fn pull_far(&mut self) {
        while let Some((k, t)) = self.far.peek() {
            if k >= self.cur + RING as u64 {
                break;
            }
            self.far.pop();
            if self.due[t as usize] == k {
                self.push_entry(t, k);
            }
            // Each pop walks a path of the heap (a page a level past the first few) and reads
            // a row of `due`: on a ring of points millions of entries come in at once, from
            // tables spilled to files, so look at the resident memory on the way.
            if self.spill.touched(tables::PAGES_A_PULL) {
                self.release_spilled();
            }
        }
    }

    /// Emits the final triangle that was in slot `t` (vertices `tri`, positions in `pts`, and any
    /// vertex not yet emitted), releases the vertices it no longer needs and recycles the slot.
    fn emit(&mut self, t: u32, tri: [VertexId; 3], pts: &[[f64; 2]]) {
        let mut ids = [0u64; 3];
        for (k, v) in tri.iter().enumerate() {
            let i = v.0 as usize;
            let vt = &mut self.vertices;
            if vt.out[i] == NOT_OUT {
                vt.out[i] = self.next_out;
                self.next_out += 1;
                self.stats.vertices += 1;
                self.events.push(Event::Vertex {
                    xy: pts[i],
                    z: vt.z[i],
                    index: vt.index[i],
                });
            }
            ids[k] = self.vertices.out[i];
        }
        if self.corners {
            for v in tri {
                let i = v.0 as usize;
                let z = self.vertices.z[i];
                self.events.push(Event::Corner { xy: pts[i], z });
            }
        }
        self.events.push(Event::Triangle(ids));
        self.stats.triangles += 1;
        for v in tri {
            let i = v.0 as usize;
            self.vertices.refs[i] -= 1;
            if self.vertices.refs[i] == 0 {
                self.release_vertex(v);
            }
        }
        self.live_triangles -= 1;
        // At the end no slot is used again: a free list of every held triangle would be the
        // only table left on the heap.
        if !self.ending {
            self.free_triangles.push(t);
        }
    }
}

impl Hooks for Finalizer {
    #[cfg(any(test, feature = "dev"))]
    const FINALISES: bool = true;

    #[inline(always)]
    fn free_slot(&mut self) -> Option<TriId> {
        self.free_triangles.pop().map(TriId)
    }

    #[inline(always)]
    fn created(&mut self, mesh: &Mesh, t: TriId) {
        for v in mesh.tri_vertices(t) {
            self.vertices.refs[v.0 as usize] += 1;
        }
        self.created_slot(t.0);
    }

    #[inline(always)]
    fn flipped(&mut self, ta: TriId, tb: TriId, gone: [VertexId; 2], new: [VertexId; 2]) {
        let r = &mut self.vertices.refs;
        r[gone[0].0 as usize] -= 1;
        r[gone[1].0 as usize] -= 1;
        r[new[0].0 as usize] += 1;
        r[new[1].0 as usize] += 1;
        self.changed(ta.0);
        self.changed(tb.0);
    }

    fn cavity_removed(&mut self, mesh: &Mesh, dead: &[u32]) {
        for &t in dead {
            for v in mesh.tri_vertices(TriId(t)) {
                self.vertices.refs[v.0 as usize] -= 1;
            }
        }
    }

    fn cavity_filled(&mut self, tri: [VertexId; 3]) {
        for v in tri {
            self.vertices.refs[v.0 as usize] += 1;
        }
    }

    /// Keeps `v` alive and blocks the finalisation of triangles near the segment.
    fn segment_pending(&mut self, v: VertexId, lo: u32, hi: u32, a: [f64; 2], b: [f64; 2]) {
        self.vertices.refs[v.0 as usize] += 1;
        self.pending.add(lo, hi, a, b);
    }

    #[inline(always)]
    fn spill_due(&mut self) -> bool {
        self.spill.touched(tables::PAGES_A_STEP)
    }

    fn release_spilled(&mut self) {
        self.due.release();
        self.blocked.release();
        self.far.table().release();
        self.ring.table().release();
        let vt = &mut self.vertices;
        vt.z.release();
        vt.index.release();
        vt.out.release();
        vt.refs.release();
        // The growth counts from the resident memory without these pages.
        self.spill.released();
    }

    fn segment_done(&mut self, v: VertexId, lo: u32, hi: u32) {
        self.pending.remove(lo, hi);
        let r = &mut self.vertices.refs[v.0 as usize];
        *r -= 1;
        if *r == 0 {
            self.release_vertex(v);
        }
    }
}

/// A streaming sweep: points are pushed one at a time in sweep order and triangles leave memory,
/// as [`Event`]s, as soon as nothing later can change them (see the [module docs](self)).
///
/// [`StreamingSweep::new`] → [`StreamingSweep::push`] … → [`StreamingSweep::finish`], with
/// [`StreamingSweep::take_events`] whenever convenient.
#[derive(Debug, Clone)]
pub struct StreamingSweep {
    /// The core, whose mode is the finaliser.
    sweep: Sweep<Finalizer>,
}

impl StreamingSweep {
    /// Starts a streaming sweep with its first point.
    pub fn new(first: StreamPoint, cfg: &StreamConfig) -> Self {
        let mut fin = Finalizer::new(cfg);
        for _ in 0..FIRST_REAL {
            fin.vertices.push(f64::NAN, u64::MAX);
        }
        fin.vertices.push(first.z, first.index);
        fin.last = first.xy;
        fin.window_y = first.xy[1];
        fin.live_vertices = 1;
        fin.stats.peak_live_vertices = 1;
        let pts = SpillVec::from_vec(vec![[f64::NAN; 2], [f64::NAN; 2], first.xy]);
        let [x0, _, x1, _] = cfg.bounds;
        let xmap = if cfg.x_sample.is_empty() {
            XMap::linear(x0, x1)
        } else {
            XMap::from_sample(cfg.x_sample.clone())
        };
        StreamingSweep {
            sweep: Sweep::start(pts, Mesh::with_capacity(1024), xmap, fin),
        }
    }

    /// Sets the breaklines; points name their constraint vertex in [`StreamPoint::constraint`],
    /// and `first_constraint` is that of the first point (given to [`StreamingSweep::new`]).
    /// Call it before the second point.
    ///
    /// # Errors
    /// [`Error::Internal`] if `first_constraint` is neither [`crate::sweep::NO_CONSTRAINT`] nor a vertex of
    /// `graph`.
    pub fn set_constraints(&mut self, graph: ConstraintGraph, first_constraint: u32) -> Result<()> {
        self.sweep.set_point_constraints(graph, first_constraint)
    }

    #[inline(always)]
    fn fin(&mut self) -> &mut Finalizer {
        self.sweep.hooks_mut()
    }

    /// Adds the next point.
    ///
    /// # Errors
    /// [`Error::OutOfOrder`] unless `p` comes strictly after the previous point in sweep order (by
    /// `y`, then `x`); duplicates must be merged before. [`Error::Internal`] if a breakline that
    /// `p` ends cannot be inserted (a bug; the sweep must not be used further).
    pub fn push(&mut self, p: StreamPoint) -> Result<()> {
        let fin = self.fin();
        if predicates::sweep_cmp(fin.last, p.xy) != std::cmp::Ordering::Less {
            return Err(Error::OutOfOrder {
                index: self.sweep.stats().points,
            });
        }
        fin.last = p.xy;
        let front = self.sweep.front().len();
        let fin = self.fin();
        fin.adapt(p.xy[1], front);
        let queued = (fin.ring.len() + fin.far.len()) as u64;
        fin.stats.peak_queued = fin.stats.peak_queued.max(queued);
        self.finalize_due(p.xy[1]);
        if self.fin().points.is_multiple_of(tables::CHECK_EVERY) {
            self.look_at_tables()?;
        }
        let fin = self.fin();
        let v = fin.vertices.add(&p);
        fin.live_vertices += 1;
        fin.stats.peak_live_vertices = fin.stats.peak_live_vertices.max(fin.live_vertices);
        self.sweep.put_point(v, p.xy);
        self.sweep.insert_point(VertexId(v), p.constraint)
    }

    /// Triangles held now (artificial ones included).
    pub fn live_triangles(&self) -> u64 {
        self.sweep.hooks().live_triangles
    }

    /// Moves the events produced so far into `out` (appending).
    pub fn take_events(&mut self, out: &mut Vec<Event>) {
        out.append(&mut self.fin().events);
    }

    /// Number of events waiting in [`StreamingSweep::take_events`].
    pub fn pending_events(&self) -> usize {
        self.sweep.hooks().events.len()
    }

    /// Working-set statistics.
    pub fn stream_stats(&self) -> StreamStats {
        let f = self.sweep.hooks();
        let mut s = f.stats;
        s.peak_pending_segments = f.pending.peak as u64;
        s.peak_spilled_bytes = f.spill.peak_spilled;
        s.spill_releases = f.spill.releases;
        s
    }

    /// What the sweep has done so far.
    pub fn stats(&self) -> SweepStats {
        self.sweep.stats()
    }

    /// What the breakline insertion has done so far.
    pub fn constraint_stats(&self) -> ConstraintStats {
        self.sweep.constraint_stats()
    }

    /// Verifies the invariants of the triangles still in memory and of the front (see
    /// [`Sweep::check`]; edges facing finalised triangles are boundary edges).
    ///
    /// # Errors
    /// [`Error::Internal`] describing the first violation.
    #[cfg(any(test, feature = "dev"))]
    pub fn check(&self) -> Result<()> {
        self.sweep.check()
    }

    /// Spills the tables of held triangles past their share of `--mem`, and drops their
    /// resident pages when they have grown by it ([`tables::Spill::look`]).
    fn look_at_tables(&mut self) -> Result<()> {
        let (pts, mesh, front, fin) = self.sweep.tables_mut();
        let (nodes, buckets, lead, last, low) = front.tables_mut();
        let vt = &mut fin.vertices;
        fin.spill.look(&mut [
            pts,
            nodes,
            buckets,
            lead,
            last,
            low,
            &mut mesh.origin,
            &mut mesh.link,
            fin.far.table(),
            fin.ring.table(),
            &mut fin.due,
            &mut fin.blocked,
            &mut vt.z,
            &mut vt.index,
            &mut vt.out,
            &mut vt.refs,
        ])
    }

    /// Processes every queue bucket the sweep line (now at `y`) has passed.
    fn finalize_due(&mut self, y: f64) {
        let ks = {
            let fin = self.fin();
            let ks = fin.bucket(y);
            fin.sweep_bucket = fin.sweep_bucket.max(ks);
            ks
        };
        loop {
            let fin = self.fin();
            if fin.cur >= ks {
                return;
            }
            if fin.ring.len() == 0 {
                // Nothing in the ring: jump straight to the sweep line or the next far entry.
                let next_far = fin.far.peek().map_or(u64::MAX, |r| r.0);
                fin.cur = ks.min(next_far.max(fin.cur + 1));
                fin.pull_far();
                continue;
            }
            let bucket = fin.cur;
            fin.cur += 1;
            let mut chain = fin.ring.detach(bucket);
            fin.pull_far();
            let mut batch = std::mem::take(&mut fin.batch);
            while self.fin().ring.next_batch(&mut chain, &mut batch) {
                for &t in &batch {
                    if self.sweep.hooks().due[t as usize] == bucket
                        && self.sweep.mesh().is_live(TriId(t))
                    {
                        // Checks of held triangles (a line's fan, a ring: millions) touch their
                        // spilled tables, the far queue's heap and the front's nodes all over:
                        // drop the pages as the checks go, not only between points (a full
                        // disk is reported by the next look between points).
                        let scans = self.fin().stats.front_scans;
                        self.check_final(t, y, ks);
                        let fin = self.fin();
                        let pages = tables::PAGES_A_CHECK * (1 + fin.stats.front_scans - scans);
                        if fin.spill.touched(pages) {
                            self.sweep.release_spilled();
                        }
                    }
                }
            }
            self.fin().batch = batch;
        }
    }

    /// Emits triangle slot `t` (and any vertex not yet emitted), releases what it no longer needs
    /// and frees the slot.
    fn finalize(&mut self, t: u32) {
        let ending = self.sweep.hooks().ending;
        let tri = self.sweep.remove_final(TriId(t), ending);
        let (pts, fin) = self.sweep.points_and_hooks_mut();
        fin.emit(t, tri, pts);
    }
}
