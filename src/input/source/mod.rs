//! Where an input's bytes come from: a local file, an HTTP(S) object or an S3 object, read at
//! any offset, with a size and an identity. The LAS/LAZ/COPC/VPC readers take a [`Source`] and
//! never learn which it is.
//!
//! Inputs keep being named by the `Path` the user gave: `https://host/a.copc.laz`,
//! `http://…` and `s3://bucket/key` are remote ([`Location::of`]), anything else is a local
//! path. Messages name the input as it was written.
//!
//! - **Identity**: a local file's size and modification time; a remote object's ETag (else its
//!   Last-Modified) and size, captured when it is first opened in the process and checked on
//!   every response (`If-Match`, the response's ETag and `Content-Range`): an object replaced
//!   while it is read is an error naming the URL, never a mix of two versions. A remote object is
//!   opened once per process ([`Source::open`] keeps it), so the header check and the decoding
//!   read the same version.
//! - **Reading**: [`Source::reader`] is a `Read + Seek` view whose buffer grows while the reads
//!   stay sequential (64 KiB at a seek, up to 8 MiB: a LAZ file streams in large ranges, a
//!   header costs one small request); `Ahead` reads a planned list of ranges (the LAZ chunks or
//!   COPC nodes a job decodes) with [`io_concurrency`] requests in flight, neighbouring ranges
//!   coalesced.
//! - **Faults** (remote): 5xx answers, dropped connections and timeouts are retried with
//!   backoff, a few times, each logged on stderr; a short body or a `Content-Range` other than
//!   the one asked for is detected; a server that ignores `Range` is read once, whole and
//!   sequentially, into an anonymous temporary file, with a warning.

mod ahead;
mod http;
mod local;
mod s3;

pub(crate) use ahead::Ahead;

use crate::error::{Error, Result};
use std::collections::HashMap;
use std::io::{self, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// Requests in flight for one remote file (`--io-concurrency`).
static IO_CONCURRENCY: AtomicUsize = AtomicUsize::new(DEFAULT_IO_CONCURRENCY);

/// The default of [`io_concurrency`]: a few requests hide the latency without crowding the
/// server (more were slower in PDAL's experience, PDAL #3913).
pub const DEFAULT_IO_CONCURRENCY: usize = 4;

/// Sets how many range requests may be in flight for one remote file (at least 1).
pub fn set_io_concurrency(n: usize) {
    IO_CONCURRENCY.store(n.max(1), Ordering::Relaxed);
}

/// How many range requests may be in flight for one remote file.
pub fn io_concurrency() -> usize {
    IO_CONCURRENCY.load(Ordering::Relaxed)
}

/// Seconds to wait for a server (`--io-timeout`); see [`set_io_timeout`].
static IO_TIMEOUT: AtomicU64 = AtomicU64::new(DEFAULT_IO_TIMEOUT);

/// The default of [`set_io_timeout`], in seconds: GDAL's `GDAL_HTTP_TIMEOUT` is 30, object stores
/// under load answer within a few seconds, and a minute leaves room for a slow proxy.
pub const DEFAULT_IO_TIMEOUT: u64 = 60;

/// Sets how long a request to a remote input may wait (at least 1 s): `secs` to connect and for
/// the answer's head, twice that for a range's body (up to 8 MiB; more for the first request,
/// which may bring a whole object, and for uploads). A request that times out is retried like
/// a dropped connection. Applies to the requests made after the call.
pub fn set_io_timeout(secs: u64) {
    IO_TIMEOUT.store(secs.max(1), Ordering::Relaxed);
}

/// How long a request to a remote input may wait for its answer to start, in seconds.
pub fn io_timeout() -> u64 {
    IO_TIMEOUT.load(Ordering::Relaxed)
}

/// Where an input lives, from the name the user gave.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// A local file.
    Local(PathBuf),
    /// An `http://` or `https://` URL.
    Http(String),
    /// An `s3://bucket/key` object.
    S3 {
        /// The bucket.
        bucket: String,
        /// The object's key.
        key: String,
    },
}

impl Location {
    /// Where `name` lives: a URL (`http://`, `https://`, `s3://`) or a local path.
    pub fn of(name: &Path) -> Location {
        let Some(text) = name.to_str() else {
            return Location::Local(name.to_path_buf());
        };
        let lower = text.get(..8).unwrap_or(text).to_ascii_lowercase();
        if lower.starts_with("http://") || lower.starts_with("https://") {
            return Location::Http(text.to_string());
        }
        if let Some(rest) = lower.starts_with("s3://").then(|| &text[5..]) {
            let (bucket, key) = rest.split_once('/').unwrap_or((rest, ""));
            return Location::S3 {
                bucket: bucket.to_string(),
                key: key.to_string(),
            };
        }
        Location::Local(name.to_path_buf())
    }

    /// Whether this is a remote object.
    pub fn is_remote(&self) -> bool {
        !matches!(self, Location::Local(_))
    }
}

/// Whether `name` is a URL (read over the network) rather than a local path.
pub fn is_remote(name: &Path) -> bool {
    Location::of(name).is_remote()
}

/// `rel`, a relative path read in a list or a `.vpc` found in `dir`, as a path or URL: beside
/// it (a URL's path joins with `/` whatever the platform; a leading `./` is dropped).
pub fn beside(dir: &Path, rel: &str) -> PathBuf {
    let rel = rel.strip_prefix("./").unwrap_or(rel);
    if is_remote(dir) {
        PathBuf::from(format!("{}/{rel}", dir.display()))
    } else {
        dir.join(rel)
    }
}

/// A remote object's version as this process reads it (its ETag, else its Last-Modified date,
/// and its size: [`Source::identity`]); `None` for a local file.
///
/// # Errors
/// [`Error::Io`] when the object cannot be opened.
pub fn remote_version(name: &Path) -> Result<Option<String>> {
    if !is_remote(name) {
        return Ok(None);
    }
    Ok(Some(Source::open(name)?.identity()))
}

/// Writes the `len` bytes of `file` (from its start) as the remote object `name`, whole or not
/// at all: an `s3://` object in one `PUT` up to 64 MiB, else in a multipart upload of 16 MiB
/// parts (more when it needs over 10000), aborted on any error so that no part stays stored.
///
/// # Errors
/// [`Error::Write`] naming `name`: an `http(s)://` destination, a refusal (access denied, no
/// such bucket), a transfer that fails after its retries.
pub fn upload(name: &Path, file: &std::fs::File, len: u64) -> Result<()> {
    let shown = name.display().to_string();
    let r = match Location::of(name) {
        Location::S3 { bucket, key } => s3::put(&shown, &bucket, &key, file, len),
        _ => Err(io::Error::new(
            io::ErrorKind::Unsupported,
            "outputs go to local files or s3:// objects",
        )),
    };
    r.map_err(|e| Error::write(name, e))?;
    // Another version now: a later read in this process opens it afresh.
    opened()
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .remove(name);
    Ok(())
}

/// Aborts the multipart uploads of this process still in progress (it is being interrupted):
/// the server deletes their stored parts. Waits a few seconds at most for each; returns how
/// many were aborted.
pub fn abort_uploads() -> usize {
    s3::abort_pending()
}

/// Checks, before a run's work, that the remote output `name` can be written: an `s3://`
/// object's bucket exists and its endpoint answers (once per bucket in a process). An access
/// denied to the check passes (credentials may put objects without listing them): the upload
/// tells then.
///
/// # Errors
/// [`Error::Write`] naming `name`: no such bucket, an endpoint that does not answer, an
/// `http(s)://` destination.
pub fn check_destination(name: &Path) -> Result<()> {
    static CHECKED: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let r = match Location::of(name) {
        Location::S3 { bucket, key } => {
            let mut checked = CHECKED.lock().unwrap_or_else(|p| p.into_inner());
            if checked.contains(&bucket) {
                return Ok(());
            }
            let r = s3::check_bucket(&name.display().to_string(), &bucket, &key);
            if r.is_ok() {
                checked.push(bucket);
            }
            r
        }
        _ => Err(io::Error::new(
            io::ErrorKind::Unsupported,
            "outputs go to local files or s3:// objects",
        )),
    };
    r.map_err(|e| Error::write(name, e))
}

/// An `s3://` object's bucket and key, or why `name` is not one (the plan's own objects).
fn s3_object(name: &Path) -> io::Result<(String, String)> {
    match Location::of(name) {
        Location::S3 { bucket, key } => Ok((bucket, key)),
        _ => Err(io::Error::new(
            io::ErrorKind::Unsupported,
            "not an s3:// object (a plan's directory is local or an s3:// prefix)",
        )),
    }
}

/// The size of the `s3://` object `name` now (a `HEAD`), `None` when there is none.
///
/// # Errors
/// [`Error::Io`] naming it: access denied, no answer after the retries, not `s3://`.
pub fn object_size(name: &Path) -> Result<Option<u64>> {
    let (bucket, key) = s3_object(name).map_err(|e| Error::io(name, e))?;
    s3::size(&name.display().to_string(), &bucket, &key).map_err(|e| Error::io(name, e))
}

/// The whole `s3://` object `name` as it is now (never the version this process saw before:
/// a plan's records are written and read again), `None` when there is none.
///
/// # Errors
/// [`Error::Io`] naming it: access denied, no answer after the retries, over 256 MiB.
pub fn read_object(name: &Path) -> Result<Option<Vec<u8>>> {
    let (bucket, key) = s3_object(name).map_err(|e| Error::io(name, e))?;
    let object = match s3::open(&name.display().to_string(), &bucket, &key) {
        Ok(o) => o,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(name, e)),
    };
    if object.len() > MAX_TEXT {
        let why = format!("{} bytes: more than a plan's file may have", object.len());
        return Err(Error::io(
            name,
            io::Error::new(io::ErrorKind::InvalidData, why),
        ));
    }
    let mut bytes = vec![0u8; object.len() as usize];
    if !bytes.is_empty() {
        object
            .read_at(0, &mut bytes)
            .map_err(|e| Error::io(name, e))?;
    }
    Ok(Some(bytes))
}

/// Deletes the `s3://` object `name` (none there is no error).
///
/// # Errors
/// [`Error::Write`] naming it.
pub fn delete_object(name: &Path) -> Result<()> {
    let (bucket, key) = s3_object(name).map_err(|e| Error::write(name, e))?;
    s3::delete(&name.display().to_string(), &bucket, &key).map_err(|e| Error::write(name, e))?;
    opened()
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .remove(name);
    Ok(())
}

/// The first object whose name starts with `prefix` (`s3://bucket/job/tiles/task_`), if any;
/// `None` too when the listing is denied (credentials may write and read objects without
/// listing them: nothing is known then).
///
/// # Errors
/// [`Error::Io`] naming the prefix: no such bucket, no answer.
pub fn first_object(prefix: &Path) -> Result<Option<PathBuf>> {
    let (bucket, key) = s3_object(prefix).map_err(|e| Error::io(prefix, e))?;
    let first = match s3::first_key(&prefix.display().to_string(), &bucket, &key) {
        Err(e) if e.kind() == io::ErrorKind::PermissionDenied => None,
        r => r.map_err(|e| Error::io(prefix, e))?,
    };
    Ok(first.map(|k| PathBuf::from(format!("s3://{bucket}/{k}"))))
}

/// The largest text input read whole from a server (a `.vpc`, a file list).
const MAX_TEXT: u64 = 256 << 20;

/// The whole text of `name`, a local file or a remote object (a `.vpc`, an `@list`).
///
/// # Errors
/// [`Error::Io`] when it cannot be read or is not UTF-8, or (remote) is over 256 MiB.
pub fn read_to_string(name: &Path) -> Result<String> {
    if !is_remote(name) {
        return std::fs::read_to_string(name).map_err(|e| Error::io(name, e));
    }
    let source = Source::open(name)?;
    if source.len() > MAX_TEXT {
        return Err(Error::io(
            name,
            io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "{} bytes: more than the {MAX_TEXT} a list of files may have",
                    source.len()
                ),
            ),
        ));
    }
    let mut bytes = vec![0u8; source.len() as usize];
    source
        .read_exact_at(0, &mut bytes)
        .map_err(|e| Error::io(name, e))?;
    String::from_utf8(bytes)
        .map_err(|e| Error::io(name, io::Error::new(io::ErrorKind::InvalidData, e)))
}

/// An object whose bytes can be read at any offset.
pub(crate) trait Object: Send + Sync {
    /// Its size in bytes.
    fn len(&self) -> u64;
    /// Fills `buf` with the bytes at `offset`; `UnexpectedEof` past the end.
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()>;
    /// What identifies this version of it (size and time, or ETag and size).
    fn identity(&self) -> String;
}

/// One input's bytes, wherever they live. Cheap to clone (shared).
#[derive(Clone)]
pub struct Source {
    name: PathBuf,
    object: Arc<dyn Object>,
    remote: bool,
    /// A remote object's blocks read through [`SourceRead`] (headers, VLRs, chunk tables,
    /// hierarchy pages: read by every part of a run that inspects the file), newest last.
    blocks: Arc<Mutex<Vec<Block>>>,
}

/// A block of a remote object: its offset and bytes.
type Block = (u64, Arc<Vec<u8>>);

/// The most blocks a remote object keeps, and the largest block kept.
const CACHED_BLOCKS: usize = 16;
const CACHED_BLOCK_LEN: usize = 1 << 20;

impl std::fmt::Debug for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Source")
            .field("name", &self.name)
            .field("identity", &self.object.identity())
            .finish()
    }
}

/// The remote objects opened by this process, by name: each is read in the version first seen.
fn opened() -> &'static Mutex<HashMap<PathBuf, Source>> {
    static OPENED: std::sync::OnceLock<Mutex<HashMap<PathBuf, Source>>> =
        std::sync::OnceLock::new();
    OPENED.get_or_init(Mutex::default)
}

impl Source {
    /// Opens the input `name` (a local path or a URL, see [`Location`]). A remote object is
    /// asked for its size and identity once per process; later opens share that version.
    ///
    /// # Errors
    /// [`Error::Io`] naming the input when it cannot be opened: a local file's error, or a
    /// server's answer (not found, access denied) or a failure that outlasted the retries.
    pub fn open(name: &Path) -> Result<Source> {
        let object: Arc<dyn Object> = match Location::of(name) {
            Location::Local(p) => Arc::new(local::Local::open(&p).map_err(|e| Error::io(&p, e))?),
            remote => {
                let mut opened = opened().lock().unwrap_or_else(|p| p.into_inner());
                if let Some(s) = opened.get(name) {
                    return Ok(s.clone());
                }
                let shown = name.display().to_string();
                let object: Arc<dyn Object> = match remote {
                    Location::S3 { bucket, key } => {
                        Arc::new(s3::open(&shown, &bucket, &key).map_err(|e| Error::io(name, e))?)
                    }
                    _ => Arc::new(http::Http::open(&shown, None).map_err(|e| Error::io(name, e))?),
                };
                let s = Source {
                    name: name.to_path_buf(),
                    object,
                    remote: true,
                    blocks: Arc::default(),
                };
                opened.insert(name.to_path_buf(), s.clone());
                return Ok(s);
            }
        };
        Ok(Source {
            name: name.to_path_buf(),
            object,
            remote: false,
            blocks: Arc::default(),
        })
    }

    /// The input's name as given.
    pub fn name(&self) -> &Path {
        &self.name
    }

    /// Its size in bytes.
    pub fn len(&self) -> u64 {
        self.object.len()
    }

    /// Whether it holds no byte.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether its bytes come over the network.
    pub fn is_remote(&self) -> bool {
        self.remote
    }

    /// What identifies the version read: `"1234 bytes, modified …"` for a local file,
    /// `"ETag \"…\", 1234 bytes"` for a remote object.
    pub fn identity(&self) -> String {
        self.object.identity()
    }

    /// Fills `buf` with the bytes at `offset`.
    ///
    /// # Errors
    /// `UnexpectedEof` when the range passes the end; the object's read errors (a remote
    /// object's naming what the server did).
    pub fn read_exact_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        if buf.is_empty() {
            return Ok(());
        }
        self.object.read_at(offset, buf)
    }

    /// A `Read + Seek` view from the first byte, buffered (see the module's notes).
    pub fn reader(&self) -> SourceRead {
        let (min, max) = if self.remote {
            (16 << 10, 8 << 20)
        } else {
            (64 << 10, 64 << 10)
        };
        SourceRead {
            source: self.clone(),
            pos: 0,
            buf: Arc::default(),
            buf_at: 0,
            next_len: min,
            min,
            max,
        }
    }
}

impl Source {
    /// The kept block holding byte `at` of a remote object.
    fn cached(&self, at: u64) -> Option<Block> {
        if !self.remote {
            return None;
        }
        let blocks = self.blocks.lock().unwrap_or_else(|p| p.into_inner());
        blocks
            .iter()
            .rev()
            .find(|(o, b)| (*o..o + b.len() as u64).contains(&at))
            .cloned()
    }

    /// Keeps a small block of a remote object for the next readers.
    fn keep(&self, at: u64, block: &Arc<Vec<u8>>) {
        if !self.remote || block.len() > CACHED_BLOCK_LEN {
            return;
        }
        let mut blocks = self.blocks.lock().unwrap_or_else(|p| p.into_inner());
        if blocks.len() == CACHED_BLOCKS {
            blocks.remove(0);
        }
        blocks.push((at, block.clone()));
    }
}

/// A [`Source`] read as a stream: `Read + Seek`, with a buffer that doubles while the reads are
/// sequential (from 16 KiB up to 8 MiB for a remote object, whose small blocks are kept for the
/// next reader) and is 64 KiB for a local file.
pub struct SourceRead {
    source: Source,
    pos: u64,
    buf: Arc<Vec<u8>>,
    buf_at: u64,
    next_len: usize,
    min: usize,
    max: usize,
}

impl SourceRead {
    /// The source read.
    pub fn source(&self) -> &Source {
        &self.source
    }
}

impl Read for SourceRead {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        let end = self.buf_at + self.buf.len() as u64;
        if !(self.buf_at..end).contains(&self.pos) {
            let len = self.source.len();
            if self.pos >= len || out.is_empty() {
                return Ok(0);
            }
            self.next_len = if self.pos == end && !self.buf.is_empty() {
                (self.next_len * 2).min(self.max)
            } else {
                self.min
            };
            let n = (self.next_len.max(out.len()) as u64).min(len - self.pos) as usize;
            self.buf_at = self.pos;
            self.buf = match self.source.cached(self.pos) {
                Some((at, block)) => {
                    self.buf_at = at;
                    block
                }
                None => {
                    let mut buf = std::mem::take(&mut self.buf);
                    let b = Arc::make_mut(&mut buf);
                    b.resize(n, 0);
                    self.source.read_exact_at(self.pos, b)?;
                    self.source.keep(self.pos, &buf);
                    buf
                }
            };
        }
        let from = (self.pos - self.buf_at) as usize;
        let n = out.len().min(self.buf.len() - from);
        out[..n].copy_from_slice(&self.buf[from..from + n]);
        self.pos += n as u64;
        Ok(n)
    }
}

impl Seek for SourceRead {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        let pos = match to {
            SeekFrom::Start(p) => Some(p),
            SeekFrom::End(d) => self.source.len().checked_add_signed(d),
            SeekFrom::Current(d) => self.pos.checked_add_signed(d),
        };
        self.pos = pos.ok_or_else(|| {
            io::Error::new(io::ErrorKind::InvalidInput, "seek before the first byte")
        })?;
        Ok(self.pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locations_from_names() {
        assert_eq!(
            Location::of(Path::new("s3://b/dir/x.laz")),
            Location::S3 {
                bucket: "b".into(),
                key: "dir/x.laz".into()
            }
        );
        assert!(is_remote(Path::new("HTTPS://h/x.laz")));
        assert!(!is_remote(Path::new("tiles/x.laz")));
        assert!(!is_remote(Path::new("http.laz")));
    }

    #[test]
    fn reader_reads_and_seeks_like_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.bin");
        let bytes: Vec<u8> = (0..300_000u32).map(|i| (i % 251) as u8).collect();
        std::fs::write(&p, &bytes).unwrap();
        let mut r = Source::open(&p).unwrap().reader();
        let mut all = Vec::new();
        r.read_to_end(&mut all).unwrap();
        assert_eq!(all, bytes);
        r.seek(SeekFrom::Start(70_000)).unwrap();
        let mut b = [0u8; 10];
        r.read_exact(&mut b).unwrap();
        assert_eq!(b, bytes[70_000..70_010]);
        r.seek(SeekFrom::End(-4)).unwrap();
        assert_eq!(r.read(&mut b).unwrap(), 4);
        assert_eq!(r.read(&mut b).unwrap(), 0);
    }
}
