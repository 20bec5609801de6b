//! Streaming Wavefront OBJ writer.
//!
//! `v x y z` lines with shortest round-trip decimals (Rust's `{}` for `f64`: parsing the text
//! gives back the same bits), `f i j k` lines with 1-based indices. OBJ allows vertices and faces
//! to interleave as long as a face only refers to earlier vertices, so nothing is spooled.
//! The metadata goes into `#` comment lines at the top.

use super::atomic::AtomicFile;
use super::mesh::{MeshMeta, SinkState};
use crate::error::Result;
use crate::sink::{MeshSink, MeshSummary};
use std::io::Write;
use std::path::Path;

/// A [`MeshSink`] writing Wavefront OBJ.
#[derive(Debug)]
pub struct ObjWriter {
    state: SinkState,
    out: Option<AtomicFile>,
    line: Vec<u8>,
}

impl ObjWriter {
    /// Starts writing `path`.
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming `path` if the output cannot be created.
    pub fn create(path: &Path, meta: &MeshMeta) -> Result<Self> {
        let state = SinkState::new(path);
        let mut out = AtomicFile::create(path)?;
        let mut head = String::new();
        for c in meta.comment_lines() {
            head.push_str("# ");
            head.push_str(&c);
            head.push('\n');
        }
        out.write_all(head.as_bytes()).map_err(|e| state.io(e))?;
        Ok(ObjWriter {
            state,
            out: Some(out),
            line: Vec::with_capacity(128),
        })
    }

    fn write_line(&mut self) -> Result<()> {
        match self.out.as_mut() {
            Some(out) => out.write_all(&self.line).map_err(|e| self.state.io(e)),
            None => Err(self.state.error("the mesh writer was already finished")),
        }
    }
}

impl MeshSink for ObjWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<()> {
        self.state.vertex(p)?;
        self.line.clear();
        // Writing into a Vec cannot fail.
        let _ = writeln!(self.line, "v {} {} {}", p[0], p[1], p[2]);
        self.write_line()
    }

    fn triangle(&mut self, t: [u64; 3]) -> Result<()> {
        self.state.triangle(t, u64::MAX - 1)?;
        self.line.clear();
        self.line.push(b'f');
        let mut digits = itoa::Buffer::new();
        for i in t {
            self.line.push(b' ');
            self.line.extend_from_slice(digits.format(i + 1).as_bytes());
        }
        self.line.push(b'\n');
        self.write_line()
    }

    fn finish(&mut self) -> Result<MeshSummary> {
        self.state.finish()?;
        let Some(out) = self.out.take() else {
            return Err(self.state.error("the mesh writer was already finished"));
        };
        let bytes = out.commit()?;
        Ok(self.state.summary(bytes))
    }
}
