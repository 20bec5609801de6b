//! Header facts of one LAS/LAZ file, and the checks that make damaged files fail cleanly.
//!
//! [`FileInfo::read`] reads the header, the VLRs and (for LAZ) the chunk table, and checks them
//! against the file's length *before* any decoder sees the file. The decoders trust these numbers
//! when they size their buffers, so a damaged header could otherwise make them allocate
//! absurd amounts of memory or panic. Every problem becomes an [`Error::Format`] naming the file.

use super::copc::{self, CopcInfo, Node};
use super::vlrs::{self, VlrInfo};
use super::world::Quantization;
use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::input::source::Source;
use serde::Serialize;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Size of an EVLR header in bytes.
const EVLR_HEADER_LEN: u64 = 60;

/// Minimum and maximum of x, y and z in real-world units, as stored in a header.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Bounds3 {
    /// Minimum x, y, z.
    pub min: [f64; 3],
    /// Maximum x, y, z.
    pub max: [f64; 3],
}

impl Bounds3 {
    /// Does this header box say where the points are: finite, min ≤ max on every axis, and not
    /// all zero (what writers leave when they did not compute it)?
    pub fn usable(&self) -> bool {
        let zero = self.min.iter().chain(&self.max).all(|v| *v == 0.0);
        let ordered = (0..3).all(|k| self.min[k] <= self.max[k]);
        let finite = self.min.iter().chain(&self.max).all(|v| v.is_finite());
        !zero && ordered && finite
    }

    /// The smallest box containing both.
    pub fn union(&self, other: &Bounds3) -> Bounds3 {
        Bounds3 {
            min: std::array::from_fn(|a| self.min[a].min(other.min[a])),
            max: std::array::from_fn(|a| self.max[a].max(other.max[a])),
        }
    }
}

/// One LAZ chunk: where its bytes are, how many points it holds, and the file-order index of its
/// first point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Chunk {
    pub(crate) offset: u64,
    pub(crate) bytes: u64,
    pub(crate) points: u64,
    pub(crate) first: u64,
}

/// Where the point records of a file are: LAZ chunks (empty for LAS), and the COPC octree
/// node of each chunk.
#[derive(Clone, Debug, Default)]
pub(crate) struct Layout {
    pub(crate) data_start: u64,
    pub(crate) chunks: Vec<Chunk>,
    pub(crate) nodes: Option<Vec<Node>>,
}

/// What a LAS/LAZ file's header says about it.
#[derive(Clone, Debug, Serialize)]
pub struct FileInfo {
    /// The file.
    pub path: PathBuf,
    /// LAS version as written in the file, e.g. `(1, 4)`.
    pub version: (u8, u8),
    /// Point data record format, 0–10 (without the LAZ compression bit).
    pub point_format: u8,
    /// Whether the points are LASzip-compressed (LAZ).
    pub compressed: bool,
    /// Bytes per point record, including extra bytes.
    pub record_length: u16,
    /// Extra bytes per record beyond the point format's standard fields.
    pub extra_bytes: u16,
    /// The number of points the reader will read: the LAS 1.4 64-bit count for point formats
    /// 6-10, the legacy 32-bit count when non-zero for the others (`announced_points`).
    pub point_count: u64,
    /// The legacy 32-bit "number of point records" field.
    pub legacy_point_count: u32,
    /// The LAS 1.4 64-bit "number of point records" field (`None` before LAS 1.4).
    pub extended_point_count: Option<u64>,
    /// Bounds stored in the header (real-world units).
    pub bounds: Bounds3,
    /// Scale factors for x, y, z.
    pub scale: [f64; 3],
    /// Offsets for x, y, z.
    pub offset: [f64; 3],
    /// The declared coordinate reference system, if any.
    pub crs: Option<Crs>,
    /// Header "system identifier".
    pub system_identifier: String,
    /// Header "generating software".
    pub generating_software: String,
    /// Oddities that do not stop reading (unreadable CRS VLR, disagreeing point counts…).
    pub warnings: Vec<String>,
    /// Points per return number, as the header counts them (5 entries before LAS 1.4, 15 in it).
    pub points_by_return: Vec<u64>,
    /// File creation day of the year and year, when set.
    pub creation: Option<(u16, u16)>,
    /// File source id (often the flight line).
    pub file_source_id: u16,
    /// Global encoding bits (bit 0: GPS time is adjusted standard time; bit 4: WKT CRS).
    pub global_encoding: u16,
    /// The VLRs, then the EVLRs.
    pub vlrs: Vec<VlrInfo>,
    /// The COPC octree, for a COPC file.
    pub copc: Option<CopcInfo>,
    #[serde(skip)]
    pub(crate) layout: Layout,
}

impl FileInfo {
    /// Reads and checks the header of a LAS/LAZ file (and, for LAZ, its chunk table).
    /// Does not read the points.
    ///
    /// # Errors
    /// [`Error::Io`] if the file cannot be opened; [`Error::Format`] if it is empty, not a
    /// LAS/LAZ file, truncated, or its header or chunk table is inconsistent.
    pub fn read(path: impl AsRef<Path>) -> Result<FileInfo> {
        inspect(path.as_ref())
    }

    /// The file's scale and offset, and how its integers become real-world doubles.
    pub fn quantization(&self) -> Quantization {
        Quantization::new(self.scale, self.offset)
    }

    /// The header extent as `[xmin, ymin, xmax, ymax]`.
    pub fn rect(&self) -> [f64; 4] {
        let b = &self.bounds;
        [b.min[0], b.min[1], b.max[0], b.max[1]]
    }

    /// The header extent when it says where the points are ([`Bounds3::usable`]): only such
    /// a box may prove that a file misses an area (an all-zero box left by a writer that did
    /// not compute it made `--bbox` skip the file's points without a word).
    pub fn known_rect(&self) -> Option<[f64; 4]> {
        self.bounds.usable().then(|| self.rect())
    }
}

pub(crate) fn format_error(path: &Path, message: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Turns an error of the `las` crate into a message a user can act on.
pub(crate) fn las_message(e: &las::Error) -> String {
    match e {
        las::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "unexpected end of file: the file is truncated".to_string()
        }
        las::Error::LasZipError(laz) => laz_message(laz),
        other => other.to_string(),
    }
}

/// Turns an error of the `laz` crate into a message a user can act on.
pub(crate) fn laz_message(e: &laz::LasZipError) -> String {
    match e {
        laz::LasZipError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "unexpected end of compressed data: the file is truncated".to_string()
        }
        other => other.to_string(),
    }
}

/// Opens, checks and describes one file.
pub(crate) fn inspect(path: &Path) -> Result<FileInfo> {
    let source = Source::open(path)?;
    let file_len = source.len();
    let mut read = source.reader();
    check_signature(path, &mut read, file_len)?;
    read.seek(SeekFrom::Start(0))
        .map_err(|e| Error::io(path, e))?;
    let raw = las::raw::Header::read_from(&mut read)
        .map_err(|e| format_error(path, format!("cannot read the header: {}", las_message(&e))))?;
    check_raw_header(path, &raw, file_len)?;
    check_evlr(path, &mut read, &raw, file_len)?;
    read.seek(SeekFrom::Start(0))
        .map_err(|e| Error::io(path, e))?;
    let header = las::Header::new(&mut read)
        .map_err(|e| format_error(path, format!("invalid header: {}", las_message(&e))))?;
    let point_count = announced_points(&raw, file_len);
    let data_start = u64::from(raw.offset_to_point_data);
    let mut layout = Layout {
        data_start,
        ..Layout::default()
    };
    if header.point_format().is_compressed {
        layout.chunks = super::laz_check::check_laz(
            path,
            &mut read,
            &header,
            point_count,
            file_len,
            data_start,
        )?;
    } else {
        check_las_length(path, &raw, point_count, file_len)?;
    }
    let evlrs = match raw.evlr.filter(|e| e.start_of_first_evlr > 0) {
        Some(e) => vlrs::read_evlrs(
            path,
            &mut read,
            e.start_of_first_evlr,
            e.number_of_evlrs,
            file_len,
            |user, record| {
                (user == "copc" && record == 1000) || (user == "LASF_Projection" && record == 2112)
            },
        )?,
        None => Vec::new(),
    };
    let copc =
        copc::index(path, &header, &evlrs, &layout.chunks, point_count)?.map(|(info, nodes)| {
            layout.nodes = Some(nodes);
            info
        });
    let mut info = describe(path, &raw, &header, point_count);
    if let Some(more) = unannounced_records(&raw, point_count, file_len) {
        info.warnings.push(format!(
            "the file holds room for {more} more points than its header announces after the \
             {point_count} it reads (a header not updated after points were added?)"
        ));
    }
    info.vlrs = vlrs::list(&header, &evlrs);
    // A WKT in an EVLR past the first (copclib writes it last), which `las` does not read.
    if info.crs.is_none() {
        info.crs = evlrs
            .iter()
            .filter(|e| e.info.user_id == "LASF_Projection" && e.info.record_id == 2112)
            .find_map(|e| Crs::from_wkt_bytes(e.data.as_ref()?));
    }
    info.copc = copc;
    info.layout = layout;
    Ok(info)
}

fn check_signature(path: &Path, read: &mut impl Read, file_len: u64) -> Result<()> {
    if file_len == 0 {
        return Err(format_error(
            path,
            "the file is empty (0 bytes): not a LAS/LAZ file",
        ));
    }
    let mut start = [0u8; 16];
    let n = read_up_to(read, &mut start).map_err(|e| Error::io(path, e))?;
    if n < 4 || &start[..4] != b"LASF" {
        let shown: String = start[..n]
            .iter()
            .map(|&b| {
                if b.is_ascii_graphic() || b == b' ' {
                    b as char
                } else {
                    '.'
                }
            })
            .collect();
        return Err(format_error(
            path,
            format!(
                "not a LAS/LAZ file: it starts with \"{shown}\" instead of the signature \"LASF\""
            ),
        ));
    }
    Ok(())
}

fn read_up_to(read: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match read.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

fn check_raw_header(path: &Path, raw: &las::raw::Header, file_len: u64) -> Result<()> {
    let (major, minor) = (raw.version.major, raw.version.minor);
    if major != 1 || minor > 4 {
        return Err(format_error(
            path,
            format!("unsupported LAS version {major}.{minor} (supported: 1.0 to 1.4)"),
        ));
    }
    if raw.header_size < raw.version.header_size() {
        return Err(format_error(
            path,
            format!(
                "header size {} is smaller than the {} bytes of a LAS {major}.{minor} header",
                raw.header_size,
                raw.version.header_size()
            ),
        ));
    }
    let data_start = u64::from(raw.offset_to_point_data);
    if data_start < u64::from(raw.header_size) {
        return Err(format_error(
            path,
            format!(
                "offset to point data {data_start} is smaller than the header size {}",
                raw.header_size
            ),
        ));
    }
    if data_start > file_len {
        return Err(format_error(
            path,
            format!(
                "the point data should start at byte {data_start}, but the file has only \
                 {file_len} bytes: the file is truncated or its header is damaged"
            ),
        ));
    }
    let scales = [raw.x_scale_factor, raw.y_scale_factor, raw.z_scale_factor];
    let offsets = [raw.x_offset, raw.y_offset, raw.z_offset];
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        if !(scales[a].is_finite() && scales[a] > 0.0) {
            return Err(format_error(
                path,
                format!(
                    "invalid {axis} scale factor {} (must be finite and > 0)",
                    scales[a]
                ),
            ));
        }
        if !offsets[a].is_finite() {
            return Err(format_error(
                path,
                format!("invalid {axis} offset {} (must be finite)", offsets[a]),
            ));
        }
    }
    Ok(())
}

/// The `las` crate reads the first EVLR whole; make sure it lies inside the file.
fn check_evlr<R: Read + Seek>(
    path: &Path,
    read: &mut R,
    raw: &las::raw::Header,
    file_len: u64,
) -> Result<()> {
    let Some(evlr) = raw
        .evlr
        .filter(|e| e.start_of_first_evlr > 0 && e.number_of_evlrs > 0)
    else {
        return Ok(());
    };
    let start = evlr.start_of_first_evlr;
    let past_end = || {
        format_error(
            path,
            format!(
                "the extended VLR at byte {start} extends past the end of the file \
                 ({file_len} bytes): the file is truncated or its header is damaged"
            ),
        )
    };
    if start
        .checked_add(EVLR_HEADER_LEN)
        .is_none_or(|end| end > file_len)
    {
        return Err(past_end());
    }
    read.seek(SeekFrom::Start(start + 20))
        .map_err(|e| Error::io(path, e))?;
    let mut len = [0u8; 8];
    read.read_exact(&mut len).map_err(|e| Error::io(path, e))?;
    let len = u64::from_le_bytes(len);
    if (start + EVLR_HEADER_LEN)
        .checked_add(len)
        .is_none_or(|end| end > file_len)
    {
        return Err(past_end());
    }
    Ok(())
}

fn check_las_length(
    path: &Path,
    raw: &las::raw::Header,
    point_count: u64,
    file_len: u64,
) -> Result<()> {
    let data_start = u64::from(raw.offset_to_point_data);
    let record = u64::from(raw.point_data_record_length);
    let needed = point_count
        .checked_mul(record)
        .and_then(|b| b.checked_add(data_start));
    match needed {
        Some(end) if end <= file_len => Ok(()),
        _ => Err(format_error(
            path,
            format!(
                "the file is truncated: the header announces {point_count} points of {record} bytes \
                 from byte {data_start}, but the file has only {file_len} bytes \
                 (room for {} points)",
                file_len.saturating_sub(data_start) / record.max(1)
            ),
        )),
    }
}

/// Whether the file is uncompressed records and nothing after them (no EVLR, no waveform
/// packets): its length then says how many records it holds.
fn records_end_the_file(raw: &las::raw::Header) -> bool {
    let compressed =
        raw.point_data_record_format & 0x80 != 0 || raw.point_data_record_format & 0x40 != 0;
    let after = raw.evlr.is_some_and(|e| e.start_of_first_evlr > 0)
        || raw
            .start_of_waveform_data_packet_record
            .is_some_and(|w| w > 0);
    !compressed && !after && raw.point_data_record_length > 0
}

/// Whole records of an uncompressed file past the announced points, when nothing else (no
/// EVLR, no waveform packets) claims those bytes.
fn unannounced_records(raw: &las::raw::Header, points: u64, file_len: u64) -> Option<u64> {
    if !records_end_the_file(raw) {
        return None;
    }
    let record = u64::from(raw.point_data_record_length);
    let end = u64::from(raw.offset_to_point_data).checked_add(points.checked_mul(record)?)?;
    let more = file_len.checked_sub(end)? / record;
    (more > 0).then_some(more)
}

/// The points a header announces. For point formats 6-10 the 64-bit count of LAS 1.4 when it is
/// non-zero: their legacy 32-bit field must be 0 (a format-6 file whose legacy field said 100 of
/// its 400 points was read as 100). Otherwise the legacy count when non-zero (LAS 1.4 R15, as
/// the `las` crate does), else the 64-bit one; but when both are set and differ in an
/// uncompressed file of `file_len` bytes with nothing after its points, the one its length fits.
pub(crate) fn announced_points(raw: &las::raw::Header, file_len: u64) -> u64 {
    let legacy = u64::from(raw.number_of_point_records);
    let Some(ext) = raw
        .large_file
        .map(|l| l.number_of_point_records)
        .filter(|&e| e > 0)
    else {
        return legacy;
    };
    if legacy == 0 || raw.point_data_record_format & 0x3f >= 6 {
        return ext;
    }
    if legacy != ext && records_end_the_file(raw) {
        let record = u64::from(raw.point_data_record_length);
        let fits = |n: u64| {
            n.checked_mul(record)
                .and_then(|b| b.checked_add(u64::from(raw.offset_to_point_data)))
                == Some(file_len)
        };
        if fits(ext) && !fits(legacy) {
            return ext;
        }
    }
    legacy
}

fn describe(
    path: &Path,
    raw: &las::raw::Header,
    header: &las::Header,
    point_count: u64,
) -> FileInfo {
    let mut warnings = Vec::new();
    let extended = raw.large_file.map(|l| l.number_of_point_records);
    let legacy = raw.number_of_point_records;
    if let Some(ext) = extended
        && legacy != 0
        && u64::from(legacy) != ext
    {
        warnings.push(format!(
            "legacy point count {legacy} differs from the LAS 1.4 count {ext}; using {} (the \
             legacy one for point formats 0-5, LAS 1.4 R15; the 64-bit one for formats 6-10, \
             whose legacy field must be 0)",
            point_count
        ));
    }
    let crs = read_crs(header, &mut warnings);
    let format = header.point_format();
    let points_by_return = match raw.large_file {
        Some(l) => l.number_of_points_by_return.to_vec(),
        None => raw.number_of_points_by_return.map(u64::from).to_vec(),
    };

    let zero = |v: f64| v + 0.0; // turn -0.0 into 0.0
    FileInfo {
        path: path.to_path_buf(),
        version: (raw.version.major, raw.version.minor),
        point_format: raw.point_data_record_format & 0x3f,
        compressed: format.is_compressed,
        record_length: raw.point_data_record_length,
        extra_bytes: format.extra_bytes,
        point_count,
        legacy_point_count: legacy,
        extended_point_count: extended,
        bounds: Bounds3 {
            min: [raw.min_x, raw.min_y, raw.min_z],
            max: [raw.max_x, raw.max_y, raw.max_z],
        },
        scale: [raw.x_scale_factor, raw.y_scale_factor, raw.z_scale_factor],
        offset: [zero(raw.x_offset), zero(raw.y_offset), zero(raw.z_offset)],
        crs,
        system_identifier: header.system_identifier().to_string(),
        generating_software: header.generating_software().to_string(),
        warnings,
        points_by_return,
        creation: (raw.file_creation_year > 0)
            .then_some((raw.file_creation_day_of_year, raw.file_creation_year)),
        file_source_id: raw.file_source_id,
        global_encoding: raw.global_encoding,
        vlrs: Vec::new(),
        copc: None,
        layout: Layout::default(),
    }
}

/// The WKT VLR wins over GeoTIFF keys when both are present (LAS 1.4 says WKT is authoritative
/// for the point formats that require it, and writers that emit both copy the same CRS).
fn read_crs(header: &las::Header, warnings: &mut Vec<String>) -> Option<Crs> {
    if let Some(crs) = header.get_wkt_crs_bytes().and_then(Crs::from_wkt_bytes) {
        return Some(crs);
    }
    match header.get_geotiff_crs() {
        Ok(Some(keys)) => Crs::from_geotiff(&keys),
        Ok(None) => None,
        Err(e) => {
            warnings.push(format!(
                "unreadable GeoTIFF CRS VLR ({}); CRS unknown",
                las_message(&e)
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Bounds3;

    #[test]
    fn a_box_is_usable_when_it_says_where_points_are() {
        let b = |min: [f64; 3], max: [f64; 3]| Bounds3 { min, max }.usable();
        assert!(b([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]));
        assert!(
            b([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            "partly zero: a point at the origin"
        );
        assert!(b([5.0; 3], [5.0; 3]), "one point");
        assert!(!b([0.0; 3], [0.0; 3]), "all zero: never computed");
        assert!(!b([1.0, 2.0, 3.0], [0.0, 5.0, 6.0]), "inverted");
        assert!(!b([f64::NAN, 2.0, 3.0], [4.0, 5.0, 6.0]));
        assert!(!b([f64::NEG_INFINITY, 2.0, 3.0], [4.0, 5.0, 6.0]));
        assert!(!b([1.0, 2.0, 3.0], [4.0, f64::INFINITY, 6.0]));
    }
}
