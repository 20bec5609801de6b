use std::time::Instant;
fn main() {
    let n: usize = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(1_000_000);
    let mut s: u64 = 0x9E3779B97F4A7C15;
    let mut r = move || { s ^= s << 13; s ^= s >> 7; s ^= s << 17; (s >> 11) as f64 / (1u64 << 53) as f64 };
    let pts: Vec<[f64; 3]> = (0..n).map(|_| [r() * 1000.0, r() * 1000.0, 0.0]).collect();
    let t0 = Instant::now();
    let prep = sweeptin::points::prepare(&pts, Default::default()).unwrap();
    let t1 = Instant::now();
    let mut sw = sweeptin::sweep::Sweep::new(prep.xy).unwrap();
    sw.run();
    let t2 = Instant::now();
    let st = sw.stats();
    let (tris, _, _) = sw.finish();
    let t3 = Instant::now();
    println!("n={n} prep {:.3}s sweep {:.3}s finish {:.3}s total {:.3}s tris {} {:?}", (t1-t0).as_secs_f64(), (t2-t1).as_secs_f64(), (t3-t2).as_secs_f64(), (t3-t0).as_secs_f64(), tris.len(), st);
}
