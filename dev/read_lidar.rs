//! Reads LAS/LAZ files with `sweeptin::input::las::LidarReader` and reports the throughput.
//!
//! `cargo run --release --example read_lidar -- [--serial] [--no-index] [--batch N] [--class 2]
//! [--bbox XMIN,YMIN,XMAX,YMAX] FILE...`

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
            "--no-index" => options.copc_index = false,
            "--bbox" => filter.bbox = Some(args.next().ok_or("--bbox B")?.parse()?),
            "--batch" => options.batch_points = args.next().ok_or("--batch N")?.parse()?,
            "--class" => filter.classes = Some(parse_classes(&args.next().ok_or("--class L")?)?),
            _ => files.push(a),
        }
    }
    let start = Instant::now();
    let mut reader = LidarReader::open_with(&files, &filter, options.clone())?;
    let mut chunk = Vec::with_capacity(1 << 20);
    let mut checksum = 0f64;
    while reader.read_chunk(&mut chunk, 1 << 20)? > 0 {
        checksum = chunk.iter().fold(checksum, |s, p| s + p.z);
        chunk.clear();
    }
    let secs = start.elapsed().as_secs_f64();
    let stats = reader.stats();
    println!(
        "{} points read, {} kept, {} skipped in {secs:.3} s: {:.2} M points/s (parallel: {}, batch: {}, checksum {checksum:.3})",
        stats.read,
        stats.kept,
        stats.skipped,
        stats.read as f64 / secs / 1e6,
        options.parallel,
        options.batch_points
    );
    Ok(())
}
