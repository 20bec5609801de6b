//! Reads LAS/LAZ files with `sweeptin::input::las::LidarReader` and reports the throughput.
//!
//! `cargo run --release --example read_lidar -- [--serial] [--batch N] [--class 2] FILE...`

use std::time::Instant;
use sweeptin::input::las::{Filter, LidarReader, ReadOptions, parse_classes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut options = ReadOptions::default();
    let mut filter = Filter::default();
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--serial" => options.parallel = false,
            "--batch" => options.batch_points = args.next().ok_or("--batch N")?.parse()?,
            "--class" => filter.classes = Some(parse_classes(&args.next().ok_or("--class L")?)?),
            _ => files.push(a),
        }
    }
    let start = Instant::now();
    let mut reader = LidarReader::open_with(&files, &filter, options)?;
    let mut chunk = Vec::with_capacity(1 << 20);
    let mut checksum = 0i64;
    while reader.read_chunk(&mut chunk, 1 << 20)? > 0 {
        checksum = chunk
            .iter()
            .fold(checksum, |s, p| s.wrapping_add(i64::from(p.z)));
        chunk.clear();
    }
    let secs = start.elapsed().as_secs_f64();
    let stats = reader.stats();
    println!(
        "{} points read, {} kept in {secs:.3} s: {:.2} M points/s (parallel: {}, batch: {}, checksum {checksum})",
        stats.read,
        stats.kept,
        stats.read as f64 / secs / 1e6,
        options.parallel,
        options.batch_points
    );
    Ok(())
}
