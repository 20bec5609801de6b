//! Point insertion (Herva 2009, section 5.1): split the triangle or edge under the point, or
//! extend the hull, then restore the Delaunay property with Lawson flips.

use super::{EdgeId, NONE, PointLocation, Tin, TriId, VertexId};
use crate::error::{Error, Result};
use crate::geom::predicates::{Orientation, check_coord};
use crate::mesh::{BOUNDARY, CONSTRAINED};

impl Tin {
    /// Inserts `p = [x, y, z]` and restores the Delaunay property. A point exactly at an existing
    /// vertex is not inserted: that vertex is returned (its height is kept).
    ///
    /// # Errors
    /// [`Error::NonFinite`] / [`Error::CoordinateOutOfRange`] for a bad coordinate,
    /// [`Error::TooManyPoints`] past `mesh::MAX_VERTICES` vertex ids, [`Error::Invalid`]
    /// on an empty TIN.
    pub fn insert(&mut self, p: [f64; 3]) -> Result<VertexId> {
        check_point(p, self.xy.len() as u64)?;
        let loc = self.locate([p[0], p[1]]);
        if let PointLocation::OnVertex(v) = loc {
            return Ok(v);
        }
        let v = self.push_vertex(p)?;
        self.insert_located(v, loc)?;
        Ok(v)
    }

    /// A vertex id for `p`, not in the triangulation: [`Tin::insert_vertex`] inserts it later
    /// (a caller that keeps its points in the TIN, inserted or not, holds each position once).
    ///
    /// # Errors
    /// As [`Tin::insert`].
    pub fn add_vertex(&mut self, p: [f64; 3]) -> Result<VertexId> {
        check_point(p, self.xy.len() as u64)?;
        self.push_vertex(p)
    }

    /// Inserts vertex `v` (added with [`Tin::add_vertex`], not in the triangulation) and
    /// restores the Delaunay property; a vertex already at its position is returned instead
    /// (`v` then stays out).
    ///
    /// # Errors
    /// [`Error::Invalid`] if `v` is not a vertex id outside the triangulation, or while vertex
    /// tracking is off.
    pub fn insert_vertex(&mut self, v: VertexId) -> Result<VertexId> {
        if (v.0 as usize) >= self.xy.len() || self.contains_vertex(v) || self.untracked {
            return Err(Error::Invalid(format!(
                "vertex {} cannot be inserted: it is not a vertex outside the triangulation",
                v.0
            )));
        }
        let loc = self.locate(self.xy(v));
        if let PointLocation::OnVertex(w) = loc {
            return Ok(w);
        }
        self.insert_located(v, loc)?;
        Ok(v)
    }

    /// Puts a removed vertex back, with the same id.
    ///
    /// # Errors
    /// [`Error::Invalid`] if `v` is in the triangulation or another vertex now has its position.
    pub fn restore(&mut self, v: VertexId) -> Result<()> {
        if (v.0 as usize) >= self.xy.len() || self.contains_vertex(v) || self.untracked {
            return Err(Error::Invalid(format!(
                "vertex {} cannot be restored: it is not a removed vertex",
                v.0
            )));
        }
        let loc = self.locate(self.xy(v));
        if let PointLocation::OnVertex(w) = loc {
            return Err(Error::Invalid(format!(
                "vertex {} cannot be restored: vertex {} has its position",
                v.0, w.0
            )));
        }
        self.insert_located(v, loc)
    }

    /// Inserts `p` known to lie in the closed triangle `t` (not at one of its vertices): no walk.
    /// Used by the grid simplifier, which knows the triangle of each candidate.
    ///
    /// # Errors
    /// [`Error::Invalid`] if `p` is outside `t` or at one of its vertices; as [`Tin::insert`].
    pub fn insert_in_triangle(&mut self, t: TriId, p: [f64; 3]) -> Result<VertexId> {
        check_point(p, self.xy.len() as u64)?;
        let q = [p[0], p[1]];
        let mut on_edge = None;
        for e in [t.edge(), t.edge().next(), t.edge().prev()] {
            let (a, b) = (self.org(e), self.dst(e));
            if self.p(a) == q || self.p(b) == q {
                return Err(Error::Invalid(
                    "point is at a vertex of the triangle".into(),
                ));
            }
            match self.orient_p(self.p(a), self.p(b), q) {
                Orientation::Clockwise => {
                    return Err(Error::Invalid("point is outside the triangle".into()));
                }
                Orientation::Collinear => on_edge = Some(e),
                Orientation::CounterClockwise => {}
            }
        }
        let loc = match on_edge {
            Some(e) => PointLocation::OnEdge(e),
            None => PointLocation::Inside(t),
        };
        let v = self.push_vertex(p)?;
        self.insert_located(v, loc)?;
        Ok(v)
    }

    /// Inserts `p` on the edge `e`, splitting it (and its twin): the new vertex takes the edge's
    /// place in both triangles and the halves keep its constrained flag, even when rounding left
    /// `p` a little off the edge's line (a segment's split point, as Triangle inserts it). The
    /// Delaunay property is then restored by flips.
    ///
    /// # Errors
    /// [`Error::Invalid`] unless every new triangle is strictly counter-clockwise (a hull edge's
    /// point may lie a rounding error outside the hull: the hull is then a hair from convex, which
    /// only [`Tin::locate`] outside the hull would notice); as [`Tin::insert`].
    pub fn split_edge_at(&mut self, e: EdgeId, p: [f64; 3]) -> Result<VertexId> {
        check_point(p, self.xy.len() as u64)?;
        let q = [p[0], p[1]];
        let (a, b, c) = (self.org(e), self.dst(e), self.org(e.prev()));
        let mut ok = self.orient_p(self.p(a), q, self.p(c)) == Orientation::CounterClockwise
            && self.orient_p(q, self.p(b), self.p(c)) == Orientation::CounterClockwise;
        if let Some(f) = self.twin(e) {
            let d = self.org(f.prev());
            ok &= self.orient_p(self.p(b), q, self.p(d)) == Orientation::CounterClockwise
                && self.orient_p(q, self.p(a), self.p(d)) == Orientation::CounterClockwise;
        }
        if !ok {
            return Err(Error::Invalid(format!(
                "split point ({}, {}) does not split the edge {} – {}",
                p[0], p[1], a.0, b.0
            )));
        }
        let v = self.push_vertex(p)?;
        self.insert_located(v, PointLocation::OnEdge(e))?;
        Ok(v)
    }

    pub(super) fn insert_located(&mut self, v: VertexId, loc: PointLocation) -> Result<()> {
        let mut stack = Vec::with_capacity(16);
        match loc {
            PointLocation::Inside(t) => self.split_triangle(v, t, &mut stack),
            PointLocation::OnEdge(e) => self.split_edge(v, e, &mut stack),
            PointLocation::Outside(e) if e.0 != NONE => self.extend_hull(v, e, &mut stack),
            _ => return Err(Error::Invalid("cannot insert into an empty TIN".into())),
        }
        self.live_vertices += 1;
        self.legalize(&mut stack);
        Ok(())
    }

    fn split_triangle(&mut self, v: VertexId, t: TriId, stack: &mut Vec<EdgeId>) {
        let [a, b, c] = self.tri_vertices(t);
        let e = t.idx();
        let l = &self.mesh.link;
        let [l0, l1, l2] = [l[e], l[e + 1], l[e + 2]];
        let t0 = self.set_triangle(t, a, b, v);
        let t1 = self.alloc_triangle(b, c, v);
        let t2 = self.alloc_triangle(c, a, v);
        self.mesh.link_to(t0, l0);
        self.mesh.link_to(t1, l1);
        self.mesh.link_to(t2, l2);
        self.pair(t0.next(), t1.prev());
        self.pair(t1.next(), t2.prev());
        self.pair(t2.next(), t0.prev());
        stack.extend([t0, t1, t2]);
    }

    fn split_edge(&mut self, v: VertexId, e: EdgeId, stack: &mut Vec<EdgeId>) {
        let flag = self.mesh.link[e.idx()] & CONSTRAINED;
        let twin = self.twin(e);
        let (a, b, c) = (self.org(e), self.dst(e), self.org(e.prev()));
        let (lb, lc) = (
            self.mesh.link[e.next().idx()],
            self.mesh.link[e.prev().idx()],
        );
        let ta = self.set_triangle(e.tri(), a, v, c);
        let tb = self.alloc_triangle(v, b, c);
        self.mesh.link_to(ta.prev(), lc);
        self.mesh.link_to(tb.next(), lb);
        self.pair(ta.next(), tb.prev());
        stack.extend([ta.prev(), tb.next()]);
        match twin {
            None => {
                // A hull edge: the halves stay on the hull, constrained if it was.
                self.mesh.link[ta.idx()] |= flag;
                self.mesh.link[tb.idx()] |= flag;
            }
            Some(f) => {
                let d = self.org(f.prev());
                let (lad, ldb) = (
                    self.mesh.link[f.next().idx()],
                    self.mesh.link[f.prev().idx()],
                );
                let tc = self.set_triangle(f.tri(), b, v, d);
                let td = self.alloc_triangle(v, a, d);
                self.mesh.link_to(tc.prev(), ldb);
                self.mesh.link_to(td.next(), lad);
                self.pair(tc.next(), td.prev());
                self.mesh.link_to(ta, td.0 | flag);
                self.mesh.link_to(tb, tc.0 | flag);
                stack.extend([tc.prev(), td.next()]);
            }
        }
    }

    fn extend_hull(&mut self, v: VertexId, e: EdgeId, stack: &mut Vec<EdgeId>) {
        let q = self.p(v);
        let visible = |tin: &Tin, h: EdgeId| {
            let (a, b) = (tin.org(h), tin.dst(h));
            tin.orient_p(tin.p(a), tin.p(b), q) == Orientation::Clockwise
        };
        // The visible hull edges, in hull order.
        let mut first = e;
        loop {
            let p = self.prev_hull_edge(first);
            if p == e || !visible(self, p) {
                break;
            }
            first = p;
        }
        let mut hull = vec![first];
        loop {
            let n = self.next_hull_edge(*hull.last().unwrap());
            if n == first || !visible(self, n) {
                break;
            }
            hull.push(n);
        }
        let mut prev_new: Option<EdgeId> = None;
        for h in hull {
            let (u, w) = (self.org(h), self.dst(h));
            // Triangle (w, u, v): w → u is the twin of the hull edge u → w.
            let t = self.alloc_triangle(w, u, v);
            self.mesh
                .link_to(t, h.0 | (self.mesh.link[h.idx()] & CONSTRAINED));
            if let Some(pn) = prev_new {
                // Previous triangle's v → u is this one's u → v.
                self.pair(t.next(), pn);
            }
            prev_new = Some(t.prev());
            stack.push(t);
        }
    }

    #[inline(always)]
    fn pair(&mut self, a: EdgeId, b: EdgeId) {
        self.mesh.pair(a, b, false);
    }

    /// The twin of `e` when `e` may be flipped: neither on the hull nor constrained.
    #[inline(always)]
    fn flippable_twin(&self, e: EdgeId) -> Option<EdgeId> {
        let l = self.mesh.link[e.idx()];
        (l & (BOUNDARY | CONSTRAINED) == 0).then_some(EdgeId(l))
    }

    /// Lawson flips from the edges in `stack`, each opposite the newly inserted vertex in its
    /// triangle (the standard insertion legalisation: flips stay in the new vertex's star).
    pub(super) fn legalize(&mut self, stack: &mut Vec<EdgeId>) {
        while let Some(e) = stack.pop() {
            let Some(f) = self.flippable_twin(e) else {
                continue;
            };
            let (a, b, p) = (self.org(e), self.dst(e), self.org(e.prev()));
            let d = self.org(f.prev());
            if self.in_circle(a, b, p, d) {
                self.flip(e);
                stack.push(e.prev());
                stack.push(f.next());
            }
        }
    }

    /// Restores the (constrained) Delaunay property around the given edges, by vertex pairs
    /// (robust to edge ids moving under flips): any non-Delaunay unconstrained edge is flipped and
    /// its quadrilateral's four sides are checked again.
    pub(super) fn legalize_edges(&mut self, mut stack: Vec<(VertexId, VertexId)>) {
        while let Some((u, w)) = stack.pop() {
            let Some(e) = self.find_edge(u, w) else {
                continue;
            };
            let Some(f) = self.flippable_twin(e) else {
                continue;
            };
            let (a, b, p) = (self.org(e), self.dst(e), self.org(e.prev()));
            let d = self.org(f.prev());
            if self.in_circle(a, b, p, d) {
                self.flip(e);
                stack.extend([(a, d), (d, b), (b, p), (p, a)]);
            }
        }
    }
}

pub(crate) fn check_point(p: [f64; 3], index: u64) -> Result<()> {
    if !p.iter().all(|c| c.is_finite()) {
        return Err(Error::NonFinite {
            index,
            x: p[0],
            y: p[1],
            z: p[2],
        });
    }
    for &value in &p[..2] {
        if !check_coord(value) {
            return Err(Error::CoordinateOutOfRange {
                index,
                value,
                max: crate::geom::predicates::MAX_COORD,
                min: crate::geom::predicates::MIN_NONZERO_COORD,
            });
        }
    }
    Ok(())
}
