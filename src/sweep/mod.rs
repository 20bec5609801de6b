//! The sweep-line Delaunay triangulation (Domiter & Žalik 2008, section 3).
//!
//! Points are inserted in sweep order (by `y`, then `x`). Each one is projected vertically onto the
//! advancing front ([`front`]) and connected to the segment it hits (the *middle case*), or, when it
//! lies exactly above a front vertex, to both segments around that vertex (the *left case*). Every
//! new triangle is legalised at once by Lawson flips with an explicit stack ([`legalize`]). Two
//! heuristics keep the front smooth ([`heuristics`]): holes next to the new point whose angle is
//! at most about 114° are filled (the paper's bound is π/2; see `HOLE_COS` in [`heuristics`]), and
//! deep basins are filled. When all points are in, the front is closed to its convex hull and the
//! triangles that use an artificial point are dropped.
//!
//! The sweep is steppable: [`Sweep::new`] → [`Sweep::step`] … → [`Sweep::finish`], and
//! [`Sweep::check`] verifies every invariant of the current state (used by tests and fuzzing).
//! The same core, monomorphised over its [`Mode`] ([`hooks`]), is the streaming sweep of
//! [`crate::finalise`].

#[cfg(any(test, feature = "dev"))]
pub mod check;
pub mod constrain;
pub mod front;
pub mod heuristics;
pub mod hooks;
pub mod legalize;

use crate::error::{Error, Result};
use crate::geom::predicates::{FIRST_REAL, P_LEFT, P_RIGHT, is_artificial};
use crate::sort::mmap::SpillVec;
use crate::mesh::{Across, BOUNDARY, CONSTRAINED, EdgeId, Mesh, TriId, VertexId};
pub use constrain::{ConstraintGraph, ConstraintStats, ConstraintVertex};
use front::{Front, NodeId, XMap};

/// Triangles and, for each of their half-edges, the half-edge across it (`u32::MAX` on the
/// hull): what [`Sweep::finish_with_twins`] returns.
pub type Twinned = (Vec<[u32; 3]>, Vec<u32>);
pub use hooks::{Batch, Mode};

/// Counters of what the sweep did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SweepStats {
    /// Points inserted.
    pub points: u64,
    /// Points that hit a front vertex exactly (the paper's left case).
    pub left_cases: u64,
    /// Lawson edge flips.
    pub flips: u64,
    /// Triangles added by the hole and basin heuristics.
    pub fills: u64,
    /// Triangles added when closing the front to the convex hull.
    pub hull_fills: u64,
    /// Largest number of front nodes.
    pub peak_front: u64,
}

/// A sweep in progress.
///
/// Two modes share all of the geometry, each a monomorphised instance of this type:
/// * **batch** (`Sweep`, that is `Sweep<Batch>`, from [`Sweep::new`]): the whole vertex table is
///   given up front and every triangle stays in memory until [`Sweep::finish`];
/// * **streaming** ([`crate::finalise::StreamingSweep`], which owns a `Sweep` whose mode is its
///   finaliser): points are pushed one at a time and a triangle leaves memory as soon as nothing
///   later can change it.
#[derive(Debug, Clone)]
pub struct Sweep<H: Mode = Batch> {
    pts: SpillVec<[f64; 2]>,
    /// Batch mode: the next vertex to insert.
    next: u32,
    mesh: Mesh,
    front: Front,
    stack: Vec<EdgeId>,
    stats: SweepStats,
    hooks: H,
    cons: Option<Box<Constraints>>,
    cstats: ConstraintStats,
}

/// Breakline state of a sweep.
#[derive(Debug, Clone)]
pub(crate) struct Constraints {
    graph: ConstraintGraph,
    /// Vertex of each constraint vertex, once swept.
    vertex: Vec<VertexId>,
    /// Batch mode: (vertex, constraint vertex) pairs in vertex order, and the next one to use.
    batch: Vec<(u32, u32)>,
    cursor: usize,
    /// Streamed breaklines: the graph comes vertex by vertex with the points instead
    /// ([`constrain::Fed`]); `graph` and `vertex` are then empty.
    fed: Option<constrain::Fed>,
}

/// No constraint vertex.
pub const NO_CONSTRAINT: u32 = u32::MAX;

/// A constraint vertex not swept yet.
const UNSWEPT: VertexId = VertexId(u32::MAX);

impl Sweep<Batch> {
    /// Starts a sweep over `pts`: two placeholder rows for the artificial points, then at least one
    /// real point, all distinct and sorted by `(y, x)` (as produced by [`crate::sort::memory::prepare`]).
    ///
    /// # Errors
    /// [`Error::TooFewPoints`] without any real point; [`Error::OutOfOrder`] if the points are not
    /// strictly increasing in sweep order.
    pub fn new(pts: Vec<[f64; 2]>) -> Result<Self> {
        let n = pts.len().saturating_sub(FIRST_REAL as usize);
        if n == 0 {
            return Err(Error::TooFewPoints {
                distinct: 0,
                total: 0,
            });
        }
        let real = &pts[FIRST_REAL as usize..];
        if let Some(i) = real.windows(2).position(|w| {
            crate::geom::predicates::sweep_cmp(w[0], w[1]) != std::cmp::Ordering::Less
        }) {
            return Err(Error::OutOfOrder {
                index: i as u64 + 1,
            });
        }
        let step = (n / 4096).max(1);
        let xmap = XMap::from_sample(real.iter().step_by(step).map(|p| p[0]).collect());
        // A Delaunay triangulation of n points (plus 2) has at most 2(n + 2) - 5 triangles.
        let mesh = Mesh::with_capacity(2 * n + 4);
        Ok(Self::start(SpillVec::from_vec(pts), mesh, xmap, Batch))
    }

    /// Inserts the next point; returns `false` when all points are in.
    ///
    /// # Errors
    /// [`Error::Internal`] if inserting a breakline ended by the point breaks an invariant (a bug;
    /// the sweep must not be used further).
    #[cfg(any(test, feature = "dev"))]
    pub fn step(&mut self) -> Result<bool> {
        if self.next as usize >= self.pts.len() {
            return Ok(false);
        }
        let v = VertexId(self.next);
        self.next += 1;
        self.insert_batch(v)?;
        Ok(true)
    }

    /// Inserts all remaining points.
    ///
    /// # Errors
    /// As [`Sweep::step`].
    pub fn run(&mut self) -> Result<()> {
        while (self.next as usize) < self.pts.len() {
            let v = VertexId(self.next);
            self.next += 1;
            self.insert_batch(v)?;
        }
        Ok(())
    }

    /// Inserts vertex `v` and the breaklines it ends.
    fn insert_batch(&mut self, v: VertexId) -> Result<()> {
        let n = self.insert(v);
        let cid = match self.cons.as_mut() {
            Some(c) if c.cursor < c.batch.len() && c.batch[c.cursor].0 == v.0 => {
                c.cursor += 1;
                c.batch[c.cursor - 1].1
            }
            _ => return Ok(()),
        };
        self.constraint_vertex(v, n, cid)
    }

    /// Sets the breaklines of a batch sweep: `vertex_of[c]` is the vertex id of constraint vertex
    /// `c` (vertex ids count from the first real vertex, as in the table given to [`Sweep::new`]).
    /// Must be called before the first [`Sweep::step`].
    ///
    /// # Panics
    /// If the first point was already swept.
    pub fn set_constraints(&mut self, graph: ConstraintGraph, vertex_of: &[u32]) {
        assert!(
            self.next == FIRST_REAL + 1,
            "constraints must be set before sweeping"
        );
        let mut batch: Vec<(u32, u32)> = vertex_of
            .iter()
            .enumerate()
            .map(|(c, &v)| (v + FIRST_REAL, c as u32))
            .collect();
        batch.sort_unstable();
        let n = graph.vertex_count();
        let mut cons = Box::new(Constraints {
            graph,
            vertex: vec![UNSWEPT; n],
            batch,
            cursor: 0,
            fed: None,
        });
        // The first vertex is already in: it ends no segment, but may start some.
        if let Some(&(v, c)) = cons.batch.first()
            && v == FIRST_REAL
        {
            cons.cursor = 1;
            cons.vertex[c as usize] = VertexId(v);
        }
        self.cons = Some(cons);
    }

    /// As [`Sweep::finish`], with the adjacency the sweep already has: `twins[3t + k]` is the
    /// half-edge on the other side of edge `k` of triangle `t` (from vertex `k` to `k + 1`),
    /// numbered the same way, or `u32::MAX` on the convex hull. Costs one pass and a map of the
    /// triangle slots (4 bytes each, while it runs), where rebuilding the adjacency from the
    /// triangles means finding every edge's twin again.
    pub fn finish_with_twins(mut self) -> (Twinned, Vec<[f64; 2]>, SweepStats) {
        self.close_hull();
        let stats = self.stats();
        let Sweep { pts, mesh, .. } = self;
        let Mesh { origin, link } = mesh;
        let slots = origin.len() / 3;
        let real = |t: usize| {
            let v = [origin[3 * t].0, origin[3 * t + 1].0, origin[3 * t + 2].0];
            !v.iter()
                .any(|&a| is_artificial(a) || a == crate::mesh::DEAD.0)
        };
        let mut new_of = vec![u32::MAX; slots];
        let mut kept = 0u32;
        for (t, n) in new_of.iter_mut().enumerate() {
            if real(t) {
                *n = kept;
                kept += 1;
            }
        }
        let mut tris = Vec::with_capacity(kept as usize);
        let mut twins = Vec::with_capacity(3 * kept as usize);
        for t in (0..slots).filter(|&t| new_of[t] != u32::MAX) {
            tris.push([0, 1, 2].map(|k| origin[3 * t + k].0 - FIRST_REAL));
            for k in 0..3 {
                let w = link[3 * t + k];
                let twin = if w & crate::mesh::BOUNDARY != 0 {
                    u32::MAX
                } else {
                    let f = (w & crate::mesh::ID_MASK) as usize;
                    match new_of[f / 3] {
                        u32::MAX => u32::MAX,
                        n => 3 * n + (f % 3) as u32,
                    }
                };
                twins.push(twin);
            }
        }
        ((tris, twins), pts.into_vec(), stats)
    }

    /// Closes the front to the convex hull, drops the artificial triangles and returns the real
    /// triangles (counter-clockwise, vertex ids relative to the first real vertex), the vertex table
    /// and the statistics.
    pub fn finish(mut self) -> (Vec<[u32; 3]>, Vec<[f64; 2]>, SweepStats) {
        self.close_hull();
        let stats = self.stats();
        let Sweep { pts, mesh, .. } = self;
        let Mesh { origin, link } = mesh;
        drop(link);
        let mut out: Vec<u32> = bytemuck::allocation::cast_vec(origin.into_vec());
        let mut k = 0;
        for t in 0..out.len() / 3 {
            let (a, b, c) = (out[3 * t], out[3 * t + 1], out[3 * t + 2]);
            if is_artificial(a) || is_artificial(b) || is_artificial(c) {
                continue;
            }
            out[3 * k] = a - FIRST_REAL;
            out[3 * k + 1] = b - FIRST_REAL;
            out[3 * k + 2] = c - FIRST_REAL;
            k += 1;
        }
        out.truncate(3 * k);
        out.shrink_to_fit();
        let tris: Vec<[u32; 3]> = match bytemuck::allocation::try_cast_vec(out) {
            Ok(t) => t,
            Err((_, out)) => out.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        };
        (tris, pts.into_vec(), stats)
    }
}

impl<H: Mode> Sweep<H> {
    /// The first triangle (P-1, P-2, first point) and the front over it.
    pub(crate) fn start(pts: SpillVec<[f64; 2]>, mut mesh: Mesh, xmap: XMap, hooks: H) -> Self {
        let first = VertexId(FIRST_REAL);
        let e = mesh.add_triangle(VertexId(P_LEFT), VertexId(P_RIGHT), first);
        // Half-edges: e: P-1→P-2 (bottom), e+1: P-2→v (under v→P-2), e+2: v→P-1 (under P-1→v).
        let front = Front::new(
            VertexId(P_LEFT),
            VertexId(P_RIGHT),
            first,
            pts[FIRST_REAL as usize],
            e.prev(),
            e.next(),
            xmap,
        );
        mesh.link[e.prev().idx()] = BOUNDARY | front.head;
        mesh.link[e.next().idx()] = BOUNDARY | front.next(front.head);
        let mut sweep = Sweep {
            pts,
            next: FIRST_REAL + 1,
            mesh,
            front,
            stack: Vec::with_capacity(64),
            stats: SweepStats {
                points: 1,
                ..SweepStats::default()
            },
            hooks,
            cons: None,
            cstats: ConstraintStats::default(),
        };
        sweep.created(e);
        sweep
    }

    /// The vertex table (local frame; rows 0 and 1 are placeholders for `P-1`, `P-2`).
    pub fn points(&self) -> &[[f64; 2]] {
        &self.pts
    }

    /// The triangles so far, artificial ones included.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The advancing front.
    pub fn front(&self) -> &Front {
        &self.front
    }

    /// The advancing front, mutable (its bucket minima are recomputed lazily).
    pub(crate) fn front_mut(&mut self) -> &mut Front {
        &mut self.front
    }

    /// What the breakline insertion has done so far.
    pub fn constraint_stats(&self) -> ConstraintStats {
        self.cstats
    }

    /// What the sweep has done so far.
    pub fn stats(&self) -> SweepStats {
        let mut s = self.stats;
        s.peak_front = self.front.peak_len() as u64;
        s
    }

    /// The mode's state (the streaming finaliser).
    #[inline(always)]
    pub(crate) fn hooks(&self) -> &H {
        &self.hooks
    }

    /// The mode's state, mutable.
    #[inline(always)]
    pub(crate) fn hooks_mut(&mut self) -> &mut H {
        &mut self.hooks
    }

    /// The vertex table, and the mode's state mutable (the finaliser reads positions while it
    /// updates itself).
    #[inline(always)]
    pub(crate) fn points_and_hooks_mut(&mut self) -> (&[[f64; 2]], &mut H) {
        (&self.pts, &mut self.hooks)
    }

    /// The point table, the mesh, the front and the mode, to move the tables elsewhere (the
    /// streaming sweep's spill, `crate::finalise`).
    pub(crate) fn tables_mut(
        &mut self,
    ) -> (&mut SpillVec<[f64; 2]>, &mut Mesh, &mut Front, &mut H) {
        (&mut self.pts, &mut self.mesh, &mut self.front, &mut self.hooks)
    }

    /// Drops the resident pages of the tables that went to temporary files (nothing for those
    /// on the heap): for walks over all of them, which would otherwise bring them all in.
    pub(crate) fn release_spilled(&mut self) {
        let (nodes, buckets, lead, last, low) = self.front.tables_mut();
        nodes.release();
        buckets.release();
        lead.release();
        last.release();
        low.release();
        self.pts.release();
        self.mesh.origin.release();
        self.mesh.link.release();
        self.hooks.release_spilled();
    }

    /// Sets the breaklines of a sweep whose points arrive one by one and name their constraint
    /// vertex (or [`NO_CONSTRAINT`]) themselves; `first_constraint` is that of the first point.
    ///
    /// # Errors
    /// [`Error::Internal`] if `first_constraint` is not a vertex of `graph`.
    pub(crate) fn set_point_constraints(
        &mut self,
        graph: ConstraintGraph,
        first_constraint: u32,
    ) -> Result<()> {
        let n = graph.vertex_count();
        let mut cons = Box::new(Constraints {
            graph,
            vertex: vec![UNSWEPT; n],
            batch: Vec::new(),
            cursor: 0,
            fed: None,
        });
        if first_constraint != NO_CONSTRAINT {
            let Some(slot) = cons.vertex.get_mut(first_constraint as usize) else {
                return Err(Error::Internal(format!(
                    "the first point is breakline vertex {first_constraint}, one of {n}"
                )));
            };
            *slot = VertexId(FIRST_REAL);
        }
        self.cons = Some(cons);
        if first_constraint != NO_CONSTRAINT {
            self.constraint_started(VertexId(FIRST_REAL), first_constraint);
        }
        Ok(())
    }

    /// Sets streamed breaklines (see [`constrain::Fed`]): each point that is a constraint vertex
    /// comes with its [`ConstraintVertex`] record ([`Sweep::next_constraint_vertex`] before the
    /// point is inserted); `first` is the first point's constraint vertex and its record.
    ///
    /// # Errors
    /// [`Error::Internal`] if the first point's record has earlier ends (nothing is earlier).
    pub(crate) fn set_fed_constraints(
        &mut self,
        first: Option<(u32, ConstraintVertex)>,
    ) -> Result<()> {
        self.cons = Some(Box::new(Constraints {
            graph: ConstraintGraph::default(),
            vertex: Vec::new(),
            batch: Vec::new(),
            cursor: 0,
            fed: Some(constrain::Fed::default()),
        }));
        if let Some((cid, rec)) = first {
            self.next_constraint_vertex(rec);
            self.fed_vertex(VertexId(FIRST_REAL), None, cid)?;
        }
        Ok(())
    }

    /// The record of the constraint vertex the next point is (streamed breaklines).
    pub(crate) fn next_constraint_vertex(&mut self, rec: ConstraintVertex) {
        if let Some(f) = self.cons.as_mut().and_then(|c| c.fed.as_mut()) {
            f.next = Some(rec);
        }
    }

    /// Stores the position of vertex `v`: the next row of the vertex table, or a row freed
    /// earlier (streaming).
    #[inline]
    pub(crate) fn put_point(&mut self, v: u32, xy: [f64; 2]) {
        let i = v as usize;
        if i == self.pts.len() {
            self.pts.push(xy);
        } else {
            self.pts[i] = xy;
        }
    }

    /// Inserts vertex `v` (in the table, after every vertex inserted so far in sweep order) and,
    /// unless `constraint` is [`NO_CONSTRAINT`], the breaklines that constraint vertex ends.
    ///
    /// # Errors
    /// [`Error::Internal`] if a breakline cannot be inserted (a bug, or a point naming a
    /// constraint vertex the sweep does not have).
    #[inline]
    pub(crate) fn insert_point(&mut self, v: VertexId, constraint: u32) -> Result<()> {
        let n = self.insert(v);
        if constraint != NO_CONSTRAINT {
            self.constraint_vertex(v, n, constraint)?;
        }
        Ok(())
    }

    /// Vertex `v` (at front node `n`) is constraint vertex `cid`: insert the segments it ends.
    fn constraint_vertex(&mut self, v: VertexId, n: NodeId, cid: u32) -> Result<()> {
        if self.cons.as_ref().is_some_and(|c| c.fed.is_some()) {
            return self.fed_vertex(v, Some(n), cid);
        }
        let Some(cons) = self
            .cons
            .as_mut()
            .filter(|c| (cid as usize) < c.vertex.len())
        else {
            return Err(Error::Internal(format!(
                "vertex {} is breakline vertex {cid}, which the sweep does not have",
                v.0
            )));
        };
        cons.vertex[cid as usize] = v;
        let lower: Vec<(u32, VertexId)> = cons
            .graph
            .lower(cid)
            .iter()
            .map(|&c| (c, cons.vertex[c as usize]))
            .collect();
        for (k, &(c, a)) in lower.iter().enumerate() {
            if a == UNSWEPT {
                return Err(Error::Internal(format!(
                    "breakline vertex {cid} was swept before the earlier end {c} of its segment"
                )));
            }
            // The front node of `v` may change while pockets are filled; it is re-located.
            let nb = if k == 0 { n } else { self.front_node_of(v)? };
            self.insert_constraint(a, v, nb)?;
            self.constraint_finished(a, c, cid);
        }
        self.constraint_started(v, cid);
        Ok(())
    }

    /// The front node of vertex `v`, which is on the front.
    fn front_node_of(&self, v: VertexId) -> Result<NodeId> {
        let n = self.front.locate(self.pts[v.0 as usize][0]);
        if self.front.vertex(n) != v {
            return Err(Error::Internal(format!(
                "vertex {} left the front while its breaklines were inserted",
                v.0
            )));
        }
        Ok(n)
    }

    /// Point event: insert vertex `v`, which lies above or on the front and after every vertex
    /// inserted so far in sweep order. Returns its front node.
    fn insert(&mut self, v: VertexId) -> NodeId {
        self.stats.points += 1;
        let x = self.pts[v.0 as usize][0];
        let l = self.front.locate(x);
        let n = self.attach(l, v);
        if self.front.node(l).x == x {
            // Left case: `v` is straight above front vertex `l`; cover it too.
            self.stats.left_cases += 1;
            self.fill(l);
        }
        self.fill_holes(n);
        n
    }

    /// Middle case: triangle (L, R, v) on the front segment right of node `l`; returns v's node.
    fn attach(&mut self, l: NodeId, v: VertexId) -> NodeId {
        let r = self.front.next(l);
        let (a, b) = (self.front.vertex(l), self.front.vertex(r));
        let below = self.front.edge(l);
        let h = self.new_triangle(a, b, v);
        self.mesh.pair(h, below, self.mesh.is_constrained(below));
        let n = self.front.insert_after(l, v, self.pts[v.0 as usize]);
        self.set_front_edge(l, h.prev());
        self.set_front_edge(n, h.next());
        self.legalize_from_apex(h);
        n
    }

    /// Covers front node `n` with the triangle (prev, n, next) and removes it from the front.
    /// `n` must lie strictly below the segment prev → next.
    fn fill(&mut self, n: NodeId) {
        let (p, q) = (self.front.prev(n), self.front.next(n));
        let (a, b, c) = (
            self.front.vertex(p),
            self.front.vertex(n),
            self.front.vertex(q),
        );
        debug_assert!(self.orient(a, b, c).is_ccw());
        let (e1, e2) = (self.front.edge(p), self.front.edge(n));
        let h = self.new_triangle(a, b, c);
        self.mesh.pair(h, e1, self.mesh.is_constrained(e1));
        self.mesh.pair(h.next(), e2, self.mesh.is_constrained(e2));
        self.front.remove(n);
        self.set_front_edge(p, h.prev());
        self.legalize_all(&[h, h.next()]);
    }

    /// Adds triangle (a, b, c) (reusing a freed slot when streaming) and returns its half-edge a → b.
    #[inline(always)]
    fn new_triangle(&mut self, a: VertexId, b: VertexId, c: VertexId) -> EdgeId {
        let e = match self.hooks.free_slot() {
            Some(t) => self.mesh.reuse_triangle(t, a, b, c),
            None => self.mesh.add_triangle(a, b, c),
        };
        self.created(e);
        if self.hooks.spill_due() {
            self.release_spilled();
        }
        e
    }

    /// Tells the mode about a new triangle (streaming: vertex references and the finalisation
    /// queue).
    #[inline(always)]
    fn created(&mut self, e: EdgeId) {
        self.hooks.created(&self.mesh, e.tri());
    }

    /// Makes `e` the boundary half-edge under the segment right of node `n`.
    #[inline(always)]
    fn set_front_edge(&mut self, n: NodeId, e: EdgeId) {
        self.front.set_edge(n, e);
        let keep = self.mesh.link[e.idx()] & CONSTRAINED;
        self.mesh.link[e.idx()] = BOUNDARY | keep | n;
    }

    /// Stores link word `word` at half-edge `slot`, which has just taken over the edge that word
    /// describes, and points the other side (twin or front node) back at `slot`.
    #[inline(always)]
    fn relink(&mut self, slot: EdgeId, word: u32) {
        self.mesh.link[slot.idx()] = word;
        match crate::mesh::across(word) {
            Across::Twin(t) => {
                let w = &mut self.mesh.link[t.idx()];
                *w = slot.0 | (*w & CONSTRAINED);
            }
            Across::Front(n) => self.front.set_edge(n, slot),
            Across::Hull => {}
        }
    }

    #[inline(always)]
    fn orient(
        &self,
        a: VertexId,
        b: VertexId,
        c: VertexId,
    ) -> crate::geom::predicates::Orientation {
        crate::geom::predicates::orient_ids(&self.pts, a.0, b.0, c.0)
    }

    /// Removes the final triangle slot `t` from the mesh and returns its vertices. Its neighbours
    /// see a hull edge from now on: the shared edge is a final Delaunay edge and will never be
    /// tested again. `ending`: the sweep is over (the front is the upper hull).
    pub(crate) fn remove_final(&mut self, t: TriId, ending: bool) -> [VertexId; 3] {
        for k in 0..3 {
            let e = EdgeId(3 * t.0 + k);
            match self.mesh.across(e) {
                Across::Twin(f) => self.mesh.detach(f),
                // During the sweep a final triangle is never under the front; at the end the
                // front is the upper hull.
                Across::Front(_) => debug_assert!(ending),
                Across::Hull => {}
            }
        }
        let tri = self.mesh.tri_vertices(t);
        self.mesh.free_triangle(t);
        tri
    }
}
