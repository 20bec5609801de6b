//! Unit tests of the validator: one hand-made invalid mesh per failure kind, valid meshes from
//! spade (Delaunay and constrained Delaunay, random and gridded).

use super::*;
use crate::synth::SplitMix64;
use spade::{ConstrainedDelaunayTriangulation, DelaunayTriangulation, Point2, Triangulation as _};

fn v2(pts: &[[f64; 2]]) -> Vec<[f64; 3]> {
    pts.iter().map(|p| [p[0], p[1], 0.0]).collect()
}

/// Expects an `Invalid` error whose message contains `needle`.
fn fails(r: Result<Report>, needle: &str) {
    match r {
        Err(Error::Invalid(msg)) => {
            assert!(msg.contains(needle), "message {msg:?} lacks {needle:?}")
        }
        other => panic!("expected Invalid containing {needle:?}, got {other:?}"),
    }
}

/// A spade triangulation as plain arrays.
fn from_spade<T: spade::Triangulation<Vertex = Point2<f64>>>(
    d: &T,
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let verts = d
        .vertices()
        .map(|v| [v.position().x, v.position().y, 0.0])
        .collect();
    let tris = d
        .inner_faces()
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    (verts, tris)
}

fn spade_delaunay(pts: &[[f64; 2]]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut d: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    for p in pts {
        d.insert(Point2::new(p[0], p[1])).unwrap();
    }
    from_spade(&d)
}

// A unit square split along the diagonal 0-2, and a point in the middle of nothing else.
const SQUARE: [[f64; 2]; 4] = [[0., 0.], [1., 0.], [1., 1.], [0., 1.]];

#[test]
fn square_both_diagonals_are_valid() {
    let v = v2(&SQUARE);
    let r = validate(&v, &[[0, 1, 2], [0, 2, 3]]).unwrap();
    assert_eq!(
        (
            r.vertices,
            r.triangles,
            r.edges,
            r.hull_vertices,
            r.cocircular_edges
        ),
        (4, 2, 5, 4, 1)
    );
    validate(&v, &[[0, 1, 3], [1, 2, 3]]).unwrap();
    // Any rotation of a triangle's corners is the same triangle.
    validate(&v, &[[1, 2, 0], [3, 0, 2]]).unwrap();
}

#[test]
fn rejects_no_triangles() {
    fails(validate(&v2(&SQUARE), &[]), "no triangles");
}

#[test]
fn rejects_index_out_of_range() {
    fails(
        validate(&v2(&SQUARE), &[[0, 1, 2], [0, 2, 4]]),
        "triangle 1 [0, 2, 4]: vertex index 4 is out of range",
    );
}

#[test]
fn rejects_repeated_corner() {
    fails(
        validate(&v2(&SQUARE), &[[0, 1, 2], [0, 2, 2]]),
        "triangle 1 [0, 2, 2] repeats a vertex",
    );
}

#[test]
fn rejects_clockwise_triangle() {
    fails(
        validate(&v2(&SQUARE), &[[0, 1, 2], [0, 3, 2]]),
        "triangle 1 (vertex 0 (0.0, 0.0), vertex 3 (0.0, 1.0), vertex 2 (1.0, 1.0)) is clockwise",
    );
}

#[test]
fn rejects_degenerate_triangle() {
    let v = v2(&[[0., 0.], [1., 0.], [2., 0.], [1., 1.]]);
    fails(
        validate(&v, &[[0, 1, 3], [1, 2, 3], [0, 1, 2]]),
        "triangle 2 (vertex 0 (0.0, 0.0), vertex 1 (1.0, 0.0), vertex 2 (2.0, 0.0)) is degenerate",
    );
}

#[test]
fn rejects_non_finite_coordinate() {
    let mut v = v2(&SQUARE);
    v[2][2] = f64::NAN;
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3]]),
        "vertex 2: coordinate is not finite",
    );
    v[2][2] = 0.0;
    v[3][0] = f64::NEG_INFINITY;
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3]]),
        "vertex 3: coordinate is not finite",
    );
}

#[test]
fn rejects_coordinate_out_of_exact_range() {
    let v = v2(&[[0., 0.], [1e-40, 0.], [1., 1.], [0., 1.]]);
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3]]),
        "vertex 1 (1e-40, 0.0): coordinate outside",
    );
}

#[test]
fn rejects_duplicate_position() {
    // Vertex 4 sits on vertex 2 (negative zero included in the comparison).
    let v = v2(&[[0., 0.], [1., 0.], [1., 1.], [-0.0, 1.], [1., 1.]]);
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3], [1, 4, 2]]),
        "vertex 2 (1.0, 1.0) and vertex 4 (1.0, 1.0) are at the same (x, y)",
    );
    let v = v2(&[[0., 0.], [1., 0.], [0., 1.], [-0.0, 0.0]]);
    fails(
        validate(&v, &[[0, 1, 2], [3, 1, 2]]),
        "are at the same (x, y)",
    );
}

#[test]
fn rejects_overlapping_triangles() {
    // Triangles 0 and 2 share the directed edge 0 -> 1: they lie on the same side of it.
    let v = v2(&[[0., 0.], [2., 0.], [2., 2.], [0., 2.], [1., 1.]]);
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3], [0, 1, 4]]),
        "directed edge vertex 0 (0.0, 0.0) -> vertex 1 (2.0, 0.0) is used by more than one triangle (0 [0, 1, 2], 2 [0, 1, 4])",
    );
}

#[test]
fn rejects_edge_with_three_triangles() {
    // Edge 0-2 carries triangles on both sides plus a third one: one direction repeats.
    let v = v2(&[[0., 0.], [2., 0.], [2., 2.], [0., 2.], [3., 0.5]]);
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3], [0, 4, 2]]),
        "directed edge vertex 2 (2.0, 2.0) -> vertex 0 (0.0, 0.0) is used by more than one triangle",
    );
}

#[test]
fn rejects_unused_vertex() {
    let v = v2(&[[0., 0.], [1., 0.], [1., 1.], [0., 1.], [5., 5.]]);
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3]]),
        "vertex 4 (5.0, 5.0) is not used by any triangle",
    );
}

#[test]
fn rejects_pinched_boundary() {
    // Two triangles touching at vertex 2 only (a bow tie).
    let v = v2(&[[0., 0.], [1., 0.], [1., 1.], [2., 1.], [2., 2.]]);
    fails(
        validate(&v, &[[0, 1, 2], [2, 3, 4]]),
        "vertex 2 (1.0, 1.0) has two outgoing boundary edges",
    );
}

#[test]
fn rejects_t_junction() {
    // Vertex 4 lies on edge 0-1 of triangle 2, which does not use it.
    let v = v2(&[[0., 0.], [2., 0.], [1., 2.], [1., -1.], [1., 0.]]);
    fails(
        validate(&v, &[[0, 4, 2], [4, 1, 2], [0, 3, 1]]),
        "has two outgoing boundary edges",
    );
}

#[test]
fn rejects_concave_boundary() {
    // An L-shape: the notch at (1, 1) leaves the boundary off the convex hull.
    let v = v2(&[[0., 0.], [2., 0.], [2., 1.], [1., 1.], [1., 2.], [0., 2.]]);
    let tris = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]];
    fails(
        validate(&v, &tris),
        "the mesh boundary is not the convex hull: the hull runs vertex 2 (2.0, 1.0) -> vertex 4 (1.0, 2.0), but the boundary runs to vertex 3 (1.0, 1.0) instead",
    );
}

#[test]
fn rejects_hole() {
    // A square ring around a square hole: outer boundary is the hull, the hole is a second loop.
    let v = v2(&[
        [0., 0.],
        [3., 0.],
        [3., 3.],
        [0., 3.],
        [1., 1.],
        [2., 1.],
        [2., 2.],
        [1., 2.],
    ]);
    let tris = [
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ];
    fails(
        validate(&v, &tris),
        "the mesh has 8 boundary edges, the convex hull 4: boundary edge vertex 4 (1.0, 1.0) -> vertex 7 (1.0, 2.0) is not on the hull",
    );
}

#[test]
fn rejects_skipped_collinear_hull_point() {
    // Vertex 4 = (1, 0) is on the hull edge 0-1 but the boundary runs 0 -> 1 past it; it is used
    // only by a triangle folded over the others.
    let v = v2(&[[0., 0.], [2., 0.], [2., 2.], [0., 2.], [1., 0.]]);
    let tris = [[0, 1, 2], [0, 2, 3], [4, 2, 3]];
    // Triangle 2 overlaps triangle 1: caught as a repeated directed edge 2 -> 3.
    fails(
        validate(&v, &tris),
        "directed edge vertex 2 (2.0, 2.0) -> vertex 3 (0.0, 2.0) is used by more than one triangle",
    );
    // A fan that leaves out (1, 0) entirely is an unused vertex.
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3]]),
        "vertex 4 (1.0, 0.0) is not used by any triangle",
    );
}

#[test]
fn hull_keeps_collinear_points() {
    // The boundary must walk through (1, 0): a valid mesh with it passes, and the hull counts it.
    let v = v2(&[[0., 0.], [2., 0.], [2., 2.], [0., 2.], [1., 0.]]);
    let r = validate(&v, &[[0, 4, 3], [4, 1, 2], [4, 2, 3]]).unwrap();
    assert_eq!(r.hull_vertices, 5);
    assert_eq!(r.triangles, 3);
}

#[test]
fn rejects_non_delaunay_edge() {
    // A kite whose short diagonal is the Delaunay one; the long one fails.
    let v = v2(&[[0., 0.], [2., -1.], [4., 0.], [2., 1.]]);
    validate(&v, &[[0, 1, 3], [1, 2, 3]]).unwrap();
    fails(
        validate(&v, &[[0, 1, 2], [0, 2, 3]]),
        "edge 0-2 is not locally Delaunay: vertex 1 (2.0, -1.0) (triangle 0) is strictly inside the circumcircle of triangle 1",
    );
}

#[test]
fn constraints_exempt_their_edge() {
    let v = v2(&[[0., 0.], [2., -1.], [4., 0.], [2., 1.]]);
    let tris = [[0, 1, 2], [0, 2, 3]];
    let r = validate_constrained(&v, &tris, &[[2, 0]]).unwrap();
    assert_eq!(r.constrained_edges, 1);
    // Duplicates and both directions count once; hull edges may be constraints too.
    let r = validate_constrained(&v, &tris, &[[0, 2], [2, 0], [0, 1]]).unwrap();
    assert_eq!(r.constrained_edges, 2);
    fails(
        validate_constrained(&v, &tris, &[[0, 1]]),
        "edge 0-2 is not locally Delaunay",
    );
}

#[test]
fn rejects_missing_constraint() {
    let v = v2(&[[0., 0.], [2., -1.], [4., 0.], [2., 1.]]);
    let tris = [[0, 1, 3], [1, 2, 3]];
    fails(
        validate_constrained(&v, &tris, &[[0, 2]]),
        "constraint vertex 0 (0.0, 0.0)-vertex 2 (4.0, 0.0) is not an edge of the mesh",
    );
    fails(
        validate_constrained(&v, &tris, &[[0, 9]]),
        "constraint 0 [0, 9]: vertex index out of range",
    );
    fails(
        validate_constrained(&v, &tris, &[[1, 3], [2, 2]]),
        "constraint 1 [2, 2] joins a vertex to itself",
    );
}

#[test]
fn euler_and_edges_on_a_fan() {
    // Centre point plus a hexagon-ish ring.
    let mut pts = vec![[0.0, 0.0]];
    for k in 0..6 {
        let a = k as f64 * std::f64::consts::PI / 3.0;
        pts.push([a.cos(), a.sin()]);
    }
    let (v, t) = spade_delaunay(&pts);
    let r = validate(&v, &t).unwrap();
    assert_eq!(
        (r.vertices, r.triangles, r.edges, r.hull_vertices),
        (7, 6, 12, 6)
    );
}

#[test]
fn local_frame_keeps_utm_coordinates_exact() {
    // Far from the origin, at 1 mm: the local frame is exact and signs are unchanged.
    let pts: Vec<[f64; 2]> = SQUARE
        .iter()
        .map(|p| [500_000.001 + p[0] * 0.001, 4_000_000.001 + p[1] * 0.001])
        .collect();
    let v = v2(&pts);
    validate(&v, &[[0, 1, 2], [0, 2, 3]]).unwrap();
    fails(validate(&v, &[[0, 2, 1], [0, 3, 2]]), "clockwise");
}

#[test]
fn spade_random_meshes_are_valid() {
    for seed in 0..30 {
        let mut r = SplitMix64::uniform(seed);
        let n = 3 + (seed as usize * 37) % 2000;
        let pts: Vec<[f64; 2]> = (0..n).map(|_| [r() * 100.0, r() * 100.0]).collect();
        let (v, t) = spade_delaunay(&pts);
        let rep = validate(&v, &t).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(rep.triangles as usize, t.len());
        assert_eq!(rep.edges, (3 * rep.triangles + rep.hull_vertices) / 2);
    }
}

#[test]
fn spade_grid_meshes_are_valid() {
    // Grids: every cell cocircular, collinear hull points on all four sides.
    for (w, h) in [(2, 2), (3, 2), (7, 5), (30, 31)] {
        let pts: Vec<[f64; 2]> = (0..w * h)
            .map(|i| [(i % w) as f64, (i / w) as f64])
            .collect();
        let (v, t) = spade_delaunay(&pts);
        let rep = validate(&v, &t).unwrap();
        assert_eq!(rep.hull_vertices, 2 * (w + h) as u64 - 4);
        assert_eq!(rep.triangles, 2 * ((w - 1) * (h - 1)) as u64);
        assert_eq!(rep.cocircular_edges, ((w - 1) * (h - 1)) as u64);
    }
}

#[test]
fn spade_cdt_meshes_are_valid() {
    for seed in 0..20 {
        let mut r = SplitMix64::uniform(seed + 100);
        let n = 10 + seed as usize * 50;
        let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> = Default::default();
        let handles: Vec<_> = (0..n)
            .map(|_| cdt.insert(Point2::new(r() * 100.0, r() * 100.0)).unwrap())
            .collect();
        for _ in 0..n / 5 {
            let a = handles[(r() * n as f64) as usize];
            let b = handles[(r() * n as f64) as usize];
            if a != b && cdt.can_add_constraint(a, b) {
                cdt.add_constraint(a, b);
            }
        }
        let constraints: Vec<[u32; 2]> = cdt
            .undirected_edges()
            .filter(|e| e.is_constraint_edge())
            .map(|e| e.vertices().map(|v| v.fix().index() as u32))
            .collect();
        let (v, t) = from_spade(&cdt);
        let rep = validate_constrained(&v, &t, &constraints)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(rep.constrained_edges as usize, constraints.len());
        // Without the constraints, some edge is usually not Delaunay.
        if seed == 19 {
            assert!(validate(&v, &t).is_err());
        }
    }
}

#[test]
fn hull_matches_brute_force() {
    // On small gridded sets (collinear runs everywhere), the hull is exactly the set of points with
    // a supporting line through them and another point, in counter-clockwise order.
    for seed in 0..200 {
        let mut r = SplitMix64::uniform(seed + 7);
        let n = 3 + seed as usize % 25;
        let mut pts: Vec<[f64; 2]> = (0..n)
            .map(|_| [(r() * 5.0).floor(), (r() * 5.0).floor()])
            .collect();
        pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        pts.dedup();
        let keys: Vec<(u64, u64, u32)> = (0..pts.len())
            .map(|i| (ordered(pts[i][0]), ordered(pts[i][1]), i as u32))
            .collect();
        let all_collinear =
            (2..pts.len()).all(|i| orient(pts[0], pts[1], pts[i]) == Orientation::Collinear);
        if pts.len() < 3 || all_collinear {
            continue;
        }
        let hull = convex_hull(&keys);
        let on_hull = |p: usize| {
            (0..pts.len()).any(|q| {
                q != p
                    && (0..pts.len())
                        .all(|s| orient(pts[p], pts[q], pts[s]) != Orientation::Clockwise)
            })
        };
        let mut want: Vec<u32> = (0..pts.len())
            .filter(|&p| on_hull(p))
            .map(|p| p as u32)
            .collect();
        let mut got = hull.clone();
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got, want, "seed {seed}: {pts:?}");
        // Counter-clockwise, never a right turn.
        for i in 0..hull.len() {
            let [a, b, c] = [0, 1, 2].map(|k| pts[hull[(i + k) % hull.len()] as usize]);
            assert_ne!(orient(a, b, c), Orientation::Clockwise, "seed {seed}");
        }
    }
}
