//! Compressed GeoTIFF and Cloud Optimized GeoTIFF (COG), written in bounded memory.
//!
//! A DEM is produced as a band of rows sweeping north, with late cells patched into rows already
//! written ([`GridWriter`] is random access), while a compressed TIFF needs each chunk whole and a
//! COG needs its directories first, its smallest overview's data next and the full resolution
//! last. So the cells are staged in a [`Scratch`] (4 bytes a cell, on disk in the output's
//! directory) and `write_tiff` assembles the file at the end:
//!
//! 1. **Overviews** (COG): each level halves the previous one (`⌈w/2⌉ × ⌈h/2⌉`), a cell the
//!    average of the cells with data among the 2 × 2 below it (nodata when none has data: GDAL's
//!    `-r average`), read two rows at a time from the previous level's scratch, until the level
//!    fits in one 512 × 512 tile. Memory: two rows.
//! 2. **Chunks**: tiles of 512 × 512 (COG; edge tiles padded with nodata) or strips of whole rows
//!    (about 64 KiB of cells each; plain GeoTIFF), smallest overview first, each read from its
//!    level's scratch, passed through the predictor and compressed on every core (a batch of at
//!    most [`BATCH_BYTES`] of cells at a time, or what a budget gives), and appended to a second
//!    temporary file.
//! 3. **Assembly**: header, GDAL's structural metadata (the "ghost area": `LAYOUT=IFDS_BEFORE_DATA`,
//!    `BLOCK_ORDER=ROW_MAJOR`, `BLOCK_LEADER=SIZE_AS_UINT4`, `BLOCK_TRAILER=LAST_4_BYTES_REPEATED`,
//!    each tile then preceded by its size and followed by its last 4 bytes again), every IFD
//!    (full resolution first, then the overviews as reduced-resolution subfiles), then the chunks
//!    copied from the temporary file. BigTIFF when the file would pass 4 GiB or when asked.
//!
//! Predictors are libtiff's: the floating-point predictor (3) regroups each row's bytes by
//! significance (most significant plane first) and differences them bytewise; the horizontal one
//! (2) differences 8-bit samples. Compression: DEFLATE (zlib, level 6, as GDAL), Zstandard (level
//! 9, as GDAL), LZW (TIFF's MSB-first variant with the early code-size switch).
//!
//! The output appears under its name only when complete ([`AtomicFile`]); the scratch and chunk
//! files are anonymous (deleted by the operating system whatever happens).

use super::geotiff::{
    Entry, encode_ifds, geo_entries, header, ifd_size, longs, nodata_text, offsets, shorts,
};
use super::raster::{
    Compression, GridWriter, Predictor, RasterFormat, ResolvedRaster, Scratch, check_cell,
    check_span,
};
use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::output::AtomicFile;
use crate::raster::GridSpec;
use rayon::prelude::*;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Side of a COG tile.
pub const TILE: u32 = 512;

/// Cells read and compressed at once (per batch of chunks), unless a budget asks for less
/// (`sweeptin merge --mem`: a quarter of it).
pub const BATCH_BYTES: usize = 64 << 20;

/// The sample type written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Samples {
    /// IEEE float32 (a DEM).
    F32,
    /// Unsigned 8-bit, values rounded and clamped to 0–255 (a hillshade).
    U8,
}

/// Size and georeferencing of an image.
#[derive(Clone, Debug)]
pub(crate) struct TiffGeo {
    /// Outer upper-left corner.
    pub origin: [f64; 2],
    /// Cell width and height (both positive).
    pub size: [f64; 2],
    /// The CRS, when known.
    pub crs: Option<Crs>,
    /// Nodata value.
    pub nodata: f32,
}

/// One resolution level's chunk grid.
struct Level {
    cols: u32,
    rows: u32,
    /// Chunk width and height (a strip is `cols` wide, its last one may be shorter).
    chunk_w: u32,
    chunk_h: u32,
    /// `(offset in the chunk file, byte count)` of each chunk, row-major.
    chunks: Vec<(u64, u64)>,
}

impl Level {
    fn new(cols: u32, rows: u32, tiled: bool, samples: Samples) -> Level {
        let (chunk_w, chunk_h) = if tiled {
            (TILE, TILE)
        } else {
            let row_bytes = u64::from(cols) * sample_bytes(samples);
            (
                cols,
                (65536 / row_bytes.max(1)).clamp(1, u64::from(rows)) as u32,
            )
        };
        Level {
            cols,
            rows,
            chunk_w,
            chunk_h,
            chunks: Vec::new(),
        }
    }

    fn across(&self) -> u32 {
        self.cols.div_ceil(self.chunk_w)
    }

    fn down(&self) -> u32 {
        self.rows.div_ceil(self.chunk_h)
    }
}

fn sample_bytes(s: Samples) -> u64 {
    match s {
        Samples::F32 => 4,
        Samples::U8 => 1,
    }
}

/// The overview of `src`: `⌈w/2⌉ × ⌈h/2⌉` cells, each the average of the cells with data among
/// the 2 × 2 it covers (nodata when none has data).
fn downsample(src: &Scratch, nodata: f32, path: &Path) -> Result<Scratch> {
    let (w, h) = (src.cols(), src.rows());
    let (ow, oh) = (w.div_ceil(2), h.div_ceil(2));
    let mut out = Scratch::new(path, ow, oh, nodata)?;
    let mut a = vec![0f32; w as usize];
    let mut b = vec![0f32; w as usize];
    let mut row = vec![0f32; ow as usize];
    let empty = |v: f32| v.to_bits() == nodata.to_bits() || v.is_nan();
    for r in 0..oh {
        src.read(2 * r, 0, &mut a)?;
        let two = 2 * r + 1 < h;
        if two {
            src.read(2 * r + 1, 0, &mut b)?;
        }
        for (c, o) in row.iter_mut().enumerate() {
            let (mut sum, mut n) = (0f64, 0u32);
            for x in [2 * c, 2 * c + 1] {
                if x >= w as usize {
                    continue;
                }
                for v in [Some(a[x]), two.then(|| b[x])].into_iter().flatten() {
                    if !empty(v) {
                        sum += f64::from(v);
                        n += 1;
                    }
                }
            }
            *o = if n == 0 {
                nodata
            } else {
                (sum / f64::from(n)) as f32
            };
        }
        out.write(r, 0, &row)?;
    }
    Ok(out)
}

/// Chunk `(cx, cy)` of `level` from its scratch: `chunk_w × h` cells, padded with `fill`
/// (`h` is the chunk height, or the rows left for the last strip).
fn read_chunk(
    stage: &Scratch,
    level: &Level,
    cx: u32,
    cy: u32,
    tiled: bool,
    fill: f32,
) -> Result<(Vec<f32>, u32)> {
    let x0 = cx * level.chunk_w;
    let y0 = cy * level.chunk_h;
    let w = level.chunk_w.min(level.cols - x0);
    let h = level.chunk_h.min(level.rows - y0);
    let out_h = if tiled { level.chunk_h } else { h };
    let cw = level.chunk_w as usize;
    let mut buf = vec![fill; cw * out_h as usize];
    for y in 0..h as usize {
        stage.read(y0 + y as u32, x0, &mut buf[y * cw..y * cw + w as usize])?;
    }
    Ok((buf, out_h))
}

/// The bytes of a chunk of `width`-wide rows after the predictor, in the file's (little-endian)
/// byte order.
fn predict(values: &[f32], width: usize, samples: Samples, predictor: Predictor) -> Vec<u8> {
    match samples {
        Samples::U8 => {
            let mut b: Vec<u8> = values
                .iter()
                .map(|v| v.round().clamp(0.0, 255.0) as u8)
                .collect();
            if predictor == Predictor::Horizontal {
                for row in b.chunks_mut(width) {
                    for k in (1..row.len()).rev() {
                        row[k] = row[k].wrapping_sub(row[k - 1]);
                    }
                }
            }
            b
        }
        Samples::F32 if predictor == Predictor::Float => {
            let mut out = vec![0u8; values.len() * 4];
            for (row, dst) in values.chunks(width).zip(out.chunks_mut(width * 4)) {
                let w = row.len();
                for (i, v) in row.iter().enumerate() {
                    let be = v.to_bits().to_be_bytes();
                    for (plane, byte) in be.iter().enumerate() {
                        dst[plane * w + i] = *byte;
                    }
                }
                for k in (1..dst.len()).rev() {
                    dst[k] = dst[k].wrapping_sub(dst[k - 1]);
                }
            }
            out
        }
        Samples::F32 => values.iter().flat_map(|v| v.to_le_bytes()).collect(),
    }
}

/// `bytes` compressed as the TIFF `Compression` tag says.
fn compress(bytes: Vec<u8>, c: Compression) -> std::io::Result<Vec<u8>> {
    Ok(match c {
        Compression::None => bytes,
        Compression::Deflate => {
            let mut e = flate2::write::ZlibEncoder::new(
                Vec::with_capacity(bytes.len() / 2),
                flate2::Compression::new(6),
            );
            e.write_all(&bytes)?;
            e.finish()?
        }
        Compression::Zstd => zstd::bulk::compress(&bytes, 9)?,
        Compression::Lzw => weezl::encode::Encoder::with_tiff_size_switch(weezl::BitOrder::Msb, 8)
            .encode(&bytes)
            .map_err(std::io::Error::other)?,
    })
}

/// GDAL's structural metadata of a COG (see the module docs), padded so the first IFD that
/// follows starts on an even offset.
fn ghost_area(head: u64) -> Vec<u8> {
    let md = "LAYOUT=IFDS_BEFORE_DATA\nBLOCK_ORDER=ROW_MAJOR\nBLOCK_LEADER=SIZE_AS_UINT4\n\
              BLOCK_TRAILER=LAST_4_BYTES_REPEATED\nKNOWN_INCOMPATIBLE_EDITION=NO\n ";
    let mut text =
        format!("GDAL_STRUCTURAL_METADATA_SIZE={:06} bytes\n{md}", md.len()).into_bytes();
    if (head + text.len() as u64) % 2 == 1 {
        text.push(0);
    }
    text
}

/// Writes the TIFF of the cells staged in `stage` to `path` (see the module docs): a COG when
/// `r.format` is [`RasterFormat::Cog`], a striped GeoTIFF otherwise. Returns the file's size.
///
/// # Errors
/// [`Error::Io`] naming `path` (or its directory, for the temporary files).
pub(crate) fn write_tiff(
    path: &Path,
    stage: Scratch,
    geo: &TiffGeo,
    r: &ResolvedRaster,
    samples: Samples,
    batch_bytes: usize,
) -> Result<u64> {
    let cog = r.format == RasterFormat::Cog;
    let mut stages = vec![stage];
    if cog {
        while stages
            .last()
            .is_some_and(|s| s.cols() > TILE || s.rows() > TILE)
        {
            let next = downsample(stages.last().expect("non-empty"), geo.nodata, path)?;
            stages.push(next);
        }
    }
    let mut levels: Vec<Level> = stages
        .iter()
        .map(|s| Level::new(s.cols(), s.rows(), cog, samples))
        .collect();
    // Chunks, smallest overview first.
    let dir = super::target::scratch_dir(path);
    let chunk_file = tempfile::tempfile_in(&dir).map_err(|e| Error::write(&dir, e))?;
    let mut out = BufWriter::with_capacity(crate::sort::WRITE_PIECE, chunk_file);
    let io = |e: std::io::Error| Error::write(path, e);
    let mut pos = 0u64;
    for (stage, level) in stages.iter().zip(levels.iter_mut()).rev() {
        let ids: Vec<(u32, u32)> = (0..level.down())
            .flat_map(|cy| (0..level.across()).map(move |cx| (cx, cy)))
            .collect();
        let chunk_bytes = (level.chunk_w as usize * level.chunk_h as usize * 4).max(1);
        let per_batch = (batch_bytes / chunk_bytes).max(1);
        for batch in ids.chunks(per_batch) {
            let encoded: Vec<Vec<u8>> = batch
                .par_iter()
                .map(|&(cx, cy)| {
                    let (cells, _) = read_chunk(stage, level, cx, cy, cog, geo.nodata)?;
                    let bytes = predict(&cells, level.chunk_w as usize, samples, r.predictor);
                    compress(bytes, r.compress).map_err(io)
                })
                .collect::<Result<_>>()?;
            for data in encoded {
                if cog {
                    out.write_all(&(data.len() as u32).to_le_bytes())
                        .map_err(io)?;
                    pos += 4;
                }
                crate::sort::write_pieces(&mut out, &data).map_err(io)?;
                level.chunks.push((pos, data.len() as u64));
                pos += data.len() as u64;
                if cog {
                    let mut tail = [0u8; 4];
                    let n = data.len().min(4);
                    tail[..n].copy_from_slice(&data[data.len() - n..]);
                    out.write_all(&tail).map_err(io)?;
                    pos += 4;
                }
            }
        }
    }
    let mut chunk_file = out.into_inner().map_err(|e| io(e.into_error()))?;
    // Directories: sizes first (they do not depend on the values), then the real offsets.
    let layout = |big: bool| -> (Vec<u8>, u64, u64) {
        let head = if big { 16 } else { 8 };
        let ghost = if cog { ghost_area(head) } else { Vec::new() };
        let ifd_start = head + ghost.len() as u64;
        let ifds: u64 = (0..levels.len())
            .map(|i| ifd_size(&entries(&levels, i, geo, r, samples, cog, 0, big), big))
            .sum();
        let data_start = (ifd_start + ifds).div_ceil(16) * 16;
        (ghost, ifd_start, data_start)
    };
    let (_, _, start) = layout(false);
    let big = r.bigtiff || start + pos > u64::from(u32::MAX);
    let (ghost, ifd_start, data_start) = layout(big);
    let mut ifds: Vec<Vec<Entry>> = (0..levels.len())
        .map(|i| entries(&levels, i, geo, r, samples, cog, data_start, big))
        .collect();
    let (ifd_bytes, _) = encode_ifds(&mut ifds, ifd_start, big);
    let mut file = AtomicFile::create(path)?;
    let mut head = header(big, ifd_start);
    head.extend_from_slice(&ghost);
    head.extend_from_slice(&ifd_bytes);
    head.resize(data_start as usize, 0);
    file.write_all(&head).map_err(|e| file.err(e))?;
    chunk_file.seek(SeekFrom::Start(0)).map_err(io)?;
    let copied = std::io::copy(&mut chunk_file, &mut file).map_err(|e| file.err(e))?;
    if copied != pos {
        return Err(Error::Output {
            path: path.to_path_buf(),
            message: format!("copied {copied} bytes of tiles, expected {pos}"),
        });
    }
    file.commit()
}

/// The IFD entries of level `i`, its chunks' offsets counted from `data_start`.
#[allow(clippy::too_many_arguments)]
fn entries(
    levels: &[Level],
    i: usize,
    geo: &TiffGeo,
    r: &ResolvedRaster,
    samples: Samples,
    tiled: bool,
    data_start: u64,
    big: bool,
) -> Vec<Entry> {
    let l = &levels[i];
    let (bits, format) = match samples {
        Samples::F32 => (32, 3),
        Samples::U8 => (8, 1),
    };
    let mut e = vec![
        longs(256, &[l.cols]),
        longs(257, &[l.rows]),
        shorts(258, &[bits]),
        shorts(259, &[r.compress.tag()]),
        shorts(262, &[1]),
        shorts(277, &[1]),
        shorts(284, &[1]),
        shorts(339, &[format]),
    ];
    if r.predictor != Predictor::None {
        e.push(shorts(317, &[r.predictor.tag()]));
    }
    let offs: Vec<u64> = l.chunks.iter().map(|c| data_start + c.0).collect();
    let counts: Vec<u64> = l.chunks.iter().map(|c| c.1).collect();
    if tiled {
        e.push(shorts(322, &[TILE as u16]));
        e.push(shorts(323, &[TILE as u16]));
        e.push(offsets(324, &offs, big));
        e.push(offsets(325, &counts, big));
    } else {
        e.push(longs(278, &[l.chunk_h]));
        e.push(offsets(273, &offs, big));
        e.push(offsets(279, &counts, big));
    }
    if i == 0 {
        e.extend(geo_entries(
            geo.origin,
            geo.size,
            geo.crs.as_ref(),
            Some(&nodata_text(geo.nodata)),
        ));
    } else {
        e.push(longs(254, &[1]));
    }
    e
}

/// A float32 DEM written as a compressed GeoTIFF or a COG: cells staged in a [`Scratch`], the
/// file assembled by [`GridWriter::finish`] (see the module docs).
#[derive(Debug)]
pub struct StagedGridWriter {
    path: PathBuf,
    spec: GridSpec,
    stage: Option<Scratch>,
    options: ResolvedRaster,
    /// Cells compressed at once ([`BATCH_BYTES`] unless a budget gives less).
    batch_bytes: usize,
}

impl StagedGridWriter {
    /// A writer for `spec` at `path` (nothing appears there before `finish`).
    ///
    /// # Errors
    /// [`Error::Output`] for an empty grid or a bad cell size; [`Error::Io`] naming the
    /// directory.
    pub fn create(path: &Path, spec: &GridSpec, options: &ResolvedRaster) -> Result<Self> {
        if spec.is_empty() || !(spec.cell > 0.0 && spec.cell.is_finite()) {
            return Err(Error::Output {
                path: path.to_path_buf(),
                message: format!(
                    "the grid is empty or its cell size is bad ({} × {} cells of {})",
                    spec.cols, spec.rows, spec.cell
                ),
            });
        }
        Ok(StagedGridWriter {
            path: path.to_path_buf(),
            spec: spec.clone(),
            stage: Some(Scratch::new(path, spec.cols, spec.rows, spec.nodata)?),
            options: *options,
            batch_bytes: BATCH_BYTES,
        })
    }

    /// At most `bytes` of cells compressed at once (at least one chunk; never more than
    /// [`BATCH_BYTES`]): the same file, in less memory.
    pub(crate) fn with_batch_bytes(mut self, bytes: usize) -> Self {
        self.batch_bytes = bytes.min(BATCH_BYTES);
        self
    }

    fn stage(&mut self) -> Result<&mut Scratch> {
        let path = &self.path;
        self.stage.as_mut().ok_or_else(|| Error::Output {
            path: path.clone(),
            message: "the raster was already finished".into(),
        })
    }
}

impl GridWriter for StagedGridWriter {
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
        self.stage()?.write(row, 0, values)
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
        self.stage()?.read(row, col, out)
    }

    fn write_span(&mut self, row: u32, col: u32, values: &[f32]) -> Result<()> {
        check_span(&self.spec, &self.path, row, col, values.len())?;
        self.stage()?.write(row, col, values)
    }

    fn finish(mut self: Box<Self>) -> Result<u64> {
        self.stage()?;
        let stage = self.stage.take().expect("checked above");
        let s = &self.spec;
        let geo = TiffGeo {
            origin: s.origin(),
            size: [s.cell, s.cell],
            crs: s.crs.clone(),
            nodata: s.nodata,
        };
        write_tiff(
            &self.path,
            stage,
            &geo,
            &self.options,
            Samples::F32,
            self.batch_bytes,
        )
    }
}

/// Writes `rows` (north to south, `cols` values each) as an 8-bit single-band GeoTIFF or COG
/// at `path`: the hillshade's writer.
///
/// # Errors
/// [`Error::Io`] naming `path`; whatever `rows` returns.
pub(crate) fn write_u8_image(
    path: &Path,
    cols: u32,
    rows: u32,
    geo: &TiffGeo,
    r: &ResolvedRaster,
    fill: impl FnOnce(&mut Scratch) -> Result<()>,
) -> Result<u64> {
    let mut stage = Scratch::new(path, cols, rows, geo.nodata)?;
    fill(&mut stage)?;
    write_tiff(path, stage, geo, r, Samples::U8, BATCH_BYTES)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(path: &Path) -> (u32, u32, Vec<f32>) {
        let f = std::fs::File::open(path).unwrap();
        let mut d = tiff::decoder::Decoder::new(std::io::BufReader::new(f))
            .unwrap()
            .with_limits(tiff::decoder::Limits::unlimited());
        let (w, h) = d.dimensions().unwrap();
        match d.read_image().unwrap() {
            tiff::decoder::DecodingResult::F32(v) => (w, h, v),
            tiff::decoder::DecodingResult::U8(v) => (w, h, v.into_iter().map(f32::from).collect()),
            _ => panic!("unexpected sample type"),
        }
    }

    fn grid(cols: u32, rows: u32) -> (GridSpec, Vec<f32>) {
        let spec = GridSpec::aligned(1.0, 0, 0, cols, rows, -9999.0);
        let v = (0..cols * rows)
            .map(|i| {
                if i % 97 == 5 {
                    -9999.0
                } else {
                    (i as f32) * 0.37 - 50.0
                }
            })
            .collect();
        (spec, v)
    }

    /// Every compression and predictor round-trips through an independent decoder (the `tiff`
    /// crate), tiled with overviews and striped, rows written in any order.
    #[test]
    fn round_trips_through_the_tiff_crate() {
        let dir = tempfile::tempdir().unwrap();
        let (spec, values) = grid(700, 530);
        for format in [RasterFormat::Cog, RasterFormat::GeoTiff] {
            for (compress, predictor) in [
                (Compression::Deflate, Predictor::Float),
                (Compression::Zstd, Predictor::Float),
                (Compression::Lzw, Predictor::None),
                (Compression::None, Predictor::None),
            ] {
                let path = dir.path().join(format!("{format:?}_{compress:?}.tif"));
                let r = ResolvedRaster {
                    format,
                    compress,
                    predictor,
                    bigtiff: compress == Compression::Zstd,
                };
                let mut w: Box<dyn GridWriter> =
                    Box::new(StagedGridWriter::create(&path, &spec, &r).unwrap());
                for row in (0..spec.rows).rev() {
                    let a = (row * spec.cols) as usize;
                    w.write_row(row, &values[a..a + spec.cols as usize])
                        .unwrap();
                }
                w.write_cell(3, 4, 1234.5).unwrap();
                assert_eq!(w.read_cell(3, 4).unwrap(), 1234.5);
                w.finish().unwrap();
                // One chunk a batch (a small `merge --mem`): the same file (one case: each
                // write costs a second in a debug build).
                if format == RasterFormat::Cog && compress == Compression::Deflate {
                    let small = dir.path().join("small_batches.tif");
                    let mut w = StagedGridWriter::create(&small, &spec, &r)
                        .unwrap()
                        .with_batch_bytes(1);
                    for row in 0..spec.rows {
                        let a = (row * spec.cols) as usize;
                        w.write_row(row, &values[a..a + spec.cols as usize])
                            .unwrap();
                    }
                    w.write_cell(3, 4, 1234.5).unwrap();
                    Box::new(w).finish().unwrap();
                    assert!(std::fs::read(&small).unwrap() == std::fs::read(&path).unwrap());
                }
                let (cols, rows, got) = decode(&path);
                assert_eq!((cols, rows), (700, 530));
                let mut want = values.clone();
                want[3 * 700 + 4] = 1234.5;
                assert!(
                    got.iter()
                        .zip(&want)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{format:?} {compress:?}"
                );
            }
        }
    }

    #[test]
    fn overviews_average_the_cells_with_data() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("o.tif");
        let mut s = Scratch::new(&p, 3, 3, -1.0).unwrap();
        s.write(0, 0, &[1.0, 3.0, 5.0]).unwrap();
        s.write(1, 0, &[-1.0, -1.0, 7.0]).unwrap();
        s.write(2, 0, &[-1.0, -1.0, -1.0]).unwrap();
        let o = downsample(&s, -1.0, &p).unwrap();
        let mut row = [0f32; 2];
        o.read(0, 0, &mut row).unwrap();
        assert_eq!(row, [2.0, 6.0]);
        o.read(1, 0, &mut row).unwrap();
        assert_eq!(row, [-1.0, -1.0]);
    }

    #[test]
    fn float_predictor_is_libtiffs() {
        // One row of two values: planes MSB first, then bytewise differences.
        let b = predict(&[1.0, 2.0], 2, Samples::F32, Predictor::Float);
        // 1.0 = 3f800000, 2.0 = 40000000: planes [3f, 40, 80, 00, 00, 00, 00, 00].
        assert_eq!(b, [0x3f, 0x01, 0x40, 0x80, 0, 0, 0, 0]);
        let h = predict(&[10.0, 12.0, 11.0], 3, Samples::U8, Predictor::Horizontal);
        assert_eq!(h, [10, 2, 255]);
    }
}
