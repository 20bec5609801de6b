//! Geometry shared by the products.
//!
//! - [`Tri`]: a triangle as the products see it: counter-clockwise and **rotated to a canonical
//!   first vertex** (the smallest by `(x, y)`), so every computation on it gives the same bits
//!   whatever rotation the stream delivered.
//! - [`Tri::locate`]: exact point location (through `geom::predicates::orient`): inside, on an
//!   edge, on a vertex, outside.
//! - [`Tri::value_at`]: linear interpolation that gives **the same bits from every triangle
//!   containing the point**: on an edge the value depends only on the edge's two endpoints (taken
//!   in a canonical order), on a vertex it is the vertex's `z`. So a point on a shared edge gets one
//!   value whichever triangle answers, and products are independent of the order of the stream.
//! - [`Tri::owns`]: the **ownership rule** that gives a point on a shared edge or vertex to exactly
//!   one triangle: the triangle that contains the point moved infinitesimally to the right (+x) and
//!   then infinitesimally up (+y) — the "top-left" rule of rasterisers. Inside a triangulation every
//!   point belongs to exactly one triangle; on the outer boundary of the TIN a point may belong to
//!   none (its perturbed copy lies outside), which is why products that must not leave gaps on the
//!   boundary also accept the closed triangle, with lower priority.
//! - [`clip`] / [`integrate`]: convex polygons carrying a linear value, clipped by a linear function
//!   (a half-plane or a level) and integrated exactly up to rounding.
//! - [`ExactSum`]: the correctly rounded sum of many `f64`s, independent of their order.

use crate::geom::predicates::{Orientation, orient, orient_det};
use std::cmp::Ordering;

/// Where a point lies relative to a triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// Strictly inside.
    Inside,
    /// On the open edge from vertex `i` to vertex `(i + 1) % 3`.
    OnEdge(usize),
    /// On vertex `i`.
    OnVertex(usize),
    /// Outside the closed triangle.
    Outside,
}

/// A triangle for the products: counter-clockwise, first vertex the smallest by `(x, y)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tri {
    /// The vertices `[x, y, z]`.
    pub v: [[f64; 3]; 3],
}

fn xy(p: &[f64; 3]) -> [f64; 2] {
    [p[0], p[1]]
}

/// Lexicographic `(x, y)` order.
pub fn cmp_xy(a: &[f64; 3], b: &[f64; 3]) -> Ordering {
    a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1]))
}

impl Tri {
    /// The canonical form of `t`; `None` if `t` is degenerate (its vertices are collinear) or has a
    /// non-finite coordinate. A clockwise triangle is reversed.
    pub fn new(t: &[[f64; 3]; 3]) -> Option<Tri> {
        if !t.iter().flatten().all(|c| c.is_finite()) {
            return None;
        }
        let mut v = *t;
        match orient(xy(&v[0]), xy(&v[1]), xy(&v[2])) {
            Orientation::CounterClockwise => {}
            Orientation::Clockwise => v.swap(1, 2),
            Orientation::Collinear => return None,
        }
        let first = (0..3)
            .min_by(|&i, &j| cmp_xy(&v[i], &v[j]))
            .expect("three vertices");
        v.rotate_left(first);
        Some(Tri { v })
    }

    /// The canonical form of a triangle known to be counter-clockwise and not degenerate (a
    /// TIN's): [`Tri::new`] without its orientation test.
    pub fn canonical_ccw(mut v: [[f64; 3]; 3]) -> Tri {
        let first = (0..3)
            .min_by(|&i, &j| cmp_xy(&v[i], &v[j]))
            .expect("three vertices");
        v.rotate_left(first);
        Tri { v }
    }

    /// `[xmin, ymin, xmax, ymax]`.
    pub fn bbox(&self) -> [f64; 4] {
        crate::geom::tri_bbox(&self.v)
    }

    /// A closed interval of `x` that holds every point of the triangle on the horizontal line
    /// `y` (when `y` lies within its box), widened by `slack` on each side: a filter for a
    /// raster's cell centres before the exact [`Tri::locate`], which decides. The crossings are
    /// computed in floating point; `slack` (a cell) covers their rounding, so the filter is
    /// conservative. A sliver spanning many rows then costs its width on each row, not its box.
    pub fn row_span(&self, y: f64, slack: f64) -> (f64, f64) {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..3 {
            let (a, b) = (self.v[i], self.v[(i + 1) % 3]);
            if (a[1] <= y && y <= b[1]) || (b[1] <= y && y <= a[1]) {
                let x = if a[1] == b[1] {
                    lo = lo.min(a[0].min(b[0]));
                    a[0].max(b[0])
                } else {
                    let t = ((y - a[1]) / (b[1] - a[1])).clamp(0.0, 1.0);
                    a[0] + t * (b[0] - a[0])
                };
                lo = lo.min(x);
                hi = hi.max(x);
            }
        }
        (lo - slack, hi + slack)
    }

    /// Exact location of `p`.
    pub fn locate(&self, p: [f64; 2]) -> Location {
        let mut on = [false; 3];
        for (i, slot) in on.iter_mut().enumerate() {
            match orient(xy(&self.v[i]), xy(&self.v[(i + 1) % 3]), p) {
                Orientation::Clockwise => return Location::Outside,
                Orientation::Collinear => *slot = true,
                Orientation::CounterClockwise => {}
            }
        }
        match on {
            [false, false, false] => Location::Inside,
            [true, false, false] => Location::OnEdge(0),
            [false, true, false] => Location::OnEdge(1),
            [false, false, true] => Location::OnEdge(2),
            // Edges i and i+1 share vertex i+1.
            [true, true, false] => Location::OnVertex(1),
            [false, true, true] => Location::OnVertex(2),
            [true, false, true] => Location::OnVertex(0),
            // Impossible for a non-degenerate triangle.
            [true, true, true] => Location::Outside,
        }
    }

    /// Is edge `i` (from vertex `i` to `i + 1`) one that owns its points under the ownership rule?
    fn owns_edge(&self, i: usize) -> bool {
        let a = self.v[i];
        let b = self.v[(i + 1) % 3];
        b[1] < a[1] || (b[1] == a[1] && b[0] > a[0])
    }

    /// Does this triangle own a point at `loc` (see the module docs)? `false` for `Outside`.
    pub fn owns(&self, loc: Location) -> bool {
        match loc {
            Location::Inside => true,
            Location::OnEdge(i) => self.owns_edge(i),
            Location::OnVertex(k) => self.owns_edge((k + 2) % 3) && self.owns_edge(k),
            Location::Outside => false,
        }
    }

    /// The linearly interpolated `z` at `p`, which lies at `loc` (from [`Tri::locate`]); see the
    /// module docs for why edge and vertex points are special. `NaN` for `Outside`.
    pub fn value_at(&self, p: [f64; 2], loc: Location) -> f64 {
        match loc {
            Location::OnVertex(k) => self.v[k][2],
            Location::OnEdge(i) => edge_value(&self.v[i], &self.v[(i + 1) % 3], p),
            Location::Inside => self.plane_value(p),
            Location::Outside => f64::NAN,
        }
    }

    /// The value of the triangle's plane at any `p` (barycentric, from the canonical first vertex).
    pub fn plane_value(&self, p: [f64; 2]) -> f64 {
        let [a, b, c] = &self.v;
        let (bx, by) = (b[0] - a[0], b[1] - a[1]);
        let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
        let (px, py) = (p[0] - a[0], p[1] - a[1]);
        let d = bx * cy - by * cx;
        let wb = (px * cy - py * cx) / d;
        let wc = (bx * py - by * px) / d;
        a[2] + wb * (b[2] - a[2]) + wc * (c[2] - a[2])
    }

    /// Twice the signed area (positive: counter-clockwise).
    pub fn area2(&self) -> f64 {
        let [a, b, c] = &self.v;
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    /// The longest edge's horizontal length.
    pub fn max_edge(&self) -> f64 {
        (0..3)
            .map(|i| {
                let (a, b) = (self.v[i], self.v[(i + 1) % 3]);
                (b[0] - a[0]).hypot(b[1] - a[1])
            })
            .fold(0.0, f64::max)
    }
}

/// Linear interpolation of `z` at `p` on the segment `a b`, computed from the endpoints in `(x, y)`
/// order so that both triangles sharing the edge get the same bits.
pub fn edge_value(a: &[f64; 3], b: &[f64; 3], p: [f64; 2]) -> f64 {
    let (a, b) = if cmp_xy(a, b) == Ordering::Greater {
        (b, a)
    } else {
        (a, b)
    };
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let s = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
    a[2] + s * (b[2] - a[2])
}

/// A vertex of a polygon: `[x, y, value]`, the value linear over the polygon.
pub type PV = [f64; 3];

/// Clips a convex polygon to where the linear function `f` is `>= 0` (`strict`: `> 0`),
/// interpolating all three coordinates at the crossings (Sutherland–Hodgman). `f` must be linear
/// along the polygon's edges for the crossings to be exact up to rounding.
pub fn clip(poly: &[PV], f: impl Fn(&PV) -> f64, strict: bool, out: &mut Vec<PV>) {
    out.clear();
    let n = poly.len();
    if n == 0 {
        return;
    }
    let inside = |v: f64| if strict { v > 0.0 } else { v >= 0.0 };
    let vals: Vec<f64> = poly.iter().map(&f).collect();
    for i in 0..n {
        let j = (i + 1) % n;
        let (p, q) = (&poly[i], &poly[j]);
        let (fp, fq) = (vals[i], vals[j]);
        let (ip, iq) = (inside(fp), inside(fq));
        if ip {
            out.push(*p);
        }
        if ip != iq {
            let t = fp / (fp - fq);
            let t = t.clamp(0.0, 1.0);
            out.push([
                p[0] + t * (q[0] - p[0]),
                p[1] + t * (q[1] - p[1]),
                p[2] + t * (q[2] - p[2]),
            ]);
        }
    }
}

/// Keeps the part of a convex polygon on the left of (or on) the directed line `a → b`.
///
/// The side is the sign of `robust`'s orientation (`geom::predicates::orient_det`), which is
/// exact: a triangle beside another, on their shared edge, leaves exactly nothing (the plain
/// formula's rounding left slivers whose ±1e-11 areas counted as cut and fill).
pub fn clip_left(poly: &[PV], a: [f64; 2], b: [f64; 2], out: &mut Vec<PV>) {
    clip(poly, |p| orient_det(a, b, [p[0], p[1]]), false, out);
}

/// `(area, ∫ value dA)` of a convex polygon (counter-clockwise gives a positive area).
pub fn integrate(poly: &[PV]) -> (f64, f64) {
    if poly.len() < 3 {
        return (0.0, 0.0);
    }
    let a = poly[0];
    let (mut area, mut integral) = (0.0, 0.0);
    for w in poly[1..].windows(2) {
        let (b, c) = (w[0], w[1]);
        let t = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2.0;
        area += t;
        integral += t * (a[2] + b[2] + c[2]) / 3.0;
    }
    (area, integral)
}

/// The exact sum of the `f64`s added, rounded once at the end (Shewchuk's partials, as Python's
/// `math.fsum`): the result does not depend on the order of the additions.
#[derive(Clone, Debug, Default)]
pub struct ExactSum {
    partials: Vec<f64>,
}

impl ExactSum {
    /// An empty sum.
    pub fn new() -> Self {
        ExactSum::default()
    }

    /// Adds `x` (must be finite).
    pub fn add(&mut self, mut x: f64) {
        let mut i = 0;
        for j in 0..self.partials.len() {
            let mut y = self.partials[j];
            if x.abs() < y.abs() {
                std::mem::swap(&mut x, &mut y);
            }
            let hi = x + y;
            let lo = y - (hi - x);
            if lo != 0.0 {
                self.partials[i] = lo;
                i += 1;
            }
            x = hi;
        }
        self.partials.truncate(i);
        self.partials.push(x);
    }

    /// The partials whose exact sum this is.
    pub fn partials(&self) -> &[f64] {
        &self.partials
    }

    /// The correctly rounded sum.
    pub fn value(&self) -> f64 {
        let p = &self.partials;
        let mut n = p.len();
        if n == 0 {
            return 0.0;
        }
        n -= 1;
        let mut hi = p[n];
        let mut lo = 0.0;
        while n > 0 {
            let x = hi;
            n -= 1;
            let y = p[n];
            hi = x + y;
            let yr = hi - x;
            lo = y - yr;
            if lo != 0.0 {
                break;
            }
        }
        if n > 0 && ((lo < 0.0 && p[n - 1] < 0.0) || (lo > 0.0 && p[n - 1] > 0.0)) {
            let y = lo * 2.0;
            let x = hi + y;
            if y == x - hi {
                hi = x;
            }
        }
        hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The DEM's filter never drops a cell centre the exact test puts in the triangle: slivers,
    /// horizontal edges, UTM offsets, centres on edges and vertices.
    #[test]
    fn row_span_holds_every_point_the_exact_test_finds() {
        let mut rng = crate::geom::rng::SplitMix64::new(7);
        for k in 0..1500 {
            let (ox, oy) = if k % 2 == 0 {
                (0.0, 0.0)
            } else {
                (500_000.0, 5_000_000.0)
            };
            let mut pt = |s: f64| {
                [
                    ox + (rng.next_f64() * s).round() / 4.0,
                    oy + (rng.next_f64() * s).round() / 4.0,
                    0.0,
                ]
            };
            let scale = [4.0, 16.0, 64.0][k % 3];
            let (a, b, mut c) = (pt(scale), pt(scale), pt(scale));
            if k % 5 == 0 {
                c[1] = a[1]; // a horizontal edge
            }
            let Some(t) = Tri::new(&[a, b, c]) else {
                continue;
            };
            let [x0, y0, x1, y1] = t.bbox();
            let mut y = y0;
            while y <= y1 {
                let (lo, hi) = t.row_span(y, 1e-9 * x0.abs().max(x1.abs()));
                let mut x = x0;
                while x <= x1 {
                    if t.locate([x, y]) != Location::Outside {
                        assert!(lo <= x && x <= hi, "{t:?} at ({x}, {y}): span {lo}..{hi}");
                    }
                    x += 0.25;
                }
                y += 0.25;
            }
        }
    }

    #[test]
    fn canonical_rotation_and_orientation() {
        let a = [0.0, 0.0, 1.0];
        let b = [1.0, 0.0, 2.0];
        let c = [0.0, 1.0, 3.0];
        let t = Tri::new(&[b, c, a]).unwrap();
        assert_eq!(t.v, [a, b, c]);
        assert_eq!(Tri::new(&[a, c, b]).unwrap().v, [a, b, c]);
        assert!(Tri::new(&[a, b, [2.0, 0.0, 0.0]]).is_none());
        assert!(Tri::new(&[a, b, [f64::NAN, 1.0, 0.0]]).is_none());
    }

    #[test]
    fn locate_edges_and_vertices() {
        let t = Tri::new(&[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]).unwrap();
        assert_eq!(t.locate([0.5, 0.5]), Location::Inside);
        assert_eq!(t.locate([1.0, 0.0]), Location::OnEdge(0));
        assert_eq!(t.locate([1.0, 1.0]), Location::OnEdge(1));
        assert_eq!(t.locate([0.0, 1.0]), Location::OnEdge(2));
        assert_eq!(t.locate([0.0, 0.0]), Location::OnVertex(0));
        assert_eq!(t.locate([2.0, 0.0]), Location::OnVertex(1));
        assert_eq!(t.locate([0.0, 2.0]), Location::OnVertex(2));
        assert_eq!(t.locate([1.5, 1.5]), Location::Outside);
        assert_eq!(t.locate([-0.0, -1.0]), Location::Outside);
    }

    /// Around an interior vertex of a fan, and along every shared edge, exactly one triangle owns
    /// each point.
    #[test]
    fn ownership_is_a_partition_of_a_fan() {
        let centre = [0.0, 0.0, 0.0];
        // 8 neighbours, including exactly horizontal and vertical directions.
        let ring: Vec<[f64; 3]> = [
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (-1.0, 1.0),
            (-1.0, 0.0),
            (-1.0, -1.0),
            (0.0, -1.0),
            (1.0, -1.0),
        ]
        .iter()
        .map(|&(x, y)| [x, y, 0.0])
        .collect();
        let tris: Vec<Tri> = (0..8)
            .map(|i| Tri::new(&[centre, ring[i], ring[(i + 1) % 8]]).unwrap())
            .collect();
        let probes = [
            [0.0, 0.0],
            [0.5, 0.0],
            [0.0, 0.5],
            [-0.5, 0.0],
            [0.0, -0.5],
            [0.5, 0.5],
            [-0.5, -0.5],
            [0.25, 0.1],
        ];
        for p in probes {
            let owners = tris.iter().filter(|t| t.owns(t.locate(p))).count();
            assert_eq!(owners, 1, "point {p:?}");
        }
    }

    #[test]
    fn edge_values_agree_bitwise_from_both_sides() {
        let a = [0.1, 0.7, 3.3];
        let b = [7.9, 2.2, -1.7];
        let p = [a[0] + 0.3 * (b[0] - a[0]), a[1] + 0.3 * (b[1] - a[1])];
        assert_eq!(
            edge_value(&a, &b, p).to_bits(),
            edge_value(&b, &a, p).to_bits()
        );
    }

    #[test]
    fn plane_is_reproduced() {
        let f = |x: f64, y: f64| 2.0 * x - 3.0 * y + 5.0;
        let pts = [[0.0, 0.0], [4.0, 1.0], [1.0, 3.0]].map(|[x, y]| [x, y, f(x, y)]);
        let t = Tri::new(&pts).unwrap();
        for p in [[1.0, 1.0], [2.0, 1.5], [1.5, 2.0]] {
            assert!((t.plane_value(p) - f(p[0], p[1])).abs() < 1e-12);
        }
    }

    #[test]
    fn clip_and_integrate_a_square() {
        let sq: Vec<PV> = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 2.0],
            [2.0, 2.0, 2.0],
            [0.0, 2.0, 0.0],
        ];
        assert_eq!(integrate(&sq), (4.0, 4.0));
        let mut out = Vec::new();
        clip(&sq, |p| p[2] - 1.0, false, &mut out);
        assert_eq!(integrate(&out), (2.0, 3.0));
        clip_left(&sq, [0.0, 1.0], [2.0, 1.0], &mut out);
        assert_eq!(integrate(&out).0, 2.0);
    }

    #[test]
    fn exact_sum_is_order_independent() {
        let mut r = crate::geom::rng::SplitMix64::new(7);
        let xs: Vec<f64> = (0..1000)
            .map(|_| (r.next_f64() - 0.5) * 10f64.powi((r.next_u64() % 30) as i32 - 15))
            .collect();
        let mut a = ExactSum::new();
        xs.iter().for_each(|&x| a.add(x));
        let mut b = ExactSum::new();
        xs.iter().rev().for_each(|&x| b.add(x));
        assert_eq!(a.value().to_bits(), b.value().to_bits());
        let mut c = ExactSum::new();
        for x in [1e100, 1.0, -1e100] {
            c.add(x);
        }
        assert_eq!(c.value(), 1.0);
        assert_eq!(ExactSum::new().value(), 0.0);
    }
}
