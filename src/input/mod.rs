//! Reading what users give: the list of input files ([`files`]: `@lists`, globs, `.vpc`),
//! point clouds ([`las`]: LAS/LAZ; [`xyz`]: text), lines and polygons
//! ([`geojson`]: the one GeoJSON reader, with a polygons view and a lines view; [`vector`]:
//! GeoPackage, OGR-SQLite and Shapefile into the same parts; [`lines`]: breaklines, from those
//! or from text),
//! rasters ([`raster`]: GeoTIFF, ESRI ASCII, for grid-to-TIN), and meshes ([`ply`]; [`stin`]:
//! sweeptin's streaming mesh, read back with bounded memory).

pub mod files;
pub mod geojson;
pub mod las;
pub mod lines;
pub mod ply;
pub mod raster;
pub mod stin;
pub mod vector;
pub mod xyz;

pub use ply::read_ply;
pub use stin::{StinEvent, StinReader};
pub use xyz::{XyzReader, read_xyz};
