//! Breaklines: constrained edges inserted during the sweep (Domiter & Žalik 2008, section 3.4.2).
//!
//! A constraint segment is inserted when its later endpoint (in sweep order) is swept. That point
//! has just been put on the advancing front; the earlier endpoint is already in the
//! triangulation, on the front or under it. Two steps:
//!
//! 1. **Front pockets.** Where the front dips below the segment (the paper's "advancing-front
//!    traversal" case), the pocket between front and segment is filled with triangles
//!    (`Sweep::fill`, exact and legalised) until every front vertex strictly between the two
//!    endpoints' x lies on or above the segment's line. Each pocket is bounded by front vertices
//!    on or above the line, so it always has a valley to fill (an x-monotone chain below a straight
//!    top edge); filling only adds triangles, some of which the next step removes again.
//! 2. **Cavity.** The segment now lies in the triangulated region. Walking from the new point to
//!    the old one, the triangles it pierces are removed and the two pseudo-polygons on either side
//!    are re-triangulated by constrained Delaunay triangulation (Anglada 1997; the vertex of each
//!    polygon edge is chosen with the perturbed in-circle test, so ties follow the crate's rule).
//!    A vertex lying exactly on the segment splits it there (lidar points often sit on
//!    breaklines); an existing edge along the segment is just marked. Edges are marked
//!    *constrained* and legalisation never flips them.
//!
//! The removed triangles' slots are reused for the new ones (a cavity of `k` triangles is
//! re-triangulated with `k` triangles), and the cavity's outer edges keep their links, including
//! the front's references, through `Sweep::relink`.

use super::front::NodeId;
use super::{Mode, Sweep};
use crate::error::{Error, Result};
use crate::geom::predicates::{CircleSide, Orientation, incircle_ids, is_artificial, sweep_cmp};
use crate::mesh::{Across, CONSTRAINED, EdgeId, TriId, VertexId};
use std::cmp::Ordering;

/// Constraint segments, by constraint vertex (a vertex of the cleaned breakline graph).
#[derive(Clone, Debug, Default)]
pub struct ConstraintGraph {
    /// CSR offsets into `lower`.
    lower_start: Vec<u32>,
    /// For each constraint vertex, the constraint vertices joined to it that come earlier in sweep
    /// order: their segments are inserted when this vertex is swept.
    lower: Vec<u32>,
    /// CSR offsets into `upper`.
    upper_start: Vec<u32>,
    /// For each constraint vertex, the later endpoints of its segments.
    upper: Vec<u32>,
    /// Positions (local frame).
    xy: Vec<[f64; 2]>,
}

impl ConstraintGraph {
    /// Builds the graph from vertex positions (local frame, distinct) and segments between them
    /// (zero-length and repeated segments are ignored).
    pub fn new(xy: Vec<[f64; 2]>, segments: &[[u32; 2]]) -> Self {
        let n = xy.len();
        let mut pairs: Vec<(u32, u32)> = segments
            .iter()
            .filter(|s| s[0] != s[1])
            .map(|s| {
                let (a, b) = (s[0], s[1]);
                match sweep_cmp(xy[a as usize], xy[b as usize]) {
                    Ordering::Less => (b, a),
                    _ => (a, b),
                }
            })
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        let mut lower_start = vec![0u32; n + 1];
        let mut upper_start = vec![0u32; n + 1];
        for &(hi, lo) in &pairs {
            lower_start[hi as usize + 1] += 1;
            upper_start[lo as usize + 1] += 1;
        }
        for i in 0..n {
            lower_start[i + 1] += lower_start[i];
            upper_start[i + 1] += upper_start[i];
        }
        let lower = pairs.iter().map(|&(_, lo)| lo).collect();
        let mut by_lower: Vec<(u32, u32)> = pairs.iter().map(|&(hi, lo)| (lo, hi)).collect();
        by_lower.sort_unstable();
        let upper = by_lower.iter().map(|&(_, hi)| hi).collect();
        ConstraintGraph {
            lower_start,
            lower,
            upper_start,
            upper,
            xy,
        }
    }

    /// Number of constraint vertices.
    pub fn vertex_count(&self) -> usize {
        self.xy.len()
    }

    /// Number of segments.
    #[cfg(any(test, feature = "dev"))]
    pub fn segment_count(&self) -> usize {
        self.lower.len()
    }

    /// Position of constraint vertex `c`.
    pub fn xy(&self, c: u32) -> [f64; 2] {
        self.xy[c as usize]
    }

    /// Earlier endpoints of the segments whose later endpoint is `c`.
    pub fn lower(&self, c: u32) -> &[u32] {
        let (s, e) = (
            self.lower_start[c as usize] as usize,
            self.lower_start[c as usize + 1] as usize,
        );
        &self.lower[s..e]
    }

    /// Later endpoints of the segments whose earlier endpoint is `c`.
    pub fn upper(&self, c: u32) -> &[u32] {
        let (s, e) = (
            self.upper_start[c as usize] as usize,
            self.upper_start[c as usize + 1] as usize,
        );
        &self.upper[s..e]
    }
}

/// A vertex of the cleaned breakline graph as a streamed run feeds it to the sweep, with the
/// point it is: where its segments go. Positions are those of the points (local frame, `-0`
/// as `+0`), which the graph's vertices have distinct.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConstraintVertex {
    /// Its position.
    pub xy: [f64; 2],
    /// The earlier ends (in sweep order) of its segments, in the order the segments are
    /// inserted (the cleaner's order of those vertices, as [`ConstraintGraph::lower`]).
    pub lower: Vec<[f64; 2]>,
    /// The later ends of its segments.
    pub upper: Vec<[f64; 2]>,
}

/// Streamed breaklines: the graph arrives vertex by vertex, each record with its point, so the
/// sweep holds only the vertices whose segments to later vertices are not all in yet (with those
/// segments' other ends), instead of a [`ConstraintGraph`].
#[derive(Clone, Debug, Default)]
pub(crate) struct Fed {
    /// The record of the point being inserted.
    pub(super) next: Option<ConstraintVertex>,
    /// Swept vertices with segments pending, by position.
    started: crate::idmap::FastMap<(u64, u64), Started>,
}

/// A swept constraint vertex whose segments to later vertices are not all in.
#[derive(Clone, Debug)]
struct Started {
    v: VertexId,
    cid: u32,
    upper: Vec<[f64; 2]>,
    open: u32,
}

/// The key of a position (bit patterns; `-0` is `+0`).
fn pos_key(p: [f64; 2]) -> (u64, u64) {
    ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits())
}

/// Counters of the constraint insertion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct ConstraintStats {
    /// Segments inserted.
    pub segments: u64,
    /// Segments that were already an edge.
    pub already_edges: u64,
    /// Pieces created by vertices lying exactly on a segment.
    pub splits: u64,
    /// Triangles removed and re-created in cavities.
    pub cavity_triangles: u64,
    /// Triangles added to fill front pockets under segments.
    pub pocket_fills: u64,
    /// Segments (or pieces) left out because they cross another breakline; clean the breaklines
    /// first (the breakline cleaning splits crossings) to avoid this.
    pub crossing_skipped: u64,
}

/// One pseudo-polygon to triangulate: base edge `a → b` (CCW inside the polygon), the chain
/// `verts[lo..hi]` from `b` back to `a`, the outer link words of the chain's edges
/// `words[lo..=hi]`, and what the base edge pairs with.
#[derive(Clone, Copy, Debug)]
struct Poly {
    a: VertexId,
    b: VertexId,
    lo: usize,
    hi: usize,
    base: Base,
}

#[derive(Clone, Copy, Debug)]
enum Base {
    /// The twin is this half-edge of an already created triangle.
    Edge(EdgeId),
    /// The base is the segment itself; its twin comes from the other polygon.
    Segment,
}

/// Chain edges of a cavity whose other side is in the cavity too.
struct Spikes {
    dead: Vec<u32>,
    /// (old half-edge, new half-edge) waiting for the new half-edge of their old twin.
    open: Vec<(EdgeId, EdgeId)>,
}

/// Where the walk from a vertex towards the segment's end goes first.
enum Start {
    /// Along an existing edge between the current vertex and a vertex on the segment (the
    /// half-edge may point either way).
    Along(EdgeId),
    /// Into the triangle of this half-edge `cur → x`, crossing its opposite edge.
    Crossing(EdgeId),
}

impl<H: Mode> Sweep<H> {
    /// Constraint vertex `cid` was swept as `v`: its segments to later vertices become pending.
    /// When streaming, they keep `v` alive and block the finalisation of triangles near them.
    pub(crate) fn constraint_started(&mut self, v: VertexId, cid: u32) {
        let Some(cons) = self.cons.as_ref() else {
            return;
        };
        let ups = cons.graph.upper(cid);
        if ups.is_empty() {
            return;
        }
        let a = self.pts[v.0 as usize];
        for &u in ups {
            self.hooks.segment_pending(v, cid, u, a, cons.graph.xy(u));
        }
    }

    /// Streamed breaklines: vertex `v` (at front node `n`, `None` for the first point, which
    /// ends no segment) is constraint vertex `cid`, whose record was given with it: the segments
    /// it ends are inserted, in its record's order, and those it starts become pending (keyed by
    /// `cid` and their place in its record).
    ///
    /// # Errors
    /// [`Error::Internal`] when the record is missing or names another position, or an earlier
    /// end was not swept (the stream is out of step: a bug), or an insertion fails.
    pub(super) fn fed_vertex(&mut self, v: VertexId, n: Option<NodeId>, cid: u32) -> Result<()> {
        let xy = self.pts[v.0 as usize];
        let rec = self
            .cons
            .as_mut()
            .and_then(|c| c.fed.as_mut())
            .and_then(|f| f.next.take())
            .filter(|r| pos_key(r.xy) == pos_key(xy));
        let Some(rec) = rec else {
            return Err(Error::Internal(format!(
                "breakline vertex {cid} at ({}, {}) came without its record in the line stream",
                xy[0], xy[1]
            )));
        };
        for (k, &lo) in rec.lower.iter().enumerate() {
            let fed = self
                .cons
                .as_mut()
                .and_then(|c| c.fed.as_mut())
                .expect("fed constraints");
            let key = pos_key(lo);
            let found = fed.started.get_mut(&key).and_then(|s| {
                let j = s.upper.iter().position(|&u| pos_key(u) == pos_key(xy))?;
                s.open -= 1;
                Some((s.v, s.cid, j as u32, s.open == 0))
            });
            let Some((a, lo_cid, j, last)) = found else {
                return Err(Error::Internal(format!(
                    "breakline vertex ({}, {}) was swept before the earlier end ({}, {}) of its \
                     segment, or that end does not list it",
                    xy[0], xy[1], lo[0], lo[1]
                )));
            };
            if last {
                fed.started.remove(&key);
            }
            let nb = match (k, n) {
                (0, Some(n)) => n,
                _ => self.front_node_of(v)?,
            };
            self.insert_constraint(a, v, nb)?;
            self.constraint_finished(a, lo_cid, j);
        }
        if !rec.upper.is_empty() {
            for (j, &u) in rec.upper.iter().enumerate() {
                self.hooks.segment_pending(v, cid, j as u32, xy, u);
            }
            let fed = self
                .cons
                .as_mut()
                .and_then(|c| c.fed.as_mut())
                .expect("fed constraints");
            let open = rec.upper.len() as u32;
            fed.started.insert(
                pos_key(xy),
                Started {
                    v,
                    cid,
                    upper: rec.upper,
                    open,
                },
            );
        }
        Ok(())
    }

    /// The segment from constraint vertex `lo` (swept as `a`) to constraint vertex `hi` is in.
    pub(crate) fn constraint_finished(&mut self, a: VertexId, lo: u32, hi: u32) {
        self.hooks.segment_done(a, lo, hi);
    }

    /// Inserts the constraint segment between `a` (inserted earlier) and `b` (just inserted, at
    /// front node `nb`). Returns the number of pieces (more than one when vertices lie on it).
    ///
    /// # Errors
    /// [`Error::Internal`] when an invariant of the insertion fails (a bug).
    pub(crate) fn insert_constraint(
        &mut self,
        a: VertexId,
        b: VertexId,
        nb: NodeId,
    ) -> Result<u32> {
        self.cstats.segments += 1;
        self.fill_pockets(a, b, nb)?;
        // An outgoing half-edge of `b`: `b` is on the front, under its right segment lies the
        // half-edge next → b, whose successor starts at b.
        let e = self.front.edge(nb).next();
        if self.mesh.org(e) != b {
            return Err(self.internal(
                a,
                b,
                "its upper end left the front while pockets were filled",
            ));
        }
        self.constrain_from(b, a, e)
    }

    /// Side of `n` with respect to the line a → b, seen from "above" (the unswept side): +1 above,
    /// 0 on the line, -1 below. `a` and `b` differ in x.
    #[inline]
    fn side_of_line(&self, a: VertexId, b: VertexId, n: VertexId) -> i32 {
        let (pa, pb) = (self.pts[a.0 as usize], self.pts[b.0 as usize]);
        let o = self.orient(a, b, n);
        // For a → b going right, left of it is above; going left, right of it is above.
        let s = match o {
            Orientation::CounterClockwise => 1,
            Orientation::Clockwise => -1,
            Orientation::Collinear => 0,
        };
        if pb[0] > pa[0] { s } else { -s }
    }

    /// Step 1: fill the front pockets under segment a–b (see the module docs).
    fn fill_pockets(&mut self, a: VertexId, b: VertexId, nb: NodeId) -> Result<()> {
        let (xa, xb) = (self.pts[a.0 as usize][0], self.pts[b.0 as usize][0]);
        if xa == xb {
            return Ok(());
        }
        let toward_a = |s: &Self, n: NodeId| {
            if xa < xb {
                s.front.prev(n)
            } else {
                s.front.next(n)
            }
        };
        let in_range = |x: f64| if xa < xb { x > xa } else { x < xa };
        loop {
            // Find the first front vertex strictly between the endpoints' x that lies below.
            let mut n = toward_a(self, nb);
            let mut below = None;
            while !is_artificial(self.front.vertex(n).0) && in_range(self.front.node(n).x) {
                if self.side_of_line(a, b, self.front.vertex(n)) < 0 {
                    below = Some(n);
                    break;
                }
                n = toward_a(self, n);
            }
            let Some(first) = below else { return Ok(()) };
            // Within its run of below-vertices, fill the first valley.
            let mut m = first;
            loop {
                if self.is_valley(m) {
                    self.cstats.pocket_fills += 1;
                    self.fill(m);
                    break;
                }
                m = toward_a(self, m);
                let v = self.front.vertex(m);
                if is_artificial(v.0)
                    || !in_range(self.front.node(m).x)
                    || self.side_of_line(a, b, v) >= 0
                {
                    return Err(self.internal(a, b, "a front pocket under it has no valley"));
                }
            }
        }
    }

    /// Is front node `n` strictly below the segment between its neighbours (all real)?
    fn is_valley(&self, n: NodeId) -> bool {
        let (p, q) = (self.front.prev(n), self.front.next(n));
        let (vp, vn, vq) = (
            self.front.vertex(p),
            self.front.vertex(n),
            self.front.vertex(q),
        );
        !is_artificial(vp.0)
            && !is_artificial(vn.0)
            && !is_artificial(vq.0)
            && self.orient(vp, vn, vq).is_ccw()
    }

    /// Step 2: make `s`–`t` a chain of constrained edges, starting from half-edge `e` out of `s`.
    fn constrain_from(&mut self, s: VertexId, t: VertexId, mut e: EdgeId) -> Result<u32> {
        let mut cur = s;
        let mut pieces = 0;
        while cur != t {
            pieces += 1;
            match self.start_towards(cur, t, e)? {
                Start::Along(f) => {
                    self.mesh.constrain(f);
                    let (from, to) = (self.mesh.org(f), self.mesh.dst(f));
                    let next = if from == cur { to } else { from };
                    if pieces == 1 && next == t {
                        self.cstats.already_edges += 1;
                    }
                    // An outgoing half-edge of `next`.
                    e = if from == next {
                        f
                    } else {
                        match self.mesh.across(f) {
                            Across::Twin(g) => g,
                            _ => f.next(),
                        }
                    };
                    cur = next;
                }
                Start::Crossing(f) => match self.dig_cavity(cur, t, f)? {
                    Some((v, out)) => {
                        cur = v;
                        e = out;
                    }
                    None => {
                        // It crosses another breakline: leave it out and report it.
                        self.cstats.crossing_skipped += 1;
                        return Ok(pieces);
                    }
                },
            }
        }
        self.cstats.splits += u64::from(pieces - 1);
        Ok(pieces)
    }

    /// Is `x` on the ray from `c` through `t`, given that the three are collinear?
    fn same_direction(&self, c: VertexId, x: VertexId, t: VertexId) -> bool {
        let (pc, px, pt) = (
            self.pts[c.0 as usize],
            self.pts[x.0 as usize],
            self.pts[t.0 as usize],
        );
        let k = if pc[0] != pt[0] { 0 } else { 1 };
        (px[k] - pc[k] > 0.0) == (pt[k] - pc[k] > 0.0) && px[k] != pc[k]
    }

    /// Finds, around `cur` (from its outgoing half-edge `e`), the edge along `cur → t` or the
    /// triangle the segment enters.
    fn start_towards(&self, cur: VertexId, t: VertexId, e: EdgeId) -> Result<Start> {
        let lost = |what: &str| self.internal(cur, t, &format!("{what} around its first end"));
        // Rotate counter-clockwise from `e` until the boundary, then clockwise from `e`.
        let mut f = e;
        let mut ccw = true;
        let mut steps = 0usize;
        loop {
            steps += 1;
            if steps >= 1 << 24 {
                return Err(lost("no way found after 2^24 steps"));
            }
            // `f` comes from rotations around `cur` only.
            debug_assert_eq!(self.mesh.org(f), cur);
            let x = self.mesh.dst(f);
            let y = self.mesh.dst(f.next());
            let ox = self.orient(cur, x, t);
            if ox == Orientation::Collinear && !is_artificial(x.0) && self.same_direction(cur, x, t)
            {
                return Ok(Start::Along(f));
            }
            let oy = self.orient(cur, y, t);
            if oy == Orientation::Collinear && !is_artificial(y.0) && self.same_direction(cur, y, t)
            {
                // Along the edge y → cur (f.prev()), which starts at y.
                return Ok(Start::Along(f.prev()));
            }
            if ox.is_ccw() && oy == Orientation::Clockwise {
                return Ok(Start::Crossing(f));
            }
            // Next outgoing half-edge.
            let next = if ccw {
                match self.mesh.across(f.prev()) {
                    Across::Twin(g) => Some(g),
                    _ => None,
                }
            } else {
                match self.mesh.across(f) {
                    Across::Twin(g) => Some(g.next()),
                    _ => None,
                }
            };
            match next {
                Some(g) if g != e => f = g,
                Some(_) => return Err(lost("its direction was not found in a full turn")),
                None if !ccw => {
                    return Err(lost("it leaves the triangulated region clockwise"));
                }
                None => {
                    ccw = false;
                    // Restart clockwise from `e` (its own triangle was already tested).
                    f = match self.mesh.across(e) {
                        Across::Twin(g) => g.next(),
                        _ => {
                            return Err(lost(
                                "it leaves the triangulated region counter-clockwise",
                            ));
                        }
                    };
                }
            }
        }
    }

    /// Removes the triangles pierced by `cur → t`, starting in the triangle of `f` (`cur → x`),
    /// up to `t` or the first vertex exactly on the segment, and re-triangulates both sides.
    /// Returns that end vertex and an outgoing half-edge of it, or `None` (and changes nothing)
    /// when the segment crosses a constrained edge.
    fn dig_cavity(
        &mut self,
        cur: VertexId,
        t: VertexId,
        f: EdgeId,
    ) -> Result<Option<(VertexId, EdgeId)>> {
        let mut dead: Vec<u32> = vec![f.tri().0];
        // Right chain (walk order) with the outer words of the edges cur→r1, r1→r2, …
        let mut right: Vec<VertexId> = vec![self.mesh.dst(f)];
        let mut right_words: Vec<EdgeId> = vec![f];
        // Left chain (walk order) with the outer words of the edges l1→cur, l2→l1, …
        let mut left: Vec<VertexId> = vec![self.mesh.dst(f.next())];
        let mut left_words: Vec<EdgeId> = vec![f.prev()];
        let mut e = f.next(); // the crossed edge x → y (right → left)
        let end = loop {
            if self.mesh.is_constrained(e) {
                return Ok(None);
            }
            let g = match self.mesh.across(e) {
                Across::Twin(g) => g,
                _ => {
                    return Err(self.internal(cur, t, "it crosses the front or the hull"));
                }
            };
            dead.push(g.tri().0);
            // Triangle of g: (y, x, z) with g = y → x.
            let z = self.apex(g);
            if is_artificial(z.0) {
                return Err(self.internal(cur, t, "it enters a triangle of an artificial point"));
            }
            let oz = self.orient(cur, t, z);
            if z == t || oz == Orientation::Collinear {
                // x → z closes the right chain, z → y the left.
                right_words.push(g.next());
                left_words.push(g.prev());
                break z;
            }
            if oz.is_ccw() {
                left.push(z);
                left_words.push(g.prev());
                e = g.next();
            } else {
                right.push(z);
                right_words.push(g.next());
                e = g.prev();
            }
        };
        self.cstats.cavity_triangles += dead.len() as u64;
        self.release_triangles(&dead);
        // Snapshot the outer links before the slots are reused. An edge whose other side is in
        // the cavity too (a vertex whose whole star is pierced hangs on it, and appears twice in
        // a chain) is re-created between the two new triangles on it.
        let mut spikes = Spikes {
            dead: dead.clone(),
            open: Vec::new(),
        };
        let snap = |s: &Self, v: &[EdgeId]| -> Vec<(EdgeId, u32)> {
            v.iter().map(|&h| (h, s.mesh.link[h.idx()])).collect()
        };
        let left_edges: Vec<(EdgeId, u32)> = snap(self, &left_words).into_iter().rev().collect();
        let right_edges = snap(self, &right_words);
        // Left polygon: base cur → end, chain from end back to cur: left reversed.
        let verts: Vec<VertexId> = left.iter().rev().copied().collect();
        let left_first =
            self.triangulate_pseudo_polygon(cur, end, &verts, &left_edges, &mut dead, &mut spikes)?;
        // Right polygon: base end → cur, chain right (walk order).
        let right_first = self.triangulate_pseudo_polygon(
            end,
            cur,
            &right,
            &right_edges,
            &mut dead,
            &mut spikes,
        )?;
        if !spikes.open.is_empty() || !dead.is_empty() {
            let what = format!(
                "its cavity was re-triangulated with {} edges unpaired and {} slots unused",
                spikes.open.len(),
                dead.len()
            );
            return Err(self.internal(cur, end, &what));
        }
        self.mesh.pair(left_first, right_first, true);
        Ok(Some((end, right_first)))
    }

    /// Links the new half-edge `h` on a cavity chain edge, which was half-edge `old` with link
    /// word `word` in the removed triangles.
    fn attach_chain_edge(&mut self, h: EdgeId, (old, word): (EdgeId, u32), spikes: &mut Spikes) {
        if let Across::Twin(o) = crate::mesh::across(word)
            && spikes.dead.contains(&o.tri().0)
        {
            // Both sides are in the cavity: pair with the new half-edge made for `o`.
            match spikes.open.iter().position(|&(k, _)| k == o) {
                Some(i) => {
                    let (_, g) = spikes.open.swap_remove(i);
                    self.mesh.pair(h, g, word & CONSTRAINED != 0);
                }
                None => spikes.open.push((old, h)),
            }
            return;
        }
        self.relink(h, word);
    }

    /// Drops the triangles in `dead` from the vertex reference counts (their slots are reused).
    fn release_triangles(&mut self, dead: &[u32]) {
        self.hooks.cavity_removed(&self.mesh, dead);
    }

    /// Constrained Delaunay triangulation of the pseudo-polygon with base `a → b` and `chain`
    /// (from `b` back to `a`); `words[i]` is the old half-edge and outer link of the chain's `i`-th
    /// edge (`b → c1`,
    /// `c1 → c2`, …, `cm → a`). Triangles go into the slots in `slots`. Returns the half-edge
    /// `a → b` of the triangle on the base.
    fn triangulate_pseudo_polygon(
        &mut self,
        a: VertexId,
        b: VertexId,
        chain: &[VertexId],
        words: &[(EdgeId, u32)],
        slots: &mut Vec<u32>,
        spikes: &mut Spikes,
    ) -> Result<EdgeId> {
        debug_assert_eq!(words.len(), chain.len() + 1);
        let mut base_edge = None;
        let mut stack = vec![Poly {
            a,
            b,
            lo: 0,
            hi: chain.len(),
            base: Base::Segment,
        }];
        while let Some(p) = stack.pop() {
            // The chain vertex that makes a constrained Delaunay triangle with the base.
            let mut k = p.lo;
            for j in p.lo + 1..p.hi {
                if incircle_ids(&self.pts, p.a.0, p.b.0, chain[k].0, chain[j].0)
                    == CircleSide::Inside
                {
                    k = j;
                }
            }
            let c = chain[k];
            let Some(slot) = slots.pop() else {
                return Err(self.internal(a, b, "its cavity needs more triangles than it had"));
            };
            let h = self.mesh.reuse_triangle(TriId(slot), p.a, p.b, c);
            self.hooks.cavity_filled([p.a, p.b, c]);
            match p.base {
                Base::Edge(g) => self.mesh.pair(h, g, false),
                Base::Segment => base_edge = Some(h),
            }
            // b → c: chain b … c_k (words lo..=k) ; c → a: chain c_k … a (words k+1..=hi).
            if k == p.lo {
                self.attach_chain_edge(h.next(), words[p.lo], spikes);
            } else {
                stack.push(Poly {
                    a: c,
                    b: p.b,
                    lo: p.lo,
                    hi: k,
                    base: Base::Edge(h.next()),
                });
            }
            if k + 1 == p.hi {
                self.attach_chain_edge(h.prev(), words[p.hi], spikes);
            } else {
                stack.push(Poly {
                    a: p.a,
                    b: c,
                    lo: k + 1,
                    hi: p.hi,
                    base: Base::Edge(h.prev()),
                });
            }
        }
        base_edge.ok_or_else(|| self.internal(a, b, "its cavity has no triangle on it"))
    }

    /// An [`Error::Internal`] from the insertion of the breakline segment between `a` and `b`:
    /// what failed, and where (sweep coordinates, relative to the run's local origin).
    fn internal(&self, a: VertexId, b: VertexId, what: &str) -> Error {
        let (pa, pb) = (self.pts[a.0 as usize], self.pts[b.0 as usize]);
        Error::Internal(format!(
            "inserting the breakline segment ({}, {})-({}, {}) (local frame): {what}",
            pa[0], pa[1], pb[0], pb[1]
        ))
    }
}
