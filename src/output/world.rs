//! Side files that georeference an image for GIS software: the ESRI world file (`.pgw` beside a
//! PNG), the `.prj` (the CRS as WKT, beside an `.asc` grid or a PNG: [`Crs::prj`]) and, beside
//! a PNG, GDAL's `.png.aux.xml` with the same WKT (GDAL, and so QGIS, reads a PNG's CRS from
//! there, not from a `.prj`). Each is written atomically, like every output; an image written to
//! a stream (`-`, a FIFO, a device) has no side files (there is nowhere beside it: never
//! `/dev/null.prj`).

use crate::crs::Crs;
use crate::error::Result;
use crate::output::AtomicFile;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The world file's path for `image`: the extension's first and last letters and `w`
/// (`shade.png` → `shade.pgw`, `dem.tif` → `dem.tfw`).
pub fn world_file_path(image: &Path) -> PathBuf {
    let ext = image
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let mut chars = ext.chars();
    let w = match (chars.next(), chars.last()) {
        (Some(a), Some(b)) => format!("{a}{b}w"),
        (Some(a), None) => format!("{a}w"),
        _ => "wld".to_string(),
    };
    image.with_extension(w)
}

/// Writes the world file of a north-up image whose outer upper-left corner is `origin`, with
/// cells `size = [width, height]`: six lines, the cell width, two zero rotations, minus the cell
/// height, then the **centre** of the upper-left cell (ESRI's convention). Returns its path
/// (`None` for an image written to a stream).
///
/// # Errors
/// [`crate::Error::Write`] naming the file.
pub fn write_world_file(image: &Path, origin: [f64; 2], size: [f64; 2]) -> Result<Option<PathBuf>> {
    if !beside_a_file(image) {
        return Ok(None);
    }
    let path = world_file_path(image);
    let text = format!(
        "{:?}\n0.0\n0.0\n{:?}\n{:?}\n{:?}\n",
        size[0],
        -size[1],
        origin[0] + size[0] / 2.0,
        origin[1] - size[1] / 2.0
    );
    write(&path, text.as_bytes())?;
    Ok(Some(path))
}

/// Is `image` written to a file (so that side files can go beside it)?
fn beside_a_file(image: &Path) -> bool {
    super::target::Destination::of(image).is_ok_and(|d| d.is_whole())
}

/// Writes `<file>.prj` (the extension replaced) with the CRS as WKT ([`Crs::prj`]: the file's
/// WKT1, or ESRI's WKT1 of its EPSG code as GDAL writes it); none when the CRS has neither
/// (no CRS, or a code sweeptin cannot spell: [`crate::crs::LostCrs`] says which). Returns the path
/// written, if any (none beside a stream).
///
/// # Errors
/// [`crate::Error::Write`] naming the file.
pub fn write_prj(file: &Path, crs: Option<&Crs>) -> Result<Option<PathBuf>> {
    let Some(wkt) = crs.and_then(Crs::prj) else {
        return Ok(None);
    };
    if !beside_a_file(file) {
        return Ok(None);
    }
    let path = file.with_extension("prj");
    write(&path, wkt.as_bytes())?;
    Ok(Some(path))
}

/// GDAL's auxiliary file beside `image` (`s.png` → `s.png.aux.xml`).
pub fn aux_xml_path(image: &Path) -> PathBuf {
    let mut name = image.as_os_str().to_owned();
    name.push(".aux.xml");
    PathBuf::from(name)
}

/// Writes GDAL's `<image>.aux.xml` holding the CRS's WKT ([`Crs::prj`]), which GDAL reads for
/// a PNG (it reads no `.prj` beside one). Returns the path written, if any.
///
/// # Errors
/// [`crate::Error::Write`] naming the file.
pub fn write_aux_xml(image: &Path, crs: Option<&Crs>) -> Result<Option<PathBuf>> {
    let Some(wkt) = crs.and_then(Crs::prj) else {
        return Ok(None);
    };
    if !beside_a_file(image) {
        return Ok(None);
    }
    let path = aux_xml_path(image);
    let escaped = wkt
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    let text = format!("<PAMDataset>\n  <SRS>{escaped}</SRS>\n</PAMDataset>\n");
    write(&path, text.as_bytes())?;
    Ok(Some(path))
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes).map_err(|e| f.err(e))?;
    f.commit()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn world_file_names_and_centre_of_the_first_cell() {
        assert_eq!(world_file_path(Path::new("a/s.png")), Path::new("a/s.pgw"));
        assert_eq!(world_file_path(Path::new("d.tif")), Path::new("d.tfw"));
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("s.png");
        let p = write_world_file(&png, [100.0, 200.0], [0.5, 0.5])
            .unwrap()
            .unwrap();
        let text = std::fs::read_to_string(p).unwrap();
        assert_eq!(text, "0.5\n0.0\n0.0\n-0.5\n100.25\n199.75\n");
        let none = write_prj(
            &png,
            Some(&Crs {
                epsg: Some(2056),
                ..Crs::default()
            }),
        )
        .unwrap();
        assert_eq!(none, None);
        let code = Crs {
            epsg: Some(2154),
            ..Crs::default()
        };
        let p = write_prj(&png, Some(&code)).unwrap().unwrap();
        assert!(
            std::fs::read_to_string(p)
                .unwrap()
                .starts_with("PROJCS[\"RGF_1993_Lambert_93\",")
        );
        let aux = write_aux_xml(&png, Some(&code)).unwrap().unwrap();
        assert_eq!(aux, dir.path().join("s.png.aux.xml"));
        let wkt = Crs {
            wkt: Some("PROJCS[\"x\"]".into()),
            ..Crs::default()
        };
        let p = write_prj(&png, Some(&wkt)).unwrap().unwrap();
        assert_eq!(std::fs::read_to_string(p).unwrap(), "PROJCS[\"x\"]");
    }
}
