//! Breaklines on gridded coordinates: points and segment endpoints on a small integer grid (or a
//! UTM-offset 1 mm grid), so that segments overlap, cross at grid points, pass through points and
//! run along collinear chains. The segments are cleaned into a planar graph (`breaklines::clean`)
//! and triangulated with the points by the batch CDT; the result must pass the independent CDT
//! validator (every segment made of edges, every other edge locally Delaunay, convex hull,
//! Euler count), and no cleaned segment may be reported as crossing another.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sweeptin::breaklines::{CleanOptions, clean};
use sweeptin::validate::validate_cdt;
use sweeptin::{Options, triangulate_cdt};

fuzz_target!(|data: &[u8]| {
    let [mode, param, rest @ ..] = data else {
        return;
    };
    let side = 2 + u32::from(*param % 13);
    let utm = mode % 2 == 1;
    let at = |a: u8, b: u8| {
        let (x, y) = (f64::from(u32::from(a) % side), f64::from(u32::from(b) % side));
        if utm {
            [500_000.0 + x * 0.001, 4_000_000.0 + y * 0.001]
        } else {
            [x, y]
        }
    };
    // First half: points; second half: segments (4 bytes each).
    let split = rest.len() / 2;
    let mut pts: Vec<[f64; 3]> = rest[..split]
        .chunks_exact(2)
        .enumerate()
        .map(|(i, c)| {
            let p = at(c[0], c[1]);
            [p[0], p[1], i as f64]
        })
        .collect();
    let lines: Vec<Vec<[f64; 3]>> = rest[split..]
        .chunks_exact(4)
        .map(|c| {
            let (a, b) = (at(c[0], c[1]), at(c[2], c[3]));
            vec![[a[0], a[1], 1.0], [b[0], b[1], 2.0]]
        })
        .collect();
    let Ok(g) = clean(&lines, &CleanOptions::default()) else {
        return;
    };
    if let Err(e) = g.check_planar() {
        panic!("cleaned graph not planar: {e}");
    }
    let base = pts.len() as u32;
    pts.extend_from_slice(&g.vertices);
    let segs: Vec<[u32; 2]> = g.segments.iter().map(|s| [s[0] + base, s[1] + base]).collect();
    let Ok(t) = triangulate_cdt(&pts, &segs, &Options::default()) else {
        return; // too few points or all collinear: the core's own fuzz targets check those
    };
    assert_eq!(t.constraint_stats.crossing_skipped, 0, "cleaned segments never cross");
    let coords = g.segment_coords();
    if let Err(e) = validate_cdt(&t.vertices, &t.triangles, &coords) {
        panic!("invalid CDT: {e}");
    }
});
