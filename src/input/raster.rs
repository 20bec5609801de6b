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
//! north to south, any whitespace between values. A `.prj` file beside it supplies the CRS (WKT).
//! A window is read by scanning from the nearest row start seen before, so reading windows in
//! row order parses the file about once per column of windows.

use crate::error::{Error, Result};
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

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

struct TiffSource {
    decoder: Decoder<BufReader<File>>,
    chunk_w: u32,
    chunk_h: u32,
    across: u32,
}

struct AsciiSource {
    /// Known row starts: `(row, byte offset, line number)`, increasing.
    rows: Vec<(u32, u64, u64)>,
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
        let mut magic = [0u8; 4];
        let n = read_up_to(&mut file, &mut magic).map_err(|e| Error::io(path, e))?;
        file.seek(SeekFrom::Start(0))
            .map_err(|e| Error::io(path, e))?;
        if n == 4
            && (&magic == b"II*\0"
                || &magic == b"MM\0*"
                || &magic == b"II+\0"
                || &magic == b"MM\0+")
        {
            open_tiff(path, file)
        } else {
            open_ascii(path, file)
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
        let (cols, rows) = (self.spec.cols, self.spec.rows);
        let band = match &self.source {
            // Whole chunks: a strip or tile row is decoded once.
            Source::Tiff(t) => t
                .chunk_h
                .max(1)
                .saturating_mul(256u32.div_ceil(t.chunk_h.max(1))),
            Source::Ascii(_) => 256,
        };
        let n = cols as usize * rows as usize;
        let mut out = Heights::F32(Vec::with_capacity(n));
        let mut r0 = 0;
        while r0 < rows {
            let h = band.min(rows - r0);
            let w = self.read_window(0, r0, cols, h)?;
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
            r0 += h;
        }
        Ok(out)
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
            Source::Tiff(t) => read_tiff_window(&self.path, t, [col0, row0, cols, rows], &mut out)?,
            Source::Ascii(a) => read_ascii_window(
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

fn tiff_error(path: &Path, e: tiff::TiffError) -> Error {
    match e {
        tiff::TiffError::IoError(io) => Error::io(path, io),
        other => format(path, format!("cannot read the TIFF: {other}")),
    }
}

// ---- GeoTIFF ----------------------------------------------------------------------------------

fn open_tiff(path: &Path, file: File) -> Result<RasterReader> {
    let mut limits = Limits::default();
    limits.ifd_value_size = 64 << 20;
    let mut dec = Decoder::new(BufReader::new(file))
        .map_err(|e| tiff_error(path, e))?
        .with_limits(limits);
    let (cols, rows) = dec.dimensions().map_err(|e| tiff_error(path, e))?;
    let spp: u16 = dec
        .find_tag_unsigned(Tag::SamplesPerPixel)
        .map_err(|e| tiff_error(path, e))?
        .unwrap_or(1);
    if spp != 1 {
        return Err(format(
            path,
            format!("{spp} samples per pixel: only single-band grids are supported"),
        ));
    }
    let bits: u16 = dec
        .find_tag_unsigned(Tag::BitsPerSample)
        .map_err(|e| tiff_error(path, e))?
        .unwrap_or(1);
    let fmt: u16 = dec
        .find_tag_unsigned(Tag::SampleFormat)
        .map_err(|e| tiff_error(path, e))?
        .unwrap_or(1);
    let sample = match (fmt, bits) {
        (1, 8) => SampleType::U8,
        (1, 16) => SampleType::U16,
        (1, 32) => SampleType::U32,
        (1, 64) => SampleType::U64,
        (2, 8) => SampleType::I8,
        (2, 16) => SampleType::I16,
        (2, 32) => SampleType::I32,
        (2, 64) => SampleType::I64,
        (3, 32) => SampleType::F32,
        (3, 64) => SampleType::F64,
        _ => {
            return Err(format(
                path,
                format!("unsupported sample format {fmt} with {bits} bits per sample"),
            ));
        }
    };
    let transform = tiff_transform(path, &mut dec, cols, rows)?;
    let nodata =
        match dec
            .find_tag(Tag::GdalNodata)
            .map_err(|e| tiff_error(path, e))?
        {
            None => None,
            Some(v) => {
                let s = v.into_string().map_err(|e| tiff_error(path, e))?;
                let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
                match s.to_ascii_lowercase().as_str() {
                    "nan" | "-nan" => None, // NaN cells are always missing
                    _ => Some(s.parse::<f64>().map_err(|_| {
                        format(path, format!("GDAL_NODATA tag {s:?} is not a number"))
                    })?),
                }
            }
        };
    let crs = tiff_crs(path, &mut dec)?;
    let (chunk_w, chunk_h) = dec.chunk_dimensions();
    if chunk_w == 0 || chunk_h == 0 {
        return Err(format(path, "TIFF chunks of size zero"));
    }
    let across = match dec.get_chunk_type() {
        ChunkType::Strip => 1,
        ChunkType::Tile => cols.div_ceil(chunk_w),
    };
    Ok(RasterReader {
        path: path.to_path_buf(),
        spec: RasterSpec {
            cols,
            rows,
            transform,
            nodata,
            crs,
        },
        sample,
        source: Source::Tiff(Box::new(TiffSource {
            decoder: dec,
            chunk_w: if across == 1 { cols } else { chunk_w },
            chunk_h,
            across,
        })),
    })
}

fn f64_tag(path: &Path, dec: &mut Decoder<BufReader<File>>, tag: Tag) -> Result<Option<Vec<f64>>> {
    match dec.find_tag(tag).map_err(|e| tiff_error(path, e))? {
        None => Ok(None),
        Some(v) => Ok(Some(v.into_f64_vec().map_err(|e| tiff_error(path, e))?)),
    }
}

fn geo_keys(path: &Path, dec: &mut Decoder<BufReader<File>>) -> Result<Vec<[u16; 4]>> {
    let Some(v) = dec
        .find_tag(Tag::GeoKeyDirectoryTag)
        .map_err(|e| tiff_error(path, e))?
    else {
        return Ok(Vec::new());
    };
    let dir = v.into_u16_vec().map_err(|e| tiff_error(path, e))?;
    if dir.len() < 4 {
        return Err(format(path, "GeoKeyDirectory is too short"));
    }
    let n = dir[3] as usize;
    if dir.len() < 4 + 4 * n {
        return Err(format(
            path,
            "GeoKeyDirectory is shorter than its key count",
        ));
    }
    Ok((0..n)
        .map(|i| {
            let k = &dir[4 + 4 * i..8 + 4 * i];
            [k[0], k[1], k[2], k[3]]
        })
        .collect())
}

/// The value of a SHORT geokey stored in the directory itself.
fn short_key(keys: &[[u16; 4]], id: u16) -> Option<u16> {
    keys.iter().find(|k| k[0] == id && k[1] == 0).map(|k| k[3])
}

const GT_RASTER_TYPE: u16 = 1025;
const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;
const USER_DEFINED: u16 = 32767;

fn tiff_transform(
    path: &Path,
    dec: &mut Decoder<BufReader<File>>,
    cols: u32,
    rows: u32,
) -> Result<[f64; 6]> {
    let keys = geo_keys(path, dec)?;
    let pixel_is_point = short_key(&keys, GT_RASTER_TYPE) == Some(2);
    let mut t = if let Some(m) = f64_tag(path, dec, Tag::ModelTransformationTag)? {
        if m.len() < 16 {
            return Err(format(path, "ModelTransformation needs 16 values"));
        }
        [m[3], m[0], m[1], m[7], m[4], m[5]]
    } else {
        let scale = f64_tag(path, dec, Tag::ModelPixelScaleTag)?;
        let tie = f64_tag(path, dec, Tag::ModelTiepointTag)?;
        match (scale, tie) {
            (Some(s), Some(tp)) if s.len() >= 2 && tp.len() >= 6 => {
                // x = X + (col - I)·sx, y = Y - (row - J)·sy.
                [
                    tp[3] - tp[0] * s[0],
                    s[0],
                    0.0,
                    tp[4] + tp[1] * s[1],
                    0.0,
                    -s[1],
                ]
            }
            _ => {
                // No georeferencing: cell indices, north-up, the first row at the top.
                [0.0, 1.0, 0.0, f64::from(rows), 0.0, -1.0]
            }
        }
    };
    if pixel_is_point {
        // The tie point names a cell centre: move the transform to the corner.
        t[0] -= 0.5 * (t[1] + t[2]);
        t[3] -= 0.5 * (t[4] + t[5]);
    }
    if !t.iter().all(|v| v.is_finite()) || t[1] * t[5] - t[2] * t[4] == 0.0 {
        return Err(format(path, format!("degenerate georeferencing {t:?}")));
    }
    let _ = cols;
    Ok(t)
}

fn tiff_crs(path: &Path, dec: &mut Decoder<BufReader<File>>) -> Result<Option<String>> {
    let keys = geo_keys(path, dec)?;
    for id in [PROJECTED_CS_TYPE, GEOGRAPHIC_TYPE] {
        if let Some(code) = short_key(&keys, id)
            && code != USER_DEFINED
            && code != 0
        {
            return Ok(Some(format!("EPSG:{code}")));
        }
    }
    Ok(None)
}

fn read_tiff_window(path: &Path, t: &mut TiffSource, w: [u32; 4], out: &mut [f64]) -> Result<()> {
    let [col0, row0, cols, rows] = w;
    let (cw, ch) = (t.chunk_w, t.chunk_h);
    let (cx0, cx1) = (col0 / cw, (col0 + cols - 1) / cw);
    let (cy0, cy1) = (row0 / ch, (row0 + rows - 1) / ch);
    for cy in cy0..=cy1 {
        for cx in cx0..=cx1 {
            let index = cy * t.across + cx;
            let data = t
                .decoder
                .read_chunk(index)
                .map_err(|e| tiff_error(path, e))?;
            let (dw, dh) = t.decoder.chunk_data_dimensions(index);
            let values = chunk_to_f64(data);
            // The decoded chunk is `dw` wide, or the full chunk width when padded.
            let stride = if values.len() >= (cw * dh) as usize && dw < cw && t.across > 1 {
                cw as usize
            } else {
                dw as usize
            };
            if values.len() < stride * (dh as usize - 1) + dw as usize {
                return Err(format(path, format!("TIFF chunk {index} is truncated")));
            }
            let (gx0, gy0) = (cx * cw, cy * ch);
            let ys = row0.max(gy0)..(row0 + rows).min(gy0 + dh);
            let xs = col0.max(gx0)..(col0 + cols).min(gx0 + dw);
            for y in ys {
                let src = (y - gy0) as usize * stride + (xs.start - gx0) as usize;
                let dst = (y - row0) as usize * cols as usize + (xs.start - col0) as usize;
                let n = xs.len();
                out[dst..dst + n].copy_from_slice(&values[src..src + n]);
            }
        }
    }
    Ok(())
}

fn chunk_to_f64(data: DecodingResult) -> Vec<f64> {
    fn conv<T: Copy>(v: Vec<T>, f: impl Fn(T) -> f64) -> Vec<f64> {
        v.into_iter().map(f).collect()
    }
    match data {
        DecodingResult::U8(v) => conv(v, f64::from),
        DecodingResult::U16(v) => conv(v, f64::from),
        DecodingResult::U32(v) => conv(v, f64::from),
        DecodingResult::U64(v) => conv(v, |x| x as f64),
        DecodingResult::I8(v) => conv(v, f64::from),
        DecodingResult::I16(v) => conv(v, f64::from),
        DecodingResult::I32(v) => conv(v, f64::from),
        DecodingResult::I64(v) => conv(v, |x| x as f64),
        DecodingResult::F16(v) => conv(v, f64::from),
        DecodingResult::F32(v) => conv(v, f64::from),
        DecodingResult::F64(v) => v,
    }
}

// ---- ESRI ASCII grid --------------------------------------------------------------------------

fn open_ascii(path: &Path, file: File) -> Result<RasterReader> {
    let mut r = BufReader::new(file);
    let mut header: Vec<(String, f64)> = Vec::new();
    let mut offset = 0u64;
    let mut line_no = 0u64;
    let mut line = String::new();
    loop {
        let start = offset;
        line.clear();
        let n = r.read_line(&mut line).map_err(|e| Error::io(path, e))?;
        if n == 0 {
            break;
        }
        let mut it = line.split_whitespace();
        let Some(key) = it.next() else {
            offset += n as u64;
            line_no += 1;
            continue;
        };
        if !key.as_bytes()[0].is_ascii_alphabetic() {
            // First data line.
            offset = start;
            break;
        }
        line_no += 1;
        offset += n as u64;
        let value = it
            .next()
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| Error::Parse {
                path: path.to_path_buf(),
                line: line_no,
                message: format!("header line {key:?} needs a number"),
            })?;
        header.push((key.to_ascii_lowercase(), value));
    }
    let get = |k: &str| header.iter().find(|(h, _)| h == k).map(|&(_, v)| v);
    let need = |k: &str| {
        get(k).ok_or_else(|| {
            format(
                path,
                format!("not a GeoTIFF, and not an ESRI ASCII grid: header has no {k:?}"),
            )
        })
    };
    let cols = need("ncols")?;
    let rows = need("nrows")?;
    for (k, v) in [("ncols", cols), ("nrows", rows)] {
        if !(v >= 1.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0) {
            return Err(format(path, format!("{k} {v} is not a positive integer")));
        }
    }
    let (cols, rows) = (cols as u32, rows as u32);
    let (dx, dy) = match (get("cellsize"), get("dx"), get("dy")) {
        (Some(c), _, _) => (c, c),
        (None, Some(dx), Some(dy)) => (dx, dy),
        _ => return Err(format(path, "header has no \"cellsize\" (nor dx and dy)")),
    };
    if !(dx > 0.0 && dy > 0.0 && dx.is_finite() && dy.is_finite()) {
        return Err(format(
            path,
            format!("cell size {dx} × {dy} is not positive"),
        ));
    }
    let x0 = match (get("xllcorner"), get("xllcenter")) {
        (Some(x), _) => x,
        (None, Some(x)) => x - 0.5 * dx,
        _ => {
            return Err(format(
                path,
                "header has no \"xllcorner\" nor \"xllcenter\"",
            ));
        }
    };
    let y0 = match (get("yllcorner"), get("yllcenter")) {
        (Some(y), _) => y,
        (None, Some(y)) => y - 0.5 * dy,
        _ => {
            return Err(format(
                path,
                "header has no \"yllcorner\" nor \"yllcenter\"",
            ));
        }
    };
    let top = y0 + f64::from(rows) * dy;
    let crs = std::fs::read_to_string(path.with_extension("prj"))
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty());
    Ok(RasterReader {
        path: path.to_path_buf(),
        spec: RasterSpec {
            cols,
            rows,
            transform: [x0, dx, 0.0, top, 0.0, -dy],
            nodata: get("nodata_value"),
            crs,
        },
        sample: SampleType::Text,
        source: Source::Ascii(AsciiSource {
            rows: vec![(0, offset, line_no + 1)],
        }),
    })
}

fn read_ascii_window(
    path: &Path,
    spec: &RasterSpec,
    a: &mut AsciiSource,
    w: [u32; 4],
    out: &mut [f64],
) -> Result<()> {
    let [col0, row0, cols, rows] = w;
    let &(start_row, start, start_line) = a
        .rows
        .iter()
        .rev()
        .find(|r| r.0 <= row0)
        .expect("row 0 is always known");
    let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
    file.seek(SeekFrom::Start(start))
        .map_err(|e| Error::io(path, e))?;
    let mut r = BufReader::with_capacity(1 << 16, file);
    let ncols = spec.cols as u64;
    let mut index = u64::from(start_row) * ncols; // token index of the next value
    let end = u64::from(row0 + rows) * ncols;
    let (mut offset, mut line) = (start, start_line);
    let mut token = Vec::with_capacity(32);
    let mut token_start = offset;
    loop {
        let buf = r.fill_buf().map_err(|e| Error::io(path, e))?;
        if buf.is_empty() {
            break;
        }
        let n = buf.len();
        for &b in buf {
            if b.is_ascii_whitespace() {
                if !token.is_empty() {
                    store_token(path, spec, a, &token, index, token_start, line, w, out)?;
                    index += 1;
                    token.clear();
                    if index >= end {
                        return Ok(());
                    }
                }
                if b == b'\n' {
                    line += 1;
                }
            } else {
                if token.is_empty() {
                    token_start = offset;
                }
                token.push(b);
            }
            offset += 1;
        }
        r.consume(n);
    }
    if !token.is_empty() {
        store_token(path, spec, a, &token, index, token_start, line, w, out)?;
        index += 1;
    }
    if index < end {
        return Err(Error::Parse {
            path: path.to_path_buf(),
            line,
            message: format!(
                "the grid ends after {index} values; the header promises {} × {}",
                spec.cols, spec.rows
            ),
        });
    }
    let _ = (col0, cols);
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn store_token(
    path: &Path,
    spec: &RasterSpec,
    a: &mut AsciiSource,
    token: &[u8],
    index: u64,
    token_start: u64,
    line: u64,
    w: [u32; 4],
    out: &mut [f64],
) -> Result<()> {
    let [col0, row0, cols, _] = w;
    let ncols = u64::from(spec.cols);
    let (row, col) = ((index / ncols) as u32, (index % ncols) as u32);
    if col == 0 && a.rows.last().is_some_and(|r| r.0 < row) {
        a.rows.push((row, token_start, line));
    }
    if row < row0 || col < col0 || col >= col0 + cols {
        return Ok(());
    }
    let text = std::str::from_utf8(token).ok();
    let v = text
        .and_then(|t| t.parse::<f64>().ok())
        .ok_or_else(|| Error::Parse {
            path: path.to_path_buf(),
            line,
            message: format!(
                "value {:?} of row {row}, column {col} is not a number",
                String::from_utf8_lossy(token)
            ),
        })?;
    out[(row - row0) as usize * cols as usize + (col - col0) as usize] = v;
    Ok(())
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
}
