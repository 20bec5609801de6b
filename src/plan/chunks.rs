//! The chunk indexes of a plan's plain LAZ/LAS files ([`ChunkIndex`]), built once when the plan
//! is saved and read by every task: `DIR/index/<k>.chunks` for the plan's file `k`; and the
//! index stored beside a file (`FILE.chunks`, [`store_chunk_index`], `sweeptin index
//! --chunks`), which `plan` copies instead of decoding the file when it is of the file as it is
//! (the same size and modification time, the same chunk table).
//!
//! A file holds a magic string, the input file's [`FileStamp`] when the index was built, the
//! spans (byte offset, bytes, points, first point, box) and the SHA-256 of all that: a task
//! refuses an index that is truncated, edited, or of the file as it was before a rewrite (the
//! plan's stamp ties the file, and so its index, to the plan).

use super::files::{FileStamp, write_atomic};
use super::{Plan, PlanDir, PlanFile, bad};
use crate::error::{Error, Result};
use crate::input::las::chunks::SpanBox;
use crate::input::las::{ChunkIndex, FileInfo};
use rayon::prelude::*;
use serde::Serialize;
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
    pub fn chunk_index_path(dir: &PlanDir, k: usize) -> PathBuf {
        dir.join("index").join(format!("{k}.chunks"))
    }

    /// Builds and writes (atomically) the chunk index of every plain LAZ/LAS file of the plan
    /// ([`super::PlanFile::indexed`]) that `dir` does not hold yet: one decoding pass over each,
    /// the files side by side and each file's chunks on every core. None in a plan with a point
    /// store ([`Plan::point_store`]: its band and its tasks read the store).
    ///
    /// # Errors
    /// The decoder's errors naming the input; [`Error::Io`] naming the index.
    pub(super) fn write_chunk_indexes(&self, dir: &PlanDir) -> Result<()> {
        // A plan with a point store reads it instead: its tasks and its band need no index.
        let wanted: Vec<usize> = (0..self.files.len())
            .filter(|&k| self.files[k].indexed && self.point_store.is_none())
            .collect();
        if wanted.is_empty() {
            return Ok(());
        }
        dir.make_dir("index")?;
        wanted.par_iter().try_for_each(|&k| {
            if self.chunk_index(dir, k).is_ok() {
                return Ok(());
            }
            let f = &self.files[k];
            let info = FileInfo::read(&f.path)?;
            let ix = match stored(f, &info) {
                Some(Ok(ix)) => ix,
                _ => ChunkIndex::build(&info)?,
            };
            let stamp = f.stamp.unwrap_or(FileStamp {
                bytes: 0,
                modified: 0,
                nanos: 0,
            });
            dir.write(&Self::chunk_index_path(dir, k), &encode(&ix, stamp))
        })
    }

    /// Reads the chunk index of the plan's file `k`.
    ///
    /// # Errors
    /// [`Error::Format`] naming the index when it is missing, truncated, edited or of another
    /// version of the file (its stamp is not the plan's).
    pub(super) fn chunk_index(&self, dir: &PlanDir, k: usize) -> Result<ChunkIndex> {
        let p = Self::chunk_index_path(dir, k);
        let f = &self.files[k];
        let again = "the plan's tasks read only the chunks it lists: make the plan again";
        let cannot = |e: String| {
            bad(
                &p,
                format!(
                    "cannot read the chunk index of {} ({e}); {again}",
                    f.path.display()
                ),
            )
        };
        let bytes = match dir.read(&p) {
            Ok(Some(b)) => b,
            Ok(None) => return Err(cannot("No such file or object".into())),
            Err(e @ Error::Options(_)) => return Err(e),
            Err(e) => return Err(cannot(e.to_string())),
        };
        let damaged = |what: &str| {
            bad(
                &p,
                format!("the chunk index of {} is {what}; {again}", f.path.display()),
            )
        };
        let (ix, stamp) = decode(&bytes).map_err(damaged)?;
        if f.stamp.is_some_and(|s| s != stamp) {
            return Err(damaged("of another version of the file than the plan's"));
        }
        Ok(ix)
    }

    /// What `plan` makes of the chunk index stored beside each of its plain LAZ/LAS files
    /// (`FILE.chunks`, [`store_chunk_index`]): read (instead of decoding the file), or left
    /// because it is not of the file as it is (and why). Files without one are not listed.
    pub fn stored_chunk_indexes(&self) -> Vec<(PathBuf, std::result::Result<(), String>)> {
        self.files
            .iter()
            .filter(|f| f.indexed && self.point_store.is_none())
            .filter_map(|f| {
                let info = FileInfo::read(&f.path).ok()?;
                let r = stored(f, &info)?;
                Some((beside(&f.path), r.map(|_| ())))
            })
            .collect()
    }

    /// The chunk indexes of the indexed files task `i` reads with a buffer of `buffer` (none in
    /// a plan with a point store).
    ///
    /// # Errors
    /// As [`Plan::chunk_index`].
    pub(super) fn task_chunks(&self, dir: &PlanDir, i: usize, buffer: f64) -> Result<TaskChunks> {
        if self.point_store.is_some() {
            return Ok(Vec::new());
        }
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

/// Where the chunk index of `file` is stored beside it: `FILE.chunks` (`tile.laz.chunks`).
pub fn beside(file: &Path) -> PathBuf {
    let mut name = file.as_os_str().to_os_string();
    name.push(".chunks");
    PathBuf::from(name)
}

/// The index stored beside the plan's local file `f` (whose header is `info`), if there is one:
/// read when it is of the file as the plan pinned it (its stamp, its chunk table), else why not.
fn stored(f: &PlanFile, info: &FileInfo) -> Option<std::result::Result<ChunkIndex, String>> {
    let stamp = f.stamp?;
    let p = beside(&f.path);
    let bytes = match std::fs::read(&p) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return None,
        Err(e) => return Some(Err(format!("cannot be read ({e})"))),
        Ok(b) => b,
    };
    Some(match decode(&bytes) {
        Err(why) => Err(format!("is {why}")),
        Ok((_, s)) if s != stamp => Err(format!(
            "is of another version of {} (its size or modification time differs)",
            f.path.display()
        )),
        Ok((ix, _)) => match ix.check(info) {
            Ok(()) => Ok(ix),
            Err(_) => Err("does not list the file's chunks (of another file?)".into()),
        },
    })
}

/// One span of a stored chunk index, as `sweeptin index --chunks --json` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ChunkBox {
    /// Index of its first point in the file.
    pub first: u64,
    /// Its points.
    pub points: u64,
    /// `[xmin, ymin, xmax, ymax]` of its points (none without points).
    pub bounds: Option<[f64; 4]>,
}

/// What [`store_chunk_index`] did with one file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StoredChunks {
    /// The LAS/LAZ file.
    pub file: PathBuf,
    /// The index written or kept (none for a COPC file, which carries its own, or a file
    /// without points).
    pub index: Option<PathBuf>,
    /// `"built"`, `"up_to_date"` (the index there is of the file as it is: kept), `"copc"` or
    /// `"no_points"`.
    pub state: &'static str,
    /// Points in the file.
    pub points: u64,
    /// Its spans, in file order: the LAZ chunks, or blocks of
    /// [`LAS_BLOCK`](crate::input::las::chunks::LAS_BLOCK) LAS records.
    pub chunks: Vec<ChunkBox>,
}

/// Builds the chunk index of the local plain LAZ/LAS file `file` (one decoding pass, its
/// chunks on every core) and writes it, atomically, to `FILE.chunks` beside it, or into the
/// directory `out` (`out/<name>.chunks`): the index `plan` would build, which a plan over the
/// file reads instead when it lies beside the file ([`Plan::stored_chunk_indexes`]). An index
/// already there that is of the file as it is (the same size and modification time, the same
/// chunk table) is kept. A COPC file (its own index) and a file without points get none.
///
/// # Errors
/// [`Error::Options`] for a URL, or an index path that is not a regular file; the decoder's
/// errors naming the file; [`Error::Io`] naming the index.
pub fn store_chunk_index(file: &Path, out: Option<&Path>) -> Result<StoredChunks> {
    if crate::input::source::is_remote(file) {
        return Err(Error::Options(format!(
            "{}: a chunk index is stored beside a local file (a remote file is read by range; \
             copy it first, or convert it to COPC)",
            file.display()
        )));
    }
    let info = FileInfo::read(file)?;
    let mut s = StoredChunks {
        file: file.to_path_buf(),
        index: None,
        state: "no_points",
        points: info.point_count,
        chunks: Vec::new(),
    };
    if info.copc.is_some() {
        s.state = "copc";
        return Ok(s);
    }
    if info.point_count == 0 {
        return Ok(s);
    }
    let p = match out {
        None => beside(file),
        Some(d) => d.join(beside(Path::new(file.file_name().unwrap_or_default()))),
    };
    if let Ok(m) = std::fs::symlink_metadata(&p)
        && !m.file_type().is_file()
    {
        return Err(Error::Options(format!(
            "{}: not a regular file where the chunk index of {} goes (remove it, or give -o \
             another directory)",
            p.display(),
            file.display()
        )));
    }
    let stamp = FileStamp::of(file)?;
    let kept = std::fs::read(&p).ok().and_then(|b| {
        let (ix, st) = decode(&b).ok()?;
        (st == stamp && ix.check(&info).is_ok()).then_some(ix)
    });
    let ix = match kept {
        Some(ix) => {
            s.state = "up_to_date";
            ix
        }
        None => {
            let ix = ChunkIndex::build(&info)?;
            // The file changed while it was decoded: an index of neither version.
            if FileStamp::of(file)? != stamp {
                return Err(Error::Options(format!(
                    "{} changed while it was indexed: index it again when it is written",
                    file.display()
                )));
            }
            write_atomic(&p, &encode(&ix, stamp))?;
            s.state = "built";
            ix
        }
    };
    s.chunks = ix
        .span_boxes()
        .map(|(first, points, bounds)| ChunkBox {
            first,
            points,
            bounds,
        })
        .collect();
    s.index = Some(p);
    Ok(s)
}

/// The index and the file's stamp in `bytes`, or what is wrong with them.
fn decode(bytes: &[u8]) -> std::result::Result<(ChunkIndex, FileStamp), &'static str> {
    if bytes.len() < HEAD + SUM || &bytes[..8] != MAGIC {
        return Err("not a sweeptin chunk index (or truncated)");
    }
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap_or_default());
    let n = usize::try_from(u64_at(32)).unwrap_or(usize::MAX);
    let len = n.checked_mul(SPAN).and_then(|s| s.checked_add(HEAD + SUM));
    if len != Some(bytes.len()) {
        return Err("truncated or extended (its length is not what it says)");
    }
    let body = bytes.len() - SUM;
    if sha(&bytes[..body]) != bytes[body..] {
        return Err("damaged or edited (its checksum does not match)");
    }
    let stamp = FileStamp {
        bytes: u64_at(8),
        modified: u64_at(16) as i64,
        nanos: u32::from_le_bytes(bytes[24..28].try_into().unwrap_or_default()),
    };
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
    Ok((ChunkIndex { spans }, stamp))
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
