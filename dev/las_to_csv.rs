//! Writes the points of LAS/LAZ files as `x,y,z` CSV (with a header), for peers that cannot read
//! LAS themselves (`gdal_grid` without the PDAL plugin). Used by `scripts/bench-products.sh`.
//!
//! `cargo run --release --example las_to_csv -- [--class 2] OUT.csv FILE...`

use std::io::Write;
use sweeptin::input::las::{Filter, LidarReader, parse_classes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut filter = Filter::default();
    let mut rest = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--class" => filter.classes = Some(parse_classes(&args.next().ok_or("--class L")?)?),
            _ => rest.push(a),
        }
    }
    let (out, files) = rest
        .split_first()
        .ok_or("usage: las_to_csv [--class L] OUT FILE...")?;
    let mut reader = LidarReader::open(files, &filter)?;
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(out)?);
    writeln!(w, "x,y,z")?;
    let mut chunk = Vec::with_capacity(1 << 20);
    let mut n = 0u64;
    while reader.read_chunk(&mut chunk, 1 << 20)? > 0 {
        for p in &chunk {
            let [x, y, z] = [p.x, p.y, p.z];
            writeln!(w, "{x},{y},{z}")?;
        }
        n += chunk.len() as u64;
        chunk.clear();
    }
    w.flush()?;
    eprintln!("las_to_csv: {n} points -> {out}");
    Ok(())
}
