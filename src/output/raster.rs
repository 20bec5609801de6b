//! The random-access row store every grid writer offers ([`GridWriter`]), the raster formats and
//! the factory that picks a writer.

use crate::error::Result;
use crate::raster::GridSpec;
use std::path::Path;

/// A raster being written: rows and single cells can be written in any order, and cells already
/// written read back. Nothing appears under the output path before [`GridWriter::finish`].
pub trait GridWriter: Send {
    /// The grid being written.
    fn spec(&self) -> &GridSpec;

    /// Writes a whole row (`values.len() == cols`; row 0 is the northern row).
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming the output; [`crate::Error::Output`] for a bad row or length.
    fn write_row(&mut self, row: u32, values: &[f32]) -> Result<()>;

    /// Writes one cell.
    ///
    /// # Errors
    /// As [`GridWriter::write_row`].
    fn write_cell(&mut self, row: u32, col: u32, value: f32) -> Result<()>;

    /// Reads back one cell; a cell never written reads as nodata.
    ///
    /// # Errors
    /// As [`GridWriter::write_row`].
    fn read_cell(&mut self, row: u32, col: u32) -> Result<f32>;

    /// Reads back `out.len()` cells of `row` from column `col` on; cells never written read as
    /// nodata. The default reads cell by cell.
    ///
    /// # Errors
    /// As [`GridWriter::write_row`].
    fn read_span(&mut self, row: u32, col: u32, out: &mut [f32]) -> Result<()> {
        for (i, v) in out.iter_mut().enumerate() {
            *v = self.read_cell(row, col + i as u32)?;
        }
        Ok(())
    }

    /// Writes `values` into `row` from column `col` on. The default writes cell by cell.
    ///
    /// # Errors
    /// As [`GridWriter::write_row`].
    fn write_span(&mut self, row: u32, col: u32, values: &[f32]) -> Result<()> {
        for (i, v) in values.iter().enumerate() {
            self.write_cell(row, col + i as u32, *v)?;
        }
        Ok(())
    }

    /// Completes the file and moves it into place; returns its size in bytes.
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming the output.
    fn finish(self: Box<Self>) -> Result<u64>;
}

/// Raster output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RasterFormat {
    /// Float32 GeoTIFF (`.tif`, `.tiff`).
    #[value(name = "tif")]
    GeoTiff,
    /// ESRI ASCII grid (`.asc`).
    #[value(name = "asc")]
    Ascii,
}

impl RasterFormat {
    /// The format a file name's extension names, if any.
    pub fn from_extension(path: &Path) -> Option<RasterFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "tif" | "tiff" => Some(RasterFormat::GeoTiff),
            "asc" => Some(RasterFormat::Ascii),
            _ => None,
        }
    }
}

/// Opens a writer for `spec` at `path`, in `format` or the format the extension names.
///
/// # Errors
/// [`crate::Error::Output`] if the format is unknown; [`crate::Error::Write`] if the file cannot be
/// created.
pub fn create_grid_writer(
    path: &Path,
    format: Option<RasterFormat>,
    spec: &GridSpec,
) -> Result<Box<dyn GridWriter>> {
    let format = format
        .or_else(|| RasterFormat::from_extension(path))
        .ok_or_else(|| {
            crate::Error::Options(format!(
                "{}: unknown raster format: use a .tif or .asc extension, or --raster-format",
                path.display()
            ))
        })?;
    Ok(match format {
        RasterFormat::GeoTiff => Box::new(super::geotiff::GeoTiffWriter::create(path, spec)?),
        RasterFormat::Ascii => Box::new(super::ascii::AsciiGridWriter::create(path, spec)?),
    })
}

/// Checks a row/column against the grid, for the writers.
pub(crate) fn check_cell(spec: &GridSpec, path: &Path, row: u32, col: u32) -> Result<()> {
    check_span(spec, path, row, col, 1)
}

/// Errors unless `len >= 1` cells of `row` from `col` on lie inside the grid.
pub(crate) fn check_span(
    spec: &GridSpec,
    path: &Path,
    row: u32,
    col: u32,
    len: usize,
) -> Result<()> {
    let end = u64::from(col) + len.max(1) as u64;
    if row >= spec.rows || end > u64::from(spec.cols) {
        return Err(crate::Error::Output {
            path: path.to_path_buf(),
            message: format!(
                "cell (row {row}, column {col}) is outside the {} × {} grid",
                spec.cols, spec.rows
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_extension() {
        assert_eq!(
            RasterFormat::from_extension(Path::new("a/DEM.TIF")),
            Some(RasterFormat::GeoTiff)
        );
        assert_eq!(
            RasterFormat::from_extension(Path::new("x.asc")),
            Some(RasterFormat::Ascii)
        );
        assert_eq!(RasterFormat::from_extension(Path::new("x.png")), None);
    }
}
