//! Breaklines: reading, cleaning into a planar straight-line graph, trimming, flat triangles.
//!
//! Breaklines (road edges, ditches, ridges, lake shores, contour lines) become constraining edges
//! of the triangulation. Real line data is messy, so it goes through three steps before the sweep
//! sees it:
//!
//! 1. [`read_file`]: GeoJSON (`LineString`, `MultiLineString`, `Polygon`, `MultiPolygon`,
//!    `GeometryCollection`, as a `FeatureCollection`, a `Feature` or a bare geometry) or a simple
//!    text format (`x y [z]` per line, a blank line ends a polyline), into [`Lines`]: polylines
//!    with their [`Source`] (file and feature or line) for error messages. Coordinates without
//!    `z` get `z = NaN`, meaning *unknown*.
//! 2. [`clean`](clean::clean): polylines → [`Pslg`] (a planar straight-line graph): exact duplicate
//!    vertices merged, zero-length segments dropped, crossings split at a new vertex, collinear
//!    overlaps merged, segments split where a vertex lies on them, repeated until nothing changes.
//!    Every decision is exact (`geom::predicates::orient`); only the coordinates of crossing
//!    points are rounded, once.
//! 3. [`trim`]: which triangles to keep (`--boundary`, `--holes`, `--max-edge`).
//!
//! and one post-pass, [`flat`]: flips that remove triangles lying flat on one contour line
//! (`--no-flat-triangles`, Herva 2009, section 4.2.2).
//!
//! ```
//! use sweeptin::breaklines::{clean::{clean, CleanOptions}};
//!
//! // Two crossing lines, one with z and one without.
//! let lines = vec![
//!     vec![[0.0, 0.0, 10.0], [2.0, 2.0, 12.0]],
//!     vec![[0.0, 2.0, f64::NAN], [2.0, 0.0, f64::NAN]],
//! ];
//! let g = clean(&lines, &CleanOptions::default()).unwrap();
//! assert_eq!(g.vertices.len(), 5); // the crossing (1, 1) is a new vertex
//! assert_eq!(g.segments.len(), 4);
//! assert_eq!(g.vertices[4], [1.0, 1.0, 11.0]); // z interpolated along the line that has it
//! assert_eq!(g.stats.crossings, 1);
//! ```
//!
//! Everything here works in whatever coordinates it is given: the pipeline gives lines in the
//! points' real-world coordinates (the doubles the outputs get, also for LAS/LAZ input; see
//! docs/ARCHITECTURE.md, "Coordinates"), and tolerances are in those units too.

pub mod clean;
pub mod flat;

pub mod trim;

pub use crate::input::lines::{LineStream, Lines, Location, Source, read_file, read_files};
pub use clean::{CleanOptions, CleanStats, Pslg, clean};
pub use trim::Trim;

use crate::error::{Error, Result};

impl crate::input::lines::Lines {
    /// Cleans the polylines into a planar straight-line graph ([`clean::clean`]); errors
    /// name the file and feature of the offending polyline.
    ///
    /// # Errors
    /// [`Error::Format`] for a coordinate the predicates cannot handle exactly.
    pub fn clean(&self, options: &CleanOptions) -> Result<Pslg> {
        clean::clean(&self.polylines, options).map_err(|e| self.name_line(e))
    }

    /// [`Lines::clean`] streamed ([`clean::stream::clean_streamed`]: sorts of `mem` bytes
    /// spilling under `tmp_dir`): the same graph as pieces in sweep order.
    ///
    /// # Errors
    /// As [`Lines::clean`], and the external sort's.
    pub fn clean_streamed(
        &self,
        options: &CleanOptions,
        mem: u64,
        tmp_dir: &std::path::Path,
    ) -> Result<clean::stream::Cleaned> {
        clean::stream::clean_streamed(self.polylines.as_slice(), options, mem, tmp_dir)
            .map_err(|e| self.name_line(e))
    }

    /// A cleaning error naming its polyline's file and feature.
    fn name_line(&self, e: Error) -> Error {
        crate::input::lines::name_bad_line(e, |p| self.sources.get(p as usize).cloned())
    }
}
