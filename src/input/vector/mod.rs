//! Lines and polygons from the vector formats road, hydro and cadastre data come in, read into
//! the same [`GeoJson`] (parts labelled by feature and part) as the GeoJSON reader, so every
//! option that takes a lines or polygon file (`--breaklines`, `--boundary`, `--trim-boundary`,
//! `--holes`, `volume --boundary`, `profile --line`) takes them all:
//!
//! - **GeoPackage** (`.gpkg`): the geometry column named in `gpkg_geometry_columns`; a blob is
//!   the GeoPackage header (`GP`, version, flags, SRS id, optional envelope) followed by WKB.
//!   The CRS is the layer's SRS when `gpkg_spatial_ref_sys` gives it an EPSG code.
//! - **OGR-SQLite / SpatiaLite** (`.sqlite`, `.db`): the geometry column named in
//!   `geometry_columns`, as plain WKB (GDAL's default) or SpatiaLite blobs (uncompressed
//!   geometries); the CRS from `spatial_ref_sys`.
//! - **Shapefile** (`.shp`, through the `shapefile` crate): PolyLine and Polygon shapes, with or
//!   without Z or M; a polygon's rings are grouped as the format says (an outer ring, clockwise,
//!   starts a polygon; the inner rings after it are its holes). The CRS from the `.prj` beside
//!   it when that WKT names an EPSG code.
//!
//! Files with several layers need the layer named: `roads.gpkg:centrelines` (the error lists
//! the layers). Features are read in the order of their row ids (their file order for a
//! Shapefile); feature indices in messages count from 0 in that order. Z values are kept; M is
//! ignored; `Point` geometries are noted, so that a view can refuse them by name, like GeoJSON's.
//! A file is recognised by its content (SQLite's header) or its extension; anything else is read
//! as GeoJSON ([`super::geojson::read`]).

mod shp;
mod sqlite;
mod wkb;

use super::geojson::{self, GeoJson};
use crate::error::{Error, Result};
use std::io::Read;
use std::path::{Path, PathBuf};

/// The vector formats read here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VectorFormat {
    /// GeoJSON (or, for breaklines, sweeptin's text lines).
    GeoJson,
    /// A SQLite database: GeoPackage or OGR-SQLite / SpatiaLite.
    Sqlite,
    /// ESRI Shapefile.
    Shapefile,
}

/// The file and layer of `path`: `FILE:LAYER` names a layer when `FILE` exists and the whole
/// does not.
pub fn split_layer(path: &Path) -> (PathBuf, Option<String>) {
    if path.exists() {
        return (path.to_path_buf(), None);
    }
    let text = path.to_string_lossy();
    if let Some(k) = text.rfind(':') {
        let (file, layer) = (&text[..k], &text[k + 1..]);
        if !layer.is_empty() && !layer.contains('/') && Path::new(file).is_file() {
            return (PathBuf::from(file), Some(layer.to_string()));
        }
    }
    (path.to_path_buf(), None)
}

/// The format of `file` (without a layer suffix): SQLite by its header, Shapefile by its
/// extension, GeoJSON otherwise.
pub fn format_of(file: &Path) -> VectorFormat {
    let mut head = [0u8; 16];
    // A file too short to read 16 bytes from is no SQLite database: `head` stays zeros.
    let _ = std::fs::File::open(file).and_then(|mut f| f.read_exact(&mut head));
    format_of_bytes(file, &head)
}

/// As [`format_of`], for the file `file` whose content is (or starts with) `bytes`.
pub(crate) fn format_of_bytes(file: &Path, bytes: &[u8]) -> VectorFormat {
    let sqlite = bytes.starts_with(b"SQLite format 3\0");
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if sqlite || matches!(ext.as_deref(), Some("gpkg" | "sqlite" | "db")) {
        VectorFormat::Sqlite
    } else if ext.as_deref() == Some("shp") {
        VectorFormat::Shapefile
    } else {
        VectorFormat::GeoJson
    }
}

/// Reads the lines and polygons of a vector file (see the module docs); `FILE:LAYER` picks a
/// layer.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Format`] naming the file (and the
/// feature and part) for a bad geometry, an unknown layer, or several layers and none named.
pub fn read(path: &Path) -> Result<GeoJson> {
    read_from(path, None)
}

/// As [`read`], from `bytes`, the content of the file `path` names (read by the caller, which
/// can then fingerprint exactly what is parsed: a plan's line files, `plan::lines`). Errors
/// name `path` as [`read`]'s do. A SQLite file's `-wal` beside it is not read: the bytes are the
/// whole database.
///
/// # Errors
/// As [`read`] (no [`Error::Io`] for the file itself).
pub(crate) fn read_bytes(path: &Path, bytes: &[u8]) -> Result<GeoJson> {
    read_from(path, Some(bytes))
}

/// [`read`] (`bytes` is `None`: the readers open the file) or [`read_bytes`].
fn read_from(path: &Path, bytes: Option<&[u8]>) -> Result<GeoJson> {
    let (file, layer) = split_layer(path);
    let format = match bytes {
        Some(b) => format_of_bytes(&file, b),
        None => format_of(&file),
    };
    match format {
        VectorFormat::Sqlite => sqlite::read(&file, bytes, layer.as_deref()),
        VectorFormat::Shapefile => {
            no_layer(&file, layer.as_deref())?;
            shp::read(&file, bytes)
        }
        VectorFormat::GeoJson => {
            no_layer(&file, layer.as_deref())?;
            match bytes {
                Some(b) => geojson::parse(b, &file),
                None => geojson::read(&file),
            }
        }
    }
}

fn no_layer(file: &Path, layer: Option<&str>) -> Result<()> {
    match layer {
        Some(l) => Err(format(
            file,
            format!(
                "has no layers to choose from (`:{l}` names a layer of a GeoPackage or SQLite file)"
            ),
        )),
        None => Ok(()),
    }
}

fn format(path: &Path, message: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// An EPSG code read from a WKT's outermost `AUTHORITY`/`ID`, as `EPSG:code`.
fn epsg_of_wkt(wkt: &[u8]) -> Option<String> {
    crate::crs::Crs::from_wkt_bytes(wkt)
        .and_then(|c| c.epsg)
        .map(|c| format!("EPSG:{c}"))
}

#[cfg(test)]
mod tests;
