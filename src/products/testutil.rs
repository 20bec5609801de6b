//! Test helpers: small TINs, and feeding them to a sink in sweep order or shuffled with late
//! triangles (the two orders every product must treat alike).

use crate::geom::rng::SplitMix64;
use crate::sink::{ProductSummary, StreamInfo, TriangleSink};
use std::path::Path;

/// A triangle and, optionally, a watermark to give after it.
pub type Step = ([[f64; 3]; 3], Option<f64>);

/// The TIN of a regular `nx × ny` grid of squares of side `h` from the origin, each square split
/// along its anti-diagonal; `z = f(x, y)`.
pub fn grid_tin(nx: usize, ny: usize, h: f64, f: impl Fn(f64, f64) -> f64) -> Vec<[[f64; 3]; 3]> {
    let p = |i: usize, j: usize| {
        let (x, y) = (i as f64 * h, j as f64 * h);
        [x, y, f(x, y)]
    };
    let mut out = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            out.push([p(i, j), p(i + 1, j), p(i, j + 1)]);
            out.push([p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    out
}

/// The Delaunay TIN of `n` random points in `[0, size]²` plus the four corners; `z = f(x, y)`.
pub fn random_tin(
    n: usize,
    size: f64,
    seed: u64,
    f: impl Fn(f64, f64) -> f64,
) -> Vec<[[f64; 3]; 3]> {
    let mut r = SplitMix64::new(seed);
    let mut pts: Vec<[f64; 3]> = [[0.0, 0.0], [size, 0.0], [0.0, size], [size, size]]
        .iter()
        .map(|&[x, y]| [x, y, f(x, y)])
        .collect();
    for _ in 0..n {
        let (x, y) = (r.next_f64() * size, r.next_f64() * size);
        pts.push([x, y, f(x, y)]);
    }
    let tin = crate::triangulate(&pts, &crate::Options::default()).unwrap();
    tin.triangles
        .iter()
        .map(|t| t.map(|i| tin.vertices[i as usize]))
        .collect()
}

/// As [`random_tin`], with points every unit along the square's sides, so that no triangle is
/// long and thin along the hull (the sweep-order watermarks then advance steadily).
pub fn random_tin_framed(
    n: usize,
    size: f64,
    seed: u64,
    f: impl Fn(f64, f64) -> f64,
) -> Vec<[[f64; 3]; 3]> {
    let mut r = SplitMix64::new(seed);
    let mut pts = Vec::new();
    let steps = size as usize;
    for i in 0..steps {
        let t = i as f64;
        for (x, y) in [(t, 0.0), (size, t), (size - t, size), (0.0, size - t)] {
            pts.push([x, y, f(x, y)]);
        }
    }
    for _ in 0..n {
        let (x, y) = (r.next_f64() * size, r.next_f64() * size);
        pts.push([x, y, f(x, y)]);
    }
    let tin = crate::triangulate(&pts, &crate::Options::default()).unwrap();
    tin.triangles
        .iter()
        .map(|t| t.map(|i| tin.vertices[i as usize]))
        .collect()
}

fn ymin(t: &[[f64; 3]; 3]) -> f64 {
    t[0][1].min(t[1][1]).min(t[2][1])
}

fn ymax(t: &[[f64; 3]; 3]) -> f64 {
    t[0][1].max(t[1][1]).max(t[2][1])
}

/// Watermarks for a sequence: after step `i`, the smallest `ymin` of the later triangles that are
/// not `late` (so late ones break the hint, as the real stream's hull triangles may).
fn with_watermarks(tris: Vec<[[f64; 3]; 3]>, late: &[bool]) -> Vec<Step> {
    let n = tris.len();
    let mut suffix = vec![f64::INFINITY; n + 1];
    for i in (0..n).rev() {
        suffix[i] = if late[i] {
            suffix[i + 1]
        } else {
            suffix[i + 1].min(ymin(&tris[i]))
        };
    }
    tris.into_iter()
        .enumerate()
        .map(|(i, t)| {
            let w = suffix[i + 1];
            (t, w.is_finite().then_some(w))
        })
        .collect()
}

/// Sorted by `ymax` (as the sweep finalises them), with exact watermarks after every triangle.
pub fn in_sweep_order(tris: &[[[f64; 3]; 3]]) -> Vec<Step> {
    let mut v = tris.to_vec();
    v.sort_by(|a, b| ymax(a).total_cmp(&ymax(b)));
    let late = vec![false; v.len()];
    with_watermarks(v, &late)
}

/// Sweep order disturbed: vertices rotated at random, neighbours swapped, and about one triangle
/// in eight held back and delivered late, after watermarks above it.
pub fn shuffled_with_watermarks(tris: &[[[f64; 3]; 3]], seed: u64) -> Vec<Step> {
    let mut r = SplitMix64::new(seed);
    let mut v = tris.to_vec();
    v.sort_by(|a, b| ymax(a).total_cmp(&ymax(b)));
    for t in &mut v {
        t.rotate_left((r.next_u64() % 3) as usize);
    }
    for i in 1..v.len() {
        if r.next_u64().is_multiple_of(3) {
            v.swap(i - 1, i);
        }
    }
    let mut normal = Vec::new();
    let mut held = Vec::new();
    for t in v {
        if r.next_u64().is_multiple_of(8) {
            held.push(t);
        } else {
            normal.push(t);
        }
    }
    // Re-insert each held triangle at a random later place.
    let mut out: Vec<[[f64; 3]; 3]> = Vec::new();
    let mut late = Vec::new();
    let n = normal.len();
    let mut inserts: Vec<(usize, [[f64; 3]; 3])> = held
        .into_iter()
        .map(|t| ((r.next_u64() as usize) % (n + 1), t))
        .collect();
    inserts.sort_by_key(|x| x.0);
    let mut k = 0;
    for (i, t) in normal.into_iter().enumerate() {
        while k < inserts.len() && inserts[k].0 <= i {
            out.push(inserts[k].1);
            late.push(true);
            k += 1;
        }
        out.push(t);
        late.push(false);
    }
    for (_, t) in &inserts[k..] {
        out.push(*t);
        late.push(true);
    }
    with_watermarks(out, &late)
}

/// begin, every step, finish.
pub fn feed(sink: &mut dyn TriangleSink, info: &StreamInfo, steps: &[Step]) -> ProductSummary {
    sink.begin(info).unwrap();
    for (t, w) in steps {
        sink.triangle(t).unwrap();
        if let Some(w) = w {
            sink.watermark(*w).unwrap();
        }
    }
    sink.finish().unwrap()
}

/// `(cols, rows, values)` of a float32 TIFF.
pub fn read_tiff(path: &Path) -> (u32, u32, Vec<f32>) {
    let f = std::fs::File::open(path).unwrap();
    let mut d = tiff::decoder::Decoder::new(std::io::BufReader::new(f)).unwrap();
    let (w, h) = d.dimensions().unwrap();
    match d.read_image().unwrap() {
        tiff::decoder::DecodingResult::F32(v) => (w, h, v),
        _ => panic!("not float32"),
    }
}
