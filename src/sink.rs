//! Where final triangles go: push-style sinks. [`MeshSink`] takes numbered vertices and triangles
//! (the mesh writers in [`crate::output`]); [`TriangleSink`] takes triangles with their
//! coordinates (the terrain products in [`crate::products`]).

use crate::crs::Crs;
use crate::error::Result;

/// A streaming mesh writer.
///
/// Vertices are numbered 0, 1, 2, … in the order they are pushed; a triangle refers only to
/// vertices already pushed. Vertex and triangle calls may interleave (streaming). Nothing appears
/// under the output path until [`finish`](MeshSink::finish) succeeds; dropping a sink without
/// finishing leaves no file behind.
pub trait MeshSink {
    /// Appends a vertex `[x, y, z]`.
    ///
    /// # Errors
    /// [`crate::Error::Output`] for a non-finite coordinate or after `finish`; [`crate::Error::Io`] if writing
    /// fails.
    fn vertex(&mut self, p: [f64; 3]) -> Result<()>;

    /// Appends a triangle of vertex numbers (counter-clockwise in `x, y` by convention).
    ///
    /// # Errors
    /// [`crate::Error::Output`] if a vertex number has not been pushed yet, exceeds what the format can
    /// store, or after `finish`; [`crate::Error::Io`] if writing fails.
    fn triangle(&mut self, t: [u64; 3]) -> Result<()>;

    /// No later triangle refers to vertex `id`. Only the streaming-mesh format records this; other
    /// writers ignore it.
    ///
    /// # Errors
    /// As [`MeshSink::triangle`].
    fn vertex_done(&mut self, _id: u64) -> Result<()> {
        Ok(())
    }

    /// Later triangles normally lie at `y >= y` (see [`TriangleSink`]). Only the
    /// streaming-mesh format records this; other writers ignore it.
    ///
    /// # Errors
    /// As [`MeshSink::triangle`].
    fn watermark(&mut self, _y: f64) -> Result<()> {
        Ok(())
    }

    /// Does this format keep the watermarks (so that whoever reads it back relies on them, and
    /// the sweep must run along y)? Only the streaming-mesh format does.
    fn keeps_watermarks(&self) -> bool {
        false
    }

    /// Writes everything out and renames into place; reports errors instead of hiding them in Drop.
    ///
    /// # Errors
    /// [`crate::Error::Io`] naming the output if writing, syncing or renaming fails; [`crate::Error::Output`] if
    /// called twice.
    fn finish(&mut self) -> Result<MeshSummary>;
}

/// What a finished [`MeshSink`] wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshSummary {
    /// Vertices written.
    pub vertices: u64,
    /// Triangles written.
    pub triangles: u64,
    /// Size of the output file in bytes.
    pub bytes: u64,
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
pub trait TriangleSink: Send {
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
