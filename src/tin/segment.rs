//! Breakline insertion into an existing TIN (Herva 2009, section 5.5), by Sloan's method: flip
//! the edges the segment crosses until it appears, then restore the constrained Delaunay
//! property around the new edges by Lawson flips (the breakline itself is never flipped).

use super::{Tin, VertexId};
use crate::error::{Error, Result};
use crate::geom::predicates::Orientation;
use std::collections::VecDeque;

impl Tin {
    /// Inserts the points of a polyline (as [`Tin::insert`]) and makes each of its segments a
    /// constrained edge. Returns the vertices of the polyline.
    ///
    /// # Errors
    /// As [`Tin::insert`] and [`Tin::insert_segment`]. On error, the segments before the failing
    /// one stay inserted.
    pub fn insert_breakline(&mut self, points: &[[f64; 3]]) -> Result<Vec<VertexId>> {
        let ids = points
            .iter()
            .map(|&p| self.insert(p))
            .collect::<Result<Vec<_>>>()?;
        for w in ids.windows(2) {
            self.insert_segment(w[0], w[1])?;
        }
        Ok(ids)
    }

    /// Makes the segment `a – b` a constrained edge. Vertices lying exactly on the segment split
    /// it into pieces.
    ///
    /// # Errors
    /// [`Error::Invalid`] if an end is not in the TIN, or if the segment properly crosses an
    /// existing constrained edge (the crossing point is not representable exactly; insert it as a
    /// vertex first). On error, the pieces before the crossing stay inserted.
    pub fn insert_segment(&mut self, a: VertexId, b: VertexId) -> Result<()> {
        for v in [a, b] {
            if self.out_edge(v).is_none() {
                return Err(Error::Invalid(format!("vertex {} is not in the TIN", v.0)));
            }
        }
        let mut work = vec![(a, b)];
        while let Some((a, b)) = work.pop() {
            if a == b {
                continue;
            }
            // (A hull edge has one half-edge only, maybe b → a.)
            if let Some(e) = self.find_edge(a, b).or_else(|| self.find_edge(b, a)) {
                self.mesh.constrain(e);
                continue;
            }
            let (crossing, stop) = self.crossings(a, b)?;
            if stop != b {
                work.push((stop, b));
            }
            if crossing.is_empty() {
                // `stop` is a neighbour of `a` on the segment.
                let e = self
                    .find_edge(a, stop)
                    .ok_or_else(|| Error::Internal("breakline walk lost its edge".into()))?;
                self.mesh.constrain(e);
                continue;
            }
            self.flip_out(a, stop, crossing)?;
        }
        Ok(())
    }

    /// Walks from `a` towards `b`; returns the edges the segment crosses (as (right, left) vertex
    /// pairs) up to the first vertex on the segment (`b`, or a vertex exactly on it).
    #[allow(clippy::type_complexity)]
    fn crossings(&self, a: VertexId, b: VertexId) -> Result<(Vec<(VertexId, VertexId)>, VertexId)> {
        let (pa, pb) = (self.xy(a), self.xy(b));
        let side = |v: VertexId| self.orient_p(pa, pb, self.xy(v));
        let mut g = None;
        for e in self.out_edges(a) {
            let u = self.dst(e);
            if side(u) == Orientation::Collinear {
                let (pu, d) = (self.xy(u), [pb[0] - pa[0], pb[1] - pa[1]]);
                if (pu[0] - pa[0]) * d[0] + (pu[1] - pa[1]) * d[1] > 0.0 {
                    return Ok((Vec::new(), u));
                }
                continue;
            }
            let w = self.org(e.prev());
            if side(u) == Orientation::Clockwise && side(w) == Orientation::CounterClockwise {
                g = Some(e.next());
                break;
            }
        }
        let mut g = g.ok_or_else(|| Error::Internal("breakline start not found".into()))?;
        let mut out = Vec::new();
        loop {
            let (u, w) = (self.org(g), self.dst(g));
            if self.is_constrained(g) {
                return Err(Error::Invalid(format!(
                    "breakline {} – {} crosses the breakline {} – {}",
                    a.0, b.0, u.0, w.0
                )));
            }
            out.push((u, w));
            let t = self
                .twin(g)
                .ok_or_else(|| Error::Internal("breakline walk left the hull".into()))?;
            let x = self.org(t.prev());
            if x == b {
                return Ok((out, b));
            }
            match side(x) {
                Orientation::Collinear => return Ok((out, x)),
                Orientation::Clockwise => g = t.prev(),
                Orientation::CounterClockwise => g = t.next(),
            }
        }
    }

    /// Sloan's flipping: removes the crossing edges, then legalises the new ones.
    fn flip_out(
        &mut self,
        a: VertexId,
        b: VertexId,
        crossing: Vec<(VertexId, VertexId)>,
    ) -> Result<()> {
        let (pa, pb) = (self.xy(a), self.xy(b));
        let mut queue: VecDeque<_> = crossing.into();
        let mut fresh = Vec::new();
        let mut guard = 0u64;
        while let Some((u, w)) = queue.pop_front() {
            guard += 1;
            if guard > 1 << 32 {
                return Err(Error::Internal("breakline flipping does not end".into()));
            }
            let e = self
                .find_edge(u, w)
                .ok_or_else(|| Error::Internal("crossing edge vanished".into()))?;
            let f = self
                .twin(e)
                .ok_or_else(|| Error::Internal("crossing edge on the hull".into()))?;
            let p = self.org(e.prev());
            let q = self.org(f.prev());
            let (pp, pq) = (self.xy(p), self.xy(q));
            let su = self.orient_p(pp, pq, self.xy(u));
            let sw = self.orient_p(pp, pq, self.xy(w));
            let convex = matches!(
                (su, sw),
                (Orientation::Clockwise, Orientation::CounterClockwise)
                    | (Orientation::CounterClockwise, Orientation::Clockwise)
            );
            if !convex {
                queue.push_back((u, w));
                continue;
            }
            self.flip(e);
            let crosses = p != a && p != b && q != a && q != b && {
                let sp = self.orient_p(pa, pb, pp);
                let sq = self.orient_p(pa, pb, pq);
                sp != Orientation::Collinear && sq != Orientation::Collinear && sp != sq
            };
            if crosses {
                queue.push_back((p, q));
            } else {
                fresh.push((p, q));
            }
        }
        let e = self
            .find_edge(a, b)
            .ok_or_else(|| Error::Internal("breakline edge missing after flips".into()))?;
        self.mesh.constrain(e);
        self.legalize_edges(fresh);
        Ok(())
    }
}
