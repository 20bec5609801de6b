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
//! 4. **A vertex exactly on the interior of a segment** (exact `orient` = 0 and strictly between
//!    the ends) splits the segment there. The vertex keeps its `z`; if it has none it takes the `z`
//!    interpolated along the segment; if the two differ by more than `z_tolerance` it is reported
//!    ([`ZConflictKind::OnLine`]).
//! 5. **Collinear overlaps** reduce to rule 4: each end of one segment that lies inside the other
//!    splits it, and the identical pieces merge (rule 3).
//! 6. **Proper crossings** (the interiors cross at one point, decided by four exact orientations)
//!    are split at the crossing point, computed once in floating point from the adaptive
//!    determinants (`geom::predicates::orient_det`) with the two segments and their ends in a
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
//!
//! # Layout
//!
//! This file holds the types, [`clean`] and the rounds (rule 8); `dedup.rs` the input checks and
//! rules 1–3, `intersect.rs` the candidate pairs and the exact tests of rules 4–6, `split.rs` what
//! a round's findings do (snapping, rule 7, and splitting).

mod dedup;
mod intersect;
mod split;
pub mod stream;
mod sweep;

#[cfg(any(test, feature = "dev"))]
pub use sweep::SweepStats;

use crate::error::{Error, Result};
use crate::geom::grid::Grid;
use rayon::prelude::*;
use std::cmp::Ordering;

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
    w.run(&mut |w: &Work, first| Ok(w.find(first)))?;
    Ok(w.finish())
}

/// [`clean`] with each round's pairs found by the plane sweep of `sweep.rs` (items sorted
/// externally within `mem` bytes under `tmp_dir`) instead of the grid: the same graph, and the
/// most the sweeps held at once. The first step of cleaning in bounded memory (issue 40); the
/// rounds themselves still hold the graph.
///
/// # Errors
/// As [`clean`], and the external sort's.
#[cfg(any(test, feature = "dev"))]
pub fn clean_by_sweep(
    polylines: &[Vec<[f64; 3]>],
    options: &CleanOptions,
    mem: u64,
    tmp_dir: &std::path::Path,
) -> Result<(Pslg, SweepStats)> {
    let mut w = Work::new(polylines, options)?;
    let mut peak = SweepStats::default();
    w.run(&mut |w: &Work, first| {
        let (found, s) = w.find_by_sweep(first, mem, tmp_dir)?;
        peak.items = peak.items.max(s.items);
        peak.peak_active = peak.peak_active.max(s.peak_active);
        peak.peak_entries = peak.peak_entries.max(s.peak_entries);
        peak.pairs_tested += s.pairs_tested;
        Ok(found)
    })?;
    Ok((w.finish(), peak))
}

/// What finds a round's contacts: every candidate pair's non-empty result, in pair order.
type Finder<'a> = dyn FnMut(&Work, bool) -> Result<intersect::Found> + 'a;

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

impl Work {
    fn warn(&mut self, c: ZConflict) {
        self.stats.z_conflicts += 1;
        if self.warnings.len() < MAX_WARNINGS {
            self.warnings.push(c);
        }
    }

    fn run(&mut self, find: &mut Finder<'_>) -> Result<()> {
        for round in 1..=MAX_ROUNDS {
            self.stats.rounds = round;
            if round > 1 {
                let items = self.segs.len() + self.isolated.len();
                self.grid = Grid::new(self.lo, self.hi, (items as f64 * CELLS_PER_ITEM) as usize);
            }
            let found = find(self, round == 1)?;
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

/// Lexicographic order of points.
#[inline]
fn lex(p: [f64; 2], q: [f64; 2]) -> Ordering {
    p[0].total_cmp(&q[0]).then(p[1].total_cmp(&q[1]))
}

#[cfg(test)]
mod tests;
