//! Dev tool: classify ground in LAS/LAZ files and write the new classes as raw bytes, one per
//! point in global input order (for `scripts/ground_accuracy.py` before/without the writer).
//!
//! cargo run --example ground_classes -- OUT.bin FILES... [--step S] [--max-distance D]
//!     [--max-angle A] [--low-noise L] [--no-mirror] [--mem BYTES]

use std::io::Write;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().ok_or("usage: OUT.bin FILES...")?);
    let mut params = sweeptin::ground::GroundParams::default();
    let mut files = Vec::new();
    let mut mem: u64 = 1 << 30;
    while let Some(a) = args.next() {
        let mut num = || -> Result<f64, Box<dyn std::error::Error>> {
            Ok(args.next().ok_or("missing value")?.parse()?)
        };
        match a.as_str() {
            "--step" => params.step = num()?,
            "--max-distance" => params.max_distance = num()?,
            "--max-angle" => params.max_angle = num()?,
            "--low-noise" => params.low_noise = num()?,
            "--offset" => params.offset = num()?,
            "--mem" => mem = num()? as u64,
            "--no-mirror" => params.mirror = false,
            _ => files.push(PathBuf::from(a)),
        }
    }
    let t = std::time::Instant::now();
    let (mut store, summary) = sweeptin::ground::classify_files(
        &files,
        &params,
        mem,
        &std::env::temp_dir(),
        &mut |_, _, _| {},
    )?;
    let mut bytes = Vec::with_capacity(store.len() as usize);
    for i in 0..store.len() {
        bytes.push(store.get(i)?);
    }
    std::fs::File::create(&out)?.write_all(&bytes)?;
    eprintln!(
        "{} points, {} ground, {} low noise, {} blocks, {:.2} s ({:.2} read, {:.2} classify), {} iterations",
        summary.points,
        summary.ground,
        summary.low_noise,
        summary.blocks,
        t.elapsed().as_secs_f64(),
        summary.read_seconds,
        summary.classify_seconds,
        summary.iterations
    );
    Ok(())
}
