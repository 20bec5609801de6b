//! The two heuristics of Domiter & Žalik (section 3.4.1) that keep the advancing front short and
//! smooth (the hole angle is widened from π/2, see `HOLE_COS`), and the closing of the front to the convex hull.
//!
//! The heuristics only choose *which* valid triangle to add next; each candidate is checked with the
//! exact [`orient`](crate::geom::predicates::orient_ids) predicate and legalised, so the floating-point
//! angles used here can never change the final triangulation, only how fast it is reached.

use super::front::NodeId;
use super::{Mode, Sweep};
use crate::geom::predicates::is_artificial;


/// Cosine of the largest hole angle that is filled at once. The paper uses π/2; about 114° cost
/// 3–5% fewer instructions on uniform and clustered points and the same on lidar-like rows
/// (callgrind, 200k points; `docs/BENCHMARKS.md`).
const HOLE_COS: f64 = -0.4;

/// The longest walk down to a basin's bottom or up to its far rim. A longer basin is left to the
/// later points and the closing of the hull: without a bound, a front that is one long basin
/// never deep enough to fill (points on a circle: the lower arc) was walked end to end at every
/// insertion, quadratic (80,000 points on a ring: 2.6 s, 1 M never finished).
const BASIN_WALK: usize = 64;

/// Walk direction along the front.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Dir {
    Left,
    Right,
}

impl<H: Mode> Sweep<H> {
    #[inline(always)]
    fn step_dir(&self, n: NodeId, d: Dir) -> NodeId {
        match d {
            Dir::Left => self.front.prev(n),
            Dir::Right => self.front.next(n),
        }
    }

    #[inline(always)]
    fn xy(&self, n: NodeId) -> [f64; 2] {
        self.pts[self.front.vertex(n).0 as usize]
    }

    #[inline(always)]
    fn is_real(&self, n: NodeId) -> bool {
        !is_artificial(self.front.vertex(n).0)
    }

    /// Can node `n` be covered by the triangle (prev, n, next)? Exact: `n` strictly below the
    /// segment prev → next, all three real.
    #[inline]
    fn fillable(&self, n: NodeId) -> bool {
        if !self.is_real(n) {
            return false;
        }
        let (p, q) = (self.front.prev(n), self.front.next(n));
        self.is_real(p)
            && self.is_real(q)
            && self
                .orient(
                    self.front.vertex(p),
                    self.front.vertex(n),
                    self.front.vertex(q),
                )
                .is_ccw()
    }

    /// Is the hole at `n` (angle between its two front segments) at most about 114°?
    #[inline]
    fn hole_is_narrow(&self, n: NodeId) -> bool {
        let (a, m, b) = (
            self.xy(self.front.prev(n)),
            self.xy(n),
            self.xy(self.front.next(n)),
        );
        let (ax, ay, bx, by) = (a[0] - m[0], a[1] - m[1], b[0] - m[0], b[1] - m[1]);
        let d = ax * bx + ay * by;
        d >= HOLE_COS * ((ax * ax + ay * ay) * (bx * bx + by * by)).sqrt()
    }

    /// After inserting the point at node `n`: fill the narrow holes next to it on both sides, then
    /// the basins.
    pub(crate) fn fill_holes(&mut self, n: NodeId) {
        for d in [Dir::Right, Dir::Left] {
            loop {
                let m = self.step_dir(n, d);
                if !self.fillable(m) || !self.hole_is_narrow(m) {
                    break;
                }
                self.stats.fills += 1;
                self.fill(m);
            }
        }
        for d in [Dir::Right, Dir::Left] {
            if self.is_basin(n, d) {
                self.fill_basin(n, d);
            }
        }
    }

    /// Does the front drop away steeply (more than 45°) from node `n` in direction `d`?
    fn is_basin(&self, n: NodeId, d: Dir) -> bool {
        let m = self.step_dir(n, d);
        if !self.is_real(m) {
            return false;
        }
        let k = self.step_dir(m, d);
        if !self.is_real(k) {
            return false;
        }
        let (p, q) = (self.xy(n), self.xy(k));
        p[1] - q[1] > (q[0] - p[0]).abs()
    }

    /// Fills the basin next to node `n` in direction `d`, from its bottom up, until what is left is
    /// shallower than it is wide.
    fn fill_basin(&mut self, n: NodeId, d: Dir) {
        let near = self.step_dir(n, d);
        // Walk down to the bottom, then up to the far rim.
        let mut bottom = near;
        for step in 0.. {
            let m = self.step_dir(bottom, d);
            if !self.is_real(m) || self.xy(m)[1] > self.xy(bottom)[1] {
                break;
            }
            if step == BASIN_WALK {
                return;
            }
            bottom = m;
        }
        if bottom == near {
            return;
        }
        let mut far = bottom;
        for step in 0.. {
            let m = self.step_dir(far, d);
            if !self.is_real(m) || self.xy(m)[1] <= self.xy(far)[1] {
                break;
            }
            if step == BASIN_WALK {
                return;
            }
            far = m;
        }
        if far == bottom {
            return;
        }
        let rim = self.xy(n)[1].min(self.xy(far)[1]);
        let width = (self.xy(far)[0] - self.xy(n)[0]).abs();
        let mut node = bottom;
        loop {
            if width > rim - self.xy(node)[1] || !self.fillable(node) {
                return;
            }
            let (p, q) = (self.front.prev(node), self.front.next(node));
            self.stats.fills += 1;
            self.fill(node);
            let (p_rim, q_rim) = match d {
                Dir::Right => (p == n, q == far),
                Dir::Left => (q == n, p == far),
            };
            node = match (p_rim, q_rim) {
                (true, true) => return,
                (true, false) => q,
                (false, true) => p,
                (false, false) => {
                    if self.xy(p)[1] < self.xy(q)[1] {
                        p
                    } else {
                        q
                    }
                }
            };
        }
    }

    /// Closes the front to its upper convex hull (Graham scan from left to right, exact). With the
    /// symbolic artificial points the result is the Delaunay triangulation of the data plus
    /// `P-1`, `P-2`, whose real triangles are the data's Delaunay triangulation.
    pub(crate) fn close_hull(&mut self) {
        let (head, tail) = (self.front.head, self.front.tail);
        let mut n = self.front.next(head);
        let mut walked = 0usize;
        while n != tail {
            walked += 1;
            // A front of millions of nodes (points on a line) spilled to temporary files: the
            // walk would bring the whole front and its points into memory at once (the fills
            // look at the resident memory themselves, `Hooks::spill_due`).
            if walked.is_multiple_of(1 << 16) || self.hooks.spill_due() {
                self.release_spilled();
            }
            let (p, q) = (self.front.prev(n), self.front.next(n));
            if self.fillable(n) {
                self.stats.hull_fills += 1;
                self.fill(n);
                n = if p == head { q } else { p };
            } else {
                n = q;
            }
        }
    }
}
