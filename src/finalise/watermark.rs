//! Watermarks: how far behind the sweep line the triangles still to come can lie (a progress
//! hint for the sinks, [`Event::Watermark`]).

use super::{Event, StreamingSweep};
use crate::geom::predicates::is_artificial;

/// Triangle slots visited between drops of the spilled tables' pages.
const RELEASE_EVERY: usize = 1 << 16;

/// Is the circumcircle of `a b c` narrower than `limit` in radius and inside the x range of the
/// data? (Floating point: a heuristic for watermarks only, never a topological decision.)
fn ordinary(a: [f64; 2], b: [f64; 2], c: [f64; 2], limit: f64, x_range: (f64, f64)) -> bool {
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    if d == 0.0 {
        return false;
    }
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    let r = (ux * ux + uy * uy).sqrt();
    let x = a[0] + ux;
    r < limit && x - r >= x_range.0 && x + r <= x_range.1
}

impl StreamingSweep {
    /// Appends a watermark event: no live triangle of ordinary size has a vertex below the
    /// returned `y`, and every later point is above it. Triangles whose finalisation waits for
    /// the end or for a long time are left out — wider than 100 point spacings, or with a
    /// circumcircle wider than that or reaching beyond the data's x range (the triangles along the
    /// left and right sides of the convex hull, whose disks the front never covers), or with a
    /// vertex more than 100 spacings below the sweep line (the rim of an empty area such as a lake,
    /// which waits until the sweep has crossed it) — so they may arrive later below the watermark
    /// ("late"), which every sink handles. The watermark therefore trails the sweep line by at
    /// most 100 spacings, whatever the data's holes. O(live triangles); call it every few
    /// thousand points.
    pub fn emit_watermark(&mut self) -> f64 {
        let fin = self.sweep.hooks();
        let wide = 100.0 / fin.inv_h;
        let mut w = fin.last[1];
        let stuck = fin.last[1] - wide;
        let x_range = fin.x_range;
        let len = self.sweep.mesh().origin.len();
        let mut from = 0;
        while from < len {
            let to = (from + 3 * RELEASE_EVERY).min(len);
            w = self.lowest_ordinary(from..to, w, stuck, wide, x_range);
            // Tables spilled to temporary files: the walk would bring them all into memory.
            self.sweep.release_spilled();
            from = to;
        }
        self.fin().events.push(Event::Watermark(w));
        w
    }

    /// [`StreamingSweep::emit_watermark`]'s minimum `w` over the triangle slots whose half-edges
    /// are `edges`.
    fn lowest_ordinary(
        &self,
        edges: std::ops::Range<usize>,
        mut w: f64,
        stuck: f64,
        wide: f64,
        x_range: (f64, f64),
    ) -> f64 {
        let pts = self.sweep.points();
        let o = &self.sweep.mesh().origin;
        for t in edges.step_by(3) {
            let [a, b, c] = [o[t], o[t + 1], o[t + 2]];
            if a == crate::mesh::DEAD
                || is_artificial(a.0)
                || is_artificial(b.0)
                || is_artificial(c.0)
            {
                continue;
            }
            let (pa, pb, pc) = (pts[a.0 as usize], pts[b.0 as usize], pts[c.0 as usize]);
            let low = pa[1].min(pb[1]).min(pc[1]);
            if low < w && low >= stuck {
                let span = pa[0].max(pb[0]).max(pc[0]) - pa[0].min(pb[0]).min(pc[0]);
                if span < wide && ordinary(pa, pb, pc, wide, x_range) {
                    w = low;
                }
            }
        }
        w
    }

}
