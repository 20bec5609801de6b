//! Rules 4–6 of the [cleaner](super), the exact tests: candidate pairs from the grid, and for each
//! pair whether a vertex lies on a segment, two collinear segments overlap, or two segments cross
//! (and where).

use super::{Work, lex};
use crate::geom::grid::Buckets;
use crate::geom::predicates::{Orientation, orient, orient_det};
use rayon::prelude::*;
use std::cmp::Ordering;

/// What one candidate pair gave.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PairResult {
    /// Up to two `(segment, vertex)` splits (rule 4/5).
    pub(super) splits: [(u32, u32); 2],
    pub(super) n_splits: u8,
    pub(super) overlap: bool,
    /// A proper crossing of the two segments, at this point.
    pub(super) cross: Option<[f64; 2]>,
}

/// A round's findings: each candidate pair's non-empty result, in pair order.
pub(super) type Found = Vec<([u32; 2], PairResult)>;

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
    /// Tests every candidate pair that involves a dirty item; returns the non-empty results in
    /// pair order.
    pub(super) fn find(&self, first_round: bool) -> Found {
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
        let mut found: Found = (0..self.grid.len() as u32)
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
            .collect();
        // In pair order, not the grid's: what a round does with its findings (the order in which
        // vertices on lines take their z) then depends on the graph alone, so a plane sweep that
        // finds the same pairs in another order gives the same graph.
        found.par_sort_unstable_by_key(|f| f.0);
        found
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
    pub(super) fn p(&self, v: u32) -> [f64; 2] {
        self.xy[v as usize]
    }

    /// Isolated vertex `v` against segment `s`.
    fn test_point(&self, s: u32, v: u32) -> PairResult {
        let [a, b] = self.segs[s as usize];
        let mut r = PairResult::default();
        if point_on(self.p(a), self.p(b), self.p(v)) {
            r.split(s, v);
        }
        r
    }

    /// Segments `s` and `t` (rules 4–6).
    fn test_pair(&self, s: u32, t: u32) -> PairResult {
        let [a, b] = self.segs[s as usize];
        let [c, d] = self.segs[t as usize];
        let ends = [a, b, c, d];
        let k = contact([self.p(a), self.p(b), self.p(c), self.p(d)]);
        let mut r = PairResult {
            overlap: k.overlap,
            cross: k.cross,
            ..PairResult::default()
        };
        for &(seg, end) in &k.splits[..k.n_splits as usize] {
            r.split(if seg == 0 { s } else { t }, ends[end as usize]);
        }
        r
    }
}

/// Is the isolated vertex `v` on the interior of the segment `ab` (rule 4)?
#[inline]
pub(super) fn point_on(a: [f64; 2], b: [f64; 2], v: [f64; 2]) -> bool {
    orient(a, b, v) == Orientation::Collinear && strictly_between(a, b, v)
}

/// What two segments of a graph with distinct vertex positions, `ab` (segment 0) and `cd`
/// (segment 1), do to each other (rules 4–6): every decision exact. Splits name the segment
/// (0 or 1) and the end (0..4 for `a, b, c, d`) lying on its interior.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Contact {
    pub(super) splits: [(u8, u8); 2],
    pub(super) n_splits: u8,
    pub(super) overlap: bool,
    pub(super) cross: Option<[f64; 2]>,
}

impl Contact {
    fn split(&mut self, seg: u8, end: u8) {
        self.splits[self.n_splits as usize] = (seg, end);
        self.n_splits += 1;
    }

    pub(super) fn is_empty(&self) -> bool {
        self.n_splits == 0 && self.cross.is_none()
    }
}

/// The exact contact of segments `p[0] p[1]` and `p[2] p[3]` (see [`Contact`]); ends at the same
/// position are the same vertex.
pub(super) fn contact(p: [[f64; 2]; 4]) -> Contact {
    let [pa, pb, pc, pd] = p;
    let mut r = Contact::default();
    // A shared end: they can only overlap along a common line.
    let shared = if pa == pc || pa == pd {
        Some((0, 1, if pa == pc { 3 } else { 2 }))
    } else if pb == pc || pb == pd {
        Some((1, 0, if pb == pc { 3 } else { 2 }))
    } else {
        None
    };
    if let Some((v, q0, q1)) = shared {
        let (pv, pp, pq) = (p[v], p[q0], p[q1]);
        if orient(pv, pp, pq) == Orientation::Collinear && same_direction(pv, pp, pq) {
            r.overlap = true;
            if strictly_between(pv, pp, pq) {
                r.split(0, q1 as u8);
            } else {
                r.split(1, q0 as u8);
            }
        }
        return r;
    }
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
        for (seg, e0, e1, v) in [
            (0, pa, pb, 2),
            (0, pa, pb, 3),
            (1, pc, pd, 0),
            (1, pc, pd, 1),
        ] {
            if strictly_between(e0, e1, p[v as usize]) {
                r.split(seg, v);
            }
        }
        r.overlap = r.n_splits > 0;
        return r;
    }
    // At most one end lies on the other segment's line (two would be the same point).
    if oc == col {
        r.split(0, 2);
    } else if od == col {
        r.split(0, 3);
    } else if oa == col {
        r.split(1, 0);
    } else if ob == col {
        r.split(1, 1);
    } else {
        r.cross = Some(crossing_point(pa, pb, pc, pd));
    }
    r
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

/// Where the segments `ab` and `cd` cross (they do, properly), from the adaptive determinants, in
/// a canonical order of segments and ends, clamped into both bounding boxes.
pub(super) fn crossing_point(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> [f64; 2] {
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
