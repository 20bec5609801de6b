//! The chunked reader over one or more LAS/LAZ files.

use super::LidarPoint;
use super::chunks::ChunkDecoder;
use super::combine::{FileMap, FileQuant, Quantization, combine};
use super::filter::{CompiledFilter, Filter, FilterStats, Verdict};
use super::header::{Bounds3, FileInfo, format_error, inspect, las_message, laz_message};
use crate::crs::Crs;
use crate::error::{Error, Result};
use std::fs::File;
use std::io::{BufReader, Read};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

/// Tuning of a [`LidarReader`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReadOptions {
    /// Decompress LAZ chunks on several threads (rayon's global pool). Each batch then spans
    /// several LAZ chunks (usually 50,000 points each), decompressed side by side.
    pub parallel: bool,
    /// Point records decoded per batch. Memory held by the reader is about
    /// `batch_points × record length` bytes (a record is 20–67 bytes plus extra bytes).
    pub batch_points: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            parallel: true,
            batch_points: 200_000,
        }
    }
}

/// Reads one or more LAS/LAZ files as one point set, chunk by chunk (see the [module
/// docs](super) for the coordinate rule and the global index).
///
/// The reader is `Send`: it can be opened on one thread and moved to another.
pub struct LidarReader {
    sources: Vec<Source>,
    quant: Quantization,
    crs: Option<Crs>,
    filter: CompiledFilter,
    stats: FilterStats,
    options: ReadOptions,
    next_source: usize,
    current: Option<Current>,
}

impl std::fmt::Debug for LidarReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LidarReader")
            .field("files", &self.sources.len())
            .field("quantization", &self.quant)
            .field("crs", &self.crs)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// One input file.
struct Source {
    info: FileInfo,
    map: FileMap,
    /// Global index of the file's first point.
    first_index: u64,
    /// The header's bounds in the file's own integers, one step wider on each side (`None`
    /// when the header has no usable bounds): a decoded point outside is corrupt.
    int_bounds: Option<[[i64; 2]; 3]>,
}

/// The integer box of `info`'s header bounds, one scale step wider on each side; `None` for a
/// header without usable bounds (all zero, or min above max).
fn int_bounds(info: &FileInfo) -> Option<[[i64; 2]; 3]> {
    let b = &info.bounds;
    let zero = b.min.iter().chain(&b.max).all(|v| *v == 0.0);
    let usable = (0..3).all(|k| b.min[k] <= b.max[k] && info.scale[k] > 0.0);
    if zero || !usable {
        return None;
    }
    Some(std::array::from_fn(|k| {
        let (s, o) = (info.scale[k], info.offset[k]);
        [
            ((b.min[k] - o) / s).floor() as i64 - 1,
            ((b.max[k] - o) / s).ceil() as i64 + 1,
        ]
    }))
}

/// The file being read.
struct Current {
    source: usize,
    decoder: Decoder,
    record_len: usize,
    extended: bool,
    /// Decoded records not yet handed out start at `pos` (bytes).
    buf: Vec<u8>,
    pos: usize,
    /// Global index of the record at `pos`.
    next_index: u64,
    /// Points per LAZ chunk (fixed-size chunks), to name the chunk of a corrupt point.
    chunk_size: Option<u64>,
    /// Records of the file not yet decoded into `buf`.
    remaining: u64,
}

enum Decoder {
    Las(BufReader<File>),
    Laz(Box<laz::LasZipDecompressor<'static, BufReader<File>>>),
    /// Chunk by chunk, in parallel, each chunk checked (see [`super::chunks`]).
    Chunks(Box<ChunkDecoder>),
}

impl LidarReader {
    /// Opens `paths` (read in this order) with the default [`ReadOptions`].
    ///
    /// # Errors
    /// [`Error::NoInput`] for an empty list; [`Error::Io`] if a file cannot be opened;
    /// [`Error::Format`] if a file is not a valid LAS/LAZ file, if the files cannot be combined
    /// exactly into one integer system, or if they declare different CRSs.
    pub fn open<P: AsRef<Path>>(paths: &[P], filter: &Filter) -> Result<LidarReader> {
        LidarReader::open_with(paths, filter, ReadOptions::default())
    }

    /// Opens `paths` with explicit options.
    ///
    /// # Errors
    /// As [`LidarReader::open`].
    pub fn open_with<P: AsRef<Path>>(
        paths: &[P],
        filter: &Filter,
        options: ReadOptions,
    ) -> Result<LidarReader> {
        if paths.is_empty() {
            return Err(Error::NoInput);
        }
        let infos: Vec<FileInfo> = paths
            .iter()
            .map(|p| inspect(p.as_ref()))
            .collect::<Result<_>>()?;
        let crs = common_crs(&infos)?;
        let quants: Vec<FileQuant<'_>> = infos
            .iter()
            .map(|i| FileQuant {
                path: &i.path,
                scale: i.scale,
                offset: i.offset,
                bounds: (i.point_count > 0).then_some(i.bounds),
            })
            .collect();
        let (quant, maps) = combine(&quants)?;
        let mut sources = Vec::with_capacity(infos.len());
        let mut first_index = 0u64;
        for (info, map) in infos.into_iter().zip(maps) {
            let count = info.point_count;
            sources.push(Source {
                int_bounds: int_bounds(&info),
                info,
                map,
                first_index,
            });
            first_index = first_index.saturating_add(count);
        }
        Ok(LidarReader {
            sources,
            filter: CompiledFilter::new(filter, &quant),
            quant,
            crs,
            stats: FilterStats::default(),
            options: ReadOptions {
                batch_points: options.batch_points.max(1),
                ..options
            },
            next_source: 0,
            current: None,
        })
    }

    /// The mapping from the points' integer coordinates to real-world coordinates.
    pub fn quantization(&self) -> &Quantization {
        &self.quant
    }

    /// The CRS declared by the files (the first declaration; all must agree), if any.
    pub fn crs(&self) -> Option<&Crs> {
        self.crs.as_ref()
    }

    /// Header facts of each file, in reading order.
    pub fn files(&self) -> impl Iterator<Item = &FileInfo> {
        self.sources.iter().map(|s| &s.info)
    }

    /// Total number of points in the files, before filtering (an upper bound on what
    /// [`LidarReader::read_chunk`] will return in all).
    pub fn point_count(&self) -> u64 {
        self.sources.iter().map(|s| s.info.point_count).sum()
    }

    /// Union of the header bounds of the files that have points (real-world units; all zero
    /// when no file has points).
    pub fn bounds(&self) -> Bounds3 {
        let mut it = self
            .sources
            .iter()
            .filter(|s| s.info.point_count > 0)
            .map(|s| s.info.bounds);
        let first = it.next().unwrap_or(Bounds3 {
            min: [0.0; 3],
            max: [0.0; 3],
        });
        it.fold(first, |a, b| a.union(&b))
    }

    /// What the filters kept and dropped so far.
    pub fn stats(&self) -> &FilterStats {
        &self.stats
    }

    /// Appends up to `max` points that pass the filter to `out` and returns how many it
    /// appended. Returns 0 once every file has been read (or when `max` is 0).
    ///
    /// # Errors
    /// [`Error::Io`] or [`Error::Format`] if a file turns out to be damaged while reading, or a
    /// coordinate does not fit in 32 bits after conversion to the common integer system. After
    /// an error the reader is finished: later calls return 0. Points appended before the error
    /// stay in `out`.
    pub fn read_chunk(&mut self, out: &mut Vec<LidarPoint>, max: usize) -> Result<usize> {
        let start = out.len();
        if let Err(e) = self.fill(out, start, max) {
            self.current = None;
            self.next_source = self.sources.len();
            return Err(e);
        }
        Ok(out.len() - start)
    }

    fn fill(&mut self, out: &mut Vec<LidarPoint>, start: usize, max: usize) -> Result<()> {
        while out.len() - start < max {
            let cur = match &mut self.current {
                Some(c) if !c.exhausted() => c,
                _ => {
                    self.current = None;
                    if !self.open_next()? {
                        break;
                    }
                    continue;
                }
            };
            let source = &self.sources[cur.source];
            if cur.pos == cur.buf.len() {
                cur.refill(&source.info.path, self.options.batch_points)?;
            }
            let room = max - (out.len() - start);
            cur.decode_into(out, room, source, &self.filter, &mut self.stats)?;
        }
        Ok(())
    }

    /// Reads every remaining point that passes the filter.
    ///
    /// # Errors
    /// As [`LidarReader::read_chunk`].
    pub fn read_all(&mut self) -> Result<Vec<LidarPoint>> {
        let mut out = Vec::new();
        while self.read_chunk(&mut out, 1 << 20)? > 0 {}
        Ok(out)
    }

    /// Opens the next file with points; `false` when there is none left.
    fn open_next(&mut self) -> Result<bool> {
        while self.next_source < self.sources.len() {
            let i = self.next_source;
            self.next_source += 1;
            if self.sources[i].info.point_count == 0 {
                continue;
            }
            self.current = Some(Current::open(i, &self.sources[i], self.options.parallel)?);
            return Ok(true);
        }
        Ok(false)
    }
}

/// The files' common CRS: files that declare one must declare the same.
fn common_crs(infos: &[FileInfo]) -> Result<Option<Crs>> {
    let mut found: Option<(&FileInfo, &Crs)> = None;
    for info in infos {
        let Some(crs) = &info.crs else { continue };
        match found {
            None => found = Some((info, crs)),
            Some((first, c)) if !c.same_as(crs) => {
                return Err(format_error(
                    &info.path,
                    format!(
                        "declares CRS {crs}, but {} declares {c}: files read together must be in \
                         the same CRS",
                        first.path.display()
                    ),
                ));
            }
            Some(_) => {}
        }
    }
    Ok(found.map(|(_, c)| c.clone()))
}

/// Runs a decoder call, turning a panic inside the third-party decoder into an error.
fn guarded<T>(path: &Path, f: impl FnOnce() -> Result<T>) -> Result<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(format_error(
            path,
            format!("the point data is damaged: the decoder failed ({what})"),
        ))
    })
}

impl Current {
    fn open(index: usize, source: &Source, parallel: bool) -> Result<Current> {
        let path = source.info.path.as_path();
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let mut read = BufReader::with_capacity(1 << 20, file);
        // Leaves `read` at the start of the point data.
        let header = las::Header::new(&mut read)
            .map_err(|e| format_error(path, format!("invalid header: {}", las_message(&e))))?;
        if header.number_of_points() != source.info.point_count {
            return Err(format_error(
                path,
                "the file changed while it was being read",
            ));
        }
        let format = header.point_format();
        let mut chunk_size = None;
        let decoder = if format.is_compressed {
            let vlr = header.laz_vlr().map_err(|e| {
                format_error(path, format!("invalid LASzip VLR: {}", las_message(&e)))
            })?;
            if !vlr.uses_variable_size_chunks() {
                chunk_size = Some(u64::from(vlr.chunk_size()).max(1));
            }
            guarded(path, || {
                let laz_err = |e: laz::LasZipError| {
                    format_error(
                        path,
                        format!("cannot decompress the points: {}", laz_message(&e)),
                    )
                };
                Ok(if parallel {
                    Decoder::Chunks(Box::new(ChunkDecoder::open(
                        path,
                        read,
                        vlr,
                        source.info.point_count,
                    )?))
                } else {
                    Decoder::Laz(Box::new(
                        laz::LasZipDecompressor::new(read, vlr).map_err(laz_err)?,
                    ))
                })
            })?
        } else {
            Decoder::Las(read)
        };
        Ok(Current {
            source: index,
            decoder,
            record_len: usize::from(format.len()),
            extended: format.is_extended,
            buf: Vec::new(),
            pos: 0,
            next_index: source.first_index,
            chunk_size,
            remaining: source.info.point_count,
        })
    }

    fn exhausted(&self) -> bool {
        self.remaining == 0 && self.pos == self.buf.len()
    }

    /// Decodes the next batch of records into `buf`.
    fn refill(&mut self, path: &Path, batch: usize) -> Result<()> {
        if let Decoder::Chunks(d) = &mut self.decoder {
            let buf = &mut self.buf;
            let n = guarded(path, || d.decode(path, batch as u64, buf))?;
            self.pos = 0;
            self.remaining -= n;
            return Ok(());
        }
        let n = self.remaining.min(batch as u64) as usize;
        self.buf.resize(n * self.record_len, 0);
        self.pos = 0;
        let buf = &mut self.buf;
        let decoder = &mut self.decoder;
        let laz_err = |e: laz::LasZipError| {
            format_error(
                path,
                format!("cannot decompress the points: {}", laz_message(&e)),
            )
        };
        guarded(path, || match decoder {
            Decoder::Las(read) => read.read_exact(buf).map_err(|e| {
                if e.kind() == std::io::ErrorKind::UnexpectedEof {
                    format_error(path, "unexpected end of file: the file is truncated")
                } else {
                    Error::io(path, e)
                }
            }),
            Decoder::Laz(d) => d
                .decompress_many(buf)
                .map_err(|e| laz_err(laz::LasZipError::IoError(e))),
            Decoder::Chunks(_) => Err(Error::Internal("chunks are decoded above".into())),
        })?;
        self.remaining -= n as u64;
        Ok(())
    }

    /// Moves decoded records into `out` through the filter, at most `room` kept points.
    fn decode_into(
        &mut self,
        out: &mut Vec<LidarPoint>,
        room: usize,
        source: &Source,
        filter: &CompiledFilter,
        stats: &mut FilterStats,
    ) -> Result<()> {
        let identity = source.map.is_identity();
        let mut kept = 0;
        while kept < room && self.pos < self.buf.len() {
            let rec = &self.buf[self.pos..self.pos + self.record_len];
            let mut p = decode(rec, self.extended, self.next_index);
            check_point(&p, source, self.chunk_size)?;
            if !identity {
                convert(&mut p, source)?;
            }
            self.pos += self.record_len;
            self.next_index += 1;
            let verdict = filter.test(&p);
            stats.count(verdict);
            if verdict == Verdict::Keep {
                out.push(p);
                kept += 1;
            }
        }
        Ok(())
    }
}

/// Decodes the fields a [`LidarPoint`] carries from one point record (formats 0–10; the record
/// is at least 20 bytes, 30 for formats 6–10).
#[inline]
fn decode(rec: &[u8], extended: bool, index: u64) -> LidarPoint {
    let le = |o: usize| i32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
    let (b14, b15) = (rec[14], rec[15]);
    let (classification, return_number, number_of_returns, flags) = if extended {
        (rec[16], b14 & 0x0f, b14 >> 4, b15 & 0x0f)
    } else {
        (b15 & 0x1f, b14 & 0x07, (b14 >> 3) & 0x07, (b15 >> 5) & 0x07)
    };
    LidarPoint {
        index,
        x: le(0),
        y: le(4),
        z: le(8),
        classification,
        return_number,
        number_of_returns,
        flags,
    }
}

/// Checks what a decoded point can be checked for: inside the header's bounds (one scale step of
/// slack) and a return number no larger than the number of returns (when that is known, > 0).
/// A point that fails is corrupt data that happened to decode.
#[inline]
fn check_point(p: &LidarPoint, source: &Source, chunk_size: Option<u64>) -> Result<()> {
    let in_box = source.int_bounds.is_none_or(|b| {
        let v = [i64::from(p.x), i64::from(p.y), i64::from(p.z)];
        (0..3).all(|k| v[k] >= b[k][0] && v[k] <= b[k][1])
    });
    let returns_ok = p.number_of_returns == 0 || p.return_number <= p.number_of_returns;
    if in_box && returns_ok {
        return Ok(());
    }
    Err(corrupt_point(p, source, chunk_size, !in_box))
}

#[cold]
fn corrupt_point(p: &LidarPoint, source: &Source, chunk_size: Option<u64>, out: bool) -> Error {
    let n = p.index - source.first_index;
    let i = &source.info;
    let at = match chunk_size.filter(|_| i.compressed) {
        Some(c) => format!("chunk {}, point {n}", n / c),
        None => format!("point {n}"),
    };
    let what = if out {
        let w = |k: usize, v: i32| i.offset[k] + i.scale[k] * f64::from(v);
        format!(
            "its position ({}, {}, {}) is outside the header's bounds x {} .. {}, y {} .. {}, \
             z {} .. {} (the data is damaged, or the header's bounds are wrong)",
            w(0, p.x),
            w(1, p.y),
            w(2, p.z),
            i.bounds.min[0],
            i.bounds.max[0],
            i.bounds.min[1],
            i.bounds.max[1],
            i.bounds.min[2],
            i.bounds.max[2]
        )
    } else {
        format!(
            "return number {} of {} returns",
            p.return_number, p.number_of_returns
        )
    };
    format_error(&i.path, format!("corrupt point data ({at}): {what}"))
}

/// Converts a point's integers into the common system.
#[inline]
fn convert(p: &mut LidarPoint, source: &Source) -> Result<()> {
    let m = &source.map;
    match (m.apply(0, p.x), m.apply(1, p.y), m.apply(2, p.z)) {
        (Some(x), Some(y), Some(z)) => {
            (p.x, p.y, p.z) = (x, y, z);
            Ok(())
        }
        _ => Err(format_error(
            &source.info.path,
            format!(
                "point {} (input index {}): its coordinates do not fit in 32-bit integers once \
                 converted to the common scale and offset of the files read together",
                p.index - source.first_index,
                p.index
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reader_is_send() {
        fn assert_send<T: Send>() {}
        assert_send::<LidarReader>();
    }

    #[test]
    fn decode_legacy_and_extended() {
        let mut rec = [0u8; 30];
        rec[0..4].copy_from_slice(&(-5i32).to_le_bytes());
        rec[4..8].copy_from_slice(&7i32.to_le_bytes());
        rec[8..12].copy_from_slice(&123456i32.to_le_bytes());
        rec[14] = 2 | (3 << 3); // legacy: return 2 of 3
        rec[15] = 9 | 0x80; // class 9, withheld
        let p = decode(&rec, false, 42);
        assert_eq!((p.index, p.x, p.y, p.z), (42, -5, 7, 123456));
        assert_eq!(
            (p.classification, p.return_number, p.number_of_returns),
            (9, 2, 3)
        );
        assert_eq!(p.flags, LidarPoint::WITHHELD);
        rec[14] = 5 | (7 << 4); // extended: return 5 of 7
        rec[15] = 0x04 | 0x08 | 0x30; // withheld + overlap, scanner channel bits
        rec[16] = 66;
        let p = decode(&rec, true, 0);
        assert_eq!(
            (p.classification, p.return_number, p.number_of_returns),
            (66, 5, 7)
        );
        assert_eq!(p.flags, LidarPoint::WITHHELD | LidarPoint::OVERLAP);
    }
}
