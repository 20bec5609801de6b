//! Turning raw input points into the sweep's vertex table.
//!
//! [`prepare`] validates every coordinate (finite, in the predicates' exact range), moves the
//! points into a local frame when that can be done without rounding, sorts them into sweep order
//! (by `y`, then `x`) with rayon, and merges exact `(x, y)` duplicates by a [`DuplicatePolicy`].
//! The result depends only on the input, never on the thread count.

use crate::error::{Error, Result};
use crate::geom::exact::exact_diff;
use crate::geom::predicates::{self, FIRST_REAL};

/// Which point survives when several share exactly the same `(x, y)`.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum DuplicatePolicy {
    /// The one that comes first in the input.
    #[default]
    First,
    /// The one that comes last in the input.
    Last,
    /// The one with the lowest `z` (first in input order among equals).
    Lowest,
    /// The one with the highest `z` (first in input order among equals).
    Highest,
}

impl DuplicatePolicy {
    /// Does candidate `(z, index)` beat the current keeper `(z, index)`?
    #[inline]
    pub fn prefers(self, cand: (f64, u64), keep: (f64, u64)) -> bool {
        match self {
            DuplicatePolicy::First => cand.1 < keep.1,
            DuplicatePolicy::Last => cand.1 > keep.1,
            DuplicatePolicy::Lowest => cand.0 < keep.0 || (cand.0 == keep.0 && cand.1 < keep.1),
            DuplicatePolicy::Highest => cand.0 > keep.0 || (cand.0 == keep.0 && cand.1 < keep.1),
        }
    }
}

/// Points in sweep order, ready for the sweep.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Vertex table indexed by vertex id: two placeholder rows for the artificial points, then the
    /// distinct points in sweep order, in the local frame.
    pub xy: Vec<[f64; 2]>,
    /// For each real vertex (`xy[i + 2]`), the index of the input point it came from.
    pub index: Vec<u32>,
    /// The local origin that was subtracted (exactly) from every input coordinate.
    pub origin: [f64; 2],
    /// Number of input points.
    pub total: u64,
    /// Number of input points merged away as exact `(x, y)` duplicates.
    pub duplicates: u64,
}

impl Prepared {
    /// Number of distinct points.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// No points at all?
    #[cfg(any(test, feature = "dev"))]
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }
}

/// Largest number of points the in-memory core accepts: half-edge ids use 30 bits, and `n`
/// points make at most `6n - 15` half-edges (the mesh's `MAX_VERTICES`, equal by a test; written
/// out here because the mesh keeps its arrays in this module's [`crate::sort::mmap::SpillVec`]).
pub const MAX_POINTS: u64 = (1 << 30) / 6 - 4;

/// A point in sort order: `key` (the order keys of `y` and `x`) and `idx` compare as `(y, x,
/// input index)` by `f64::total_cmp` (see [`order_key`]), so the bucket sorts compare integers:
/// one 128-bit comparison for the position (24 bytes: a `u128` field would align to 32).
#[derive(Clone, Copy, PartialEq, Eq)]
struct Rec {
    key: [u64; 2],
    idx: u32,
}

impl Rec {
    fn new(x: f64, y: f64, idx: u32) -> Rec {
        Rec {
            key: [order_key(y), order_key(x)],
            idx,
        }
    }

    #[inline(always)]
    fn position(&self) -> u128 {
        u128::from(self.key[0]) << 64 | u128::from(self.key[1])
    }

    fn x(&self) -> f64 {
        from_order_key(self.key[1])
    }

    fn y(&self) -> f64 {
        from_order_key(self.key[0])
    }
}

impl Ord for Rec {
    #[inline(always)]
    fn cmp(&self, other: &Rec) -> std::cmp::Ordering {
        (self.position(), self.idx).cmp(&(other.position(), other.idx))
    }
}

impl PartialOrd for Rec {
    fn partial_cmp(&self, other: &Rec) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

/// The bits of `v` as an integer in the order of `f64::total_cmp` (negative values with every bit
/// flipped, the others with the sign bit set).
#[inline(always)]
fn order_key(v: f64) -> u64 {
    let b = v.to_bits();
    if b >> 63 == 1 { !b } else { b | 1 << 63 }
}

/// The inverse of [`order_key`].
#[inline(always)]
fn from_order_key(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

/// Validates, sorts and de-duplicates `points` (`[x, y, z]`).
///
/// # Errors
/// [`Error::NonFinite`] or [`Error::CoordinateOutOfRange`] naming the first bad point,
/// [`Error::TooManyPoints`] beyond [`MAX_POINTS`].
pub fn prepare(points: &[[f64; 3]], policy: DuplicatePolicy) -> Result<Prepared> {
    let total = points.len() as u64;
    if total > MAX_POINTS {
        return Err(Error::TooManyPoints {
            count: total,
            max: MAX_POINTS,
        });
    }
    let (origin, y_range) = choose_origin(points)?;
    let recs = sort_local(points, origin, y_range)?;
    let (xy, index) = dedupe(&recs, points, policy);
    let duplicates = total - index.len() as u64;
    Ok(Prepared {
        xy,
        index,
        origin,
        total,
        duplicates,
    })
}

/// The bounding box's lower-left corner, if subtracting it is exact for every point; otherwise the
/// true origin (the predicates are exact either way; a local frame keeps the magnitudes small).
/// Also returns the input's y range.
fn choose_origin(points: &[[f64; 3]]) -> Result<([f64; 2], (f64, f64))> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi_y = f64::NEG_INFINITY;
    for (i, p) in points.iter().enumerate() {
        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
            return Err(Error::NonFinite {
                index: i as u64,
                x: p[0],
                y: p[1],
                z: p[2],
            });
        }
        lo[0] = lo[0].min(p[0]);
        lo[1] = lo[1].min(p[1]);
        hi_y = hi_y.max(p[1]);
    }
    if points.is_empty() {
        return Ok(([0.0; 2], (0.0, 0.0)));
    }
    let exact = points
        .iter()
        .all(|p| exact_diff(p[0], lo[0]) && exact_diff(p[1], lo[1]));
    Ok((if exact { lo } else { [0.0; 2] }, (lo[1], hi_y)))
}

/// Moves the points into the local frame (checking the range) and sorts them into sweep order:
/// a counting sort into about n/8 buckets by `y` (at most 2²²), then an exact sort of each bucket
/// (in parallel for large inputs).
/// Bucketing is monotone in `y`, so the result is exactly the order by `(y, x, input index)`.
fn sort_local(points: &[[f64; 3]], origin: [f64; 2], y_range: (f64, f64)) -> Result<Vec<Rec>> {
    let n = points.len();
    let nb = (n / 8).clamp(1, 1 << 22);
    let base = y_range.0 - origin[1];
    let span = y_range.1 - y_range.0;
    let scale = if span > 0.0 && span.is_finite() {
        nb as f64 / span
    } else {
        0.0
    };
    let bucket = |y: f64| (((y - base) * scale) as usize).min(nb - 1);
    let mut start = vec![0u32; nb + 1];
    for (i, p) in points.iter().enumerate() {
        let (x, y) = local(p, origin);
        for v in [x, y] {
            if !predicates::check_coord(v) {
                return Err(Error::CoordinateOutOfRange {
                    index: i as u64,
                    value: v,
                    max: predicates::MAX_COORD,
                    min: predicates::MIN_NONZERO_COORD,
                });
            }
        }
        start[bucket(y) + 1] += 1;
    }
    for b in 0..nb {
        start[b + 1] += start[b];
    }
    let mut recs = vec![Rec { key: [0; 2], idx: 0 }; n];
    let mut fill = start.clone();
    for (i, p) in points.iter().enumerate() {
        let (x, y) = local(p, origin);
        let b = bucket(y);
        recs[fill[b] as usize] = Rec::new(x, y, i as u32);
        fill[b] += 1;
    }
    drop(fill);
    sort_buckets(&mut recs, &start);
    Ok(recs)
}

/// `p` in the local frame; `+ 0.0` turns -0.0 into +0.0 so both sort as one position.
#[inline(always)]
fn local(p: &[f64; 3], origin: [f64; 2]) -> (f64, f64) {
    ((p[0] - origin[0]) + 0.0, (p[1] - origin[1]) + 0.0)
}

/// Points from which [`sort_buckets`] goes parallel: below, handing the work to rayon costs more
/// than it saves (a tile's run, tens of thousands of points, runs on a worker of its own and the
/// other workers keep the other cores busy).
const PARALLEL_SORT_MIN: usize = 1 << 20;

/// Sorts each bucket `recs[start[b]..start[b + 1]]`, in parallel over groups of buckets for
/// large inputs.
fn sort_buckets(recs: &mut [Rec], start: &[u32]) {
    use rayon::prelude::*;
    if recs.len() < PARALLEL_SORT_MIN {
        for w in start.windows(2) {
            recs[w[0] as usize..w[1] as usize].sort_unstable();
        }
        return;
    }
    let nb = start.len() - 1;
    let groups = 64.min(nb);
    let mut pieces = Vec::with_capacity(groups);
    let mut rest = recs;
    let mut done = 0usize;
    for g in 0..groups {
        let b_end = (g + 1) * nb / groups;
        let end = start[b_end] as usize;
        let (piece, tail) = rest.split_at_mut(end - done);
        pieces.push((piece, &start[g * nb / groups..=b_end], done));
        rest = tail;
        done = end;
    }
    pieces.into_par_iter().for_each(|(piece, bounds, offset)| {
        for w in bounds.windows(2) {
            let (lo, hi) = (w[0] as usize - offset, w[1] as usize - offset);
            piece[lo..hi].sort_unstable();
        }
    });
}

fn dedupe(recs: &[Rec], points: &[[f64; 3]], policy: DuplicatePolicy) -> (Vec<[f64; 2]>, Vec<u32>) {
    let mut xy = Vec::with_capacity(recs.len() + FIRST_REAL as usize);
    xy.push([f64::NAN; 2]);
    xy.push([f64::NAN; 2]);
    let mut index: Vec<u32> = Vec::with_capacity(recs.len());
    let mut prev: Option<(f64, f64)> = None;
    for r in recs {
        let (x, y) = (r.x(), r.y());
        if prev == Some((x, y)) {
            let keep = *index.last().expect("a previous point exists");
            let cand = (points[r.idx as usize][2], r.idx as u64);
            let kept = (points[keep as usize][2], keep as u64);
            if policy.prefers(cand, kept) {
                *index.last_mut().expect("a previous point exists") = r.idx;
            }
            continue;
        }
        prev = Some((x, y));
        xy.push([x, y]);
        index.push(r.idx);
    }
    (xy, index)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_points_is_the_meshs_max_vertices() {
        assert_eq!(MAX_POINTS, crate::mesh::MAX_VERTICES);
    }

    #[test]
    fn records_stay_small() {
        assert_eq!(std::mem::size_of::<Rec>(), 24);
    }

    #[test]
    fn sorts_and_merges_duplicates_by_policy() {
        let pts = [
            [1.0, 1.0, 5.0],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 3.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 9.0],
        ];
        let p = prepare(&pts, DuplicatePolicy::First).unwrap();
        assert_eq!(p.duplicates, 2);
        assert_eq!(p.index, vec![1, 3, 0]);
        assert_eq!(&p.xy[2..], &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]);
        assert_eq!(prepare(&pts, DuplicatePolicy::Last).unwrap().index[2], 4);
        assert_eq!(prepare(&pts, DuplicatePolicy::Lowest).unwrap().index[2], 2);
        assert_eq!(prepare(&pts, DuplicatePolicy::Highest).unwrap().index[2], 4);
    }

    #[test]
    fn order_keys_sort_as_total_cmp() {
        let v = [
            f64::NEG_INFINITY,
            -1e300,
            -2.5,
            -f64::MIN_POSITIVE,
            -0.0,
            0.0,
            f64::MIN_POSITIVE,
            1.0,
            1.0 + f64::EPSILON,
            7e305,
            f64::INFINITY,
        ];
        for a in v {
            assert_eq!(from_order_key(order_key(a)).to_bits(), a.to_bits());
            for b in v {
                assert_eq!(order_key(a).cmp(&order_key(b)), a.total_cmp(&b), "{a} {b}");
            }
        }
    }

    #[test]
    fn negative_zero_is_zero() {
        let pts = [[0.0, 0.0, 1.0], [-0.0, -0.0, 2.0], [1.0, 0.0, 0.0]];
        let p = prepare(&pts, DuplicatePolicy::First).unwrap();
        assert_eq!(p.duplicates, 1);
    }

    #[test]
    fn local_origin_is_exact() {
        let pts = [
            [500_000.125, 4_000_000.5, 1.0],
            [500_001.0, 4_000_002.25, 2.0],
        ];
        let p = prepare(&pts, DuplicatePolicy::First).unwrap();
        assert_eq!(p.origin, [500_000.125, 4_000_000.5]);
        assert_eq!(p.xy[3], [0.875, 1.75]);
    }

    #[test]
    fn names_the_bad_point() {
        let pts = [[0.0, 0.0, 0.0], [1.0, f64::NAN, 0.0]];
        match prepare(&pts, DuplicatePolicy::First) {
            Err(Error::NonFinite { index: 1, .. }) => {}
            other => panic!("{other:?}"),
        }
    }
}
