//! Measures XYZ reading speed: `cargo run --release --example xyz_throughput -- FILE.xyz`.
//! Reads the file twice with the chunked reader (1 Mi points per chunk) and once with
//! `read_xyz`, and prints MB/s and points/s for each pass.

use std::time::Instant;
use sweeptin::input::{XyzReader, read_xyz};

fn main() -> sweeptin::Result<()> {
    let path = std::env::args()
        .nth(1)
        .expect("usage: xyz_throughput FILE.xyz");
    let bytes = std::fs::metadata(&path)
        .map_err(|e| sweeptin::Error::io(&path, e))?
        .len();
    let report = |what: &str, points: usize, secs: f64| {
        println!(
            "{what}: {points} points, {:.1} MB in {secs:.2} s: {:.0} MB/s, {:.1} M points/s",
            bytes as f64 / 1e6,
            bytes as f64 / 1e6 / secs,
            points as f64 / 1e6 / secs
        );
    };
    for pass in 1..=2 {
        let t = Instant::now();
        let mut reader = XyzReader::open(&path)?;
        let mut chunk = Vec::with_capacity(1 << 20);
        let mut total = 0;
        let mut checksum = 0.0;
        loop {
            chunk.clear();
            let n = reader.read_chunk(&mut chunk, 1 << 20)?;
            if n == 0 {
                break;
            }
            total += n;
            checksum += chunk[n - 1][2];
        }
        report(
            &format!("chunked pass {pass} (checksum {checksum})"),
            total,
            t.elapsed().as_secs_f64(),
        );
    }
    let t = Instant::now();
    let all = read_xyz(&path)?;
    report("read_xyz", all.len(), t.elapsed().as_secs_f64());
    Ok(())
}
