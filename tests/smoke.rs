use crate::mesh;

use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use sweeptin::sort::memory::{DuplicatePolicy, prepare};
use sweeptin::sweep::Sweep;
use sweeptin::synth::SplitMix64;
use sweeptin::{Options, triangulate};

fn tri_set(tris: &[[u32; 3]], verts: &[[f64; 3]]) -> Vec<[(u64, u64); 3]> {
    let mut out: Vec<[(u64, u64); 3]> = tris
        .iter()
        .map(|t| {
            let mut k = t.map(|i| {
                (
                    verts[i as usize][0].to_bits(),
                    verts[i as usize][1].to_bits(),
                )
            });
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

fn spade_set(pts: &[[f64; 3]]) -> Vec<[(u64, u64); 3]> {
    let mut d: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    for p in pts {
        d.insert(Point2::new(p[0], p[1])).unwrap();
    }
    mesh::spade_keys(&d)
}

#[test]
fn stepwise_check_small() {
    for seed in 0..300 {
        let mut r = SplitMix64::uniform(seed);
        let n = 3 + (seed as usize % 40);
        let pts: Vec<[f64; 3]> = (0..n).map(|_| [r(), r(), 0.0]).collect();
        let prep = prepare(&pts, DuplicatePolicy::First).unwrap();
        let mut s = Sweep::new(prep.xy).unwrap();
        s.check()
            .unwrap_or_else(|e| panic!("seed {seed} init: {e}"));
        let mut k = 0;
        while s.step().unwrap() {
            k += 1;
            s.check()
                .unwrap_or_else(|e| panic!("seed {seed} step {k}: {e}"));
        }
        let (tris, _, _) = s.finish();
        let t = triangulate(&pts, &Options::default()).unwrap();
        assert_eq!(tris.len(), t.triangles.len());
        assert_eq!(
            tri_set(&t.triangles, &t.vertices),
            spade_set(&pts),
            "seed {seed}"
        );
    }
}

#[test]
fn matches_spade_random() {
    for seed in 0..20 {
        let mut r = SplitMix64::uniform(seed + 1000);
        let n = 20000;
        let pts: Vec<[f64; 3]> = (0..n).map(|_| [r() * 1000.0, r() * 1000.0, 0.0]).collect();
        let t = triangulate(&pts, &Options::default()).unwrap();
        assert_eq!(
            tri_set(&t.triangles, &t.vertices),
            spade_set(&pts),
            "seed {seed}"
        );
    }
}

fn stream_set(
    pts: &[[f64; 3]],
    check: bool,
) -> (Vec<[(u64, u64); 3]>, sweeptin::finalise::StreamStats) {
    use sweeptin::finalise::{Event, StreamConfig, StreamPoint, StreamingSweep};
    let prep = prepare(pts, DuplicatePolicy::First).unwrap();
    let real = &prep.xy[2..];
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in real {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let cfg = StreamConfig {
        x_sample: real.iter().step_by(64).map(|p| p[0]).collect(),
        bounds: [x0, y0, x1, y1],
        expected_points: real.len() as u64,
        spill: None,
        // Every triangle comes with its corners: they must be its vertices' positions.
        corners: true,
    };
    let sp = |i: usize| StreamPoint {
        xy: real[i],
        z: 0.0,
        index: i as u64,
        constraint: u32::MAX,
    };
    let mut s = StreamingSweep::new(sp(0), &cfg);
    let mut events = Vec::new();
    for i in 1..real.len() {
        s.push(sp(i)).unwrap();
        if check {
            s.check().unwrap_or_else(|e| panic!("after point {i}: {e}"));
        }
        s.take_events(&mut events);
    }
    s.finish();
    s.take_events(&mut events);
    let mut verts: Vec<[f64; 2]> = Vec::new();
    let mut done = std::collections::HashSet::new();
    let mut tris = Vec::new();
    let mut corners = Vec::new();
    for e in &events {
        match *e {
            Event::Vertex { xy, .. } => {
                verts.push([xy[0] + prep.origin[0], xy[1] + prep.origin[1]])
            }
            Event::Corner { xy, .. } => {
                corners.push([xy[0] + prep.origin[0], xy[1] + prep.origin[1]])
            }
            Event::Triangle(t) => {
                for v in t {
                    assert!(!done.contains(&v), "triangle uses released vertex {v}");
                }
                let at: Vec<[f64; 2]> = t.iter().map(|&v| verts[v as usize]).collect();
                assert_eq!(corners, at, "the corners sent before triangle {t:?}");
                corners.clear();
                let mut k = t.map(|v| {
                    (
                        verts[v as usize][0].to_bits(),
                        verts[v as usize][1].to_bits(),
                    )
                });
                k.sort();
                tris.push(k);
            }
            Event::VertexDone(v) => assert!(done.insert(v), "vertex {v} released twice"),
            Event::Watermark(_) => {}
        }
    }
    assert_eq!(
        done.len(),
        verts.len(),
        "every vertex released exactly once"
    );
    tris.sort();
    (tris, s.stream_stats())
}

#[test]
fn streaming_equals_batch() {
    for seed in 0..200 {
        let mut r = SplitMix64::uniform(seed + 7);
        let n = 3 + (seed as usize * 7 % 300);
        let pts: Vec<[f64; 3]> = (0..n).map(|_| [r(), r(), 0.0]).collect();
        let (s, _) = stream_set(&pts, n < 100);
        let t = triangulate(&pts, &Options::default()).unwrap();
        let b = tri_set(&t.triangles, &t.vertices);
        assert_eq!(s, b, "seed {seed}");
    }
    // Grids: ties everywhere.
    for w in [3usize, 10, 57] {
        let pts: Vec<[f64; 3]> = (0..w * w)
            .map(|i| [(i % w) as f64, (i / w) as f64, 0.0])
            .collect();
        let (s, _) = stream_set(&pts, true);
        let t = triangulate(&pts, &Options::default()).unwrap();
        assert_eq!(s, tri_set(&t.triangles, &t.vertices), "grid {w}");
    }
}

#[test]
fn streaming_memory_is_bounded() {
    let mut r = SplitMix64::uniform(99);
    let n = 200_000;
    let pts: Vec<[f64; 3]> = (0..n).map(|_| [r() * 1000.0, r() * 1000.0, 0.0]).collect();
    let (s, st) = stream_set(&pts, false);
    assert_eq!(s.len() as u64, st.triangles);
    eprintln!("{st:?}");
    assert!(st.peak_live_triangles < 40_000, "{st:?}");
}

/// Degenerate strips keep the streaming sweep's bookkeeping linear. Two aligned rows far apart:
/// each point of the upper row takes over the whole fan of the one before (n flips a point), and
/// each flip used to queue another entry for the same triangle slot. A diagonal band: the
/// triangles along its upper side wait for a part of the front that never rises, and used to be
/// checked again every few buckets until the end.
#[test]
fn streaming_bookkeeping_is_linear_on_degenerate_strips() {
    let n = 1500;
    let rows: Vec<[f64; 3]> = (0..2 * n)
        .map(|i| [(i % n) as f64, (i / n * n) as f64, 0.0])
        .collect();
    let m = 8000;
    let band: Vec<[f64; 3]> = (0..2 * m)
        .map(|i| {
            let k = (i % m) as f64;
            [k, k + (i / m) as f64 * 200.0, 0.0]
        })
        .collect();
    for (name, pts) in [("rows", rows), ("band", band)] {
        let (s, st) = stream_set(&pts, false);
        let t = triangulate(&pts, &Options::default()).unwrap();
        assert_eq!(s, tri_set(&t.triangles, &t.vertices), "{name}");
        eprintln!("{name}: {st:?}");
        assert!(
            st.peak_queued <= 2 * st.peak_live_triangles,
            "{name}: {st:?}"
        );
        assert!(st.rechecks <= 12 * st.triangles, "{name}: {st:?}");
    }
}
