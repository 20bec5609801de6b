//! Streaming SMS 2DM mesh writer (Aquaveo SMS's ASCII 2-D mesh: what HEC-RAS, TELEMAC's
//! converters, TUFLOW FV, BASEMENT and QGIS's MDAL read).
//!
//! ```text
//! MESH2D
//! MESHNAME "reach"
//! ND 1 x y z
//! …
//! E3T 1 n1 n2 n3 1
//! …
//! ```
//!
//! Node and element ids are 1-based; an element lists its nodes counter-clockwise (as given to
//! [`MeshSink::triangle`]) with material 1. Coordinates are written in the shortest form that
//! reads back to the same double. The format has no place for a CRS or comments (tools take the
//! CRS from the project), so [`MeshMeta`] is not recorded. Nodes come first and elements after
//! them, so elements are spooled (24 bytes each) to an anonymous temporary file and appended at
//! [`finish`](MeshSink::finish); memory use is bounded by the I/O buffers.

use super::atomic::AtomicFile;
use super::mesh::{
    MeshMeta, SinkState, SpooledOutput, face_record, read_face_record, rewind_spool,
};
use crate::error::Result;
use crate::sink::{MeshSink, MeshSummary};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// A [`MeshSink`] writing an SMS 2DM mesh.
#[derive(Debug)]
pub struct Sms2dmWriter {
    state: SinkState,
    out: Option<AtomicFile>,
    faces: Option<BufWriter<File>>,
    line: Vec<u8>,
}

impl Sms2dmWriter {
    /// Starts writing `path` (the mesh is named after the file stem); elements are spooled to
    /// the output's directory.
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming `path` if the output or the spool file cannot be created.
    pub fn create(path: &Path, _meta: &MeshMeta) -> Result<Self> {
        let SpooledOutput {
            state,
            mut out,
            faces,
        } = SpooledOutput::create(path, &super::target::scratch_dir(path))?;
        let name: String = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "mesh".into())
            .chars()
            .map(|c| if c == '"' || c.is_control() { '_' } else { c })
            .collect();
        out.write_all(format!("MESH2D\nMESHNAME \"{name}\"\n").as_bytes())
            .map_err(|e| state.io(e))?;
        Ok(Sms2dmWriter {
            state,
            out: Some(out),
            faces: Some(faces),
            line: Vec::with_capacity(96),
        })
    }

    fn finish_inner(&mut self) -> Result<MeshSummary> {
        self.state.finish()?;
        let (Some(mut out), Some(faces)) = (self.out.take(), self.faces.take()) else {
            return Err(self.state.error("the mesh writer was already finished"));
        };
        let mut reader = rewind_spool(&self.state, faces)?;
        let io = |e| self.state.io(e);
        let mut digits = itoa::Buffer::new();
        for i in 0..self.state.triangles {
            let face = read_face_record(&mut reader).map_err(io)?;
            self.line.clear();
            self.line.extend_from_slice(b"E3T ");
            self.line.extend_from_slice(digits.format(i + 1).as_bytes());
            for v in face {
                self.line.push(b' ');
                self.line.extend_from_slice(digits.format(v + 1).as_bytes());
            }
            self.line.extend_from_slice(b" 1\n");
            out.write_all(&self.line).map_err(io)?;
        }
        let bytes = out.commit()?;
        Ok(self.state.summary(bytes))
    }
}

impl MeshSink for Sms2dmWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<()> {
        self.state.vertex(p)?;
        self.line.clear();
        // Writing into a Vec cannot fail.
        let _ = writeln!(
            self.line,
            "ND {} {} {} {}",
            self.state.vertices, p[0], p[1], p[2]
        );
        self.state.put(self.out.as_mut(), &self.line)
    }

    fn triangle(&mut self, t: [u64; 3]) -> Result<()> {
        self.state.triangle(t, u64::MAX - 1)?;
        self.state.put(self.faces.as_mut(), &face_record(t))
    }

    fn finish(&mut self) -> Result<MeshSummary> {
        let result = self.finish_inner();
        self.out = None;
        self.faces = None;
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_then_elements() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("reach.2dm");
        let mut w = Sms2dmWriter::create(&path, &MeshMeta::default()).unwrap();
        w.vertex([0.0, 0.0, 1.5]).unwrap();
        w.vertex([1.0, 0.0, 2.0]).unwrap();
        w.triangle([0, 1, 2]).unwrap_err();
        w.vertex([0.0, 1.0, 770530.15]).unwrap();
        w.triangle([0, 1, 2]).unwrap();
        let s = w.finish().unwrap();
        assert_eq!((s.vertices, s.triangles), (3, 1));
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "MESH2D\nMESHNAME \"reach\"\nND 1 0 0 1.5\nND 2 1 0 2\nND 3 0 1 770530.15\n\
             E3T 1 1 2 3 1\n"
        );
        assert_eq!(s.bytes, text.len() as u64);
    }
}
