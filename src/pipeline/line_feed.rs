//! Breaklines streamed into the sweep (issue 40, item 3, step 3): the cleaned graph never held
//! whole.
//!
//! ```text
//! pieces from the streamed cleaner (sweep order of their lower ends)
//!   ─► half-edges, external sort by their vertex:  at a segment's upper end, its lower end
//!      (with the cleaner's order of that vertex); at its lower end, its upper end; an isolated
//!      vertex alone
//!   ─► merge thread: each vertex's run of half-edges is one point record (LINE_FLAG | rank)
//!      merged into the sorted points, and its `ConstraintVertex` record goes with that point
//!      in the batch to the sweep
//!   ─► sweep: the segments a vertex ends are inserted in the cleaner's order of their lower
//!      ends (as `ConstraintGraph::lower`), so the mesh is the in-memory path's byte for byte
//! ```
//!
//! Held: the sort's budget (a quarter of `--mem`) while the half-edges are written and, as
//! `--mem` allows, while they are read; the sweep's started vertices (those with segments
//! pending); the records of the points in flight between the threads. Two half-edges of 64
//! bytes per segment are spilled.

use super::lines::{Drape, DrapeSink, FarTally};
use crate::breaklines::Source;
use crate::breaklines::clean::stream::Cleaned;
use crate::error::{Error, Result};
use crate::geom::predicates::sweep_cmp;
use crate::idmap::FastMap;
use crate::sort::external::{ExternalSorter, Merge, SortKey, SortRecord, sweep_order};
use crate::sweep::ConstraintVertex;
use std::cell::RefCell;
use std::cmp::Ordering;
use std::collections::VecDeque;
use std::path::Path;
use std::rc::Rc;

/// Half-edge kinds, in the order a vertex's run lists them.
const LOWER: u32 = 0;
const UPPER: u32 = 1;
const ALONE: u32 = 2;

/// One end of a segment, or an isolated vertex, as the external sort stores it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct Half {
    /// The vertex (`-0` as `+0`).
    at: [f64; 2],
    /// The segment's other end (`at` when alone).
    other: [f64; 2],
    /// Height of `at`.
    z: f64,
    /// The cleaner's order of `other` (for [`LOWER`]): id, then round.
    id: u64,
    round: u32,
    kind: u32,
    /// Records are 64 bytes (the sort's maps take sizes that divide their window).
    pad: u64,
}

impl SortKey for Half {
    #[inline]
    fn order(a: &Self, b: &Self) -> Ordering {
        sweep_cmp(a.at, b.at)
            .then(a.kind.cmp(&b.kind))
            .then(a.round.cmp(&b.round))
            .then(a.id.cmp(&b.id))
            .then(a.other[0].total_cmp(&b.other[0]))
            .then(a.other[1].total_cmp(&b.other[1]))
    }
    // Distinct pieces make distinct records.
    const STABLE: bool = false;
}

/// The cleaned graph as half-edges sorted by vertex, ready to join the points.
pub(crate) struct LineFeed {
    halves: Merge<Half>,
    /// Box of the vertices `[x0, y0, x1, y1]`.
    pub(crate) bounds: [f64; 4],
    /// Vertices (the cleaner's count).
    pub(crate) vertices: u64,
    /// The vertices without `z` (sorted, distinct) and a line through each (none for a lone
    /// vertex), until draped.
    unknown: Vec<([f64; 2], Option<u32>)>,
    /// Their heights from the points' TIN, by position, until they join the points.
    heights: FastMap<(u64, u64), f64>,
}

impl std::fmt::Debug for LineFeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LineFeed")
            .field("bounds", &self.bounds)
            .field("vertices", &self.vertices)
            .finish_non_exhaustive()
    }
}

/// `-0` as `+0`.
fn plus(p: [f64; 3]) -> [f64; 2] {
    [p[0] + 0.0, p[1] + 0.0]
}

/// Sorts the half-edges of the streamed cleaner's output, in `mem` bytes spilling under `tmp`.
///
/// # Errors
/// The cleaner's stream's and the sort's.
pub(crate) fn build(mut cleaned: Cleaned, mem: u64, tmp: &Path) -> Result<LineFeed> {
    let mut sorter = ExternalSorter::<Half>::new(mem, tmp);
    let mut bounds = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut grow = |p: [f64; 2]| {
        bounds = [
            bounds[0].min(p[0]),
            bounds[1].min(p[1]),
            bounds[2].max(p[0]),
            bounds[3].max(p[1]),
        ];
    };
    let mut unknown = Vec::new();
    while let Some((piece, key)) = cleaned.next_keyed() {
        let (lo, hi) = (plus(piece.lo), plus(piece.hi));
        grow(lo);
        grow(hi);
        let line = (lo != hi).then_some(piece.line);
        for (p, z) in [(lo, piece.lo[2]), (hi, piece.hi[2])] {
            if z.is_nan() {
                unknown.push((p, line));
            }
        }
        if lo == hi {
            sorter.push(Half {
                at: lo,
                other: lo,
                z: piece.lo[2],
                kind: ALONE,
                ..Half::default()
            })?;
            continue;
        }
        sorter.push(Half {
            at: hi,
            other: lo,
            z: piece.hi[2],
            id: key[0].1,
            round: key[0].0,
            kind: LOWER,
            pad: 0,
        })?;
        sorter.push(Half {
            at: lo,
            other: hi,
            z: piece.lo[2],
            kind: UPPER,
            ..Half::default()
        })?;
    }
    if let Some(e) = cleaned.take_error() {
        return Err(e);
    }
    // A vertex's first line in the order of the pieces names it.
    unknown.sort_by(|a, b| sweep_cmp(a.0, b.0));
    unknown.dedup_by(|a, b| a.0 == b.0);
    Ok(LineFeed {
        halves: sorter.finish()?,
        bounds,
        vertices: cleaned.stats.vertices,
        unknown,
        heights: FastMap::default(),
    })
}

impl LineFeed {
    /// Gives the vertices without `z` the height of the points' TIN (`drape` runs the
    /// points-only pass, as [`super::lines::prepare`] does); returns how many.
    ///
    /// # Errors
    /// The pass's; [`Error::Format`] for a vertex outside the points' TIN, naming a line
    /// through it (`source` gives polyline `i`'s place).
    pub(crate) fn drape(
        &mut self,
        drape: Drape,
        source: &dyn Fn(u64) -> Option<Source>,
    ) -> Result<u64> {
        if self.unknown.is_empty() {
            return Ok(0);
        }
        let mut sink = DrapeSink::new(self.unknown.iter().map(|u| u.0).collect());
        drape(&mut sink)?;
        for (k, &(p, line)) in self.unknown.iter().enumerate() {
            let z = sink.z[k];
            if z.is_nan() {
                let source = line.and_then(|l| source(u64::from(l)));
                return Err(super::lines::outside_error_at(p, source.as_ref()));
            }
            self.heights.insert(pos_key(p), z);
        }
        let n = self.unknown.len() as u64;
        self.unknown = Vec::new();
        Ok(n)
    }
}

/// The key of a position (bit patterns).
fn pos_key(p: [f64; 2]) -> (u64, u64) {
    (p[0].to_bits(), p[1].to_bits())
}

/// The records of the line vertices taken from the stream and not yet given to the sweep.
pub(crate) type Records = Rc<RefCell<VecDeque<ConstraintVertex>>>;

/// The sorted points with the line vertices merged in (each a record `LINE_FLAG | rank`, in
/// sweep order, its [`ConstraintVertex`] queued in [`Records`]).
pub(crate) struct WithLines<'a> {
    points: &'a mut Merge,
    lines: Option<LineFeed>,
    next_point: Option<SortRecord>,
    next_line: Option<SortRecord>,
    head: Option<Half>,
    rank: u64,
    records: Records,
    far: FarTally,
    error: Option<Error>,
}

impl<'a> WithLines<'a> {
    /// `points` with the vertices of `lines` (if any); `points_z` is the points' range of
    /// heights, for the far-heights warning.
    pub(crate) fn new(
        points: &'a mut Merge,
        mut lines: Option<LineFeed>,
        points_z: [f64; 2],
    ) -> Self {
        let head = lines.as_mut().and_then(|l| l.halves.next());
        let next_point = points.next();
        let mut w = WithLines {
            points,
            lines,
            next_point,
            next_line: None,
            head,
            rank: 0,
            records: Records::default(),
            far: FarTally::new(points_z),
            error: None,
        };
        w.next_line = w.line_vertex();
        w
    }

    /// The queue of records (shared with the caller, which takes one per line vertex).
    pub(crate) fn records(&self) -> Records {
        Rc::clone(&self.records)
    }

    /// The next line vertex from the half-edges: its point record (its record queued).
    fn line_vertex(&mut self) -> Option<SortRecord> {
        let first = self.head.take()?;
        let halves = &mut self.lines.as_mut()?.halves;
        let mut rec = ConstraintVertex {
            xy: first.at,
            ..ConstraintVertex::default()
        };
        let mut h = Some(first);
        while let Some(x) = h.filter(|x| x.at == first.at) {
            match x.kind {
                LOWER => rec.lower.push(x.other),
                UPPER => rec.upper.push(x.other),
                _ => {}
            }
            h = halves.next();
        }
        self.head = h;
        if self.rank >= u64::from(crate::sweep::NO_CONSTRAINT) {
            self.error = Some(Error::Options(format!(
                "the breaklines have more than {} vertices after cleaning, more than one run \
                 can take: split the lines into parts and run them as tiles (`sweeptin plan`)",
                crate::sweep::NO_CONSTRAINT - 1
            )));
            return None;
        }
        let index = super::lines::LINE_FLAG | self.rank;
        self.rank += 1;
        let mut z = first.z;
        if z.is_nan()
            && let Some(h) = self.lines.as_mut()?.heights.remove(&pos_key(first.at))
        {
            z = h;
        }
        self.far.add(z);
        self.records.borrow_mut().push_back(rec);
        Some(SortRecord {
            x: first.at[0],
            y: first.at[1],
            z,
            index,
        })
    }

    /// The error that cut either stream short, and what the line vertices' heights warn of.
    pub(crate) fn finish(mut self) -> Result<Option<super::lines::FarHeights>> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        if let Some(e) = self.points.take_error() {
            return Err(e);
        }
        if let Some(e) = self.lines.as_mut().and_then(|l| l.halves.take_error()) {
            return Err(e);
        }
        Ok(self.far.finish())
    }
}

impl Iterator for WithLines<'_> {
    type Item = SortRecord;
    fn next(&mut self) -> Option<SortRecord> {
        let take_line = match (&self.next_point, &self.next_line) {
            (None, None) => return None,
            (Some(_), None) => false,
            (None, Some(_)) => true,
            (Some(p), Some(l)) => sweep_order(l, p) == Ordering::Less,
        };
        if take_line {
            let r = self.next_line.take();
            self.next_line = self.line_vertex();
            r
        } else {
            let r = self.next_point.take();
            self.next_point = self.points.next();
            r
        }
    }
}

#[cfg(test)]
mod tests;
