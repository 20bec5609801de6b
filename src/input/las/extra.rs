//! Extra bytes: the attributes a point record carries past its format's standard fields,
//! described by the `LASF_Spec` record 4 VLR (LAS 1.4 R15, section 2.5.2.4; laspy, PDAL and
//! LAStools read and write it in every LAS version).
//!
//! [`ExtraDims::of`] parses the descriptors of a file and places each attribute in the record;
//! [`ExtraDim::value`] reads one point's value (scale and offset applied). The point writer
//! (`output::las`) appends new attributes with [`descriptor`], and the reader takes z from one
//! with `--z-from NAME` ([`crate::input::las::Filter::z_from`]).

use crate::error::{Error, Result};
use std::path::Path;

/// User id of the extra bytes VLR.
pub const USER_ID: &str = "LASF_Spec";
/// Record id of the extra bytes VLR.
pub const RECORD_ID: u16 = 4;
/// Bytes of one descriptor.
pub const DESCRIPTOR_LEN: usize = 192;
/// Data type code of a double (`f64`), the type the writer gives new attributes.
pub const DOUBLE: u8 = 10;

/// Bytes of each point format's standard fields (0–10).
pub const STANDARD_LEN: [u16; 11] = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67];

/// One attribute of the extra bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtraDim {
    /// Its name, as in the descriptor.
    pub name: String,
    /// Its first byte in the point record.
    pub start: usize,
    /// The LAS data type (1–10 scalars, 0 undocumented bytes, 11–30 deprecated arrays).
    pub data_type: u8,
    /// Bytes it takes in the record.
    pub len: usize,
    /// Scale applied to the stored number (1 when the descriptor sets none).
    pub scale: f64,
    /// Offset added after the scale (0 when the descriptor sets none).
    pub offset: f64,
}

impl ExtraDim {
    /// The attribute's value in `record` (scale and offset applied); `None` for undocumented
    /// bytes and the deprecated array types.
    pub fn value(&self, record: &[u8]) -> Option<f64> {
        let b = record.get(self.start..self.start + self.len)?;
        let raw = match self.data_type {
            1 => f64::from(b[0]),
            2 => f64::from(b[0] as i8),
            3 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            4 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            5 => f64::from(u32::from_le_bytes(b.try_into().ok()?)),
            6 => f64::from(i32::from_le_bytes(b.try_into().ok()?)),
            7 => u64::from_le_bytes(b.try_into().ok()?) as f64,
            8 => i64::from_le_bytes(b.try_into().ok()?) as f64,
            9 => f64::from(f32::from_le_bytes(b.try_into().ok()?)),
            10 => f64::from_le_bytes(b.try_into().ok()?),
            _ => return None,
        };
        Some(raw * self.scale + self.offset)
    }
}

/// The extra bytes of a file's records, as its descriptors place them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExtraDims {
    /// The attributes, in record order.
    pub dims: Vec<ExtraDim>,
    /// Bytes the descriptors describe (from the end of the standard fields).
    pub described: usize,
}

/// Bytes a value of `data_type` takes (`options` holds the count of undocumented bytes).
fn type_len(data_type: u8, options: u8) -> Option<usize> {
    let base = |t: u8| match t {
        1 | 2 => 1,
        3 | 4 => 2,
        5 | 6 | 9 => 4,
        _ => 8,
    };
    match data_type {
        0 => Some(usize::from(options)),
        1..=10 => Some(base(data_type)),
        11..=20 => Some(2 * base(data_type - 10)),
        21..=30 => Some(3 * base(data_type - 20)),
        _ => None,
    }
}

fn text(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).trim().to_string()
}

impl ExtraDims {
    /// Parses the payload of an extra bytes VLR for records of point format `format` and
    /// `record_len` bytes (`path` for messages).
    ///
    /// # Errors
    /// [`Error::Format`] when the payload is not whole descriptors, a type is unknown, or the
    /// attributes run past the record.
    pub fn of(path: &Path, payload: &[u8], format: u8, record_len: u16) -> Result<ExtraDims> {
        let bad = |m: String| Error::Format {
            path: path.to_path_buf(),
            message: format!("extra bytes VLR: {m}"),
        };
        if !payload.len().is_multiple_of(DESCRIPTOR_LEN) {
            return Err(bad(format!(
                "{} bytes are not whole descriptors of {DESCRIPTOR_LEN} bytes",
                payload.len()
            )));
        }
        let standard = usize::from(STANDARD_LEN[usize::from(format.min(10))]);
        let mut at = standard;
        let mut dims = Vec::new();
        for d in payload.chunks_exact(DESCRIPTOR_LEN) {
            let (data_type, options) = (d[2], d[3]);
            let name = text(&d[4..36]);
            let len = type_len(data_type, options).ok_or_else(|| {
                bad(format!(
                    "attribute {name:?} has unknown data type {data_type}"
                ))
            })?;
            let f = |k: usize| f64::from_le_bytes(d[k..k + 8].try_into().unwrap_or_default());
            let scale = if options & 8 != 0 && data_type != 0 {
                f(112)
            } else {
                1.0
            };
            let offset = if options & 16 != 0 && data_type != 0 {
                f(136)
            } else {
                0.0
            };
            dims.push(ExtraDim {
                name,
                start: at,
                data_type,
                len,
                scale,
                offset,
            });
            at += len;
        }
        if at > usize::from(record_len) {
            return Err(bad(format!(
                "the attributes need {at} bytes per record, but records have {record_len}"
            )));
        }
        Ok(ExtraDims {
            dims,
            described: at - standard,
        })
    }

    /// The attribute named `name` (exact, then ignoring case).
    pub fn find(&self, name: &str) -> Option<&ExtraDim> {
        self.dims
            .iter()
            .find(|d| d.name == name)
            .or_else(|| self.dims.iter().find(|d| d.name.eq_ignore_ascii_case(name)))
    }

    /// The names, for messages.
    pub fn names(&self) -> Vec<String> {
        self.dims.iter().map(|d| d.name.clone()).collect()
    }
}

/// The attribute `name` of the file `info` describes, placed in its records.
///
/// # Errors
/// [`Error::Format`] when the file has no such attribute (the message lists those it has), or
/// its extra bytes VLR is damaged; [`Error::Io`] when it cannot be read.
pub fn find_in_file(info: &super::FileInfo, name: &str) -> Result<ExtraDim> {
    let path = info.path.as_path();
    let mut f = crate::input::source::Source::open(path)?.reader();
    let header = las::Header::new(&mut f).map_err(|e| Error::Format {
        path: path.to_path_buf(),
        message: format!("invalid header: {}", super::header::las_message(&e)),
    })?;
    let dims = match header
        .vlrs()
        .iter()
        .find(|v| v.user_id == USER_ID && v.record_id == RECORD_ID)
    {
        Some(v) => ExtraDims::of(path, &v.data, info.point_format, info.record_length)?,
        None => ExtraDims::default(),
    };
    dims.find(name).cloned().ok_or_else(|| Error::Format {
        path: path.to_path_buf(),
        message: format!(
            "--z-from {name}: the file has no such extra-bytes attribute (it has: {}); \
             `sweeptin info` lists them",
            match dims.names() {
                n if n.is_empty() => "none".to_string(),
                n => n.join(", "),
            }
        ),
    })
}

/// A descriptor of an attribute stored as a double, named `name` (at most 32 bytes).
pub fn descriptor(name: &str, description: &str) -> [u8; DESCRIPTOR_LEN] {
    let mut d = [0u8; DESCRIPTOR_LEN];
    d[2] = DOUBLE;
    put_text(&mut d[4..36], name);
    put_text(&mut d[160..192], description);
    d
}

/// A descriptor of `len` undocumented bytes (data type 0).
pub fn undocumented(len: u8) -> [u8; DESCRIPTOR_LEN] {
    let mut d = [0u8; DESCRIPTOR_LEN];
    d[3] = len;
    d
}

fn put_text(dst: &mut [u8], s: &str) {
    let b = s.as_bytes();
    let n = b.len().min(dst.len());
    dst[..n].copy_from_slice(&b[..n]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptors_place_attributes_after_the_standard_fields() {
        let mut payload = Vec::new();
        payload.extend(undocumented(3));
        payload.extend(descriptor("HeightAboveGround", "height"));
        let dims = ExtraDims::of(Path::new("x"), &payload, 1, 28 + 11).unwrap();
        assert_eq!(dims.described, 11);
        let h = dims.find("heightaboveground").unwrap();
        assert_eq!((h.start, h.len, h.data_type), (31, 8, DOUBLE));
        let mut record = vec![0u8; 39];
        record[31..39].copy_from_slice(&1.25f64.to_le_bytes());
        assert_eq!(h.value(&record), Some(1.25));
        assert!(ExtraDims::of(Path::new("x"), &payload, 1, 30).is_err());
    }
}
