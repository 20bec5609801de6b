//! Mesh pieces (`.pieces`): a plan's `tin` task writes the tiles of its mesh as they come out of
//! the tiled engine, and `sweeptin merge` joins every task's pieces into one mesh.
//!
//! A piece is one tile's owned triangles, the vertices they use (and the owned vertices other
//! tiles' triangles use), and for each vertex its number of triangles in the whole mesh when the
//! tile owns it (`u32::MAX` otherwise): what the merge needs to number each vertex once and to
//! know when no later piece uses it (see [`crate::sink::MeshSink::piece`]).
//!
//! The file is `STPIECE2`, then for each piece four 64-bit words (tile x, tile y, vertices,
//! triangles), the vertices (`3 × f64` each), their degrees (`u32`), the triangles (`3 × u32`)
//! and a 64-bit checksum of all these (`Checksum`), and at the end `STPIECE$` with the number
//! of pieces, so that a cut file is refused. A piece is checked before it is handed on: a
//! damaged file is an input's error naming it (bit flips merged into a different mesh with
//! exit 0, or failed as an internal error), and counts larger than the bytes left are refused
//! before anything is allocated. Numbers are little-endian (the machines that run plans are).
//! Written through an [`AtomicFile`]. (`STPIECE1`, without checksums, is refused: its task runs
//! again.)

use super::atomic::AtomicFile;
use crate::error::{Error, Result};
use crate::sink::{MeshSink, MeshSummary};
use std::fs::File;
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"STPIECE2";
const OLD_MAGIC: &[u8; 8] = b"STPIECE1";
const END: &[u8; 8] = b"STPIECE$";
/// Bytes of one vertex (position and degree), of one triangle, of a checksum.
const VERTEX: u64 = 24 + 4;
const TRIANGLE: u64 = 12;
const SUM: u64 = 8;

/// A piece's checksum: each 8-byte word (the last one of a slice padded with zeros) mixed into
/// the state by an exclusive or, a multiplication by an odd constant and a rotation, each a
/// bijection of the state, so a change within one word always changes the sum, and any other
/// change does but with a chance of 2⁻⁶⁴. It finds damage on disk, not forgeries.
#[derive(Clone, Copy, Debug)]
struct Checksum(u64);

impl Checksum {
    fn new() -> Self {
        Checksum(0x243F_6A88_85A3_08D3)
    }

    fn add(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..c.len()].copy_from_slice(c);
            self.0 = ((self.0 ^ u64::from_le_bytes(w)).wrapping_mul(0x9E37_79B9_7F4A_7C15))
                .rotate_left(29);
        }
    }

    fn value(self) -> u64 {
        self.0
    }
}

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
        let parts: [&[u8]; 4] = [
            &head,
            bytemuck::cast_slice(vertices),
            bytemuck::cast_slice(degree),
            bytemuck::cast_slice(triangles),
        ];
        let mut sum = Checksum::new();
        for part in parts {
            sum.add(part);
            crate::sort::write_pieces(out, part).map_err(|e| out.err(e))?;
        }
        out.write_all(&sum.value().to_le_bytes())
            .map_err(|e| out.err(e))?;
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
    /// Bytes not read yet.
    left: u64,
}

impl PieceReader {
    /// Opens `path` and checks its first bytes.
    ///
    /// # Errors
    /// [`Error::Io`] if it cannot be read; [`Error::Format`] if it is not a pieces file.
    pub fn open(path: &Path) -> Result<Self> {
        let f = File::open(path).map_err(|e| Error::io(path, e))?;
        let left = f.metadata().map_err(|e| Error::io(path, e))?.len();
        let mut r = PieceReader {
            r: BufReader::with_capacity(1 << 20, f),
            path: path.to_path_buf(),
            read: 0,
            left,
        };
        let mut m = [0u8; 8];
        r.exact(&mut m)?;
        if &m == OLD_MAGIC {
            return Err(r.bad("a pieces file of an older sweeptin, without checksums"));
        }
        if &m != MAGIC {
            return Err(r.bad("not a sweeptin pieces file (or its first bytes are damaged)"));
        }
        Ok(r)
    }

    /// Piece [`PieceReader::read`] does not hold what its task wrote.
    fn damaged(&self) -> Error {
        self.bad(&format!(
            "piece {} is damaged (its checksum or counts do not hold): the file changed after \
             its task wrote it",
            self.read + 1
        ))
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
        })?;
        self.left = self.left.saturating_sub(b.len() as u64);
        Ok(())
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
        // Counts are checked against the bytes left before anything is allocated.
        let need = nv
            .checked_mul(VERTEX)
            .and_then(|v| v.checked_add(nt.checked_mul(TRIANGLE)?))
            .and_then(|b| b.checked_add(SUM));
        if nv > u64::from(u32::MAX) || nt > 2 * nv + 2 {
            return Err(self.damaged());
        }
        if need.is_none_or(|b| b > self.left) {
            return Err(self.bad(&format!(
                "cut short (the task did not finish writing it), or the counts of piece {} are \
                 damaged",
                self.read + 1
            )));
        }
        let vertices: Vec<[f64; 3]> = self.records(nv as usize)?;
        let degree: Vec<u32> = self.records(nv as usize)?;
        let triangles: Vec<[u32; 3]> = self.records(nt as usize)?;
        let mut sum = Checksum::new();
        sum.add(&tag);
        sum.add(&rest);
        sum.add(bytemuck::cast_slice(&vertices));
        sum.add(bytemuck::cast_slice(&degree));
        sum.add(bytemuck::cast_slice(&triangles));
        let mut stored = [0u8; 8];
        self.exact(&mut stored)?;
        if u64::from_le_bytes(stored) != sum.value()
            || triangles.iter().flatten().any(|&i| u64::from(i) >= nv)
            || vertices.iter().flatten().any(|c| !c.is_finite())
        {
            return Err(self.damaged());
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

    fn read_all(path: &Path) -> Result<Vec<Piece>> {
        let mut r = PieceReader::open(path)?;
        let mut all = Vec::new();
        while let Some(p) = r.next_piece()? {
            all.push(p);
        }
        Ok(all)
    }

    #[test]
    fn every_flipped_bit_of_a_pieces_file_is_found() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.pieces");
        let mut w = PieceWriter::create(&path).unwrap();
        let v = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 2.0],
            [0.0, 1.0, 3.0],
            [1.0, 1.0, 4.0],
        ];
        w.piece((3, -2), &v, &[2, u32::MAX, 2, 1], &[[0, 1, 2], [1, 3, 2]])
            .unwrap();
        w.piece((4, -2), &v[..3], &[1, 1, 1], &[[0, 1, 2]]).unwrap();
        w.finish().unwrap();
        let good = std::fs::read(&path).unwrap();
        assert_eq!(read_all(&path).unwrap().len(), 2);
        for bit in 0..8 * good.len() {
            let mut b = good.clone();
            b[bit / 8] ^= 1 << (bit % 8);
            std::fs::write(&path, &b).unwrap();
            match read_all(&path) {
                Err(Error::Format { .. }) => {}
                other => panic!("bit {bit}: {other:?}"),
            }
        }
        // Counts beyond the bytes left are refused before anything is allocated.
        let mut b = good.clone();
        b[24..32].copy_from_slice(&u64::from(u32::MAX).to_le_bytes());
        b[32..40].copy_from_slice(&0u64.to_le_bytes());
        std::fs::write(&path, &b).unwrap();
        let e = read_all(&path).unwrap_err();
        assert!(e.to_string().contains("counts of piece 1"), "{e}");
        // A file of the format without checksums says so.
        let mut b = good;
        b[..8].copy_from_slice(OLD_MAGIC);
        std::fs::write(&path, &b).unwrap();
        let e = read_all(&path).unwrap_err();
        assert!(e.to_string().contains("older sweeptin"), "{e}");
    }
}
