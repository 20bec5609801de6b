//! Decoding a file's point records span by span, on every core.
//!
//! A *span* is a run of point records that decodes on its own: a LAZ chunk (a COPC octree node is
//! one), or a slice of an uncompressed LAS file. The reader and `info` pick the spans they need
//! (all of them, or the COPC nodes that meet an area), [`FileDecoder::decode`] reads their bytes,
//! decompresses them side by side (rayon's global pool) and hands each span's raw records to a
//! job, in span order, so the results do not depend on the number of threads.

use super::header::{Chunk, FileInfo, format_error, las_message, laz_message};
use super::world::Quantization;
use crate::error::{Error, Result};
use crate::input::source::{Ahead, Source};
use rayon::prelude::*;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// One file open for decoding.
pub(crate) struct FileDecoder {
    path: PathBuf,
    source: Source,
    /// A remote file's spans, read ahead ([`FileDecoder::plan`]).
    ahead: Option<Ahead>,
    vlr: Option<laz::LazVlr>,
    pub(crate) record_len: usize,
    pub(crate) extended: bool,
    pub(crate) quant: Quantization,
    /// Span buffers given back, reused by the next reads (each with [`LAYOUT_HEAD`] bytes before
    /// the span's bytes): fresh ones fault in fresh pages, batch after batch.
    spare: Vec<Vec<u8>>,
    raw: RawPool,
    /// CPU time spent decoding spans, on whichever thread.
    cpu: crate::clock::Tally,
}

/// Bytes before a LAZ chunk in the layout a decompressor expects: the chunk table's offset.
const LAYOUT_HEAD: usize = 8;

/// Buffers of decompressed records, shared by a file's decoding jobs and reused from span to
/// span: there are as many as spans ever decompressed at once (not one per thread of the pool,
/// which would hold 1.4 MB on each of 32 threads for the life of the process).
type RawPool = Arc<Spare<u8>>;

/// Vectors given back for reuse, shared between threads (fresh ones fault in fresh pages).
#[derive(Debug)]
pub(crate) struct Spare<T>(Mutex<Vec<Vec<T>>>);

impl<T> Default for Spare<T> {
    fn default() -> Self {
        Spare(Mutex::new(Vec::new()))
    }
}

impl<T> Spare<T> {
    /// A vector given back earlier (its contents as they were left), or a new one.
    pub(crate) fn take(&self) -> Vec<T> {
        self.0
            .lock()
            .ok()
            .and_then(|mut v| v.pop())
            .unwrap_or_default()
    }

    /// Gives `v` back for reuse.
    pub(crate) fn give(&self, v: Vec<T>) {
        if let Ok(mut spare) = self.0.lock() {
            spare.push(v);
        }
    }
}

/// Which fields a job needs (LAZ 1.4 layered chunks skip the others).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Fields {
    /// Coordinates, returns, classification and flags.
    Filter,
    /// Those, intensity and GPS time.
    Stats,
    /// Every field (a rewrite keeps them all).
    All,
}

impl Fields {
    fn selection(self) -> laz::DecompressionSelection {
        let base = laz::DecompressionSelection::base()
            .decompress_z()
            .decompress_classification()
            .decompress_flags();
        match self {
            Fields::Filter => base,
            Fields::Stats => base.decompress_intensity().decompress_gps_time(),
            Fields::All => laz::DecompressionSelection::all(),
        }
    }
}

impl FileDecoder {
    /// Opens the file described by `info` (checked by [`FileInfo::read`]).
    pub(crate) fn open(info: &FileInfo) -> Result<FileDecoder> {
        let path = info.path.as_path();
        let source = Source::open(path)?;
        let vlr = if info.compressed {
            let header = las::Header::new(&mut source.reader())
                .map_err(|e| format_error(path, format!("invalid header: {}", las_message(&e))))?;
            // The count the `las` crate takes (the legacy one when non-zero) as when checked.
            let crate_count = match info.legacy_point_count {
                0 => info.extended_point_count.unwrap_or(0),
                n => u64::from(n),
            };
            if header.number_of_points() != crate_count {
                return Err(format_error(
                    path,
                    "the file changed while it was being read",
                ));
            }
            Some(header.laz_vlr().map_err(|e| {
                format_error(path, format!("invalid LASzip VLR: {}", las_message(&e)))
            })?)
        } else {
            None
        };
        Ok(FileDecoder {
            path: info.path.clone(),
            source,
            ahead: None,
            vlr,
            record_len: usize::from(info.record_length),
            extended: info.point_format >= 6,
            quant: info.quantization(),
            spare: Vec::new(),
            raw: RawPool::default(),
            cpu: crate::clock::Tally::default(),
        })
    }

    /// Tells a remote file's decoder which spans it will read, in order: their bytes are read
    /// ahead, neighbours in one request, a few requests in flight (`--io-concurrency`). A local
    /// file is read span by span as asked.
    pub(crate) fn plan(&mut self, spans: &[Chunk]) {
        if self.source.is_remote() && !spans.is_empty() {
            let ranges: Vec<(u64, u64)> = spans.iter().map(|s| (s.offset, s.bytes)).collect();
            self.ahead = Some(Ahead::new(&self.source, &ranges));
        }
    }

    /// Adds this decoder's CPU time to `cpu` (shared with the reader that reports it).
    pub(crate) fn tallied(self, cpu: crate::clock::Tally) -> FileDecoder {
        FileDecoder { cpu, ..self }
    }

    /// Reads and decompresses `spans`, runs `job` on each span's raw records (`span.points`
    /// records of `record_len` bytes) and returns the results in span order. The first error in
    /// span order wins, whether reading, decompressing or the job's: a span whose bytes cannot
    /// be read stops the reading, and the spans before it are decoded first.
    pub(crate) fn decode<T: Send>(
        &mut self,
        spans: &[Chunk],
        parallel: bool,
        fields: Fields,
        job: impl Fn(&Chunk, &[u8]) -> Result<T> + Sync,
    ) -> Result<Vec<T>> {
        if self.source.is_remote()
            && let Some(first) = spans.first()
            && !self.ahead.as_ref().is_some_and(|a| a.covers(first.offset))
        {
            self.plan(spans);
        }
        let mut bytes = Vec::with_capacity(spans.len());
        let mut unread = None;
        for s in spans {
            match self.read(std::slice::from_ref(s)) {
                Ok(b) => bytes.extend(b),
                Err(e) => {
                    unread = Some(e);
                    break;
                }
            }
        }
        let read = &spans[..bytes.len()];
        let result = self.spans().decode(read, &mut bytes, parallel, fields, job);
        self.give_back(bytes);
        match (result, unread) {
            (Ok(_), Some(e)) => Err(e),
            (result, _) => result,
        }
    }

    /// What decodes this file's spans once their bytes are read, on any thread.
    pub(crate) fn spans(&self) -> SpanDecoder {
        SpanDecoder {
            path: self.path.clone(),
            vlr: self.vlr.clone(),
            layers: match &self.vlr {
                Some(vlr) if self.source.is_remote() => super::laz_check::layer_count(vlr),
                _ => None,
            },
            record_len: self.record_len,
            raw: self.raw.clone(),
            cpu: self.cpu.clone(),
        }
    }

    /// Reads the bytes of `spans`, each in a buffer of its own (see [`SpanDecoder::decode`]).
    pub(crate) fn read(&mut self, spans: &[Chunk]) -> Result<Vec<Vec<u8>>> {
        let mut bytes: Vec<Vec<u8>> = (0..spans.len())
            .map(|_| self.spare.pop().unwrap_or_default())
            .collect();
        for (s, b) in spans.iter().zip(&mut bytes) {
            b.clear();
            b.resize(LAYOUT_HEAD + s.bytes as usize, 0);
            match &mut self.ahead {
                Some(a) => a.read(s.offset, &mut b[LAYOUT_HEAD..]),
                None => self.source.read_exact_at(s.offset, &mut b[LAYOUT_HEAD..]),
            }
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::UnexpectedEof {
                    format_error(&self.path, "unexpected end of file: the file is truncated")
                } else {
                    Error::io(&self.path, e)
                }
            })?;
        }
        Ok(bytes)
    }

    /// Takes back buffers [`FileDecoder::read`] handed out, for the next call.
    pub(crate) fn give_back(&mut self, bytes: Vec<Vec<u8>>) {
        self.spare.extend(bytes);
    }
}

/// Decodes a file's spans from their bytes: what a [`FileDecoder`] knows of the file, owned, so
/// that a batch can be decoded on another thread while the next one is read.
#[derive(Clone)]
pub(crate) struct SpanDecoder {
    path: PathBuf,
    vlr: Option<laz::LazVlr>,
    /// The layer count of a remote file's layered chunks, checked as each arrives (a local
    /// file's were checked with its header: `laz_check`).
    layers: Option<u64>,
    record_len: usize,
    raw: RawPool,
    /// CPU time spent decoding spans, on whichever thread.
    cpu: crate::clock::Tally,
}

impl SpanDecoder {
    /// Decompresses `spans` from `bytes` (as [`FileDecoder::read`] filled them), runs `job` on
    /// each span's raw records (`span.points` records of `record_len` bytes) and returns the
    /// results in span order. The first error in span order wins (decompressing or the job's),
    /// whichever thread met it.
    pub(crate) fn decode<T: Send>(
        &self,
        spans: &[Chunk],
        bytes: &mut [Vec<u8>],
        parallel: bool,
        fields: Fields,
        job: impl Fn(&Chunk, &[u8]) -> Result<T> + Sync,
    ) -> Result<Vec<T>> {
        let (path, vlr, len) = (self.path.as_path(), self.vlr.as_ref(), self.record_len);
        let one = |(s, b): (&Chunk, &mut Vec<u8>)| -> Result<T> {
            self.cpu.timed(|| match vlr {
                None => job(s, &b[LAYOUT_HEAD..]),
                Some(vlr) => {
                    let mut raw = self.raw.take();
                    // The decompressor writes every byte it is given (or fails): only growth is
                    // zeroed.
                    let need = s.points as usize * len;
                    if raw.len() < need {
                        raw.resize(need, 0);
                    }
                    let entry = laz::laszip::ChunkTableEntry {
                        point_count: s.points,
                        byte_count: s.bytes,
                    };
                    let head = LAYOUT_HEAD + vlr.items_size() as usize + 4;
                    let fits = match self.layers {
                        Some(layers) => super::laz_check::layers_fit(
                            b.get(head..).unwrap_or_default(),
                            vlr,
                            layers,
                            s.bytes,
                        ),
                        None => Ok(()),
                    };
                    let out = fits
                        .and_then(|()| {
                            decode_chunk(b, &mut raw[..need], vlr, entry, fields.selection())
                        })
                        .map_err(|what| {
                            format_error(
                                path,
                                format!(
                                    "corrupt LAZ data in the chunk at byte {} (points {} to {}): \
                                     {what}",
                                    s.offset,
                                    s.first,
                                    s.first + s.points.max(1) - 1
                                ),
                            )
                        })
                        .and_then(|()| job(s, &raw[..need]));
                    self.raw.give(raw);
                    out
                }
            })
        };
        let parts = &mut bytes[..spans.len()];
        guarded(path, || {
            let all: Vec<Result<T>> = if parallel {
                spans.par_iter().zip(parts).map(one).collect()
            } else {
                spans.iter().zip(parts).map(one).collect()
            };
            all.into_iter().collect()
        })
    }
}

/// Decodes one LAZ chunk, `layout[LAYOUT_HEAD..]`, into `out` (its points' records) with a
/// decompressor that sees only them, and checks that it used exactly them. `layout` gets the
/// chunk table's offset in its head and the table after the chunk (its end is cut back). A
/// decoder running over damaged bytes takes them for data (a zeroed chunk decodes into 50,000
/// copies of one point): a chunk whose points end before its bytes do, or need more bytes than it
/// has, is corrupt — which a file's length alone cannot tell (that is "truncated").
fn decode_chunk(
    layout: &mut Vec<u8>,
    out: &mut [u8],
    vlr: &laz::LazVlr,
    entry: laz::laszip::ChunkTableEntry,
    selection: laz::DecompressionSelection,
) -> std::result::Result<(), String> {
    // The layout a decompressor expects: the offset of the chunk table, the chunk, the table.
    let end = layout.len();
    let bytes_len = end - LAYOUT_HEAD;
    layout[..LAYOUT_HEAD].copy_from_slice(&(end as i64).to_le_bytes());
    let mut table = laz::laszip::ChunkTable::with_capacity(1);
    table.push(entry);
    let written = table
        .write_to(&mut *layout, vlr)
        .map_err(|e| format!("cannot set up its decoder: {e}"));
    let used = written.and_then(|()| decode_layout(layout, out, vlr, entry, selection, bytes_len));
    layout.truncate(end);
    let used = used?;
    if used != bytes_len as u64 {
        return Err(format!(
            "its {} points decode from {used} of its {bytes_len} bytes",
            entry.point_count,
        ));
    }
    Ok(())
}

/// Runs the decompressor over `buf` (see [`decode_chunk`]); the chunk bytes it used.
fn decode_layout(
    buf: &[u8],
    out: &mut [u8],
    vlr: &laz::LazVlr,
    entry: laz::laszip::ChunkTableEntry,
    selection: laz::DecompressionSelection,
    bytes_len: usize,
) -> std::result::Result<u64, String> {
    let run = || -> std::result::Result<u64, String> {
        let mut d =
            laz::LasZipDecompressor::selective(std::io::Cursor::new(buf), vlr.clone(), selection)
                .map_err(|e| laz_message(&e))?;
        d.decompress_many(out).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                format!(
                    "its {} points need more than its {bytes_len} bytes",
                    entry.point_count,
                )
            } else {
                e.to_string()
            }
        })?;
        Ok(d.get().position() - LAYOUT_HEAD as u64)
    };
    // The decoder asserts on some damaged input: that too is this chunk's corruption.
    catch_unwind(AssertUnwindSafe(run)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(format!("the decoder failed on it ({what})"))
    })
}

/// The spans of `info` to decode: every LAZ chunk, or slices of about `batch` LAS records; with
/// `keep`, only the COPC nodes whose rectangle it keeps (all chunks of a file without an index).
pub(crate) fn spans(
    info: &FileInfo,
    batch: u64,
    keep: Option<&dyn Fn([f64; 4]) -> bool>,
) -> Vec<Chunk> {
    let layout = &info.layout;
    if !info.compressed {
        let len = u64::from(info.record_length);
        let batch = batch.max(1);
        return (0..info.point_count.div_ceil(batch))
            .map(|k| {
                let first = k * batch;
                let points = batch.min(info.point_count - first);
                Chunk {
                    offset: layout.data_start + first * len,
                    bytes: points * len,
                    points,
                    first,
                }
            })
            .collect();
    }
    match (keep, &layout.nodes) {
        (Some(keep), Some(nodes)) => nodes
            .iter()
            .filter(|n| keep(n.rect))
            .map(|n| layout.chunks[n.chunk])
            .collect(),
        _ => layout.chunks.clone(),
    }
}

/// Runs a decoder call, turning a panic inside the third-party decoder into an error.
pub(crate) fn guarded<T>(path: &Path, f: impl FnOnce() -> Result<T>) -> Result<T> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::las::header::inspect;

    /// Buffers of decompressed records are reused without zeroing: every byte of a record is
    /// written, even in the layers a layered (COPC, format 6) chunk was not asked to decode.
    #[test]
    fn reused_record_buffers_hold_nothing_stale() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lidR_Topography.copc.laz");
        let info = inspect(&src).unwrap();
        assert!(info.point_format >= 6);
        let chunks = &info.layout.chunks;
        for fields in [Fields::Filter, Fields::Stats] {
            let records = |d: &mut FileDecoder| {
                d.decode(chunks, false, fields, |_, raw| Ok(raw.to_vec()))
                    .unwrap()
            };
            let clean = records(&mut FileDecoder::open(&info).unwrap());
            let mut dirty = FileDecoder::open(&info).unwrap();
            let most = chunks.iter().map(|c| c.points).max().unwrap() as usize;
            dirty
                .raw
                .give(vec![0xAA; most * info.record_length as usize]);
            assert!(
                records(&mut dirty) == clean,
                "stale bytes in decoded records"
            );
        }
    }

    /// Decoding a batch of spans at once, a corrupt span (or one whose records the job refuses)
    /// wins over a later span whose bytes cannot be read (here, one beyond the end of the file).
    #[test]
    fn a_corrupt_span_wins_over_a_later_unreadable_one() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lidR_Topography.copc.laz");
        let info = inspect(&src).unwrap();
        let chunks = &info.layout.chunks;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("damaged.laz");
        let mut bytes = std::fs::read(&src).unwrap();
        let c = chunks[1];
        bytes[c.offset as usize..(c.offset + c.bytes) as usize].fill(0);
        std::fs::write(&path, &bytes).unwrap();
        let info = inspect(&path).unwrap();
        let beyond = Chunk {
            offset: bytes.len() as u64 + 10,
            ..chunks[2]
        };
        for parallel in [false, true] {
            let mut d = FileDecoder::open(&info).unwrap();
            let spans = [chunks[0], c, beyond];
            let e = d.decode(&spans, parallel, Fields::Filter, |_, _| Ok(()));
            let message = e.unwrap_err().to_string();
            assert!(
                message.contains(&format!("chunk at byte {}", c.offset)),
                "{message}"
            );
            // Without the corrupt span, the unreadable one is the error.
            let e = d.decode(
                &[chunks[0], beyond],
                parallel,
                Fields::Filter,
                |_, _| Ok(()),
            );
            assert!(e.unwrap_err().to_string().contains("truncated"));
            // A job's error in an earlier span (a point it refuses) wins too.
            let first = chunks[0].offset;
            let refuse = |s: &Chunk, _: &[u8]| match s.offset == first {
                true => Err(format_error(&path, "point refused")),
                false => Ok(()),
            };
            let e = d.decode(&[chunks[0], beyond], parallel, Fields::Filter, refuse);
            assert!(e.unwrap_err().to_string().contains("point refused"));
        }
    }
}
