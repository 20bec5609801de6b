//! A dynamic Delaunay TIN: insert points, delete points, insert breaklines, interpolate heights.
//!
//! The triangles live in the crate's one half-edge store, [`crate::mesh::Mesh`], as the sweep's
//! do: triangle `t` owns half-edges `3t, 3t+1, 3t+2` counter-clockwise, with the same typed ids
//! ([`VertexId`], [`EdgeId`], [`TriId`]) and link words: the twin (the same edge seen from the
//! neighbouring triangle), or [`crate::mesh::HULL`] on the convex hull (a TIN has no advancing
//! front), plus the constrained flag of a breakline edge (never flipped). Freed triangle slots are
//! reused. Every vertex remembers one outgoing half-edge.
//!
//! Every geometric decision goes through [`crate::geom::predicates`]: [`orient`] and the perturbed
//! [`incircle`] with the crate's tie rule (the latest point in sweep order carries the dominant
//! lift), so the triangulation is the *unique* Delaunay triangulation of its points under that rule:
//! whatever the order of insertions and deletions, it equals what [`crate::triangulate`] builds from
//! scratch for the same points (as long as no breakline was inserted).
//!
//! The operations (Herva 2009, sections 5.1–5.5):
//! * [`Tin::insert`]: walk to the point, split a triangle (or an edge, or extend the hull), restore
//!   the Delaunay property with Lawson flips;
//! * [`Tin::remove`]: take out the star of a vertex and fill the hole with the Delaunay ears of its
//!   link (hull vertices included: the hole is then an open chain and the new hull its convex hull);
//! * [`Tin::insert_segment`]: force a constrained edge by Sloan's flipping, then restore the
//!   constrained Delaunay property around it;
//! * [`Tin::interpolate`]: linear interpolation on the triangle under a point;
//! * [`Tin::leave_one_out`]: the leave-one-out accuracy check (section 7.3.4).

use crate::error::{Error, Result};
use crate::geom::predicates::{CircleSide, Orientation, incircle, orient};
use crate::mesh::Mesh;
pub use crate::mesh::{EdgeId, TriId, VertexId};
pub use crossval::CrossValidation;

mod check;
mod crossval;
mod delete;
mod insert;
pub(crate) use insert::check_point;
mod segment;
mod store;
#[cfg(test)]
mod tests;

/// No edge / no vertex.
const NONE: u32 = u32::MAX;
/// `vedge` of a live vertex while vertex tracking is off.
const UNTRACKED: u32 = NONE - 1;

/// Where a query point lies in a [`Tin`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointLocation {
    /// Strictly inside this triangle.
    Inside(TriId),
    /// On the relative interior of this edge (either half-edge may be returned).
    OnEdge(EdgeId),
    /// Exactly at this vertex.
    OnVertex(VertexId),
    /// Outside the convex hull; the hull half-edge has the point strictly on its outer side.
    Outside(EdgeId),
}

/// A dynamic Delaunay (or, with breaklines, constrained Delaunay) triangulation.
#[derive(Clone, Debug, Default)]
pub struct Tin {
    xy: Vec<[f64; 2]>,
    z: Vec<f64>,
    /// The triangles.
    mesh: Mesh,
    /// One outgoing half-edge per vertex, [`NONE`] for a vertex not in the triangulation.
    vedge: Vec<u32>,
    free: Vec<TriId>,
    live_vertices: usize,
    live_triangles: usize,
    /// Triangle to start the next walk from.
    hint: u32,
    /// Triangles created or changed by the operations since the last [`Tin::take_touched`].
    touched: Vec<TriId>,
    record: bool,
    rng: u64,
    flips: u64,
    /// Is `vedge` maintained (see [`Tin::set_vertex_tracking`])?
    untracked: bool,
}

impl Tin {
    /// A TIN of the triangles of a [`crate::Triangulation`] (or any valid triangulation:
    /// counter-clockwise triangles of distinct vertices forming a manifold with a convex hull).
    ///
    /// # Errors
    /// [`Error::Invalid`] when an edge is shared by more than two triangles or used twice in the
    /// same direction.
    pub fn from_triangles(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Result<Tin> {
        let mut tin = Tin {
            xy: vertices.iter().map(|p| [p[0], p[1]]).collect(),
            z: vertices.iter().map(|p| p[2]).collect(),
            vedge: vec![NONE; vertices.len()],
            rng: 0x9E37_79B9_7F4A_7C15,
            ..Tin::default()
        };
        if 3 * triangles.len() as u64 > crate::mesh::MAX_HALF_EDGES {
            return Err(Error::Invalid(
                "too many triangles for a dynamic TIN".into(),
            ));
        }
        tin.mesh = Mesh::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            tin.mesh
                .add_triangle(VertexId(tri[0]), VertexId(tri[1]), VertexId(tri[2]));
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a as usize >= vertices.len() || a == b {
                    return Err(Error::Invalid(format!("triangle {t} has a bad vertex")));
                }
                tin.vedge[a as usize] = (3 * t + k) as u32;
            }
        }
        // Half-edges by origin (a counting sort: 4 bytes per half-edge and per vertex, where
        // sorting (edge key, half-edge) pairs took 16 per half-edge and O(m log m)); the twin of
        // a → b is then among the few half-edges leaving b.
        let n = vertices.len();
        let mut start = vec![0u32; n + 1];
        for tri in triangles {
            for &a in tri {
                start[a as usize + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        // Each half-edge leaving a vertex, and its destination beside it (scanned together).
        let mut by_origin = vec![0u32; 3 * triangles.len()];
        let mut dst_of = vec![0u32; 3 * triangles.len()];
        for (t, tri) in triangles.iter().enumerate() {
            for (k, &a) in tri.iter().enumerate() {
                let i = next[a as usize] as usize;
                by_origin[i] = (3 * t + k) as u32;
                dst_of[i] = tri[(k + 1) % 3];
                next[a as usize] += 1;
            }
        }
        drop(next);
        let range = |v: u32| start[v as usize] as usize..start[v as usize + 1] as usize;
        // In triangle order: each half-edge's own link word is written in sequence.
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let e = (3 * t + k) as u32;
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let along = dst_of[range(a)].iter().filter(|&&d| d == b).count();
                let mut twins = range(b).filter(|&j| dst_of[j] == a).map(|j| by_origin[j]);
                let (twin, more) = (twins.next(), twins.count());
                if along + usize::from(twin.is_some()) + more > 2 {
                    return Err(Error::Invalid(
                        "an edge is shared by 3 or more triangles".into(),
                    ));
                }
                if along > 1 {
                    return Err(Error::Invalid(
                        "two triangles use the same edge in the same direction".into(),
                    ));
                }
                if let Some(f) = twin.filter(|&f| f > e) {
                    tin.mesh.pair(EdgeId(e), EdgeId(f), false);
                }
            }
        }
        tin.live_triangles = triangles.len();
        tin.live_vertices = tin.vedge.iter().filter(|&&e| e != NONE).count();
        Ok(tin)
    }

    /// A TIN of a triangulation whose adjacency is known (`twins` as
    /// [`crate::triangulation::triangulate_with_twins`] gives it): no search, one pass.
    ///
    /// # Errors
    /// [`Error::Invalid`] for a bad vertex, or twins that are not each other's.
    pub fn from_twins(vertices: &[[f64; 3]], triangles: &[[u32; 3]], twins: &[u32]) -> Result<Tin> {
        if twins.len() != 3 * triangles.len() {
            return Err(Error::Invalid(format!(
                "{} twins for {} triangles",
                twins.len(),
                triangles.len()
            )));
        }
        if 3 * triangles.len() as u64 > crate::mesh::MAX_HALF_EDGES {
            return Err(Error::Invalid(
                "too many triangles for a dynamic TIN".into(),
            ));
        }
        let mut tin = Tin {
            xy: vertices.iter().map(|p| [p[0], p[1]]).collect(),
            z: vertices.iter().map(|p| p[2]).collect(),
            vedge: vec![NONE; vertices.len()],
            rng: 0x9E37_79B9_7F4A_7C15,
            ..Tin::default()
        };
        tin.mesh = Mesh::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            if tri.iter().any(|&v| v as usize >= vertices.len()) {
                return Err(Error::Invalid(format!("triangle {t} has a bad vertex")));
            }
            tin.mesh
                .add_triangle(VertexId(tri[0]), VertexId(tri[1]), VertexId(tri[2]));
            for (k, &a) in tri.iter().enumerate() {
                tin.vedge[a as usize] = (3 * t + k) as u32;
            }
        }
        for (e, &f) in twins.iter().enumerate() {
            if f == u32::MAX {
                continue;
            }
            if twins.get(f as usize) != Some(&(e as u32)) {
                return Err(Error::Invalid(format!(
                    "half-edges {e} and {f} are not each other's twins"
                )));
            }
            if f as usize > e {
                tin.mesh.pair(EdgeId(e as u32), EdgeId(f), false);
            }
        }
        tin.live_triangles = triangles.len();
        tin.live_vertices = tin.vedge.iter().filter(|&&e| e != NONE).count();
        Ok(tin)
    }

    /// A TIN of a [`crate::Triangulation`].
    ///
    /// # Errors
    /// See [`Tin::from_triangles`].
    pub fn from_triangulation(t: &crate::Triangulation) -> Result<Tin> {
        Tin::from_triangles(&t.vertices, &t.triangles)
    }

    /// Delaunay TIN of `points` (built by [`crate::triangulate`]).
    ///
    /// # Errors
    /// Any error of [`crate::triangulate`].
    pub fn from_points(points: &[[f64; 3]]) -> Result<Tin> {
        let t = crate::triangulate(points, &crate::Options::default())?;
        Tin::from_triangulation(&t)
    }

    /// Number of vertices in the triangulation.
    pub fn vertex_count(&self) -> usize {
        self.live_vertices
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.live_triangles
    }

    /// Number of vertex ids ever used (live or removed).
    pub fn vertex_slots(&self) -> usize {
        self.xy.len()
    }

    /// Number of triangle slots (live or free).
    pub fn triangle_slots(&self) -> usize {
        self.mesh.triangle_count()
    }

    /// Makes room for `vertices` more vertices (and their two triangles each) without growing
    /// any table by more than that: for a caller that bounds its memory and knows how many
    /// points come next (a table grown by `push` may double).
    pub fn reserve_exact(&mut self, vertices: usize) {
        self.xy.reserve_exact(vertices);
        self.z.reserve_exact(vertices);
        self.vedge.reserve_exact(vertices);
        self.mesh.origin.reserve_exact(6 * vertices);
        self.mesh.link.reserve_exact(6 * vertices);
    }

    /// Makes room for `vertices` more vertex ids (positions only, no triangles): for vertices
    /// added with [`Tin::add_vertex`] and inserted later.
    pub fn reserve_vertices_exact(&mut self, vertices: usize) {
        self.xy.reserve_exact(vertices);
        self.z.reserve_exact(vertices);
        self.vedge.reserve_exact(vertices);
    }

    /// Makes room for the triangles of `vertices` more inserted vertices (two each), without
    /// growing the triangle tables by more than that.
    pub fn reserve_triangles_exact(&mut self, vertices: usize) {
        self.mesh.origin.reserve_exact(6 * vertices);
        self.mesh.link.reserve_exact(6 * vertices);
    }

    /// Vertices whose triangles fit before the triangle tables must grow.
    pub fn triangle_room(&self) -> usize {
        let t = self.mesh.origin.capacity().min(self.mesh.link.capacity()) / 6;
        t.saturating_sub(self.mesh.origin.len() / 6)
    }

    /// Vertices that fit before a table must grow.
    pub fn vertex_room(&self) -> usize {
        let v = self.xy.capacity().min(self.z.capacity()).min(self.vedge.capacity());
        let t = self.mesh.origin.capacity().min(self.mesh.link.capacity()) / 6;
        (v - self.xy.len()).min(t.saturating_sub(self.mesh.origin.len() / 6))
    }

    /// Bytes the TIN holds on the heap (what its tables have allocated, used or not).
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.xy.capacity() * size_of::<[f64; 2]>()
            + self.z.capacity() * size_of::<f64>()
            + self.mesh.origin.capacity() * size_of::<VertexId>()
            + self.mesh.link.capacity() * size_of::<u32>()
            + self.vedge.capacity() * size_of::<u32>()
            + (self.free.capacity() + self.touched.capacity()) * size_of::<TriId>()
    }

    /// Edge flips done so far.
    pub fn flips(&self) -> u64 {
        self.flips
    }

    /// Position of `v` in the plane.
    #[inline(always)]
    pub fn xy(&self, v: VertexId) -> [f64; 2] {
        self.xy[v.0 as usize]
    }

    /// Height of `v`.
    #[inline(always)]
    pub fn z(&self, v: VertexId) -> f64 {
        self.z[v.0 as usize]
    }

    /// `[x, y, z]` of `v`.
    #[inline(always)]
    pub fn point(&self, v: VertexId) -> [f64; 3] {
        let [x, y] = self.xy(v);
        [x, y, self.z(v)]
    }

    /// Is `v` in the triangulation (not removed)?
    pub fn contains_vertex(&self, v: VertexId) -> bool {
        (v.0 as usize) < self.vedge.len() && self.vedge[v.0 as usize] != NONE
    }

    /// Is triangle slot `t` in use?
    #[inline(always)]
    pub fn is_live(&self, t: TriId) -> bool {
        self.mesh.is_live(t)
    }

    /// Origin vertex of `e`.
    #[inline(always)]
    pub fn org(&self, e: EdgeId) -> VertexId {
        self.mesh.org(e)
    }

    /// Destination vertex of `e`.
    #[inline(always)]
    pub fn dst(&self, e: EdgeId) -> VertexId {
        self.mesh.dst(e)
    }

    /// The twin of `e`, or `None` on the hull.
    #[inline(always)]
    pub fn twin(&self, e: EdgeId) -> Option<EdgeId> {
        self.mesh.twin(e)
    }

    /// Is `e` constrained (a breakline edge)?
    #[inline(always)]
    pub fn is_constrained(&self, e: EdgeId) -> bool {
        self.mesh.is_constrained(e)
    }

    /// The vertices of triangle `t`, counter-clockwise.
    #[inline(always)]
    pub fn tri_vertices(&self, t: TriId) -> [VertexId; 3] {
        self.mesh.tri_vertices(t)
    }

    /// Live triangles.
    pub fn triangles(&self) -> impl Iterator<Item = TriId> + '_ {
        (0..self.triangle_slots() as u32)
            .map(TriId)
            .filter(|&t| self.is_live(t))
    }

    /// Live vertices.
    pub fn vertices(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.xy.len() as u32)
            .map(VertexId)
            .filter(|&v| self.contains_vertex(v))
    }

    /// The live vertices as `[x, y, z]` and the live triangles as indices into them.
    pub fn to_mesh(&self) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut remap = vec![NONE; self.xy.len()];
        let mut vertices = Vec::with_capacity(self.live_vertices);
        for v in self.vertices() {
            remap[v.0 as usize] = vertices.len() as u32;
            vertices.push(self.point(v));
        }
        let triangles = self
            .triangles()
            .map(|t| self.tri_vertices(t).map(|v| remap[v.0 as usize]))
            .collect();
        (vertices, triangles)
    }

    /// Starts recording the triangles that operations create or change (see
    /// [`Tin::take_touched`]).
    pub fn record_touched(&mut self, on: bool) {
        self.record = on;
        self.touched.clear();
    }

    /// The triangles created or changed since the last call (possibly with repeats, possibly
    /// freed since), when recording is on.
    pub fn take_touched(&mut self, out: &mut Vec<TriId>) {
        out.append(&mut self.touched);
    }

    /// An outgoing half-edge of `v`, if `v` is in the triangulation.
    pub fn out_edge(&self, v: VertexId) -> Option<EdgeId> {
        let e = *self.vedge.get(v.0 as usize)?;
        (e < UNTRACKED).then_some(EdgeId(e))
    }

    /// The outgoing half-edges of `v` in counter-clockwise order; for a hull vertex, starting at
    /// its outgoing hull edge.
    pub fn out_edges(&self, v: VertexId) -> Vec<EdgeId> {
        let Some(start) = self.out_edge(v) else {
            return Vec::new();
        };
        // Rotate clockwise to the hull edge, if there is one.
        let mut e = start;
        loop {
            match self.twin(e) {
                None => break,
                Some(t) => {
                    e = t.next();
                    if e == start {
                        break;
                    }
                }
            }
        }
        let first = e;
        let mut out = vec![first];
        loop {
            match self.twin(e.prev()) {
                None => break,
                Some(t) => {
                    if t == first {
                        break;
                    }
                    e = t;
                    out.push(e);
                }
            }
        }
        out
    }

    /// Is `v` on the convex hull?
    pub fn is_hull_vertex(&self, v: VertexId) -> bool {
        self.out_edges(v)
            .first()
            .is_some_and(|&e| self.twin(e).is_none())
    }

    /// The half-edge from `a` to `b`, if the edge exists.
    pub fn find_edge(&self, a: VertexId, b: VertexId) -> Option<EdgeId> {
        self.out_edges(a).into_iter().find(|&e| self.dst(e) == b)
    }

    #[inline(always)]
    fn p(&self, v: VertexId) -> [f64; 2] {
        self.xy[v.0 as usize]
    }

    #[inline(always)]
    fn orient_v(&self, a: VertexId, b: VertexId, c: VertexId) -> Orientation {
        self.orient_p(self.p(a), self.p(b), self.p(c))
    }

    /// [`orient`] of two TIN points and any point `q` (the adaptive predicate, like every
    /// orientation decision of the crate).
    #[inline(always)]
    fn orient_p(&self, a: [f64; 2], b: [f64; 2], q: [f64; 2]) -> Orientation {
        orient(a, b, q)
    }

    /// Perturbed in-circle: is `d` inside the circle of the counter-clockwise `a, b, c`?
    #[inline(always)]
    fn in_circle(&self, a: VertexId, b: VertexId, c: VertexId, d: VertexId) -> bool {
        let (pa, pb, pc, pd) = (self.p(a), self.p(b), self.p(c), self.p(d));
        let side = incircle(pa, pb, pc, pd);
        side == CircleSide::Inside
    }


    /// Makes the next walk start from triangle `t` (a triangle near the next query point makes
    /// [`Tin::locate`], [`Tin::insert`] and [`Tin::restore`] fast).
    pub fn set_hint(&mut self, t: TriId) {
        self.hint = t.0;
    }

    /// Locates `p`, walking from the last triangle an operation used.
    pub fn locate(&mut self, p: [f64; 2]) -> PointLocation {
        let mut t = self.hint;
        if t as usize >= self.triangle_slots() || !self.is_live(TriId(t)) {
            match self.triangles().next() {
                Some(s) => t = s.0,
                None => return PointLocation::Outside(EdgeId(NONE)),
            }
        }
        self.locate_from(TriId(t), p)
    }

    /// Locates `p` by a visibility walk from triangle `start` (randomised: terminates on any
    /// triangulation, constrained or not).
    pub fn locate_from(&mut self, start: TriId, p: [f64; 2]) -> PointLocation {
        let mut rng = self.rng;
        let (loc, last) = self.walk(start, p, &mut rng);
        self.rng = rng;
        if let Some(t) = last {
            self.hint = t.0;
        }
        loc
    }

    /// As [`Tin::locate_from`] without changing the TIN, the walk's edge order drawn from `rng`
    /// (any seed: it changes only which of two triangles a point on their common edge is
    /// reported in), so that many walks can run at once on several threads.
    pub fn walk_from(&self, start: TriId, p: [f64; 2], rng: &mut u64) -> PointLocation {
        self.walk(start, p, rng).0
    }

    /// The visibility walk, and the triangle it ended in (none when it ended on a vertex).
    ///
    /// Each triangle's corners are read once, and the edge the walk entered by is not tested
    /// again (the point lies strictly on its inner side): the same draws, the same path and the
    /// same answer as testing it, with a third fewer predicates on long walks.
    fn walk(&self, start: TriId, p: [f64; 2], rng: &mut u64) -> (PointLocation, Option<TriId>) {
        let mut e0 = start.edge();
        let mut entry = NONE;
        'walk: loop {
            let mut k = (xorshift(rng) % 3) as usize;
            let base = e0.0 - e0.0 % 3;
            let t = TriId(base / 3);
            let vs = self.mesh.tri_vertices(t);
            let c = [self.p(vs[0]), self.p(vs[1]), self.p(vs[2])];
            let mut on_edge = None;
            for _ in 0..3 {
                let k1 = NEXT_CORNER[k];
                let e = EdgeId(base + k as u32);
                if e.0 != entry {
                    let (pa, pb) = (c[k], c[k1]);
                    match self.orient_p(pa, pb, p) {
                        Orientation::Clockwise => match self.twin(e) {
                            Some(f) => {
                                e0 = f;
                                entry = f.0;
                                continue 'walk;
                            }
                            None => return (PointLocation::Outside(e), Some(t)),
                        },
                        Orientation::Collinear => {
                            if pa == p {
                                return (PointLocation::OnVertex(vs[k]), None);
                            }
                            if pb == p {
                                return (PointLocation::OnVertex(vs[k1]), None);
                            }
                            on_edge = Some(e);
                        }
                        Orientation::CounterClockwise => {}
                    }
                }
                k = k1;
            }
            let loc = match on_edge {
                Some(e) => PointLocation::OnEdge(e),
                None => PointLocation::Inside(t),
            };
            return (loc, Some(t));
        }
    }

    /// Height of the TIN at `(x, y)` by linear interpolation, or `None` outside the hull.
    pub fn interpolate(&mut self, p: [f64; 2]) -> Option<f64> {
        match self.locate(p) {
            PointLocation::Outside(_) => None,
            PointLocation::OnVertex(v) => Some(self.z(v)),
            PointLocation::OnEdge(e) => {
                let (a, b) = (self.org(e), self.dst(e));
                Some(lerp_edge(self.point(a), self.point(b), p))
            }
            PointLocation::Inside(t) => {
                let [a, b, c] = self.tri_vertices(t).map(|v| self.point(v));
                Some(planar(a, b, c, p))
            }
        }
    }

    /// The hull edge following hull edge `e` (counter-clockwise along the hull).
    pub fn next_hull_edge(&self, e: EdgeId) -> EdgeId {
        let mut f = e.next();
        while let Some(t) = self.twin(f) {
            f = t.next();
        }
        f
    }

    /// The hull edge preceding hull edge `e`.
    pub fn prev_hull_edge(&self, e: EdgeId) -> EdgeId {
        let mut g = e.prev();
        while let Some(t) = self.twin(g) {
            g = t.prev();
        }
        g
    }
}

/// The corner after each corner of a triangle (counter-clockwise).
const NEXT_CORNER: [usize; 3] = [1, 2, 0];

/// xorshift64*: only to vary which edge a walk tries first (the walk ends in the same place
/// whatever it draws, but for a point on an edge, which of its two triangles).
fn xorshift(rng: &mut u64) -> u64 {
    *rng ^= *rng >> 12;
    *rng ^= *rng << 25;
    *rng ^= *rng >> 27;
    rng.wrapping_mul(0x2545_F491_4F6C_DD1D)
}

/// Height at `p` of the plane through `a, b, c` (floating point; `a, b, c` not collinear).
#[inline]
pub fn planar(a: [f64; 3], b: [f64; 3], c: [f64; 3], p: [f64; 2]) -> f64 {
    let (ux, uy, uz) = (b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    let (vx, vy, vz) = (c[0] - a[0], c[1] - a[1], c[2] - a[2]);
    let det = ux * vy - uy * vx;
    let (px, py) = (p[0] - a[0], p[1] - a[1]);
    // Barycentric weights of b and c.
    let wb = (px * vy - py * vx) / det;
    let wc = (ux * py - uy * px) / det;
    a[2] + wb * uz + wc * vz
}

/// Is `q` in the closed counter-clockwise triangle `t` (inside, or on an edge or a corner)?
/// Exact ([`orient`]): the bucket test of the methods that keep points in the triangle that
/// contains them (`simplify::thin`, `ground`).
#[inline]
pub fn in_closed_triangle(t: &[[f64; 2]; 3], q: [f64; 2]) -> bool {
    orient(t[0], t[1], q) != Orientation::Clockwise
        && orient(t[1], t[2], q) != Orientation::Clockwise
        && orient(t[2], t[0], q) != Orientation::Clockwise
}

/// Height at `p` (on the segment) of the line through `a, b`.
#[inline]
pub fn lerp_edge(a: [f64; 3], b: [f64; 3], p: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = if dx.abs() >= dy.abs() {
        (p[0] - a[0]) / dx
    } else {
        (p[1] - a[1]) / dy
    };
    a[2] + t * (b[2] - a[2])
}
