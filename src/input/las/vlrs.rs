//! The VLRs and EVLRs of a file: listed for `sweeptin info`, and the EVLRs read past the first
//! one (the `las` crate reads only the first; COPC writers such as copclib write one hierarchy
//! EVLR per page).

use super::header::format_error;
use crate::error::{Error, Result};
use serde::Serialize;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// One VLR or EVLR, as listed by `sweeptin info`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct VlrInfo {
    /// User id, e.g. `LASF_Projection`.
    pub user_id: String,
    /// Record id, e.g. 2112 (OGC WKT).
    pub record_id: u16,
    /// The record's own description.
    pub description: String,
    /// Payload bytes.
    pub bytes: u64,
    /// An extended VLR (after the points).
    pub extended: bool,
}

/// One EVLR: where its payload starts in the file, and the payload when it was asked for.
pub(crate) struct Evlr {
    pub(crate) at: u64,
    pub(crate) info: VlrInfo,
    pub(crate) data: Option<Vec<u8>>,
}

/// Size of an EVLR header in bytes.
const HEADER_LEN: u64 = 60;
/// At most this many EVLRs are listed (a damaged count cannot make us loop for long).
const MAX_EVLRS: u32 = 1 << 16;

/// Reads the header of every EVLR from `first` on, and the payload of those `keep` selects,
/// each checked against the file's length.
pub(crate) fn read_evlrs<R: Read + Seek>(
    path: &Path,
    read: &mut R,
    first: u64,
    count: u32,
    file_len: u64,
    keep: impl Fn(&str, u16) -> bool,
) -> Result<Vec<Evlr>> {
    let mut out = Vec::new();
    let mut at = first;
    for i in 0..count.min(MAX_EVLRS) {
        let past_end = || {
            format_error(
                path,
                format!(
                    "extended VLR {i} at byte {at} extends past the end of the file ({file_len} \
                     bytes): the file is truncated or its header is damaged"
                ),
            )
        };
        if at.checked_add(HEADER_LEN).is_none_or(|e| e > file_len) {
            return Err(past_end());
        }
        let mut h = [0u8; HEADER_LEN as usize];
        read.seek(SeekFrom::Start(at))
            .and_then(|_| read.read_exact(&mut h))
            .map_err(|e| Error::io(path, e))?;
        let text = |b: &[u8]| {
            String::from_utf8_lossy(b)
                .trim_end_matches('\0')
                .trim()
                .to_string()
        };
        let user_id = text(&h[2..18]);
        let record_id = u16::from_le_bytes([h[18], h[19]]);
        let len = u64::from_le_bytes(h[20..28].try_into().unwrap_or_default());
        let data_at = at + HEADER_LEN;
        if data_at.checked_add(len).is_none_or(|e| e > file_len) {
            return Err(past_end());
        }
        let data = if keep(&user_id, record_id) {
            let mut d = vec![0u8; len as usize];
            read.read_exact(&mut d).map_err(|e| Error::io(path, e))?;
            Some(d)
        } else {
            None
        };
        out.push(Evlr {
            at: data_at,
            info: VlrInfo {
                user_id,
                record_id,
                description: text(&h[28..60]),
                bytes: len,
                extended: true,
            },
            data,
        });
        at = data_at + len;
    }
    Ok(out)
}

/// The VLRs of `header`, then the EVLRs.
pub(crate) fn list(header: &las::Header, evlrs: &[Evlr]) -> Vec<VlrInfo> {
    header
        .vlrs()
        .iter()
        .map(|v| VlrInfo {
            user_id: v.user_id.clone(),
            record_id: v.record_id,
            description: v.description.clone(),
            bytes: v.data.len() as u64,
            extended: false,
        })
        .chain(evlrs.iter().map(|e| e.info.clone()))
        .collect()
}
