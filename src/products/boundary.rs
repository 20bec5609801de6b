//! A boundary polygon, decomposed into convex trapezoids so that triangles can be clipped to it
//! exactly (up to rounding) however the polygon looks.
//!
//! The decomposition: sort the distinct `y` of all vertices (and of points where edges cross);
//! between two consecutive ones (a *slab*) no edge starts, ends or crosses another, so the edges
//! crossing the slab keep their left-to-right order, and the stretches between them where the
//! area is inside are trapezoids. Each polygon's first ring is its outline and the others are
//! holes, whatever their orientation in the file (rings are re-oriented). A point is inside a
//! polygon where its outline winds around it (non-zero rule) and none of its holes does; a hole
//! takes area from its own polygon only (a hole outside its outline took nothing and added its
//! own area); several polygons cover their union.

use super::geom::{PV, clip_left, integrate};
use crate::error::{Error, Result};
use crate::input::geojson::Polygon;
use std::path::Path;

/// One trapezoid: bottom-left, bottom-right, top-right, top-left (counter-clockwise).
type Trap = [[f64; 2]; 4];

/// A polygonal area to which products are restricted (see the module docs).
#[derive(Clone, Debug)]
pub struct Boundary {
    /// Slab limits, increasing.
    ys: Vec<f64>,
    /// Trapezoids of slab `i` (between `ys[i]` and `ys[i + 1]`), left to right.
    slabs: Vec<Vec<Trap>>,
}

/// An edge as `(lower end, upper end, +1 if the ring runs upwards along it, else -1, its
/// polygon, whether its ring is a hole)`.
type Edge = ([f64; 2], [f64; 2], i32, usize, bool);

fn x_at(e: &Edge, y: f64) -> f64 {
    let (a, b, ..) = e;
    if y <= a[1] {
        return a[0];
    }
    if y >= b[1] {
        return b[0];
    }
    a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
}

/// Twice the signed area of a ring.
fn ring_area2(ring: &[[f64; 2]]) -> f64 {
    (0..ring.len())
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

/// Most rounds of splitting slabs where edges cross.
const MAX_ROUNDS: usize = 64;

impl Boundary {
    /// Decomposes `polygons` (each: outline, then holes).
    ///
    /// # Errors
    /// [`Error::Options`] if there is no area, or the edges cross too often to decompose them.
    pub fn new(polygons: &[Polygon]) -> Result<Boundary> {
        Self::decompose(polygons).map_err(|m| Error::Options(m.into()))
    }

    /// Reads the polygons of a GeoJSON file ([`crate::input::geojson::read_polygons`]) and
    /// decomposes them.
    ///
    /// # Errors
    /// The reader's errors; [`Error::Format`] naming the file for the problems of
    /// [`Boundary::new`].
    pub fn read(path: &Path) -> Result<Boundary> {
        let polygons = crate::input::geojson::read_polygons(path)?;
        Self::decompose(&polygons).map_err(|m| Error::Format {
            path: path.to_path_buf(),
            message: m.into(),
        })
    }

    fn decompose(polygons: &[Polygon]) -> std::result::Result<Boundary, &'static str> {
        let mut edges: Vec<Edge> = Vec::new();
        for (k, poly) in polygons.iter().enumerate() {
            for (i, ring) in poly.iter().enumerate() {
                let ccw = ring_area2(ring) > 0.0;
                // Outline counter-clockwise, holes clockwise.
                let flip = if ccw == (i == 0) { 1 } else { -1 };
                for j in 0..ring.len() {
                    let (a, b) = (ring[j], ring[(j + 1) % ring.len()]);
                    if a[1] == b[1] {
                        continue;
                    }
                    edges.push(if a[1] < b[1] {
                        (a, b, flip, k, i > 0)
                    } else {
                        (b, a, -flip, k, i > 0)
                    });
                }
            }
        }
        let mut ys: Vec<f64> = edges.iter().flat_map(|e| [e.0[1], e.1[1]]).collect();
        edges.sort_by(|a, b| a.0[1].total_cmp(&b.0[1]));
        for _ in 0..MAX_ROUNDS {
            ys.sort_by(f64::total_cmp);
            ys.dedup();
            if ys.len() < 2 {
                return Err("the boundary has no area");
            }
            let (slabs, crossings) = Self::slabs(&edges, &ys, polygons.len());
            if crossings.is_empty() {
                let b = Boundary { ys, slabs };
                if b.area() <= 0.0 {
                    return Err("the boundary has no area");
                }
                return Ok(b);
            }
            ys.extend(crossings);
        }
        Err("the boundary's edges cross too often to decompose it")
    }

    /// The trapezoids of every slab, or the `y` of points where edges cross inside a slab.
    fn slabs(edges: &[Edge], ys: &[f64], polygons: usize) -> (Vec<Vec<Trap>>, Vec<f64>) {
        let mut slabs = Vec::with_capacity(ys.len() - 1);
        // Per polygon: the winding numbers of its outline and of its holes left of the edge
        // (each back at 0 right of a slab's last edge), and how many polygons hold it.
        let mut outline = vec![0i32; polygons];
        let mut holes = vec![0i32; polygons];
        let mut inside = 0usize;
        let mut crossings = Vec::new();
        let mut active: Vec<Edge> = Vec::new();
        let mut next = 0;
        for w in ys.windows(2) {
            let (y0, y1) = (w[0], w[1]);
            active.retain(|e| e.1[1] > y0);
            while next < edges.len() && edges[next].0[1] <= y0 {
                if edges[next].1[1] > y0 {
                    active.push(edges[next]);
                }
                next += 1;
            }
            let ym = (y0 + y1) / 2.0;
            active.sort_by(|a, b| x_at(a, ym).total_cmp(&x_at(b, ym)));
            for pair in active.windows(2) {
                let (l, r) = (&pair[0], &pair[1]);
                let d0 = x_at(r, y0) - x_at(l, y0);
                let d1 = x_at(r, y1) - x_at(l, y1);
                if d0 < 0.0 || d1 < 0.0 {
                    // They cross where the difference of their x vanishes (linear in y).
                    let t = d0 / (d0 - d1);
                    let y = y0 + t * (y1 - y0);
                    if y > y0 && y < y1 {
                        crossings.push(y);
                    }
                }
            }
            let mut traps = Vec::new();
            let mut left: Option<&Edge> = None;
            for e in &active {
                let before = inside;
                let k = e.3;
                let was = outline[k] != 0 && holes[k] == 0;
                if e.4 {
                    holes[k] += e.2;
                } else {
                    outline[k] += e.2;
                }
                let is = outline[k] != 0 && holes[k] == 0;
                inside = inside + usize::from(is) - usize::from(was);
                if before == 0 && inside != 0 {
                    left = Some(e);
                } else if before != 0 && inside == 0 {
                    let l = left.take().expect("opened when the winding left zero");
                    traps.push([
                        [x_at(l, y0), y0],
                        [x_at(e, y0), y0],
                        [x_at(e, y1), y1],
                        [x_at(l, y1), y1],
                    ]);
                }
            }
            slabs.push(traps);
        }
        (slabs, crossings)
    }

    /// The area inside the boundary.
    pub fn area(&self) -> f64 {
        self.slabs
            .iter()
            .flatten()
            .map(|t| {
                let poly: Vec<PV> = t.iter().map(|p| [p[0], p[1], 0.0]).collect();
                integrate(&poly).0
            })
            .sum()
    }

    /// Calls `f` with every piece of the convex polygon `poly` (vertices carrying a linear value)
    /// that lies inside the boundary; the pieces do not overlap and cover `poly ∩ boundary`.
    pub fn clip(&self, poly: &[PV], mut f: impl FnMut(&[PV])) {
        let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut xmin, mut xmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in poly {
            ymin = ymin.min(p[1]);
            ymax = ymax.max(p[1]);
            xmin = xmin.min(p[0]);
            xmax = xmax.max(p[0]);
        }
        // Slabs overlapping [ymin, ymax].
        let first = self.ys.partition_point(|&y| y <= ymin).saturating_sub(1);
        let mut a = Vec::new();
        let mut b = Vec::new();
        for i in first..self.slabs.len() {
            if self.ys[i] >= ymax {
                break;
            }
            for t in &self.slabs[i] {
                let (tx0, tx1) = (t[0][0].min(t[3][0]), t[1][0].max(t[2][0]));
                if tx1 < xmin || tx0 > xmax {
                    continue;
                }
                a.clear();
                a.extend_from_slice(poly);
                for k in 0..4 {
                    clip_left(&a, t[k], t[(k + 1) % 4], &mut b);
                    std::mem::swap(&mut a, &mut b);
                    if a.len() < 3 {
                        break;
                    }
                }
                if a.len() >= 3 {
                    f(&a);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, s: f64) -> Vec<[f64; 2]> {
        vec![[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]]
    }

    #[test]
    fn area_with_hole_and_second_polygon() {
        let b = Boundary::new(&[
            vec![square(0.0, 0.0, 10.0), square(2.0, 2.0, 3.0)],
            vec![vec![[20.0, 0.0], [30.0, 5.0], [20.0, 10.0]]],
        ])
        .unwrap();
        assert_eq!(b.area(), 100.0 - 9.0 + 50.0);
    }

    #[test]
    fn clipping_a_triangle_sums_to_its_part_inside() {
        // A concave L-shaped boundary.
        let l = vec![
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 1.0],
            [1.0, 1.0],
            [1.0, 4.0],
            [0.0, 4.0],
        ];
        let b = Boundary::new(&[vec![l]]).unwrap();
        assert_eq!(b.area(), 7.0);
        // A big square with value = x: ∫ x over the L = ∫ over [0,4]x[0,1] + [0,1]x[1,4].
        let sq: Vec<PV> = vec![
            [-1.0, -1.0, -1.0],
            [5.0, -1.0, 5.0],
            [5.0, 5.0, 5.0],
            [-1.0, 5.0, -1.0],
        ];
        let (mut area, mut integral) = (0.0, 0.0);
        b.clip(&sq, |p| {
            let (a, i) = integrate(p);
            area += a;
            integral += i;
        });
        assert!((area - 7.0).abs() < 1e-12);
        assert!((integral - (8.0 + 1.5)).abs() < 1e-12);
    }

    #[test]
    fn crossing_and_overlapping_rings() {
        // A bow tie: two triangles of area 1 each.
        let bow = vec![[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]];
        let b = Boundary::new(&[vec![bow]]).unwrap();
        assert!((b.area() - 2.0).abs() < 1e-12);
        // Two overlapping squares (one clockwise): their union.
        let mut cw = square(1.0, 1.0, 2.0);
        cw.reverse();
        let overlap = [vec![square(0.0, 0.0, 2.0)], vec![cw]];
        assert_eq!(Boundary::new(&overlap).unwrap().area(), 7.0);
        // A hole given counter-clockwise is still a hole.
        let holed = [vec![square(0.0, 0.0, 4.0), square(1.0, 1.0, 1.0)]];
        assert_eq!(Boundary::new(&holed).unwrap().area(), 15.0);
        // A hole outside its outline takes nothing (it added its own area), a hole straddling
        // the outline only the part inside; another polygon covering a hole covers it.
        let astray = [vec![square(0.0, 0.0, 4.0), square(10.0, 10.0, 2.0)]];
        assert_eq!(Boundary::new(&astray).unwrap().area(), 16.0);
        let straddling = [vec![square(0.0, 0.0, 4.0), square(3.0, 1.0, 2.0)]];
        assert_eq!(Boundary::new(&straddling).unwrap().area(), 14.0);
        let covered = [
            vec![square(0.0, 0.0, 4.0), square(1.0, 1.0, 1.0)],
            vec![square(1.0, 1.0, 1.0)],
        ];
        assert_eq!(Boundary::new(&covered).unwrap().area(), 16.0);
        assert!(Boundary::new(&[vec![vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]]]).is_err());
    }
}
