//! sweeptin's streaming mesh format (`.stin`), specified in `docs/FORMATS.md`.
//!
//! A header, then fixed-size 32-byte little-endian records in the order the streaming sweep
//! produced them: a vertex comes before the first triangle that uses it, and a *vertex done* record
//! after the last one, so a reader needs memory only for the vertices in use at a time — the
//! advancing front — never for the whole TIN. Watermark records carry the sweep's progress hint.
//! An end record with the counts closes the file, so a truncated file is detected.
//!
//! Header: `SWEEPTIN-STREAM\0` (16 bytes), version `u32` (1), record size `u32` (32), CRS length
//! `u32`, flags `u32` (what the mesh is, [`MeshKind::bits`]; 0 in files of earlier versions,
//! which is a Delaunay mesh of its vertices' hull), the CRS text (UTF-8, WKT or `EPSG:n`), zero padding to a multiple of
//! 32 bytes. Records: tag `u32`, reserved `u32`, then 24 bytes:
//!
//! | tag | record | payload |
//! |---|---|---|
//! | 1 | vertex (numbered 0, 1, … in order) | x, y, z: `f64` |
//! | 2 | triangle (counter-clockwise) | a, b, c: `u64` vertex numbers |
//! | 3 | vertex done | id: `u64`, 16 zero bytes |
//! | 4 | watermark | y: `f64`, 16 zero bytes |
//! | 5 | end | vertex count `u64`, triangle count `u64`, 8 zero bytes |

use crate::error::{Error, Result};
use crate::idmap::IdMap;
use crate::validate::MeshKind;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

/// File signature.
pub const MAGIC: &[u8; 16] = b"SWEEPTIN-STREAM\0";
/// Format version.
pub const VERSION: u32 = 1;
/// Size of every record.
pub const RECORD: usize = 32;

pub(crate) const T_VERTEX: u32 = 1;
pub(crate) const T_TRIANGLE: u32 = 2;
pub(crate) const T_DONE: u32 = 3;
pub(crate) const T_WATERMARK: u32 = 4;
pub(crate) const T_END: u32 = 5;

/// One event read back from a streaming mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StinEvent {
    /// A vertex (numbered in order of appearance).
    Vertex([f64; 3]),
    /// A triangle, with its vertices' coordinates resolved.
    Triangle {
        /// Vertex numbers.
        ids: [u64; 3],
        /// Their coordinates.
        points: [[f64; 3]; 3],
    },
    /// A vertex no later triangle uses.
    VertexDone(u64),
    /// Progress hint.
    Watermark(f64),
}

/// Reads a streaming mesh with memory for the live vertices only.
#[derive(Debug)]
pub struct StinReader {
    path: PathBuf,
    input: BufReader<std::fs::File>,
    crs: Option<String>,
    kind: MeshKind,
    live: IdMap<[f64; 3]>,
    vertices: u64,
    triangles: u64,
    record: u64,
    ended: bool,
}

impl StinReader {
    /// Opens `path` and reads its header.
    ///
    /// # Errors
    /// [`Error::Io`] if it cannot be read, [`Error::Format`] if it is not a streaming mesh.
    pub fn open(path: &Path) -> Result<Self> {
        let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let mut input = BufReader::with_capacity(1 << 20, f);
        let bad = |m: String| Error::Format {
            path: path.to_path_buf(),
            message: m,
        };
        let mut head = [0u8; 32];
        input.read_exact(&mut head).map_err(|_| {
            bad("not a sweeptin streaming mesh: file shorter than the header".into())
        })?;
        if &head[..16] != MAGIC {
            return Err(bad("not a sweeptin streaming mesh: wrong signature".into()));
        }
        let word = |i: usize| u32::from_le_bytes(head[i..i + 4].try_into().expect("4 bytes"));
        if word(16) != VERSION || word(20) as usize != RECORD {
            return Err(bad(format!(
                "unsupported streaming mesh version {} / record size {}",
                word(16),
                word(20)
            )));
        }
        let kind = MeshKind::from_bits(word(28)).map_err(|b| {
            bad(format!(
                "header flags {b:#x} unknown (a later version's file, or damage)"
            ))
        })?;
        let crs_len = word(24) as usize;
        if crs_len > 1 << 20 {
            return Err(bad(format!("CRS length {crs_len} is not plausible")));
        }
        let mut crs = vec![0u8; (32 + crs_len).div_ceil(RECORD) * RECORD - 32];
        input
            .read_exact(&mut crs)
            .map_err(|_| bad("truncated in the header's CRS".into()))?;
        crs.truncate(crs_len);
        let crs = String::from_utf8(crs).map_err(|_| bad("CRS is not UTF-8".into()))?;
        Ok(StinReader {
            path: path.to_path_buf(),
            input,
            crs: (!crs.is_empty()).then_some(crs),
            kind,
            live: IdMap::default(),
            vertices: 0,
            triangles: 0,
            record: 0,
            ended: false,
        })
    }

    /// The CRS recorded in the header.
    pub fn crs(&self) -> Option<&str> {
        self.crs.as_deref()
    }

    /// What the mesh is, from the header's flags ([`MeshKind`]).
    pub fn kind(&self) -> MeshKind {
        self.kind
    }

    /// Vertices currently held (not yet released).
    pub fn live_vertices(&self) -> usize {
        self.live.len()
    }

    fn bad(&self, m: impl std::fmt::Display) -> Error {
        Error::Format {
            path: self.path.clone(),
            message: format!("record {}: {m}", self.record),
        }
    }

    /// The next event, or `None` after the end record.
    ///
    /// # Errors
    /// [`Error::Format`] naming the record for a truncated or inconsistent file.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Result<Option<StinEvent>> {
        if self.ended {
            return Ok(None);
        }
        let mut r = [0u8; RECORD];
        if self.input.read_exact(&mut r).is_err() {
            return Err(self.bad("file ends without its end record (truncated)"));
        }
        let tag = u32::from_le_bytes(r[0..4].try_into().expect("4 bytes"));
        let u = |i: usize| u64::from_le_bytes(r[i..i + 8].try_into().expect("8 bytes"));
        let f = |i: usize| f64::from_le_bytes(r[i..i + 8].try_into().expect("8 bytes"));
        let ev = match tag {
            T_VERTEX => {
                let p = [f(8), f(16), f(24)];
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(self.bad("vertex has a non-finite coordinate"));
                }
                self.live.insert(self.vertices, p);
                self.vertices += 1;
                StinEvent::Vertex(p)
            }
            T_TRIANGLE => {
                let ids = [u(8), u(16), u(24)];
                let mut points = [[0.0; 3]; 3];
                for k in 0..3 {
                    points[k] = match self.live.get(&ids[k]) {
                        Some(p) => *p,
                        None => {
                            return Err(self.bad(format!(
                                "triangle refers to vertex {} which is not live",
                                ids[k]
                            )));
                        }
                    };
                }
                self.triangles += 1;
                StinEvent::Triangle { ids, points }
            }
            T_DONE => {
                let id = u(8);
                if self.live.remove(&id).is_none() {
                    return Err(self.bad(format!("vertex {id} released but not live")));
                }
                StinEvent::VertexDone(id)
            }
            T_WATERMARK => StinEvent::Watermark(f(8)),
            T_END => {
                if u(8) != self.vertices || u(16) != self.triangles {
                    return Err(self.bad(format!(
                        "end record counts {} vertices / {} triangles, file has {} / {}",
                        u(8),
                        u(16),
                        self.vertices,
                        self.triangles
                    )));
                }
                self.ended = true;
                return Ok(None);
            }
            t => return Err(self.bad(format!("unknown record tag {t}"))),
        };
        self.record += 1;
        Ok(Some(ev))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{MeshMeta, StinWriter};
    use crate::sink::MeshSink;

    #[test]
    fn round_trip_and_truncation() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.stin");
        let meta = MeshMeta {
            crs: Some("EPSG:2154".into()),
            comments: vec![],
        };
        let mut w = StinWriter::create(&path, &meta).unwrap();
        let kind = MeshKind {
            trimmed: true,
            not_delaunay: true,
            ..MeshKind::default()
        };
        w.declare(kind).unwrap();
        w.declare(MeshKind::default()).unwrap();
        w.vertex([0., 0., 1.]).unwrap();
        // Once records are written, the kind can no longer change.
        assert!(w.declare(kind).is_ok());
        assert!(
            w.declare(MeshKind {
                constrained: true,
                ..kind
            })
            .is_err()
        );
        w.vertex([1., 0., 2.]).unwrap();
        w.vertex([0., 1., 3.]).unwrap();
        w.triangle([0, 1, 2]).unwrap();
        w.vertex_done(1).unwrap();
        w.watermark(0.5).unwrap();
        w.finish().unwrap();
        let mut r = StinReader::open(&path).unwrap();
        assert_eq!(r.crs(), Some("EPSG:2154"));
        assert_eq!(r.kind(), kind);
        let mut evs = Vec::new();
        while let Some(e) = r.next().unwrap() {
            evs.push(e);
        }
        assert_eq!(evs.len(), 6);
        assert_eq!(
            evs[3],
            StinEvent::Triangle {
                ids: [0, 1, 2],
                points: [[0., 0., 1.], [1., 0., 2.], [0., 1., 3.]]
            }
        );
        assert_eq!(r.live_vertices(), 2);
        // Cut the end record off: detected.
        let bytes = std::fs::read(&path).unwrap();
        let cut = dir.path().join("cut.stin");
        std::fs::write(&cut, &bytes[..bytes.len() - 32]).unwrap();
        let mut r = StinReader::open(&cut).unwrap();
        let err = loop {
            match r.next() {
                Ok(Some(_)) => continue,
                Ok(None) => panic!("truncation not detected"),
                Err(e) => break e,
            }
        };
        assert!(err.to_string().contains("truncated"), "{err}");
    }
}
