//! The saddle experiment of Herva (2009), chapter 7.3: the surface
//! `z = 15 sin(πx/20) − 15 sin(πy/20)` on [0, 100]², sampled at N points of which 400 lie on the
//! boundary one unit apart (so the convex hull is the square), triangulated, and compared with the
//! exact surface: volume against z = 0 (exactly 0), volume difference against a second surface
//! `z + 5(x − 50)` sampled independently (exactly 0), and the height error at random points.
//!
//! Shared by `tests/products_accuracy.rs` and `examples/saddle_accuracy.rs`.

use std::f64::consts::PI;
use sweeptin::products::geom::{Location, Tri};
use sweeptin::products::overlay::{BandStore, OverlaySink};
use sweeptin::products::volume::VolumeSink;
use sweeptin::sink::{StreamInfo, TriangleSink};
use sweeptin::synth::SplitMix64;

/// The thesis's reference surface.
pub fn saddle(x: f64, y: f64) -> f64 {
    15.0 * (PI * x / 20.0).sin() - 15.0 * (PI * y / 20.0).sin()
}

/// The second surface of table 7.3.
pub fn tilted(x: f64, y: f64) -> f64 {
    saddle(x, y) + 5.0 * (x - 50.0)
}

/// N points: the 400 boundary points, then N − 400 uniform random ones; `z = f(x, y)`.
pub fn points(n: usize, seed: u64, f: fn(f64, f64) -> f64) -> Vec<[f64; 3]> {
    let mut pts = Vec::with_capacity(n);
    for i in 0..100 {
        let i = f64::from(i);
        for (x, y) in [(i, 0.0), (100.0, i), (100.0 - i, 100.0), (0.0, 100.0 - i)] {
            pts.push([x, y, f(x, y)]);
        }
    }
    let mut r = SplitMix64::new(seed);
    while pts.len() < n {
        let (x, y) = (r.next_f64() * 100.0, r.next_f64() * 100.0);
        pts.push([x, y, f(x, y)]);
    }
    pts
}

/// The TIN's triangles.
pub fn tin(pts: &[[f64; 3]]) -> Vec<[[f64; 3]; 3]> {
    let t = sweeptin::triangulate(pts, &sweeptin::Options::default()).unwrap();
    t.triangles
        .iter()
        .map(|tr| tr.map(|i| t.vertices[i as usize]))
        .collect()
}

fn info() -> StreamInfo {
    StreamInfo {
        crs: None,
        bounds: [0.0, 0.0, 100.0, 100.0],
    }
}

fn feed(sink: &mut dyn TriangleSink, tris: &[[[f64; 3]; 3]]) -> sweeptin::sink::ProductSummary {
    sink.begin(&info()).unwrap();
    for t in tris {
        sink.triangle(t).unwrap();
    }
    sink.finish().unwrap()
}

/// Net volume of the TIN against z = 0 (table 7.2: exactly 0 for the surface).
pub fn volume(tris: &[[[f64; 3]; 3]]) -> f64 {
    let mut s = VolumeSink::new(0.0, None).unwrap();
    feed(&mut s, tris);
    s.totals().net_volume
}

/// Net volume of `surface` against `reference` through the banded overlay (table 7.3).
pub fn volume_difference(surface: &[[[f64; 3]; 3]], reference: &[[[f64; 3]; 3]]) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let mut store = BandStore::new(dir.path(), 128);
    feed(&mut store, reference);
    let mut o = OverlaySink::new(store.into_reader().unwrap(), None, usize::MAX);
    feed(&mut o, surface);
    o.totals().net_volume
}

/// `(average, maximum)` absolute height error of the TIN at `count` random points.
pub fn interpolation_error(tris: &[[[f64; 3]; 3]], count: usize, seed: u64) -> (f64, f64) {
    // Triangles by 1 × 1 cell.
    let mut grid: Vec<Vec<Tri>> = vec![Vec::new(); 100 * 100];
    for t in tris.iter().filter_map(Tri::new) {
        let [x0, y0, x1, y1] = t.bbox();
        let c = |v: f64| (v.floor() as usize).min(99);
        for cy in c(y0)..=c(y1) {
            for cx in c(x0)..=c(x1) {
                grid[cy * 100 + cx].push(t);
            }
        }
    }
    let mut r = SplitMix64::new(seed);
    let (mut sum, mut max) = (0.0, 0.0f64);
    for _ in 0..count {
        let p = [r.next_f64() * 100.0, r.next_f64() * 100.0];
        let cell = &grid[(p[1] as usize).min(99) * 100 + (p[0] as usize).min(99)];
        let z = cell
            .iter()
            .find_map(|t| {
                let loc = t.locate(p);
                (loc != Location::Outside).then(|| t.value_at(p, loc))
            })
            .expect("the hull is the square");
        let e = (z - saddle(p[0], p[1])).abs();
        sum += e;
        max = max.max(e);
    }
    (sum / count as f64, max)
}
