//! Writer of sweeptin's streaming mesh format (`.stin`); the format and its reader are in
//! [`crate::input::stin`].

use super::atomic::AtomicFile;
use super::mesh::{MeshMeta, SinkState};
use crate::error::Result;
use crate::input::stin::{
    MAGIC, RECORD, T_DONE, T_END, T_TRIANGLE, T_VERTEX, T_WATERMARK, VERSION,
};
use crate::sink::{MeshSink, MeshSummary};
use crate::validate::MeshKind;
use std::io::Write;
use std::path::Path;

fn record(tag: u32, a: [u8; 8], b: [u8; 8], c: [u8; 8]) -> [u8; RECORD] {
    let mut r = [0u8; RECORD];
    r[0..4].copy_from_slice(&tag.to_le_bytes());
    r[8..16].copy_from_slice(&a);
    r[16..24].copy_from_slice(&b);
    r[24..32].copy_from_slice(&c);
    r
}

/// A [`MeshSink`] writing the streaming mesh format.
#[derive(Debug)]
pub struct StinWriter {
    state: SinkState,
    out: Option<AtomicFile>,
    /// The header, until the first record: the kind declared goes into its flag word.
    head: Option<Vec<u8>>,
    kind: MeshKind,
}

impl StinWriter {
    /// Starts writing `path`.
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming `path` if the output cannot be created.
    pub fn create(path: &Path, meta: &MeshMeta) -> Result<Self> {
        let state = SinkState::new(path);
        let out = AtomicFile::create(path)?;
        let crs = meta.crs.clone().unwrap_or_default().into_bytes();
        let mut head = Vec::with_capacity(32 + crs.len() + RECORD);
        head.extend_from_slice(MAGIC);
        head.extend_from_slice(&VERSION.to_le_bytes());
        head.extend_from_slice(&(RECORD as u32).to_le_bytes());
        head.extend_from_slice(&(crs.len() as u32).to_le_bytes());
        // The flags (MeshKind::bits), set when the header is written.
        head.extend_from_slice(&0u32.to_le_bytes());
        head.extend_from_slice(&crs);
        head.resize(head.len().div_ceil(RECORD) * RECORD, 0);
        Ok(StinWriter {
            state,
            out: Some(out),
            head: Some(head),
            kind: MeshKind::default(),
        })
    }

    fn put(&mut self, r: &[u8; RECORD]) -> Result<()> {
        let Some(out) = self.out.as_mut() else {
            return Err(self.state.error("the mesh writer was already finished"));
        };
        if let Some(mut head) = self.head.take() {
            head[28..32].copy_from_slice(&self.kind.bits().to_le_bytes());
            out.write_all(&head).map_err(|e| self.state.io(e))?;
        }
        out.write_all(r).map_err(|e| self.state.io(e))
    }
}

impl MeshSink for StinWriter {
    fn declare(&mut self, kind: MeshKind) -> Result<()> {
        let kind = self.kind.union(kind);
        if self.head.is_none() && kind != self.kind {
            return Err(crate::Error::Internal(
                "a streaming mesh's kind was declared after its first record".into(),
            ));
        }
        self.kind = kind;
        Ok(())
    }

    fn vertex(&mut self, p: [f64; 3]) -> Result<()> {
        self.state.vertex(p)?;
        self.put(&record(
            T_VERTEX,
            p[0].to_le_bytes(),
            p[1].to_le_bytes(),
            p[2].to_le_bytes(),
        ))
    }

    fn triangle(&mut self, t: [u64; 3]) -> Result<()> {
        self.state.triangle(t, u64::MAX - 1)?;
        self.put(&record(
            T_TRIANGLE,
            t[0].to_le_bytes(),
            t[1].to_le_bytes(),
            t[2].to_le_bytes(),
        ))
    }

    fn vertex_done(&mut self, id: u64) -> Result<()> {
        self.put(&record(T_DONE, id.to_le_bytes(), [0; 8], [0; 8]))
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        self.put(&record(T_WATERMARK, y.to_le_bytes(), [0; 8], [0; 8]))
    }

    fn keeps_watermarks(&self) -> bool {
        true
    }

    fn finish(&mut self) -> Result<MeshSummary> {
        let end = record(
            T_END,
            self.state.vertices.to_le_bytes(),
            self.state.triangles.to_le_bytes(),
            [0; 8],
        );
        self.put(&end)?;
        self.state.finish()?;
        let Some(out) = self.out.take() else {
            return Err(self.state.error("the mesh writer was already finished"));
        };
        let bytes = out.commit()?;
        Ok(self.state.summary(bytes))
    }
}
