//! Unit tests of the cleaner: one per rule, then random inputs checked by a brute-force planarity
//! test that shares no code with the cleaner.

use super::intersect::crossing_point;
use super::*;
use crate::geom::predicates::{Orientation, orient, orient_det};
use crate::synth::SplitMix64;
use std::collections::HashMap;

fn run(lines: &[Vec<[f64; 3]>]) -> Pslg {
    let g = clean(lines, &CleanOptions::default()).unwrap();
    brute_force_planar(&g);
    g
}

fn l2(pts: &[[f64; 2]]) -> Vec<[f64; 3]> {
    pts.iter().map(|p| [p[0], p[1], f64::NAN]).collect()
}

/// Output segments as sorted coordinate pairs.
fn geometry(g: &Pslg) -> Vec<[[u64; 2]; 2]> {
    let k = |v: u32| {
        let p = g.vertices[v as usize];
        [p[0].to_bits(), p[1].to_bits()]
    };
    let mut out: Vec<[[u64; 2]; 2]> = g
        .segments
        .iter()
        .map(|s| {
            let (a, b) = (k(s[0]), k(s[1]));
            if a <= b { [a, b] } else { [b, a] }
        })
        .collect();
    out.sort_unstable();
    out
}

/// O(n²) check with its own predicates logic: no two segments share any point but a common end.
fn brute_force_planar(g: &Pslg) {
    let p = |v: u32| {
        let q = g.vertices[v as usize];
        [q[0], q[1]]
    };
    let mut seen = std::collections::HashSet::new();
    for v in &g.vertices {
        assert!(
            seen.insert(((v[0] + 0.0).to_bits(), (v[1] + 0.0).to_bits())),
            "vertex twice: {v:?}"
        );
    }
    let on = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        orient(a, b, c) == Orientation::Collinear
            && c[0] >= a[0].min(b[0])
            && c[0] <= a[0].max(b[0])
            && c[1] >= a[1].min(b[1])
            && c[1] <= a[1].max(b[1])
    };
    for (i, s) in g.segments.iter().enumerate() {
        assert!(s[0] < s[1]);
        let (a, b) = (p(s[0]), p(s[1]));
        // No vertex other than its ends on a segment.
        for v in 0..g.vertices.len() as u32 {
            if v != s[0] && v != s[1] {
                assert!(
                    !on(a, b, p(v)),
                    "vertex {v} {:?} on segment {i} {a:?}-{b:?}",
                    p(v)
                );
            }
        }
        for t in &g.segments[i + 1..] {
            assert_ne!(s, t, "segment twice");
            let (c, d) = (p(t[0]), p(t[1]));
            let shared = s.iter().any(|v| t.contains(v));
            if shared {
                continue; // overlap along a common line would put an end on the other: checked above
            }
            let o1 = orient(a, b, c);
            let o2 = orient(a, b, d);
            let o3 = orient(c, d, a);
            let o4 = orient(c, d, b);
            let proper = o1 != o2
                && o3 != o4
                && [o1, o2, o3, o4]
                    .iter()
                    .all(|o| *o != Orientation::Collinear);
            assert!(!proper, "segments {a:?}-{b:?} and {c:?}-{d:?} cross");
        }
    }
    g.check_planar().unwrap();
}

/// Union-find: every input segment's ends are connected in the output.
fn assert_connected(lines: &[Vec<[f64; 3]>], g: &Pslg) {
    let mut parent: Vec<usize> = (0..g.vertices.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for s in &g.segments {
        let (a, b) = (
            find(&mut parent, s[0] as usize),
            find(&mut parent, s[1] as usize),
        );
        parent[a] = b;
    }
    let index: HashMap<(u64, u64), usize> = g
        .vertices
        .iter()
        .enumerate()
        .map(|(i, v)| (((v[0] + 0.0).to_bits(), (v[1] + 0.0).to_bits()), i))
        .collect();
    for l in lines {
        for w in l.windows(2) {
            let a = index[&((w[0][0] + 0.0).to_bits(), (w[0][1] + 0.0).to_bits())];
            let b = index[&((w[1][0] + 0.0).to_bits(), (w[1][1] + 0.0).to_bits())];
            assert_eq!(
                find(&mut parent, a),
                find(&mut parent, b),
                "{w:?} disconnected"
            );
        }
    }
}

#[test]
fn clean_input_passes_unchanged() {
    let lines = vec![
        l2(&[[0., 0.], [1., 0.], [1., 1.]]),
        l2(&[[3., 3.], [4., 4.]]),
    ];
    let g = run(&lines);
    assert_eq!(g.vertices.len(), 5);
    assert_eq!(g.segments, vec![[0, 1], [1, 2], [3, 4]]);
    assert_eq!(g.lines, vec![0, 0, 1]);
    assert_eq!(g.stats.rounds, 1);
    assert_eq!(g.stats.input_segments, 3);
}

#[test]
fn duplicates_zero_length_and_shared_edges() {
    // Two squares sharing the edge (1,0)-(1,1), traversed in opposite directions; a repeated
    // vertex in the first one.
    let lines = vec![
        l2(&[[0., 0.], [1., 0.], [1., 0.], [1., 1.], [0., 1.], [0., 0.]]),
        l2(&[[1., 1.], [1., 0.], [2., 0.], [2., 1.], [1., 1.]]),
    ];
    let g = run(&lines);
    assert_eq!(g.vertices.len(), 6);
    assert_eq!(g.segments.len(), 7);
    assert_eq!(g.stats.zero_length, 1);
    assert_eq!(g.stats.duplicate_segments, 1);
    assert_eq!(g.stats.merged_vertices, 11 - 6);
    assert_eq!(g.stats.crossings + g.stats.vertex_splits, 0);
}

#[test]
fn t_junction_splits_the_segment() {
    let lines = vec![
        vec![[0., 0., 0.], [4., 0., 4.]],
        vec![[2., 0., 7.], [2., 3., 7.]],
    ];
    let g = run(&lines);
    assert_eq!(g.segments.len(), 3);
    assert_eq!(g.stats.vertex_splits, 1);
    // The vertex keeps its own z and the disagreement with the line (z = 2 there) is reported.
    assert_eq!(g.vertices[2], [2., 0., 7.]);
    assert_eq!(g.stats.z_conflicts, 1);
    assert_eq!(g.warnings[0].kind, ZConflictKind::OnLine);
    assert_eq!(g.warnings[0].z, [7., 2.]);
    // A vertex without z takes the line's.
    let lines = vec![
        vec![[0., 0., 0.], [4., 0., 4.]],
        vec![[1., 0., f64::NAN], [1., -3., 1.]],
    ];
    let g = run(&lines);
    assert_eq!(g.vertices[2], [1., 0., 1.]);
    assert_eq!(g.stats.z_conflicts, 0);
}

#[test]
fn collinear_overlaps_merge() {
    // Partial overlap, containment, and a chain along the same line.
    let lines = vec![
        l2(&[[0., 0.], [4., 0.]]),
        l2(&[[2., 0.], [6., 0.]]),
        l2(&[[1., 0.], [3., 0.]]),
        l2(&[[6., 0.], [5., 0.]]),
    ];
    let g = run(&lines);
    assert_eq!(g.vertices.len(), 7);
    // 0-1-2-3-4-5-6 along x.
    assert_eq!(g.segments.len(), 6);
    assert!(g.stats.overlaps >= 3, "{:?}", g.stats);
    assert!(g.stats.merged_pieces >= 2, "{:?}", g.stats);
    assert_eq!(g.stats.crossings, 0);
    assert_connected(&lines, &g);
    // Diagonal overlap with a shared end.
    let lines = vec![l2(&[[0., 0.], [3., 3.]]), l2(&[[0., 0.], [1., 1.]])];
    let g = run(&lines);
    assert_eq!(g.segments.len(), 2);
    assert_eq!(g.stats.overlaps, 1);
}

#[test]
fn isolated_vertex_on_a_segment_splits_it() {
    let lines = vec![l2(&[[0., 0.], [2., 2.]]), l2(&[[1., 1.]]), l2(&[[5., 5.]])];
    let g = run(&lines);
    assert_eq!(g.segments.len(), 2);
    assert_eq!(g.vertices.len(), 4);
}

#[test]
fn crossing_gets_z_from_both_lines() {
    let lines = vec![
        vec![[0., 0., 10.], [2., 2., 12.]],
        vec![[0., 2., 10.], [2., 0., 10.]],
    ];
    let g = run(&lines);
    assert_eq!(g.stats.crossings, 1);
    assert_eq!(g.vertices[4][..2], [1., 1.]);
    // 11 and 10 differ by more than 0.1: the mean is kept and reported.
    assert_eq!(g.vertices[4][2], 10.5);
    assert_eq!(g.stats.z_conflicts, 1);
    assert_eq!(g.warnings[0].kind, ZConflictKind::Crossing);
    assert_eq!(g.warnings[0].lines, [0, 1]);
    let opts = CleanOptions {
        z_tolerance: 2.0,
        ..CleanOptions::default()
    };
    assert_eq!(clean(&lines, &opts).unwrap().stats.z_conflicts, 0);
}

#[test]
fn duplicate_vertices_keep_the_first_known_z() {
    let lines = vec![
        vec![[0., 0., f64::NAN], [1., 0., 1.]],
        vec![[0., 0., 5.], [0., 1., 1.]],
        vec![[0., 0., 9.], [-1., 0., 1.]],
    ];
    let g = run(&lines);
    assert_eq!(g.vertices[0], [0., 0., 5.]);
    assert_eq!(g.stats.z_conflicts, 1);
    assert_eq!(g.warnings[0].kind, ZConflictKind::Duplicate);
    assert_eq!(g.warnings[0].lines, [0, 2]);
}

#[test]
fn crossing_through_an_existing_vertex() {
    // The crossing point of the two diagonals is exactly the vertex (1, 1) of a third line.
    let lines = vec![
        l2(&[[0., 0.], [2., 2.]]),
        l2(&[[0., 2.], [2., 0.]]),
        l2(&[[1., 1.], [1., 5.]]),
    ];
    let g = run(&lines);
    assert_eq!(g.vertices.len(), 6);
    assert_eq!(g.segments.len(), 5);
    assert_eq!(g.stats.new_vertices, 0);
}

#[test]
fn nearly_concurrent_lines_meet_in_one_vertex() {
    // Lines through (0.1, 0.7) in many directions, with rounded ends: the pairwise crossing points
    // are all within a few ulps of each other and must become one vertex (or a few, well apart).
    let c = [0.1, 0.7];
    let lines: Vec<Vec<[f64; 3]>> = (0..12)
        .map(|k| {
            let t = 0.1 + k as f64 * 0.261;
            let (s, co) = t.sin_cos();
            l2(&[
                [c[0] - 3.0 * co, c[1] - 3.0 * s],
                [c[0] + 2.0 * co, c[1] + 2.0 * s],
            ])
        })
        .collect();
    let g = run(&lines);
    assert_connected(&lines, &g);
    let near = g
        .vertices
        .iter()
        .filter(|v| (v[0] - c[0]).abs() < 1e-9 && (v[1] - c[1]).abs() < 1e-9)
        .count();
    assert!(near <= 2, "{near} vertices near the centre; {:?}", g.stats);
    assert!(g.stats.snapped > 0);
}

#[test]
fn bad_coordinates_are_errors() {
    let lines = vec![l2(&[[0., 0.], [1., 1.]]), l2(&[[0., 0.], [f64::NAN, 1.]])];
    match clean(&lines, &CleanOptions::default()) {
        Err(Error::BadLine {
            polyline, vertex, ..
        }) => assert_eq!((polyline, vertex), (1, 1)),
        other => panic!("{other:?}"),
    }
    let lines = vec![l2(&[[0., 0.], [1e300, 1.]])];
    assert!(clean(&lines, &CleanOptions::default()).is_err());
    let lines = vec![vec![[0., 0., f64::INFINITY], [1., 1., 0.]]];
    assert!(clean(&lines, &CleanOptions::default()).is_err());
    // Empty input is fine.
    let g = clean(&[], &CleanOptions::default()).unwrap();
    assert!(g.vertices.is_empty() && g.segments.is_empty());
}

/// Random segments with ends on a small integer grid: full of collinear overlaps, T-junctions,
/// shared ends and crossings at representable and non-representable points.
fn grid_segments(rng: &mut SplitMix64, n: usize, size: u64) -> Vec<Vec<[f64; 3]>> {
    (0..n)
        .map(|_| {
            let k = 2 + rng.below(3) as usize;
            (0..k)
                .map(|_| {
                    [
                        rng.below(size) as f64,
                        rng.below(size) as f64,
                        rng.below(5) as f64,
                    ]
                })
                .collect()
        })
        .collect()
}

#[test]
fn random_grid_segments_become_planar() {
    for seed in 0..40 {
        let mut rng = SplitMix64::new(seed);
        let n = 5 + rng.below(40) as usize;
        let size = 3 + rng.below(8);
        let lines = grid_segments(&mut rng, n, size);
        let g = clean(&lines, &CleanOptions::default()).unwrap();
        brute_force_planar(&g);
        assert_connected(&lines, &g);
        assert!(g.stats.rounds < 10, "seed {seed}: {:?}", g.stats);
    }
}

#[test]
fn random_float_segments_become_planar() {
    for seed in 0..20 {
        let mut rng = SplitMix64::new(seed + 1000);
        let lines: Vec<Vec<[f64; 3]>> = (0..60)
            .map(|_| {
                let a = [rng.range(0.0, 10.0), rng.range(0.0, 10.0)];
                let b = [a[0] + rng.range(-3.0, 3.0), a[1] + rng.range(-3.0, 3.0)];
                l2(&[a, b])
            })
            .collect();
        let g = clean(&lines, &CleanOptions::default()).unwrap();
        brute_force_planar(&g);
        assert_connected(&lines, &g);
        assert!(g.stats.crossings > 10);
    }
}

#[test]
fn at_utm_offsets_too() {
    // The same grid inputs shifted to large coordinates, scaled to cm.
    for seed in 0..10 {
        let mut rng = SplitMix64::new(seed + 77);
        let lines: Vec<Vec<[f64; 3]>> = grid_segments(&mut rng, 30, 6)
            .into_iter()
            .map(|l| {
                l.into_iter()
                    .map(|p| [447_000.0 + 0.01 * p[0], 84_900.0 + 0.01 * p[1], p[2]])
                    .collect()
            })
            .collect();
        let g = clean(&lines, &CleanOptions::default()).unwrap();
        brute_force_planar(&g);
        assert_connected(&lines, &g);
    }
}

#[test]
fn output_depends_on_geometry_not_on_order() {
    for seed in 0..15 {
        let mut rng = SplitMix64::new(seed + 500);
        let lines = grid_segments(&mut rng, 25, 7);
        let a = clean(&lines, &CleanOptions::default()).unwrap();
        let reversed: Vec<Vec<[f64; 3]>> = lines
            .iter()
            .rev()
            .map(|l| l.iter().rev().copied().collect())
            .collect();
        let b = clean(&reversed, &CleanOptions::default()).unwrap();
        assert_eq!(geometry(&a), geometry(&b), "seed {seed}");
        // And twice the same call gives the same ids.
        let c = clean(&lines, &CleanOptions::default()).unwrap();
        assert_eq!(a.segments, c.segments);
        assert_eq!(a.lines, c.lines);
    }
}

#[test]
fn check_planar_finds_problems() {
    let g = Pslg {
        vertices: vec![[0., 0., 0.], [2., 2., 0.], [0., 2., 0.], [2., 0., 0.]],
        segments: vec![[0, 1], [2, 3]],
        lines: vec![0, 1],
        ..Pslg::default()
    };
    assert!(
        g.check_planar()
            .unwrap_err()
            .to_string()
            .contains("crosses")
    );
    let g = Pslg {
        vertices: vec![[0., 0., 0.], [2., 2., 0.], [1., 1., 0.]],
        segments: vec![[0, 1]],
        lines: vec![0],
        ..Pslg::default()
    };
    assert!(
        g.check_planar()
            .unwrap_err()
            .to_string()
            .contains("vertex 2")
    );
}

#[test]
fn crossing_point_is_canonical() {
    let (a, b, c, d) = ([0.0, 0.0], [3.0, 1.0], [0.1, 1.0], [2.9, -0.3]);
    let p = crossing_point(a, b, c, d);
    assert_eq!(p, crossing_point(b, a, d, c));
    assert_eq!(p, crossing_point(c, d, a, b));
    assert_eq!(p, crossing_point(d, c, b, a));
    assert!((orient_det(a, b, p)).abs() < 1e-14);
}
