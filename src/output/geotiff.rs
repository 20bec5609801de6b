//! Float32 GeoTIFF output with random access to rows and cells.
//!
//! The file is a plain little-endian TIFF (BigTIFF when the pixels alone pass 4 GiB): one IFD,
//! uncompressed, one row per strip, `SampleFormat = IEEE float`, and the georeferencing GDAL
//! reads:
//! - `ModelPixelScaleTag` (33550) `(cell, cell, 0)` and `ModelTiepointTag` (33922) tying raster
//!   point (0, 0) — the outer upper-left corner — to [`GridSpec::origin`];
//! - `GeoKeyDirectoryTag` (34735) with `GTRasterTypeGeoKey = PixelIsArea` and, when the CRS has an
//!   EPSG code, `GTModelTypeGeoKey` plus `ProjectedCSTypeGeoKey` (or `GeographicTypeGeoKey`) and
//!   `VerticalCSTypeGeoKey` when a vertical code is known;
//! - `GDAL_NODATA` (42113), the nodata value as ASCII text.
//!
//! Everything before the pixels (header, IFD, tag data) is written at creation; the pixel area has
//! a fixed place, so rows can be written in any order (a DEM fills the image bottom-up, as the sweep
//! goes north) and single cells patched later. Rows never written read as zero bytes, so every row
//! must be written once; [`GeoTiffWriter::finish`] fills the rows never written with nodata.

use super::raster::{GridWriter, check_cell, check_span};
use crate::crs::{Crs, HorizontalKind};
use crate::error::{Error, Result};
use crate::output::AtomicFile;
use crate::raster::GridSpec;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// TIFF field types.
pub(crate) const SHORT: u16 = 3;
pub(crate) const LONG: u16 = 4;
const ASCII: u16 = 2;
const DOUBLE: u16 = 12;
pub(crate) const LONG8: u16 = 16;

/// A float32 GeoTIFF being written (see the module docs).
#[derive(Debug)]
pub struct GeoTiffWriter {
    file: AtomicFile,
    spec: GridSpec,
    /// Byte offset of row 0's first pixel.
    data_offset: u64,
    /// Which rows were written (to fill the others at the end).
    written: Vec<bool>,
    /// A second handle on the temporary file, for reading cells back.
    reader: Option<File>,
    path: PathBuf,
}

/// One IFD entry before layout.
pub(crate) struct Entry {
    pub(crate) tag: u16,
    pub(crate) kind: u16,
    pub(crate) count: u64,
    pub(crate) bytes: Vec<u8>,
}

pub(crate) fn shorts(tag: u16, v: &[u16]) -> Entry {
    Entry {
        tag,
        kind: SHORT,
        count: v.len() as u64,
        bytes: v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    }
}

pub(crate) fn longs(tag: u16, v: &[u32]) -> Entry {
    Entry {
        tag,
        kind: LONG,
        count: v.len() as u64,
        bytes: v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    }
}

pub(crate) fn doubles(tag: u16, v: &[f64]) -> Entry {
    Entry {
        tag,
        kind: DOUBLE,
        count: v.len() as u64,
        bytes: v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    }
}

pub(crate) fn ascii(tag: u16, s: &str) -> Entry {
    let mut bytes = s.as_bytes().to_vec();
    bytes.push(0);
    Entry {
        tag,
        kind: ASCII,
        count: bytes.len() as u64,
        bytes,
    }
}

/// `offsets` or byte counts as `LONG` (classic TIFF) or `LONG8` (BigTIFF) values.
pub(crate) fn offsets(tag: u16, v: &[u64], big: bool) -> Entry {
    if big {
        Entry {
            tag,
            kind: LONG8,
            count: v.len() as u64,
            bytes: v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    } else {
        longs(tag, &v.iter().map(|&x| x as u32).collect::<Vec<_>>())
    }
}

/// The georeferencing tags of a north-up image whose outer upper-left corner is `origin`, with
/// cells of `size` (x, y), a CRS and a nodata value: `ModelPixelScale`, `ModelTiepoint`,
/// `GeoKeyDirectory`, `GDAL_NODATA`.
pub(crate) fn geo_entries(
    origin: [f64; 2],
    size: [f64; 2],
    crs: Option<&Crs>,
    nodata: Option<&str>,
) -> Vec<Entry> {
    let mut e = vec![
        doubles(33550, &[size[0], size[1], 0.0]),
        doubles(33922, &[0.0, 0.0, 0.0, origin[0], origin[1], 0.0]),
        shorts(34735, &geokeys(crs)),
    ];
    if let Some(n) = nodata {
        e.push(ascii(42113, n));
    }
    e
}

/// Bytes of one IFD and its out-of-line tag data.
pub(crate) fn ifd_size(entries: &[Entry], big: bool) -> u64 {
    let (inline, entry_size, count_size) = if big { (8, 20, 8) } else { (4, 12, 2) };
    let mut n = count_size + entries.len() as u64 * entry_size + inline as u64;
    for e in entries {
        if e.bytes.len() > inline {
            n += e.bytes.len() as u64 + (e.bytes.len() as u64 & 1);
        }
    }
    n
}

/// Encodes IFDs one after the other from file offset `start` (even), each followed by its tag
/// data and chained to the next; the entries are sorted by tag here. Returns the bytes and each
/// IFD's offset.
pub(crate) fn encode_ifds(ifds: &mut [Vec<Entry>], start: u64, big: bool) -> (Vec<u8>, Vec<u64>) {
    let (inline, entry_size, count_size) = if big { (8, 20, 8) } else { (4, 12, 2) };
    let mut out = Vec::new();
    let mut at = Vec::with_capacity(ifds.len());
    let mut pos = start;
    let last = ifds.len().saturating_sub(1);
    for (i, entries) in ifds.iter_mut().enumerate() {
        entries.sort_by_key(|e| e.tag);
        at.push(pos);
        let size = ifd_size(entries, big);
        let mut extra_offset = pos + count_size + entries.len() as u64 * entry_size + inline as u64;
        let mut extra = Vec::new();
        let word = |out: &mut Vec<u8>, v: u64| {
            if big {
                out.extend_from_slice(&v.to_le_bytes());
            } else {
                out.extend_from_slice(&(v as u32).to_le_bytes());
            }
        };
        if big {
            out.extend_from_slice(&(entries.len() as u64).to_le_bytes());
        } else {
            out.extend_from_slice(&(entries.len() as u16).to_le_bytes());
        }
        for e in entries.iter() {
            out.extend_from_slice(&e.tag.to_le_bytes());
            out.extend_from_slice(&e.kind.to_le_bytes());
            word(&mut out, e.count);
            if e.bytes.len() <= inline {
                let mut v = e.bytes.clone();
                v.resize(inline, 0);
                out.extend_from_slice(&v);
            } else {
                word(&mut out, extra_offset);
                extra.extend_from_slice(&e.bytes);
                if e.bytes.len() & 1 == 1 {
                    extra.push(0);
                }
                extra_offset += e.bytes.len() as u64 + (e.bytes.len() as u64 & 1);
            }
        }
        let next = if i < last { pos + size } else { 0 };
        word(&mut out, next);
        out.extend_from_slice(&extra);
        pos += size;
    }
    (out, at)
}

/// The TIFF header pointing at the first IFD.
pub(crate) fn header(big: bool, first_ifd: u64) -> Vec<u8> {
    let mut out = b"II".to_vec();
    if big {
        out.extend_from_slice(&43u16.to_le_bytes());
        out.extend_from_slice(&8u16.to_le_bytes());
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(&first_ifd.to_le_bytes());
    } else {
        out.extend_from_slice(&42u16.to_le_bytes());
        out.extend_from_slice(&(first_ifd as u32).to_le_bytes());
    }
    out
}

/// The GeoKey directory for a CRS (always with `GTRasterTypeGeoKey = PixelIsArea`).
fn geokeys(crs: Option<&Crs>) -> Vec<u16> {
    let mut keys: Vec<[u16; 4]> = vec![[1025, 0, 1, 1]];
    let horizontal = crs.and_then(|c| c.horizontal_epsg());
    let code16 = |c: u32| u16::try_from(c).ok();
    if let Some((code, kind)) = horizontal.and_then(|(c, k)| code16(c).map(|c| (c, k))) {
        let (model, key) = match kind {
            HorizontalKind::Projected => (1, 3072),
            HorizontalKind::Geographic => (2, 2048),
        };
        keys.push([1024, 0, 1, model]);
        keys.push([key, 0, 1, code]);
        // A unit override of the input's keys (feet) goes with its code.
        if let (HorizontalKind::Projected, Some(u)) = (kind, crs.and_then(|c| c.linear_units)) {
            keys.push([3076, 0, 1, u]);
        }
    }
    if let Some(v) = crs.and_then(|c| c.vertical_epsg).and_then(code16) {
        keys.push([4096, 0, 1, v]);
        if let Some(u) = crs.and_then(|c| c.vertical_units) {
            keys.push([4099, 0, 1, u]);
        }
    }
    keys.sort_unstable();
    let mut dir = vec![1, 1, 0, keys.len() as u16];
    dir.extend(keys.iter().flatten());
    dir
}

/// Shortest text that reads back as exactly `v` (GDAL parses it with `CPLAtof`).
pub(crate) fn nodata_text(v: f32) -> String {
    if v.is_nan() {
        "nan".to_string()
    } else {
        format!("{v}")
    }
}

impl GeoTiffWriter {
    /// Creates the file (under a temporary name until [`GridWriter::finish`]) and writes
    /// everything but the pixels.
    ///
    /// # Errors
    /// [`Error::Output`] for an empty grid or a bad cell size; [`Error::Write`] naming `path`.
    pub fn create(path: &Path, spec: &GridSpec) -> Result<GeoTiffWriter> {
        Self::create_with(path, spec, false)
    }

    /// As [`GeoTiffWriter::create`], in the BigTIFF layout when `bigtiff` (otherwise only when
    /// the file would pass 4 GiB).
    ///
    /// # Errors
    /// As [`GeoTiffWriter::create`].
    pub fn create_with(path: &Path, spec: &GridSpec, bigtiff: bool) -> Result<GeoTiffWriter> {
        let bad = |message: String| Error::Output {
            path: path.to_path_buf(),
            message,
        };
        if spec.is_empty() {
            return Err(bad(format!(
                "the grid is empty ({} × {} cells)",
                spec.cols, spec.rows
            )));
        }
        if !(spec.cell > 0.0 && spec.cell.is_finite()) {
            return Err(bad(format!("bad cell size {}", spec.cell)));
        }
        let row_bytes = u64::from(spec.cols) * 4;
        let pixels = row_bytes * u64::from(spec.rows);
        // Room for the header, IFD and tag data (about 200 bytes + 8 per row): a generous bound.
        let meta_bound = 4096 + 16 * u64::from(spec.rows);
        let big = bigtiff || pixels + meta_bound > u64::from(u32::MAX);
        let (header, data_offset) = Self::layout(spec, big)?;
        let mut file = AtomicFile::create_seekable(path, "a GeoTIFF")?;
        file.write_all(&header).map_err(|e| file.err(e))?;
        Ok(GeoTiffWriter {
            file,
            spec: spec.clone(),
            data_offset,
            written: vec![false; spec.rows as usize],
            reader: None,
            path: path.to_path_buf(),
        })
    }

    /// Header + IFD + tag data, and the offset where pixels start.
    fn layout(spec: &GridSpec, big: bool) -> Result<(Vec<u8>, u64)> {
        let rows = u64::from(spec.rows);
        let row_bytes = u64::from(spec.cols) * 4;
        let [x0, y0] = spec.origin();
        let mut entries = vec![
            longs(256, &[spec.cols]),
            longs(257, &[spec.rows]),
            shorts(258, &[32]),
            shorts(259, &[1]),
            shorts(262, &[1]),
            // 273 StripOffsets: filled in once the data offset is known.
            shorts(277, &[1]),
            longs(278, &[1]),
            // 279 StripByteCounts: below.
            shorts(284, &[1]),
            shorts(339, &[3]),
        ];
        entries.extend(geo_entries(
            [x0, y0],
            [spec.cell, spec.cell],
            spec.crs.as_ref(),
            Some(&nodata_text(spec.nodata)),
        ));
        let counts = if big {
            Entry {
                tag: 279,
                kind: LONG8,
                count: rows,
                bytes: (0..rows).flat_map(|_| row_bytes.to_le_bytes()).collect(),
            }
        } else {
            longs(279, &vec![row_bytes as u32; rows as usize])
        };
        entries.push(counts);
        // Placeholder offsets of the right size; patched below.
        entries.push(Entry {
            tag: 273,
            kind: if big { LONG8 } else { LONG },
            count: rows,
            bytes: vec![0; (rows * if big { 8 } else { 4 }) as usize],
        });
        entries.sort_by_key(|e| e.tag);
        let (inline, entry_size, head) = if big { (8, 20, 16) } else { (4, 12, 8) };
        let count_size = if big { 8 } else { 2 };
        let ifd_size = count_size + entries.len() as u64 * entry_size + inline as u64;
        let mut extra_offset = head + ifd_size;
        let mut extra_total = 0u64;
        for e in &entries {
            if e.bytes.len() > inline {
                extra_total += e.bytes.len() as u64 + (e.bytes.len() as u64 & 1);
            }
        }
        let data_offset = (extra_offset + extra_total).div_ceil(16) * 16;
        // Now the strip offsets.
        for e in entries.iter_mut().filter(|e| e.tag == 273) {
            e.bytes = (0..rows)
                .flat_map(|r| {
                    let off = data_offset + r * row_bytes;
                    if big {
                        off.to_le_bytes().to_vec()
                    } else {
                        (off as u32).to_le_bytes().to_vec()
                    }
                })
                .collect();
        }
        let mut out = Vec::with_capacity(data_offset as usize);
        if big {
            out.extend_from_slice(b"II");
            out.extend_from_slice(&43u16.to_le_bytes());
            out.extend_from_slice(&8u16.to_le_bytes());
            out.extend_from_slice(&0u16.to_le_bytes());
            out.extend_from_slice(&16u64.to_le_bytes());
            out.extend_from_slice(&(entries.len() as u64).to_le_bytes());
        } else {
            out.extend_from_slice(b"II");
            out.extend_from_slice(&42u16.to_le_bytes());
            out.extend_from_slice(&8u32.to_le_bytes());
            out.extend_from_slice(&(entries.len() as u16).to_le_bytes());
        }
        let mut extra = Vec::new();
        for e in &entries {
            out.extend_from_slice(&e.tag.to_le_bytes());
            out.extend_from_slice(&e.kind.to_le_bytes());
            if big {
                out.extend_from_slice(&e.count.to_le_bytes());
            } else {
                out.extend_from_slice(&(e.count as u32).to_le_bytes());
            }
            if e.bytes.len() <= inline {
                let mut v = e.bytes.clone();
                v.resize(inline, 0);
                out.extend_from_slice(&v);
            } else {
                if big {
                    out.extend_from_slice(&extra_offset.to_le_bytes());
                } else {
                    out.extend_from_slice(&(extra_offset as u32).to_le_bytes());
                }
                extra.extend_from_slice(&e.bytes);
                if e.bytes.len() & 1 == 1 {
                    extra.push(0);
                }
                extra_offset += e.bytes.len() as u64 + (e.bytes.len() as u64 & 1);
            }
        }
        out.extend_from_slice(&vec![0u8; inline]); // next IFD: none
        out.extend_from_slice(&extra);
        out.resize(data_offset as usize, 0);
        Ok((out, data_offset))
    }

    fn offset(&self, row: u32, col: u32) -> u64 {
        self.data_offset + (u64::from(row) * u64::from(self.spec.cols) + u64::from(col)) * 4
    }

    fn write_at(&mut self, offset: u64, bytes: &[u8]) -> Result<()> {
        let f = &mut self.file;
        f.seek(SeekFrom::Start(offset)).map_err(|e| f.err(e))?;
        f.write_all(bytes).map_err(|e| f.err(e))
    }
}

impl GridWriter for GeoTiffWriter {
    fn spec(&self) -> &GridSpec {
        &self.spec
    }

    fn write_row(&mut self, row: u32, values: &[f32]) -> Result<()> {
        check_cell(&self.spec, &self.path, row, 0)?;
        if values.len() != self.spec.cols as usize {
            return Err(Error::Output {
                path: self.path.clone(),
                message: format!(
                    "row {row} has {} values, the grid {} columns",
                    values.len(),
                    self.spec.cols
                ),
            });
        }
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.written[row as usize] = true;
        self.write_at(self.offset(row, 0), &bytes)
    }

    fn write_cell(&mut self, row: u32, col: u32, value: f32) -> Result<()> {
        self.write_span(row, col, &[value])
    }

    fn read_cell(&mut self, row: u32, col: u32) -> Result<f32> {
        let mut v = [0f32];
        self.read_span(row, col, &mut v)?;
        Ok(v[0])
    }

    fn read_span(&mut self, row: u32, col: u32, out: &mut [f32]) -> Result<()> {
        check_span(&self.spec, &self.path, row, col, out.len())?;
        if !self.written[row as usize] {
            out.fill(self.spec.nodata);
            return Ok(());
        }
        let offset = self.offset(row, col);
        let f = &mut self.file;
        f.flush().map_err(|e| f.err(e))?;
        if self.reader.is_none() {
            let temp = self
                .file
                .temp_path()
                .map(Path::to_path_buf)
                .ok_or_else(|| Error::Internal("a GeoTIFF being written to a stream".into()))?;
            self.reader = Some(File::open(&temp).map_err(|e| Error::write(&temp, e))?);
        }
        let path = &self.path;
        let reader = self.reader.as_mut().expect("opened above");
        let mut b = vec![0u8; 4 * out.len()];
        reader
            .seek(SeekFrom::Start(offset))
            .and_then(|_| reader.read_exact(&mut b))
            .map_err(|e| Error::write(path, e))?;
        for (v, c) in out.iter_mut().zip(b.chunks_exact(4)) {
            *v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        }
        Ok(())
    }

    fn write_span(&mut self, row: u32, col: u32, values: &[f32]) -> Result<()> {
        check_span(&self.spec, &self.path, row, col, values.len())?;
        if !self.written[row as usize] {
            let nodata = vec![self.spec.nodata; self.spec.cols as usize];
            self.write_row(row, &nodata)?;
        }
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.write_at(self.offset(row, col), &bytes)
    }

    fn finish(mut self: Box<Self>) -> Result<u64> {
        let nodata = vec![self.spec.nodata; self.spec.cols as usize];
        for row in 0..self.spec.rows {
            if !self.written[row as usize] {
                self.write_row(row, &nodata)?;
            }
        }
        drop(self.reader.take());
        self.file.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crs::Crs;

    fn read_with_tiff_crate(path: &Path) -> (u32, u32, Vec<f32>) {
        let f = File::open(path).unwrap();
        let mut d = tiff::decoder::Decoder::new(std::io::BufReader::new(f)).unwrap();
        let (w, h) = d.dimensions().unwrap();
        match d.read_image().unwrap() {
            tiff::decoder::DecodingResult::F32(v) => (w, h, v),
            _ => panic!("not float32"),
        }
    }

    #[test]
    fn rows_in_any_order_cells_patched_and_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.tif");
        let mut spec = GridSpec::aligned(2.0, 10, 20, 3, 4, -9999.0);
        spec.crs = Some(Crs {
            epsg: Some(3794),
            ..Crs::default()
        });
        let mut w: Box<dyn GridWriter> = Box::new(GeoTiffWriter::create(&path, &spec).unwrap());
        w.write_row(3, &[1.0, 2.0, 3.0]).unwrap();
        w.write_row(1, &[4.0, 5.0, 6.0]).unwrap();
        assert_eq!(w.read_cell(3, 2).unwrap(), 3.0);
        assert_eq!(w.read_cell(0, 0).unwrap(), -9999.0);
        w.write_cell(3, 1, 7.5).unwrap();
        assert_eq!(w.read_cell(3, 1).unwrap(), 7.5);
        w.write_cell(0, 2, 8.0).unwrap();
        assert!(w.write_cell(4, 0, 1.0).is_err());
        assert!(w.write_row(0, &[1.0]).is_err());
        w.finish().unwrap();
        let (cols, rows, v) = read_with_tiff_crate(&path);
        assert_eq!((cols, rows), (3, 4));
        let n = -9999.0;
        assert_eq!(
            v,
            [n, n, 8.0, 4.0, 5.0, 6.0, n, n, n, 1.0, 7.5, 3.0].to_vec()
        );
    }

    #[test]
    fn geokeys_projected_geographic_vertical_and_none() {
        let mut spec = GridSpec::aligned(1.0, 0, 0, 1, 1, 0.0);
        let geokeys = |s: &GridSpec| super::geokeys(s.crs.as_ref());
        assert_eq!(geokeys(&spec), [1, 1, 0, 1, 1025, 0, 1, 1]);
        spec.crs = Some(Crs {
            epsg: Some(2154),
            vertical_epsg: Some(5720),
            ..Crs::default()
        });
        assert_eq!(
            geokeys(&spec),
            [
                1, 1, 0, 4, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 2154, 4096, 0, 1, 5720
            ]
        );
        spec.crs = Some(Crs {
            epsg: Some(4326),
            ..Crs::default()
        });
        assert_eq!(
            geokeys(&spec)[4..],
            [1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326]
        );
        // The input keys' model type (EPSG:6318 is geographic, outside 4000–4999) and unit
        // overrides (feet: they were dropped, and feet read as metres).
        spec.crs = Some(Crs {
            epsg: Some(6318),
            model_type: Some(2),
            ..Crs::default()
        });
        assert_eq!(
            geokeys(&spec)[4..],
            [1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 6318]
        );
        spec.crs = Some(Crs {
            epsg: Some(26915),
            vertical_epsg: Some(5703),
            model_type: Some(1),
            linear_units: Some(9002),
            vertical_units: Some(9002),
            ..Crs::default()
        });
        assert_eq!(
            geokeys(&spec)[4..],
            [
                1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 26915, 3076, 0, 1, 9002, 4096, 0, 1,
                5703, 4099, 0, 1, 9002
            ]
        );
    }

    #[test]
    fn empty_grid_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let spec = GridSpec::aligned(1.0, 0, 0, 0, 5, 0.0);
        let e = GeoTiffWriter::create(&dir.path().join("e.tif"), &spec).unwrap_err();
        assert!(e.to_string().contains("empty"), "{e}");
    }

    #[test]
    fn bigtiff_layout_reads_back() {
        // Force the BigTIFF layout on a small grid and read it with the tiff crate.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.tif");
        let spec = GridSpec::aligned(1.0, 0, 0, 2, 2, -1.0);
        let (header, data_offset) = GeoTiffWriter::layout(&spec, true).unwrap();
        let mut bytes = header;
        assert_eq!(bytes.len() as u64, data_offset);
        for v in [1.0f32, 2.0, 3.0, 4.0] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(
            read_with_tiff_crate(&path),
            (2, 2, vec![1.0, 2.0, 3.0, 4.0])
        );
    }
}
