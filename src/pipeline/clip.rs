//! `--clip-breaklines`: the lines cut to the convex hull of the points, which a points-only
//! pass gives as a triangle stream (moved out of `lines.rs`, unchanged).

use super::TriangleSink;
use super::lines::ClipSummary;
use crate::breaklines::Lines;
use crate::error::Result;
use crate::geom::predicates::{Orientation, orient};
use crate::sink::ProductSummary;

/// The convex hull of the points, from the triangle stream of a points-only pass: triangle
/// corners are gathered and reduced to their hull whenever [`HullSink::BATCH`] have piled up,
/// so memory stays bounded.
#[derive(Default)]
pub(super) struct HullSink {
    buffer: Vec<[f64; 3]>,
}

impl HullSink {
    const BATCH: usize = 1 << 21;

    fn reduce(&mut self) {
        let h = crate::tiles::hull::hull(&mut self.buffer);
        self.buffer = h;
    }

    /// The hull's corners, counter-clockwise.
    pub(super) fn finish_hull(mut self) -> Vec<[f64; 2]> {
        self.reduce();
        self.buffer.iter().map(|p| [p[0], p[1]]).collect()
    }
}

impl TriangleSink for HullSink {
    fn begin(&mut self, _info: &super::StreamInfo) -> Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        self.buffer.extend_from_slice(t);
        if self.buffer.len() >= Self::BATCH {
            self.reduce();
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        Ok(ProductSummary::None)
    }
}

/// Is `q` inside or on the convex polygon `hull` (counter-clockwise), decided exactly?
fn in_hull(hull: &[[f64; 2]], q: [f64; 2]) -> bool {
    let n = hull.len();
    n >= 3 && (0..n).all(|i| orient(hull[i], hull[(i + 1) % n], q) != Orientation::Clockwise)
}

/// The point at `t` of segment `a → b` (z interpolated; NaN stays NaN).
fn along(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    if t <= 0.0 {
        return a;
    }
    if t >= 1.0 {
        return b;
    }
    [
        a[0] + t * (b[0] - a[0]),
        a[1] + t * (b[1] - a[1]),
        a[2] + t * (b[2] - a[2]),
    ]
}

/// The part of segment `a → b` inside the convex `hull`, as parameters `[t0, t1]`, with both
/// ends checked inside exactly (a computed crossing that rounds outside is moved towards the
/// inside by bisection). `None` when no part is inside.
fn clip_segment(hull: &[[f64; 2]], a: [f64; 3], b: [f64; 3]) -> Option<(f64, f64)> {
    let inside = |t: f64| {
        let p = along(a, b, t);
        in_hull(hull, [p[0], p[1]])
    };
    let (ia, ib) = (inside(0.0), inside(1.0));
    if ia && ib {
        return Some((0.0, 1.0));
    }
    // Cyrus–Beck in floating point for the interval.
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let n = hull.len();
    let d = [b[0] - a[0], b[1] - a[1]];
    for i in 0..n {
        let (p, q) = (hull[i], hull[(i + 1) % n]);
        let e = [q[0] - p[0], q[1] - p[1]];
        // Signed (left = inside) distances, scaled.
        let fa = e[0] * (a[1] - p[1]) - e[1] * (a[0] - p[0]);
        let fd = e[0] * d[1] - e[1] * d[0];
        if fd == 0.0 {
            if fa < 0.0 {
                return None;
            }
            continue;
        }
        let t = -fa / fd;
        if fd > 0.0 {
            t0 = t0.max(t);
        } else {
            t1 = t1.min(t);
        }
    }
    if t0 > t1 {
        return None;
    }
    // A point known inside, to bisect towards.
    let mid = if ia {
        0.0
    } else if ib {
        1.0
    } else {
        let m = 0.5 * (t0 + t1);
        if !inside(m) {
            return None;
        }
        m
    };
    let settle = |t: f64| {
        if inside(t) {
            return t;
        }
        let (mut out, mut inn) = (t, mid);
        for _ in 0..64 {
            let m = 0.5 * (out + inn);
            if m == out || m == inn {
                break;
            }
            if inside(m) {
                inn = m;
            } else {
                out = m;
            }
        }
        inn
    };
    let s0 = if ia { 0.0 } else { settle(t0) };
    let s1 = if ib { 1.0 } else { settle(t1) };
    (s0 < s1).then_some((s0, s1))
}

/// Cuts every polyline to the convex `hull` (see [`LineOptions::clip`]): the parts inside are
/// kept as separate polylines (a line that leaves and comes back becomes two), with their
/// sources; what was cut is summed.
pub(super) fn clip(lines: &Lines, hull: &[[f64; 2]]) -> (Lines, ClipSummary) {
    let mut out = Lines {
        crs: lines.crs.clone(),
        ..Lines::default()
    };
    let mut s = ClipSummary {
        lines: lines.len() as u64,
        ..ClipSummary::default()
    };
    let len = |a: [f64; 3], b: [f64; 3]| (b[0] - a[0]).hypot(b[1] - a[1]);
    for (line, source) in lines.polylines.iter().zip(&lines.sources) {
        let mut pieces: Vec<Vec<[f64; 3]>> = Vec::new();
        let mut open = false;
        let (mut total, mut kept) = (0.0, 0.0);
        for w in line.windows(2) {
            let (a, b) = (w[0], w[1]);
            let l = len(a, b);
            total += l;
            let Some((t0, t1)) = clip_segment(hull, a, b) else {
                open = false;
                continue;
            };
            let (p, q) = (along(a, b, t0), along(a, b, t1));
            kept += len(p, q);
            if !(open && t0 == 0.0) {
                pieces.push(vec![p]);
            }
            if let Some(piece) = pieces.last_mut() {
                piece.push(q);
            }
            open = t1 == 1.0;
        }
        s.length += total;
        let cut = (total - kept).max(0.0);
        s.length_cut += cut;
        if pieces.is_empty() {
            s.lines_dropped += 1;
            continue;
        }
        if pieces.len() > 1 || pieces[0].len() != line.len() {
            s.lines_cut += 1;
        }
        for piece in pieces {
            out.polylines.push(piece);
            out.sources.push(source.clone());
        }
    }
    (out, s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_to_a_convex_hull() {
        let hull = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        let src = crate::breaklines::Source {
            path: std::sync::Arc::from(std::path::Path::new("l.geojson")),
            location: crate::breaklines::Location::Line(1),
        };
        let lines = Lines {
            polylines: vec![
                // Crosses the square, leaves and comes back: two pieces.
                vec![
                    [-5.0, 5.0, 0.0],
                    [5.0, 5.0, 10.0],
                    [5.0, 15.0, 20.0],
                    [8.0, 5.0, f64::NAN],
                ],
                // Wholly inside.
                vec![[1.0, 1.0, f64::NAN], [2.0, 2.0, f64::NAN]],
                // Wholly outside.
                vec![[20.0, 20.0, 1.0], [30.0, 20.0, 1.0]],
            ],
            sources: vec![src.clone(), src.clone(), src],
            crs: None,
        };
        let (out, s) = clip(&lines, &hull);
        assert_eq!((s.lines, s.lines_cut, s.lines_dropped), (3, 1, 1));
        assert_eq!(out.polylines.len(), 3);
        assert_eq!(
            out.polylines[0],
            vec![[0.0, 5.0, 5.0], [5.0, 5.0, 10.0], [5.0, 10.0, 15.0]]
        );
        assert_eq!(out.polylines[1][1][..2], [8.0, 5.0]);
        assert!(
            out.polylines
                .iter()
                .flatten()
                .all(|p| in_hull(&hull, [p[0], p[1]]))
        );
        let xy = |l: &Vec<[f64; 3]>| l.iter().map(|p| [p[0], p[1]]).collect::<Vec<_>>();
        assert_eq!(xy(&out.polylines[2]), xy(&lines.polylines[1]));
        let want = 5.0 + 5.0 + 1.5f64.hypot(5.0) + 10.0;
        assert!((s.length_cut - want).abs() < 1e-9, "{s:?}");
        // A crossing that rounds outside is moved in.
        let tri = [[0.0, 0.0], [3.0, 0.1], [0.1, 3.0]];
        let (t0, t1) = clip_segment(&tri, [-1.0, 0.7, 0.0], [5.0, 0.9, 0.0]).unwrap();
        for t in [t0, t1] {
            let p = along([-1.0, 0.7, 0.0], [5.0, 0.9, 0.0], t);
            assert!(in_hull(&tri, [p[0], p[1]]));
        }
    }
}
