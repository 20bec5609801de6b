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
pub mod source;
pub mod spread;
pub mod stin;
pub mod vector;
pub mod xyz;

pub use ply::{read_ply, read_ply_kind};

/// What a file is, from its first bytes, when it is a binary format a user may give by mistake
/// (a raster as points, an image as a DEM): `"a TIFF image"`, `"a LAS/LAZ point cloud"`, …;
/// `None` for anything else (text included). For messages that say what the file is instead of
/// quoting its bytes.
pub fn sniff(head: &[u8]) -> Option<&'static str> {
    const KINDS: [(&[u8], &str); 11] = [
        (b"II*\0", "a TIFF image"),
        (b"MM\0*", "a TIFF image"),
        (b"II+\0", "a BigTIFF image"),
        (b"MM\0+", "a BigTIFF image"),
        (
            b"LASF",
            "a LAS/LAZ point cloud (give it a .las or .laz name)",
        ),
        (b"\x89PNG", "a PNG image"),
        (b"PK\x03\x04", "a ZIP archive (a NumPy .npz?)"),
        (b"\x93NUMPY", "a NumPy array (.npy)"),
        (b"\x1f\x8b", "a gzip-compressed file"),
        (b"SQLite format 3", "an SQLite database (a GeoPackage?)"),
        (b"ply\n", "a PLY mesh"),
    ];
    KINDS
        .iter()
        .find(|(magic, _)| head.starts_with(magic))
        .map(|(_, kind)| *kind)
        .or_else(|| {
            head.starts_with(stin::MAGIC)
                .then_some("a streaming mesh (.stin)")
        })
}
pub use stin::{StinEvent, StinReader};
pub use xyz::{XyzReader, read_xyz};
