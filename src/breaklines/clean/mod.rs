//! Polylines → a planar straight-line graph (PSLG): the constraints the sweep can insert.
//!
//! # Rules
//!
//! 1. **Duplicate vertices.** Vertices with exactly the same `(x, y)` are one vertex. Its `z` is
//!    the first *known* `z` in input order (polyline by polyline, vertex by vertex); a later known
//!    `z` that differs by more than `z_tolerance` is reported ([`ZConflictKind::Duplicate`]).
//! 2. **Zero-length segments** (consecutive vertices at the same `(x, y)`) are dropped.
//! 3. **Duplicate segments** (the same two vertices, either direction, as the shared edges of a
//!    planar partition) are merged; the first polyline is recorded as the segment's line.
//! 4. **A vertex exactly on the interior of a segment** (exact [`orient`] = 0 and strictly between
//!    the ends) splits the segment there. The vertex keeps its `z`; if it has none it takes the `z`
//!    interpolated along the segment; if the two differ by more than `z_tolerance` it is reported
//!    ([`ZConflictKind::OnLine`]).
//! 5. **Collinear overlaps** reduce to rule 4: each end of one segment that lies inside the other
//!    splits it, and the identical pieces merge (rule 3).
//! 6. **Proper crossings** (the interiors cross at one point, decided by four exact orientations)
//!    are split at the crossing point, computed once in floating point from the adaptive
//!    determinants ([`crate::geom::predicates::orient_det`]) with the two segments and their ends in a
//!    canonical (coordinate) order, so the point depends only on the geometry, not on input order;
//!    it is clamped into both segments' bounding boxes. Its `z` is interpolated linearly along each
//!    segment; the mean of the known values is kept, and two values that differ by more than
//!    `z_tolerance` are reported ([`ZConflictKind::Crossing`]).
//! 7. **Snapping.** A crossing point within the snap distance of an existing vertex (an input
//!    vertex or one created earlier) *is* that vertex (the nearest; on a tie the lowest in `(x, y)`
//!    order), and crossing points of one round within the snap distance of each other become one
//!    vertex (crossings are taken in `(x, y)` order of their points; each becomes the vertex
//!    nearest to it so far, or a new one). This is what makes the process stop: the rounded
//!    point, or the snapped vertex, is off the original lines by a few units in the last place, so
//!    the pieces can meet other segments the originals missed (three lines through almost the
//!    same point). Those new contacts are checked in the next round; snapping turns every one of
//!    them that is within the snap distance of a vertex into that vertex, so new vertices are at
//!    least the snap distance apart and only finitely many can ever be created. The default snap
//!    distance is `2^-36` (1.5e-11) times the largest coordinate magnitude, some 65,000 units in
//!    the last place of the coordinates: far above the rounding error of a crossing point, far
//!    below any real feature (6.5 µm for coordinates around 447 km).
//! 8. **Rounds.** Rules 4–7 repeat on the pieces created in the previous round (against every
//!    segment near them) until a round finds nothing. Segments that did not change are never
//!    tested against each other again. More than [`MAX_ROUNDS`] rounds is reported as an error.
//!
//! Exactness: every topological decision (does it cross, touch, overlap, lie on) is an exact
//! orientation or an exact coordinate comparison; only rule 6 rounds (a new point) and rule 7
//! measures a distance in floating point.
//!
//! Determinism: vertices are merged by sorting, candidate pairs come from a grid whose buckets are
//! sorted, pair tests run in parallel but their results are collected in pair order, and no hash
//! map is ever iterated. The output depends only on the input and options, not on thread count.
//!
//! # Cost
//!
//! Candidate pairs come from a uniform grid of about one cell per segment: `O(n + k)` pair tests
//! per round for `n` segments with `k` candidate pairs, almost all in the first round.

use crate::error::{Error, Result};
use crate::geom::grid::{Buckets, Grid};
use crate::geom::predicates::{Orientation, check_coord, orient, orient_det};
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::HashMap;

/// Rounds after which [`clean`] gives up.
pub const MAX_ROUNDS: u32 = 64;
/// Default snap distance relative to the largest coordinate magnitude (`2^-36`).
pub const SNAP_REL: f64 = 1.0 / (1u64 << 36) as f64;
/// At most this many [`ZConflict`]s are kept (all are counted).
pub const MAX_WARNINGS: usize = 1000;
/// Grid cells per segment.
const CELLS_PER_ITEM: f64 = 1.0;

/// Options of [`clean`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CleanOptions {
    /// Two `z` values for one place that differ by more than this are reported (in the data's
    /// units). `z` values are never rejected: the first (duplicates, vertices on lines) or the
    /// mean (crossings) is kept.
    pub z_tolerance: f64,
    /// Snap distance (module docs, rule 7) in the data's units; `None` for the default,
    /// [`SNAP_REL`] times the largest coordinate magnitude.
    pub snap: Option<f64>,
}

impl Default for CleanOptions {
    fn default() -> Self {
        CleanOptions {
            z_tolerance: 0.1,
            snap: None,
        }
    }
}

/// What [`clean`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CleanStats {
    /// Vertices given (over all polylines).
    pub input_vertices: u64,
    /// Segments given (consecutive vertex pairs).
    pub input_segments: u64,
    /// Input vertices merged into an earlier one at exactly the same `(x, y)`.
    pub merged_vertices: u64,
    /// Segments dropped because both ends are at the same `(x, y)`.
    pub zero_length: u64,
    /// Input segments identical (same two ends) to an earlier one, merged.
    pub duplicate_segments: u64,
    /// Proper crossings split.
    pub crossings: u64,
    /// Crossings that landed on an existing vertex (snap, rule 7) instead of a new one.
    pub snapped: u64,
    /// Vertices created at crossings.
    pub new_vertices: u64,
    /// Segments split at a vertex lying exactly on their interior (T-junctions, overlaps).
    pub vertex_splits: u64,
    /// Pairs of collinear segments that share more than a point.
    pub overlaps: u64,
    /// Pieces merged because they were identical after splitting (overlaps merged).
    pub merged_pieces: u64,
    /// Places where two `z` values differ by more than the tolerance.
    pub z_conflicts: u64,
    /// Rounds until nothing changed (1 when the input was already clean).
    pub rounds: u32,
    /// Vertices out.
    pub vertices: u64,
    /// Segments out.
    pub segments: u64,
}

/// Where two `z` values for one place disagree.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum ZConflictKind {
    /// Two input vertices at the same `(x, y)`.
    Duplicate,
    /// Two lines cross: `z` interpolated along each.
    Crossing,
    /// A vertex lies on another line: its `z` and the `z` interpolated along the line.
    OnLine,
}

/// A `z` disagreement (see [`CleanOptions::z_tolerance`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ZConflict {
    /// Where.
    pub at: [f64; 2],
    /// The two values (the first is the one kept, except at crossings, where the mean is).
    pub z: [f64; 2],
    /// What met there.
    pub kind: ZConflictKind,
    /// The input polylines involved (indices into the input).
    pub lines: [u32; 2],
}

/// A planar straight-line graph: no two segments meet except at a common end.
#[derive(Clone, Debug, Default)]
pub struct Pslg {
    /// Distinct vertices `[x, y, z]` (`z` is `NaN` where no line gave one): the input vertices in
    /// order of first appearance, then those created at crossings.
    pub vertices: Vec<[f64; 3]>,
    /// Segments as vertex index pairs, smaller index first, sorted.
    pub segments: Vec<[u32; 2]>,
    /// For each segment, the input polyline it lies on (the first one, when several do).
    pub lines: Vec<u32>,
    /// The first [`MAX_WARNINGS`] `z` disagreements.
    pub warnings: Vec<ZConflict>,
    /// Counters.
    pub stats: CleanStats,
}

impl Pslg {
    /// Checks that the graph is planar: distinct vertex positions, no two segments crossing,
    /// overlapping or touching except at a common end, no vertex inside a segment (the same exact
    /// tests as [`clean`], run on every pair of nearby segments).
    ///
    /// # Errors
    /// [`Error::Internal`] describing the first problem found (cleaning makes every graph
    /// planar, so a failure is a bug).
    pub fn check_planar(&self) -> Result<()> {
        self.planar_problem().map_err(Error::Internal)
    }

    fn planar_problem(&self) -> std::result::Result<(), String> {
        let n = self.vertices.len();
        if let Some(s) = self
            .segments
            .iter()
            .find(|s| s[0] == s[1] || s[0] as usize >= n || s[1] as usize >= n)
        {
            return Err(format!("segment {s:?} is degenerate or out of range"));
        }
        let xy: Vec<[f64; 2]> = self.vertices.iter().map(|p| [p[0], p[1]]).collect();
        let mut keys: Vec<(u64, u64)> = xy
            .iter()
            .map(|p| ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()))
            .collect();
        keys.par_sort_unstable();
        if keys.windows(2).any(|w| w[0] == w[1]) {
            return Err("two vertices share the same (x, y)".into());
        }
        let mut used = vec![false; n];
        for s in &self.segments {
            used[s[0] as usize] = true;
            used[s[1] as usize] = true;
        }
        let (lo, hi, _) = bounds(&xy);
        let w = Work {
            z: vec![f64::NAN; n],
            vline: vec![0; n],
            isolated: (0..n as u32).filter(|&v| !used[v as usize]).collect(),
            lo,
            hi,
            grid: Grid::new(lo, hi, self.segments.len().max(1)),
            xy,
            segs: self.segments.clone(),
            line: self.lines.clone(),
            dirty: vec![true; self.segments.len()],
            snap: 0.0,
            ztol: f64::INFINITY,
            stats: CleanStats::default(),
            warnings: Vec::new(),
        };
        match w.find(true).first() {
            None => Ok(()),
            Some(([i, j], r)) => {
                let seg = |k: u32| {
                    let s = self.segments[k as usize];
                    format!("{k} ({:?} - {:?})", w.p(s[0]), w.p(s[1]))
                };
                let other = if (*j as usize) < self.segments.len() {
                    format!("segment {}", seg(*j))
                } else {
                    let v = w.isolated[*j as usize - self.segments.len()];
                    format!("vertex {v} {:?}", w.p(v))
                };
                let what = if r.cross.is_some() {
                    "crosses"
                } else {
                    "touches or overlaps"
                };
                Err(format!("segment {} {what} {other}", seg(*i)))
            }
        }
    }

    /// The segments as coordinate pairs (for [`crate::validate::validate_cdt`]).
    pub fn segment_coords(&self) -> Vec<[[f64; 2]; 2]> {
        let p = |v: u32| {
            let q = self.vertices[v as usize];
            [q[0], q[1]]
        };
        self.segments.iter().map(|s| [p(s[0]), p(s[1])]).collect()
    }
}

/// Cleans `polylines` (`[x, y, z]`, `z = NaN` when unknown) into a planar straight-line graph by
/// the rules in the [module docs](self).
///
/// # Errors
/// [`Error::BadLine`] for a vertex whose `x` or `y` is not finite or outside the predicates' exact
/// range, or whose `z` is infinite; [`Error::TooManyPoints`] beyond 2^32 - 1 vertices;
/// [`Error::Internal`] if the graph is not planar after [`MAX_ROUNDS`] rounds.
pub fn clean(polylines: &[Vec<[f64; 3]>], options: &CleanOptions) -> Result<Pslg> {
    let mut w = Work::new(polylines, options)?;
    w.run()?;
    Ok(w.finish())
}

/// The graph being cleaned.
struct Work {
    xy: Vec<[f64; 2]>,
    z: Vec<f64>,
    /// Input polyline where each vertex first appears.
    vline: Vec<u32>,
    segs: Vec<[u32; 2]>,
    line: Vec<u32>,
    /// Created in the last round (to be tested against everything near).
    dirty: Vec<bool>,
    /// Vertices on no segment (tested against segments that might pass through them).
    isolated: Vec<u32>,
    /// Bounding box of the vertices (crossing points stay inside).
    lo: [f64; 2],
    hi: [f64; 2],
    grid: Grid,
    snap: f64,
    ztol: f64,
    stats: CleanStats,
    warnings: Vec<ZConflict>,
}

/// What one candidate pair gave.
#[derive(Clone, Copy, Debug, Default)]
struct PairResult {
    /// Up to two `(segment, vertex)` splits (rule 4/5).
    splits: [(u32, u32); 2],
    n_splits: u8,
    overlap: bool,
    /// A proper crossing of the two segments, at this point.
    cross: Option<[f64; 2]>,
}

impl PairResult {
    fn split(&mut self, seg: u32, v: u32) {
        self.splits[self.n_splits as usize] = (seg, v);
        self.n_splits += 1;
    }

    fn is_empty(&self) -> bool {
        self.n_splits == 0 && self.cross.is_none()
    }
}

impl Work {
    fn new(polylines: &[Vec<[f64; 3]>], options: &CleanOptions) -> Result<Work> {
        check_input(polylines)?;
        let total: usize = polylines.iter().map(Vec::len).sum();
        if total >= u32::MAX as usize {
            return Err(Error::TooManyPoints {
                count: total as u64,
                max: u32::MAX as u64 - 1,
            });
        }
        let id_of = merge_ids(polylines, total);
        let mut w = Work {
            xy: Vec::new(),
            z: Vec::new(),
            vline: Vec::new(),
            segs: Vec::new(),
            line: Vec::new(),
            dirty: Vec::new(),
            isolated: Vec::new(),
            lo: [0.0; 2],
            hi: [0.0; 2],
            grid: Grid::new([0.0; 2], [0.0; 2], 1),
            snap: 0.0,
            ztol: options.z_tolerance,
            stats: CleanStats {
                input_vertices: total as u64,
                ..CleanStats::default()
            },
            warnings: Vec::new(),
        };
        w.add_vertices(polylines, &id_of);
        w.add_segments(polylines, &id_of);
        let (lo, hi, mag) = bounds(&w.xy);
        (w.lo, w.hi) = (lo, hi);
        let items = w.segs.len() + w.isolated.len();
        w.grid = Grid::new(lo, hi, (items as f64 * CELLS_PER_ITEM) as usize);
        w.snap = options.snap.unwrap_or(SNAP_REL * mag).max(0.0);
        Ok(w)
    }

    /// Creates the distinct vertices in order of first appearance; first known `z` wins.
    fn add_vertices(&mut self, polylines: &[Vec<[f64; 3]>], id_of: &[u32]) {
        let mut g = 0usize;
        for (i, p) in polylines.iter().enumerate() {
            for v in p {
                let id = id_of[g] as usize;
                g += 1;
                if id == self.xy.len() {
                    self.xy.push([v[0] + 0.0, v[1] + 0.0]);
                    self.z.push(v[2]);
                    self.vline.push(i as u32);
                    continue;
                }
                self.stats.merged_vertices += 1;
                let kept = self.z[id];
                if kept.is_nan() {
                    self.z[id] = v[2];
                } else if (v[2] - kept).abs() > self.ztol {
                    self.warn(ZConflict {
                        at: self.xy[id],
                        z: [kept, v[2]],
                        kind: ZConflictKind::Duplicate,
                        lines: [self.vline[id], i as u32],
                    });
                }
            }
        }
    }

    /// Segments between consecutive distinct vertices, normalised, sorted and deduplicated.
    fn add_segments(&mut self, polylines: &[Vec<[f64; 3]>], id_of: &[u32]) {
        let mut segs: Vec<([u32; 2], u32)> = Vec::new();
        let mut g = 0usize;
        for (i, p) in polylines.iter().enumerate() {
            let ids = &id_of[g..g + p.len()];
            g += p.len();
            self.stats.input_segments += ids.len().saturating_sub(1) as u64;
            for w in ids.windows(2) {
                if w[0] == w[1] {
                    self.stats.zero_length += 1;
                } else {
                    segs.push(([w[0].min(w[1]), w[0].max(w[1])], i as u32));
                }
            }
        }
        segs.par_sort_unstable();
        let before = segs.len();
        segs.dedup_by_key(|s| s.0);
        self.stats.duplicate_segments = (before - segs.len()) as u64;
        let mut used = vec![false; self.xy.len()];
        for (s, _) in &segs {
            used[s[0] as usize] = true;
            used[s[1] as usize] = true;
        }
        self.isolated = (0..self.xy.len() as u32)
            .filter(|&v| !used[v as usize])
            .collect();
        self.line = segs.iter().map(|s| s.1).collect();
        self.segs = segs.into_iter().map(|s| s.0).collect();
        self.dirty = vec![true; self.segs.len()];
    }

    fn warn(&mut self, c: ZConflict) {
        self.stats.z_conflicts += 1;
        if self.warnings.len() < MAX_WARNINGS {
            self.warnings.push(c);
        }
    }

    fn run(&mut self) -> Result<()> {
        for round in 1..=MAX_ROUNDS {
            self.stats.rounds = round;
            if round > 1 {
                let items = self.segs.len() + self.isolated.len();
                self.grid = Grid::new(self.lo, self.hi, (items as f64 * CELLS_PER_ITEM) as usize);
            }
            let found = self.find(round == 1);
            if found.is_empty() {
                return Ok(());
            }
            self.apply(found);
        }
        Err(Error::Internal(format!(
            "breaklines still not planar after {MAX_ROUNDS} rounds of splitting ({} segments, \
             {} vertices); the snap distance {:e} may be too small for these coordinates",
            self.segs.len(),
            self.xy.len(),
            self.snap
        )))
    }

    /// Tests every candidate pair that involves a dirty item; returns the non-empty results in
    /// pair order.
    fn find(&self, first_round: bool) -> Vec<([u32; 2], PairResult)> {
        let n_seg = self.segs.len() as u32;
        let buckets = self.buckets();
        let dirty = |i: u32| {
            if i < n_seg {
                self.dirty[i as usize]
            } else {
                first_round
            }
        };
        // Each dirty item gathers the items sharing a cell with it; a pair of two dirty items is
        // tested from its first one. Items are taken cell by cell (each from the first cell it is
        // in), so that nearby items are processed together.
        let first = |i: u32| {
            if i < n_seg {
                let [a, b] = self.segs[i as usize];
                let mut first = u32::MAX;
                self.grid
                    .segment_cells(self.p(a), self.p(b), |c| first = first.min(c));
                first
            } else {
                self.grid
                    .cell_of(self.p(self.isolated[(i - n_seg) as usize]))
            }
        };
        (0..self.grid.len() as u32)
            .into_par_iter()
            .flat_map_iter(|c| {
                buckets
                    .cell(c)
                    .iter()
                    .copied()
                    .filter(move |&i| dirty(i) && first(i) == c)
            })
            .flat_map_iter(|i| {
                let mut cand: Vec<u32> = Vec::new();
                let mut visit = |c: u32| {
                    for &j in buckets.cell(c) {
                        if j != i && (i < n_seg || j < n_seg) && (j > i || !dirty(j)) {
                            cand.push(j);
                        }
                    }
                };
                if i < n_seg {
                    let [a, b] = self.segs[i as usize];
                    self.grid.segment_cells(self.p(a), self.p(b), visit);
                } else {
                    visit(
                        self.grid
                            .cell_of(self.p(self.isolated[(i - n_seg) as usize])),
                    );
                }
                cand.sort_unstable();
                cand.dedup();
                cand.into_iter().filter_map(move |j| {
                    let (s, t) = (i.min(j), i.max(j));
                    let r = if t >= n_seg {
                        self.test_point(s, self.isolated[(t - n_seg) as usize])
                    } else {
                        self.test_pair(s, t)
                    };
                    (!r.is_empty()).then_some(([s, t], r))
                })
            })
            .collect()
    }

    /// Segments and isolated points bucketed over the grid.
    fn buckets(&self) -> Buckets {
        let n_seg = self.segs.len() as u64;
        let mut pairs: Vec<u64> = self
            .segs
            .par_iter()
            .enumerate()
            .flat_map_iter(|(i, s)| {
                let mut cells = Vec::with_capacity(4);
                self.grid.segment_cells(self.p(s[0]), self.p(s[1]), |c| {
                    cells.push((u64::from(c) << 32) | i as u64)
                });
                cells
            })
            .collect();
        for (k, &v) in self.isolated.iter().enumerate() {
            pairs.push((u64::from(self.grid.cell_of(self.p(v))) << 32) | (n_seg + k as u64));
        }
        Buckets::from_pairs(self.grid.len(), pairs)
    }

    #[inline]
    fn p(&self, v: u32) -> [f64; 2] {
        self.xy[v as usize]
    }

    /// Isolated vertex `v` against segment `s`.
    fn test_point(&self, s: u32, v: u32) -> PairResult {
        let [a, b] = self.segs[s as usize];
        let mut r = PairResult::default();
        let (pa, pb, pv) = (self.p(a), self.p(b), self.p(v));
        if orient(pa, pb, pv) == Orientation::Collinear && strictly_between(pa, pb, pv) {
            r.split(s, v);
        }
        r
    }

    /// Segments `s` and `t` (rules 4–6).
    fn test_pair(&self, s: u32, t: u32) -> PairResult {
        let [a, b] = self.segs[s as usize];
        let [c, d] = self.segs[t as usize];
        let mut r = PairResult::default();
        // A shared end: they can only overlap along a common line.
        let shared = if a == c || a == d {
            Some((a, b, if a == c { d } else { c }))
        } else if b == c || b == d {
            Some((b, a, if b == c { d } else { c }))
        } else {
            None
        };
        if let Some((v, p, q)) = shared {
            let (pv, pp, pq) = (self.p(v), self.p(p), self.p(q));
            if orient(pv, pp, pq) == Orientation::Collinear && same_direction(pv, pp, pq) {
                r.overlap = true;
                if strictly_between(pv, pp, pq) {
                    r.split(s, q);
                } else {
                    r.split(t, p);
                }
            }
            return r;
        }
        let (pa, pb, pc, pd) = (self.p(a), self.p(b), self.p(c), self.p(d));
        let oc = orient(pa, pb, pc);
        let od = orient(pa, pb, pd);
        if oc == od && oc != Orientation::Collinear {
            return r;
        }
        let oa = orient(pc, pd, pa);
        let ob = orient(pc, pd, pb);
        if oa == ob && oa != Orientation::Collinear {
            return r;
        }
        let col = Orientation::Collinear;
        if oc == col && od == col {
            for (seg, e0, e1, v, pv) in [
                (s, pa, pb, c, pc),
                (s, pa, pb, d, pd),
                (t, pc, pd, a, pa),
                (t, pc, pd, b, pb),
            ] {
                if strictly_between(e0, e1, pv) {
                    r.split(seg, v);
                }
            }
            r.overlap = r.n_splits > 0;
            return r;
        }
        // At most one end lies on the other segment's line (two would be the same point).
        if oc == col {
            r.split(s, c);
        } else if od == col {
            r.split(s, d);
        } else if oa == col {
            r.split(t, a);
        } else if ob == col {
            r.split(t, b);
        } else {
            r.cross = Some(crossing_point(pa, pb, pc, pd));
        }
        r
    }

    /// Turns the pair results into splits (creating or snapping crossing vertices) and applies
    /// them.
    fn apply(&mut self, found: Vec<([u32; 2], PairResult)>) {
        let mut splits: Vec<(u32, u32)> = Vec::new();
        let mut on_line: Vec<(u32, u32)> = Vec::new();
        let mut crossings: Vec<(u32, u32, [f64; 2])> = Vec::new();
        for ([i, j], r) in found {
            self.stats.overlaps += u64::from(r.overlap);
            for &(seg, v) in &r.splits[..r.n_splits as usize] {
                on_line.push((seg, v));
            }
            if let Some(p) = r.cross {
                crossings.push((i, j, p));
            }
        }
        for &(seg, v) in &on_line {
            let zi = self.z_along(seg, self.p(v));
            self.merge_z(v, zi, [self.line[seg as usize], self.vline[v as usize]]);
        }
        self.stats.vertex_splits += on_line.len() as u64;
        splits.extend(on_line);
        if !crossings.is_empty() {
            self.stats.crossings += crossings.len() as u64;
            // In the order of the points, so that which crossing point of a cluster becomes the
            // vertex depends on the geometry only.
            crossings.par_sort_by(|x, y| lex(x.2, y.2).then((x.0, x.1).cmp(&(y.0, y.1))));
            // The nearest existing vertex of each crossing, in parallel; the vertices made in this
            // round are looked at in order below.
            let vertices = Buckets::points(&self.grid, &self.xy);
            let old: Vec<Option<Near>> = crossings
                .par_iter()
                .map(|c| {
                    let mut best = None;
                    self.snap_cells(c.2, |cell| {
                        for &v in vertices.cell(cell) {
                            best = closer(best, c.2, self.xy[v as usize], v, self.snap);
                        }
                    });
                    best
                })
                .collect();
            let mut fresh: HashMap<u32, Vec<u32>> = HashMap::new();
            for ((s, t, p), near) in crossings.into_iter().zip(old) {
                let v = self.crossing_vertex(s, t, p, near, &mut fresh);
                for seg in [s, t] {
                    let [a, b] = self.segs[seg as usize];
                    if v != a && v != b {
                        splits.push((seg, v));
                    }
                }
            }
        }
        self.split(splits);
    }

    /// The cells within the snap distance of `p`.
    fn snap_cells(&self, p: [f64; 2], f: impl FnMut(u32)) {
        let (lo, hi) = (
            [p[0] - self.snap, p[1] - self.snap],
            [p[0] + self.snap, p[1] + self.snap],
        );
        self.grid.box_cells(lo, hi, f);
    }

    /// The vertex for the crossing of `s` and `t` at `p`: the nearest of `near` (the nearest
    /// older vertex within the snap distance) and the vertices made in this round (`fresh`, by
    /// cell), or a new one.
    fn crossing_vertex(
        &mut self,
        s: u32,
        t: u32,
        p: [f64; 2],
        near: Option<Near>,
        fresh: &mut HashMap<u32, Vec<u32>>,
    ) -> u32 {
        let (zs, zt) = (self.z_along(s, p), self.z_along(t, p));
        let lines = [self.line[s as usize], self.line[t as usize]];
        let mut best = near;
        if !fresh.is_empty() {
            self.snap_cells(p, |c| {
                for &v in fresh.get(&c).map_or(&[][..], |l| &l[..]) {
                    best = closer(best, p, self.xy[v as usize], v, self.snap);
                }
            });
        }
        if let Some(Near { v, .. }) = best {
            self.stats.snapped += 1;
            self.merge_z(v, zs, lines);
            self.merge_z(v, zt, lines);
            return v;
        }
        let z = match (zs.is_nan(), zt.is_nan()) {
            (false, false) => {
                if (zs - zt).abs() > self.ztol {
                    self.warn(ZConflict {
                        at: p,
                        z: [zs, zt],
                        kind: ZConflictKind::Crossing,
                        lines,
                    });
                }
                0.5 * (zs + zt)
            }
            (false, true) => zs,
            _ => zt,
        };
        let v = self.xy.len() as u32;
        self.xy.push(p);
        self.z.push(z);
        self.vline.push(lines[0]);
        self.stats.new_vertices += 1;
        fresh.entry(self.grid.cell_of(p)).or_default().push(v);
        v
    }

    /// Gives `v` the value `zin` if it has none; reports a disagreement otherwise.
    fn merge_z(&mut self, v: u32, zin: f64, lines: [u32; 2]) {
        let kept = self.z[v as usize];
        if kept.is_nan() {
            self.z[v as usize] = zin;
        } else if (zin - kept).abs() > self.ztol {
            self.warn(ZConflict {
                at: self.p(v),
                z: [kept, zin],
                kind: ZConflictKind::OnLine,
                lines,
            });
        }
    }

    /// `z` interpolated linearly along segment `seg` at (the projection of) `p`.
    fn z_along(&self, seg: u32, p: [f64; 2]) -> f64 {
        let [a, b] = self.segs[seg as usize];
        let (pa, pb) = (self.p(a), self.p(b));
        let (za, zb) = (self.z[a as usize], self.z[b as usize]);
        let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
        let u = ((p[0] - pa[0]) * dx + (p[1] - pa[1]) * dy) / (dx * dx + dy * dy);
        let u = u.clamp(0.0, 1.0);
        za + u * (zb - za)
    }

    /// Replaces every segment that has splits by its pieces; merges identical segments.
    fn split(&mut self, mut splits: Vec<(u32, u32)>) {
        splits.par_sort_unstable();
        splits.dedup();
        let mut out: Vec<([u32; 2], u32, bool)> =
            Vec::with_capacity(self.segs.len() + splits.len());
        let mut k = 0;
        let mut chain: Vec<u32> = Vec::new();
        for (i, &[a, b]) in self.segs.iter().enumerate() {
            let line = self.line[i];
            if k >= splits.len() || splits[k].0 != i as u32 {
                out.push(([a, b], line, false));
                continue;
            }
            chain.clear();
            while k < splits.len() && splits[k].0 == i as u32 {
                chain.push(splits[k].1);
                k += 1;
            }
            let (pa, pb) = (self.p(a), self.p(b));
            chain.sort_by(|&u, &v| along(pa, pb, self.p(u), self.p(v)));
            let mut prev = a;
            for &v in chain.iter().chain(std::iter::once(&b)) {
                out.push(([prev.min(v), prev.max(v)], line, true));
                prev = v;
            }
        }
        out.par_sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.cmp(&y.1)));
        let before = out.len();
        // Identical segments: keep the first line; it needs testing only if every copy is new.
        let mut merged: Vec<([u32; 2], u32, bool)> = Vec::with_capacity(out.len());
        for s in out {
            match merged.last_mut() {
                Some(last) if last.0 == s.0 => last.2 &= s.2,
                _ => merged.push(s),
            }
        }
        self.stats.merged_pieces += (before - merged.len()) as u64;
        self.segs = merged.iter().map(|s| s.0).collect();
        self.line = merged.iter().map(|s| s.1).collect();
        self.dirty = merged.iter().map(|s| s.2).collect();
        self.refresh_isolated();
    }

    /// Drops isolated vertices that became segment ends.
    fn refresh_isolated(&mut self) {
        if self.isolated.is_empty() {
            return;
        }
        let mut used = vec![false; self.xy.len()];
        for s in &self.segs {
            used[s[0] as usize] = true;
            used[s[1] as usize] = true;
        }
        self.isolated.retain(|&v| !used[v as usize]);
    }

    fn finish(self) -> Pslg {
        let mut stats = self.stats;
        stats.vertices = self.xy.len() as u64;
        stats.segments = self.segs.len() as u64;
        Pslg {
            vertices: self
                .xy
                .iter()
                .zip(&self.z)
                .map(|(p, &z)| [p[0], p[1], z])
                .collect(),
            segments: self.segs,
            lines: self.line,
            warnings: self.warnings,
            stats,
        }
    }
}

/// Every `x, y` finite and in the predicates' range, every `z` finite or `NaN`.
fn check_input(polylines: &[Vec<[f64; 3]>]) -> Result<()> {
    let bad = polylines.par_iter().enumerate().find_map_first(|(i, p)| {
        p.iter().enumerate().find_map(|(k, v)| {
            let message = if !(v[0].is_finite() && v[1].is_finite()) {
                format!("coordinate is not finite ({}, {})", v[0], v[1])
            } else if !(check_coord(v[0]) && check_coord(v[1])) {
                format!(
                    "coordinate ({}, {}) is outside the range where the predicates are exact",
                    v[0], v[1]
                )
            } else if v[2].is_infinite() {
                format!("z is infinite ({})", v[2])
            } else {
                return None;
            };
            Some(Error::BadLine {
                polyline: i as u64,
                vertex: k as u64,
                message,
            })
        })
    });
    match bad {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// For every input vertex (in input order), its distinct-vertex id; ids are given in order of
/// first appearance.
fn merge_ids(polylines: &[Vec<[f64; 3]>], total: usize) -> Vec<u32> {
    let flat: Vec<[f64; 2]> = polylines
        .iter()
        .flatten()
        .map(|v| [v[0] + 0.0, v[1] + 0.0])
        .collect();
    let mut keys: Vec<(u64, u64, u32)> = flat
        .par_iter()
        .enumerate()
        .map(|(g, p)| (p[0].to_bits(), p[1].to_bits(), g as u32))
        .collect();
    keys.par_sort_unstable();
    // First appearance of each position.
    let mut rep = vec![0u32; total];
    let mut k = 0;
    while k < keys.len() {
        let first = keys[k].2;
        let mut e = k;
        while e < keys.len() && keys[e].0 == keys[k].0 && keys[e].1 == keys[k].1 {
            rep[keys[e].2 as usize] = first;
            e += 1;
        }
        k = e;
    }
    let mut id_of = vec![0u32; total];
    let mut next = 0u32;
    for g in 0..total {
        let r = rep[g] as usize;
        if r == g {
            id_of[g] = next;
            next += 1;
        } else {
            id_of[g] = id_of[r];
        }
    }
    id_of
}

/// Bounding box and largest coordinate magnitude.
fn bounds(xy: &[[f64; 2]]) -> ([f64; 2], [f64; 2], f64) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in xy {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if xy.is_empty() {
        return ([0.0; 2], [0.0; 2], 0.0);
    }
    let mag = lo[0]
        .abs()
        .max(lo[1].abs())
        .max(hi[0].abs())
        .max(hi[1].abs());
    (lo, hi, mag)
}

/// `c` strictly between `a` and `b`, for `c` on the line `ab` (exact comparisons).
#[inline]
fn strictly_between(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let k = if a[0] != b[0] { 0 } else { 1 };
    (a[k] < c[k] && c[k] < b[k]) || (b[k] < c[k] && c[k] < a[k])
}

/// `p` and `q` on the same side of `v` on a common line through `v` (exact comparisons).
#[inline]
fn same_direction(v: [f64; 2], p: [f64; 2], q: [f64; 2]) -> bool {
    let sgn = |a: f64, b: f64| a.partial_cmp(&b).unwrap_or(Ordering::Equal);
    sgn(p[0], v[0]) == sgn(q[0], v[0]) && sgn(p[1], v[1]) == sgn(q[1], v[1])
}

/// Order of `u` and `v` along the segment from `a` to `b`: along its dominant axis, then the
/// other one (exact for points on the segment; a consistent order for points snapped near it).
fn along(a: [f64; 2], b: [f64; 2], u: [f64; 2], v: [f64; 2]) -> Ordering {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (major, minor) = if dx.abs() >= dy.abs() { (0, 1) } else { (1, 0) };
    let dir = |d: f64, x: f64, y: f64| {
        if d < 0.0 {
            y.total_cmp(&x)
        } else {
            x.total_cmp(&y)
        }
    };
    let d = [dx, dy];
    dir(d[major], u[major], v[major]).then(dir(d[minor], u[minor], v[minor]))
}

/// A vertex near a crossing point.
#[derive(Clone, Copy, Debug)]
struct Near {
    d2: f64,
    at: [f64; 2],
    v: u32,
}

/// `best`, or vertex `v` at `q` if it is within `snap` of `p` (or exactly at `p`) and nearer
/// (ties: lower in `(x, y)` order).
#[inline]
fn closer(best: Option<Near>, p: [f64; 2], q: [f64; 2], v: u32, snap: f64) -> Option<Near> {
    let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
    if !(d2 <= snap * snap || q == p) {
        return best;
    }
    match best {
        Some(b) if d2.total_cmp(&b.d2).then(lex(q, b.at)) != Ordering::Less => best,
        _ => Some(Near { d2, at: q, v }),
    }
}

/// Lexicographic order of points.
#[inline]
fn lex(p: [f64; 2], q: [f64; 2]) -> Ordering {
    p[0].total_cmp(&q[0]).then(p[1].total_cmp(&q[1]))
}

/// Where the segments `ab` and `cd` cross (they do, properly), from the adaptive determinants, in
/// a canonical order of segments and ends, clamped into both bounding boxes.
fn crossing_point(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> [f64; 2] {
    let norm = |p: [f64; 2], q: [f64; 2]| {
        if lex(p, q) == Ordering::Greater {
            (q, p)
        } else {
            (p, q)
        }
    };
    let (s0, s1) = (norm(a, b), norm(c, d));
    let ((a, b), (c, d)) = if lex(s0.0, s1.0).then(lex(s0.1, s1.1)) == Ordering::Greater {
        (s1, s0)
    } else {
        (s0, s1)
    };
    let da = orient_det(c, d, a);
    let db = orient_det(c, d, b);
    let t = da / (da - db);
    let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    let mut out = [0.0; 2];
    for k in 0..2 {
        let lo = a[k].min(b[k]).max(c[k].min(d[k]));
        let hi = a[k].max(b[k]).min(c[k].max(d[k]));
        out[k] = p[k].clamp(lo, hi) + 0.0;
    }
    out
}

#[cfg(test)]
mod tests;
