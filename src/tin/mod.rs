//! A dynamic Delaunay TIN: insert points, delete points, insert breaklines, interpolate heights.
//!
//! Storage follows the sweep's mesh (`crate::mesh`): flat half-edge arrays, triangle `t`
//! owning half-edges `3t, 3t+1, 3t+2` counter-clockwise, typed `u32` ids. Each half-edge has a
//! *link word*: its twin (the same edge seen from the neighbouring triangle), or [`NO_TWIN`] on the
//! convex hull, with bit 31 set when the edge is constrained (a breakline, never flipped). Freed
//! triangle slots are reused. Every vertex remembers one outgoing half-edge.
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
pub use crossval::CrossValidation;

mod crossval;
mod delete;
mod insert;
mod segment;
#[cfg(test)]
mod tests;

/// A vertex of a [`Tin`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct VertexId(pub u32);

/// A half-edge of a [`Tin`]: `3 * triangle + corner`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct EdgeId(pub u32);

/// A triangle slot of a [`Tin`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TriId(pub u32);

impl EdgeId {
    /// The next half-edge counter-clockwise in the same triangle.
    #[inline(always)]
    pub fn next(self) -> EdgeId {
        EdgeId(if self.0 % 3 == 2 {
            self.0 - 2
        } else {
            self.0 + 1
        })
    }

    /// The previous half-edge in the same triangle.
    #[inline(always)]
    pub fn prev(self) -> EdgeId {
        EdgeId(if self.0.is_multiple_of(3) {
            self.0 + 2
        } else {
            self.0 - 1
        })
    }

    /// The triangle of this half-edge.
    #[inline(always)]
    pub fn tri(self) -> TriId {
        TriId(self.0 / 3)
    }

    #[inline(always)]
    fn idx(self) -> usize {
        self.0 as usize
    }
}

impl TriId {
    /// The first half-edge of the triangle.
    #[inline(always)]
    pub fn edge(self) -> EdgeId {
        EdgeId(3 * self.0)
    }
}

/// Link word of a hull edge (no twin).
pub const NO_TWIN: u32 = 0x7FFF_FFFF;
/// Link-word flag of a constrained edge.
pub const CONSTRAINED: u32 = 1 << 31;
/// No edge / no vertex.
const NONE: u32 = u32::MAX;
/// Origin of the half-edges of a free triangle slot.
const DEAD: u32 = u32::MAX;
/// Largest number of half-edges.
const MAX_EDGES: usize = NO_TWIN as usize;

/// Where a query point lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
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
    origin: Vec<u32>,
    link: Vec<u32>,
    /// One outgoing half-edge per vertex, [`NONE`] for a vertex not in the triangulation.
    vedge: Vec<u32>,
    free: Vec<u32>,
    live_vertices: usize,
    live_triangles: usize,
    /// Triangle to start the next walk from.
    hint: u32,
    /// Triangles created or changed by the operations since the last [`Tin::take_touched`].
    touched: Vec<u32>,
    record: bool,
    rng: u64,
    flips: u64,
    /// Is `vedge` maintained (see [`Tin::set_vertex_tracking`])?
    untracked: bool,
}

/// `vedge` of a live vertex while vertex tracking is off.
const UNTRACKED: u32 = NONE - 1;

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
        if 3 * triangles.len() >= MAX_EDGES {
            return Err(Error::Invalid(
                "too many triangles for a dynamic TIN".into(),
            ));
        }
        let mut keys: Vec<(u64, u32)> = Vec::with_capacity(3 * triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a as usize >= vertices.len() || a == b {
                    return Err(Error::Invalid(format!("triangle {t} has a bad vertex")));
                }
                tin.origin.push(a);
                tin.link.push(NO_TWIN);
                tin.vedge[a as usize] = (3 * t + k) as u32;
                let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                keys.push((key, (3 * t + k) as u32));
            }
        }
        keys.sort_unstable();
        let mut i = 0;
        while i < keys.len() {
            let mut j = i + 1;
            while j < keys.len() && keys[j].0 == keys[i].0 {
                j += 1;
            }
            match j - i {
                1 => {}
                2 => {
                    let (e, f) = (keys[i].1, keys[i + 1].1);
                    if tin.origin[e as usize] == tin.origin[f as usize] {
                        return Err(Error::Invalid(
                            "two triangles use the same edge in the same direction".into(),
                        ));
                    }
                    tin.link[e as usize] = f;
                    tin.link[f as usize] = e;
                }
                _ => {
                    return Err(Error::Invalid(
                        "an edge is shared by 3 or more triangles".into(),
                    ));
                }
            }
            i = j;
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
        self.origin.len() / 3
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
        self.origin[3 * t.0 as usize] != DEAD
    }

    /// Origin vertex of `e`.
    #[inline(always)]
    pub fn org(&self, e: EdgeId) -> VertexId {
        VertexId(self.origin[e.idx()])
    }

    /// Destination vertex of `e`.
    #[inline(always)]
    pub fn dst(&self, e: EdgeId) -> VertexId {
        VertexId(self.origin[e.next().idx()])
    }

    /// The twin of `e`, or `None` on the hull.
    #[inline(always)]
    pub fn twin(&self, e: EdgeId) -> Option<EdgeId> {
        let w = self.link[e.idx()] & !CONSTRAINED;
        (w != NO_TWIN).then_some(EdgeId(w))
    }

    /// Is `e` constrained (a breakline edge)?
    #[inline(always)]
    pub fn is_constrained(&self, e: EdgeId) -> bool {
        self.link[e.idx()] & CONSTRAINED != 0
    }

    /// The vertices of triangle `t`, counter-clockwise.
    #[inline(always)]
    pub fn tri_vertices(&self, t: TriId) -> [VertexId; 3] {
        let e = 3 * t.0 as usize;
        [
            VertexId(self.origin[e]),
            VertexId(self.origin[e + 1]),
            VertexId(self.origin[e + 2]),
        ]
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
        out.extend(self.touched.drain(..).map(TriId));
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
    fn p(&self, v: u32) -> [f64; 2] {
        self.xy[v as usize]
    }

    #[inline(always)]
    fn orient_v(&self, a: u32, b: u32, c: u32) -> Orientation {
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
    fn in_circle(&self, a: u32, b: u32, c: u32, d: u32) -> bool {
        let (pa, pb, pc, pd) = (self.p(a), self.p(b), self.p(c), self.p(d));
        let side = incircle(pa, pb, pc, pd);
        side == CircleSide::Inside
    }

    fn next_random(&mut self) -> u64 {
        // xorshift64*: only to vary which edge a walk tries first (no effect on the result).
        self.rng ^= self.rng >> 12;
        self.rng ^= self.rng << 25;
        self.rng ^= self.rng >> 27;
        self.rng.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

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
            for e in 0..self.origin.len() {
                let v = self.origin[e];
                if v != DEAD {
                    self.vedge[v as usize] = e as u32;
                }
            }
        }
    }

    /// Makes the next walk start from triangle `t` (a triangle near the next query point makes
    /// [`Tin::locate`], [`Tin::insert`] and [`Tin::restore`] fast).
    pub fn set_hint(&mut self, t: TriId) {
        self.hint = t.0;
    }

    /// Locates `p`, walking from the last triangle an operation used.
    pub fn locate(&mut self, p: [f64; 2]) -> Location {
        let mut t = self.hint;
        if t as usize >= self.triangle_slots() || !self.is_live(TriId(t)) {
            match self.triangles().next() {
                Some(s) => t = s.0,
                None => return Location::Outside(EdgeId(NONE)),
            }
        }
        self.locate_from(TriId(t), p)
    }

    /// Locates `p` by a visibility walk from triangle `start` (randomised: terminates on any
    /// triangulation, constrained or not).
    pub fn locate_from(&mut self, start: TriId, p: [f64; 2]) -> Location {
        let mut e0 = start.edge();
        'walk: loop {
            let r = (self.next_random() % 3) as u32;
            let first = EdgeId(e0.0 - e0.0 % 3 + r);
            let mut on_edge = None;
            let mut e = first;
            for _ in 0..3 {
                let (a, b) = (self.origin[e.idx()], self.origin[e.next().idx()]);
                match self.orient_p(self.p(a), self.p(b), p) {
                    Orientation::Clockwise => match self.twin(e) {
                        Some(t) => {
                            e0 = t;
                            continue 'walk;
                        }
                        None => {
                            self.hint = e.tri().0;
                            return Location::Outside(e);
                        }
                    },
                    Orientation::Collinear => {
                        if self.p(a) == p {
                            return Location::OnVertex(VertexId(a));
                        }
                        if self.p(b) == p {
                            return Location::OnVertex(VertexId(b));
                        }
                        on_edge = Some(e);
                    }
                    Orientation::CounterClockwise => {}
                }
                e = e.next();
            }
            self.hint = e.tri().0;
            return match on_edge {
                Some(e) => Location::OnEdge(e),
                None => Location::Inside(e.tri()),
            };
        }
    }

    /// Height of the TIN at `(x, y)` by linear interpolation, or `None` outside the hull.
    pub fn interpolate(&mut self, p: [f64; 2]) -> Option<f64> {
        match self.locate(p) {
            Location::Outside(_) => None,
            Location::OnVertex(v) => Some(self.z(v)),
            Location::OnEdge(e) => {
                let (a, b) = (self.org(e), self.dst(e));
                Some(lerp_edge(self.point(a), self.point(b), p))
            }
            Location::Inside(t) => {
                let [a, b, c] = self.tri_vertices(t).map(|v| self.point(v));
                Some(planar(a, b, c, p))
            }
        }
    }

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
            if self.orient_v(a.0, b.0, c.0) != Orientation::CounterClockwise {
                return bad(format!("triangle {} is not counter-clockwise", t.0));
            }
            for k in 0..3 {
                let e = EdgeId(3 * t.0 + k);
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
                        if !self.is_constrained(e) && self.in_circle(a.0, b.0, c.0, d.0) {
                            return bad(format!("edge {} is not locally Delaunay", e.0));
                        }
                    }
                    None => {
                        // Hull convexity: the next hull edge turns left or goes straight.
                        let (u, v) = (self.org(e), self.dst(e));
                        let nxt = self.next_hull_edge(e);
                        let w = self.dst(nxt);
                        if self.orient_v(u.0, v.0, w.0) == Orientation::Clockwise {
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
                && (e as usize >= self.origin.len()
                    || self.origin[e as usize] != v as u32
                    || !self.is_live(EdgeId(e).tri()))
            {
                return bad(format!("vertex {v} has a stale edge"));
            }
        }
        Ok(())
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
            let e = 3 * t;
            (0..3)
                .map(|k| new_v[self.origin[e + k] as usize])
                .min()
                .unwrap()
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
        let mut origin = vec![DEAD; 3 * n];
        let mut link = vec![NO_TWIN; 3 * n];
        for (t, &nt) in new_t.iter().enumerate() {
            if nt == NONE {
                continue;
            }
            for k in 0..3 {
                let (old, new) = (3 * t + k, 3 * nt as usize + k);
                origin[new] = new_v[self.origin[old] as usize];
                let l = self.link[old];
                let id = l & !CONSTRAINED;
                link[new] = if id == NO_TWIN {
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
        self.origin = origin;
        self.link = link;
        self.vedge = vedge;
        self.free.clear();
        self.hint = 0;
        self.touched.clear();
        Ok(new_v)
    }

    // ---- low-level storage -------------------------------------------------------------------

    fn alloc_triangle(&mut self, a: u32, b: u32, c: u32) -> EdgeId {
        self.live_triangles += 1;
        let e = match self.free.pop() {
            Some(t) => {
                let e = 3 * t as usize;
                self.origin[e..e + 3].copy_from_slice(&[a, b, c]);
                self.link[e..e + 3].copy_from_slice(&[NO_TWIN; 3]);
                e as u32
            }
            None => {
                let e = self.origin.len() as u32;
                self.origin.extend_from_slice(&[a, b, c]);
                self.link.extend_from_slice(&[NO_TWIN; 3]);
                e
            }
        };
        if !self.untracked {
            self.vedge[a as usize] = e;
            self.vedge[b as usize] = e + 1;
            self.vedge[c as usize] = e + 2;
        }
        if self.record {
            self.touched.push(e / 3);
        }
        EdgeId(e)
    }

    /// Overwrites live triangle `t` with `a, b, c`, keeping nothing of its links.
    fn set_triangle(&mut self, t: u32, a: u32, b: u32, c: u32) -> EdgeId {
        let e = 3 * t as usize;
        self.origin[e..e + 3].copy_from_slice(&[a, b, c]);
        self.link[e..e + 3].copy_from_slice(&[NO_TWIN; 3]);
        if !self.untracked {
            self.vedge[a as usize] = e as u32;
            self.vedge[b as usize] = e as u32 + 1;
            self.vedge[c as usize] = e as u32 + 2;
        }
        if self.record {
            self.touched.push(t);
        }
        EdgeId(e as u32)
    }

    fn free_triangle(&mut self, t: u32) {
        let e = 3 * t as usize;
        self.origin[e..e + 3].copy_from_slice(&[DEAD; 3]);
        self.free.push(t);
        self.live_triangles -= 1;
    }

    /// Links half-edge `a` to `b`'s outside: `b` is a half-edge or [`NO_TWIN`], possibly with the
    /// [`CONSTRAINED`] flag.
    #[inline(always)]
    fn link_to(&mut self, a: EdgeId, b: u32) {
        self.link[a.idx()] = b;
        let id = b & !CONSTRAINED;
        if id != NO_TWIN {
            self.link[id as usize] = a.0 | (b & CONSTRAINED);
        }
    }

    /// Flips the edge `e` (shared by triangles `a, b, p` and `b, a, d`) into `p, d`. The diagonal
    /// keeps the ids `e` and its twin; afterwards `e` is `d → p` in triangle `d, p, a` and its
    /// twin `p → d` in triangle `p, d, b`.
    fn flip(&mut self, e0: EdgeId) {
        let f0 = EdgeId(self.link[e0.idx()] & !CONSTRAINED);
        let (e1, e2, f1, f2) = (e0.next(), e0.prev(), f0.next(), f0.prev());
        let a = self.origin[e0.idx()];
        let b = self.origin[e1.idx()];
        let p = self.origin[e2.idx()];
        let d = self.origin[f2.idx()];
        let (le1, le2, lf1, lf2) = (
            self.link[e1.idx()],
            self.link[e2.idx()],
            self.link[f1.idx()],
            self.link[f2.idx()],
        );
        self.origin[e0.idx()] = d;
        self.origin[e1.idx()] = p;
        self.origin[e2.idx()] = a;
        self.origin[f0.idx()] = p;
        self.origin[f1.idx()] = d;
        self.origin[f2.idx()] = b;
        self.link_to(e1, le2);
        self.link_to(e2, lf1);
        self.link_to(f1, lf2);
        self.link_to(f2, le1);
        if !self.untracked {
            self.vedge[a as usize] = e2.0;
            self.vedge[b as usize] = f2.0;
            self.vedge[p as usize] = e1.0;
            self.vedge[d as usize] = f1.0;
        }
        self.flips += 1;
        if self.record {
            self.touched.push(e0.tri().0);
            self.touched.push(f0.tri().0);
        }
    }

    fn push_vertex(&mut self, p: [f64; 3]) -> Result<u32> {
        if self.xy.len() >= NONE as usize - 1 {
            return Err(Error::TooManyPoints {
                count: self.xy.len() as u64 + 1,
                max: NONE as u64 - 1,
            });
        }
        self.xy.push([p[0], p[1]]);
        self.z.push(p[2]);
        self.vedge
            .push(if self.untracked { UNTRACKED } else { NONE });
        Ok(self.xy.len() as u32 - 1)
    }
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
