//! Lawson legalisation: flip every edge whose opposite vertex lies inside the neighbouring
//! triangle's circumcircle, with an explicit stack (no recursion, so no stack overflow on long
//! flip cascades).
//!
//! Two entry points:
//! * `Sweep::legalize_from_apex` after a point event: only edges opposite the new point can become
//!   illegal (the classic incremental-insertion argument), so a flip pushes just the two edges
//!   opposite the apex in the two new triangles.
//! * `Sweep::legalize_all` after a fill, which adds a triangle between existing vertices: there is
//!   no new point to argue from, so a flip pushes all four outer edges of the quadrilateral.

use super::{Mode, Sweep};
use crate::geom::predicates::{CircleSide, incircle_ids};
use crate::mesh::{Across, EdgeId, VertexId};

impl<H: Mode> Sweep<H> {
    /// If the edge `a` (which has a twin) is illegal, flips it and returns the four outer edges
    /// `[a, a.next, b, b.next]` in their new slots; `None` when it is legal or constrained.
    ///
    /// Before: triangle `a` is (pr, pl, p0) with `a = pr → pl`, triangle `b` is (pl, pr, p1).
    /// After: triangle `a` is (p1, pl, p0), triangle `b` is (p0, pr, p1); the new diagonal is
    /// `p0 → p1` at `a.prev` and `p1 → p0` at `b.prev`.
    #[inline(always)]
    fn flip_if_illegal(&mut self, a: EdgeId) -> Option<EdgeId> {
        let word = self.mesh.link[a.idx()];
        let b = match crate::mesh::across(word) {
            Across::Twin(b) if word & crate::mesh::CONSTRAINED == 0 => b,
            _ => return None,
        };
        let (al, ar) = (a.next(), a.prev());
        let bl = b.prev();
        let o = &self.mesh.origin;
        let (p0, pr, pl, p1) = (o[ar.idx()], o[a.idx()], o[al.idx()], o[bl.idx()]);
        if incircle_ids(&self.pts, p0.0, pr.0, pl.0, p1.0) != CircleSide::Inside {
            return None;
        }
        self.stats.flips += 1;
        let (hbl, har) = (self.mesh.link[bl.idx()], self.mesh.link[ar.idx()]);
        self.mesh.origin[a.idx()] = p1;
        self.mesh.origin[b.idx()] = p0;
        self.relink(a, hbl);
        self.relink(b, har);
        self.mesh.pair(ar, bl, false);
        self.hooks.flipped(a.tri(), b.tri(), [pr, pl], [p0, p1]);
        Some(b)
    }

    /// Legalises edge `a` of a triangle whose apex (the vertex opposite `a`) was just inserted.
    pub(crate) fn legalize_from_apex(&mut self, a: EdgeId) {
        let base = self.stack.len();
        let mut a = a;
        loop {
            if let Some(b) = self.flip_if_illegal(a) {
                // Both edges opposite the apex: `a` (now p1 → pl) and `b.next` (pr → p1).
                self.stack.push(b.next());
                continue;
            }
            if self.stack.len() == base {
                return;
            }
            a = self.stack.pop().expect("stack is not empty");
        }
    }

    /// Legalises the given edges and everything their flips disturb.
    pub(crate) fn legalize_all(&mut self, edges: &[EdgeId]) {
        let base = self.stack.len();
        self.stack.extend_from_slice(edges);
        while self.stack.len() > base {
            let a = self.stack.pop().expect("stack is not empty");
            if let Some(b) = self.flip_if_illegal(a) {
                self.stack.extend_from_slice(&[a, a.next(), b, b.next()]);
                // A flip touches two triangles and four vertices: on held triangles spilled to
                // files (a ring of points), a cascade brings their pages in.
                if self.hooks.spill_due() {
                    self.release_spilled();
                }
            }
        }
    }

    /// The vertex opposite half-edge `e` in its triangle.
    #[inline(always)]
    pub(crate) fn apex(&self, e: EdgeId) -> VertexId {
        self.mesh.org(e.prev())
    }
}
