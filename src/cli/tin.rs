//! `sweeptin tin`: points in, Delaunay TIN out.

use anyhow::Context;
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::io::{MeshFormat, MeshMeta, create_mesh_sink, read_xyz};

/// Arguments of `sweeptin tin`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input points: XYZ text (`x y z` per line, separated by commas, semicolons, tabs or spaces;
    /// `#` comments and one header line allowed; extra columns ignored).
    pub input: PathBuf,
    /// Output mesh: .ply (binary PLY), .obj (Wavefront OBJ) or .xml (LandXML 1.2).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output format, when the extension does not say it.
    #[arg(long, value_enum)]
    pub format: Option<MeshFormat>,
    /// Coordinate reference system recorded in the output (`EPSG:xxxx` or WKT).
    #[arg(long)]
    pub crs: Option<String>,
    /// Which point survives among exact (x, y) duplicates.
    #[arg(long, value_enum, default_value_t = sweeptin::DuplicatePolicy::First)]
    pub duplicates: sweeptin::DuplicatePolicy,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let meta = MeshMeta {
        crs: args.crs.clone(),
        comments: vec![format!("from {}", args.input.display())],
    };
    // Open the output first: a bad output path fails before any heavy work, and the temporary
    // file is removed on every error below.
    let mut sink = create_mesh_sink(&args.output, args.format, &meta)?;
    let points = read_xyz(&args.input)?;
    let options = sweeptin::Options {
        duplicates: args.duplicates,
    };
    let tin = sweeptin::triangulate(&points, &options)
        .with_context(|| format!("cannot triangulate {}", args.input.display()))?;
    for &v in &tin.vertices {
        sink.vertex(v)?;
    }
    for t in &tin.triangles {
        sink.triangle(t.map(u64::from))?;
    }
    let summary = sink.finish()?;
    let format = args
        .format
        .or_else(|| MeshFormat::from_extension(&args.output))
        .map_or("mesh", MeshFormat::name);
    eprintln!(
        "sweeptin: {} points ({} duplicates merged) -> {}: {} vertices, {} triangles, {} {} in {:.2} s",
        points.len(),
        tin.duplicates,
        args.output.display(),
        summary.vertices,
        summary.triangles,
        human_bytes(summary.bytes),
        format,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `1536` → `1.5 KiB`.
fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = bytes as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{v:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn human_bytes() {
        assert_eq!(super::human_bytes(12), "12 B");
        assert_eq!(super::human_bytes(1536), "1.5 KiB");
        assert_eq!(super::human_bytes(5 << 30), "5.0 GiB");
    }
}
