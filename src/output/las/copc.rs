//! COPC output (`.copc.laz`): the points a [rewrite](super::rewrite_points) writes, reordered
//! into a Cloud Optimized Point Cloud by the `copc-writer` crate (pure Rust, MIT/Apache-2.0).
//!
//! The rewrite first writes a plain LAS file (uncompressed: it is read back at once) in a
//! temporary directory under `--tmp-dir`; `copc-writer` then reads it through its own `las`
//! reader into a spill file beside it (a fixed-size record a point, memory-mapped), sorts the
//! points into the octree with index files of 4 bytes a point a level (in the system's
//! temporary directory, `$TMPDIR`: the crate takes no other), and compresses one octree node
//! (at most [`NODE_POINTS`] points) at a time into a temporary COPC file, which is finally
//! copied into the output ([`crate::output::AtomicFile`]: it appears only complete; an S3
//! output is uploaded). Memory: a node's points and the writers' buffers beside the page
//! cache of the spill (measured: docs/BENCHMARKS.md).
//!
//! What COPC changes, and what it keeps:
//! - **Point order**: the octree's (nodes in the hierarchy's order), never the input's. Compare
//!   a COPC output with another by the points, not by position.
//! - **Point format**: COPC is LAS 1.4 with point format 6 or 7 (8 with NIR, which
//!   `copc-writer` cannot write): formats 0 and 1 become 6, 2 and 3 become 7, each field
//!   carried to its LAS 1.4 spelling (the scan angle rank in degrees to the scaled angle of
//!   0.006°, the flags to their own bits); extra bytes and their descriptions are kept. Formats
//!   with NIR or waveforms (4, 5, 8, 9, 10) are refused before any work.
//! - **CRS**: a WKT record is kept; GeoTIFF keys (LAS ≤ 1.3) become the WKT of their EPSG code
//!   (with its `AUTHORITY`), for the codes sweeptin can spell (`Crs::prj`); another code, or a
//!   vertical code beside the horizontal one, is refused before any work.
//! - Scale, offset, GPS time type, file source id, GUID, system identifier, generating
//!   software, creation date (a day 0 too) and the other VLRs and EVLRs are kept.

use super::RewriteSummary;
use crate::error::{Error, Result};
use crate::input::las::FileInfo;
use crate::output::{AtomicFile, RegisteredTempDir};
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;

/// Where a LAS header holds the creation day of the year and the year (two `u16`).
const CREATION_AT: u64 = 90;

/// Points of an octree node at most (one LAZ chunk): `copc-writer`'s default, PDAL's order.
pub const NODE_POINTS: u32 = 100_000;

/// Does `path` name a COPC file (`.copc.laz`, any case)?
pub fn is_copc_path(path: &Path) -> bool {
    path.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.to_ascii_lowercase().ends_with(".copc.laz"))
}

/// Refuses `output` when it names a COPC file (`.copc.laz`) but `what` writes plain LAS/LAZ
/// (only `ground` writes COPC, [`CopcOutput`]): a plain LAZ under a COPC name would be taken
/// for one and fail in a COPC reader.
///
/// # Errors
/// [`Error::Options`] naming the output and the `.laz` name to give instead.
pub fn refuse_plain_copc(output: &Path, what: &str) -> Result<()> {
    if !is_copc_path(output) {
        return Ok(());
    }
    let mut laz = output.as_os_str().to_string_lossy().into_owned();
    laz.truncate(laz.len() - ".copc.laz".len());
    Err(Error::Options(format!(
        "{}: {what} writes plain LAZ, not COPC (only `sweeptin ground` writes a .copc.laz): \
         name the output {laz}.laz",
        output.display()
    )))
}

/// How the points of one input are written to a COPC file: checked from its header before
/// any work ([`CopcOutput::check`]).
#[derive(Clone, Debug)]
pub struct CopcOutput {
    /// The WKT of the input's GeoTIFF keys, when it has no WKT record.
    wkt: Option<String>,
    /// The input's creation day and year, as they are (`copc-writer` puts today's date for a
    /// day 0, which LAS allows: the output would change from day to day).
    created: (u16, u16),
}

impl CopcOutput {
    /// Checks that the points of `input` can be written to the COPC file `output` with every
    /// attribute and the CRS kept.
    ///
    /// # Errors
    /// [`Error::Options`] naming the input for a point format with NIR or waveforms, a CRS in
    /// GeoTIFF keys sweeptin cannot spell as WKT, or no points (a COPC file holds at least
    /// one); the header reader's errors; [`Error::Write`] naming the system's temporary
    /// directory (`$TMPDIR`, where `copc-writer` keeps its index files) when no file can be
    /// made there.
    pub fn check(input: &Path, output: &Path) -> Result<CopcOutput> {
        let info = FileInfo::read(input)?;
        let refuse = |why: String| {
            let mut laz = output.as_os_str().to_string_lossy().into_owned();
            laz.truncate(laz.len() - ".copc.laz".len().min(laz.len()));
            Error::Options(format!(
                "{}: {why}, which the COPC output {} cannot keep: write -o {laz}.laz (plain LAZ, \
                 every attribute kept) instead",
                input.display(),
                output.display()
            ))
        };
        match info.point_format {
            0..=3 | 6 | 7 => {}
            f => {
                return Err(refuse(format!(
                    "point format {f} (with {})",
                    if f == 8 { "NIR" } else { "waveforms" }
                )));
            }
        }
        if info.point_count == 0 {
            return Err(refuse("no points (a COPC file holds at least one)".into()));
        }
        let wkt = match &info.crs {
            Some(crs) if crs.wkt.is_none() => {
                let code = crs.epsg.filter(|_| crs.vertical_epsg.is_none());
                let spelled = code.and_then(|c| Some((c, crs.prj()?)));
                let Some((code, text)) = spelled else {
                    return Err(refuse(format!(
                        "a CRS in GeoTIFF keys ({}) that sweeptin cannot spell as the WKT COPC \
                         needs",
                        crs.definition().unwrap_or_else(|| "no EPSG code".into())
                    )));
                };
                // ESRI's WKT1 names no authority: the code, so that readers find it.
                let text = text.strip_suffix(']').unwrap_or(&text).to_string();
                Some(format!("{text},AUTHORITY[\"EPSG\",\"{code}\"]]"))
            }
            _ => None,
        };
        // `copc-writer` puts its octree index files in the system's temporary directory, not
        // `--tmp-dir`: one that cannot take a file is found now, not after the classification.
        let sys_tmp = std::env::temp_dir();
        tempfile::tempfile_in(&sys_tmp).map_err(|e| {
            let what = format!(
                "the COPC writer keeps its index files in the temporary directory ($TMPDIR), \
                 where no file can be made ({e}): set TMPDIR to a writable directory"
            );
            Error::write(&sys_tmp, std::io::Error::new(e.kind(), what))
        })?;
        Ok(CopcOutput {
            wkt,
            created: info.creation.unwrap_or_default(),
        })
    }

    /// Writes the points of `input` to the COPC file `output` through `rewrite`, which writes
    /// them (with their edits) to the plain LAS file it is given; temporary files under `tmp`.
    /// The summary is the rewrite's, with the output's path and size.
    ///
    /// # Errors
    /// The rewrite's; [`Error::Write`] naming `output` when `copc-writer` or the copy fails,
    /// [`Error::Options`] for what it refuses. No output is left.
    pub fn write(
        &self,
        output: &Path,
        tmp: &Path,
        rewrite: impl FnOnce(&Path) -> Result<RewriteSummary>,
    ) -> Result<RewriteSummary> {
        let dir = RegisteredTempDir::new_in(tmp)?;
        let las = dir.path().join("points.las");
        let mut summary = rewrite(&las)?;
        let copc = dir.path().join("points.copc.laz");
        let params = copc_writer::CopcWriterParams::new(NODE_POINTS);
        copc_writer::convert_las_to_copc_streaming_with_crs_wkt_override(
            &las,
            &copc,
            &params,
            dir.path(),
            &copc_core::NeverCancel,
            self.wkt.as_deref(),
        )
        .map_err(|e| match e {
            copc_core::Error::Io { context, source } => Error::write(
                output,
                std::io::Error::new(source.kind(), format!("{context}: {source}")),
            ),
            copc_core::Error::Unsupported(m) => {
                Error::Options(format!("{}: {m}", output.display()))
            }
            copc_core::Error::Cancelled => Error::Interrupted,
            other => Error::Format {
                path: output.to_path_buf(),
                message: format!("the COPC writer refused the points: {other}"),
            },
        })?;
        std::fs::remove_file(&las).map_err(|e| Error::write(&las, e))?;
        let mut from = std::fs::File::open(&copc).map_err(|e| Error::write(output, e))?;
        let mut out = AtomicFile::create_seekable(output, "a COPC file")?;
        std::io::copy(&mut from, &mut out).map_err(|e| out.err(e))?;
        let mut date = [0u8; 4];
        date[..2].copy_from_slice(&self.created.0.to_le_bytes());
        date[2..].copy_from_slice(&self.created.1.to_le_bytes());
        out.seek(SeekFrom::Start(CREATION_AT))
            .and_then(|_| out.write_all(&date))
            .and_then(|_| out.seek(SeekFrom::End(0)).map(|_| ()))
            .map_err(|e| out.err(e))?;
        summary.bytes = out.commit()?;
        summary.output = output.to_path_buf();
        summary.compressed = true;
        summary
            .notes
            .retain(|n| !n.contains("written as plain LAZ"));
        Ok(summary)
    }
}
