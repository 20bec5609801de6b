//! LAZ decoding chunk by chunk, each chunk checked against the chunk table.
//!
//! A LAZ file's points are compressed in chunks (usually 50,000 points) listed in a chunk table
//! with their sizes. A decoder that runs over the chunks as one stream takes damaged bytes for
//! data: a file with its middle zeroed decodes "fine" into 50,000 copies of one point. Here each
//! chunk is decoded on its own, from exactly its bytes, and must use exactly them: a chunk whose
//! points end before its bytes do, or need more bytes than it has, is **corrupt** (named by its
//! number and its points), which is not the same as a **truncated** file (bytes missing at the
//! end, found from the file's length). Chunks are decoded in parallel (rayon's pool).

use super::header::{format_error, laz_message};
use crate::error::{Error, Result};
use laz::laszip::{ChunkTable, ChunkTableEntry};
use rayon::prelude::*;
use std::fs::File;
use std::io::{BufReader, Cursor, Read};
use std::path::Path;

/// Decodes the chunks of one LAZ file in order (see the module docs).
pub(super) struct ChunkDecoder {
    input: BufReader<File>,
    vlr: laz::LazVlr,
    table: Vec<ChunkTableEntry>,
    /// The next chunk to decode.
    next: usize,
    /// Points not yet decoded.
    remaining: u64,
    /// Number of the first point of the next chunk, in the file.
    first_point: u64,
}

impl ChunkDecoder {
    /// Reads the chunk table of the LAZ file whose point data `input` is at (its chunk-table
    /// offset), leaving it at the first chunk.
    pub(super) fn open(
        path: &Path,
        mut input: BufReader<File>,
        vlr: laz::LazVlr,
        points: u64,
    ) -> Result<ChunkDecoder> {
        let table = ChunkTable::read_from(&mut input, &vlr).map_err(|e| {
            format_error(
                path,
                format!("cannot read the LAZ chunk table: {}", laz_message(&e)),
            )
        })?;
        Ok(ChunkDecoder {
            input,
            vlr,
            table: table.as_ref().to_vec(),
            next: 0,
            remaining: points,
            first_point: 0,
        })
    }

    /// Decodes whole chunks, as many as fit in `max_points` points (at least one), into `out`
    /// (resized to their records); returns the number of points.
    ///
    /// # Errors
    /// [`Error::Format`]: "truncated" when the file ends inside a chunk, "corrupt (chunk K,
    /// points A to B)" when a chunk's bytes do not decode into exactly its points.
    pub(super) fn decode(
        &mut self,
        path: &Path,
        max_points: u64,
        out: &mut Vec<u8>,
    ) -> Result<u64> {
        let point_size = self.vlr.items_size() as usize;
        let mut chunks: Vec<(usize, u64, Vec<u8>)> = Vec::new();
        let mut total = 0u64;
        while self.remaining > 0 && self.next < self.table.len() {
            let e = self.table[self.next];
            // A fixed-size table lists the chunk size for the last chunk too.
            let n = e.point_count.min(self.remaining);
            if !chunks.is_empty() && total + n > max_points {
                break;
            }
            let mut bytes = vec![0u8; usize::try_from(e.byte_count).unwrap_or(usize::MAX)];
            self.input.read_exact(&mut bytes).map_err(|err| {
                if err.kind() == std::io::ErrorKind::UnexpectedEof {
                    format_error(
                        path,
                        format!(
                            "unexpected end of file in LAZ chunk {}: the file is truncated",
                            self.next
                        ),
                    )
                } else {
                    Error::io(path, err)
                }
            })?;
            chunks.push((self.next, self.first_point, bytes));
            self.next += 1;
            self.remaining -= n;
            self.first_point += n;
            total += n;
        }
        if chunks.is_empty() && self.remaining > 0 {
            return Err(format_error(
                path,
                format!(
                    "the LAZ chunk table lists fewer points than the header ({} missing)",
                    self.remaining
                ),
            ));
        }
        out.clear();
        out.resize(total as usize * point_size, 0);
        let mut slices = Vec::with_capacity(chunks.len());
        let mut rest = &mut out[..];
        let mut starts = Vec::with_capacity(chunks.len());
        for (k, (_, first, _)) in chunks.iter().enumerate() {
            let end = chunks.get(k + 1).map_or(self.first_point, |c| c.1);
            let (head, tail) = rest.split_at_mut((end - first) as usize * point_size);
            slices.push(head);
            starts.push(*first);
            rest = tail;
        }
        let vlr = &self.vlr;
        let failed = chunks
            .par_iter()
            .zip(slices.par_iter_mut())
            .map(|((index, first, bytes), slice)| {
                decode_chunk(vlr, bytes, slice)
                    .err()
                    .map(|what| (*index, *first, slice.len() / point_size, what))
            })
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .next();
        if let Some((index, first, n, what)) = failed {
            return Err(format_error(
                path,
                format!(
                    "corrupt LAZ data in chunk {index} (points {first} to {}): {what}",
                    first + n as u64 - 1
                ),
            ));
        }
        Ok(total)
    }
}

/// Decodes one chunk's `bytes` into `out` (its points' records) with a decompressor that sees
/// only them, and checks that it used exactly them.
fn decode_chunk(
    vlr: &laz::LazVlr,
    bytes: &[u8],
    out: &mut [u8],
) -> std::result::Result<(), String> {
    let points = out.len() / vlr.items_size() as usize;
    // The layout a decompressor expects: the offset of the chunk table, the chunk, the table.
    let mut buf = Vec::with_capacity(8 + bytes.len() + 32);
    buf.extend_from_slice(&((8 + bytes.len()) as i64).to_le_bytes());
    buf.extend_from_slice(bytes);
    let mut table = ChunkTable::with_capacity(1);
    table.push(ChunkTableEntry {
        point_count: points as u64,
        byte_count: bytes.len() as u64,
    });
    table
        .write_to(&mut buf, vlr)
        .map_err(|e| format!("cannot set up its decoder: {e}"))?;
    let run = || -> std::result::Result<u64, String> {
        let mut d = laz::LasZipDecompressor::new(Cursor::new(&buf[..]), vlr.clone())
            .map_err(|e| laz_message(&e))?;
        d.decompress_many(out).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                format!(
                    "its {points} points need more than its {} bytes",
                    bytes.len()
                )
            } else {
                e.to_string()
            }
        })?;
        Ok(d.get().position() - 8)
    };
    let used = std::panic::catch_unwind(std::panic::AssertUnwindSafe(run))
        .unwrap_or_else(|_| Err("the decoder failed on it".into()))?;
    if used != bytes.len() as u64 {
        return Err(format!(
            "its {points} points decode from {used} of its {} bytes",
            bytes.len()
        ));
    }
    Ok(())
}
