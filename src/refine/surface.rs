//! The original surface: the input mesh's triangles in a uniform grid, to interpolate the height
//! of a Steiner point on the surface the user gave (not on the refined mesh, whose earlier Steiner
//! points would otherwise compound interpolation) and to tell the domain from the holes.

use crate::geom::grid::{Buckets, Grid};
use crate::geom::predicates::{Orientation, orient};
use crate::tin::planar;

/// The input triangles with their adjacency (for walks) and, built on first use, a grid of
/// their bounding boxes (for points no walk reaches).
pub(super) struct Surface<'a> {
    vertices: &'a [[f64; 3]],
    triangles: &'a [[u32; 3]],
    /// Twin of each half-edge `3t + k` (from corner `k` to `k + 1`), `u32::MAX` on the boundary.
    twins: Vec<u32>,
    index: std::sync::OnceLock<Index>,
}

/// The grid of a [`Surface`].
struct Index {
    /// Bounding box of each triangle: `[min x, min y, max x, max y]` (a quick rejection).
    boxes: Vec<[f64; 4]>,
    grid: Grid,
    buckets: Buckets,
}

impl<'a> Surface<'a> {
    /// The surface of `triangles` (counter-clockwise, indices checked by the caller).
    pub(super) fn new(vertices: &'a [[f64; 3]], triangles: &'a [[u32; 3]]) -> Surface<'a> {
        let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push(((u64::from(a) << 32) | u64::from(b), (3 * i + k) as u32));
            }
        }
        edges.sort_unstable();
        let mut twins = vec![u32::MAX; 3 * triangles.len()];
        for &(key, e) in &edges {
            let rev = key.rotate_right(32);
            if let Ok(j) = edges.binary_search_by_key(&rev, |&(k, _)| k) {
                twins[e as usize] = edges[j].1;
            }
        }
        Surface {
            vertices,
            triangles,
            twins,
            index: std::sync::OnceLock::new(),
        }
    }

    /// The grid, built on first use.
    fn index(&self) -> &Index {
        self.index.get_or_init(|| {
            let (vertices, triangles) = (self.vertices, self.triangles);
            let mut boxes = Vec::with_capacity(triangles.len());
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for t in triangles {
                let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
                for &v in t {
                    let p = vertices[v as usize];
                    for k in 0..2 {
                        a[k] = a[k].min(p[k]);
                        b[k] = b[k].max(p[k]);
                    }
                }
                for k in 0..2 {
                    lo[k] = lo[k].min(a[k]);
                    hi[k] = hi[k].max(b[k]);
                }
                boxes.push([a[0], a[1], b[0], b[1]]);
            }
            // Four cells a triangle: few candidates per query, even among long thin triangles.
            let grid = Grid::new(lo, hi, 4 * triangles.len().max(1));
            let buckets = Buckets::counted(grid.len(), boxes.len(), |i, f| {
                let b = boxes[i];
                grid.box_cells([b[0], b[1]], [b[2], b[3]], f)
            });
            Index {
                boxes,
                grid,
                buckets,
            }
        })
    }

    /// The first input triangle (lowest index) whose closed area holds `p`, exactly.
    pub(super) fn triangle_at(&self, p: [f64; 2]) -> Option<u32> {
        let xy = |v: u32| {
            let q = self.vertices[v as usize];
            [q[0], q[1]]
        };
        let index = self.index();
        index
            .buckets
            .cell(index.grid.cell_of(p))
            .iter()
            .copied()
            .find(|&i| {
                let b = index.boxes[i as usize];
                if p[0] < b[0] || p[1] < b[1] || p[0] > b[2] || p[1] > b[3] {
                    return false;
                }
                let [a, b, c] = self.triangles[i as usize];
                let (a, b, c) = (xy(a), xy(b), xy(c));
                orient(a, b, p) != Orientation::Clockwise
                    && orient(b, c, p) != Orientation::Clockwise
                    && orient(c, a, p) != Orientation::Clockwise
            })
    }

    /// Height of the input surface at `p` (linear in the triangle that holds it), or `None`
    /// outside the input mesh.
    pub(super) fn height(&self, p: [f64; 2]) -> Option<f64> {
        self.height_near(p, u32::MAX).map(|(z, _)| z)
    }

    /// [`Surface::height`] and the triangle holding `p`, found by a visibility walk from triangle
    /// `start` (exact orientations; any triangle, or `u32::MAX`), or by the grid when the walk
    /// reaches the boundary or takes long (both find a triangle whose closed area holds `p`).
    pub(super) fn height_near(&self, p: [f64; 2], start: u32) -> Option<(f64, u32)> {
        let xy = |v: u32| {
            let q = self.vertices[v as usize];
            [q[0], q[1]]
        };
        let mut found = None;
        let mut t = start;
        if (t as usize) < self.triangles.len() {
            'walk: for _ in 0..256 {
                let tri = self.triangles[t as usize];
                for k in 0..3 {
                    if orient(xy(tri[k]), xy(tri[(k + 1) % 3]), p) == Orientation::Clockwise {
                        let twin = self.twins[3 * t as usize + k];
                        if twin == u32::MAX {
                            break 'walk;
                        }
                        t = twin / 3;
                        continue 'walk;
                    }
                }
                found = Some(t);
                break;
            }
        }
        let t = match found {
            Some(t) => t,
            None => self.triangle_at(p)?,
        };
        let [a, b, c] = self.triangles[t as usize].map(|v| self.vertices[v as usize]);
        Some((planar(a, b, c, p), t))
    }
}

/// Heights on `surface` of the points `p`, each found by a walk from the last point's triangle:
/// the points are visited in rows of a grid over their extent, so each walk is short and the
/// triangles it reads are warm. A point a rounding error outside the surface gets the plane of
/// the last triangle found.
pub(super) fn heights(surface: &Surface<'_>, p: &[[f64; 2]]) -> Vec<f64> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for q in p {
        for k in 0..2 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let cell = (((hi[0] - lo[0]) * (hi[1] - lo[1])) / p.len().max(1) as f64)
        .sqrt()
        .max(f64::MIN_POSITIVE)
        * 16.0;
    let key = |q: [f64; 2]| {
        let (cx, cy) = (
            ((q[0] - lo[0]) / cell) as u64,
            ((q[1] - lo[1]) / cell) as u64,
        );
        // Boustrophedon rows: the walk turns round at a row's end instead of jumping back.
        let cx = if cy % 2 == 1 {
            u64::from(u32::MAX) - cx
        } else {
            cx
        };
        (cy << 32) | cx
    };
    let mut order: Vec<(u64, u32)> = p
        .iter()
        .enumerate()
        .map(|(i, &q)| (key(q), i as u32))
        .collect();
    order.sort_unstable();
    let mut out = vec![f64::NAN; p.len()];
    // Start at the triangle whose first corner is nearest the first point (no grid needed).
    let mut t = match order.first() {
        None => return out,
        Some(&(_, i)) => {
            let q = p[i as usize];
            let d = |t: &[u32; 3]| {
                let v = surface.vertices[t[0] as usize];
                (v[0] - q[0]).powi(2) + (v[1] - q[1]).powi(2)
            };
            (0..surface.triangles.len())
                .min_by(|&a, &b| d(&surface.triangles[a]).total_cmp(&d(&surface.triangles[b])))
                .map_or(u32::MAX, |t| t as u32)
        }
    };
    for (_, i) in order {
        let q = p[i as usize];
        match surface.height_near(q, t) {
            Some((z, found)) => {
                out[i as usize] = z;
                t = found;
            }
            None if t != u32::MAX => {
                let [a, b, c] = surface.triangles[t as usize].map(|v| surface.vertices[v as usize]);
                out[i as usize] = planar(a, b, c, q);
            }
            None => {}
        }
    }
    out
}
