//! Dumps a grid (GeoTIFF or ESRI ASCII) as raw little-endian `f64`, row-major, missing cells NaN,
//! for the peer benchmarks (`scripts/bench-simplify.sh`). Prints `cols rows` on stdout.
//!
//! `cargo run --release --example dem_to_raw -- in.tif out.f64`

use std::io::Write;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(args.len() == 3, "usage: dem_to_raw IN OUT");
    let mut r = sweeptin::input::raster::RasterReader::open(&args[1])?;
    let (cols, rows) = (r.spec().cols, r.spec().rows);
    let h = r.read_all()?;
    let mut out = std::io::BufWriter::new(std::fs::File::create(&args[2])?);
    for v in h {
        out.write_all(&v.to_le_bytes())?;
    }
    out.flush()?;
    println!("{cols} {rows}");
    Ok(())
}
