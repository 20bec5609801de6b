//! From input files to finalised triangles, delivered to sinks.
//!
//! PROVISIONAL: this first version reads everything into memory and runs the in-memory
//! triangulation; the streaming pipeline (external sort → streaming sweep) replaces the body of
//! [`run`] with the same signature.

use crate::error::{Error, Result};
use crate::io::sink::MeshSink;
use crate::lidar::{Crs, Filter, LidarReader};
use crate::points::DuplicatePolicy;
use std::path::PathBuf;

/// What to triangulate.
#[derive(Clone, Debug)]
pub struct Input {
    /// Point files: LAS/LAZ (by extension `.las`/`.laz`) or XYZ text; several files form one set.
    pub paths: Vec<PathBuf>,
    /// LAS/LAZ filters (ignored for XYZ).
    pub filter: Filter,
    /// Which point survives among exact (x, y) duplicates.
    pub duplicates: DuplicatePolicy,
}

/// Facts about the data, given to every sink before the first triangle.
#[derive(Clone, Debug, Default)]
pub struct StreamInfo {
    /// Coordinate reference system of the input, when known.
    pub crs: Option<Crs>,
    /// Real-world extent of the points: `[xmin, ymin, xmax, ymax]`.
    pub bounds: [f64; 4],
}

/// A consumer of final triangles (DEM, contours, volumes, …).
///
/// Triangles arrive roughly in increasing `y`, in real-world coordinates `[x, y, z]`,
/// counter-clockwise in (x, y). [`TriangleSink::watermark`] is a *hint*: later triangles normally lie
/// entirely at `y >= watermark`, so a sink may flush what lies below; but a few triangles can still
/// arrive *late* (long thin triangles along the convex hull, whose circumcircles are too large to
/// finalise early), and every sink must handle a late triangle correctly.
pub trait TriangleSink {
    /// Called once before the first triangle.
    fn begin(&mut self, info: &StreamInfo) -> Result<()>;
    /// One final triangle.
    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()>;
    /// Progress hint (see the trait docs).
    fn watermark(&mut self, _y: f64) -> Result<()> {
        Ok(())
    }
    /// Called once after the last triangle; returns a machine-readable summary.
    fn finish(&mut self) -> Result<serde_json::Value>;
}

/// What a run did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunSummary {
    /// Points read (after filters).
    pub points_read: u64,
    /// Points triangulated (after merging duplicates).
    pub points_kept: u64,
    /// Exact (x, y) duplicates merged away.
    pub duplicates: u64,
    /// Triangles delivered.
    pub triangles: u64,
}

fn is_lidar(p: &std::path::Path) -> bool {
    matches!(
        p.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()),
        Some(e) if e == "las" || e == "laz"
    )
}

/// Reads all points of `input` in real-world coordinates, with the CRS when known.
pub fn read_points(input: &Input) -> Result<(Vec<[f64; 3]>, Option<Crs>)> {
    if input.paths.is_empty() {
        return Err(Error::NoInput);
    }
    if input.paths.iter().all(|p| is_lidar(p)) {
        let mut r = LidarReader::open(&input.paths, &input.filter)?;
        let pts = r.read_all()?;
        let q = *r.quantization();
        let crs = r.crs().cloned();
        Ok((pts.iter().map(|p| q.to_world(p)).collect(), crs))
    } else {
        let mut all = Vec::new();
        for p in &input.paths {
            all.extend(crate::io::xyz::read_xyz(p)?);
        }
        Ok((all, None))
    }
}

/// Triangulates `input` and delivers the result to `mesh` (if any) and every sink.
///
/// # Errors
/// Any reader, triangulation or sink error.
pub fn run(
    input: &Input,
    mesh: Option<&mut dyn MeshSink>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<RunSummary> {
    let (points, crs) = read_points(input)?;
    let mut bounds = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in &points {
        bounds[0] = bounds[0].min(p[0]);
        bounds[1] = bounds[1].min(p[1]);
        bounds[2] = bounds[2].max(p[0]);
        bounds[3] = bounds[3].max(p[1]);
    }
    let tin = crate::triangulate(
        &points,
        &crate::Options {
            duplicates: input.duplicates,
        },
    )?;
    let info = StreamInfo { crs, bounds };
    for s in sinks.iter_mut() {
        s.begin(&info)?;
    }
    if let Some(m) = mesh {
        for v in &tin.vertices {
            m.vertex(*v)?;
        }
        for t in &tin.triangles {
            m.triangle(t.map(u64::from))?;
        }
    }
    for t in &tin.triangles {
        let tri = t.map(|i| tin.vertices[i as usize]);
        for s in sinks.iter_mut() {
            s.triangle(&tri)?;
        }
    }
    Ok(RunSummary {
        points_read: points.len() as u64,
        points_kept: tin.vertices.len() as u64,
        duplicates: tin.duplicates,
        triangles: tin.triangles.len() as u64,
    })
}
