//! Writing a virtual point cloud (`.vpc`) from LAS/LAZ headers: the STAC ItemCollection that
//! PDAL wrench, lasR and QGIS read (see [`crate::input::las::vpc`] for the format).

use super::atomic::AtomicFile;
use crate::error::Result;
use crate::input::las::FileInfo;
use crate::input::las::vpc::{ItemCollection, item};
use std::path::Path;

/// Writes `path` listing `files` (their header facts), with paths relative to the `.vpc`'s
/// folder; returns the size written. An item whose CRS cannot be turned into WGS 84 has no
/// `geometry` or `bbox` ([`crate::input::las::vpc::item`]): [`without_footprint`] names them.
///
/// # Errors
/// [`crate::Error::Format`] for a file with points whose header box says nothing (all zero,
/// inverted or not finite: readers place files by these boxes, and a `.vpc` cannot hold a
/// NaN); [`crate::Error::Io`] naming `path`; nothing is left under `path` on error.
pub fn write_vpc(path: &Path, files: &[FileInfo]) -> Result<u64> {
    if let Some(f) = files
        .iter()
        .find(|f| f.point_count > 0 && !f.bounds.usable())
    {
        return Err(crate::Error::Format {
            path: f.path.clone(),
            message: "its header's box says nothing (all zero, inverted or not finite): a \
                      virtual point cloud places files by their headers' boxes; repair the \
                      header (e.g. lasinfo -repair_bb)"
                .into(),
        });
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    let collection = ItemCollection {
        kind: "FeatureCollection".into(),
        features: files.iter().map(|f| item(f, dir)).collect(),
    };
    let mut out = AtomicFile::create(path)?;
    serde_json::to_writer_pretty(&mut out, &collection)
        .map_err(|e| out.err(std::io::Error::other(e)))?;
    std::io::Write::write_all(&mut out, b"\n").map_err(|e| out.err(e))?;
    out.commit()
}

/// The files of `files` whose items get no WGS 84 `geometry` and `bbox` (their CRS unknown or
/// not one sweeptin can invert: [`crate::crs::Crs::wgs84_ring`]), for a warning.
pub fn without_footprint(files: &[FileInfo]) -> Vec<&FileInfo> {
    files
        .iter()
        .filter(|f| {
            let r = f.rect();
            f.crs.as_ref().and_then(|c| c.wgs84_ring(r, 1)).is_none()
        })
        .collect()
}
