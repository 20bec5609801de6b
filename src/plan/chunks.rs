//! The chunk indexes of a plan's plain LAZ/LAS files ([`ChunkIndex`]), built once when the plan
//! is saved and read by every task: `DIR/index/<k>.chunks` for the plan's file `k`.
//!
//! A file holds a magic string, the input file's [`FileStamp`] when the index was built, the
//! spans (byte offset, bytes, points, first point, box) and the SHA-256 of all that: a task
//! refuses an index that is truncated, edited, or of the file as it was before a rewrite (the
//! plan's stamp ties the file, and so its index, to the plan).

use super::files::{FileStamp, own_file, write_atomic};
use super::{Plan, bad};
use crate::error::{Error, Result};
use crate::input::las::chunks::SpanBox;
use crate::input::las::{ChunkIndex, FileInfo};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

const MAGIC: &[u8; 8] = b"STCHUNK1";
const HEAD: usize = 8 + 24 + 8;
const SPAN: usize = 64;
const SUM: usize = 32;

/// The chunk indexes a task reads with, by input path.
pub(super) type TaskChunks = Vec<(PathBuf, Arc<ChunkIndex>)>;

impl Plan {
    /// Where the chunk index of the plan's file `k` lies under `dir`.
    pub fn chunk_index_path(dir: &Path, k: usize) -> PathBuf {
        dir.join("index").join(format!("{k}.chunks"))
    }

    /// Builds and writes (atomically) the chunk index of every plain LAZ/LAS file of the plan
    /// ([`super::PlanFile::indexed`]) that `dir` does not hold yet: one decoding pass over each,
    /// the files side by side and each file's chunks on every core.
    ///
    /// # Errors
    /// The decoder's errors naming the input; [`Error::Io`] naming the index.
    pub(super) fn write_chunk_indexes(&self, dir: &Path) -> Result<()> {
        let wanted: Vec<usize> = (0..self.files.len())
            .filter(|&k| self.files[k].indexed)
            .collect();
        if wanted.is_empty() {
            return Ok(());
        }
        let idir = dir.join("index");
        std::fs::create_dir_all(&idir).map_err(|e| Error::write(&idir, e))?;
        wanted.par_iter().try_for_each(|&k| {
            if self.chunk_index(dir, k).is_ok() {
                return Ok(());
            }
            let f = &self.files[k];
            let info = FileInfo::read(&f.path)?;
            let ix = ChunkIndex::build(&info)?;
            let stamp = f.stamp.unwrap_or(FileStamp {
                bytes: 0,
                modified: 0,
                nanos: 0,
            });
            write_atomic(&Self::chunk_index_path(dir, k), &encode(&ix, stamp))
        })
    }

    /// Reads the chunk index of the plan's file `k`.
    ///
    /// # Errors
    /// [`Error::Format`] naming the index when it is missing, truncated, edited or of another
    /// version of the file (its stamp is not the plan's).
    pub(super) fn chunk_index(&self, dir: &Path, k: usize) -> Result<ChunkIndex> {
        let p = Self::chunk_index_path(dir, k);
        own_file(&p)?;
        let f = &self.files[k];
        let again = "the plan's tasks read only the chunks it lists: make the plan again";
        let bytes = std::fs::read(&p).map_err(|e| {
            bad(
                &p,
                format!(
                    "cannot read the chunk index of {} ({e}); {again}",
                    f.path.display()
                ),
            )
        })?;
        let damaged = |what: &str| {
            bad(
                &p,
                format!("the chunk index of {} is {what}; {again}", f.path.display()),
            )
        };
        if bytes.len() < HEAD + SUM || &bytes[..8] != MAGIC {
            return Err(damaged("not a sweeptin chunk index (or truncated)"));
        }
        let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap_or_default());
        let n = usize::try_from(u64_at(32)).unwrap_or(usize::MAX);
        let len = n.checked_mul(SPAN).and_then(|s| s.checked_add(HEAD + SUM));
        if len != Some(bytes.len()) {
            return Err(damaged(
                "truncated or extended (its length is not what it says)",
            ));
        }
        let body = bytes.len() - SUM;
        if sha(&bytes[..body]) != bytes[body..] {
            return Err(damaged("damaged or edited (its checksum does not match)"));
        }
        let stamp = FileStamp {
            bytes: u64_at(8),
            modified: u64_at(16) as i64,
            nanos: u32::from_le_bytes(bytes[24..28].try_into().unwrap_or_default()),
        };
        if f.stamp.is_some_and(|s| s != stamp) {
            return Err(damaged("of another version of the file than the plan's"));
        }
        let spans = (0..n)
            .map(|i| {
                let o = HEAD + i * SPAN;
                let f64_at = |k: usize| f64::from_bits(u64_at(o + 32 + 8 * k));
                SpanBox {
                    span: crate::input::las::header::Chunk {
                        offset: u64_at(o),
                        bytes: u64_at(o + 8),
                        points: u64_at(o + 16),
                        first: u64_at(o + 24),
                    },
                    rect: [f64_at(0), f64_at(1), f64_at(2), f64_at(3)],
                }
            })
            .collect();
        Ok(ChunkIndex { spans })
    }

    /// The chunk indexes of the indexed files task `i` reads with a buffer of `buffer`.
    ///
    /// # Errors
    /// As [`Plan::chunk_index`].
    pub(super) fn task_chunks(&self, dir: &Path, i: usize, buffer: f64) -> Result<TaskChunks> {
        let g = super::grown(self.task(i)?.bounds, buffer);
        (0..self.files.len())
            .filter(|&k| {
                let f = &self.files[k];
                f.indexed && f.points > 0 && super::overlaps(&f.bounds, &g)
            })
            .map(|k| {
                Ok((
                    self.files[k].path.clone(),
                    Arc::new(self.chunk_index(dir, k)?),
                ))
            })
            .collect()
    }
}

/// The bytes of index `ix` of a file with stamp `stamp`.
fn encode(ix: &ChunkIndex, stamp: FileStamp) -> Vec<u8> {
    let mut b = Vec::with_capacity(HEAD + SPAN * ix.spans.len() + SUM);
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&stamp.bytes.to_le_bytes());
    b.extend_from_slice(&stamp.modified.to_le_bytes());
    b.extend_from_slice(&stamp.nanos.to_le_bytes());
    b.extend_from_slice(&[0; 4]);
    b.extend_from_slice(&(ix.spans.len() as u64).to_le_bytes());
    for s in &ix.spans {
        let c = s.span;
        for v in [c.offset, c.bytes, c.points, c.first] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in s.rect {
            b.extend_from_slice(&v.to_bits().to_le_bytes());
        }
    }
    let sum = sha(&b);
    b.extend_from_slice(&sum);
    b
}

fn sha(bytes: &[u8]) -> Vec<u8> {
    use sha2::Digest;
    sha2::Sha256::digest(bytes).to_vec()
}
