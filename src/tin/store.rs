//! The TIN's bookkeeping over the shared half-edge store ([`crate::mesh::Mesh`]): triangle slots
//! with a free list, the vertex → edge map, the record of touched triangles, the edge flip, and
//! the renumbering for locality ([`Tin::relayout`]).

use super::{NONE, Tin, UNTRACKED};
use crate::error::{Error, Result};
use crate::mesh::{BOUNDARY, CONSTRAINED, DEAD, EdgeId, HULL, ID_MASK, MAX_VERTICES, Mesh};
use crate::mesh::{TriId, VertexId};

impl Tin {
    /// Turns the vertex → edge map off or on. Off, insertions skip its upkeep (random writes that
    /// cost a tenth of an insertion on large TINs): for bulk insertion, such as the grid
    /// simplifier's. While it is off, [`Tin::remove`], [`Tin::restore`], [`Tin::out_edges`],
    /// [`Tin::find_edge`] and breakline insertion do not work (they report the vertex as unknown);
    /// turning it on rebuilds the map in one pass over the triangles.
    pub fn set_vertex_tracking(&mut self, on: bool) {
        if on != self.untracked {
            return;
        }
        for e in &mut self.vedge {
            if *e != NONE {
                *e = UNTRACKED;
            }
        }
        self.untracked = !on;
        if on {
            for (e, &v) in self.mesh.origin.iter().enumerate() {
                if v != DEAD {
                    self.vedge[v.0 as usize] = e as u32;
                }
            }
        }
    }

    /// Renumbers the vertices (new vertex `i` is the old `order[i]`; `order` must list every live
    /// vertex once) and the triangles (by their smallest new vertex id), dropping removed
    /// vertices and free slots. Neighbouring points then sit near each other in memory when
    /// `order` is spatial. Returns, for each old vertex id, its new id (`u32::MAX` if dropped).
    ///
    /// # Errors
    /// [`Error::Invalid`] if `order` is not a permutation of the live vertices.
    pub fn relayout(&mut self, order: &[VertexId]) -> Result<Vec<u32>> {
        self.set_vertex_tracking(true);
        let mut new_v = vec![NONE; self.xy.len()];
        for (i, &v) in order.iter().enumerate() {
            if !self.contains_vertex(v) || new_v[v.0 as usize] != NONE {
                return Err(Error::Invalid("relayout order is not a permutation".into()));
            }
            new_v[v.0 as usize] = i as u32;
        }
        if order.len() != self.live_vertices {
            return Err(Error::Invalid("relayout order misses vertices".into()));
        }
        // Counting sort of the live triangles by their smallest new vertex id.
        let slots = self.triangle_slots();
        let key = |t: usize| {
            let [a, b, c] = self.mesh.tri_vertices(TriId(t as u32));
            new_v[a.0 as usize]
                .min(new_v[b.0 as usize])
                .min(new_v[c.0 as usize])
        };
        let mut start = vec![0u32; order.len() + 1];
        for t in 0..slots {
            if self.is_live(TriId(t as u32)) {
                start[key(t) as usize + 1] += 1;
            }
        }
        for i in 0..order.len() {
            start[i + 1] += start[i];
        }
        let new_t: Vec<u32> = (0..slots)
            .map(|t| {
                if self.is_live(TriId(t as u32)) {
                    let k = key(t) as usize;
                    start[k] += 1;
                    start[k] - 1
                } else {
                    NONE
                }
            })
            .collect();
        let n = self.live_triangles;
        let mut mesh = Mesh {
            origin: vec![DEAD; 3 * n].into(),
            link: vec![HULL; 3 * n].into(),
        };
        for (t, &nt) in new_t.iter().enumerate() {
            if nt == NONE {
                continue;
            }
            for k in 0..3 {
                let (old, new) = (3 * t + k, 3 * nt as usize + k);
                mesh.origin[new] = VertexId(new_v[self.mesh.origin[old].0 as usize]);
                let l = self.mesh.link[old];
                let id = l & ID_MASK;
                mesh.link[new] = if l & BOUNDARY != 0 {
                    l
                } else {
                    (3 * new_t[id as usize / 3] + id % 3) | (l & CONSTRAINED)
                };
            }
        }
        let mut vedge = vec![NONE; order.len()];
        for (i, &v) in order.iter().enumerate() {
            let e = self.vedge[v.0 as usize];
            vedge[i] = 3 * new_t[e as usize / 3] + e % 3;
        }
        self.xy = order.iter().map(|&v| self.xy[v.0 as usize]).collect();
        self.z = order.iter().map(|&v| self.z[v.0 as usize]).collect();
        self.mesh = mesh;
        self.vedge = vedge;
        self.free.clear();
        self.hint = 0;
        self.touched.clear();
        Ok(new_v)
    }

    /// A new triangle `a, b, c` (in a free slot when there is one), all edges on the hull.
    pub(super) fn alloc_triangle(&mut self, a: VertexId, b: VertexId, c: VertexId) -> EdgeId {
        self.live_triangles += 1;
        let e = match self.free.pop() {
            Some(t) => self.mesh.reuse_triangle(t, a, b, c),
            None => self.mesh.add_triangle(a, b, c),
        };
        self.track(e, [a, b, c]);
        e
    }

    /// Overwrites live triangle `t` with `a, b, c`, keeping nothing of its links.
    pub(super) fn set_triangle(
        &mut self,
        t: TriId,
        a: VertexId,
        b: VertexId,
        c: VertexId,
    ) -> EdgeId {
        let e = self.mesh.reuse_triangle(t, a, b, c);
        self.track(e, [a, b, c]);
        e
    }

    /// Vertex edges and the touched record of the new triangle at `e`.
    #[inline(always)]
    fn track(&mut self, e: EdgeId, [a, b, c]: [VertexId; 3]) {
        if !self.untracked {
            self.vedge[a.0 as usize] = e.0;
            self.vedge[b.0 as usize] = e.0 + 1;
            self.vedge[c.0 as usize] = e.0 + 2;
        }
        if self.record {
            self.touched.push(e.tri());
        }
    }

    pub(super) fn free_triangle(&mut self, t: TriId) {
        self.mesh.free_triangle(t);
        self.free.push(t);
        self.live_triangles -= 1;
    }

    /// Flips the edge `e` (shared by triangles `a, b, p` and `b, a, d`) into `p, d`. The diagonal
    /// keeps the ids `e` and its twin; afterwards `e` is `d → p` in triangle `d, p, a` and its
    /// twin `p → d` in triangle `p, d, b`.
    pub(super) fn flip(&mut self, e0: EdgeId) {
        let m = &mut self.mesh;
        let f0 = EdgeId(m.link[e0.idx()] & ID_MASK);
        let (e1, e2, f1, f2) = (e0.next(), e0.prev(), f0.next(), f0.prev());
        let (a, b, p, d) = (m.org(e0), m.org(e1), m.org(e2), m.org(f2));
        let (le1, le2, lf1, lf2) = (
            m.link[e1.idx()],
            m.link[e2.idx()],
            m.link[f1.idx()],
            m.link[f2.idx()],
        );
        m.origin[e0.idx()] = d;
        m.origin[e1.idx()] = p;
        m.origin[e2.idx()] = a;
        m.origin[f0.idx()] = p;
        m.origin[f1.idx()] = d;
        m.origin[f2.idx()] = b;
        m.link_to(e1, le2);
        m.link_to(e2, lf1);
        m.link_to(f1, lf2);
        m.link_to(f2, le1);
        if !self.untracked {
            self.vedge[a.0 as usize] = e2.0;
            self.vedge[b.0 as usize] = f2.0;
            self.vedge[p.0 as usize] = e1.0;
            self.vedge[d.0 as usize] = f1.0;
        }
        self.flips += 1;
        if self.record {
            self.touched.push(e0.tri());
            self.touched.push(f0.tri());
        }
    }

    /// A new vertex id for `p`, not yet in the triangulation.
    ///
    /// # Errors
    /// [`Error::TooManyPoints`] past [`MAX_VERTICES`] vertex ids (which keeps every half-edge id
    /// within the mesh's 30 bits).
    pub(super) fn push_vertex(&mut self, p: [f64; 3]) -> Result<VertexId> {
        if self.xy.len() as u64 >= MAX_VERTICES {
            return Err(Error::TooManyPoints {
                count: self.xy.len() as u64 + 1,
                max: MAX_VERTICES,
            });
        }
        self.xy.push([p[0], p[1]]);
        self.z.push(p[2]);
        self.vedge
            .push(if self.untracked { UNTRACKED } else { NONE });
        Ok(VertexId(self.xy.len() as u32 - 1))
    }
}
