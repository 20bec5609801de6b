//! Reading single-band grids: GeoTIFF (via the `tiff` crate) and ESRI ASCII grid.
//!
//! [`RasterReader::open`] reads only the header; [`RasterReader::read_window`] decodes only the
//! TIFF strips or tiles that intersect the window, so a grid far larger than memory can be
//! processed window by window. Values come back as `f64` with every missing cell (the nodata
//! value, or NaN) as NaN.
//!
//! GeoTIFF support: one sample per pixel; signed and unsigned 8/16/32-bit integers, 32- and 64-bit
//! floats; strips or tiles; any compression the `tiff` crate decodes (none, LZW, Deflate,
//! PackBits, with or without predictor); georeferencing from `ModelTransformation`, or
//! `ModelPixelScale` + `ModelTiepoint`, honouring `PixelIsPoint` the way GDAL does (the transform
//! is shifted by half a cell so that it always refers to cell corners); the CRS from the
//! GeoKeyDirectory (`ProjectedCSTypeGeoKey`, else `GeographicTypeGeoKey`) as `EPSG:code`; nodata
//! from the `GDAL_NODATA` tag.
//!
//! ESRI ASCII grid: `ncols`, `nrows`, `xllcorner`/`xllcenter`, `yllcorner`/`yllcenter`,
//! `cellsize` (or `dx` and `dy`), optional `NODATA_value`, keys in any case, values in rows from
//! north to south, any whitespace between values, nothing but whitespace after the last one (a
//! window that reaches the last row reads on to the end of the file). A `.prj` file beside it
//! supplies the CRS (WKT).
//!
//! Both formats: every cell centre must be a coordinate the predicates handle exactly (the
//! grid's corners within `|x|, |y| <= 2^52`), or the grid is refused when opened.
//! A window is read by scanning from the nearest row start seen before, so reading windows in
//! row order parses the file about once per column of windows.

mod ascii;
mod geotiff;

use crate::error::{Error, Result};
use ascii::AsciiSource;
use geotiff::TiffSource;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Size, georeferencing, nodata value and CRS of a grid being read (a general affine transform;
/// the writers' north-up `grid::GridSpec` is separate).
///
/// Cell `(col, row)` covers the parallelogram whose corners are the images of `(col, row)` and
/// `(col + 1, row + 1)` under [`RasterSpec::transform`]; its value belongs to its centre
/// `(col + 0.5, row + 0.5)`. Row 0 is the first row stored in the file (the northern one for a
/// usual north-up grid).
#[derive(Clone, Debug, PartialEq)]
pub struct RasterSpec {
    /// Number of columns.
    pub cols: u32,
    /// Number of rows.
    pub rows: u32,
    /// Affine transform from cell-corner `(col, row)` to world `(x, y)`, in GDAL's order:
    /// `x = t[0] + col·t[1] + row·t[2]`, `y = t[3] + col·t[4] + row·t[5]`.
    pub transform: [f64; 6],
    /// The value that marks a missing cell, if any (NaN cells are always missing).
    pub nodata: Option<f64>,
    /// Coordinate reference system: `EPSG:xxxx`, or WKT, when known.
    pub crs: Option<String>,
}

impl RasterSpec {
    /// A north-up grid whose top-left corner is `(x0, y_top)`, with square cells of `size`.
    pub fn north_up(cols: u32, rows: u32, x0: f64, y_top: f64, size: f64) -> Self {
        RasterSpec {
            cols,
            rows,
            transform: [x0, size, 0.0, y_top, 0.0, -size],
            nodata: None,
            crs: None,
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> u64 {
        u64::from(self.cols) * u64::from(self.rows)
    }

    /// World position of cell-grid position `(col, row)` (fractional; `+0.5` is a centre).
    #[inline]
    pub fn world(&self, col: f64, row: f64) -> [f64; 2] {
        let t = &self.transform;
        [
            t[0] + col * t[1] + row * t[2],
            t[3] + col * t[4] + row * t[5],
        ]
    }

    /// World position of the centre of cell `(col, row)`.
    #[inline]
    pub fn cell_center(&self, col: u32, row: u32) -> [f64; 2] {
        self.world(f64::from(col) + 0.5, f64::from(row) + 0.5)
    }

    /// Is the transform free of rotation and shear?
    pub fn is_axis_aligned(&self) -> bool {
        self.transform[2] == 0.0 && self.transform[4] == 0.0
    }

    /// Cell width and height in world units (absolute values, along the grid's axes).
    pub fn cell_size(&self) -> (f64, f64) {
        let t = &self.transform;
        (t[1].hypot(t[4]), t[2].hypot(t[5]))
    }

    /// Does the transform flip orientation (true for a usual north-up grid, whose row index grows
    /// southwards)?
    pub fn flips_orientation(&self) -> bool {
        let t = &self.transform;
        t[1] * t[5] - t[2] * t[4] < 0.0
    }

    /// Is `v` a missing value under this grid's nodata rule?
    #[inline]
    pub fn is_nodata(&self, v: f64) -> bool {
        v.is_nan() || self.nodata == Some(v)
    }
}

/// Storage type of the grid's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SampleType {
    /// Signed 8-bit integer.
    I8,
    /// Unsigned 8-bit integer.
    U8,
    /// Signed 16-bit integer.
    I16,
    /// Unsigned 16-bit integer.
    U16,
    /// Signed 32-bit integer.
    I32,
    /// Unsigned 32-bit integer.
    U32,
    /// Signed 64-bit integer.
    I64,
    /// Unsigned 64-bit integer.
    U64,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
    /// Decimal text (ESRI ASCII grid).
    Text,
}

/// A whole grid in memory, row-major, missing cells NaN: `f32` when every value is exactly an
/// `f32` (8- and 16-bit integers, float32, and any grid whose values happen to fit), else `f64`.
#[derive(Clone, Debug, PartialEq)]
pub enum Heights {
    /// 4 bytes per cell.
    F32(Vec<f32>),
    /// 8 bytes per cell.
    F64(Vec<f64>),
}

impl Heights {
    /// Number of cells.
    pub fn len(&self) -> usize {
        match self {
            Heights::F32(v) => v.len(),
            Heights::F64(v) => v.len(),
        }
    }

    /// Is the grid empty?
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        match self {
            Heights::F32(v) => 4 * v.len(),
            Heights::F64(v) => 8 * v.len(),
        }
    }
}

/// A grid file opened for reading.
pub struct RasterReader {
    path: PathBuf,
    spec: RasterSpec,
    sample: SampleType,
    source: Source,
}

enum Source {
    Tiff(Box<TiffSource>),
    Ascii(AsciiSource),
}

impl std::fmt::Debug for RasterReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RasterReader")
            .field("path", &self.path)
            .field("spec", &self.spec)
            .field("sample", &self.sample)
            .finish()
    }
}

impl RasterReader {
    /// Opens a GeoTIFF (`.tif`, `.tiff`) or ESRI ASCII grid (`.asc`, or any file starting with
    /// `ncols`), reading only its header.
    ///
    /// # Errors
    /// [`Error::Io`] if the file cannot be opened; [`Error::Format`] / [`Error::Parse`] naming the
    /// file when it is not a supported grid.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
        let mut head = [0u8; 16];
        let n = read_up_to(&mut file, &mut head).map_err(|e| Error::io(path, e))?;
        let magic = [head[0], head[1], head[2], head[3]];
        file.seek(SeekFrom::Start(0))
            .map_err(|e| Error::io(path, e))?;
        if n >= 4
            && (&magic == b"II*\0"
                || &magic == b"MM\0*"
                || &magic == b"II+\0"
                || &magic == b"MM\0+")
        {
            let r = geotiff::open_tiff(path, file)?;
            // Every cell centre in the predicates' exact range (the ASCII reader names the
            // header line instead).
            let (c, w) = (f64::from(r.spec.cols), f64::from(r.spec.rows));
            for corner in [[0.0, 0.0], [c, 0.0], [0.0, w], [c, w]] {
                let p = r.spec.world(corner[0], corner[1]);
                if !(in_exact_range(p[0]) && in_exact_range(p[1])) {
                    return Err(format(
                        path,
                        format!(
                            "the grid's corner ({:e}, {:e}) is outside the coordinates a TIN \
                             can hold exactly (|x| and |y| up to {:e}): check its \
                             georeferencing (ModelTiepoint, ModelPixelScale, \
                             ModelTransformation)",
                            p[0],
                            p[1],
                            crate::geom::predicates::MAX_COORD
                        ),
                    ));
                }
            }
            Ok(r)
        } else if let Some(kind) = crate::input::sniff(&head[..n]) {
            Err(Error::Format {
                path: path.to_path_buf(),
                message: format!("is {kind}, not a GeoTIFF or an ESRI ASCII grid"),
            })
        } else {
            ascii::open_ascii(path, file)
        }
    }

    /// The grid's size, georeferencing, nodata value and CRS.
    pub fn spec(&self) -> &RasterSpec {
        &self.spec
    }

    /// How values are stored in the file.
    pub fn sample_type(&self) -> SampleType {
        self.sample
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads the whole grid, row-major, missing cells as NaN.
    ///
    /// # Errors
    /// As [`RasterReader::read_window`].
    pub fn read_all(&mut self) -> Result<Vec<f64>> {
        let (c, r) = (self.spec.cols, self.spec.rows);
        self.read_window(0, 0, c, r)
    }

    /// Reads the whole grid as compactly as it is exact ([`Heights`]), band by band, so that the
    /// peak memory is the result plus one band (never a full `f64` copy of an `f32`-exact grid).
    ///
    /// # Errors
    /// As [`RasterReader::read_window`].
    pub fn read_heights(&mut self) -> Result<Heights> {
        let rows = self.spec.rows;
        self.read_rows(0, rows)
    }

    /// Reads the full-width rows `row0 .. row0 + rows` as compactly as they are exact
    /// ([`Heights`]), a band of [`RasterReader::read_band_rows`] rows at a time: the peak memory
    /// is the result plus one band as `f64` (see [`RasterReader::read_bytes`]).
    ///
    /// # Errors
    /// As [`RasterReader::read_window`].
    pub fn read_rows(&mut self, row0: u32, rows: u32) -> Result<Heights> {
        let cols = self.spec.cols;
        let band = self.read_band_rows();
        let n = cols as usize * rows as usize;
        let mut out = Heights::F32(Vec::with_capacity(n));
        let (mut r, end) = (row0, row0.saturating_add(rows));
        while r < end {
            // Bands aligned on the file's chunks: a strip or tile row is decoded once.
            let h = (band - r % band).min(end - r);
            let w = self.read_window(0, r, cols, h)?;
            if let Heights::F32(v) = &mut out {
                let start = v.len();
                v.extend(w.iter().map(|&x| x as f32));
                if !w
                    .iter()
                    .zip(&v[start..])
                    .all(|(&x, &f)| f64::from(f) == x || x.is_nan())
                {
                    let mut wide: Vec<f64> = Vec::with_capacity(n);
                    wide.extend(v[..start].iter().map(|&f| f64::from(f)));
                    out = Heights::F64(wide);
                }
            }
            if let Heights::F64(v) = &mut out {
                v.extend_from_slice(&w);
            }
            r += h;
        }
        Ok(out)
    }

    /// The rows [`RasterReader::read_rows`] reads at a time: whole strips or tile rows, about
    /// 256 rows.
    pub fn read_band_rows(&self) -> u32 {
        match &self.source {
            Source::Tiff(t) => t
                .chunk_h
                .max(1)
                .saturating_mul(256u32.div_ceil(t.chunk_h.max(1))),
            Source::Ascii(_) => 256,
        }
    }

    /// Bytes [`RasterReader::read_rows`] holds besides its result when reading `rows` rows, at
    /// most: one band of rows as `f64`, and one decoded TIFF strip or tile (as stored and as
    /// `f64`, see [`RasterReader::chunk_bytes`]).
    pub fn read_bytes(&self, rows: u32) -> u64 {
        let band = u64::from(self.spec.cols) * u64::from(self.read_band_rows().min(rows)) * 8;
        band + self.chunk_bytes()
    }

    /// Bytes one decoded TIFF strip or tile takes (as stored and as `f64`); 0 for a text grid.
    pub fn chunk_bytes(&self) -> u64 {
        match &self.source {
            Source::Tiff(t) => u64::from(t.chunk_w) * u64::from(t.chunk_h) * 16,
            Source::Ascii(_) => 0,
        }
    }

    /// Reads the `cols × rows` window whose top-left cell is `(col0, row0)`, row-major, missing
    /// cells as NaN. Only the strips or tiles that meet the window are decoded.
    ///
    /// # Errors
    /// [`Error::Format`] for a window outside the grid or a damaged file; [`Error::Parse`] for a
    /// bad value in an ASCII grid; [`Error::Io`] when reading fails.
    pub fn read_window(&mut self, col0: u32, row0: u32, cols: u32, rows: u32) -> Result<Vec<f64>> {
        if u64::from(col0) + u64::from(cols) > u64::from(self.spec.cols)
            || u64::from(row0) + u64::from(rows) > u64::from(self.spec.rows)
        {
            return Err(self.format_error(format!(
                "window {cols}×{rows} at ({col0}, {row0}) is outside the {}×{} grid",
                self.spec.cols, self.spec.rows
            )));
        }
        let n = cols as usize * rows as usize;
        let mut out = vec![f64::NAN; n];
        if n == 0 {
            return Ok(out);
        }
        match &mut self.source {
            Source::Tiff(t) => {
                geotiff::read_tiff_window(&self.path, t, [col0, row0, cols, rows], &mut out)?
            }
            Source::Ascii(a) => ascii::read_ascii_window(
                &self.path,
                &self.spec,
                a,
                [col0, row0, cols, rows],
                &mut out,
            )?,
        }
        for v in &mut out {
            if self.spec.is_nodata(*v) {
                *v = f64::NAN;
            }
        }
        Ok(out)
    }

    fn format_error(&self, message: String) -> Error {
        Error::Format {
            path: self.path.clone(),
            message,
        }
    }
}

/// Is `v` a coordinate the predicates handle exactly (finite, `|v| <=`
/// [`MAX_COORD`](crate::geom::predicates::MAX_COORD))? A grid's edges are checked with it, so
/// that every cell centre is.
fn in_exact_range(v: f64) -> bool {
    v.is_finite() && v.abs() <= crate::geom::predicates::MAX_COORD
}

fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

fn format(path: &Path, message: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_grid_with_wrapped_rows_and_prj() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.asc");
        std::fs::write(
            &p,
            "NCOLS 3\nnrows 2\nxllcenter 10\nyllcenter 20\ncellsize 2\nNODATA_value -9999\n\
             1 2\n3\n4 -9999 6\n",
        )
        .unwrap();
        std::fs::write(dir.path().join("g.prj"), "PROJCS[\"x\"]\n").unwrap();
        let mut r = RasterReader::open(&p).unwrap();
        let s = r.spec().clone();
        assert_eq!((s.cols, s.rows), (3, 2));
        assert_eq!(s.transform, [9.0, 2.0, 0.0, 23.0, 0.0, -2.0]);
        assert_eq!(s.cell_center(0, 1), [10.0, 20.0]);
        assert_eq!(s.crs.as_deref(), Some("PROJCS[\"x\"]"));
        let all = r.read_all().unwrap();
        assert_eq!(&all[..4], &[1.0, 2.0, 3.0, 4.0]);
        assert!(all[4].is_nan());
        assert_eq!(all[5], 6.0);
        assert_eq!(r.read_window(1, 1, 2, 1).unwrap()[1], 6.0);
        assert_eq!(r.read_window(0, 0, 1, 2).unwrap(), vec![1.0, 4.0]);
        match r.read_heights().unwrap() {
            Heights::F32(v) => assert_eq!(v[5], 6.0),
            Heights::F64(_) => panic!("small integers fit f32"),
        }
        assert!(r.read_window(2, 0, 2, 1).is_err());
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.asc");
        std::fs::write(
            &p,
            "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 x\n",
        )
        .unwrap();
        let e = RasterReader::open(&p).unwrap().read_all().unwrap_err();
        assert!(e.to_string().contains(":7:"), "{e}");
        std::fs::write(
            &p,
            "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 0.1\n",
        )
        .unwrap();
        assert!(
            matches!(RasterReader::open(&p).unwrap().read_heights().unwrap(), Heights::F64(v) if v[3] == 0.1)
        );
        std::fs::write(
            &p,
            "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3\n",
        )
        .unwrap();
        let e = RasterReader::open(&p).unwrap().read_all().unwrap_err();
        assert!(e.to_string().contains("ends after 3 values"), "{e}");
        std::fs::write(&p, "hello\n").unwrap();
        assert!(RasterReader::open(&p).is_err());
    }

    /// Issue 41, item 8: an extra row, or a `NODATA_value` line after the data, was ignored
    /// (its -9999 read as a height); `xllcorner 1e300` gave a mesh outside the exact range.
    #[test]
    fn ascii_data_after_the_grid_and_edges_out_of_range_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.asc");
        let head = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
        let fails = |text: String, says: &str| {
            std::fs::write(&p, text).unwrap();
            let e = RasterReader::open(&p).and_then(|mut r| r.read_heights().map(|_| ()));
            let e = e.expect_err(says);
            assert_eq!(e.kind(), crate::ErrorKind::Input, "{e}");
            assert!(e.to_string().contains(says), "{e}");
        };
        fails(
            format!("{head}1 2\n3 4\n5 6\n"),
            ":8: \"5\" after the grid's last value",
        );
        fails(
            format!("{head}1 2\n3 -9999\nNODATA_value -9999\n"),
            ":8: \"NODATA_value\" after the grid's last value: a header line",
        );
        fails(format!("{head}1 2\n3 inf\n"), ":7: value \"inf\"");
        fails(
            head.replace("xllcorner 0", "xllcorner 1e300") + "1 2\n3 4\n",
            ":3: xllcorner 1e300",
        );
        fails(
            head.replace("cellsize 1", "cellsize 1e16") + "1 2\n3 4\n",
            ":5: cellsize 1e16: the grid's east edge at 2e16",
        );
        // Trailing whitespace and a last line without a line break are fine; a window that
        // does not reach the last row does not read on.
        std::fs::write(&p, format!("{head}1 2\n3 4 \n\n  \t\n")).unwrap();
        let mut r = RasterReader::open(&p).unwrap();
        assert_eq!(r.read_all().unwrap(), vec![1.0, 2.0, 3.0, 4.0]);
        std::fs::write(&p, format!("{head}1 2\n3 4\n5\n")).unwrap();
        let mut r = RasterReader::open(&p).unwrap();
        assert_eq!(r.read_window(0, 0, 2, 1).unwrap(), vec![1.0, 2.0]);
        assert!(r.read_window(0, 1, 2, 1).is_err());
    }
}
