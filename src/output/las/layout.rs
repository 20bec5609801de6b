//! What a rewritten file keeps of its input around the points: the header, the VLRs, the bytes
//! between them and the points, the EVLRs; and what changes with the output's encoding.
//!
//! The header and VLRs are kept as raw bytes; only these fields are patched: the offset to the
//! point data, the number of VLRs, the point format's compression bit, the record length (when
//! attributes are added), the start of the first EVLR and of the waveform packets (when they
//! move), and the z bounds (when z is edited). The LASzip VLR is rebuilt for a LAZ output and
//! dropped for a LAS one; a COPC file's own records (user id `copc`) are dropped, since the
//! output is plain LAZ.

use crate::error::{Error, Result};
use crate::input::las::extra::{self, ExtraDims};
use crate::input::las::header::format_error;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

const VLR_HEADER_LEN: usize = 54;
const EVLR_HEADER_LEN: u64 = 60;

/// Header byte offsets (LAS 1.0–1.4).
pub(super) mod at {
    pub(crate) const OFFSET_TO_POINTS: usize = 96;
    pub(crate) const NUMBER_OF_VLRS: usize = 100;
    pub(crate) const FORMAT: usize = 104;
    pub(crate) const RECORD_LEN: usize = 105;
    pub(crate) const LEGACY_COUNT: usize = 107;
    pub(crate) const LEGACY_RETURNS: usize = 111;
    pub(crate) const MAX_X: usize = 179;
    pub(crate) const MAX_Z: usize = 211;
    pub(crate) const MIN_Z: usize = 219;
    pub(crate) const WAVEFORM: usize = 227;
    pub(crate) const FIRST_EVLR: usize = 235;
    pub(crate) const NUMBER_OF_EVLRS: usize = 243;
    pub(crate) const COUNT_14: usize = 247;
    pub(crate) const RETURNS_14: usize = 255;
}

/// One VLR, whole (its 54-byte header and payload).
#[derive(Clone, Debug)]
pub(super) struct Vlr {
    pub(super) user_id: String,
    pub(super) record_id: u16,
    pub(super) bytes: Vec<u8>,
}

impl Vlr {
    fn new(user_id: &str, record_id: u16, description: &str, payload: &[u8]) -> Result<Vlr> {
        let len = u16::try_from(payload.len()).map_err(|_| {
            Error::Options(format!(
                "a {user_id} VLR of {} bytes does not fit a VLR (65,535 bytes at most)",
                payload.len()
            ))
        })?;
        let mut bytes = vec![0u8; VLR_HEADER_LEN];
        put_text(&mut bytes[2..18], user_id);
        bytes[18..20].copy_from_slice(&record_id.to_le_bytes());
        bytes[20..22].copy_from_slice(&len.to_le_bytes());
        put_text(&mut bytes[22..54], description);
        bytes.extend_from_slice(payload);
        Ok(Vlr {
            user_id: user_id.into(),
            record_id,
            bytes,
        })
    }

    fn payload(&self) -> &[u8] {
        &self.bytes[VLR_HEADER_LEN..]
    }

    fn is(&self, user_id: &str, record_id: u16) -> bool {
        self.user_id == user_id && self.record_id == record_id
    }
}

/// One EVLR of the input: where it starts and its whole length (header and payload).
#[derive(Clone, Copy, Debug)]
pub(super) struct Evlr {
    pub(super) at: u64,
    pub(super) len: u64,
}

/// The input file around its points.
#[derive(Debug)]
pub(super) struct Source {
    pub(super) header: Vec<u8>,
    pub(super) vlrs: Vec<Vlr>,
    /// Bytes after the last VLR, before the points (user-defined bytes).
    pub(super) gap: Vec<u8>,
    pub(super) evlrs: Vec<Evlr>,
    pub(super) version: (u8, u8),
    pub(super) format: u8,
    pub(super) record_len: u16,
}

fn text(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).trim().to_string()
}

fn put_text(dst: &mut [u8], s: &str) {
    let n = s.len().min(dst.len());
    dst[..n].copy_from_slice(&s.as_bytes()[..n]);
}

fn u16_at(b: &[u8], k: usize) -> u16 {
    u16::from_le_bytes([b[k], b[k + 1]])
}

fn u32_at(b: &[u8], k: usize) -> u32 {
    u32::from_le_bytes(b[k..k + 4].try_into().unwrap_or_default())
}

fn u64_at(b: &[u8], k: usize) -> u64 {
    u64::from_le_bytes(b[k..k + 8].try_into().unwrap_or_default())
}

impl Source {
    /// Reads the header block (everything before the points) and lists the EVLRs of `path`,
    /// which [`crate::input::las::FileInfo::read`] has checked.
    pub(super) fn read(
        path: &Path,
        file: &mut (impl Read + Seek),
        file_len: u64,
    ) -> Result<Source> {
        let io = |e| Error::io(path, e);
        let mut head = [0u8; 227];
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.read_exact(&mut head[..227.min(file_len as usize)])
            .map_err(io)?;
        let data_start = u64::from(u32_at(&head, at::OFFSET_TO_POINTS));
        let mut block = vec![0u8; data_start as usize];
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.read_exact(&mut block).map_err(io)?;
        let header_len = usize::from(u16_at(&block, 94));
        let version = (block[24], block[25]);
        let mut vlrs = Vec::new();
        let mut k = header_len;
        for i in 0..u32_at(&block, at::NUMBER_OF_VLRS) {
            if k + VLR_HEADER_LEN > block.len() {
                return Err(format_error(
                    path,
                    format!("VLR {i} at byte {k} runs into the point data"),
                ));
            }
            let len = usize::from(u16_at(&block, k + 20));
            let end = k + VLR_HEADER_LEN + len;
            if end > block.len() {
                return Err(format_error(
                    path,
                    format!("VLR {i} at byte {k} runs into the point data"),
                ));
            }
            vlrs.push(Vlr {
                user_id: text(&block[k + 2..k + 18]),
                record_id: u16_at(&block, k + 18),
                bytes: block[k..end].to_vec(),
            });
            k = end;
        }
        let gap = block[k..].to_vec();
        block.truncate(header_len);
        let mut evlrs = Vec::new();
        let (first, count) = match version {
            (1, 4) if header_len >= 247 => (
                u64_at(&block, at::FIRST_EVLR),
                u32_at(&block, at::NUMBER_OF_EVLRS),
            ),
            // LAS 1.3: the waveform packets are one EVLR, when stored in the file.
            (1, 3) if header_len >= 235 && u16_at(&block, 6) & 2 != 0 => {
                let w = u64_at(&block, at::WAVEFORM);
                (w, u32::from(w > 0))
            }
            _ => (0, 0),
        };
        let mut pos = first;
        for i in 0..if first > 0 { count } else { 0 } {
            let mut h = [0u8; EVLR_HEADER_LEN as usize];
            let past = || {
                format_error(
                    path,
                    format!(
                        "extended VLR {i} at byte {pos} extends past the end of the file: the \
                         file is truncated or its header is damaged"
                    ),
                )
            };
            if pos
                .checked_add(EVLR_HEADER_LEN)
                .is_none_or(|e| e > file_len)
            {
                return Err(past());
            }
            file.seek(SeekFrom::Start(pos)).map_err(io)?;
            file.read_exact(&mut h).map_err(io)?;
            let len = EVLR_HEADER_LEN.saturating_add(u64_at(&h, 20));
            if pos.checked_add(len).is_none_or(|e| e > file_len) {
                return Err(past());
            }
            // COPC's hierarchy (and any other `copc` record) describes chunks the output does
            // not keep.
            if text(&h[2..18]) != "copc" {
                evlrs.push(Evlr { at: pos, len });
            }
            pos += len;
        }
        Ok(Source {
            version,
            format: block[at::FORMAT] & 0x3f,
            record_len: u16_at(&block, at::RECORD_LEN),
            header: block,
            vlrs,
            gap,
            evlrs,
        })
    }

    /// The fixed chunk size of the input's LASzip VLR (`None` for LAS, variable chunks or an
    /// unreadable VLR).
    pub(super) fn laz_chunk_size(&self) -> Option<u32> {
        let v = self
            .vlrs
            .iter()
            .find(|v| v.is(laz::LazVlr::USER_ID, laz::LazVlr::RECORD_ID))?;
        let vlr = laz::LazVlr::from_buffer(v.payload()).ok()?;
        (!vlr.uses_variable_size_chunks() && vlr.chunk_size() > 0).then(|| vlr.chunk_size())
    }

    /// The extra bytes VLR's attributes (none without one).
    pub(super) fn extra_dims(&self, path: &Path) -> Result<ExtraDims> {
        match self
            .vlrs
            .iter()
            .find(|v| v.is(extra::USER_ID, extra::RECORD_ID))
        {
            Some(v) => ExtraDims::of(path, v.payload(), self.format, self.record_len),
            None => Ok(ExtraDims::default()),
        }
    }
}

/// The output's header block, before the points.
pub(super) struct Plan {
    pub(super) block: Vec<u8>,
    pub(super) record_len: u16,
}

/// Builds the output's header and VLRs: `laz` the output's LASzip VLR payload (`None` for LAS),
/// `added` the descriptors of the attributes appended to every record (`added_len` bytes).
pub(super) fn plan(
    path: &Path,
    src: &Source,
    laz: Option<&[u8]>,
    added: &[[u8; extra::DESCRIPTOR_LEN]],
    added_len: u16,
) -> Result<Plan> {
    let mut vlrs: Vec<Vlr> = Vec::with_capacity(src.vlrs.len() + 2);
    let laszip = |v: &Vlr| v.is(laz::LazVlr::USER_ID, laz::LazVlr::RECORD_ID);
    let mut laz_placed = false;
    let mut extra_placed = added.is_empty();
    for v in &src.vlrs {
        if v.user_id == "copc" {
            continue;
        }
        if laszip(v) {
            if let Some(payload) = laz {
                vlrs.push(Vlr::new(
                    laz::LazVlr::USER_ID,
                    laz::LazVlr::RECORD_ID,
                    laz::LazVlr::DESCRIPTION,
                    payload,
                )?);
                laz_placed = true;
            }
            continue;
        }
        if v.is(extra::USER_ID, extra::RECORD_ID) && !extra_placed {
            vlrs.push(extra_vlr(path, src, Some(v), added)?);
            extra_placed = true;
            continue;
        }
        vlrs.push(v.clone());
    }
    if !extra_placed {
        vlrs.push(extra_vlr(path, src, None, added)?);
    }
    if let (Some(payload), false) = (laz, laz_placed) {
        vlrs.push(Vlr::new(
            laz::LazVlr::USER_ID,
            laz::LazVlr::RECORD_ID,
            laz::LazVlr::DESCRIPTION,
            payload,
        )?);
    }
    let record_len = src.record_len.checked_add(added_len).ok_or_else(|| {
        Error::Options(format!(
            "{}: records of {} bytes cannot grow by {added_len} (65,535 bytes at most)",
            path.display(),
            src.record_len
        ))
    })?;
    let mut block = src.header.clone();
    for v in &vlrs {
        block.extend_from_slice(&v.bytes);
    }
    block.extend_from_slice(&src.gap);
    let data_start = u32::try_from(block.len()).map_err(|_| {
        Error::Options(format!(
            "{}: the header and VLRs would take {} bytes, more than LAS allows",
            path.display(),
            block.len()
        ))
    })?;
    block[at::OFFSET_TO_POINTS..at::OFFSET_TO_POINTS + 4]
        .copy_from_slice(&data_start.to_le_bytes());
    block[at::NUMBER_OF_VLRS..at::NUMBER_OF_VLRS + 4]
        .copy_from_slice(&(vlrs.len() as u32).to_le_bytes());
    let format = src.header[at::FORMAT] & 0x3f;
    block[at::FORMAT] = if laz.is_some() { format | 0x80 } else { format };
    block[at::RECORD_LEN..at::RECORD_LEN + 2].copy_from_slice(&record_len.to_le_bytes());
    Ok(Plan { block, record_len })
}

/// The extra bytes VLR of the output: the input's descriptors (`old`), one for bytes they leave
/// undescribed, then `added`.
fn extra_vlr(
    path: &Path,
    src: &Source,
    old: Option<&Vlr>,
    added: &[[u8; extra::DESCRIPTOR_LEN]],
) -> Result<Vlr> {
    let dims = src.extra_dims(path)?;
    let standard = extra::STANDARD_LEN[usize::from(src.format.min(10))];
    let undescribed = usize::from(src.record_len.saturating_sub(standard)) - dims.described;
    let mut payload = old.map(|v| v.payload().to_vec()).unwrap_or_default();
    let mut left = undescribed;
    while left > 0 {
        let n = left.min(255);
        payload.extend(extra::undocumented(n as u8));
        left -= n;
    }
    for d in added {
        payload.extend_from_slice(d);
    }
    let description = "Extra Bytes Record";
    let mut v = Vlr::new(extra::USER_ID, extra::RECORD_ID, description, &payload)?;
    if let Some(old) = old {
        // Keep the input's own VLR header (its description), with the new length.
        v.bytes[..VLR_HEADER_LEN].copy_from_slice(&old.bytes[..VLR_HEADER_LEN]);
        v.bytes[20..22].copy_from_slice(&(payload.len() as u16).to_le_bytes());
    }
    Ok(v)
}

/// Patches the header of a finished output: where its EVLRs now start (`evlr_start`; the
/// waveform packets' start moved with the EVLR that holds them, `moved` maps old EVLR starts to
/// new), how many, and the z bounds when z was edited.
pub(super) fn finish_header(
    src: &Source,
    block: &mut [u8],
    evlr_start: u64,
    moved: &[(u64, u64)],
    z_bounds: Option<[f64; 2]>,
) {
    let header_len = src.header.len();
    if src.version >= (1, 3) && header_len >= 235 {
        let w = u64_at(&src.header, at::WAVEFORM);
        if let Some(&(_, new)) = moved.iter().find(|(old, _)| *old == w && w > 0) {
            block[at::WAVEFORM..at::WAVEFORM + 8].copy_from_slice(&new.to_le_bytes());
        }
    }
    if src.version >= (1, 4) && header_len >= 247 {
        let old = u64_at(&src.header, at::FIRST_EVLR);
        let first = if !moved.is_empty() || old != 0 {
            evlr_start
        } else {
            0
        };
        block[at::FIRST_EVLR..at::FIRST_EVLR + 8].copy_from_slice(&first.to_le_bytes());
        block[at::NUMBER_OF_EVLRS..at::NUMBER_OF_EVLRS + 4]
            .copy_from_slice(&(moved.len() as u32).to_le_bytes());
    }
    if let Some([min, max]) = z_bounds {
        block[at::MAX_Z..at::MAX_Z + 8].copy_from_slice(&max.to_le_bytes());
        block[at::MIN_Z..at::MIN_Z + 8].copy_from_slice(&min.to_le_bytes());
    }
}

/// Patches the header of an output that holds another set of points than its source's (some
/// left out, or several files joined): the point counts, by return too, and the x, y, z
/// bounds (`[[min, max]; 3]`). The legacy 32-bit counts are written where the source filled
/// them (LAS 1.4 with point formats 6–10 leaves them 0): the count of every point (before LAS
/// 1.4 it is the only count a reader has; points of return 6 and 7, which point formats 0–5
/// can hold, are in it though the five counts by return cannot name them), and 0 past their
/// range in LAS 1.4, whose 64-bit count holds it. More points than 32 bits count in an older
/// version are refused (the output is not committed).
pub(super) fn count_points(
    src: &Source,
    block: &mut [u8],
    points: u64,
    returns: &[u64; 15],
    bounds: [[f64; 2]; 3],
    output: &std::path::Path,
) -> Result<()> {
    let put32 = |block: &mut [u8], k: usize, v: u64| {
        let v = u32::try_from(v).unwrap_or(0);
        block[k..k + 4].copy_from_slice(&v.to_le_bytes());
    };
    let fits = points <= u64::from(u32::MAX);
    if !fits && src.version < (1, 4) {
        return Err(Error::Options(format!(
            "{}: {points} points do not fit the 32-bit count of a LAS {}.{} header: \
             give LAS 1.4 inputs (e.g. `las2las -set_version 1.4`) or write fewer points a file",
            output.display(),
            src.version.0,
            src.version.1
        )));
    }
    if u32_at(&src.header, at::LEGACY_COUNT) != 0 || src.version < (1, 4) {
        put32(block, at::LEGACY_COUNT, if fits { points } else { 0 });
        for (r, &n) in returns[..5].iter().enumerate() {
            put32(block, at::LEGACY_RETURNS + 4 * r, if fits { n } else { 0 });
        }
    }
    if src.version >= (1, 4) && src.header.len() >= at::RETURNS_14 + 15 * 8 {
        block[at::COUNT_14..at::COUNT_14 + 8].copy_from_slice(&points.to_le_bytes());
        for (r, &n) in returns.iter().enumerate() {
            let k = at::RETURNS_14 + 8 * r;
            block[k..k + 8].copy_from_slice(&n.to_le_bytes());
        }
    }
    for (a, [min, max]) in bounds.iter().enumerate() {
        let k = at::MAX_X + 16 * a;
        block[k..k + 8].copy_from_slice(&max.to_le_bytes());
        block[k + 8..k + 16].copy_from_slice(&min.to_le_bytes());
    }
    Ok(())
}
