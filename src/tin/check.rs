//! The structural check of a [`Tin`] (tests and fuzzing).

use super::{EdgeId, Tin, UNTRACKED, VertexId};
use crate::error::{Error, Result};
use crate::geom::predicates::Orientation;

impl Tin {
    /// Checks the structure: twins are mutual, triangles counter-clockwise, vertex edges valid,
    /// hull edges convex, and every unconstrained edge locally Delaunay (perturbed rule).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first violation.
    pub fn check(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Invalid(m));
        let mut live = 0;
        for t in self.triangles() {
            live += 1;
            let [a, b, c] = self.tri_vertices(t);
            if self.orient_v(a, b, c) != Orientation::CounterClockwise {
                return bad(format!("triangle {} is not counter-clockwise", t.0));
            }
            for e in [t.edge(), t.edge().next(), t.edge().prev()] {
                match self.twin(e) {
                    Some(f) => {
                        if !self.is_live(f.tri()) || self.twin(f) != Some(e) {
                            return bad(format!("edge {} has a broken twin", e.0));
                        }
                        if self.org(f) != self.dst(e) || self.dst(f) != self.org(e) {
                            return bad(format!("edge {} and its twin differ", e.0));
                        }
                        if self.is_constrained(e) != self.is_constrained(f) {
                            return bad(format!("edge {} constrained on one side only", e.0));
                        }
                        let d = self.org(f.prev());
                        if !self.is_constrained(e) && self.in_circle(a, b, c, d) {
                            return bad(format!("edge {} is not locally Delaunay", e.0));
                        }
                    }
                    None => {
                        // Hull convexity: the next hull edge turns left or goes straight.
                        let (u, v) = (self.org(e), self.dst(e));
                        let nxt = self.next_hull_edge(e);
                        let w = self.dst(nxt);
                        if self.orient_v(u, v, w) == Orientation::Clockwise {
                            return bad(format!("hull is not convex at vertex {}", v.0));
                        }
                    }
                }
            }
        }
        if live != self.live_triangles {
            return bad("triangle count is off".into());
        }
        for (v, &e) in self.vedge.iter().enumerate() {
            if e < UNTRACKED
                && (e as usize >= self.mesh.origin.len()
                    || self.org(EdgeId(e)) != VertexId(v as u32)
                    || !self.is_live(EdgeId(e).tri()))
            {
                return bad(format!("vertex {v} has a stale edge"));
            }
        }
        Ok(())
    }
}
