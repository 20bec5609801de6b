//! Terrain products computed from the stream of final triangles, each a
//! [`TriangleSink`](crate::sink::TriangleSink), so that several run in one pass with bounded
//! memory:
//!
//! - [`dem`]: DEM rasters (float32 GeoTIFF, ESRI ASCII grid) by linear interpolation at cell
//!   centres.
//! - [`contours`]: contour lines stitched into polylines across the stream (GeoJSON).
//! - [`volume`]: cut and fill volumes and areas against a plane, within an optional
//!   [`boundary`] polygon; [`overlay`]: the same against a second surface.
//! - [`sample`]: heights at query points; [`profile`]: sections along polylines.
//! - [`hillshade`]: a shaded-relief PNG of a DEM GeoTIFF (not a sink: it reads a raster).
//!
//! Every product handles triangles in any order: the watermark is only used to release memory,
//! and a late triangle (below the watermark) is still taken into account exactly. Shared geometry
//! (exact point location, interpolation that is the same from every triangle, the ownership rule
//! for points on edges, exact sums) is in [`geom`].
//!
//! Each sink's [`finish`](crate::sink::TriangleSink::finish) returns its typed summary (a
//! [`ProductSummary`](crate::sink::ProductSummary) variant, defined in [`crate::sink`]);
//! [`Fanout`](crate::sink::Fanout) runs several in one pass.

pub mod boundary;
pub mod contours;
pub mod dem;
pub mod geom;
pub mod hillshade;
pub mod overlay;
pub mod profile;
pub mod sample;
pub mod volume;

#[cfg(test)]
pub(crate) mod testutil;
