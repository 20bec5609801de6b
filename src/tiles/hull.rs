//! The convex hull of all the points, whose corners every tile's run holds (so that a run's hull
//! is the whole hull). They are real input points, so adding them to a run never changes a
//! certified triangle.

use super::index::BlockIndex;
use crate::error::Result;
use crate::geom::predicates::{Orientation, on_segment, orient};
use crate::idmap::FastSet;

fn xy(p: &[f64; 3]) -> [f64; 2] {
    [p[0], p[1]]
}

/// Andrew's monotone chain over `p` sorted lexicographically in some frame; `turn` is the
/// orientation a kept triple must have (counter-clockwise for an `(x, y)` order, clockwise for a
/// `(y, x)` order, which is a mirror image). Collinear points are left out.
fn chain(p: &[[f64; 3]], turn: Orientation) -> Vec<[f64; 3]> {
    let mut h: Vec<[f64; 3]> = Vec::new();
    for pass in 0..2 {
        let base = h.len();
        let it: Box<dyn Iterator<Item = &[f64; 3]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for q in it {
            while h.len() >= base + 2
                && orient(xy(&h[h.len() - 2]), xy(&h[h.len() - 1]), xy(q)) != turn
            {
                h.pop();
            }
            h.push(*q);
        }
        h.pop();
    }
    h
}

/// Points below which [`inner_box`] is not looked for (sorting them costs less).
const FILTER_FROM: usize = 1024;

/// A box strictly inside the convex hull of the points `v` (Akl and Toussaint's filter: the
/// hull of the extreme points in eight directions, then a box a little inside the points'
/// bounding box whose corners lie strictly inside that octagon, tested exactly). Points in
/// the box are inside the hull and none of them is a corner: they need not be sorted. The
/// extremes are chosen in floating point, but they are input points, so their hull lies in
/// the points' hull whatever was chosen.
fn inner_box(v: &[[f64; 3]]) -> Option<[f64; 4]> {
    if v.len() < FILTER_FROM {
        return None;
    }
    const DIRS: [[f64; 2]; 8] =
        [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]];
    let mut best = [(f64::NEG_INFINITY, [0.0; 3]); 8];
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in v {
        for (b, d) in best.iter_mut().zip(DIRS) {
            let s = d[0] * p[0] + d[1] * p[1];
            if s > b.0 {
                *b = (s, *p);
            }
        }
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    // Every direction found a point (no sum overflowed), and the box is finite.
    if !(lo[0].is_finite() && lo[1].is_finite() && hi[0].is_finite() && hi[1].is_finite())
        || best.iter().any(|b| !b.0.is_finite())
    {
        return None;
    }
    let mut ext: Vec<[f64; 3]> = best.iter().map(|b| b.1).collect();
    let octagon = sorted_hull(&mut ext);
    if octagon.len() < 3 {
        return None;
    }
    let strictly_in = |q: [f64; 2]| {
        (0..octagon.len()).all(|i| {
            orient(xy(&octagon[i]), xy(&octagon[(i + 1) % octagon.len()]), q)
                == Orientation::CounterClockwise
        })
    };
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    [1.0 / 64.0, 1.0 / 16.0, 1.0 / 4.0].into_iter().find_map(|s| {
        let b = [lo[0] + s * w, lo[1] + s * h, hi[0] - s * w, hi[1] - s * h];
        (b[0] < b[2]
            && b[1] < b[3]
            && [[b[0], b[1]], [b[2], b[1]], [b[2], b[3]], [b[0], b[3]]].into_iter().all(strictly_in))
        .then_some(b)
    })
}

/// Is `p` outside the closed box `b` (or is there no box)?
fn outside(b: Option<&[f64; 4]>, p: &[f64; 3]) -> bool {
    b.is_none_or(|b| !(p[0] >= b[0] && p[0] <= b[2] && p[1] >= b[1] && p[1] <= b[3]))
}

/// The corners of the convex hull of `v` (any order, duplicates allowed), counter-clockwise.
/// `v` is reordered: the points that may be corners first, sorted.
pub(crate) fn hull(v: &mut [[f64; 3]]) -> Vec<[f64; 3]> {
    let b = inner_box(v);
    let mut k = 0;
    for i in 0..v.len() {
        if outside(b.as_ref(), &v[i]) {
            v.swap(i, k);
            k += 1;
        }
    }
    sorted_hull(&mut v[..k])
}

/// [`hull`] of points it may not reorder: only the points that may be corners are copied.
pub(crate) fn hull_of(v: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let b = inner_box(v);
    let mut w: Vec<[f64; 3]> = v.iter().filter(|p| outside(b.as_ref(), p)).copied().collect();
    sorted_hull(&mut w)
}

/// [`hull`] without the filter: sorts all of `v`.
fn sorted_hull(v: &mut [[f64; 3]]) -> Vec<[f64; 3]> {
    v.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let mut d: Vec<[f64; 3]> = Vec::with_capacity(v.len());
    for p in v.iter() {
        if d.last().is_none_or(|q| q[0] != p[0] || q[1] != p[1]) {
            d.push(*p);
        }
    }
    if d.len() < 3 {
        return d;
    }
    chain(&d, Orientation::CounterClockwise)
}

/// The number of distinct positions of the points on the boundary of their convex hull: its
/// corners, and the points exactly on its edges (exact orientation), found in the blocks along
/// each edge (rows of blocks, the edge's span in each a block wider on either side). A
/// triangulation of `V` distinct points of which `B` lie there has `2V − B − 2` triangles.
///
/// # Errors
/// Reading the index.
pub(crate) fn boundary_points(index: &BlockIndex) -> Result<u64> {
    let h = index.hull();
    let n = h.len();
    if n < 3 {
        // All on a line: no triangle, and no polygon to walk.
        return Ok(n as u64);
    }
    let g = index.grid;
    let mut on: FastSet<(u64, u64)> = FastSet::default();
    let mut pts = Vec::new();
    for i in 0..n {
        let (a, b) = (xy(&h[i]), xy(&h[(i + 1) % n]));
        let (ylo, yhi) = (a[1].min(b[1]), a[1].max(b[1]));
        for by in g.block_of(a[0], ylo).1 - 1..=g.block_of(a[0], yhi).1 + 1 {
            let [x0, x1] = span(a, b, by as f64 * g.block, (by + 1) as f64 * g.block);
            let (bx0, bx1) = (g.block_of(x0, ylo).0 - 1, g.block_of(x1, ylo).0 + 1);
            for &k in index.keys_in_row(by, bx0, bx1 + 1) {
                pts.clear();
                index.read_block(k, &mut pts)?;
                for p in &pts {
                    let q = xy(p);
                    if q != a && q != b && on_segment(a, b, q) {
                        on.insert(((q[0] + 0.0).to_bits(), (q[1] + 0.0).to_bits())); // -0 is 0
                    }
                }
            }
        }
    }
    Ok((n + on.len()) as u64)
}

/// The `x` range of the segment `a b` over `y0 ..= y1` (clamped to the segment; a little wide).
fn span(a: [f64; 2], b: [f64; 2], y0: f64, y1: f64) -> [f64; 2] {
    let (xlo, xhi) = (a[0].min(b[0]), a[0].max(b[0]));
    if a[1] == b[1] {
        return [xlo, xhi];
    }
    let at = |y: f64| {
        let t = ((y - a[1]) / (b[1] - a[1])).clamp(0.0, 1.0);
        a[0] + t * (b[0] - a[0])
    };
    let (p, q) = (at(y0), at(y1));
    [p.min(q).max(xlo), p.max(q).min(xhi)]
}


/// Sorts `pts` (`(x, y, z, global index)`) by position and keeps at each position only the
/// point the duplicate `policy` keeps (the block index's rule): the streamed hull's points and
/// the plan's hull band.
pub(crate) fn keep_preferred(pts: &mut Vec<([f64; 3], u64)>, policy: crate::DuplicatePolicy) {
    pts.sort_unstable_by(|a, b| {
        (a.0[0].total_cmp(&b.0[0]))
            .then(a.0[1].total_cmp(&b.0[1]))
            .then_with(|| {
                if policy.prefers((a.0[2], a.1), (b.0[2], b.1)) {
                    std::cmp::Ordering::Less
                } else if policy.prefers((b.0[2], b.1), (a.0[2], a.1)) {
                    std::cmp::Ordering::Greater
                } else {
                    std::cmp::Ordering::Equal
                }
            })
    });
    pts.dedup_by(|b, a| a.0[0] == b.0[0] && a.0[1] == b.0[1]);
}

/// The corners of the convex hull of points streamed by, each with the height the duplicate
/// policy keeps among the points at its position (as [`super::index::BlockIndex`]'s hull):
/// points are buffered and folded into the corners a batch at a time.
#[derive(Debug, Clone)]
pub(crate) struct HullBuilder {
    policy: crate::DuplicatePolicy,
    /// Corners so far and the points since, as `(x, y, z, global index)`.
    pts: Vec<([f64; 3], u64)>,
    corners: usize,
}

/// Points buffered before they are folded into the corners.
const HULL_BATCH: usize = 1 << 16;

impl HullBuilder {
    pub(crate) fn new(policy: crate::DuplicatePolicy) -> Self {
        HullBuilder {
            policy,
            pts: Vec::new(),
            corners: 0,
        }
    }

    /// Adds the point `p` of global input index `index`.
    pub(crate) fn add(&mut self, p: [f64; 3], index: u64) {
        self.pts.push((p, index));
        if self.pts.len() >= self.corners + HULL_BATCH {
            self.fold();
        }
    }

    fn fold(&mut self) {
        keep_preferred(&mut self.pts, self.policy);
        let mut v: Vec<[f64; 3]> = self.pts.iter().map(|p| p.0).collect();
        let h = hull(&mut v);
        let keep: Vec<([f64; 3], u64)> = h
            .iter()
            .map(|c| {
                let i = self
                    .pts
                    .binary_search_by(|p| {
                        p.0[0].total_cmp(&c[0]).then(p.0[1].total_cmp(&c[1]))
                    })
                    .unwrap_or(0);
                self.pts[i]
            })
            .collect();
        self.corners = keep.len();
        self.pts = keep;
    }

    /// The corners, counter-clockwise.
    pub(crate) fn finish(mut self) -> Vec<[f64; 3]> {
        self.fold();
        self.pts.into_iter().map(|p| p.0).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_grid() {
        let mut v = vec![];
        for y in 0..4 {
            for x in 0..4 {
                v.push([x as f64, y as f64, 0.0]);
            }
        }
        v.push([1.5, 1.7, 0.0]);
        v.sort_by(|a, b| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0])));
        let square = vec![[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]];
        let from_origin = |mut h: Vec<[f64; 2]>| {
            let i = h.iter().position(|p| *p == [0.0, 0.0]).unwrap();
            h.rotate_left(i);
            h
        };
        let h = hull(&mut v.clone());
        assert_eq!(from_origin(h.iter().map(xy).collect()), square);
    }

    /// The filtered hull is the hull of all the points sorted (corners, order and start), on
    /// shapes where the box is found and where it is not: a disc, a rotated lattice, a thin
    /// slanted strip, a line, two far clusters, at UTM-sized offsets, with duplicates.
    #[test]
    fn the_inner_box_leaves_the_hull_as_it_is() {
        let mut rng = crate::geom::rng::SplitMix64::new(11);
        type Shape = fn(f64, f64) -> Option<[f64; 2]>;
        let shapes: [Shape; 5] = [
            |u, v| ((u - 0.5).powi(2) + (v - 0.5).powi(2) <= 0.25).then_some([u, v]),
            |u, v| Some([0.6 * u - 0.8 * v, 0.8 * u + 0.6 * v]),
            |u, v| Some([u, 0.3 * u + 0.001 * v]),
            |u, _| Some([u, 2.0 * u]),
            |u, v| Some(if u < 0.5 { [u * 0.01, v * 0.01] } else { [100.0 + u * 0.01, 50.0 + v * 0.01] }),
        ];
        for (s, shape) in shapes.iter().enumerate() {
            for n in [1000, 1100, 20_000] {
                let mut v = Vec::new();
                while v.len() < n {
                    let (u, w) = (rng.below(1 << 20) as f64 / (1 << 20) as f64, rng.below(1 << 20) as f64 / (1 << 20) as f64);
                    if let Some(q) = shape(u, w) {
                        let p = [511_000.0 + q[0] * 1000.0, 122_000.0 + q[1] * 1000.0, rng.below(9) as f64];
                        v.push(p);
                        if rng.below(50) == 0 {
                            v.push(p);
                        }
                    }
                }
                let want = sorted_hull(&mut v.clone());
                assert_eq!(hull_of(&v).iter().map(xy).collect::<Vec<_>>(), want.iter().map(xy).collect::<Vec<_>>(), "shape {s}, {n}");
                assert_eq!(hull(&mut v).iter().map(xy).collect::<Vec<_>>(), want.iter().map(xy).collect::<Vec<_>>(), "shape {s}, {n}");
            }
        }
        // The box is found on a filled square, and the lattice's corners are the hull.
        let mut g: Vec<[f64; 3]> = (0..10_000).map(|i| [(i % 100) as f64, (i / 100) as f64, 0.0]).collect();
        assert!(inner_box(&g).is_some());
        assert_eq!(hull(&mut g).len(), 4);
    }

    /// The streamed hull is the hull of all the points, a batch at a time, each corner with
    /// the height the duplicate policy keeps there.
    #[test]
    fn a_streamed_hull_is_the_hull_with_the_policys_heights() {
        let mut rng = crate::geom::rng::SplitMix64::new(7);
        let mut pts = Vec::new();
        for i in 0..200_000u64 {
            let p = [
                511_000.0 + rng.below(1000) as f64 * 0.25,
                122_000.0 + rng.below(700) as f64 * 0.25,
                rng.below(100) as f64,
            ];
            pts.push((p, i));
        }
        // Every corner of the square's lattice duplicated, with heights above and below.
        for (k, c) in [[511_000.0, 122_000.0], [511_249.75, 122_174.75]].iter().enumerate() {
            pts.push(([c[0], c[1], -5.0], 300_000 + k as u64));
            pts.push(([c[0], c[1], 500.0], 400_000 + k as u64));
        }
        let want = hull(&mut pts.iter().map(|p| p.0).collect::<Vec<_>>());
        for policy in [crate::DuplicatePolicy::First, crate::DuplicatePolicy::Lowest] {
            let mut b = HullBuilder::new(policy);
            for &(p, i) in &pts {
                b.add(p, i);
            }
            let got = b.finish();
            assert_eq!(got.len(), want.len());
            for c in &got {
                let keep = pts
                    .iter()
                    .filter(|p| p.0[0] == c[0] && p.0[1] == c[1])
                    .reduce(|k, p| if policy.prefers((p.0[2], p.1), (k.0[2], k.1)) { p } else { k })
                    .unwrap();
                assert_eq!(c[2], keep.0[2], "{policy:?} at {c:?}");
                assert!(want.iter().any(|w| w[0] == c[0] && w[1] == c[1]));
            }
        }
    }

    /// `2V − B − 2` with [`boundary_points`] is spade's number of triangles: points on a lattice
    /// in a triangle, a rotated square and a strip (many on slanted hull edges), with duplicates,
    /// at UTM-sized offsets, the index spilled to disk.
    #[test]
    fn euler_with_the_boundary_points_counts_spades_triangles() {
        use spade::{DelaunayTriangulation, Point2, Triangulation as _};
        let dir = tempfile::tempdir().unwrap();
        let mut rng = crate::geom::rng::SplitMix64::new(3);
        type Shape = fn(i64, i64) -> bool;
        let shapes: [Shape; 3] = [
            |x, y| x + y <= 40,
            |x, y| (x - 20).abs() + (y - 20).abs() <= 17,
            |x, y| (y - x / 3).abs() <= 2,
        ];
        for (s, inside) in shapes.iter().enumerate() {
            let mut pts = Vec::new();
            for y in 0..=40i64 {
                for x in 0..=40i64 {
                    if inside(x, y) && rng.below(3) > 0 {
                        let p = [511_000.0 + x as f64 * 0.5, 122_000.0 + y as f64 * 0.5, 0.0];
                        pts.push(p);
                        if rng.below(10) == 0 {
                            pts.push([p[0], p[1], 1.0]);
                        }
                    }
                }
            }
            let grid = crate::tiles::grid::TileGrid::new(2.0, 1).unwrap();
            let index = crate::tiles::index::index(1, &pts, grid, dir.path());
            let mut t = DelaunayTriangulation::<Point2<f64>>::new();
            for p in &pts {
                t.insert(Point2::new(p[0], p[1])).unwrap();
            }
            let v = t.num_vertices() as u64;
            let b = boundary_points(&index).unwrap();
            assert_eq!(2 * v - b - 2, t.num_inner_faces() as u64, "shape {s}: {v} points, {b} on the hull");
        }
    }
}
