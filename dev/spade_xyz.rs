//! The in-core yardstick of the memory benchmark (`scripts/bench-memory.sh`): reads an XYZ file
//! with sweeptin's reader and bulk-loads its points into spade's Delaunay triangulation.
//! `cargo run --release --example spade_xyz -- FILE.xyz` prints one line,
//! `points triangles load_seconds triangulate_seconds` (peak memory is measured from outside).

use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .ok_or_else(|| anyhow::anyhow!("usage: spade_xyz FILE.xyz"))?;
    let t = Instant::now();
    let pts = sweeptin::input::read_xyz(&path)?;
    let load = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let xy: Vec<Point2<f64>> = pts.iter().map(|p| Point2::new(p[0], p[1])).collect();
    drop(pts);
    let d: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::bulk_load(xy)?;
    let secs = t.elapsed().as_secs_f64();
    println!(
        "{} {} {load:.3} {secs:.3}",
        d.num_vertices(),
        d.num_inner_faces()
    );
    Ok(())
}
