//! The in-memory API: an exact Delaunay triangulation of a few points, checked by the
//! independent validator, then a constrained one with a breakline.
//!
//! ```sh
//! cargo run --example triangulate_points
//! ```

use sweeptin::{Options, triangulate, triangulate_cdt};

fn main() -> sweeptin::Result<()> {
    // A 4 × 4 lattice: every square is cocircular, and the tie rule decides the diagonals, the
    // same way every time.
    let mut points = Vec::new();
    for y in 0..4 {
        for x in 0..4 {
            points.push([f64::from(x), f64::from(y), f64::from(x * y)]);
        }
    }
    let tin = triangulate(&points, &Options::default())?;
    sweeptin::validate::validate(&tin.vertices, &tin.triangles)?;
    println!(
        "{} vertices, {} triangles",
        tin.vertices.len(),
        tin.triangles.len()
    );
    for t in tin.triangles.iter().take(4) {
        println!("  triangle {t:?}");
    }
    // A breakline from corner to corner: its segments become edges of the triangulation.
    let cdt = triangulate_cdt(&points, &[[0, 15]], &Options::default())?;
    println!("with a breakline: {} triangles", cdt.triangles.len());
    Ok(())
}
