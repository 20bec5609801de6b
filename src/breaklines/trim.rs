//! Which triangles to keep: `--boundary` (keep inside), `--holes` (drop inside), `--max-edge`.
//!
//! # Inside a set of rings
//!
//! A boundary or hole file holds closed rings (every ring of every polygon). A point is *inside*
//! when a ray from it crosses the rings an odd number of times (the even-odd rule): inside an outer
//! ring and not inside one of its holes, with no need for the rings to be oriented one way or the
//! other. (Polygons of one file that overlap cancel out where they overlap: give a union.)
//!
//! # Deciding a triangle exactly
//!
//! The pipeline inserts the rings as constraint edges, so no triangle straddles a ring: each lies
//! entirely on one side. The test point is therefore any point strictly inside the triangle; this
//! module uses a *symbolic* one, `p = a + ε(b - a) + ε²(c - a)` for an infinitesimal `ε > 0`, which
//! is strictly inside triangle `abc` whatever its orientation, and evaluates the ray test on it
//! exactly: "is vertex `v` above `p`" is a comparison of `y` values (ties broken by `b.y`, then
//! `c.y`), and the side of `p` relative to a ring edge `uv` is the first non-zero of
//! `orient(u, v, a)`, `orient(u, v, b)`, `orient(u, v, c)` (`geom::predicates::orient`). No
//! coordinate of a test point is ever rounded. *Caveat*: if a ring is **not** inserted as a
//! constraint and crosses a triangle, the answer is the one for the part of the triangle at its
//! first corner.
//!
//! # Speed
//!
//! The ring edges are bucketed in a uniform grid (about two cells per edge). Every cell without an
//! edge is inside or outside as a whole, decided once while building. A query in such a cell is a
//! table lookup; a query in a cell with edges casts its ray only as far as the next empty cell in
//! the same row, whose status finishes the count.
//!
//! # Maximum edge length
//!
//! `--max-edge L` drops triangles with an edge longer than `L` (the concave outline users ask for).
//! Lengths are compared in floating point (a length within rounding of `L` may go either way: this
//! is a threshold, not a topological decision).

use crate::error::{Error, Result};
use crate::geom::grid::{Buckets, Grid};
use crate::geom::predicates::{Orientation, orient};
use crate::input::geojson::is_ring;
use crate::input::lines::Lines;

/// Cell status: no edge in the cell, the cell is outside.
const OUTSIDE: u8 = 0;
/// No edge in the cell, the cell is inside.
const INSIDE: u8 = 1;
/// The cell holds edges.
const EDGES: u8 = 2;

/// The trimming rules of a run.
#[derive(Clone, Debug, Default)]
pub struct Trim {
    boundary: Option<Region>,
    holes: Option<Region>,
    max_edge2: Option<f64>,
    rings: Vec<Vec<[f64; 3]>>,
}

impl Trim {
    /// Trimming by `boundary` rings (keep inside; `None`: keep everything), `holes` rings (drop
    /// inside) and a maximum edge length. Every ring must be closed (the last vertex repeats the
    /// first); coordinates in the triangles' frame and units.
    ///
    /// # Errors
    /// [`Error::BadLine`] naming the first ring that is not closed or has a non-finite coordinate
    /// (`polyline` counts the boundary rings, then the hole rings, each from 0); [`Error::Options`]
    /// for a `max_edge` that is not a positive finite length.
    pub fn new(
        boundary: Option<&[Vec<[f64; 3]>]>,
        holes: &[Vec<[f64; 3]>],
        max_edge: Option<f64>,
    ) -> Result<Trim> {
        if let Some(l) = max_edge
            && !(l.is_finite() && l > 0.0)
        {
            return Err(Error::Options(format!(
                "--max-edge must be a positive finite length, got {l}"
            )));
        }
        let mut rings = Vec::new();
        let boundary = match boundary {
            Some(b) => {
                check_rings(b)?;
                rings.extend_from_slice(b);
                Some(Region::new(b))
            }
            None => None,
        };
        let holes = if holes.is_empty() {
            None
        } else {
            check_rings(holes)?;
            rings.extend_from_slice(holes);
            Some(Region::new(holes))
        };
        Ok(Trim {
            boundary,
            holes,
            max_edge2: max_edge.map(|l| l * l),
            rings,
        })
    }

    /// [`Trim::new`] from breakline files read with [`super::read_file`]; errors name the file.
    ///
    /// # Errors
    /// [`Error::Format`] for a line that is not a closed ring or a file without any ring;
    /// [`Error::Options`] for a bad `max_edge`.
    pub fn from_lines(
        boundary: Option<&Lines>,
        holes: Option<&Lines>,
        max_edge: Option<f64>,
    ) -> Result<Trim> {
        for l in [boundary, holes].into_iter().flatten() {
            l.require_rings()?;
        }
        if let Some(b) = boundary
            && b.is_empty()
        {
            return Err(Error::Format {
                path: Default::default(),
                message: "the boundary file holds no polygon: nothing would be kept".into(),
            });
        }
        let holes = holes.map_or(&[][..], |h| &h.polylines[..]);
        Trim::new(boundary.map(|b| &b.polylines[..]), holes, max_edge)
    }

    /// Does this trim keep every triangle?
    pub fn keeps_all(&self) -> bool {
        self.boundary.is_none() && self.holes.is_none() && self.max_edge2.is_none()
    }

    /// All boundary and hole rings, as closed polylines: insert them as constraints so that no
    /// triangle straddles a ring (see the module docs).
    pub fn rings(&self) -> &[Vec<[f64; 3]>] {
        &self.rings
    }

    /// Is triangle `t` kept? (`z` is ignored; either orientation.)
    pub fn keep(&self, t: &[[f64; 3]; 3]) -> bool {
        if let Some(m) = self.max_edge2 {
            for k in 0..3 {
                let (p, q) = (t[k], t[(k + 1) % 3]);
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                if dx * dx + dy * dy > m {
                    return false;
                }
            }
        }
        let probe = Probe {
            a: [t[0][0], t[0][1]],
            b: [t[1][0], t[1][1]],
            c: [t[2][0], t[2][1]],
        };
        if let Some(b) = &self.boundary
            && !b.contains(&probe)
        {
            return false;
        }
        if let Some(h) = &self.holes
            && h.contains(&probe)
        {
            return false;
        }
        true
    }
}

fn check_rings(rings: &[Vec<[f64; 3]>]) -> Result<()> {
    for (i, r) in rings.iter().enumerate() {
        if let Some(k) = r
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(Error::BadLine {
                polyline: i as u64,
                vertex: k as u64,
                message: "coordinate is not finite".into(),
            });
        }
        if !is_ring(r) {
            return Err(Error::BadLine {
                polyline: i as u64,
                vertex: 0,
                message: format!(
                    "not a closed ring ({} vertices; a ring has at least 4 and ends where it \
                     starts)",
                    r.len()
                ),
            });
        }
    }
    Ok(())
}

/// The symbolic point `a + ε(b - a) + ε²(c - a)`, strictly inside triangle `abc`.
struct Probe {
    a: [f64; 2],
    b: [f64; 2],
    c: [f64; 2],
}

/// A test point of the ray casting: the symbolic [`Probe`] or a real point.
trait Point {
    /// Is `v` strictly above the point?
    fn below(&self, v: [f64; 2]) -> bool;
    /// Orientation of `u, v, point`.
    fn side(&self, u: [f64; 2], v: [f64; 2]) -> Orientation;
    /// The point's `(x, y)` (exactly, or up to an infinitesimal).
    fn at(&self) -> [f64; 2];
}

impl Point for Probe {
    fn below(&self, v: [f64; 2]) -> bool {
        let (a, b, c) = (self.a[1], self.b[1], self.c[1]);
        v[1] > a || (v[1] == a && (b < a || (b == a && c < a)))
    }

    fn side(&self, u: [f64; 2], v: [f64; 2]) -> Orientation {
        for p in [self.a, self.b, self.c] {
            let o = orient(u, v, p);
            if o != Orientation::Collinear {
                return o;
            }
        }
        Orientation::Collinear
    }

    fn at(&self) -> [f64; 2] {
        self.a
    }
}

impl Point for [f64; 2] {
    fn below(&self, v: [f64; 2]) -> bool {
        v[1] > self[1]
    }

    fn side(&self, u: [f64; 2], v: [f64; 2]) -> Orientation {
        orient(u, v, *self)
    }

    fn at(&self) -> [f64; 2] {
        *self
    }
}

/// The even-odd interior of a set of closed rings, with a grid of cell statuses.
#[derive(Clone, Debug)]
struct Region {
    pts: Vec<[f64; 2]>,
    edges: Vec<[u32; 2]>,
    grid: Grid,
    buckets: Buckets,
    status: Vec<u8>,
}

impl Region {
    fn new(rings: &[Vec<[f64; 3]>]) -> Region {
        let mut pts = Vec::new();
        let mut edges = Vec::new();
        for r in rings {
            let base = pts.len() as u32;
            pts.extend(r.iter().map(|p| [p[0], p[1]]));
            for k in 0..r.len().saturating_sub(1) {
                let (p, q) = (r[k], r[k + 1]);
                if p[0] != q[0] || p[1] != q[1] {
                    edges.push([base + k as u32, base + k as u32 + 1]);
                }
            }
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &pts {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if pts.is_empty() {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        let grid = Grid::new(lo, hi, 2 * edges.len());
        let buckets = Buckets::segments(&grid, &pts, &edges);
        let mut region = Region {
            pts,
            edges,
            grid,
            buckets,
            status: Vec::new(),
        };
        region.status = region.cell_status();
        region
    }

    /// Inside or outside for every cell without edges, right to left along each row.
    fn cell_status(&self) -> Vec<u8> {
        let g = &self.grid;
        let mut status = vec![EDGES; g.len()];
        let nx = g.nx();
        let ny = (g.len() / nx as usize) as u32;
        for r in 0..ny {
            // Status of the nearest empty cell to the right (beyond the grid: outside).
            let mut next: (u32, u8) = (nx, OUTSIDE);
            for c in (0..nx).rev() {
                let cell = g.cell(c, r);
                if !self.buckets.cell(cell).is_empty() {
                    continue;
                }
                let Some(q) = g.centre(c, r) else {
                    continue; // treated as a cell with edges: queries there cast rays
                };
                let s = self.parity(&q, r, c + 1, next.0) ^ next.1;
                status[cell as usize] = s;
                next = (c, s);
            }
        }
        status
    }

    /// Parity of the crossings of the ray from `p` to the right with the edges of cells
    /// `c0..c1` of row `r`.
    fn parity(&self, p: &impl Point, r: u32, c0: u32, c1: u32) -> u8 {
        let mut ids: Vec<u32> = Vec::new();
        for c in c0..c1 {
            ids.extend_from_slice(self.buckets.cell(self.grid.cell(c, r)));
        }
        if ids.is_empty() {
            return 0;
        }
        ids.sort_unstable();
        ids.dedup();
        let mut odd = 0u8;
        for e in ids {
            let [i, j] = self.edges[e as usize];
            let (u, v) = (self.pts[i as usize], self.pts[j as usize]);
            let (bu, bv) = (p.below(u), p.below(v));
            if bu != bv && (p.side(u, v) == Orientation::CounterClockwise) == bv {
                odd ^= 1;
            }
        }
        odd
    }

    /// Is `p` inside (even-odd)?
    fn contains(&self, p: &impl Point) -> bool {
        if self.edges.is_empty() {
            return false;
        }
        let at = p.at();
        let (c, r) = (self.grid.col(at[0]), self.grid.row(at[1]));
        let s = self.status[self.grid.cell(c, r) as usize];
        if s != EDGES {
            return s == INSIDE;
        }
        let nx = self.grid.nx();
        let mut end = c + 1;
        while end < nx && self.status[self.grid.cell(end, r) as usize] == EDGES {
            end += 1;
        }
        let beyond = if end < nx {
            self.status[self.grid.cell(end, r) as usize]
        } else {
            OUTSIDE
        };
        self.parity(p, r, c, end) ^ beyond == INSIDE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::SplitMix64;

    fn ring(pts: &[[f64; 2]]) -> Vec<[f64; 3]> {
        let mut r: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[1], f64::NAN]).collect();
        r.push(r[0]);
        r
    }

    fn tri(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> [[f64; 3]; 3] {
        [[a[0], a[1], 0.], [b[0], b[1], 0.], [c[0], c[1], 0.]]
    }

    /// Brute-force even-odd test of a real point not on any edge.
    fn brute(rings: &[Vec<[f64; 3]>], p: [f64; 2]) -> bool {
        let mut inside = false;
        for r in rings {
            for w in r.windows(2) {
                let (u, v) = ([w[0][0], w[0][1]], [w[1][0], w[1][1]]);
                if (u[1] > p[1]) != (v[1] > p[1]) {
                    let x = u[0] + (p[1] - u[1]) * (v[0] - u[0]) / (v[1] - u[1]);
                    if x > p[0] {
                        inside = !inside;
                    }
                }
            }
        }
        inside
    }

    #[test]
    fn square_with_a_hole() {
        let outer = ring(&[[0., 0.], [10., 0.], [10., 10.], [0., 10.]]);
        let inner = ring(&[[4., 4.], [4., 6.], [6., 6.], [6., 4.]]);
        let t = Trim::new(Some(&[outer.clone(), inner.clone()]), &[], None).unwrap();
        // Triangles with corners on the rings, on both sides.
        assert!(t.keep(&tri([0., 0.], [10., 0.], [4., 4.])));
        assert!(!t.keep(&tri([4., 4.], [6., 4.], [6., 6.])));
        assert!(!t.keep(&tri([10., 0.], [12., 0.], [10., 10.])));
        assert!(t.keep(&tri([10., 10.], [10., 0.], [6., 6.]))); // clockwise
        assert_eq!(t.rings().len(), 2);
        // The same square as boundary and the inner ring as a hole file: same answers.
        let t2 = Trim::new(Some(&[outer]), &[inner], None).unwrap();
        for tr in [
            tri([0., 0.], [10., 0.], [4., 4.]),
            tri([4., 4.], [6., 4.], [6., 6.]),
            tri([10., 0.], [12., 0.], [10., 10.]),
        ] {
            assert_eq!(t.keep(&tr), t2.keep(&tr));
        }
    }

    #[test]
    fn triangles_along_horizontal_edges() {
        // Horizontal ring edges at the probe's height: the y-tie rule decides.
        let sq = ring(&[[0., 0.], [4., 0.], [4., 2.], [0., 2.]]);
        let t = Trim::new(Some(&[sq]), &[], None).unwrap();
        // Inside, with an edge on the bottom side and the first corner on it.
        assert!(t.keep(&tri([1., 0.], [3., 0.], [2., 1.])));
        // Outside, just below the bottom side.
        assert!(!t.keep(&tri([1., 0.], [2., -1.], [3., 0.])));
        // Inside, the first corner on the top side, the triangle below it.
        assert!(t.keep(&tri([1., 2.], [2., 1.], [3., 2.])));
        assert!(!t.keep(&tri([1., 2.], [3., 2.], [2., 3.])));
        // Corners on the ring's corners.
        assert!(t.keep(&tri([0., 0.], [4., 0.], [4., 2.])));
        assert!(!t.keep(&tri([4., 0.], [5., 1.], [4., 2.])));
    }

    #[test]
    fn max_edge() {
        let t = Trim::new(None, &[], Some(2.0)).unwrap();
        assert!(t.keep(&tri([0., 0.], [1., 0.], [0., 1.])));
        assert!(!t.keep(&tri([0., 0.], [3., 0.], [0., 1.])));
        assert!(!t.keep(&tri([0., 0.], [2., 0.], [0., 2.]))); // the diagonal is 2.83
        assert!(t.keep(&tri([0., 0.], [2., 0.], [1., 1.])));
        let e = Trim::new(None, &[], Some(0.0)).unwrap_err();
        assert!(matches!(e, Error::Options(_)), "{e:?}");
        assert_eq!(
            e.to_string(),
            "--max-edge must be a positive finite length, got 0"
        );
        assert!(Trim::new(None, &[], Some(f64::NAN)).is_err());
        assert!(Trim::new(None, &[], None).unwrap().keeps_all());
    }

    #[test]
    fn bad_rings() {
        let open = vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]];
        assert!(Trim::new(Some(&[open]), &[], None).is_err());
        let nan = ring(&[[0., 0.], [1., f64::NAN], [1., 1.]]);
        assert!(Trim::new(None, &[nan], None).is_err());
        // An empty boundary keeps nothing.
        let t = Trim::new(Some(&[]), &[], None).unwrap();
        assert!(!t.keep(&tri([0., 0.], [1., 0.], [0., 1.])));
    }

    /// A star-shaped polygon with many vertices and holes, against brute force on random points.
    #[test]
    fn many_vertices_against_brute_force() {
        let mut rng = SplitMix64::new(3);
        let mut rings = Vec::new();
        let n = 3000;
        let outer: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let r = 50.0 + 30.0 * rng.next_f64() + 10.0 * (7.0 * t).sin();
                [r * t.cos(), r * t.sin()]
            })
            .collect();
        rings.push(ring(&outer));
        for &(cx, cy) in &[(0.0, 0.0), (20.0, 5.0)] {
            let hole: Vec<[f64; 2]> = (0..200)
                .map(|k| {
                    let t = -std::f64::consts::TAU * k as f64 / 200.0;
                    let r = 6.0 + 2.0 * rng.next_f64();
                    [cx + r * t.cos(), cy + r * t.sin()]
                })
                .collect();
            rings.push(ring(&hole));
        }
        let t = Trim::new(Some(&rings), &[], None).unwrap();
        let mut inside = 0;
        for _ in 0..20000 {
            let p = [rng.range(-100.0, 100.0), rng.range(-100.0, 100.0)];
            // A tiny triangle at p: its probe is p (up to an infinitesimal).
            let tr = tri(p, [p[0] + 1e-9, p[1]], [p[0], p[1] + 1e-9]);
            let want = brute(&rings, p);
            assert_eq!(t.keep(&tr), want, "{p:?}");
            inside += usize::from(want);
        }
        assert!(inside > 3000 && inside < 15000, "{inside}");
    }

    #[test]
    fn from_lines_requires_rings() {
        let lines = Lines::default();
        assert!(Trim::from_lines(Some(&lines), None, None).is_err());
        assert!(
            Trim::from_lines(None, Some(&lines), None)
                .unwrap()
                .keeps_all()
        );
    }
}
