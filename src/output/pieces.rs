//! Mesh pieces (`.pieces`): a plan's `tin` task writes the tiles of its mesh as they come out of
//! the tiled engine, and `sweeptin merge` joins every task's pieces into one mesh.
//!
//! A piece is one tile's owned triangles, the vertices they use (and the owned vertices other
//! tiles' triangles use), and for each vertex its number of triangles in the whole mesh when the
//! tile owns it (`u32::MAX` otherwise): what the merge needs to number each vertex once and to
//! know when no later piece uses it (see [`crate::sink::MeshSink::piece`]).
//!
//! The file is `STPIECE1`, then for each piece four 64-bit words (tile x, tile y, vertices,
//! triangles), the vertices (`3 × f64` each), their degrees (`u32`), the triangles (`3 × u32`),
//! and at the end `STPIECE$` with the number of pieces, so that a cut file is refused. Numbers
//! are little-endian (the machines that run plans are). Written through an [`AtomicFile`].

use super::atomic::AtomicFile;
use crate::error::{Error, Result};
use crate::sink::{MeshSink, MeshSummary};
use std::fs::File;
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"STPIECE1";
const END: &[u8; 8] = b"STPIECE$";

/// Writes the pieces of a tiled run (a [`MeshSink`] that takes pieces only).
#[derive(Debug)]
pub struct PieceWriter {
    out: Option<AtomicFile>,
    path: PathBuf,
    pieces: u64,
    summary: MeshSummary,
}

impl PieceWriter {
    /// Starts writing `path`.
    ///
    /// # Errors
    /// As [`AtomicFile::create`].
    pub fn create(path: &Path) -> Result<Self> {
        let mut out = AtomicFile::create(path)?;
        out.write_all(MAGIC).map_err(|e| out.err(e))?;
        Ok(PieceWriter {
            out: Some(out),
            path: path.to_path_buf(),
            pieces: 0,
            summary: MeshSummary::default(),
        })
    }

    fn misuse(&self) -> Error {
        Error::Output {
            path: self.path.clone(),
            message: "a pieces file takes whole pieces of a tiled run, not numbered vertices"
                .into(),
        }
    }
}

fn words(w: [u64; 4]) -> [u8; 32] {
    let mut b = [0u8; 32];
    for (i, v) in w.iter().enumerate() {
        b[8 * i..8 * i + 8].copy_from_slice(&v.to_le_bytes());
    }
    b
}

impl MeshSink for PieceWriter {
    fn vertex(&mut self, _p: [f64; 3]) -> Result<()> {
        Err(self.misuse())
    }

    fn triangle(&mut self, _t: [u64; 3]) -> Result<()> {
        Err(self.misuse())
    }

    fn takes_pieces(&self) -> bool {
        true
    }

    fn piece(
        &mut self,
        tile: (i64, i64),
        vertices: &[[f64; 3]],
        degree: &[u32],
        triangles: &[[u32; 3]],
    ) -> Result<()> {
        let path = self.path.clone();
        let out = self.out.as_mut().ok_or_else(|| Error::Output {
            path,
            message: "written after finish".into(),
        })?;
        debug_assert_eq!(vertices.len(), degree.len());
        let head = words([
            tile.0 as u64,
            tile.1 as u64,
            vertices.len() as u64,
            triangles.len() as u64,
        ]);
        let r = out
            .write_all(&head)
            .and_then(|()| crate::sort::write_pieces(out, bytemuck::cast_slice(vertices)))
            .and_then(|()| crate::sort::write_pieces(out, bytemuck::cast_slice(degree)))
            .and_then(|()| crate::sort::write_pieces(out, bytemuck::cast_slice(triangles)));
        r.map_err(|e| out.err(e))?;
        self.pieces += 1;
        self.summary.vertices += vertices.len() as u64;
        self.summary.triangles += triangles.len() as u64;
        Ok(())
    }

    fn finish(&mut self) -> Result<MeshSummary> {
        let Some(mut out) = self.out.take() else {
            return Err(Error::Output {
                path: self.path.clone(),
                message: "finished twice".into(),
            });
        };
        out.write_all(END)
            .and_then(|()| out.write_all(&self.pieces.to_le_bytes()))
            .map_err(|e| out.err(e))?;
        self.summary.bytes = out.commit()?;
        Ok(self.summary)
    }
}

/// One piece read back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Piece {
    /// The tile (in the task's grid of tiles).
    pub tile: (i64, i64),
    /// Vertices `[x, y, z]`.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles of the whole mesh at each owned vertex, `u32::MAX` at the others.
    pub degree: Vec<u32>,
    /// Owned triangles, indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// Reads a pieces file front to back.
#[derive(Debug)]
pub struct PieceReader {
    r: BufReader<File>,
    path: PathBuf,
    read: u64,
}

impl PieceReader {
    /// Opens `path` and checks its first bytes.
    ///
    /// # Errors
    /// [`Error::Io`] if it cannot be read; [`Error::Format`] if it is not a pieces file.
    pub fn open(path: &Path) -> Result<Self> {
        let f = File::open(path).map_err(|e| Error::io(path, e))?;
        let mut r = PieceReader {
            r: BufReader::with_capacity(1 << 20, f),
            path: path.to_path_buf(),
            read: 0,
        };
        let mut m = [0u8; 8];
        r.exact(&mut m)?;
        if &m != MAGIC {
            return Err(r.bad("not a sweeptin pieces file"));
        }
        Ok(r)
    }

    fn bad(&self, message: &str) -> Error {
        Error::Format {
            path: self.path.clone(),
            message: message.into(),
        }
    }

    fn exact(&mut self, b: &mut [u8]) -> Result<()> {
        self.r.read_exact(b).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                self.bad("cut short (the task did not finish writing it)")
            } else {
                Error::io(&self.path, e)
            }
        })
    }

    fn records<T: bytemuck::Pod + Default>(&mut self, n: usize) -> Result<Vec<T>> {
        let mut v = vec![T::default(); n];
        self.exact(bytemuck::cast_slice_mut(&mut v))?;
        Ok(v)
    }

    /// The next piece, or `None` after the last one.
    ///
    /// # Errors
    /// [`Error::Format`] for a cut or damaged file.
    pub fn next_piece(&mut self) -> Result<Option<Piece>> {
        let mut tag = [0u8; 8];
        self.exact(&mut tag)?;
        if &tag == END {
            let mut n = [0u8; 8];
            self.exact(&mut n)?;
            if u64::from_le_bytes(n) != self.read {
                return Err(self.bad("its piece count does not match its pieces"));
            }
            return Ok(None);
        }
        let mut rest = [0u8; 24];
        self.exact(&mut rest)?;
        let word = |b: &[u8]| u64::from_le_bytes(b.try_into().expect("8 bytes"));
        let (tx, ty) = (word(&tag) as i64, word(&rest[..8]) as i64);
        let (nv, nt) = (word(&rest[8..16]), word(&rest[16..]));
        if nv > u64::from(u32::MAX) || nt > 2 * nv + 2 {
            return Err(self.bad("a piece's header is damaged"));
        }
        let vertices: Vec<[f64; 3]> = self.records(nv as usize)?;
        let degree: Vec<u32> = self.records(nv as usize)?;
        let triangles: Vec<[u32; 3]> = self.records(nt as usize)?;
        if triangles.iter().flatten().any(|&i| u64::from(i) >= nv)
            || vertices.iter().flatten().any(|c| !c.is_finite())
        {
            return Err(self.bad("a piece is damaged"));
        }
        self.read += 1;
        Ok(Some(Piece {
            tile: (tx, ty),
            vertices,
            degree,
            triangles,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_round_trip_and_a_cut_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.pieces");
        let mut w = PieceWriter::create(&path).unwrap();
        assert!(w.vertex([0.0; 3]).is_err());
        let v = [[0.0, 0.0, 1.0], [1.0, 0.0, 2.0], [0.0, 1.0, 3.0]];
        w.piece((-1, 2), &v, &[1, u32::MAX, 1], &[[0, 1, 2]])
            .unwrap();
        w.piece((0, 2), &[], &[], &[]).unwrap();
        let s = w.finish().unwrap();
        assert_eq!((s.vertices, s.triangles), (3, 1));
        let mut r = PieceReader::open(&path).unwrap();
        let p = r.next_piece().unwrap().unwrap();
        assert_eq!(p.tile, (-1, 2));
        assert_eq!(p.vertices, v.to_vec());
        assert_eq!(p.degree, vec![1, u32::MAX, 1]);
        assert_eq!(p.triangles, vec![[0, 1, 2]]);
        assert!(r.next_piece().unwrap().unwrap().vertices.is_empty());
        assert!(r.next_piece().unwrap().is_none());
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 20]).unwrap();
        let mut r = PieceReader::open(&path).unwrap();
        let e = r.next_piece().and_then(|_| r.next_piece()).unwrap_err();
        assert!(e.to_string().contains("cut short"), "{e}");
    }
}
