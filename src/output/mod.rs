//! Writing results, each output appearing only when complete ([`AtomicFile`]).
//!
//! - [`mesh`]: mesh formats and [`create_mesh_sink`], which picks a writer: [`PlyWriter`] (binary
//!   PLY), [`ObjWriter`] (Wavefront OBJ), [`LandXmlWriter`] (LandXML 1.2), [`StinWriter`]
//!   (sweeptin's streaming mesh). No writer holds the mesh in memory.
//! - [`raster`]: the [`GridWriter`] row store, [`RasterOptions`] and [`create_grid_writer`]:
//!   [`geotiff`] (float32 GeoTIFF written in place), [`cog`] (compressed GeoTIFF and Cloud
//!   Optimized GeoTIFF, staged and assembled in bounded memory) and [`ascii`] (ESRI ASCII grid
//!   with a `.prj`); [`world`]: world files and `.prj` files beside images.
//! - [`geojson`]: a streaming GeoJSON feature writer.
//! - [`pieces`]: the tiles of a plan's `tin` task, for the merge.
//! - [`vpc`]: virtual point clouds (`.vpc`) from LAS/LAZ headers.
//! - [`atomic`]: [`AtomicFile`] and the registry of temporary paths deleted on Ctrl-C
//!   ([`install_interrupt_handler`]); [`target`]: what an output path is (a file, a link, a
//!   stream) and the temporary files of dead runs.
//!
//! ```
//! use sweeptin::output::{create_mesh_sink, MeshMeta};
//! use sweeptin::input::read_ply;
//!
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("tin.ply");
//! let mut sink = create_mesh_sink(&path, None, &MeshMeta::default()).unwrap();
//! sink.vertex([0.0, 0.0, 1.0]).unwrap();
//! sink.vertex([1.0, 0.0, 2.0]).unwrap();
//! sink.vertex([0.0, 1.0, 3.0]).unwrap();
//! sink.triangle([0, 1, 2]).unwrap();
//! let summary = sink.finish().unwrap();
//! assert_eq!((summary.vertices, summary.triangles), (3, 1));
//!
//! let (vertices, triangles) = read_ply(&path).unwrap();
//! assert_eq!(vertices[2], [0.0, 1.0, 3.0]);
//! assert_eq!(triangles, vec![[0, 1, 2]]);
//! ```

pub mod ascii;
pub mod atomic;
pub mod cog;
pub mod geojson;
pub mod geotiff;
pub mod landxml;
pub mod mesh;
pub mod obj;
pub mod pieces;
pub mod ply;
pub mod raster;
pub mod sms2dm;
pub mod stin;
pub mod target;
pub mod vpc;
pub mod world;

pub use atomic::{AtomicFile, RegisteredTempDir, install_interrupt_handler};
pub use landxml::LandXmlWriter;
pub use mesh::{MeshFormat, MeshMeta, create_mesh_sink};
pub use obj::ObjWriter;
pub use ply::PlyWriter;
pub use raster::{GridWriter, MemoryGrid, RasterFormat, RasterOptions, create_grid_writer};
pub use sms2dm::Sms2dmWriter;
pub use stin::StinWriter;
pub use target::{check_output, distinct_outputs};

/// The most bytes handed to one `write` call by [`write_pieces`].
const WRITE_PIECE: usize = 1 << 20;

/// Writes `bytes` in pieces of a megabyte. One `write` of many megabytes (a sort's half, a tile's
/// vertices) makes Linux fill the page cache with 2 MiB folios, and on a virtual machine that
/// hands free memory back to its host each such folio is faulted in page by page: spilling
/// ARSO's ground runs in 13 MB writes took 0.9 s of system CPU, in 1 MB pieces 0.03 s
/// (docs/BENCHMARKS.md, evening of 2026-12-04). Elsewhere it costs nothing.
///
/// # Errors
/// The writer's.
pub(crate) fn write_pieces(w: &mut impl std::io::Write, bytes: &[u8]) -> std::io::Result<()> {
    bytes.chunks(WRITE_PIECE).try_for_each(|p| w.write_all(p))
}
