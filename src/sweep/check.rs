//! [`Sweep::check`]: every invariant of a sweep in progress, checked exactly. O(triangles); for
//! tests, fuzzing and debugging.

use super::{Mode, Sweep};
use crate::error::{Error, Result};
use crate::geom::predicates::{CircleSide, incircle_ids};
use crate::mesh::{Across, EdgeId, TriId};

impl<H: Mode> Sweep<H> {
    /// Verifies the sweep's invariants and returns the first violation found:
    ///
    /// * every triangle is strictly counter-clockwise (symbolic points included);
    /// * twins are mutual, run in opposite directions and agree on the constrained flag;
    /// * every boundary half-edge is either the bottom edge `P-1 → P-2` or lies under exactly the
    ///   front segment that names it, and every front segment names its half-edge;
    /// * the front runs from `P-1` to `P-2`, strictly increasing in `x`;
    /// * every unconstrained interior edge is locally Delaunay (perturbed exact in-circle).
    ///
    /// # Errors
    /// [`Error::Internal`] describing the first violation.
    pub fn check(&self) -> Result<()> {
        self.check_triangles()
            .and_then(|()| self.check_front())
            .map_err(Error::Internal)
    }

    fn check_triangles(&self) -> Result<(), String> {
        let m = &self.mesh;
        let mut hull_edges = 0;
        for t in 0..m.triangle_count() as u32 {
            if !m.is_live(TriId(t)) {
                continue;
            }
            let [a, b, c] = m.tri_vertices(TriId(t));
            if !self.orient(a, b, c).is_ccw() {
                return Err(format!(
                    "triangle {t} ({a:?}, {b:?}, {c:?}) is not counter-clockwise"
                ));
            }
            for k in 0..3 {
                let e = EdgeId(3 * t + k);
                match m.across(e) {
                    Across::Twin(f) => {
                        if m.across(f) != Across::Twin(e) {
                            return Err(format!("half-edge {e:?}: twin {f:?} does not point back"));
                        }
                        if m.org(f) != m.dst(e) || m.dst(f) != m.org(e) {
                            return Err(format!("half-edges {e:?} and {f:?} are not opposite"));
                        }
                        if m.is_constrained(e) != m.is_constrained(f) {
                            return Err(format!("half-edges {e:?}, {f:?} disagree on constraint"));
                        }
                        if !m.is_constrained(e) && e < f {
                            let d = self.apex(f);
                            let [p, q, r] = [self.apex(e), m.org(e), m.dst(e)];
                            if incircle_ids(&self.pts, p.0, q.0, r.0, d.0) == CircleSide::Inside {
                                return Err(format!(
                                    "edge {q:?}-{r:?} is not locally Delaunay ({p:?} / {d:?})"
                                ));
                            }
                        }
                    }
                    Across::Front(n) => {
                        let node = self.front.node(n);
                        if node.edge != e {
                            return Err(format!("front node {n} does not own half-edge {e:?}"));
                        }
                        let next = self.front.node(node.next);
                        if m.dst(e) != node.v || m.org(e) != next.v {
                            return Err(format!("half-edge {e:?} is not under front node {n}"));
                        }
                    }
                    Across::Hull => hull_edges += 1,
                }
            }
        }
        // In batch mode the only boundary edge off the front is the bottom edge P-1 → P-2; when
        // streaming, edges facing finalised triangles are boundary edges too.
        if !H::FINALISES && hull_edges != 1 {
            return Err(format!(
                "{hull_edges} boundary edges outside the front (want 1)"
            ));
        }
        Ok(())
    }

    fn check_front(&self) -> Result<(), String> {
        let f = &self.front;
        let mut count = 0;
        let mut prev_x = f64::NEG_INFINITY;
        let mut last = f.head;
        for n in f.iter() {
            count += 1;
            let node = f.node(n);
            if n != f.head && node.x <= prev_x {
                return Err(format!("front is not increasing in x at node {n}"));
            }
            if n != f.head && f.node(node.prev).next != n {
                return Err(format!("front links broken at node {n}"));
            }
            if n != f.tail {
                if self.mesh.across(node.edge) != Across::Front(n) {
                    return Err(format!("front node {n}: its half-edge does not name it"));
                }
                let x = self.pts[node.v.0 as usize][0];
                if n != f.head && x != node.x {
                    return Err(format!("front node {n}: stale x"));
                }
            }
            prev_x = node.x;
            last = n;
        }
        if last != f.tail {
            return Err("front does not end at P-2".into());
        }
        if count != f.len() {
            return Err(format!("front has {count} nodes but counts {}", f.len()));
        }
        Ok(())
    }
}
