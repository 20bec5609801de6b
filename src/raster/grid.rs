//! The geometry of a north-up raster grid, and the random-access row store every grid writer
//! offers.
//!
//! # Conventions
//!
//! A [`GridSpec`] describes `cols × rows` square cells of side `cell`. Row 0 is the **northern**
//! row (largest `y`), as in GeoTIFF and ESRI ASCII grids; column 0 is the western one. Cells are
//! areas ("pixel is area"): `origin` is the outer upper-left **corner** of cell (0, 0), and the
//! value of a cell is the surface's value at the cell's **centre**.
//!
//! Grids that sweeptin produces are *aligned*: every centre lies on a whole multiple of the cell
//! size, so rasters from separate runs over adjacent tiles line up exactly ([`GridSpec::aligned`]).

use crate::error::Result;
use crate::lidar::Crs;
use std::path::Path;

/// A north-up grid of square cells.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// Upper-left outer corner `[x, y]` of cell (0, 0) (row 0 is the northern row).
    pub origin: [f64; 2],
    /// Side of a cell (> 0), in the units of the coordinates.
    pub cell: f64,
    /// Number of columns.
    pub cols: u32,
    /// Number of rows.
    pub rows: u32,
    /// The value stored in cells without data.
    pub nodata: f32,
    /// Coordinate reference system, when known.
    pub crs: Option<Crs>,
}

impl GridSpec {
    /// The grid whose lower-left cell centre is `(kx0 × cell, ky0 × cell)`: centres on whole
    /// multiples of the cell size.
    pub fn aligned(cell: f64, kx0: i64, ky0: i64, cols: u32, rows: u32, nodata: f32) -> GridSpec {
        let top = ky0 + i64::from(rows) - 1;
        GridSpec {
            origin: [
                kx0 as f64 * cell - cell / 2.0,
                top as f64 * cell + cell / 2.0,
            ],
            cell,
            cols,
            rows,
            nodata,
            crs: None,
        }
    }

    /// `x` of the centre of column `col`.
    pub fn centre_x(&self, col: u32) -> f64 {
        self.origin[0] + (f64::from(col) + 0.5) * self.cell
    }

    /// `y` of the centre of row `row` (row 0 is the northern row).
    pub fn centre_y(&self, row: u32) -> f64 {
        self.origin[1] - (f64::from(row) + 0.5) * self.cell
    }

    /// The real-world extent `[xmin, ymin, xmax, ymax]` of the cells' areas.
    pub fn extent(&self) -> [f64; 4] {
        [
            self.origin[0],
            self.origin[1] - f64::from(self.rows) * self.cell,
            self.origin[0] + f64::from(self.cols) * self.cell,
            self.origin[1],
        ]
    }

    /// Number of cells.
    pub fn len(&self) -> u64 {
        u64::from(self.cols) * u64::from(self.rows)
    }

    /// Does the grid have no cell at all?
    pub fn is_empty(&self) -> bool {
        self.cols == 0 || self.rows == 0
    }

    /// Is `v` this grid's nodata value (bit for bit, so a NaN nodata works too)?
    pub fn is_nodata(&self, v: f32) -> bool {
        v.to_bits() == self.nodata.to_bits()
    }
}

/// A raster being written: rows and single cells can be written in any order, and cells already
/// written read back. Nothing appears under the output path before [`GridWriter::finish`].
pub trait GridWriter: Send {
    /// The grid being written.
    fn spec(&self) -> &GridSpec;

    /// Writes a whole row (`values.len() == cols`; row 0 is the northern row).
    ///
    /// # Errors
    /// [`crate::Error::Io`] naming the output; [`crate::Error::Output`] for a bad row or length.
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
    /// [`crate::Error::Io`] naming the output.
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
/// [`crate::Error::Output`] if the format is unknown; [`crate::Error::Io`] if the file cannot be
/// created.
pub fn create_grid_writer(
    path: &Path,
    format: Option<RasterFormat>,
    spec: &GridSpec,
) -> Result<Box<dyn GridWriter>> {
    let format = format
        .or_else(|| RasterFormat::from_extension(path))
        .ok_or_else(|| crate::Error::Output {
            path: path.to_path_buf(),
            message: "unknown raster format: use a .tif or .asc extension, or --format".into(),
        })?;
    Ok(match format {
        RasterFormat::GeoTiff => Box::new(super::geotiff_write::GeoTiffWriter::create(path, spec)?),
        RasterFormat::Ascii => Box::new(super::ascii_write::AsciiGridWriter::create(path, spec)?),
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
    fn aligned_centres_fall_on_multiples() {
        let g = GridSpec::aligned(0.5, 1_541_100, 12_555_101, 100, 100, -9999.0);
        assert_eq!(g.origin, [770_549.75, 6_277_600.25]);
        assert_eq!(g.centre_x(0), 770_550.0);
        assert_eq!(g.centre_y(0), 6_277_600.0);
        assert_eq!(g.centre_y(99), 6_277_550.5);
        assert_eq!(
            g.extent(),
            [770_549.75, 6_277_550.25, 770_599.75, 6_277_600.25]
        );
        assert_eq!(g.len(), 10_000);
    }

    #[test]
    fn nan_nodata_compares_by_bits() {
        let mut g = GridSpec::aligned(1.0, 0, 0, 1, 1, f32::NAN);
        assert!(g.is_nodata(f32::NAN));
        g.nodata = -9999.0;
        assert!(!g.is_nodata(f32::NAN) && g.is_nodata(-9999.0));
    }

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
