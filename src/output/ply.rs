//! Streaming binary little-endian PLY writer.
//!
//! PLY wants both counts in the header and all vertices before all faces, while a streaming
//! triangulation interleaves them. So the writer
//! 1. writes a header with placeholder counts, padded by a `comment` line so that the header has
//!    the same length whatever the final counts are (up to 20 digits each);
//! 2. writes vertices straight after it, into the output's temporary file;
//! 3. spools faces, already encoded, to an anonymous temporary file;
//! 4. at [`finish`](MeshSink::finish), rewrites the header in place with the true counts and
//!    appends the spooled faces; then commits the [`AtomicFile`].
//!
//! A stream (a FIFO, a device, standard output) cannot be rewritten in place: the vertices are
//! then spooled too, and the whole file is written at the end.
//!
//! Memory use is two (three) I/O buffers, whatever the mesh size.
//!
//! Layout: `element vertex N` with `property double x`, `y`, `z`; `element face M` with
//! `property list uchar uint vertex_indices`.

use super::atomic::AtomicFile;
use super::mesh::{MeshMeta, SinkState, SpooledOutput, rewind_spool};
use crate::error::Result;
use crate::sink::{MeshSink, MeshSummary};
use crate::validate::MeshKind;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::Path;

/// Width reserved for the two counts together, in decimal digits (20 digits each fits any `u64`).
const COUNT_DIGITS: usize = 40;

/// Bytes of one encoded face: the count `3u8` and three little-endian `u32`s.
const FACE_BYTES: usize = 13;

/// A [`MeshSink`] writing binary little-endian PLY.
#[derive(Debug)]
pub struct PlyWriter {
    state: SinkState,
    comments: Vec<String>,
    /// What the producer declared (the `comment sweeptin: …` line).
    kind: MeshKind,
    out: Option<AtomicFile>,
    faces: Option<BufWriter<File>>,
    /// Spooled vertices, when the output is a stream.
    vertices: Option<BufWriter<File>>,
    header_len: usize,
}

impl PlyWriter {
    /// Starts writing `path`; faces are spooled to the output's directory.
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming `path` if the output or the spool file cannot be created.
    pub fn create(path: &Path, meta: &MeshMeta) -> Result<Self> {
        Self::create_with_spool_dir(path, meta, &super::target::scratch_dir(path))
    }

    /// Like [`create`](Self::create), with the face spool file in `spool_dir`.
    ///
    /// # Errors
    /// [`crate::Error::Write`] if the output or the spool file cannot be created.
    pub fn create_with_spool_dir(path: &Path, meta: &MeshMeta, spool_dir: &Path) -> Result<Self> {
        let SpooledOutput {
            state,
            mut out,
            faces,
        } = SpooledOutput::create(path, spool_dir)?;
        let comments = meta.comment_lines();
        let header = header(&comments, MeshKind::default(), 0, 0);
        let vertices = if out.is_stream() {
            let spool = tempfile::tempfile_in(spool_dir).map_err(|e| state.io(e))?;
            Some(BufWriter::with_capacity(crate::sort::WRITE_PIECE, spool))
        } else {
            out.write_all(header.as_bytes()).map_err(|e| state.io(e))?;
            None
        };
        Ok(PlyWriter {
            state,
            comments,
            kind: MeshKind::default(),
            out: Some(out),
            faces: Some(faces),
            vertices,
            header_len: header.len(),
        })
    }

    fn finish_inner(&mut self) -> Result<MeshSummary> {
        self.state.finish()?;
        let (Some(mut out), Some(faces)) = (self.out.take(), self.faces.take()) else {
            return Err(self.state.error("the mesh writer was already finished"));
        };
        let mut spool = rewind_spool(&self.state, faces)?;
        let io = |e| self.state.io(e);
        let header = header(
            &self.comments,
            self.kind,
            self.state.vertices,
            self.state.triangles,
        );
        if header.len() != self.header_len {
            return Err(crate::Error::Internal(format!(
                "PLY header changed length ({} -> {} bytes)",
                self.header_len,
                header.len()
            )));
        }
        match self.vertices.take() {
            Some(vertices) => {
                // A stream: header, vertices, faces, in order.
                let mut vertices = rewind_spool(&self.state, vertices)?;
                out.write_all(header.as_bytes()).map_err(io)?;
                std::io::copy(&mut vertices, &mut out).map_err(io)?;
            }
            None => {
                out.seek(SeekFrom::Start(0)).map_err(io)?;
                out.write_all(header.as_bytes()).map_err(io)?;
                out.seek(SeekFrom::End(0)).map_err(io)?;
            }
        }
        let copied = std::io::copy(&mut spool, &mut out).map_err(io)?;
        if copied != self.state.triangles * FACE_BYTES as u64 {
            return Err(crate::Error::Internal(format!(
                "PLY face spool holds {copied} bytes for {} faces",
                self.state.triangles
            )));
        }
        let bytes = out.commit()?;
        Ok(self.state.summary(bytes))
    }
}

/// `text` in ASCII, as a PLY header must be (readers such as Python's `plyfile` decode it as
/// ASCII, and failed on `°`): a few signs spelled out (`°` → ` deg`, `×` → `x`, `²` → `2`…),
/// any other non-ASCII character as `<U+00E9>`, control characters as spaces.
pub(crate) fn ascii_comment(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            ' '..='~' => out.push(c),
            '°' => out.push_str(" deg"),
            '×' => out.push('x'),
            '²' => out.push('2'),
            '³' => out.push('3'),
            'µ' => out.push('u'),
            '–' | '—' | '−' => out.push('-'),
            '‘' | '’' => out.push('\''),
            '“' | '”' => out.push('"'),
            '…' => out.push_str("..."),
            c if c.is_control() => out.push(' '),
            c => out.push_str(&format!("<U+{:04X}>", u32::from(c))),
        }
    }
    out
}

/// The comment line that says what the mesh is ([`MeshKind`]): `sweeptin: ` and its words,
/// padded to a fixed width (the header is rewritten with the kind declared, at the same length).
pub(crate) const KIND_PREFIX: &str = "sweeptin:";

/// The header (ASCII: every comment through [`ascii_comment`]); its length depends neither on
/// the counts nor on the kind.
fn header(comments: &[String], kind: MeshKind, vertices: u64, faces: u64) -> String {
    let mut h = String::from("ply\nformat binary_little_endian 1.0\n");
    for c in comments {
        h.push_str("comment ");
        h.push_str(&ascii_comment(c));
        h.push('\n');
    }
    h.push_str(&format!(
        "comment {KIND_PREFIX} {:<w$}\n",
        kind.words(),
        w = MeshKind::MAX_WORDS
    ));
    let (v, f) = (vertices.to_string(), faces.to_string());
    // Trailing spaces in a comment line keep the header length fixed; readers ignore comments.
    h.push_str("comment");
    h.push_str(&" ".repeat(COUNT_DIGITS - v.len() - f.len()));
    h.push('\n');
    h.push_str(&format!(
        "element vertex {v}\nproperty double x\nproperty double y\nproperty double z\n\
         element face {f}\nproperty list uchar uint vertex_indices\nend_header\n"
    ));
    h
}

impl MeshSink for PlyWriter {
    fn declare(&mut self, kind: MeshKind) -> Result<()> {
        self.kind = self.kind.union(kind);
        Ok(())
    }

    fn vertex(&mut self, p: [f64; 3]) -> Result<()> {
        self.state.vertex(p)?;
        let mut rec = [0u8; 24];
        for (chunk, c) in rec.chunks_exact_mut(8).zip(p) {
            chunk.copy_from_slice(&c.to_le_bytes());
        }
        match self.out.as_mut() {
            Some(out) => match self.vertices.as_mut() {
                Some(spool) => spool.write_all(&rec).map_err(|e| self.state.io(e)),
                None => out.write_all(&rec).map_err(|e| self.state.io(e)),
            },
            None => Err(self.state.error("the mesh writer was already finished")),
        }
    }

    fn triangle(&mut self, t: [u64; 3]) -> Result<()> {
        self.state.triangle(t, u64::from(u32::MAX))?;
        let mut rec = [3u8; FACE_BYTES];
        for (chunk, i) in rec[1..].chunks_exact_mut(4).zip(t) {
            chunk.copy_from_slice(&(i as u32).to_le_bytes());
        }
        self.state.put(self.faces.as_mut(), &rec)
    }

    fn finish(&mut self) -> Result<MeshSummary> {
        let result = self.finish_inner();
        // On error, drop the outputs now so the temporary files go away at once.
        self.out = None;
        self.faces = None;
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_length_is_fixed() {
        let c = vec!["generated by test".to_string()];
        let n = header(&c, MeshKind::default(), 0, 0).len();
        assert_eq!(header(&c, MeshKind::default(), 123, 4567).len(), n);
        assert_eq!(header(&c, MeshKind::default(), u64::MAX, u64::MAX).len(), n);
        assert!(header(&c, MeshKind::default(), 5, 6).contains("element vertex 5\n"));
        assert!(header(&c, MeshKind::default(), 5, 6).contains("element face 6\n"));
    }

    /// Issue 41, item 13: `refine` wrote "°" in a comment and `plyfile` raised
    /// UnicodeDecodeError. Every comment (the CRS's WKT, file names) is written in ASCII.
    #[test]
    fn the_header_is_ascii_whatever_the_comments() {
        let c = vec![
            "quality mesh (min angle 30°) of /data/Réseau/tile – 2×2.laz".to_string(),
            "crs GEOGCS[\"Nouvelle Triangulation Française\"]\u{7}".to_string(),
        ];
        let h = header(&c, MeshKind::default(), 1, 2);
        assert!(h.is_ascii(), "{h}");
        assert!(
            h.contains("min angle 30 deg) of /data/R<U+00E9>seau/tile - 2x2.laz\n"),
            "{h}"
        );
        assert!(h.contains("Fran<U+00E7>aise\"] \n"), "{h}");
        assert_eq!(header(&c, MeshKind::default(), u64::MAX, 0).len(), h.len());
        // The kind's line: fixed width whatever it says.
        let all = MeshKind {
            constrained: true,
            trimmed: true,
            not_delaunay: true,
        };
        assert_eq!(all.words().len(), MeshKind::MAX_WORDS);
        let k = header(&c, all, 1, 2);
        assert_eq!(k.len(), h.len());
        assert!(
            k.contains("comment sweeptin: constrained trimmed not-delaunay\n"),
            "{k}"
        );
        assert!(h.contains(&format!("comment sweeptin: delaunay{}\n", " ".repeat(24))));
    }
}
