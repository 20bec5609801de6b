//! The candidates in a fixed grid of small cells (each cell's points in point order), so that a
//! triangle an iteration created or changed finds its candidates by scanning the cells under
//! its bounding box with exact point-in-triangle tests ([`holds`]: the same owner as
//! [`super::holder`] gives a walk's answer), instead of each candidate walking from its old
//! triangle.

use super::{Densify, NONE};
use crate::error::{Error, Result};
use crate::geom::predicates::{Orientation, orient};
use crate::tin::{EdgeId, Tin, TriId, VertexId};
use rayon::prelude::*;

/// Triangles one task scans (pieces on every core).
const SCAN_PIECE: usize = 256;

/// The candidates by cell: cell `c`'s are `pts[start[c]..start[c + 1]]`.
#[derive(Default)]
pub(super) struct Cells {
    x0: f64,
    y0: f64,
    inv: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    pts: Vec<u32>,
    /// A triangle whose bounding box covers more cells than this is not scanned (its
    /// candidates walk, as before); 0: no triangle is.
    pub(super) limit: usize,
}

impl Cells {
    /// The cells of the candidates `cand` in a triangle (`tri`; points of `tin`, point `i`
    /// at vertex `virtuals + i`).
    pub(super) fn new(tin: &Tin, virtuals: usize, cand: &[u32], tri: &[u32]) -> Cells {
        let env = |k: &str, v: f64| {
            std::env::var(k)
                .ok()
                .and_then(|s| s.parse().ok())
                .unwrap_or(v)
        };
        let per_cell = env("SWEEPTIN_GROUND_CELL_PER", 4.0);
        let limit = env("SWEEPTIN_GROUND_CELL_LIMIT", 16.0) as usize;
        let cand: Vec<u32> = cand
            .iter()
            .copied()
            .filter(|&i| tri[i as usize] != NONE)
            .collect();
        let cand = &cand[..];
        if cand.is_empty() || limit == 0 {
            return Cells::default();
        }
        let xy = |i: u32| tin.xy(VertexId((virtuals + i as usize) as u32));
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for &i in cand {
            let p = xy(i);
            b = [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ];
        }
        let area = ((b[2] - b[0]) * (b[3] - b[1])).max(f64::MIN_POSITIVE);
        let side = (area / cand.len() as f64 * per_cell).sqrt().max(1e-9);
        let nx = (((b[2] - b[0]) / side) as usize + 1).min(1 << 15);
        let ny = (((b[3] - b[1]) / side) as usize + 1).min(1 << 15);
        let mut c = Cells {
            x0: b[0],
            y0: b[1],
            inv: 1.0 / side,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            pts: vec![0; cand.len()],
            limit,
        };
        let cell = |c: &Cells, i: u32| {
            let p = xy(i);
            c.cy(p[1]) * c.nx + c.cx(p[0])
        };
        for &i in cand {
            let k = cell(&c, i);
            c.start[k + 1] += 1;
        }
        for k in 1..c.start.len() {
            c.start[k] += c.start[k - 1];
        }
        let mut fill = c.start.clone();
        for &i in cand {
            let k = cell(&c, i);
            c.pts[fill[k] as usize] = i;
            fill[k] += 1;
        }
        c
    }

    #[inline]
    fn cx(&self, x: f64) -> usize {
        (((x - self.x0) * self.inv).max(0.0) as usize).min(self.nx - 1)
    }

    #[inline]
    fn cy(&self, y: f64) -> usize {
        (((y - self.y0) * self.inv).max(0.0) as usize).min(self.ny - 1)
    }

    pub(super) fn heap_bytes(&self) -> usize {
        4 * (self.start.capacity() + self.pts.capacity())
    }
}

impl Densify<'_> {
    /// Links the candidates of the scanned triangles of `touched` (see [`Densify::scan_cells`])
    /// and takes them out of `gathered` (the candidates to move, in point order).
    pub(super) fn take_scanned(
        &mut self,
        touched: &[TriId],
        gathered: &mut Vec<u32>,
    ) -> Result<()> {
        if self.cells.limit == 0 || self.cells.nx == 0 {
            return Ok(());
        }
        // The candidates to move, one bit each: the scan claims only these (a candidate on an
        // edge or at a vertex whose triangle did not change stays where it is, as before).
        for &i in gathered.iter() {
            self.moving[i as usize / 64] |= 1 << (i % 64);
        }
        let mut scanned = std::mem::take(&mut self.scanned);
        self.scan_cells(touched, &mut scanned);
        let mut twice = false;
        for &(t, i) in &scanned {
            self.link(i, t);
            let w = &mut self.moving[i as usize / 64];
            twice |= *w & (1 << (i % 64)) == 0;
            *w &= !(1 << (i % 64));
        }
        let moving = &mut self.moving;
        gathered.retain(|&i| {
            let w = &mut moving[i as usize / 64];
            let left = *w & (1 << (i % 64)) != 0;
            *w &= !(1 << (i % 64));
            left
        });
        if twice {
            return Err(Error::Internal(
                "ground: a candidate found in two triangles".into(),
            ));
        }
        self.scanned = scanned;
        Ok(())
    }

    /// The candidates held by the live triangles of `tris` whose boxes cover at most
    /// `cells.limit` cells, as `(triangle, point)` in `tris`' order (each triangle's in cell
    /// order).
    pub(super) fn scan_cells(&self, tris: &[TriId], out: &mut Vec<(u32, u32)>) {
        out.clear();
        let c = &self.cells;
        if c.limit == 0 || c.nx == 0 {
            return;
        }
        let piece = |tris: &[TriId]| {
            let mut found = Vec::new();
            for &t in tris {
                if !self.tin.is_live(t) {
                    continue;
                }
                let vs = self.tin.tri_vertices(t);
                let p = [self.tin.xy(vs[0]), self.tin.xy(vs[1]), self.tin.xy(vs[2])];
                let (x0, x1) = (
                    p[0][0].min(p[1][0]).min(p[2][0]),
                    p[0][0].max(p[1][0]).max(p[2][0]),
                );
                let (y0, y1) = (
                    p[0][1].min(p[1][1]).min(p[2][1]),
                    p[0][1].max(p[1][1]).max(p[2][1]),
                );
                let (cx0, cx1, cy0, cy1) = (c.cx(x0), c.cx(x1), c.cy(y0), c.cy(y1));
                if (cx1 - cx0 + 1) * (cy1 - cy0 + 1) > c.limit {
                    continue;
                }
                for cy in cy0..=cy1 {
                    let row = cy * c.nx;
                    let (a, b) = (c.start[row + cx0] as usize, c.start[row + cx1 + 1] as usize);
                    for &i in &c.pts[a..b] {
                        if self.moving[i as usize / 64] & (1 << (i % 64)) == 0 {
                            continue;
                        }
                        let q = self.tin.xy(self.vid(i));
                        if q[0] < x0 || q[0] > x1 || q[1] < y0 || q[1] > y1 {
                            continue;
                        }
                        if holds(&self.tin, t, &p, q) {
                            found.push((t.0, i));
                        }
                    }
                }
            }
            found
        };
        if tris.len() < 2 * SCAN_PIECE {
            *out = piece(tris);
        } else {
            let parts: Vec<Vec<(u32, u32)>> = tris.par_chunks(SCAN_PIECE).map(piece).collect();
            for part in parts {
                out.extend_from_slice(&part);
            }
        }
    }
}

/// Does triangle `t` (corners at `p`, counter-clockwise) hold `q`: is `q` in it (closed), and,
/// on an edge, is `t` the lower slot of the edge's two triangles? Exact ([`orient`]), the rule
/// of [`super::holder`]. Never at a corner: a candidate at a vertex stays with the triangle of
/// the vertex's out-edge when it was last moved (which may change while that triangle does
/// not), so it moves only when its triangle changes, by a walk, as before.
#[inline]
fn holds(tin: &Tin, t: TriId, p: &[[f64; 2]; 3], q: [f64; 2]) -> bool {
    let mut on = NONE;
    for k in 0..3 {
        let k1 = if k == 2 { 0 } else { k + 1 };
        match orient(p[k], p[k1], q) {
            Orientation::Clockwise => return false,
            Orientation::Collinear => {
                if p[k] == q || p[k1] == q {
                    return false;
                }
                on = k as u32;
            }
            Orientation::CounterClockwise => {}
        }
    }
    if on == NONE {
        return true;
    }
    match tin.twin(EdgeId(3 * t.0 + on)) {
        Some(f) => t.0 < f.tri().0,
        None => true,
    }
}
