//! The writer thread's end of the pipeline: final triangles to the mesh writer and the triangle
//! sinks, in real-world coordinates, trimmed, with vertices written lazily when trimming can leave
//! some unused; and the `--no-flat-triangles` pass, which needs the whole triangulation.

use super::lines::LINE_FLAG;
use super::{Frame, TriangleSink};
use crate::breaklines::Trim;
use crate::breaklines::flat::{FlatStats, remove_flat_triangles};
use crate::error::Result;
use crate::finalise::Event;
use crate::geom::predicates::{Orientation, orient};
use crate::idmap::IdMap;
use crate::sink::MeshSink;
use std::collections::HashMap;

/// Not written (yet).
const NOT_OUT: u64 = u64::MAX;

/// Do triangles going to `sinks` (some or none) through `trim` need their corners' positions?
pub(super) fn corners_needed(sinks: bool, trim: Option<&Trim>) -> bool {
    sinks || trim.is_some_and(|t| !t.keeps_all())
}

/// Delivers events to the outputs (see the module docs).
pub(crate) struct Emitter<'m, 's, 't> {
    frame: Frame,
    mesh: Option<&'m mut (dyn MeshSink + Send)>,
    sinks: &'s mut [&'t mut dyn TriangleSink],
    /// `None`: every triangle is kept, and vertices are written as they come.
    trim: Option<&'s Trim>,
    /// Output number of each live vertex (by sweep number), kept only when trimming can leave
    /// vertices unused and the output numbers them as they are first used.
    live: IdMap<u64>,
    /// The next triangle's corners ([`Event::Corner`]), in real-world coordinates, and how many
    /// have come.
    corners: [[f64; 3]; 3],
    n_corners: usize,
    next_in: u64,
    next_out: u64,
    triangles: u64,
    trimmed: u64,
}

impl<'m, 's, 't> Emitter<'m, 's, 't> {
    pub(super) fn new(
        frame: Frame,
        mesh: Option<&'m mut (dyn MeshSink + Send)>,
        sinks: &'s mut [&'t mut dyn TriangleSink],
        trim: Option<&'s Trim>,
    ) -> Self {
        let trim = trim.filter(|t| !t.keeps_all());
        Emitter {
            frame,
            mesh,
            sinks,
            trim,
            live: IdMap::default(),
            corners: [[0.0; 3]; 3],
            n_corners: 0,
            next_in: 0,
            next_out: 0,
            triangles: 0,
            trimmed: 0,
        }
    }

    /// Do the triangles need their corners' positions (for the sinks or the trimming)? The
    /// sweep then sends them before each triangle ([`crate::finalise::StreamConfig::corners`]).
    pub(super) fn needs_corners(&self) -> bool {
        corners_needed(!self.sinks.is_empty(), self.trim)
    }

    /// Vertices and triangles written, triangles trimmed.
    pub(super) fn counts(&self) -> (u64, u64, u64) {
        (self.next_out, self.triangles, self.trimmed)
    }

    /// One event of the sweep (the sweep's frame).
    pub(super) fn event(&mut self, ev: Event) -> Result<()> {
        match ev {
            Event::Vertex { xy, z, .. } => self.vertex(self.frame.world(xy, z)),
            Event::Corner { xy, z } => {
                let k = self.n_corners.min(2);
                self.corners[k] = self.frame.world(xy, z);
                self.n_corners += 1;
                Ok(())
            }
            // A sweep along x works on the mirror image: counter-clockwise there is clockwise here.
            Event::Triangle(t) if self.frame.swap => {
                let [a, b, c] = self.corners;
                self.corners = [a, c, b];
                self.triangle([t[0], t[2], t[1]])
            }
            Event::Triangle(t) => self.triangle(t),
            Event::VertexDone(i) => self.vertex_done(i),
            // Watermarks are heights (world y); a sweep along x has none to give.
            Event::Watermark(_) if self.frame.swap => Ok(()),
            Event::Watermark(y) => {
                if let Some(m) = self.mesh.as_mut() {
                    m.watermark(y)?;
                }
                for s in self.sinks.iter_mut() {
                    s.watermark(y)?;
                }
                Ok(())
            }
        }
    }

    fn vertex(&mut self, w: [f64; 3]) -> Result<()> {
        let id = self.next_in;
        self.next_in += 1;
        if self.trim.is_some() {
            // Written when a kept triangle first uses it.
            self.live.insert(id, NOT_OUT);
            return Ok(());
        }
        if let Some(m) = self.mesh.as_mut() {
            m.vertex(w)?;
        }
        self.next_out += 1;
        Ok(())
    }

    fn triangle(&mut self, t: [u64; 3]) -> Result<()> {
        if !self.needs_corners() {
            if let Some(m) = self.mesh.as_mut() {
                m.triangle(t)?;
            }
            self.triangles += 1;
            return Ok(());
        }
        if self.n_corners != 3 {
            return Err(crate::error::Error::Internal(format!(
                "triangle {t:?} came with {} corners, not 3",
                self.n_corners
            )));
        }
        self.n_corners = 0;
        let p = self.corners;
        if let Some(trim) = self.trim {
            if !trim.keep(&p) {
                self.trimmed += 1;
                return Ok(());
            }
            let mut out = [0u64; 3];
            for k in 0..3 {
                let e = self.live.get_mut(&t[k]).expect("live vertex");
                if *e == NOT_OUT {
                    if let Some(m) = self.mesh.as_mut() {
                        m.vertex(p[k])?;
                    }
                    *e = self.next_out;
                    self.next_out += 1;
                }
                out[k] = *e;
            }
            if let Some(m) = self.mesh.as_mut() {
                m.triangle(out)?;
            }
        } else if let Some(m) = self.mesh.as_mut() {
            m.triangle(t)?;
        }
        for s in self.sinks.iter_mut() {
            s.triangle(&p)?;
        }
        self.triangles += 1;
        Ok(())
    }

    fn vertex_done(&mut self, i: u64) -> Result<()> {
        let out = if self.trim.is_some() {
            self.live.remove(&i).unwrap_or(NOT_OUT)
        } else {
            i
        };
        if out != NOT_OUT
            && let Some(m) = self.mesh.as_mut()
        {
            m.vertex_done(out)?;
        }
        Ok(())
    }
}

/// Vertex adjacency in compressed rows: `(start, neighbours)`.
type Adjacency = (Vec<u32>, Vec<u32>);

/// The whole triangulation, held for `--no-flat-triangles`.
#[derive(Default)]
pub(crate) struct Collected {
    vertices: Vec<[f64; 3]>,
    /// Graph vertex id of each vertex, or `u32::MAX`.
    line_vertex: Vec<u32>,
    triangles: Vec<[u32; 3]>,
}

impl Collected {
    /// Records one event (watermarks and vertex releases are dropped: everything is held).
    pub(super) fn event(&mut self, ev: Event) {
        match ev {
            Event::Vertex { xy, z, index } => {
                self.vertices.push([xy[0], xy[1], z]);
                self.line_vertex.push(if index & LINE_FLAG != 0 {
                    (index & !LINE_FLAG) as u32
                } else {
                    u32::MAX
                });
            }
            Event::Triangle(t) => self.triangles.push(t.map(|i| i as u32)),
            Event::Corner { .. } | Event::VertexDone(_) | Event::Watermark(_) => {}
        }
    }

    /// Flips flat triangles away (`segments` and `lines`: the breakline graph), then replays the
    /// result into `emit`.
    pub(super) fn finish(
        mut self,
        segments: &[[u32; 2]],
        lines: &[u32],
        emit: &mut Emitter,
    ) -> Result<FlatStats> {
        let mut vertex_of = HashMap::new();
        for (v, &c) in self.line_vertex.iter().enumerate() {
            if c != u32::MAX {
                vertex_of.insert(c, v as u32);
            }
        }
        let adj = self.adjacency();
        let mut cons = Vec::with_capacity(segments.len());
        let mut cons_lines = Vec::with_capacity(segments.len());
        for (s, &l) in segments.iter().zip(lines) {
            if let (Some(&a), Some(&b)) = (vertex_of.get(&s[0]), vertex_of.get(&s[1])) {
                for piece in self.pieces(&adj, a, b) {
                    cons.push(piece);
                    cons_lines.push(l);
                }
            }
        }
        let stats = remove_flat_triangles(&self.vertices, &mut self.triangles, &cons, &cons_lines);
        for v in &self.vertices {
            emit.event(Event::Vertex {
                xy: [v[0], v[1]],
                z: v[2],
                index: 0,
            })?;
        }
        for t in &self.triangles {
            if emit.needs_corners() {
                for &v in t {
                    let [x, y, z] = self.vertices[v as usize];
                    emit.event(Event::Corner { xy: [x, y], z })?;
                }
            }
            emit.event(Event::Triangle(t.map(u64::from)))?;
        }
        for i in 0..self.vertices.len() as u64 {
            emit.event(Event::VertexDone(i))?;
        }
        Ok(stats)
    }

    fn adjacency(&self) -> Adjacency {
        let n = self.vertices.len();
        let mut start = vec![0u32; n + 1];
        for t in &self.triangles {
            for &v in t {
                start[v as usize + 1] += 2;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut nb = vec![0u32; start[n] as usize];
        for t in &self.triangles {
            for k in 0..3 {
                let (v, a, b) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let f = &mut fill[v as usize];
                nb[*f as usize] = a;
                nb[*f as usize + 1] = b;
                *f += 2;
            }
        }
        (start, nb)
    }

    /// The mesh edges along the breakline segment `a`–`b` (it may have been split where points lie
    /// exactly on it): from `a`, the neighbour exactly on the segment and further along, until `b`.
    fn pieces(&self, adj: &Adjacency, a: u32, b: u32) -> Vec<[u32; 2]> {
        let xy = |v: u32| {
            let p = self.vertices[v as usize];
            [p[0], p[1]]
        };
        let (pa, pb) = (xy(a), xy(b));
        let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
        // Exact "further along": the segment's dominant axis, compared exactly.
        let along = |v: [f64; 2]| {
            if dx.abs() >= dy.abs() {
                v[0] * dx.signum()
            } else {
                v[1] * dy.signum()
            }
        };
        let mut out = Vec::new();
        let mut cur = a;
        while cur != b {
            let (s, e) = (
                adj.0[cur as usize] as usize,
                adj.0[cur as usize + 1] as usize,
            );
            let here = along(xy(cur));
            let next = adj.1[s..e].iter().copied().find(|&n| {
                let q = xy(n);
                orient(pa, pb, q) == Orientation::Collinear
                    && along(q) > here
                    && along(q) <= along(pb)
            });
            match next {
                Some(n) => {
                    out.push([cur, n]);
                    cur = n;
                }
                None => break,
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::{ProductSummary, StreamInfo};

    #[derive(Default)]
    struct Record(Vec<[[f64; 3]; 3]>);

    impl TriangleSink for Record {
        fn begin(&mut self, _info: &StreamInfo) -> Result<()> {
            Ok(())
        }
        fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
            self.0.push(*t);
            Ok(())
        }
        fn finish(&mut self) -> Result<ProductSummary> {
            Ok(ProductSummary::None)
        }
    }

    /// A sink gets each triangle's corners from the corner events, in the triangle's order
    /// (mirrored for a sweep along x), and the writer keeps no table of live vertices (a ring
    /// of points has nearly all of them live at once).
    #[test]
    fn triangles_take_their_corners_from_the_stream_and_no_vertex_is_held() {
        let pts = [[0.0, 0.0, 5.0], [1.0, 0.0, 6.0], [0.0, 1.0, 7.0]];
        for swap in [false, true] {
            let mut rec = Record::default();
            let mut sinks: [&mut dyn TriangleSink; 1] = [&mut rec];
            let mut emit = Emitter::new(Frame { swap }, None, &mut sinks, None);
            assert!(emit.needs_corners());
            for p in pts {
                let (xy, z) = ([p[0], p[1]], p[2]);
                emit.event(Event::Vertex { xy, z, index: 0 }).unwrap();
            }
            for p in pts {
                emit.event(Event::Corner {
                    xy: [p[0], p[1]],
                    z: p[2],
                })
                .unwrap();
            }
            emit.event(Event::Triangle([0, 1, 2])).unwrap();
            assert!(emit.live.is_empty(), "no vertex map without trimming");
            for i in 0..3 {
                emit.event(Event::VertexDone(i)).unwrap();
            }
            // A triangle without its corners is an internal error, not a wrong cell.
            assert!(emit.event(Event::Triangle([0, 1, 2])).is_err());
            drop(emit);
            let w = |p: [f64; 3]| Frame { swap }.world([p[0], p[1]], p[2]);
            let want = if swap {
                [w(pts[0]), w(pts[2]), w(pts[1])]
            } else {
                pts.map(w)
            };
            assert_eq!(rec.0, vec![want]);
        }
    }
}
