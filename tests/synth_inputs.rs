//! sweeptin on the synthetic inputs of `sweeptin::synth`, checked against spade.
//!
//! Where the Delaunay triangulation is unique (uniform, clustered: no four cocircular points) the
//! triangle sets must be equal. On the degenerate inputs (lidar-like, grids, rings) only the
//! number of triangles is fixed (2n − 2 − h for n distinct points, h on the hull), so the counts
//! must agree, every triangle must be strictly counter-clockwise, and the independent exact
//! validator (`sweeptin::validate`) must accept the mesh as a Delaunay triangulation.

use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use sweeptin::geom::predicates::{Orientation, orient};
use sweeptin::{Options, Triangulation, synth, triangulate};

type Key = [(u64, u64); 3];

fn sorted_keys(tris: impl Iterator<Item = [[f64; 2]; 3]>) -> Vec<Key> {
    let mut out: Vec<Key> = tris
        .map(|t| {
            let mut k = t.map(|p| (p[0].to_bits(), p[1].to_bits()));
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

fn ours(t: &Triangulation) -> Vec<Key> {
    sorted_keys(t.triangles.iter().map(|tri| {
        tri.map(|i| {
            let v = t.vertices[i as usize];
            [v[0], v[1]]
        })
    }))
}

fn spade(pts: &[[f64; 3]]) -> Vec<Key> {
    let v: Vec<Point2<f64>> = pts.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let d = DelaunayTriangulation::<Point2<f64>>::bulk_load(v).unwrap();
    sorted_keys(
        d.inner_faces()
            .map(|f| f.vertices().map(|v| [v.position().x, v.position().y])),
    )
}

fn all_ccw(t: &Triangulation) {
    for tri in &t.triangles {
        let [a, b, c] = tri.map(|i| {
            let v = t.vertices[i as usize];
            [v[0], v[1]]
        });
        assert_eq!(orient(a, b, c), Orientation::CounterClockwise, "{tri:?}");
    }
}

#[test]
fn unique_delaunay_inputs_match_spade() {
    for (name, pts) in [
        ("uniform", synth::uniform(20_000, 1)),
        ("clustered", synth::clustered(20_000, 2)),
    ] {
        let t = triangulate(&pts, &Options::default()).unwrap();
        all_ccw(&t);
        assert_eq!(ours(&t), spade(&pts), "{name}");
    }
}

#[test]
fn degenerate_inputs_match_spade_counts() {
    for (name, pts) in [
        ("lidar_like", synth::lidar_like(30_000, 3)),
        ("grid", synth::grid(60, 40, 0.5)),
        ("tilted_grid", synth::tilted_grid(50, 50, 0.7, 0.3)),
        ("ring", synth::ring(64, 25.0)),
    ] {
        let t = triangulate(&pts, &Options::default()).unwrap();
        all_ccw(&t);
        let r = sweeptin::validate::validate(&t.vertices, &t.triangles)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(r.triangles as usize, t.triangles.len(), "{name}");
        assert_eq!(t.triangles.len(), spade(&pts).len(), "{name}");
        assert_eq!(
            t.vertices.len() as u64 + t.duplicates,
            pts.len() as u64,
            "{name}"
        );
    }
}
