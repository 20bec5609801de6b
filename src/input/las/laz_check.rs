//! The LAZ checks made before any point is decoded: the LASzip VLR against the point format,
//! the chunk table against the file's length and the header's point count (a damaged or
//! truncated LAZ file is refused by name, never decoded into garbage).

use super::header::{Chunk, format_error, las_message, laz_message};
use crate::error::{Error, Result};
use crate::input::source::SourceRead;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// The LASzip VLR's user id and record id.
const LASZIP_USER_ID: &str = "laszip encoded";
const LASZIP_RECORD_ID: u16 = 22204;

/// Checks the LASzip VLR and the chunk table against the file length and the point count;
/// returns the chunks.
pub(super) fn check_laz(
    path: &Path,
    file: &mut SourceRead,
    header: &las::Header,
    points: u64,
    file_len: u64,
    data_start: u64,
) -> Result<Vec<Chunk>> {
    let has_vlr = header
        .all_vlrs()
        .any(|v| v.user_id == LASZIP_USER_ID && v.record_id == LASZIP_RECORD_ID);
    if !has_vlr {
        return Err(format_error(
            path,
            "the point format is marked compressed (LAZ) but the LASzip VLR is missing",
        ));
    }
    let vlr = header
        .laz_vlr()
        .map_err(|e| format_error(path, format!("invalid LASzip VLR: {}", las_message(&e))))?;
    let record_len = u64::from(header.point_format().len());
    if vlr.items_size() != record_len {
        return Err(format_error(
            path,
            format!(
                "the LASzip VLR describes {}-byte points but the header says {record_len} bytes",
                vlr.items_size()
            ),
        ));
    }
    let variable = vlr.uses_variable_size_chunks();
    if !variable && vlr.chunk_size() == 0 {
        return Err(format_error(path, "the LASzip VLR has a chunk size of 0"));
    }
    let table_at = chunk_table_offset(path, file, file_len, data_start)?;
    let n_chunks = read_chunk_count(path, file, table_at)?;
    // Every chunk holds at least one byte and one point (writers may add one empty chunk).
    let max_chunks = file_len.min(points.saturating_add(1));
    if n_chunks > max_chunks {
        return Err(format_error(
            path,
            format!(
                "the LAZ chunk table claims {n_chunks} chunks, impossible for {points} points \
                 in {file_len} bytes: the file is damaged"
            ),
        ));
    }
    if points == 0 {
        return Ok(Vec::new()); // nothing will be decompressed
    }
    if n_chunks == 0 {
        return Err(format_error(
            path,
            format!("the LAZ chunk table is empty but the header announces {points} points"),
        ));
    }
    file.seek(SeekFrom::Start(data_start))
        .map_err(|e| Error::io(path, e))?;
    let table =
        laz::laszip::ChunkTable::read_from(BufReader::new(&mut *file), &vlr).map_err(|e| {
            format_error(
                path,
                format!("cannot read the LAZ chunk table: {}", laz_message(&e)),
            )
        })?;
    check_chunk_entries(path, &table, &vlr, points, table_at - (data_start + 8))?;
    // A remote file's chunks are checked as their bytes arrive (`layers_fit`), not by a
    // request per chunk here.
    if let Some(layers) = layer_count(&vlr)
        && !file.source().is_remote()
    {
        check_layers(path, file, &table, &vlr, data_start + 8, layers)?;
    }
    // Fixed-size chunks: the table says `chunk_size` for the last one too, which may hold fewer.
    let entries: &[laz::laszip::ChunkTableEntry] = table.as_ref();
    let mut chunks = Vec::with_capacity(entries.len());
    let (mut offset, mut first) = (data_start + 8, 0u64);
    for e in entries {
        let n = e.point_count.min(points - first);
        if n > 0 {
            chunks.push(Chunk {
                offset,
                bytes: e.byte_count,
                points: n,
                first,
            });
        }
        offset += e.byte_count;
        first += n;
    }
    Ok(chunks)
}

/// Number of layer sizes at the start of each chunk of a *layered* LAZ file (point formats
/// 6–10), or `None` for point-wise compression. Layer sizes are `u32`s the decoder trusts when
/// it sizes its buffers, hence [`check_layers`].
pub(super) fn layer_count(vlr: &laz::LazVlr) -> Option<u64> {
    use laz::LazItemType as T;
    let items = vlr.items();
    if !items.iter().any(|i| matches!(i.item_type(), T::Point14)) {
        return None;
    }
    Some(
        items
            .iter()
            .map(|i| match i.item_type() {
                T::Point14 => 9,
                T::RGBNIR14 => 2,
                T::Byte14(n) => u64::from(n),
                _ => 1,
            })
            .sum(),
    )
}

/// Each layered chunk starts with one raw point, a point count and the layer sizes; their sum
/// must fit in the chunk's bytes.
fn check_layers(
    path: &Path,
    file: &mut SourceRead,
    table: &laz::laszip::ChunkTable,
    vlr: &laz::LazVlr,
    first_chunk_at: u64,
    layers: u64,
) -> Result<()> {
    let head_len = vlr.items_size() + 4;
    let mut sizes = vec![0u8; (layers * 4) as usize];
    let mut at = first_chunk_at;
    let entries: &[laz::laszip::ChunkTableEntry] = table.as_ref();
    for (i, e) in entries.iter().enumerate() {
        if e.byte_count >= head_len + 4 * layers {
            file.source()
                .read_exact_at(at + head_len, &mut sizes)
                .map_err(|e| Error::io(path, e))?;
        }
        layers_fit(&sizes, vlr, layers, e.byte_count).map_err(|what| {
            format_error(
                path,
                format!("LAZ chunk {i} (at byte {at}) is damaged: {what}"),
            )
        })?;
        at += e.byte_count;
    }
    Ok(())
}

/// Whether a layered chunk of `byte_count` bytes holds the layers its sizes claim: `sizes` are
/// the `4 × layers` bytes after its first raw point and point count (read only when the chunk
/// is long enough to hold them).
pub(super) fn layers_fit(
    sizes: &[u8],
    vlr: &laz::LazVlr,
    layers: u64,
    byte_count: u64,
) -> std::result::Result<(), String> {
    let head_len = vlr.items_size() + 4;
    if byte_count < head_len + 4 * layers {
        return Err("it is too short to hold its layer sizes".into());
    }
    let total: u64 = sizes
        .chunks_exact(4)
        .take(layers as usize)
        .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
        .sum();
    if head_len + 4 * layers + total > byte_count {
        return Err(format!(
            "its layers claim {total} bytes, more than the chunk's {byte_count} bytes"
        ));
    }
    Ok(())
}

/// Where the chunk table starts, found the way LASzip does: the 8 bytes at the start of the
/// point data, or (when a streaming writer could not go back to fill them) the file's last 8.
fn chunk_table_offset(
    path: &Path,
    file: &mut SourceRead,
    file_len: u64,
    data_start: u64,
) -> Result<u64> {
    let read_i64 = |file: &mut SourceRead, at: u64| -> Result<i64> {
        let mut b = [0u8; 8];
        file.seek(SeekFrom::Start(at))
            .and_then(|_| file.read_exact(&mut b))
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::UnexpectedEof {
                    format_error(path, "the LAZ point data is missing: the file is truncated")
                } else {
                    Error::io(path, e)
                }
            })?;
        Ok(i64::from_le_bytes(b))
    };
    let mut offset = read_i64(file, data_start)?;
    if offset <= data_start as i64 && file_len >= data_start + 16 {
        offset = read_i64(file, file_len - 8)?;
    }
    if offset <= data_start as i64 {
        return Err(format_error(
            path,
            "the LAZ chunk table is missing (no valid offset to it): the file is truncated or \
             was not finished by its writer",
        ));
    }
    let offset = offset as u64;
    if offset.saturating_add(8) > file_len {
        return Err(format_error(
            path,
            format!(
                "the LAZ chunk table should start at byte {offset}, past the end of the file \
                 ({file_len} bytes): the file is truncated"
            ),
        ));
    }
    Ok(offset)
}

fn read_chunk_count(path: &Path, file: &mut SourceRead, table_at: u64) -> Result<u64> {
    let mut b = [0u8; 8];
    file.seek(SeekFrom::Start(table_at))
        .and_then(|_| file.read_exact(&mut b))
        .map_err(|e| Error::io(path, e))?;
    Ok(u64::from(u32::from_le_bytes([b[4], b[5], b[6], b[7]])))
}

fn check_chunk_entries(
    path: &Path,
    table: &laz::laszip::ChunkTable,
    vlr: &laz::LazVlr,
    points: u64,
    data_bytes: u64,
) -> Result<()> {
    let entries: &[laz::laszip::ChunkTableEntry] = table.as_ref();
    let mut bytes = 0u64;
    let mut counted = 0u64;
    for e in entries {
        bytes = bytes.saturating_add(e.byte_count);
        counted = counted.saturating_add(e.point_count);
    }
    if bytes > data_bytes {
        return Err(format_error(
            path,
            format!(
                "the LAZ chunk table lists {bytes} bytes of compressed points but only \
                 {data_bytes} bytes precede the table: the file is damaged"
            ),
        ));
    }
    let consistent = if vlr.uses_variable_size_chunks() {
        counted == points
    } else {
        let size = u64::from(vlr.chunk_size());
        points <= counted && points > counted - size
    };
    if !consistent {
        return Err(format_error(
            path,
            format!(
                "the LAZ chunk table ({} chunks, {counted} points) does not match the {points} \
                 points announced by the header: the file is damaged",
                entries.len()
            ),
        ));
    }
    Ok(())
}
