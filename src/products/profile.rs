//! The profile of the TIN along polylines: a 3D polyline with a vertex at every triangle edge the
//! line crosses, plus chainage.
//!
//! For every line segment `p → q` and every triangle, the sink records (exactly, through
//! `geom::predicates::orient`):
//! - where the segment properly crosses a triangle edge — the point computed from the edge and the
//!   segment alone, so the two triangles sharing the edge record the same bits;
//! - where the segment passes exactly through a TIN vertex (the vertex itself, its `z`);
//! - the polyline's own vertices, with their height (empty when outside the TIN).
//!
//! Points are sorted along each line and de-duplicated. Two crossings can round to the same point
//! with heights that differ in the last bits (a line passing within rounding of a TIN vertex
//! crosses two of its edges there): the lowest height is kept, so the file does not depend on
//! the order the triangles came in (a tiled run's differs from the sweep's). Between two
//! consecutive points the line runs inside one triangle, so the profile is exactly the TIN's
//! section. **Chainage** is the horizontal distance along the line from its start.
//!
//! The output CSV has the columns `line,chainage,x,y,z`; `z` is empty at polyline vertices outside
//! the TIN. Memory is proportional to the output (the lines and the points found).

use super::geom::{Location, Tri, cmp_xy};
use crate::error::{Error, Result};
use crate::geom::predicates::{Orientation, orient};
use crate::output::AtomicFile;
use crate::sink::{ProductSummary, ProfileSummary, StreamInfo, TriangleSink};
use std::collections::HashMap;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A point of the profile: line, segment, parameter along the segment, position and height.
#[derive(Clone, Copy, Debug)]
struct Hit {
    line: u32,
    seg: u32,
    t: f64,
    xy: [f64; 2],
    z: f64,
}

/// A segment of a line.
#[derive(Clone, Copy, Debug)]
struct Seg {
    line: u32,
    seg: u32,
    p: [f64; 2],
    q: [f64; 2],
}

/// A [`TriangleSink`] computing profiles along polylines (see the module docs).
pub struct ProfileSink {
    output: PathBuf,
    lines: Vec<Vec<[f64; 2]>>,
    segs: Vec<Seg>,
    /// Segment ids by grid cell.
    grid: HashMap<(i64, i64), Vec<u32>>,
    cell: f64,
    origin: [f64; 2],
    hits: Vec<Hit>,
    /// Heights of the polyline vertices (NaN until answered).
    vertex_z: Vec<Vec<f64>>,
    scratch: Vec<u32>,
}

fn param(p: [f64; 2], q: [f64; 2], v: [f64; 2]) -> f64 {
    let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
    ((v[0] - p[0]) * dx + (v[1] - p[1]) * dy) / (dx * dx + dy * dy)
}

impl ProfileSink {
    /// Profiles along `lines` (each at least two points), written to `output` at the end.
    ///
    /// # Errors
    /// [`Error::Output`] if a line has fewer than two points or a non-finite coordinate.
    pub fn new(mut lines: Vec<Vec<[f64; 2]>>, output: &Path) -> Result<ProfileSink> {
        let bad = |message: String| Error::Output {
            path: output.to_path_buf(),
            message,
        };
        // A repeated vertex (common in digitised lines) is one vertex: the first of a line
        // got no height when its segment had no length.
        for l in lines.iter_mut() {
            l.dedup();
        }
        if let Some(li) = lines.iter().position(|l| l.len() == 1) {
            return Err(bad(format!(
                "line {li} has no length (all its points are one point): `sweeptin sample` gives \
                 the height at a point"
            )));
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut segs = Vec::new();
        for (li, l) in lines.iter().enumerate() {
            if l.len() < 2 || !l.iter().flatten().all(|c| c.is_finite()) {
                return Err(bad(format!(
                    "line {li} needs two or more points with finite coordinates"
                )));
            }
            for p in l {
                for a in 0..2 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            for (si, w) in l.windows(2).enumerate() {
                if w[0] != w[1] {
                    segs.push(Seg {
                        line: li as u32,
                        seg: si as u32,
                        p: w[0],
                        q: w[1],
                    });
                }
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let cell = if extent > 0.0 { extent / 512.0 } else { 1.0 };
        let mut sink = ProfileSink {
            output: output.to_path_buf(),
            vertex_z: lines.iter().map(|l| vec![f64::NAN; l.len()]).collect(),
            lines,
            segs,
            grid: HashMap::new(),
            cell,
            origin: lo,
            hits: Vec::new(),
            scratch: Vec::new(),
        };
        sink.index();
        Ok(sink)
    }

    fn key(&self, p: [f64; 2]) -> (i64, i64) {
        (
            ((p[0] - self.origin[0]) / self.cell).floor() as i64,
            ((p[1] - self.origin[1]) / self.cell).floor() as i64,
        )
    }

    /// Files every segment under the grid cells it passes through (sampled at a quarter cell,
    /// with the neighbouring cells, which over-covers safely).
    fn index(&mut self) {
        for (i, s) in self.segs.iter().enumerate() {
            let len = (s.q[0] - s.p[0]).hypot(s.q[1] - s.p[1]);
            let steps = ((len / (self.cell / 4.0)).ceil() as usize).max(1);
            let mut cells = Vec::new();
            for k in 0..=steps {
                let t = k as f64 / steps as f64;
                let p = [
                    s.p[0] + t * (s.q[0] - s.p[0]),
                    s.p[1] + t * (s.q[1] - s.p[1]),
                ];
                let (cx, cy) = self.key(p);
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        cells.push((cx + dx, cy + dy));
                    }
                }
            }
            cells.sort_unstable();
            cells.dedup();
            for c in cells {
                self.grid.entry(c).or_default().push(i as u32);
            }
        }
    }

    fn cross(&mut self, s: &Seg, t: &Tri) {
        let xy = |v: &[f64; 3]| [v[0], v[1]];
        let o: Vec<Orientation> = t.v.iter().map(|v| orient(s.p, s.q, xy(v))).collect();
        for k in 0..3 {
            // The segment passes through vertex k.
            if o[k] == Orientation::Collinear {
                let v = xy(&t.v[k]);
                let u = param(s.p, s.q, v);
                if u > 0.0 && u < 1.0 {
                    self.hits.push(Hit {
                        line: s.line,
                        seg: s.seg,
                        t: u,
                        xy: v,
                        z: t.v[k][2],
                    });
                }
            }
            // The segment properly crosses edge k.
            let (a, b) = (&t.v[k], &t.v[(k + 1) % 3]);
            let opposite = |x: Orientation, y: Orientation| {
                x != Orientation::Collinear && y != Orientation::Collinear && x != y
            };
            if !opposite(o[k], o[(k + 1) % 3]) {
                continue;
            }
            if !opposite(orient(xy(a), xy(b), s.p), orient(xy(a), xy(b), s.q)) {
                continue;
            }
            let (a, b) = if cmp_xy(a, b).is_gt() { (b, a) } else { (a, b) };
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let (dx, dy) = (s.q[0] - s.p[0], s.q[1] - s.p[1]);
            let e = ((s.p[0] - a[0]) * dy - (s.p[1] - a[1]) * dx) / (ex * dy - ey * dx);
            let e = e.clamp(0.0, 1.0);
            let point = [a[0] + e * ex, a[1] + e * ey];
            self.hits.push(Hit {
                line: s.line,
                seg: s.seg,
                t: param(s.p, s.q, point).clamp(0.0, 1.0),
                xy: point,
                z: a[2] + e * (b[2] - a[2]),
            });
        }
    }

    fn write(&mut self) -> Result<u64> {
        // Polyline vertices: segment i at t = 0, and the last one at the end of the last segment.
        for (li, l) in self.lines.iter().enumerate() {
            for (vi, p) in l.iter().enumerate() {
                let (seg, t) = if vi + 1 == l.len() {
                    (vi as u32 - 1, 1.0)
                } else {
                    (vi as u32, 0.0)
                };
                self.hits.push(Hit {
                    line: li as u32,
                    seg,
                    t,
                    xy: *p,
                    z: self.vertex_z[li][vi],
                });
            }
        }
        self.hits.sort_by(|a, b| {
            (a.line, a.seg)
                .cmp(&(b.line, b.seg))
                .then(a.t.total_cmp(&b.t))
                .then(a.xy[0].total_cmp(&b.xy[0]))
                .then(a.xy[1].total_cmp(&b.xy[1]))
                .then(a.z.total_cmp(&b.z))
        });
        self.hits.dedup_by(|b, a| a.line == b.line && a.xy == b.xy);
        let mut out = AtomicFile::create(&self.output)?;
        let mut w = BufWriter::with_capacity(1 << 16, &mut out);
        let io = |e| Error::write(&self.output, e);
        writeln!(w, "line,chainage,x,y,z").map_err(io)?;
        let mut chain = Vec::new();
        for l in &self.lines {
            let mut c = vec![0.0];
            for wd in l.windows(2) {
                let last = *c.last().expect("starts with 0");
                c.push(last + (wd[1][0] - wd[0][0]).hypot(wd[1][1] - wd[0][1]));
            }
            chain.push(c);
        }
        for h in &self.hits {
            let c = &chain[h.line as usize];
            let s = h.seg as usize;
            let chainage = c[s] + h.t * (c[s + 1] - c[s]);
            let z = if h.z.is_nan() {
                String::new()
            } else {
                h.z.to_string()
            };
            writeln!(w, "{},{chainage},{},{},{z}", h.line, h.xy[0], h.xy[1]).map_err(io)?;
        }
        w.flush().map_err(io)?;
        drop(w);
        out.commit()
    }
}

impl TriangleSink for ProfileSink {
    fn begin(&mut self, _info: &StreamInfo) -> Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        let bb = t.bbox();
        let (k0, k1) = (self.key([bb[0], bb[1]]), self.key([bb[2], bb[3]]));
        let mut ids = std::mem::take(&mut self.scratch);
        ids.clear();
        for ky in k0.1..=k1.1 {
            for kx in k0.0..=k1.0 {
                if let Some(v) = self.grid.get(&(kx, ky)) {
                    ids.extend_from_slice(v);
                }
            }
        }
        ids.sort_unstable();
        ids.dedup();
        for &i in &ids {
            let s = self.segs[i as usize];
            let sb = [
                s.p[0].min(s.q[0]),
                s.p[1].min(s.q[1]),
                s.p[0].max(s.q[0]),
                s.p[1].max(s.q[1]),
            ];
            if sb[0] > bb[2] || sb[2] < bb[0] || sb[1] > bb[3] || sb[3] < bb[1] {
                continue;
            }
            self.cross(&s, &t);
            // The segment's end points are polyline vertices.
            for (vi, p) in [(s.seg as usize, s.p), (s.seg as usize + 1, s.q)] {
                let z = &mut self.vertex_z[s.line as usize][vi];
                if z.is_nan() {
                    let loc = t.locate(p);
                    if loc != Location::Outside {
                        *z = t.value_at(p, loc);
                    }
                }
            }
        }
        self.scratch = ids;
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        let bytes = self.write()?;
        let inside = self
            .vertex_z
            .iter()
            .flatten()
            .filter(|z| !z.is_nan())
            .count();
        Ok(ProductSummary::Profile(ProfileSummary {
            path: self.output.clone(),
            lines: self.lines.len() as u64,
            points: self.hits.len() as u64,
            line_vertices_inside: inside as u64,
            bytes,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::products::testutil::{
        Step, feed, grid_tin, in_sweep_order, random_tin, shuffled_with_watermarks,
    };

    fn run(lines: Vec<Vec<[f64; 2]>>, steps: &[Step]) -> String {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("p.csv");
        let mut sink = ProfileSink::new(lines, &out).unwrap();
        let info = StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 100.0, 100.0],
        };
        feed(&mut sink, &info, steps);
        std::fs::read_to_string(&out).unwrap()
    }

    fn rows(text: &str) -> Vec<Vec<String>> {
        text.lines()
            .skip(1)
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    }

    /// On a regular grid, a horizontal line at y = 0.5 crosses every vertical and diagonal edge;
    /// on a plane every point has the plane's height; shuffled gives the same file.
    #[test]
    fn crossings_on_a_grid_and_plane_heights() {
        let f = |x: f64, y: f64| 2.0 * x + y;
        let tris = grid_tin(4, 2, 1.0, f);
        let line = vec![vec![[-1.0, 0.5], [4.5, 0.5]]];
        let a = run(line.clone(), &in_sweep_order(&tris));
        let b = run(line, &shuffled_with_watermarks(&tris, 1));
        assert_eq!(a, b);
        let r = rows(&a);
        // Start (outside), verticals x = 0..4 and diagonals x = 0.5..3.5 (9 crossings), end.
        assert_eq!(r.len(), 11, "{a}");
        assert_eq!(r[0][4], "");
        assert_eq!(r[10][4], "");
        for row in &r[1..10] {
            let (x, y, z): (f64, f64, f64) = (
                row[2].parse().unwrap(),
                row[3].parse().unwrap(),
                row[4].parse().unwrap(),
            );
            assert_eq!(y, 0.5);
            assert!((z - f(x, y)).abs() < 1e-12, "{row:?}");
            let chainage: f64 = row[1].parse().unwrap();
            assert!((chainage - (x + 1.0)).abs() < 1e-12);
        }
    }

    /// A line through grid vertices exactly (the diagonal y = x runs along no edge here, the
    /// anti-diagonal does): vertices are hit once each, with their own height.
    #[test]
    fn through_vertices_and_along_edges() {
        let f = |x: f64, y: f64| x * y;
        let tris = grid_tin(3, 3, 1.0, f);
        let r = rows(&run(
            vec![vec![[0.0, 3.0], [3.0, 0.0]], vec![[0.0, 0.0], [3.0, 3.0]]],
            &in_sweep_order(&tris),
        ));
        let line0: Vec<&Vec<String>> = r.iter().filter(|x| x[0] == "0").collect();
        // Along the anti-diagonal: the 4 grid vertices only.
        assert_eq!(line0.len(), 4, "{r:?}");
        let line1: Vec<&Vec<String>> = r.iter().filter(|x| x[0] == "1").collect();
        // Across the squares: 4 vertices + 3 crossings of anti-diagonal edges.
        assert_eq!(line1.len(), 7, "{r:?}");
        for row in r {
            let (x, y, z): (f64, f64, f64) = (
                row[2].parse().unwrap(),
                row[3].parse().unwrap(),
                row[4].parse().unwrap(),
            );
            if x.fract() == 0.0 && y.fract() == 0.0 {
                assert_eq!(z, x * y);
            }
        }
    }

    /// A line passing within rounding of vertex `v` crosses its edges `a v` and `v b` at the
    /// same point with heights that differ in the last bits; the file is the same whichever of
    /// the triangles on the two edges comes first (it was not: a tiled ARSO profile differed from
    /// the sweep's in one row).
    #[test]
    fn a_near_vertex_crossing_does_not_depend_on_the_order() {
        let (a, b, v) = ([0.0, -1.0, 2.9], [2.0, -1.0, 0.7], [1.0, 1e-300, 0.3]);
        let (c, d) = ([0.0, 1.0, 0.0], [2.0, 1.0, 0.0]);
        let (t0, t1, t2, t3) = ([a, v, c], [a, b, v], [v, b, d], [v, d, c]);
        let line = vec![vec![[0.5, 0.0], [1.5, 0.0]]];
        let x = run(line.clone(), &[t0, t1, t2, t3].map(|t| (t, None)));
        let y = run(line, &[t2, t1, t0, t3].map(|t| (t, None)));
        assert_eq!(x, y);
        // The two edges' heights at the crossing do differ (else this test shows nothing).
        assert_ne!(a[2] + (v[2] - a[2]), v[2]);
    }

    #[test]
    fn random_tin_profile_is_linear_between_points() {
        let f = |x: f64, y: f64| (x / 10.0).sin() * 5.0 + y / 20.0;
        let tris = random_tin(500, 100.0, 4, f);
        let line = vec![vec![[5.0, 5.0], [95.0, 40.0], [20.0, 90.0]]];
        let a = run(line.clone(), &in_sweep_order(&tris));
        assert_eq!(a, run(line, &shuffled_with_watermarks(&tris, 3)));
        let r = rows(&a);
        assert!(r.len() > 40);
        let mut last = -1.0;
        for row in &r {
            let c: f64 = row[1].parse().unwrap();
            assert!(c >= last);
            last = c;
            assert!(!row[4].is_empty());
        }
    }
}
