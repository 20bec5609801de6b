//! Checks of a grid's TIN independent of the simplifier: the triangles rasterised back onto the
//! grid (world coordinates, barycentric interpolation), and the mesh's conformity.

#![allow(dead_code)]

use std::collections::HashMap;
use sweeptin::input::raster::RasterSpec;

/// What the rasterisation found.
#[derive(Debug, Default)]
pub struct Check {
    pub max_error: f64,
    pub uncovered_valid: usize,
    pub covered_missing: usize,
}

/// Rasterises the TIN onto the grid: every valid cell centre inside (or on) a triangle gets the
/// triangle's linear interpolation; vertices count as covered.
pub fn rasterise(
    spec: &RasterSpec,
    h: &[f64],
    vertices: &[[f64; 3]],
    triangles: &[[u64; 3]],
) -> Check {
    let (cols, rows) = (spec.cols as usize, spec.rows as usize);
    let t = spec.transform;
    let det = t[1] * t[5] - t[2] * t[4];
    // World → fractional cell index (centre of cell (c, r) at c + 0.5, r + 0.5).
    let to_cell = |x: f64, y: f64| {
        let (dx, dy) = (x - t[0], y - t[3]);
        (
            (t[5] * dx - t[2] * dy) / det,
            (-t[4] * dx + t[1] * dy) / det,
        )
    };
    let mut covered = vec![false; cols * rows];
    let mut out = Check::default();
    for v in vertices {
        let (c, r) = to_cell(v[0], v[1]);
        covered[(r - 0.5).round() as usize * cols + (c - 0.5).round() as usize] = true;
    }
    for tri in triangles {
        let [a, b, c] = tri.map(|i| vertices[i as usize]);
        let pa = to_cell(a[0], a[1]);
        let pb = to_cell(b[0], b[1]);
        let pc = to_cell(c[0], c[1]);
        let area = (pb.0 - pa.0) * (pc.1 - pa.1) - (pb.1 - pa.1) * (pc.0 - pa.0);
        let lo_c = pa.0.min(pb.0).min(pc.0).floor().max(0.0) as usize;
        let hi_c = (pa.0.max(pb.0).max(pc.0).ceil() as usize).min(cols);
        let lo_r = pa.1.min(pb.1).min(pc.1).floor().max(0.0) as usize;
        let hi_r = (pa.1.max(pb.1).max(pc.1).ceil() as usize).min(rows);
        for r in lo_r..hi_r {
            for col in lo_c..hi_c {
                let (x, y) = (col as f64 + 0.5, r as f64 + 0.5);
                let wa = ((pb.0 - x) * (pc.1 - y) - (pb.1 - y) * (pc.0 - x)) / area;
                let wb = ((pc.0 - x) * (pa.1 - y) - (pc.1 - y) * (pa.0 - x)) / area;
                let wc = 1.0 - wa - wb;
                let eps = 1e-9;
                if wa < -eps || wb < -eps || wc < -eps {
                    continue;
                }
                let i = r * cols + col;
                if h[i].is_nan() {
                    if wa > eps && wb > eps && wc > eps {
                        out.covered_missing += 1;
                    }
                    continue;
                }
                covered[i] = true;
                let z = wa * a[2] + wb * b[2] + wc * c[2];
                out.max_error = out.max_error.max((z - h[i]).abs());
            }
        }
    }
    out.uncovered_valid = (0..cols * rows)
        .filter(|&i| !h[i].is_nan() && !covered[i])
        .count();
    out
}

/// Is the mesh conforming (no vertex inside another triangle's edge)? Every edge has at most
/// two triangles, on opposite sides; returns the edges with one triangle (the boundary).
pub fn boundary_edges(triangles: &[[u64; 3]]) -> Vec<[u64; 2]> {
    let mut seen: HashMap<[u64; 2], (u32, u32)> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let e = seen.entry([a.min(b), a.max(b)]).or_default();
            if a < b {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
        }
    }
    let mut out = Vec::new();
    for (e, (up, down)) in seen {
        assert!(
            up <= 1 && down <= 1,
            "edge {e:?} has {up} + {down} triangles"
        );
        if up + down == 1 {
            out.push(e);
        }
    }
    out.sort_unstable();
    out
}
