//! Point removal (Herva 2009, sections 5.3–5.4).
//!
//! Removing a vertex leaves a hole bounded by its *link*: a closed, star-shaped polygon for an
//! interior vertex; an open chain for a hull vertex, whose hole is bounded by the chain and its
//! convex hull. Every link edge stays Delaunay (its empty-circle witness is unchanged), so the
//! triangles that fill the hole are exactly the Delaunay triangles of the link's vertices inside
//! it. They are found as *Delaunay ears*: three consecutive link vertices turning left whose
//! (perturbed) circle holds no other link vertex; such an ear always exists while the hole is not
//! filled (a triangulated polygon has two ears, at most one of which uses a new hull edge). No flip
//! is needed afterwards. Near breaklines the link edges need not be Delaunay; when no empty-circle
//! ear exists, any left-turning ear with no link vertex in it is taken and the new edges are then
//! legalised by flips (constrained Delaunay).

use super::{EdgeId, NONE, Tin, VertexId};
use crate::error::{Error, Result};
use crate::geom::predicates::Orientation;
use crate::mesh::{BOUNDARY, HULL, ID_MASK};

/// How a removal will fill the hole.
struct RemovalPlan {
    spokes: Vec<EdgeId>,
    ring: Vec<VertexId>,
    hull: bool,
    steps: Vec<(u32, bool)>,
}

impl Tin {
    /// Removes vertex `v` and re-triangulates its hole (Delaunay, or constrained Delaunay when
    /// breaklines are present). Hull vertices may be removed: the hull shrinks to the convex hull
    /// of the rest.
    ///
    /// # Errors
    /// [`Error::Invalid`] if `v` is not in the triangulation, is an end of a constrained edge, or
    /// if removing it would leave no triangle (all remaining points collinear). Nothing changes on
    /// error.
    pub fn remove(&mut self, v: VertexId) -> Result<()> {
        let plan = self.plan_removal(v)?;
        let RemovalPlan {
            spokes,
            mut ring,
            hull,
            steps,
        } = plan;
        // rim[i] = outside of the link edge ring[i] → ring[i+1].
        let mut rim: Vec<u32> = spokes
            .iter()
            .map(|&e| self.mesh.link[e.next().idx()])
            .collect();
        for &e in &spokes {
            self.free_triangle(e.tri());
        }
        for &r in &rim {
            if r & BOUNDARY == 0 {
                self.mesh.detach(EdgeId(r & ID_MASK));
            }
        }
        self.vedge[v.0 as usize] = NONE;
        self.live_vertices -= 1;
        // Ring vertices keep an edge in a triangle outside the hole when they have one; the ears
        // give one to the others.
        for &u in &ring {
            self.vedge[u.0 as usize] = NONE;
        }
        for &r in &rim {
            if r & BOUNDARY == 0 {
                let e = EdgeId(r & ID_MASK);
                let (u, w) = (self.org(e), self.dst(e));
                self.vedge[u.0 as usize] = e.0;
                self.vedge[w.0 as usize] = e.next().0;
            }
        }
        let all: Vec<VertexId> = ring.clone();
        let mut new_edges = Vec::new();
        for &(i, fallback) in &steps {
            let i = i as usize;
            let n = ring.len();
            let (i1, i2) = ((i + 1) % n, (i + 2) % n);
            if fallback {
                new_edges.push((ring[i], ring[i2]));
            }
            let t = self.alloc_triangle(ring[i], ring[i1], ring[i2]);
            self.mesh.link_to(t, rim[i]);
            self.mesh.link_to(t.next(), rim[i1]);
            // The polygon edge ring[i] → ring[i2] now has the ear's edge ring[i2] → ring[i]
            // outside.
            rim[i] = t.prev().0;
            self.mesh.link[t.prev().idx()] = HULL;
            ring.remove(i1);
            rim.remove(i1);
        }
        if !hull {
            let t = self.alloc_triangle(ring[0], ring[1], ring[2]);
            self.mesh.link_to(t, rim[0]);
            self.mesh.link_to(t.next(), rim[1]);
            self.mesh.link_to(t.prev(), rim[2]);
        }
        for &u in &all {
            if self.vedge[u.0 as usize] == NONE {
                self.repair_vertex_edge(u);
            }
        }
        if !new_edges.is_empty() {
            self.legalize_edges(new_edges);
        }
        Ok(())
    }

    /// The triangles that [`Tin::remove`] would put in place of the star of `v`, without changing
    /// anything (exact when no breakline is near `v`; next to breaklines, flips may follow).
    ///
    /// # Errors
    /// As [`Tin::remove`].
    pub fn removal_preview(&self, v: VertexId, out: &mut Vec<[VertexId; 3]>) -> Result<()> {
        self.removal_preview_with(v, |t| {
            out.push(t);
            true
        })?;
        Ok(())
    }

    /// Like [`Tin::removal_preview`], handing each triangle to `f` as soon as it is known;
    /// stops early, returning `false`, when `f` returns `false`.
    ///
    /// # Errors
    /// As [`Tin::remove`].
    pub fn removal_preview_with(
        &self,
        v: VertexId,
        mut f: impl FnMut([VertexId; 3]) -> bool,
    ) -> Result<bool> {
        let (spokes, hull) = self.star(v)?;
        let mut ring = self.link_of(&spokes, hull);
        let all = ring.clone();
        let mut ok = true;
        self.ears(&mut ring, &all, hull, |t, _| {
            ok = f(t);
            ok
        });
        if ok && !hull {
            ok = f([ring[0], ring[1], ring[2]]);
        }
        Ok(ok)
    }

    /// The spokes of `v` (counter-clockwise, from the hull edge for a hull vertex) and whether
    /// `v` is on the hull, after the checks of [`Tin::remove`].
    fn star(&self, v: VertexId) -> Result<(Vec<EdgeId>, bool)> {
        if self.out_edge(v).is_none() {
            return Err(Error::Invalid(format!("vertex {} is not in the TIN", v.0)));
        }
        let spokes = self.out_edges(v);
        if spokes
            .iter()
            .any(|&e| self.is_constrained(e) || self.is_constrained(e.prev()))
        {
            return Err(Error::Invalid(format!(
                "vertex {} is an end of a breakline and cannot be removed",
                v.0
            )));
        }
        let hull = self.twin(spokes[0]).is_none();
        if hull && spokes.len() == self.live_triangles {
            let ring = self.link_of(&spokes, hull);
            if self.all_collinear(&ring) {
                return Err(Error::Invalid(format!(
                    "removing vertex {} would leave no triangle",
                    v.0
                )));
            }
        }
        Ok((spokes, hull))
    }

    /// The link of a star: `dst` of every spoke, and for a hull vertex the last spoke's far end.
    fn link_of(&self, spokes: &[EdgeId], hull: bool) -> Vec<VertexId> {
        let mut ring: Vec<VertexId> = spokes.iter().map(|&e| self.dst(e)).collect();
        if hull {
            ring.push(self.org(spokes.last().unwrap().prev()));
        }
        ring
    }

    fn plan_removal(&self, v: VertexId) -> Result<RemovalPlan> {
        let (spokes, hull) = self.star(v)?;
        let ring = self.link_of(&spokes, hull);
        let mut work = ring.clone();
        let mut steps = Vec::with_capacity(ring.len());
        self.ears(&mut work, &ring, hull, |_, step| {
            steps.push(step);
            true
        });
        Ok(RemovalPlan {
            spokes,
            ring,
            hull,
            steps,
        })
    }

    /// Ear clipping of the hole in `ring` (shrunk in place): calls `f(triangle, (position, fallback))`
    /// for each ear, stopping when `f` returns `false`. Delaunay ears when one exists; otherwise
    /// (next to breaklines) any left-turning ear with no link vertex of `all` in it. A closed
    /// ring stops at its last three vertices, which form one more triangle.
    fn ears(
        &self,
        ring: &mut Vec<VertexId>,
        all: &[VertexId],
        hull: bool,
        mut f: impl FnMut([VertexId; 3], (u32, bool)) -> bool,
    ) {
        loop {
            let n = ring.len();
            if !hull && n == 3 {
                return;
            }
            let ears = if hull { n.saturating_sub(2) } else { n };
            let mut chosen = None;
            for i in 0..ears {
                let (a, b, c) = (ring[i], ring[(i + 1) % n], ring[(i + 2) % n]);
                if self.orient_v(a, b, c) == Orientation::CounterClockwise
                    && all
                        .iter()
                        .all(|&w| w == a || w == b || w == c || !self.in_circle(a, b, c, w))
                {
                    chosen = Some((i, false));
                    break;
                }
            }
            if chosen.is_none() {
                chosen = (0..ears)
                    .find(|&i| {
                        let (a, b, c) = (ring[i], ring[(i + 1) % n], ring[(i + 2) % n]);
                        self.orient_v(a, b, c) == Orientation::CounterClockwise
                            && self.ear_is_empty(a, b, c, all)
                    })
                    .map(|i| (i, true));
            }
            let Some((i, fb)) = chosen else {
                return; // hull case: the chain is convex, the hole is filled
            };
            let tri = [ring[i], ring[(i + 1) % n], ring[(i + 2) % n]];
            if !f(tri, (i as u32, fb)) {
                return;
            }
            ring.remove((i + 1) % n);
        }
    }

    fn all_collinear(&self, pts: &[VertexId]) -> bool {
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        pts.iter()
            .all(|&c| self.orient_v(a, b, c) == Orientation::Collinear)
    }

    /// Does the closed triangle `a, b, c` hold no other vertex of `all`?
    fn ear_is_empty(&self, a: VertexId, b: VertexId, c: VertexId, all: &[VertexId]) -> bool {
        all.iter().all(|&w| {
            w == a
                || w == b
                || w == c
                || self.orient_v(a, b, w) == Orientation::Clockwise
                || self.orient_v(b, c, w) == Orientation::Clockwise
                || self.orient_v(c, a, w) == Orientation::Clockwise
        })
    }

    /// Points `vedge[u]` at some live outgoing edge of `u`, searching the triangle slots (only
    /// reached for a vertex left without a triangle by an ear-clipping order that never touched
    /// it, which cannot happen for a valid hole; kept as a safety net).
    fn repair_vertex_edge(&mut self, u: VertexId) {
        for (e, &v) in self.mesh.origin.iter().enumerate() {
            if v == u && self.is_live(EdgeId(e as u32).tri()) {
                self.vedge[u.0 as usize] = e as u32;
                return;
            }
        }
    }
}
