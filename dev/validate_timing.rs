//! Times the validator on a uniform random triangulation: `cargo run --release --example
//! validate_timing -- 1000000`.
use std::time::Instant;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("a point count"))
        .unwrap_or(1_000_000);
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut r = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<[f64; 3]> = (0..n).map(|_| [r() * 1000.0, r() * 1000.0, 0.0]).collect();
    let t0 = Instant::now();
    let tin = sweeptin::triangulate(&pts, &sweeptin::Options::default()).expect("triangulate");
    let t1 = Instant::now();
    let report = sweeptin::validate::validate(&tin.vertices, &tin.triangles).expect("valid");
    let t2 = Instant::now();
    println!(
        "n={n} triangulate {:.3}s validate {:.3}s threads {} {report:?}",
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        rayon::current_num_threads()
    );
}
