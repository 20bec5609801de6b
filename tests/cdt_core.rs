//! Breaklines in the sweep core: invariants after every step, and the triangle set of spade's
//! constrained Delaunay triangulation on random inputs in general position.

use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation as _};
use sweeptin::geom::predicates::{Orientation, orient};
use sweeptin::sort::memory::{DuplicatePolicy, prepare};
use sweeptin::synth::SplitMix64;
use sweeptin::{Options, triangulate_cdt};

fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let o1 = orient(a, b, c);
    let o2 = orient(a, b, d);
    let o3 = orient(c, d, a);
    let o4 = orient(c, d, b);
    let ne = |x: Orientation, y: Orientation| {
        x != Orientation::Collinear && y != Orientation::Collinear && x != y
    };
    ne(o1, o2) && ne(o3, o4)
}

/// Random points and random non-crossing segments between them (no shared endpoints check
/// needed: segments may share endpoints).
fn random_input(seed: u64, n: usize, m: usize) -> (Vec<[f64; 3]>, Vec<[u32; 2]>) {
    let mut r = SplitMix64::uniform(seed);
    let pts: Vec<[f64; 3]> = (0..n).map(|_| [r() * 100.0, r() * 100.0, r()]).collect();
    let mut segs: Vec<[u32; 2]> = Vec::new();
    let xy = |i: u32| [pts[i as usize][0], pts[i as usize][1]];
    let mut tries = 0;
    while segs.len() < m && tries < 50 * m {
        tries += 1;
        let a = (r() * n as f64) as u32;
        let b = (r() * n as f64) as u32;
        if a == b {
            continue;
        }
        // Short-ish segments, like real breaklines, plus a few long ones.
        let (pa, pb) = (xy(a), xy(b));
        let len = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
        if len > 30.0 && !segs.len().is_multiple_of(10) {
            continue;
        }
        let collinear_with_point = (0..n as u32).any(|k| {
            k != a
                && k != b
                && orient(pa, pb, xy(k)) == Orientation::Collinear
                && (xy(k)[0] - pa[0]) * (xy(k)[0] - pb[0]) <= 0.0
                && (xy(k)[1] - pa[1]) * (xy(k)[1] - pb[1]) <= 0.0
        });
        if collinear_with_point
            || segs.iter().any(|s| {
                (s[0] == a && s[1] == b)
                    || (s[0] == b && s[1] == a)
                    || cross(xy(s[0]), xy(s[1]), pa, pb)
            })
        {
            continue;
        }
        segs.push([a, b]);
    }
    (pts, segs)
}

type Key = [(u64, u64); 3];

fn key(ps: [[f64; 2]; 3]) -> Key {
    let mut k = ps.map(|p| (p[0].to_bits(), p[1].to_bits()));
    k.sort();
    k
}

fn spade_cdt(pts: &[[f64; 3]], segs: &[[u32; 2]]) -> Vec<Key> {
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    let handles: Vec<_> = pts
        .iter()
        .map(|p| cdt.insert(Point2::new(p[0], p[1])).unwrap())
        .collect();
    for s in segs {
        assert!(cdt.add_constraint(handles[s[0] as usize], handles[s[1] as usize]));
    }
    let mut out: Vec<Key> = cdt
        .inner_faces()
        .map(|f| key(f.vertices().map(|v| [v.position().x, v.position().y])))
        .collect();
    out.sort();
    out
}

fn ours(pts: &[[f64; 3]], segs: &[[u32; 2]]) -> Vec<Key> {
    let t = triangulate_cdt(pts, segs, &Options::default()).unwrap();
    assert_eq!(t.constraint_stats.crossing_skipped, 0);
    let mut out: Vec<Key> = t
        .triangles
        .iter()
        .map(|tri| key(tri.map(|i| [t.vertices[i as usize][0], t.vertices[i as usize][1]])))
        .collect();
    out.sort();
    out
}

#[test]
fn equals_spade_cdt_on_random_segments() {
    let seeds: u64 = std::env::var("CDT_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(120);
    for seed in 0..seeds {
        let n = 10 + (seed as usize * 13) % 300;
        let (pts, segs) = random_input(seed, n, n / 3);
        assert_eq!(
            ours(&pts, &segs),
            spade_cdt(&pts, &segs),
            "seed {seed}, n {n}"
        );
    }
}

/// Segment endpoints given as exact duplicates of other points (merged away by the duplicate
/// policy) refer to the surviving point: the result is the one with the survivors' indices.
#[test]
fn segments_ending_at_merged_duplicates() {
    for seed in 0..40 {
        let n = 20 + (seed as usize * 17) % 200;
        let (mut pts, segs) = random_input(seed, n, n / 3);
        let expected = ours(&pts, &segs);
        // Duplicate every endpoint of every other segment, once before the original (so that
        // the copy survives under the default policy) and once after it, and point the segments
        // at the copies.
        let mut moved = segs.clone();
        for (k, s) in moved.iter_mut().enumerate().filter(|(k, _)| k % 2 == 0) {
            for (j, e) in s.iter_mut().enumerate() {
                let p = pts[*e as usize];
                pts.push(p);
                if (k / 2 + j) % 2 == 0 {
                    *e = (pts.len() - 1) as u32;
                }
            }
        }
        assert_eq!(ours(&pts, &moved), expected, "seed {seed}");
        let mut front = pts.clone();
        front.rotate_right(pts.len() - n);
        let shift = (pts.len() - n) as u32;
        let remap = |i: u32| {
            if i < n as u32 {
                i + shift
            } else {
                i - n as u32
            }
        };
        let moved: Vec<[u32; 2]> = moved.iter().map(|s| s.map(remap)).collect();
        assert_eq!(ours(&front, &moved), expected, "seed {seed}, copies first");
    }
}

#[test]
fn stepwise_invariants_with_breaklines() {
    for seed in 0..150 {
        let n = 6 + (seed as usize * 7) % 60;
        let (pts, segs) = random_input(seed + 5000, n, n / 2);
        let prep = prepare(&pts, DuplicatePolicy::First).unwrap();
        // Same mapping as triangulate_cdt: endpoints to sorted vertex ids.
        let t = triangulate_cdt(&pts, &segs, &Options::default()).unwrap();
        assert!(!t.triangles.is_empty());
        let mut s = sweeptin::sweep::Sweep::new(prep.xy.clone()).unwrap();
        let real = &prep.xy[2..];
        let vid = |i: u32| {
            let p = pts[i as usize];
            let q = [p[0] - prep.origin[0], p[1] - prep.origin[1]];
            real.iter().position(|v| *v == q).unwrap() as u32
        };
        let mut ends: Vec<u32> = segs.iter().flatten().map(|&i| vid(i)).collect();
        ends.sort_unstable();
        ends.dedup();
        let cid = |v: u32| ends.binary_search(&v).unwrap() as u32;
        let cs: Vec<[u32; 2]> = segs
            .iter()
            .map(|s| [cid(vid(s[0])), cid(vid(s[1]))])
            .collect();
        let g = sweeptin::sweep::ConstraintGraph::new(
            ends.iter().map(|&v| real[v as usize]).collect(),
            &cs,
        );
        s.set_constraints(g, &ends);
        let mut k = 0;
        while s.step().unwrap() {
            k += 1;
            s.check()
                .unwrap_or_else(|e| panic!("seed {seed} step {k}: {e}"));
            if let Some(o) = overlapping(&s) {
                panic!("seed {seed} step {k}: triangles {o:?} overlap");
            }
        }
    }
}

fn overlapping(s: &sweeptin::sweep::Sweep) -> Option<(u32, u32)> {
    let m = s.mesh();
    let p = s.points();
    let tris: Vec<(u32, [u32; 3])> = (0..m.triangle_count() as u32)
        .map(sweeptin::mesh::TriId)
        .filter(|&t| m.is_live(t))
        .map(|t| (t.0, m.tri_vertices(t).map(|v| v.0)))
        .filter(|(_, v)| v.iter().all(|&x| x >= 2))
        .collect();
    let sep = |a: &[u32; 3], b: &[u32; 3]| {
        (0..3).any(|i| {
            let (u, v) = (p[a[i] as usize], p[a[(i + 1) % 3] as usize]);
            b.iter()
                .all(|&w| orient(u, v, p[w as usize]) != Orientation::CounterClockwise)
        })
    };
    for i in 0..tris.len() {
        for j in i + 1..tris.len() {
            let (a, b) = (&tris[i].1, &tris[j].1);
            if !sep(a, b) && !sep(b, a) {
                return Some((tris[i].0, tris[j].0));
            }
        }
    }
    None
}

/// The mesh edges that make up each input segment (through vertices lying on it), or a panic
/// naming the segment that is not a union of mesh edges.
fn segment_pieces(
    t: &sweeptin::Triangulation,
    pts: &[[f64; 3]],
    segs: &[[u32; 2]],
) -> Vec<[u32; 2]> {
    let xy = |v: &[f64; 3]| [v[0], v[1]];
    let mut edges = std::collections::HashSet::new();
    for tri in &t.triangles {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    let mut out = Vec::new();
    for s in segs {
        let (a, b) = (xy(&pts[s[0] as usize]), xy(&pts[s[1] as usize]));
        let mut on: Vec<(f64, u32)> = t
            .vertices
            .iter()
            .enumerate()
            .filter(|(_, v)| {
                let p = xy(v);
                orient(a, b, p) == Orientation::Collinear
                    && p[0] >= a[0].min(b[0])
                    && p[0] <= a[0].max(b[0])
                    && p[1] >= a[1].min(b[1])
                    && p[1] <= a[1].max(b[1])
            })
            .map(|(i, v)| (((v[0] - a[0]).powi(2) + (v[1] - a[1]).powi(2)), i as u32))
            .collect();
        on.sort_by(|x, y| x.0.total_cmp(&y.0));
        for w in on.windows(2) {
            let (u, v) = (w[0].1, w[1].1);
            assert!(
                edges.contains(&(u.min(v), u.max(v))),
                "segment {s:?}: piece {u}-{v} missing"
            );
            out.push([u, v]);
        }
    }
    out
}

#[test]
fn degenerate_grids_with_breaklines_validate() {
    let w = 24usize;
    let pts: Vec<[f64; 3]> = (0..w * w)
        .map(|i| [(i % w) as f64, (i / w) as f64, 0.0])
        .collect();
    let at = |x: usize, y: usize| (y * w + x) as u32;
    let mut segs = vec![
        [at(0, 3), at(23, 3)],   // along a grid row: split at every point
        [at(5, 0), at(5, 2)],    // along a column, ending at the row above
        [at(2, 5), at(20, 23)],  // diagonal through grid points
        [at(3, 5), at(21, 23)],  // parallel diagonal
        [at(12, 0), at(18, 2)],  // 3:1 slope, through (15, 1)
        [at(0, 23), at(10, 13)], // anti-diagonal
    ];
    // A closed ring (a lake shore) of axis-parallel edges.
    let ring = [(14, 5), (19, 5), (19, 9), (14, 9)];
    for k in 0..4 {
        let (p, q) = (ring[k], ring[(k + 1) % 4]);
        segs.push([at(p.0, p.1), at(q.0, q.1)]);
    }
    // Exact transformations only (powers of two), so collinear points stay collinear.
    let (s10, s30) = (2f64.powi(-10), 2f64.powi(-30));
    for (scale, dx, dy) in [
        (1.0, 0.0, 0.0),
        (s10, 500_000.0, 4_000_000.0),
        (s30, 0.0, 0.0),
        (1024.0, 0.0, 0.0),
    ] {
        let p2: Vec<[f64; 3]> = pts
            .iter()
            .map(|p| [p[0] * scale + dx, p[1] * scale + dy, 0.0])
            .collect();
        let t = triangulate_cdt(&p2, &segs, &Options::default()).unwrap();
        assert_eq!(t.constraint_stats.crossing_skipped, 0);
        let pieces = segment_pieces(&t, &p2, &segs);
        sweeptin::validate::validate_constrained(&t.vertices, &t.triangles, &pieces)
            .unwrap_or_else(|e| panic!("scale {scale}: {e}"));
    }
}

#[test]
fn crossing_breaklines_are_reported_not_fatal() {
    let pts = [
        [0.0, 0.0, 0.0],
        [10.0, 10.0, 0.0],
        [0.0, 10.0, 0.0],
        [10.0, 0.0, 0.0],
        [5.0, 20.0, 0.0],
    ];
    let t = triangulate_cdt(&pts, &[[0, 1], [2, 3]], &Options::default()).unwrap();
    assert_eq!(t.constraint_stats.crossing_skipped, 1);
    sweeptin::validate::validate(&t.vertices, &t.triangles).unwrap();
}

/// The streaming sweep with breaklines gives the batch sweep's triangles, releases every vertex
/// once, and keeps pending breaklines from being finalised across.
#[test]
fn streaming_breaklines_equal_batch() {
    use sweeptin::finalise::{Event, StreamConfig, StreamPoint, StreamingSweep};
    for seed in 0..60 {
        let n = 20 + (seed as usize * 37) % 600;
        let (pts, segs) = random_input(seed + 9000, n, n / 4);
        let batch = ours(&pts, &segs);
        let prep = prepare(&pts, DuplicatePolicy::First).unwrap();
        let real = &prep.xy[2..];
        let vid = |i: u32| {
            let p = pts[i as usize];
            let q = [p[0] - prep.origin[0], p[1] - prep.origin[1]];
            real.binary_search_by(|v| sweeptin::geom::predicates::sweep_cmp(*v, q))
                .unwrap() as u32
        };
        let mut ends: Vec<u32> = segs.iter().flatten().map(|&i| vid(i)).collect();
        ends.sort_unstable();
        ends.dedup();
        let cid = |v: u32| ends.binary_search(&v).map_or(u32::MAX, |c| c as u32);
        let cs: Vec<[u32; 2]> = segs
            .iter()
            .map(|s| [cid(vid(s[0])), cid(vid(s[1]))])
            .collect();
        let g = sweeptin::sweep::ConstraintGraph::new(
            ends.iter().map(|&v| real[v as usize]).collect(),
            &cs,
        );
        let cfg = StreamConfig {
            x_sample: vec![],
            bounds: [0.0, 0.0, 100.0, 100.0],
            expected_points: real.len() as u64,
            spill: None,
            corners: false,
        };
        let sp = |i: usize| StreamPoint {
            xy: real[i],
            z: 0.0,
            index: i as u64,
            constraint: cid(i as u32),
        };
        let mut s = StreamingSweep::new(sp(0), &cfg);
        s.set_constraints(g, cid(0)).unwrap();
        let mut events = Vec::new();
        for i in 1..real.len() {
            s.push(sp(i)).unwrap();
            if n < 200 {
                s.check()
                    .unwrap_or_else(|e| panic!("seed {seed} point {i}: {e}"));
            }
        }
        s.finish();
        s.take_events(&mut events);
        let mut verts = Vec::new();
        let mut done = std::collections::HashSet::new();
        let mut tris = Vec::new();
        for e in events {
            match e {
                Event::Vertex { xy, .. } => {
                    verts.push([xy[0] + prep.origin[0], xy[1] + prep.origin[1]])
                }
                Event::Triangle(t) => {
                    assert!(t.iter().all(|v| !done.contains(v)));
                    tris.push(key(t.map(|v| verts[v as usize])));
                }
                Event::VertexDone(v) => assert!(done.insert(v)),
                Event::Corner { .. } | Event::Watermark(_) => {}
            }
        }
        assert_eq!(
            done.len(),
            verts.len(),
            "seed {seed}: every vertex released once"
        );
        tris.sort();
        assert_eq!(tris, batch, "seed {seed}");
        assert!(s.stream_stats().peak_pending_segments > 0);
    }
}

/// Breaklines that do not match the points are an internal error, not a panic: a batch sweep
/// given a segment whose later end (in the graph) is swept before its earlier end, and a
/// streaming sweep given a point naming a breakline vertex it has no graph for.
#[test]
fn mismatched_breaklines_are_errors_not_panics() {
    use sweeptin::Error;
    use sweeptin::finalise::{StreamConfig, StreamPoint, StreamingSweep};
    let pts = [
        [0.0, 0.0, 0.0],
        [1.0, 0.5, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 2.0, 0.0],
    ];
    let prep = prepare(&pts, DuplicatePolicy::First).unwrap();
    let mut s = sweeptin::sweep::Sweep::new(prep.xy.clone()).unwrap();
    // Constraint vertex 1 is the later end of the segment, but it is mapped to vertex 1 and
    // constraint vertex 0 to vertex 3: the later end comes first.
    let g = sweeptin::sweep::ConstraintGraph::new(vec![[0.0, 0.0], [1.0, 1.0]], &[[0, 1]]);
    s.set_constraints(g, &[3, 1]);
    assert!(matches!(s.run(), Err(Error::Internal(_))));

    let cfg = StreamConfig {
        x_sample: vec![],
        bounds: [0.0, 0.0, 1.0, 2.0],
        expected_points: 4,
        spill: None,
        corners: false,
    };
    let sp = |i: usize, constraint: u32| StreamPoint {
        xy: prep.xy[2 + i],
        z: 0.0,
        index: i as u64,
        constraint,
    };
    let mut s = StreamingSweep::new(sp(0, u32::MAX), &cfg);
    s.push(sp(1, u32::MAX)).unwrap();
    match s.push(sp(2, 7)) {
        Err(Error::Internal(m)) => assert!(m.contains("breakline vertex 7"), "{m}"),
        other => panic!("{other:?}"),
    }
    let mut s = StreamingSweep::new(sp(0, 7), &cfg);
    let g = sweeptin::sweep::ConstraintGraph::new(vec![[0.0, 0.0], [1.0, 1.0]], &[[0, 1]]);
    assert!(matches!(s.set_constraints(g, 7), Err(Error::Internal(_))));
}
