use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use sweeptin::points::{DuplicatePolicy, prepare};
use sweeptin::sweep::Sweep;
use sweeptin::{Options, triangulate};

fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed.wrapping_mul(0x9E3779B97F4A7C15) | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn tri_set(tris: &[[u32; 3]], verts: &[[f64; 3]]) -> Vec<[(u64, u64); 3]> {
    let mut out: Vec<[(u64, u64); 3]> = tris
        .iter()
        .map(|t| {
            let mut k = t.map(|i| (verts[i as usize][0].to_bits(), verts[i as usize][1].to_bits()));
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
    let mut out: Vec<[(u64, u64); 3]> = d
        .inner_faces()
        .map(|f| {
            let mut k = f.vertices().map(|v| (v.position().x.to_bits(), v.position().y.to_bits()));
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

#[test]
fn stepwise_check_small() {
    for seed in 0..300 {
        let mut r = rng(seed);
        let n = 3 + (seed as usize % 40);
        let pts: Vec<[f64; 3]> = (0..n).map(|_| [r(), r(), 0.0]).collect();
        let prep = prepare(&pts, DuplicatePolicy::First).unwrap();
        let mut s = Sweep::new(prep.xy).unwrap();
        s.check().unwrap_or_else(|e| panic!("seed {seed} init: {e}"));
        let mut k = 0;
        while s.step() {
            k += 1;
            s.check().unwrap_or_else(|e| panic!("seed {seed} step {k}: {e}"));
        }
        let (tris, _, _) = s.finish();
        let t = triangulate(&pts, &Options::default()).unwrap();
        assert_eq!(tris.len(), t.triangles.len());
        assert_eq!(tri_set(&t.triangles, &t.vertices), spade_set(&pts), "seed {seed}");
    }
}

#[test]
fn matches_spade_random() {
    for seed in 0..20 {
        let mut r = rng(seed + 1000);
        let n = 20000;
        let pts: Vec<[f64; 3]> = (0..n).map(|_| [r() * 1000.0, r() * 1000.0, 0.0]).collect();
        let t = triangulate(&pts, &Options::default()).unwrap();
        assert_eq!(tri_set(&t.triangles, &t.vertices), spade_set(&pts), "seed {seed}");
    }
}
