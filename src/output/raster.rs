//! The random-access row store every grid writer offers ([`GridWriter`]), the raster formats,
//! their options ([`RasterOptions`]) and the factory that picks a writer; [`Scratch`], the
//! anonymous temporary cell store of the writers that transcribe at the end (ESRI ASCII,
//! compressed GeoTIFF, COG).

use crate::error::{Error, Result};
use crate::raster::GridSpec;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

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

    /// The cells, row 0 (north) first, of a grid kept in memory ([`MemoryGrid`]); `None` for a
    /// file. Taken once, before [`GridWriter::finish`].
    fn take_values(&mut self) -> Option<Vec<f32>> {
        None
    }
}

/// A grid kept in memory instead of a file, for rasters handed to a caller (the Python
/// package's `Tin.rasterize`): the same DEM sink fills it, then [`GridWriter::take_values`]
/// gives the cells.
pub struct MemoryGrid {
    spec: GridSpec,
    values: Vec<f32>,
}

impl MemoryGrid {
    /// A grid of `spec`, every cell nodata.
    ///
    /// # Errors
    /// [`crate::Error::OutOfMemory`] when the cells do not fit in memory.
    pub fn new(spec: &GridSpec) -> Result<MemoryGrid> {
        let n = usize::try_from(spec.len()).unwrap_or(usize::MAX);
        let mut values = Vec::new();
        values
            .try_reserve_exact(n)
            .map_err(|_| crate::Error::OutOfMemory {
                what: format!("a {} × {} raster in memory", spec.cols, spec.rows),
                bytes: spec.len().saturating_mul(4),
                hint: "use a larger cell or a smaller box, or write the DEM to a file".into(),
            })?;
        values.resize(n, spec.nodata);
        Ok(MemoryGrid {
            spec: spec.clone(),
            values,
        })
    }

    fn at(&self, row: u32, col: u32, len: usize) -> Result<usize> {
        check_span(&self.spec, Path::new("(memory)"), row, col, len)?;
        Ok(row as usize * self.spec.cols as usize + col as usize)
    }
}

impl GridWriter for MemoryGrid {
    fn spec(&self) -> &GridSpec {
        &self.spec
    }

    fn write_row(&mut self, row: u32, values: &[f32]) -> Result<()> {
        self.write_span(row, 0, values)
    }

    fn write_cell(&mut self, row: u32, col: u32, value: f32) -> Result<()> {
        let i = self.at(row, col, 1)?;
        self.values[i] = value;
        Ok(())
    }

    fn read_cell(&mut self, row: u32, col: u32) -> Result<f32> {
        let i = self.at(row, col, 1)?;
        Ok(self.values[i])
    }

    fn read_span(&mut self, row: u32, col: u32, out: &mut [f32]) -> Result<()> {
        let i = self.at(row, col, out.len())?;
        out.copy_from_slice(&self.values[i..i + out.len()]);
        Ok(())
    }

    fn write_span(&mut self, row: u32, col: u32, values: &[f32]) -> Result<()> {
        let i = self.at(row, col, values.len())?;
        self.values[i..i + values.len()].copy_from_slice(values);
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<u64> {
        Ok(0)
    }

    fn take_values(&mut self) -> Option<Vec<f32>> {
        Some(std::mem::take(&mut self.values))
    }
}

/// Raster output formats (named as `--format` names them, also in a plan's `plan.json`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
pub enum RasterFormat {
    /// Float32 GeoTIFF (`.tif`, `.tiff`).
    #[value(name = "tif", alias = "gtiff")]
    #[serde(rename = "tif")]
    GeoTiff,
    /// Cloud Optimized GeoTIFF (`.tif`): tiled 512 × 512, compressed, internal overviews.
    #[value(name = "cog")]
    #[serde(rename = "cog")]
    Cog,
    /// ESRI ASCII grid (`.asc`), with a `.prj` beside it when the CRS is known.
    #[value(name = "asc")]
    #[serde(rename = "asc")]
    Ascii,
}

/// GeoTIFF compression.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Compression {
    /// Uncompressed.
    #[default]
    None,
    /// DEFLATE (zlib), read by every TIFF reader.
    Deflate,
    /// Zstandard: faster than DEFLATE at a similar size (GDAL ≥ 2.3, libtiff ≥ 4.0.10).
    Zstd,
    /// LZW, GDAL's default for COG.
    Lzw,
}

impl Compression {
    /// The TIFF `Compression` tag value.
    pub(crate) fn tag(self) -> u16 {
        match self {
            Compression::None => 1,
            Compression::Lzw => 5,
            Compression::Deflate => 8,
            Compression::Zstd => 50000,
        }
    }
}

/// GeoTIFF predictor, applied before compression (GDAL's `PREDICTOR=1|2|3`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Predictor {
    /// No predictor (1).
    #[value(alias = "1")]
    None,
    /// Horizontal differencing of integer samples (2): for 8-bit images such as a hillshade.
    #[value(alias = "2")]
    Horizontal,
    /// The floating-point predictor (3): bytes regrouped by significance and differenced, which
    /// makes float DEMs compress about twice as well.
    #[value(alias = "3")]
    Float,
}

impl Predictor {
    /// The option's value.
    fn name(self) -> &'static str {
        match self {
            Predictor::None => "none",
            Predictor::Horizontal => "horizontal",
            Predictor::Float => "float",
        }
    }

    /// The TIFF `Predictor` tag value.
    pub(crate) fn tag(self) -> u16 {
        match self {
            Predictor::None => 1,
            Predictor::Horizontal => 2,
            Predictor::Float => 3,
        }
    }
}

/// How a raster is written: format, compression, predictor, BigTIFF. Checked once
/// ([`RasterOptions::resolve`]) before any work.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RasterOptions {
    /// The format; by the output's extension when `None`.
    pub format: Option<RasterFormat>,
    /// Compression; `None`: DEFLATE for a COG, none for a plain GeoTIFF.
    pub compress: Option<Compression>,
    /// Predictor; `None`: the floating-point predictor (horizontal for 8-bit images) when
    /// compressed, none otherwise.
    pub predictor: Option<Predictor>,
    /// Write BigTIFF even when the file would fit in 4 GiB (it is chosen by itself beyond).
    pub bigtiff: bool,
}

/// [`RasterOptions`] with every default decided, for one output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResolvedRaster {
    /// The format.
    pub format: RasterFormat,
    /// Compression (none for ESRI ASCII).
    pub compress: Compression,
    /// Predictor.
    pub predictor: Predictor,
    /// Force BigTIFF.
    pub bigtiff: bool,
}

impl RasterOptions {
    /// Decides the format (from the extension of `path` when not given) and the defaults, and
    /// refuses what does not go together. `integer` says the samples are 8-bit integers (a
    /// hillshade) rather than float32.
    ///
    /// # Errors
    /// [`Error::Options`] naming `path` for an unknown format, compression or predictor options
    /// on an ESRI ASCII grid, or a predictor that does not suit the samples.
    pub fn resolve(&self, path: &Path, integer: bool) -> Result<ResolvedRaster> {
        // A format or option that does not fit the output is a usage error (exit 2).
        let bad = |message: String| Error::Options(format!("{}: {message}", path.display()));
        let format = self
            .format
            .or_else(|| RasterFormat::from_extension(path))
            .ok_or_else(|| {
                bad("unknown raster format: use a .tif or .asc extension, or --format".into())
            })?;
        if format == RasterFormat::Ascii {
            if self.compress.is_some_and(|c| c != Compression::None)
                || self.predictor.is_some_and(|p| p != Predictor::None)
                || self.bigtiff
            {
                return Err(bad(
                    "--compress, --predictor and --bigtiff apply to GeoTIFF and COG outputs, not to an ESRI ASCII grid"
                        .into(),
                ));
            }
            return Ok(ResolvedRaster {
                format,
                compress: Compression::None,
                predictor: Predictor::None,
                bigtiff: false,
            });
        }
        let compress = self.compress.unwrap_or(match format {
            RasterFormat::Cog => Compression::Deflate,
            _ => Compression::None,
        });
        let natural = if integer {
            Predictor::Horizontal
        } else {
            Predictor::Float
        };
        let predictor = match (self.predictor, compress) {
            (Some(p), _) => p,
            (None, Compression::None) => Predictor::None,
            (None, _) => natural,
        };
        if predictor != Predictor::None && compress == Compression::None {
            return Err(bad(format!(
                "--predictor {} needs compression (--compress deflate, zstd or lzw)",
                predictor.name()
            )));
        }
        if predictor != Predictor::None && predictor != natural {
            return Err(bad(format!(
                "--predictor {} does not suit {} samples (use {})",
                predictor.name(),
                if integer { "8-bit integer" } else { "float32" },
                natural.name(),
            )));
        }
        Ok(ResolvedRaster {
            format,
            compress,
            predictor,
            bigtiff: self.bigtiff,
        })
    }
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

/// Opens a float32 writer for `spec` at `path`, as `options` say (the format by the extension
/// unless given): an uncompressed GeoTIFF is written in place; a compressed GeoTIFF, a COG and an
/// ESRI ASCII grid are staged in a [`Scratch`] and transcribed by [`GridWriter::finish`].
///
/// # Errors
/// As [`RasterOptions::resolve`]; [`crate::Error::Io`] if the file cannot be created.
pub fn create_grid_writer(
    path: &Path,
    options: &RasterOptions,
    spec: &GridSpec,
) -> Result<Box<dyn GridWriter>> {
    create_grid_writer_within(path, options, spec, super::cog::BATCH_BYTES)
}

/// [`create_grid_writer`] whose compressed GeoTIFF or COG compresses at most `batch_bytes` of
/// cells at once (`sweeptin merge --mem`); the same file whatever the batch.
pub(crate) fn create_grid_writer_within(
    path: &Path,
    options: &RasterOptions,
    spec: &GridSpec,
    batch_bytes: usize,
) -> Result<Box<dyn GridWriter>> {
    let r = options.resolve(path, false)?;
    Ok(match r.format {
        RasterFormat::GeoTiff if r.compress == Compression::None => Box::new(
            super::geotiff::GeoTiffWriter::create_with(path, spec, r.bigtiff)?,
        ),
        RasterFormat::GeoTiff | RasterFormat::Cog => Box::new(
            super::cog::StagedGridWriter::create(path, spec, &r)?.with_batch_bytes(batch_bytes),
        ),
        RasterFormat::Ascii => Box::new(super::ascii::AsciiGridWriter::create(path, spec)?),
    })
}

/// A `cols × rows` grid of float32 cells in an anonymous temporary file (deleted by the
/// operating system even if the process is killed), row-major from the northern row, with
/// random access: the stage of the writers that transcribe at the end. Rows never written read
/// as the fill value.
#[derive(Debug)]
pub struct Scratch {
    file: File,
    cols: u32,
    rows: u32,
    fill: f32,
    written: Vec<bool>,
    /// The output the scratch is for, named in errors.
    path: PathBuf,
}

impl Scratch {
    /// An empty store beside `path` (in its directory, which the output will be in anyway).
    ///
    /// # Errors
    /// [`Error::Io`] naming the directory.
    pub fn new(path: &Path, cols: u32, rows: u32, fill: f32) -> Result<Scratch> {
        let dir = super::target::scratch_dir(path);
        let file = tempfile::tempfile_in(&dir).map_err(|e| Error::write(&dir, e))?;
        Ok(Scratch {
            file,
            cols,
            rows,
            fill,
            written: vec![false; rows as usize],
            path: path.to_path_buf(),
        })
    }

    /// Columns.
    pub fn cols(&self) -> u32 {
        self.cols
    }

    /// Rows.
    pub fn rows(&self) -> u32 {
        self.rows
    }

    fn offset(&self, row: u32, col: u32) -> u64 {
        (u64::from(row) * u64::from(self.cols) + u64::from(col)) * 4
    }

    /// Writes `values` into `row` from column `col` on (the caller checked the span).
    ///
    /// # Errors
    /// [`Error::Io`] naming the output.
    pub fn write(&mut self, row: u32, col: u32, values: &[f32]) -> Result<()> {
        if !self.written[row as usize] && (col > 0 || values.len() < self.cols as usize) {
            let fill = vec![self.fill; self.cols as usize];
            self.put(row, 0, &fill)?;
        }
        self.written[row as usize] = true;
        self.put(row, col, values)
    }

    fn put(&self, row: u32, col: u32, values: &[f32]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(values);
        let bytes: Vec<u8> = if cfg!(target_endian = "little") {
            bytes.to_vec()
        } else {
            values.iter().flat_map(|v| v.to_le_bytes()).collect()
        };
        self.file
            .write_all_at(&bytes, self.offset(row, col))
            .map_err(|e| Error::write(&self.path, e))
    }

    /// Reads `out.len()` cells of `row` from column `col` on.
    ///
    /// # Errors
    /// [`Error::Io`] naming the output.
    pub fn read(&self, row: u32, col: u32, out: &mut [f32]) -> Result<()> {
        if !self.written[row as usize] {
            out.fill(self.fill);
            return Ok(());
        }
        let mut bytes = vec![0u8; out.len() * 4];
        self.file
            .read_exact_at(&mut bytes, self.offset(row, col))
            .map_err(|e| Error::write(&self.path, e))?;
        for (v, c) in out.iter_mut().zip(bytes.chunks_exact(4)) {
            *v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        }
        Ok(())
    }

    /// Was `row` ever written?
    pub fn has_row(&self, row: u32) -> bool {
        self.written[row as usize]
    }
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

    #[test]
    fn options_resolve_defaults_and_refusals() {
        let p = Path::new("d.tif");
        let cog = RasterOptions {
            format: Some(RasterFormat::Cog),
            ..RasterOptions::default()
        };
        let r = cog.resolve(p, false).unwrap();
        assert_eq!(
            (r.compress, r.predictor),
            (Compression::Deflate, Predictor::Float)
        );
        let r = cog.resolve(p, true).unwrap();
        assert_eq!(r.predictor, Predictor::Horizontal);
        let plain = RasterOptions::default().resolve(p, false).unwrap();
        assert_eq!(
            (plain.format, plain.compress, plain.predictor),
            (RasterFormat::GeoTiff, Compression::None, Predictor::None)
        );
        let zstd = RasterOptions {
            compress: Some(Compression::Zstd),
            ..RasterOptions::default()
        };
        assert_eq!(zstd.resolve(p, false).unwrap().predictor, Predictor::Float);
        let e = RasterOptions {
            predictor: Some(Predictor::Float),
            ..RasterOptions::default()
        }
        .resolve(p, false)
        .unwrap_err();
        assert!(e.to_string().contains("needs compression"), "{e}");
        let e = RasterOptions {
            compress: Some(Compression::Deflate),
            predictor: Some(Predictor::Horizontal),
            ..RasterOptions::default()
        }
        .resolve(p, false)
        .unwrap_err();
        assert!(e.to_string().contains("does not suit"), "{e}");
        let e = zstd.resolve(Path::new("d.asc"), false).unwrap_err();
        assert!(e.to_string().contains("ESRI ASCII"), "{e}");
        assert!(
            RasterOptions::default()
                .resolve(Path::new("d.png"), false)
                .is_err()
        );
    }

    #[test]
    fn scratch_reads_back_and_fills() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = Scratch::new(&dir.path().join("x.tif"), 3, 2, -1.0).unwrap();
        s.write(1, 1, &[5.0]).unwrap();
        let mut row = [0.0; 3];
        s.read(1, 0, &mut row).unwrap();
        assert_eq!(row, [-1.0, 5.0, -1.0]);
        s.read(0, 0, &mut row).unwrap();
        assert_eq!(row, [-1.0; 3]);
        assert!(s.has_row(1) && !s.has_row(0));
    }
}
