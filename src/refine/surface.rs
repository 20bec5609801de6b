//! The original surface: the input mesh's triangles in a uniform grid, to interpolate the height
//! of a Steiner point on the surface the user gave (not on the refined mesh, whose earlier Steiner
//! points would otherwise compound interpolation) and to tell the domain from the holes.

use crate::geom::grid::{Buckets, Grid};
use crate::geom::predicates::{Orientation, orient};
use crate::tin::planar;

/// The input triangles, bucketed by the grid cells their bounding boxes meet.
pub(super) struct Surface<'a> {
    vertices: &'a [[f64; 3]],
    triangles: &'a [[u32; 3]],
    grid: Grid,
    buckets: Buckets,
}

impl<'a> Surface<'a> {
    /// The surface of `triangles` (counter-clockwise, indices checked by the caller).
    pub fn new(vertices: &'a [[f64; 3]], triangles: &'a [[u32; 3]]) -> Surface<'a> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for t in triangles {
            for &v in t {
                let p = vertices[v as usize];
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let grid = Grid::new(lo, hi, triangles.len().max(1));
        let mut pairs = Vec::with_capacity(2 * triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for &v in t {
                let p = vertices[v as usize];
                for k in 0..2 {
                    a[k] = a[k].min(p[k]);
                    b[k] = b[k].max(p[k]);
                }
            }
            grid.box_cells(a, b, |c| pairs.push((u64::from(c) << 32) | i as u64));
        }
        let buckets = Buckets::from_pairs(grid.len(), pairs);
        Surface {
            vertices,
            triangles,
            grid,
            buckets,
        }
    }

    /// The first input triangle (lowest index) whose closed area holds `p`, exactly.
    pub fn triangle_at(&self, p: [f64; 2]) -> Option<u32> {
        let xy = |v: u32| {
            let q = self.vertices[v as usize];
            [q[0], q[1]]
        };
        self.buckets
            .cell(self.grid.cell_of(p))
            .iter()
            .copied()
            .find(|&i| {
                let [a, b, c] = self.triangles[i as usize];
                let (a, b, c) = (xy(a), xy(b), xy(c));
                orient(a, b, p) != Orientation::Clockwise
                    && orient(b, c, p) != Orientation::Clockwise
                    && orient(c, a, p) != Orientation::Clockwise
            })
    }

    /// Height of the input surface at `p` (linear in the triangle that holds it), or `None`
    /// outside the input mesh.
    pub fn height(&self, p: [f64; 2]) -> Option<f64> {
        let t = self.triangle_at(p)?;
        let [a, b, c] = self.triangles[t as usize].map(|v| self.vertices[v as usize]);
        Some(planar(a, b, c, p))
    }
}
