//! The sweep-line Delaunay triangulation (Domiter & Žalik 2008, section 3).
//!
//! Points are inserted in sweep order (by `y`, then `x`). Each one is projected vertically onto the
//! advancing front ([`front`]) and connected to the segment it hits (the *middle case*), or, when it
//! lies exactly above a front vertex, to both segments around that vertex (the *left case*). Every
//! new triangle is legalised at once by Lawson flips with an explicit stack ([`legalize`]). Two
//! heuristics keep the front smooth ([`heuristics`]): holes next to the new point whose angle is
//! below π/2 are filled, and deep basins are filled. When all points are in, the front is closed to
//! its convex hull and the triangles that use an artificial point are dropped.
//!
//! The sweep is steppable: [`Sweep::new`] → [`Sweep::step`] … → [`Sweep::finish`], and
//! [`Sweep::check`] verifies every invariant of the current state (used by tests and fuzzing).

pub mod check;
pub mod constrain;
pub mod front;
pub mod heuristics;
pub mod legalize;

use crate::error::{Error, Result};
pub use crate::finalise::{Event, StreamConfig, StreamPoint, StreamStats};
use crate::geom::predicates::{FIRST_REAL, P_LEFT, P_RIGHT, is_artificial};
use crate::mesh::{Across, BOUNDARY, CONSTRAINED, EdgeId, Mesh, TriId, VertexId};
pub use constrain::{ConstraintGraph, ConstraintStats};
use front::{Front, NodeId, XMap};

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
/// Two modes share all of the geometry:
/// * **batch** ([`Sweep::new`]): the whole vertex table is given up front and every triangle stays in
///   memory until [`Sweep::finish`];
/// * **streaming** ([`Sweep::streaming`], see [`crate::finalise`]): points are pushed one at a time and a
///   triangle leaves memory (as an [`Event`]) as soon as nothing later can change it.
#[derive(Debug, Clone)]
pub struct Sweep {
    pub(crate) pts: Vec<[f64; 2]>,
    pub(crate) next: u32,
    pub(crate) mesh: Mesh,
    pub(crate) front: Front,
    pub(crate) stack: Vec<EdgeId>,
    pub(crate) stats: SweepStats,
    pub(crate) fin: Option<Box<crate::finalise::Finalizer>>,
    pub(crate) cons: Option<Box<Constraints>>,
    pub(crate) cstats: ConstraintStats,
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
}

/// No constraint vertex.
pub const NO_CONSTRAINT: u32 = u32::MAX;

impl Sweep {
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
        Ok(Self::start(pts, mesh, xmap, None))
    }

    /// The first triangle (P-1, P-2, first point) and the front over it.
    pub(crate) fn start(
        pts: Vec<[f64; 2]>,
        mut mesh: Mesh,
        xmap: XMap,
        fin: Option<Box<crate::finalise::Finalizer>>,
    ) -> Self {
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
            fin,
            cons: None,
            cstats: ConstraintStats::default(),
        };
        sweep.created(e);
        sweep
    }

    /// Inserts the next point; returns `false` when all points are in.
    pub fn step(&mut self) -> bool {
        if self.next as usize >= self.pts.len() {
            return false;
        }
        let v = VertexId(self.next);
        self.next += 1;
        self.insert_batch(v);
        true
    }

    /// Inserts all remaining points.
    pub fn run(&mut self) {
        while (self.next as usize) < self.pts.len() {
            let v = VertexId(self.next);
            self.next += 1;
            self.insert_batch(v);
        }
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

    /// Batch mode: inserts vertex `v` and the breaklines it ends.
    fn insert_batch(&mut self, v: VertexId) {
        let n = self.insert(v);
        let cid = match self.cons.as_mut() {
            Some(c) if c.cursor < c.batch.len() && c.batch[c.cursor].0 == v.0 => {
                c.cursor += 1;
                c.batch[c.cursor - 1].1
            }
            _ => return,
        };
        self.constraint_vertex(v, n, cid);
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
            vertex: vec![VertexId(u32::MAX); n],
            batch,
            cursor: 0,
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

    /// Sets the breaklines of a streaming sweep; points name their constraint vertex in
    /// [`StreamPoint::constraint`].
    pub fn set_stream_constraints(&mut self, graph: ConstraintGraph, first_constraint: u32) {
        let n = graph.vertex_count();
        let mut cons = Box::new(Constraints {
            graph,
            vertex: vec![VertexId(u32::MAX); n],
            batch: Vec::new(),
            cursor: 0,
        });
        if first_constraint != NO_CONSTRAINT {
            cons.vertex[first_constraint as usize] = VertexId(FIRST_REAL);
        }
        self.cons = Some(cons);
        if first_constraint != NO_CONSTRAINT {
            self.constraint_started(VertexId(FIRST_REAL), first_constraint);
        }
    }

    /// Vertex `v` (at front node `n`) is constraint vertex `cid`: insert the segments it ends.
    pub(crate) fn constraint_vertex(&mut self, v: VertexId, n: NodeId, cid: u32) {
        let cons = self.cons.as_mut().expect("constraints are set");
        cons.vertex[cid as usize] = v;
        let lower: Vec<VertexId> = cons
            .graph
            .lower(cid)
            .iter()
            .map(|&c| cons.vertex[c as usize])
            .collect();
        for (k, &a) in lower.iter().enumerate() {
            debug_assert!(a.0 != u32::MAX, "a breakline's lower end was not swept");
            // The front node of `v` may change while pockets are filled; it is re-located.
            let nb = if k == 0 { n } else { self.front_node_of(v) };
            self.insert_constraint(a, v, nb);
            let c = self.cons.as_ref().expect("set").graph.lower(cid)[k];
            self.constraint_finished(a, c, cid);
        }
        self.constraint_started(v, cid);
    }

    /// The front node of vertex `v`, which is on the front.
    fn front_node_of(&self, v: VertexId) -> NodeId {
        let n = self.front.locate(self.pts[v.0 as usize][0]);
        debug_assert_eq!(self.front.vertex(n), v);
        n
    }

    /// Point event: insert vertex `v`, which lies above or on the front and after every vertex
    /// inserted so far in sweep order. Returns its front node.
    pub(crate) fn insert(&mut self, v: VertexId) -> NodeId {
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
        let e = match self.fin.as_mut().and_then(|f| f.free_triangles.pop()) {
            Some(t) => self.mesh.reuse_triangle(TriId(t), a, b, c),
            None => self.mesh.add_triangle(a, b, c),
        };
        self.created(e);
        e
    }

    /// Streaming bookkeeping for a new triangle: vertex references and the finalisation queue.
    #[inline(always)]
    fn created(&mut self, e: EdgeId) {
        if let Some(f) = self.fin.as_mut() {
            let o = &self.mesh.origin;
            for k in 0..3 {
                f.vertices.refs[o[e.idx() + k].0 as usize] += 1;
            }
            f.created(e.tri().0);
        }
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

    /// Closes the front to the convex hull, drops the artificial triangles and returns the real
    /// triangles (counter-clockwise, vertex ids relative to the first real vertex), the vertex table
    /// and the statistics.
    pub fn finish(mut self) -> (Vec<[u32; 3]>, Vec<[f64; 2]>, SweepStats) {
        self.close_hull();
        let stats = self.stats();
        let Sweep { pts, mesh, .. } = self;
        let Mesh { origin, link } = mesh;
        drop(link);
        let mut out: Vec<u32> = bytemuck::allocation::cast_vec(origin);
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
        (tris, pts, stats)
    }
}
