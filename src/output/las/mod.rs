//! Rewriting a LAS/LAZ file point by point, keeping everything else.
//!
//! [`rewrite_points`] copies a file to a new one, calling an editor once per point in file
//! order. The editor sees each point's **raw record** through a [`PointEdit`] and may change
//! its classification (and, through [`rewrite_points_with`], its z and the attributes the
//! rewrite appends); nothing else can change. The output keeps the input's point format,
//! record length, extra bytes, VLRs and EVLRs, CRS, LAS version (1.0–1.4), GPS times, scale
//! and offset, header fields (system identifier and generating software included) and the
//! points' order:
//!
//! - **LAS in, LAS out** with no edit is byte for byte the input.
//! - **LAZ** output is compressed by the `laz` crate, chunks on every core (rayon), with the
//!   input's chunk size (50,000 points when the input's chunks vary, as in COPC); the LASzip
//!   VLR is rebuilt (at the input's VLR's place) and the chunk table written anew.
//! - The output's encoding follows its extension (`.laz` compressed, anything else LAS), so
//!   LAZ → LAS and LAS → LAZ convert: the LASzip VLR is dropped or appended, the offsets and
//!   the point format's compression bit follow.
//! - A **COPC** input (`.copc.laz`) gives plain LAZ: its points in the file's chunk order, its
//!   `copc` VLR and hierarchy EVLRs dropped. A COPC output is written by [`CopcOutput`] from
//!   the plain LAS file a rewrite writes (the points then in the octree's order).
//!
//! Memory is bounded: the points stream through in batches of chunks (about
//! [`BATCH_BYTES`] of records), decoded and compressed on every core.
//!
//! The output is atomic ([`crate::output::AtomicFile`]): written to a temporary file beside it
//! and renamed into place only when complete, so an error (the editor's included) leaves no
//! output. It must be a regular file name or nothing yet: an input of the rewrite, a symbolic
//! link, a FIFO, a device or a directory is refused before anything is read.
//!
//! ```no_run
//! use sweeptin::output::las::rewrite_points;
//! use std::path::Path;
//!
//! // Every point below 100 m becomes ground (class 2).
//! let summary = rewrite_points(Path::new("in.laz"), Path::new("out.laz"), &mut |p| {
//!     if p.xyz().2 < 100.0 {
//!         p.set_classification(2);
//!     }
//!     Ok(())
//! })?;
//! println!("{} of {} points changed", summary.changed, summary.points);
//! # Ok::<(), sweeptin::Error>(())
//! ```

mod copc;
mod layout;

pub use copc::{CopcOutput, NODE_POINTS, is_copc_path, refuse_plain_copc};

use crate::error::{Error, Result};
use crate::input::las::decode::{Fields, FileDecoder, spans};
use crate::input::las::extra;
use crate::input::las::header::{Chunk, inspect};
use crate::input::las::world::Quantization;
use crate::output::AtomicFile;
use serde::Serialize;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Records decoded, edited and written at once (bytes of input records, at least one chunk).
pub const BATCH_BYTES: u64 = 32 << 20;

/// Points per LAZ chunk when the input's chunks vary in size (LASzip's default).
const DEFAULT_CHUNK: u32 = 50_000;

/// One point of the file being rewritten, as the editor sees it.
pub struct PointEdit<'a> {
    index: u64,
    record: &'a mut [u8],
    format: u8,
    quant: &'a Quantization,
    /// Where each appended attribute starts in the record.
    added: &'a [usize],
    changed: bool,
    z_changed: bool,
    /// A class that does not fit the point format, refused at the end of the edit.
    refused: Option<u8>,
    /// Left out of the output ([`PointEdit::skip`]).
    skipped: bool,
}

impl PointEdit<'_> {
    /// The point's 0-based index in this file, in file order.
    pub fn index(&self) -> u64 {
        self.index
    }

    /// The ASPRS classification (5 bits in point formats 0–5, 8 bits in 6–10).
    pub fn classification(&self) -> u8 {
        if self.format >= 6 {
            self.record[16]
        } else {
            self.record[15] & 0x1f
        }
    }

    /// Sets the classification, patching only its bits: in point formats 0–5 the low 5 bits
    /// of byte 15 (the synthetic, key-point and withheld flags kept), in 6–10 byte 16.
    ///
    /// A class above 31 does not fit formats 0–5: the point is left as it is and the rewrite
    /// fails with [`Error::Options`] naming the point and the class (no output is written).
    pub fn set_classification(&mut self, class: u8) {
        if class == self.classification() {
            return;
        }
        if self.format >= 6 {
            self.record[16] = class;
        } else if class > 31 {
            self.refused = Some(class);
            return;
        } else {
            self.record[15] = (self.record[15] & 0xe0) | class;
        }
        self.changed = true;
    }

    /// The stored integers X, Y, Z.
    fn ints(&self) -> [i32; 3] {
        std::array::from_fn(|a| {
            i32::from_le_bytes(self.record[4 * a..4 * a + 4].try_into().unwrap_or_default())
        })
    }

    /// World coordinates, exactly as the readers give them ([`crate::input::las::world`]).
    pub fn xyz(&self) -> (f64, f64, f64) {
        let [x, y, z] = self.quant.to_world(self.ints());
        (x, y, z)
    }

    /// Replaces z by `z` (world units), stored with the file's z scale and offset (rounded to
    /// the nearest step). The header's z bounds are recomputed.
    ///
    /// # Errors
    /// [`Error::Options`] when `z` is not finite or does not fit the file's 32-bit integers.
    pub fn set_z(&mut self, z: f64) -> Result<()> {
        let (scale, offset) = (self.quant.scale[2], self.quant.offset[2]);
        let n = ((z - offset) / scale).round();
        if !(n.is_finite() && n >= f64::from(i32::MIN) && n <= f64::from(i32::MAX)) {
            return Err(Error::Options(format!(
                "point {}: z = {z} does not fit the file's z scale {scale} and offset {offset}",
                self.index
            )));
        }
        let n = n as i32;
        if n != self.ints()[2] {
            self.record[8..12].copy_from_slice(&n.to_le_bytes());
            self.changed = true;
        }
        self.z_changed = true;
        Ok(())
    }

    /// Sets the `k`-th attribute the rewrite appends ([`RewriteOptions::add`]; stored as a
    /// double).
    ///
    /// # Panics
    /// When the rewrite appends fewer than `k + 1` attributes.
    pub fn set_added(&mut self, k: usize, value: f64) {
        let at = self.added[k];
        self.record[at..at + 8].copy_from_slice(&value.to_le_bytes());
    }

    /// Flags the point *withheld* (in formats 0–5 bit 7 of byte 15, in 6–10 bit 2 of byte 15).
    pub fn set_withheld(&mut self) {
        let bit = if self.format >= 6 { 0x04 } else { 0x80 };
        if self.record[15] & bit == 0 {
            self.record[15] |= bit;
            self.changed = true;
        }
    }

    /// The whole record, read-only (the point format's fields, then the extra bytes).
    pub fn record(&self) -> &[u8] {
        self.record
    }

    /// Leaves the point out of the output: the header's point counts (by return too) and its
    /// x, y, z bounds then count only the points written.
    pub fn skip(&mut self) {
        self.skipped = true;
    }

    /// The point's return number (bits 0–2 of byte 14 in formats 0–5, 0–3 in 6–10).
    fn return_number(&self) -> u8 {
        self.record[14] & if self.format >= 6 { 0x0f } else { 0x07 }
    }
}

/// An attribute appended to every record (a double, in the extra bytes).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AddedAttribute {
    /// Its name (at most 32 bytes), such as PDAL's `HeightAboveGround`.
    pub name: String,
    /// Its description (at most 32 bytes).
    pub description: String,
}

/// What a rewrite changes beyond the editor's per-point edits.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RewriteOptions {
    /// Attributes appended to every record, in order: the extra bytes VLR gains their
    /// descriptors (it is created when missing), records grow by 8 bytes each; 0 until set.
    pub add: Vec<AddedAttribute>,
}

/// What a rewrite did.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RewriteSummary {
    /// The output file.
    pub output: PathBuf,
    /// Points written (all of the input's, less those the editor skipped).
    pub points: u64,
    /// Points left out: by the editor ([`PointEdit::skip`]), or not read
    /// ([`rewrite_points_in`]).
    #[serde(skip_serializing_if = "is_zero")]
    pub skipped: u64,
    /// Points whose classification or z the editor changed.
    pub changed: u64,
    /// Bytes of the output file.
    pub bytes: u64,
    /// Whether the output is LAZ.
    pub compressed: bool,
    /// Notes for the user (a COPC input written as plain LAZ).
    pub notes: Vec<String>,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// Does `path` name a LAZ file (`.laz`, any case; `.copc.laz` too)?
pub fn is_laz_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("laz"))
}

/// Rewrites `input` to `output`, calling `edit` once per point in file order (see the
/// [module docs](self)).
///
/// # Errors
/// [`Error::Options`] when `output` is `input` (or a link to it); [`Error::Output`] when it is a
/// symbolic link, a FIFO, a device or a directory; [`Error::Format`] / [`Error::Io`] for a
/// damaged or unreadable input; [`Error::Write`] when writing fails; the editor's own errors.
/// In every case no output file is left.
pub fn rewrite_points(
    input: &Path,
    output: &Path,
    edit: &mut dyn FnMut(&mut PointEdit<'_>) -> Result<()>,
) -> Result<RewriteSummary> {
    rewrite_points_with(input, output, &RewriteOptions::default(), edit)
}

/// Refuses an output not named `.las` or `.laz`, an output that is an input, or one that is not
/// a regular file (or nothing yet).
pub fn check_point_output(output: &Path, inputs: &[PathBuf]) -> Result<()> {
    check_output_target(output, inputs)?;
    let ext = output.extension().and_then(|e| e.to_str());
    if !ext.is_some_and(|e| e.eq_ignore_ascii_case("las") || e.eq_ignore_ascii_case("laz")) {
        return Err(Error::Options(format!(
            "{}: a point file is named OUT.laz (compressed) or OUT.las: the name says what \
             readers find in it",
            output.display()
        )));
    }
    Ok(())
}

/// [`check_point_output`] but for the name's extension: an output of points (a LAS/LAZ file or
/// a `.vpc`) that is an input, or not a regular file (or nothing yet), is refused.
pub(crate) fn check_output_target(output: &Path, inputs: &[PathBuf]) -> Result<()> {
    match std::fs::symlink_metadata(output) {
        Ok(m) if !m.file_type().is_file() => {
            let what = if m.file_type().is_symlink() {
                "a symbolic link"
            } else if m.is_dir() {
                "a directory"
            } else {
                "not a regular file (a FIFO, a device or a socket)"
            };
            return Err(Error::Output {
                path: output.to_path_buf(),
                message: format!(
                    "it is {what}: a point file is written only to a regular file name \
                     (remove it or give another name)"
                ),
            });
        }
        _ => {}
    }
    crate::output::distinct_outputs(&[("the output", output)], inputs, "the rewrite")?;
    crate::output::check_output(output)
}

/// [`rewrite_points`] with [`RewriteOptions`]: attributes appended to every record.
///
/// # Errors
/// As [`rewrite_points`].
pub fn rewrite_points_with(
    input: &Path,
    output: &Path,
    options: &RewriteOptions,
    edit: &mut dyn FnMut(&mut PointEdit<'_>) -> Result<()>,
) -> Result<RewriteSummary> {
    check_point_output(output, &[input.to_path_buf()])?;
    rewrite(
        &[input.to_path_buf()],
        output,
        options,
        None,
        &mut |_, p| edit(p),
        BATCH_BYTES,
    )
}

/// [`rewrite_points`] of only some of the input's points: the spans of records (LAZ chunks,
/// slices of LAS records) for which `keep(first, count)` is false (the points `first ..
/// first + count` in file order) are neither decoded nor written, as if the editor had
/// [skipped](PointEdit::skip) each of their points. A plan's ground task reads so only the
/// chunks that meet its tile.
///
/// # Errors
/// As [`rewrite_points`].
pub fn rewrite_points_in(
    input: &Path,
    output: &Path,
    keep: &dyn Fn(u64, u64) -> bool,
    edit: &mut dyn FnMut(&mut PointEdit<'_>) -> Result<()>,
) -> Result<RewriteSummary> {
    check_point_output(output, &[input.to_path_buf()])?;
    let opts = RewriteOptions::default();
    rewrite(
        &[input.to_path_buf()],
        output,
        &opts,
        Some(keep),
        &mut |_, p| edit(p),
        BATCH_BYTES,
    )
}

/// Writes the points of `inputs`, one after the other (each in its file order), into one file
/// `output`, calling `edit` with the input's position and each point (which it may change or
/// [skip](PointEdit::skip)). The inputs must share their point format, record length, extra
/// bytes, scale and offset (the records are copied as they are); the output keeps the first
/// input's header, VLRs and EVLRs, with the point counts and bounds of the points written.
///
/// # Errors
/// [`Error::Options`] naming the first input that differs from the first in point format,
/// record length, extra bytes, scale or offset (the records of one file cannot hold both);
/// otherwise as [`rewrite_points`].
pub fn join_points(
    inputs: &[PathBuf],
    output: &Path,
    edit: &mut dyn FnMut(usize, &mut PointEdit<'_>) -> Result<()>,
) -> Result<RewriteSummary> {
    join_points_within(inputs, output, edit, BATCH_BYTES)
}

/// [`join_points`] decoding and compressing about `batch_bytes` of records at a time (at least
/// one LAZ chunk; never more than [`BATCH_BYTES`]): `sweeptin merge --mem`. The same file
/// whatever the batch.
pub(crate) fn join_points_within(
    inputs: &[PathBuf],
    output: &Path,
    edit: &mut dyn FnMut(usize, &mut PointEdit<'_>) -> Result<()>,
    batch_bytes: u64,
) -> Result<RewriteSummary> {
    check_point_output(output, inputs)?;
    let Some(first) = inputs.first() else {
        return Err(Error::NoInput);
    };
    let head = |p: &Path| -> Result<(crate::input::las::FileInfo, Option<Vec<u8>>)> {
        let info = inspect(p)?;
        let mut file = crate::input::source::Source::open(p)?.reader();
        let len = file.source().len();
        let src = layout::Source::read(p, &mut file, len)?;
        let extra = src
            .vlrs
            .iter()
            .find(|v| v.user_id == extra::USER_ID && v.record_id == extra::RECORD_ID)
            .map(|v| v.bytes[54..].to_vec());
        Ok((info, extra))
    };
    let (a, a_extra) = head(first)?;
    for p in &inputs[1..] {
        let (b, b_extra) = head(p)?;
        let differs = if a.point_format != b.point_format {
            Some(format!(
                "point format {} (not {})",
                b.point_format, a.point_format
            ))
        } else if a.record_length != b.record_length || a_extra != b_extra {
            Some(format!(
                "records of {} bytes with their extra bytes (not {} bytes as {})",
                b.record_length,
                a.record_length,
                first.display()
            ))
        } else if a.version != b.version {
            Some(format!(
                "LAS {}.{} (not {}.{})",
                b.version.0, b.version.1, a.version.0, a.version.1
            ))
        } else if (a.global_encoding ^ b.global_encoding) & 1 != 0 {
            let time = |e: u16| {
                if e & 1 == 0 {
                    "GPS week time"
                } else {
                    "adjusted standard GPS time"
                }
            };
            Some(format!(
                "{} (not {})",
                time(b.global_encoding),
                time(a.global_encoding)
            ))
        } else if a.scale != b.scale || a.offset != b.offset {
            Some(format!(
                "scale {:?} and offset {:?} (not {:?} and {:?})",
                b.scale, b.offset, a.scale, a.offset
            ))
        } else {
            None
        };
        if let Some(d) = differs {
            return Err(Error::Options(format!(
                "{}: {d}: its points cannot be written unchanged into one file with those of {}",
                p.display(),
                first.display()
            )));
        }
    }
    rewrite(
        inputs,
        output,
        &RewriteOptions::default(),
        None,
        edit,
        batch_bytes.min(BATCH_BYTES),
    )
}

/// The rewrite of `inputs` (one file's, or several alike: [`join_points`]) into `output`.
fn rewrite(
    inputs: &[PathBuf],
    output: &Path,
    options: &RewriteOptions,
    keep: Option<&dyn Fn(u64, u64) -> bool>,
    edit: &mut dyn FnMut(usize, &mut PointEdit<'_>) -> Result<()>,
    batch_bytes: u64,
) -> Result<RewriteSummary> {
    // The caller's checks say so before any work; this guards the writer itself.
    refuse_plain_copc(output, "the point rewrite")?;
    let input = inputs.first().ok_or(Error::NoInput)?.as_path();
    let info = inspect(input)?;
    let mut file = crate::input::source::Source::open(input)?.reader();
    let file_len = file.source().len();
    let src = layout::Source::read(input, &mut file, file_len)?;
    let compress = is_laz_path(output);
    let added_len = 8 * options.add.len();
    let added_len = u16::try_from(added_len)
        .map_err(|_| Error::Options("too many attributes to add".into()))?;
    let descriptors: Vec<_> = options
        .add
        .iter()
        .map(|a| extra::descriptor(&a.name, &a.description))
        .collect();
    let out_len = usize::from(info.record_length) + usize::from(added_len);
    let laz_vlr = if compress {
        let extra = out_len - usize::from(extra::STANDARD_LEN[usize::from(info.point_format)]);
        let items =
            laz::LazItemRecordBuilder::default_for_point_format_id(info.point_format, extra as u16)
                .map_err(|e| {
                    Error::Options(format!(
                        "{}: point format {} cannot be written as LAZ: {e}",
                        output.display(),
                        info.point_format
                    ))
                })?;
        let chunk = src.laz_chunk_size().unwrap_or(DEFAULT_CHUNK);
        Some(
            laz::LazVlrBuilder::new(items)
                .with_fixed_chunk_size(chunk)
                .build(),
        )
    } else {
        None
    };
    let laz_payload = match &laz_vlr {
        Some(v) => {
            let mut p = Vec::new();
            v.write_to(&mut p)
                .map_err(|e| Error::Internal(e.to_string()))?;
            Some(p)
        }
        None => None,
    };
    let plan = layout::plan(input, &src, laz_payload.as_deref(), &descriptors, added_len)?;
    if usize::from(plan.record_len) != out_len {
        return Err(Error::Internal(format!(
            "the rewrite of {} planned records of {} bytes, not {out_len}",
            input.display(),
            plan.record_len
        )));
    }
    let mut notes = Vec::new();
    let mut out = AtomicFile::create_seekable(output, "a LAS/LAZ file")?;
    out.write_all(&plan.block).map_err(|e| out.err(e))?;
    let mut sink = match laz_vlr {
        Some(v) => Sink::Laz(
            laz::ParLasZipCompressor::new(out, v)
                .map_err(|e| Error::Internal(format!("cannot start the LAZ compressor: {e}")))?,
        ),
        None => Sink::Las(out),
    };
    let added: Vec<usize> = (0..options.add.len())
        .map(|k| usize::from(info.record_length) + 8 * k)
        .collect();
    let record_len = usize::from(info.record_length);
    let mut tally = Tally::default();
    let mut records = Vec::new();
    for (k, path) in inputs.iter().enumerate() {
        let info = if k == 0 { info.clone() } else { inspect(path)? };
        if info.copc.is_some() {
            notes.push(format!(
                "{}: a COPC file, written as plain LAZ to {}: its points in the file's chunk \
                 order, its COPC index dropped",
                path.display(),
                output.display()
            ));
        }
        let quant = info.quantization();
        let mut all = spans(&info, (batch_bytes / record_len.max(1) as u64).max(1), None);
        if let Some(keep) = keep {
            let before: u64 = all.iter().map(|s| s.points).sum();
            all.retain(|s| keep(s.first, s.points));
            tally.skipped += before - all.iter().map(|s| s.points).sum::<u64>();
        }
        let mut decoder = FileDecoder::open(&info)?;
        for batch in batches(&all, record_len as u64, batch_bytes) {
            let raw = decoder.decode(batch, true, Fields::All, |_, raw| Ok(raw.to_vec()))?;
            records.clear();
            for (span, span_records) in batch.iter().zip(&raw) {
                for (j, rec) in span_records.chunks_exact(record_len).enumerate() {
                    let start = records.len();
                    records.extend_from_slice(rec);
                    records.resize(start + out_len, 0);
                    let mut p = PointEdit {
                        index: span.first + j as u64,
                        record: &mut records[start..],
                        format: info.point_format,
                        quant: &quant,
                        added: &added,
                        changed: false,
                        z_changed: false,
                        refused: None,
                        skipped: false,
                    };
                    edit(k, &mut p)?;
                    let skipped = p.skipped;
                    tally.add(&p, path)?;
                    if skipped {
                        records.truncate(start);
                    }
                }
            }
            sink.write(&records).map_err(|e| Error::write(output, e))?;
        }
    }
    let mut out = sink.finish(output)?;
    // The EVLRs, copied after the points.
    let evlr_start = out.stream_position().map_err(|e| out.err(e))?;
    let mut moved = Vec::with_capacity(src.evlrs.len());
    for e in &src.evlrs {
        let now = out.stream_position().map_err(|e| out.err(e))?;
        moved.push((e.at, now));
        file.seek(SeekFrom::Start(e.at))
            .map_err(|err| Error::io(input, err))?;
        copy_exact(&mut file, &mut out, e.len, input, output)?;
    }
    let mut block = plan.block;
    let z_bounds = tally.z_changed.then_some(tally.z);
    layout::finish_header(&src, &mut block, evlr_start, &moved, z_bounds);
    if tally.skipped > 0 || inputs.len() > 1 {
        // Another set of points than the first input's: its counts and bounds.
        layout::count_points(
            &src,
            &mut block,
            tally.points,
            &tally.returns,
            tally.bounds(),
            output,
        )?;
    }
    let header_len = src.header.len();
    out.seek(SeekFrom::Start(0))
        .and_then(|_| out.write_all(&block[..header_len]))
        .and_then(|_| out.seek(SeekFrom::End(0)).map(|_| ()))
        .map_err(|e| out.err(e))?;
    let bytes = out.commit()?;
    Ok(RewriteSummary {
        output: output.to_path_buf(),
        points: tally.points,
        skipped: tally.skipped,
        changed: tally.changed,
        bytes,
        compressed: compress,
        notes,
    })
}

/// Where the edited records go.
enum Sink {
    Las(AtomicFile),
    Laz(laz::ParLasZipCompressor<AtomicFile>),
}

impl Sink {
    fn write(&mut self, records: &[u8]) -> std::io::Result<()> {
        match self {
            Sink::Las(f) => f.write_all(records),
            Sink::Laz(c) => c.compress_many(records),
        }
    }

    /// Ends the points (a LAZ file's last chunk and its chunk table).
    fn finish(self, output: &Path) -> Result<AtomicFile> {
        match self {
            Sink::Las(f) => Ok(f),
            Sink::Laz(mut c) => {
                c.done().map_err(|e| match e {
                    laz::LasZipError::IoError(io) => Error::write(output, io),
                    other => Error::Internal(format!("LAZ compression failed: {other}")),
                })?;
                Ok(c.into_inner())
            }
        }
    }
}

/// Counts and bounds of the points written.
#[derive(Default)]
struct Tally {
    points: u64,
    skipped: u64,
    changed: u64,
    z_changed: bool,
    z: [f64; 2],
    /// x, y bounds (min, max) of the points written.
    xy: [[f64; 2]; 2],
    /// Points written by return number (1 to 15).
    returns: [u64; 15],
}

impl Tally {
    fn add(&mut self, p: &PointEdit<'_>, input: &Path) -> Result<()> {
        if let Some(class) = p.refused {
            return Err(Error::Options(format!(
                "{}: point {}: class {class} does not fit point format {} (classes 0 to 31 in \
                 formats 0-5); rewrite the file as LAS 1.4 point format 6-10 first",
                input.display(),
                p.index,
                p.format
            )));
        }
        if p.skipped {
            self.skipped += 1;
            return Ok(());
        }
        let (x, y, z) = p.xyz();
        if self.points == 0 {
            self.z = [z, z];
            self.xy = [[x, x], [y, y]];
        } else {
            self.z = [self.z[0].min(z), self.z[1].max(z)];
            self.xy = [
                [self.xy[0][0].min(x), self.xy[0][1].max(x)],
                [self.xy[1][0].min(y), self.xy[1][1].max(y)],
            ];
        }
        if let Some(n) = self
            .returns
            .get_mut(usize::from(p.return_number()).wrapping_sub(1))
        {
            *n += 1;
        }
        self.points += 1;
        self.changed += u64::from(p.changed);
        self.z_changed |= p.z_changed;
        Ok(())
    }

    /// `[[xmin, xmax], [ymin, ymax], [zmin, zmax]]` of the points written (zeros for none).
    fn bounds(&self) -> [[f64; 2]; 3] {
        [self.xy[0], self.xy[1], self.z]
    }
}

/// Consecutive runs of spans holding about `batch_bytes` of records (at least one span): a
/// batch of LAZ chunks decodes and compresses on every core.
fn batches(spans: &[Chunk], record_len: u64, batch_bytes: u64) -> impl Iterator<Item = &[Chunk]> {
    let mut rest = spans;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        let (mut bytes, mut n) = (0, 0);
        while n < rest.len() && (n == 0 || bytes < batch_bytes) {
            bytes += rest[n].points * record_len;
            n += 1;
        }
        let (now, later) = rest.split_at(n);
        rest = later;
        Some(now)
    })
}

/// Copies `len` bytes from `from` to `to`, a piece at a time.
fn copy_exact(
    from: &mut crate::input::source::SourceRead,
    to: &mut AtomicFile,
    len: u64,
    input: &Path,
    output: &Path,
) -> Result<()> {
    let mut left = len;
    let mut buf = vec![0u8; crate::sort::WRITE_PIECE];
    while left > 0 {
        let n = left.min(buf.len() as u64) as usize;
        std::io::Read::read_exact(from, &mut buf[..n]).map_err(|e| Error::io(input, e))?;
        to.write_all(&buf[..n])
            .map_err(|e| Error::write(output, e))?;
        left -= n as u64;
    }
    Ok(())
}
