//! Rules 1–3 of the [cleaner](super::super) streamed: the input checked, exact duplicate
//! vertices merged (first known `z` wins, in input order), zero-length segments dropped and
//! duplicate segments merged, with external sorts instead of the arrays of `dedup.rs`:
//!
//! 1. every input vertex, with its place `g` in the input, sorted by position: each run of
//!    equal positions is one vertex, named by its first `g` (which orders vertices as `clean()`
//!    numbers them), its `z` the first known one;
//! 2. the same records, now carrying their vertex, sorted back by `g` and read beside the
//!    polylines: consecutive vertices make the segments, sorted by the sweep axis (round 1's
//!    input; duplicates merge as the round reads them);
//! 3. each occurrence, flagged when it is the end of a segment, sorted by position: a vertex
//!    that no segment ends at is an isolated vertex.
//!
//! The polylines are read once, in order, from a [`PolylineSource`] (step 2 finds where each
//! polyline ends from the polyline each record carries), so they are never held.
//!
//! Held: the records of one position (its duplicates), the sorts' budgets.

use super::super::dedup::check_vertex;
use super::super::{CleanOptions, CleanStats, MAX_WARNINGS, SNAP_REL, ZConflict, ZConflictKind};
use super::PolylineSource;
use super::rec::{DIRTY, POINT, Rec, V};
use crate::error::{Error, Result};
use crate::geom::predicates::sweep_cmp;
use crate::sort::external::{ExternalSorter, Merge, SortKey};
use std::cmp::Ordering;
use std::path::Path;

/// Record flag of step 3: the occurrence ends a segment.
const USED: u32 = 4;

/// An input vertex and its place in the input (steps 1 and 2).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct Occ {
    p: [f64; 2],
    z: f64,
    /// Place in the input (over all polylines).
    g: u64,
    /// The vertex (the first `g` at this position), after step 1.
    id: u64,
    /// The polyline of `g`; after step 1, the vertex's.
    line: u32,
    /// Sorted by position (0) or by `g` (1).
    by_g: u32,
    /// The polyline of `g` (steps 1 and 2).
    own: u64,
    pad: u64,
}

impl SortKey for Occ {
    #[inline]
    fn order(a: &Self, b: &Self) -> Ordering {
        if a.by_g != 0 {
            a.g.cmp(&b.g)
        } else {
            sweep_cmp(a.p, b.p).then(a.g.cmp(&b.g))
        }
    }
    const STABLE: bool = false;
}

/// Round 1's input.
pub(super) struct Prepared {
    /// The segments and isolated vertices, sorted (duplicate segments not yet merged).
    pub(super) items: Merge<Rec>,
    /// How many were pushed.
    pub(super) count: u64,
    /// The input counters of rules 1–3 (`duplicate_segments` is counted as round 1 reads).
    pub(super) stats: CleanStats,
    /// Rule 1's height disagreements, the first [`MAX_WARNINGS`] in input order.
    pub(super) warnings: Vec<ZConflict>,
    /// Range of `x` over the vertices.
    pub(super) x: [f64; 2],
    pub(super) snap: f64,
}

/// Rules 1–3 over `polylines` read once in order, within `mem` bytes of sorting; `None` when
/// the heights are mixed (some vertices with `z`, some without).
///
/// # Errors
/// As `clean()`'s input checks (the first bad vertex in input order), the source's and the
/// external sorts'.
pub(super) fn prepare(
    polylines: &(impl PolylineSource + ?Sized),
    options: &CleanOptions,
    mem: u64,
    tmp: &Path,
) -> Result<Option<Prepared>> {
    let budget = (mem / 4).max(1 << 20);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut by_pos = ExternalSorter::<Occ>::new(budget, tmp);
    let (mut g, mut i) = (0u64, 0u64);
    polylines.for_each_polyline(&mut |l| {
        if g + l.len() as u64 >= u64::from(u32::MAX) {
            return Err(Error::TooManyPoints {
                count: g + l.len() as u64,
                max: u64::from(u32::MAX) - 1,
            });
        }
        for (k, v) in l.iter().enumerate() {
            check_vertex(i, k as u64, v)?;
            let p = [v[0] + 0.0, v[1] + 0.0];
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            by_pos.push(Occ {
                p,
                z: v[2],
                g,
                line: i as u32,
                own: i,
                ..Occ::default()
            })?;
            g += 1;
        }
        i += 1;
        Ok(())
    })?;
    let total = g;
    let mut stats = CleanStats {
        input_vertices: total,
        ..CleanStats::default()
    };
    if total == 0 {
        (lo, hi) = ([0.0; 2], [0.0; 2]);
    }
    let mag = lo[0]
        .abs()
        .max(lo[1].abs())
        .max(hi[0].abs())
        .max(hi[1].abs());
    let snap = options.snap.unwrap_or(SNAP_REL * mag).max(0.0);
    // Step 1: one vertex per position.
    let mut by_g = ExternalSorter::<Occ>::new(budget, tmp);
    let mut warnings: Vec<(u64, ZConflict)> = Vec::new();
    let (mut known, mut vertices) = (0u64, 0u64);
    let mut merge = by_pos.finish()?;
    let mut group: Vec<Occ> = Vec::new();
    let mut flush = |group: &mut Vec<Occ>, stats: &mut CleanStats| -> Result<()> {
        let Some(first) = group.first().copied() else {
            return Ok(());
        };
        let mut kept = first.z;
        for o in &group[1..] {
            stats.merged_vertices += 1;
            if kept.is_nan() {
                kept = o.z;
            } else if (o.z - kept).abs() > options.z_tolerance {
                stats.z_conflicts += 1;
                warnings.push((
                    o.g,
                    ZConflict {
                        at: first.p,
                        z: [kept, o.z],
                        kind: ZConflictKind::Duplicate,
                        lines: [first.line, o.line],
                    },
                ));
                if warnings.len() >= 2 * MAX_WARNINGS {
                    warnings.sort_by_key(|w| w.0);
                    warnings.truncate(MAX_WARNINGS);
                }
            }
        }
        vertices += 1;
        known += u64::from(!kept.is_nan());
        for o in group.drain(..) {
            by_g.push(Occ {
                z: kept,
                id: first.g,
                line: first.line,
                by_g: 1,
                ..o
            })?;
        }
        Ok(())
    };
    for o in merge.by_ref() {
        if group.first().is_some_and(|f| f.p != o.p) {
            flush(&mut group, &mut stats)?;
        }
        group.push(o);
    }
    flush(&mut group, &mut stats)?;
    if let Some(e) = merge.take_error() {
        return Err(e);
    }
    drop(merge);
    if known != 0 && known != vertices {
        return Ok(None);
    }
    warnings.sort_by_key(|w| w.0);
    warnings.truncate(MAX_WARNINGS);
    // Step 2: the segments, the records in input order (a polyline ends where `own` changes).
    let mut items = ExternalSorter::<Rec>::new(budget, tmp);
    let mut ends = ExternalSorter::<Rec>::new(budget, tmp);
    let mut merge = by_g.finish()?;
    let mut count = 0u64;
    let mut prev: Option<(V, bool, u64)> = None;
    let mut read = 0u64;
    for o in merge.by_ref() {
        read += 1;
        let v = V {
            p: o.p,
            z: o.z,
            round: 0,
            id: o.id,
            vline: o.line,
        };
        let mut used = false;
        match prev {
            Some((u, u_used, line)) if line == o.own => {
                stats.input_segments += 1;
                let joined = u.id != v.id;
                if joined {
                    items.push(Rec::new(u, v, o.own as u32, DIRTY))?;
                    count += 1;
                } else {
                    stats.zero_length += 1;
                }
                used = joined;
                ends.push(occurrence(u, u_used || joined))?;
            }
            Some((u, u_used, _)) => ends.push(occurrence(u, u_used))?,
            None => {}
        }
        prev = Some((v, used, o.own));
    }
    if let Some((u, used, _)) = prev {
        ends.push(occurrence(u, used))?;
    }
    if let Some(e) = merge.take_error() {
        return Err(e);
    }
    if read != total {
        return Err(Error::Internal("breakline vertices lost in sorting".into()));
    }
    drop(merge);
    // Step 3: vertices no segment ends at.
    let mut merge = ends.finish()?;
    let mut cur: Option<(Rec, bool)> = None;
    for r in merge.by_ref() {
        match &mut cur {
            Some((c, used)) if c.lo == r.lo => *used |= r.flags & USED != 0,
            _ => {
                if let Some((c, false)) = cur.take() {
                    items.push(c)?;
                    count += 1;
                }
                cur = Some((r, r.flags & USED != 0));
            }
        }
    }
    if let Some((c, false)) = cur.take() {
        items.push(c)?;
        count += 1;
    }
    if let Some(e) = merge.take_error() {
        return Err(e);
    }
    Ok(Some(Prepared {
        items: items.finish()?,
        count,
        stats,
        warnings: warnings.into_iter().map(|w| w.1).collect(),
        x: [lo[0], hi[0]],
        snap,
    }))
}

/// An occurrence of `v` for step 3, as the isolated vertex it may be.
fn occurrence(v: V, used: bool) -> Rec {
    let mut r = Rec::new(v, v, 0, POINT | DIRTY);
    if used {
        r.flags |= USED;
    }
    r
}
