//! Writing results, each output appearing only when complete ([`AtomicFile`]).
//!
//! - [`mesh`]: mesh formats and [`create_mesh_sink`], which picks a writer: [`PlyWriter`] (binary
//!   PLY), [`ObjWriter`] (Wavefront OBJ), [`LandXmlWriter`] (LandXML 1.2), [`StinWriter`]
//!   (sweeptin's streaming mesh). No writer holds the mesh in memory.
//! - [`raster`]: the [`GridWriter`] row store, [`RasterOptions`] and [`create_grid_writer`]:
//!   [`geotiff`] (float32 GeoTIFF written in place), [`cog`] (compressed GeoTIFF and Cloud
//!   Optimized GeoTIFF, staged and assembled in bounded memory) and [`ascii`] (ESRI ASCII grid
//!   with a `.prj`); [`world`]: world files and `.prj` files beside images.
//! - [`las`]: LAS/LAZ files rewritten point by point ([`las::rewrite_points`]), everything
//!   but the edited fields kept.
//! - [`geojson`]: a streaming GeoJSON feature writer; [`gpkg`]: a GeoPackage layer of lines;
//!   [`lines`]: [`lines::LineWriter`], either of them by the output's extension (contours).
//! - [`pieces`]: the tiles of a plan's `tin` task, for the merge.
//! - [`vpc`]: virtual point clouds (`.vpc`) from LAS/LAZ headers.
//! - [`atomic`]: [`AtomicFile`] and the registry of temporary paths deleted on Ctrl-C;
//!   [`interrupt`]: the handler that deletes them ([`install_interrupt_handler`]) and passes
//!   the signal on to child processes (`run --all`'s tasks); [`target`]: what an output path
//!   is (a file, a link, a stream) and the temporary files of dead runs.
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
pub mod gpkg;
pub mod interrupt;
pub mod landxml;
pub mod las;
pub mod lines;
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

pub use atomic::{AtomicFile, RegisteredTempDir};
pub use interrupt::install_interrupt_handler;
pub use landxml::LandXmlWriter;
pub use mesh::{MeshFormat, MeshMeta, create_mesh_sink};
pub use obj::ObjWriter;
pub use ply::PlyWriter;
pub use raster::{GridWriter, MemoryGrid, RasterFormat, RasterOptions, create_grid_writer};
pub use sms2dm::Sms2dmWriter;
pub use stin::StinWriter;
pub use target::{ascii_grid_prj, check_output, distinct_outputs};

/// `s` escaped for XML and HTML text and attribute values (LandXML, a VRT, the plan report):
/// the five markup characters as entities (`&#39;` for the apostrophe, which both read), and
/// control characters, which XML 1.0 does not allow, as spaces.
pub fn escape_markup(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c if (c as u32) < 0x20 => out.push(' '),
            c => out.push(c),
        }
    }
    out
}
