//! Validation of a streaming mesh (`.stin`) in bounded memory: [`StreamChecker`], fed the
//! stream's events (`sweeptin check mesh.stin` reads them with `input::stin::StinReader`).
//!
//! The in-memory validator ([`super::validate`]) holds the whole mesh. A `.stin` says when a
//! vertex is no longer used (its *vertex done* record), so a checker can keep only what the
//! stream keeps: the live vertices and the edges waiting for their twin — the advancing front,
//! not the mesh. The checks are local, each decided exactly:
//!
//! 1. every triangle is strictly counter-clockwise and uses live vertices;
//! 2. every directed edge is used once (so each undirected edge by at most two triangles, in
//!    opposite directions);
//! 3. every interior edge is locally Delaunay (the vertex across it is not strictly inside the
//!    circumcircle of the triangle on this side; unperturbed, so cocircular quadruples pass);
//! 4. every vertex is used by a triangle, and no two live vertices share their `(x, y)`;
//! 5. when a vertex is done, its edges without a twin are boundary edges: none, or one in and one
//!    out, turning left or straight (a convex corner, never reflex);
//! 6. Euler's count `V − E + T = 1` (one piece, no hole) and the boundary's total turn is one full
//!    turn (it winds once): with 5, the boundary is one convex loop, the convex hull.
//!
//! What the in-memory check does and this one cannot: vertex distinctness against vertices
//! already done (a duplicate position is caught only while both are live, or as a degenerate
//! triangle) and the exact hull by a monotone chain (collinear hull points are checked by the
//! corner test of 5 instead). Memory: the live vertices and pending edges, about 100 bytes each.

use super::Report;
use crate::error::{Error, Result};
use crate::geom::predicates::{CircleSide, Orientation, incircle_exact, orient};
use crate::idmap::{FastMap, IdMap};

/// What a [`StreamChecker`] checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamCheck {
    /// The boundary is the convex hull and the mesh has no hole (5, 6; off for trimmed meshes).
    pub convex_hull: bool,
    /// Interior edges are locally Delaunay (3; off for `--no-flat-triangles` meshes).
    pub delaunay: bool,
}

impl Default for StreamCheck {
    fn default() -> Self {
        StreamCheck {
            convex_hull: true,
            delaunay: true,
        }
    }
}

impl StreamCheck {
    /// The checks a streaming mesh of `kind` must pass (its header's flags): as
    /// [`super::CdtCheck::for_kind`] without segments (the streaming check takes none).
    pub fn for_kind(kind: super::MeshKind) -> Self {
        let c = super::CdtCheck::for_kind(kind, false);
        StreamCheck {
            convex_hull: c.convex_hull,
            delaunay: c.delaunay,
        }
    }
}

/// What a live vertex has seen so far.
struct Live {
    xy: [f64; 2],
    used: bool,
}

/// A directed edge waiting for its twin: the vertex opposite it in its triangle.
struct Pending {
    opposite: [f64; 2],
}

/// Checks a streaming mesh as its events come (see the module docs): [`StreamChecker::vertex`],
/// [`StreamChecker::triangle`], [`StreamChecker::done`] in stream order, then
/// [`StreamChecker::finish`].
pub struct StreamChecker {
    check: StreamCheck,
    live: IdMap<Live>,
    positions: FastMap<(u64, u64), u64>,
    /// Directed edges `(a, b)` of triangles whose twin `(b, a)` has not come yet.
    edges: FastMap<(u64, u64), Pending>,
    /// Each live vertex's pending edges (out and in), to find its boundary edges when done.
    star: IdMap<Vec<(u64, u64)>>,
    /// Boundary edges found at one end (done first), by their other end: `(from, to)` ends.
    boundary: IdMap<Vec<(bool, [[f64; 2]; 2])>>,
    report: Report,
    used_vertices: u64,
    turning: f64,
    peak_live: usize,
    peak_edges: usize,
    vertices: u64,
}

/// What [`StreamChecker`] found, with the memory it needed.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StreamReport {
    /// The counts (as [`super::validate`] reports them; `cocircular_edges` counted too).
    pub report: Report,
    /// Most vertices held at once.
    pub peak_live_vertices: u64,
    /// Most edges waiting for their twin at once.
    pub peak_pending_edges: u64,
}

fn invalid(m: String) -> Error {
    Error::Invalid(m)
}

impl StreamChecker {
    /// A checker making the checks of `check`.
    pub fn new(check: StreamCheck) -> StreamChecker {
        StreamChecker {
            check,
            live: IdMap::default(),
            positions: FastMap::default(),
            edges: FastMap::default(),
            star: IdMap::default(),
            boundary: IdMap::default(),
            report: Report::default(),
            used_vertices: 0,
            turning: 0.0,
            peak_live: 0,
            peak_edges: 0,
            vertices: 0,
        }
    }

    /// The next vertex (numbered 0, 1, … in order).
    ///
    /// # Errors
    /// [`Error::Invalid`] for a vertex at the position of a live one.
    pub fn vertex(&mut self, p: [f64; 3]) -> Result<()> {
        let id = self.vertices;
        self.vertices += 1;
        let xy = [p[0] + 0.0, p[1] + 0.0];
        let key = (xy[0].to_bits(), xy[1].to_bits());
        if let Some(other) = self.positions.insert(key, id) {
            return Err(invalid(format!(
                "vertices {other} and {id} are at the same position ({}, {})",
                xy[0], xy[1]
            )));
        }
        self.live.insert(id, Live { xy, used: false });
        self.peak_live = self.peak_live.max(self.live.len());
        Ok(())
    }

    /// The next triangle: its vertices' numbers and coordinates.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the triangle (orientation, an edge used twice, not Delaunay).
    pub fn triangle(&mut self, ids: [u64; 3], points: [[f64; 3]; 3]) -> Result<()> {
        let n = self.report.triangles;
        let p = points.map(|q| [q[0], q[1]]);
        if orient(p[0], p[1], p[2]) != Orientation::CounterClockwise {
            return Err(invalid(format!(
                "triangle {n} ({}, {}, {}) is not strictly counter-clockwise",
                ids[0], ids[1], ids[2]
            )));
        }
        for &v in &ids {
            if let Some(l) = self.live.get_mut(&v) {
                l.used = true;
            }
        }
        for k in 0..3 {
            let (a, b, c) = (ids[k], ids[(k + 1) % 3], ids[(k + 2) % 3]);
            let opposite = p[(k + 2) % 3];
            if self.edges.contains_key(&(a, b)) {
                return Err(invalid(format!(
                    "edge {a} -> {b} is used by two triangles in the same direction \
                     (triangle {n} overlaps another)"
                )));
            }
            match self.edges.remove(&(b, a)) {
                Some(twin) => {
                    self.report.edges += 1;
                    // Triangle (a, b, c) and the twin's (b, a, twin.opposite).
                    match incircle_exact(p[k], p[(k + 1) % 3], opposite, twin.opposite) {
                        CircleSide::Inside if self.check.delaunay => {
                            return Err(invalid(format!(
                                "edge {a}-{b} (triangle {n}, opposite vertex {c}) is not locally \
                                 Delaunay: the vertex across it is inside the circumcircle"
                            )));
                        }
                        CircleSide::On => self.report.cocircular_edges += 1,
                        _ => {}
                    }
                    for v in [a, b] {
                        if let Some(s) = self.star.get_mut(&v) {
                            s.retain(|e| *e != (b, a));
                        }
                    }
                }
                None => {
                    self.edges.insert((a, b), Pending { opposite });
                    for v in [a, b] {
                        self.star.entry(v).or_default().push((a, b));
                    }
                }
            }
        }
        self.peak_edges = self.peak_edges.max(self.edges.len());
        self.report.triangles += 1;
        Ok(())
    }

    /// Vertex `v` is used by no later triangle.
    ///
    /// # Errors
    /// [`Error::Invalid`] for an unused vertex or a boundary that is not convex there.
    pub fn done(&mut self, v: u64) -> Result<()> {
        let Some(l) = self.live.remove(&v) else {
            return Ok(());
        };
        self.positions
            .remove(&(l.xy[0].to_bits(), l.xy[1].to_bits()));
        if !l.used {
            return Err(invalid(format!("vertex {v} is used by no triangle")));
        }
        self.used_vertices += 1;
        let mine = self.star.remove(&v).unwrap_or_default();
        let (mut inward, mut outward) = (Vec::new(), Vec::new());
        for (a, b) in mine {
            // Still pending when one end is done: a boundary edge (no twin can come any more).
            if self.edges.remove(&(a, b)).is_none() {
                continue;
            }
            let other = if a == v { b } else { a };
            let xy_other = self.live.get(&other).map(|o| o.xy);
            let ends = match xy_other {
                Some(o) if a == v => [l.xy, o],
                Some(o) => [o, l.xy],
                None => continue,
            };
            // For `other`, the edge is outgoing when it starts there.
            self.boundary.entry(other).or_default().push((b == v, ends));
            if let Some(s) = self.star.get_mut(&other) {
                s.retain(|x| *x != (a, b));
            }
            self.report.edges += 1;
            self.report.hull_vertices += 1;
            if a == v {
                outward.push(ends)
            } else {
                inward.push(ends)
            }
        }
        // Boundary edges whose other end was done before: found there, closed here.
        for (out, ends) in self.boundary.remove(&v).unwrap_or_default() {
            if out {
                outward.push(ends);
            } else {
                inward.push(ends);
            }
        }
        if !self.check.convex_hull {
            return Ok(());
        }
        match (inward.as_slice(), outward.as_slice()) {
            ([], []) => Ok(()),
            ([i], [o]) => {
                let (u, w) = (i[0], o[1]);
                if orient(u, l.xy, w) == Orientation::Clockwise {
                    return Err(invalid(format!(
                        "the boundary turns right at vertex {v} ({}, {}): not the convex hull \
                         (a hole, a notch, or a trimmed mesh: use --trimmed)",
                        l.xy[0], l.xy[1]
                    )));
                }
                let d1 = [l.xy[0] - u[0], l.xy[1] - u[1]];
                let d2 = [w[0] - l.xy[0], w[1] - l.xy[1]];
                let turn = (d1[0] * d2[1] - d1[1] * d2[0]).atan2(d1[0] * d2[0] + d1[1] * d2[1]);
                self.turning += turn;
                Ok(())
            }
            (i, o) => Err(invalid(format!(
                "vertex {v} has {} incoming and {} outgoing boundary edges: the mesh is not one \
                 piece without holes",
                i.len(),
                o.len()
            ))),
        }
    }

    /// The end of the stream: the vertices still live are done, then the global counts.
    ///
    /// # Errors
    /// [`Error::Invalid`] for a mesh that is not one convex piece.
    pub fn finish(mut self) -> Result<StreamReport> {
        let mut rest: Vec<u64> = self.live.keys().copied().collect();
        rest.sort_unstable();
        for v in rest {
            self.done(v)?;
        }
        self.report.vertices = self.used_vertices;
        if self.check.convex_hull && self.report.triangles > 0 {
            // V − E + T = 1 for one disk.
            let chi = self.report.vertices as i64 - self.report.edges as i64
                + self.report.triangles as i64;
            if chi != 1 {
                return Err(invalid(format!(
                    "Euler's count V - E + T is {chi}, not 1 ({} vertices, {} edges, {} \
                     triangles): the mesh is not one piece without holes",
                    self.report.vertices, self.report.edges, self.report.triangles
                )));
            }
            let turns = self.turning / std::f64::consts::TAU;
            if (turns - 1.0).abs() > 1e-6 * (1.0 + self.report.hull_vertices as f64) {
                return Err(invalid(format!(
                    "the boundary turns {turns:.6} times around, not once: it is not the convex \
                     hull"
                )));
            }
        }
        Ok(StreamReport {
            report: self.report,
            peak_live_vertices: self.peak_live as u64,
            peak_pending_edges: self.peak_edges as u64,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feeds a mesh in the order a `.stin` would: vertices, triangles, no done records (the end
    /// finishes every vertex).
    fn check(vertices: &[[f64; 3]], triangles: &[[u64; 3]], check: StreamCheck) -> Result<Report> {
        let mut c = StreamChecker::new(check);
        for v in vertices {
            c.vertex(*v)?;
        }
        for t in triangles {
            c.triangle(*t, t.map(|i| vertices[i as usize]))?;
        }
        c.finish().map(|r| r.report)
    }

    #[test]
    fn a_square_passes_and_broken_ones_are_named() {
        let all = StreamCheck::default();
        let sq = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.4, 1.0],
        ];
        let good = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        let r = check(&sq, &good, all).unwrap();
        assert_eq!((r.vertices, r.triangles), (5, 4));
        assert_eq!((r.edges, r.hull_vertices), (8, 4));
        let e = check(&sq, &[[0, 4, 1], [1, 2, 4], [2, 3, 4], [3, 0, 4]], all).unwrap_err();
        assert!(e.to_string().contains("counter-clockwise"), "{e}");
        // A notch: the boundary turns right.
        let notch = [[0, 1, 4], [1, 2, 4], [2, 3, 4]];
        let e = check(&sq, &notch, all).unwrap_err();
        assert!(e.to_string().contains("turns right"), "{e}");
        let trimmed = StreamCheck {
            convex_hull: false,
            ..all
        };
        check(&sq, &notch, trimmed).unwrap();
        // Not Delaunay: the long diagonal of a thin rhombus.
        let rh = [
            [0.0, 0.0, 0.0],
            [2.0, -0.2, 0.0],
            [4.0, 0.0, 0.0],
            [2.0, 0.2, 0.0],
        ];
        let e = check(&rh, &[[0, 1, 2], [0, 2, 3]], all).unwrap_err();
        assert!(e.to_string().contains("locally Delaunay"), "{e}");
        check(&rh, &[[0, 1, 3], [1, 2, 3]], all).unwrap();
        // An unused vertex; two triangles on one directed edge.
        let mut extra = sq.to_vec();
        extra.push([9.0, 9.0, 0.0]);
        let e = check(&extra, &good, all).unwrap_err();
        assert!(e.to_string().contains("used by no triangle"), "{e}");
        let e = check(&sq, &[[0, 1, 4], [0, 1, 2]], all).unwrap_err();
        assert!(e.to_string().contains("same direction"), "{e}");
    }
}
