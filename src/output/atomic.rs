//! Atomic output files and clean-up of temporary files on Ctrl-C.
//!
//! Every output `sweeptin` writes goes through an [`AtomicFile`]: the bytes go to a hidden temporary
//! file in the same directory as the final path (`.NAME.sweeptin-HOST.PID-XXXXXX.tmp`), and only
//! [`AtomicFile::commit`] flushes, fsyncs and renames it onto the final path. A crash, an error or
//! an interruption therefore never leaves a partial file under the final name; the temporary file
//! of a killed run is removed by the next run to the same output ([`super::target`]). FIFOs,
//! devices and standard output are written directly ([`AtomicFile::is_stream`]).
//!
//! Temporary paths that must not outlive the process are kept in a process-wide registry
//! ([`register_temp`]). [`super::interrupt::install_interrupt_handler`] makes Ctrl-C (SIGINT), SIGTERM and SIGHUP
//! delete every registered path ([`cleanup_registered_temps`]) and exit with 128 + the signal's
//! number (130, 143, 129), the shell's convention. Modules that
//! spill to disk (the external sort under `--tmp-dir`) use [`RegisteredTempDir`] or register their
//! own paths.
//!
//! Spool files that are only read back by the process that wrote them should instead be anonymous
//! ([`tempfile::tempfile_in`]): the operating system deletes those even after `kill -9`.

use super::target::{Destination, remove_stale_temps, temp_prefix};
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Size of the write buffer of an [`AtomicFile`].
const WRITE_BUFFER: usize = crate::sort::WRITE_PIECE;

/// Exit code after an interruption by Ctrl-C (128 + SIGINT, the shell convention); SIGTERM
/// gives 143 and SIGHUP 129.
pub const INTERRUPTED_EXIT_CODE: i32 = 130;

/// What a registered temporary path is, which decides how it is deleted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TempKind {
    /// A file: deleted with `remove_file`.
    File,
    /// A directory: deleted with everything in it.
    Dir,
}

/// A set of temporary paths to delete on interruption. The process-wide one is behind
/// [`register_temp`] and [`cleanup_registered_temps`]; tests make their own.
struct TempRegistry {
    inner: Mutex<RegistryInner>,
}

struct RegistryInner {
    next_id: u64,
    entries: BTreeMap<u64, (PathBuf, TempKind)>,
}

impl TempRegistry {
    const fn new() -> Self {
        TempRegistry {
            inner: Mutex::new(RegistryInner {
                next_id: 0,
                entries: BTreeMap::new(),
            }),
        }
    }

    /// Locks the registry, ignoring poisoning: the map stays consistent whatever panicked.
    fn lock(&self) -> MutexGuard<'_, RegistryInner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn register(&'static self, path: PathBuf, kind: TempKind) -> TempRegistration {
        let mut inner = self.lock();
        let id = inner.next_id;
        inner.next_id += 1;
        inner.entries.insert(id, (path, kind));
        TempRegistration { registry: self, id }
    }

    fn paths(&self) -> Vec<(PathBuf, TempKind)> {
        self.lock().entries.values().cloned().collect()
    }

    fn cleanup(&self) -> usize {
        let entries = std::mem::take(&mut self.lock().entries);
        entries
            .into_values()
            .filter(|(path, kind)| {
                let removed = match kind {
                    TempKind::File => std::fs::remove_file(path),
                    TempKind::Dir => std::fs::remove_dir_all(path),
                };
                removed.is_ok()
            })
            .count()
    }
}

static REGISTRY: TempRegistry = TempRegistry::new();

/// Proof that a temporary path is in the registry; dropping it takes the path out again (it does
/// **not** delete the path: its owner does that).
#[must_use = "dropping the registration unregisters the path at once"]
pub struct TempRegistration {
    registry: &'static TempRegistry,
    id: u64,
}

impl std::fmt::Debug for TempRegistration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TempRegistration")
            .field("id", &self.id)
            .finish()
    }
}

impl Drop for TempRegistration {
    fn drop(&mut self) {
        self.registry.lock().entries.remove(&self.id);
    }
}

/// Registers a temporary file or directory to be deleted if the process is interrupted.
///
/// Keep the returned [`TempRegistration`] while the path exists; drop it after deleting the path
/// yourself (or after renaming it into a permanent place).
pub fn register_temp(path: impl Into<PathBuf>, kind: TempKind) -> TempRegistration {
    REGISTRY.register(path.into(), kind)
}

/// The paths registered now, in registration order.
pub fn registered_temps() -> Vec<(PathBuf, TempKind)> {
    REGISTRY.paths()
}

/// Deletes every registered temporary path and empties the registry; returns how many paths were
/// actually deleted (paths already gone are not counted). This is what the interrupt handler runs;
/// errors are ignored because there is nothing better to do with them while exiting.
pub fn cleanup_registered_temps() -> usize {
    REGISTRY.cleanup()
}

/// A temporary directory that is deleted (with its contents) when dropped, and also when the
/// process is interrupted. For spill files under `--tmp-dir`.
#[derive(Debug)]
pub struct RegisteredTempDir {
    // Field order matters: the directory is deleted before it is unregistered.
    dir: tempfile::TempDir,
    _registration: TempRegistration,
}

impl RegisteredTempDir {
    /// Creates `PARENT/.sweeptin-XXXXXX.tmp/`.
    ///
    /// # Errors
    /// [`Error::Write`] naming `parent` if the directory cannot be created.
    pub fn new_in(parent: &Path) -> Result<Self> {
        let dir = tempfile::Builder::new()
            .prefix(".sweeptin-")
            .suffix(".tmp")
            .tempdir_in(parent)
            .map_err(|e| Error::write(parent, e))?;
        let registration = register_temp(dir.path(), TempKind::Dir);
        Ok(RegisteredTempDir {
            dir,
            _registration: registration,
        })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        self.dir.path()
    }
}

/// An output file that appears under its final name only when complete.
///
/// Writes go, buffered, to a hidden temporary file next to the final path (the target of a
/// symbolic link); [`commit`](Self::commit) moves it into place. Dropping an `AtomicFile` without
/// committing deletes the temporary file and leaves any existing file at the final path
/// untouched. A FIFO, a character device or standard output is written directly instead
/// ([`AtomicFile::is_stream`]; see [`super::target`] for the whole rule).
///
/// `Write` and `Seek` errors are plain [`io::Error`]s; wrap them with [`AtomicFile::err`] to name
/// the final path. A stream cannot seek: its `Seek` fails (writers that need it open with
/// [`AtomicFile::create_seekable`]).
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    inner: Inner,
}

#[derive(Debug)]
enum Inner {
    Replace {
        target: PathBuf,
        mode: Option<u32>,
        // Field order matters: the temporary file is deleted before it is unregistered.
        writer: BufWriter<tempfile::NamedTempFile>,
        /// Bytes written, and how many when write-behind last started ([`WRITE_BEHIND`]).
        behind: (u64, u64),
        /// `target` is a remote object ([`Destination::Object`]): the commit uploads the
        /// temporary file instead of renaming it.
        upload: bool,
        _registration: TempRegistration,
    },
    Stream {
        writer: BufWriter<StreamOut>,
        written: u64,
    },
}

/// Where a stream's bytes go: the process's own standard output or error, or an opened FIFO or
/// device.
#[derive(Debug)]
enum StreamOut {
    Stdout(io::Stdout),
    Stderr(io::Stderr),
    File(File),
}

impl Write for StreamOut {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self {
            StreamOut::Stdout(s) => s.write(buf),
            StreamOut::Stderr(s) => s.write(buf),
            StreamOut::File(f) => f.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self {
            StreamOut::Stdout(s) => s.flush(),
            StreamOut::Stderr(s) => s.flush(),
            StreamOut::File(f) => f.flush(),
        }
    }
}

impl AtomicFile {
    /// Starts writing `path` (see [`super::target::Destination::of`] for what happens with each
    /// kind of path): a temporary file `.NAME.sweeptin-HOST.PID-XXXXXX.tmp` beside the final
    /// file, after deleting those that dead runs left there; or the stream, opened for writing.
    ///
    /// # Errors
    /// [`Error::Write`] naming `path` if the directory does not exist or is not writable, or the
    /// stream cannot be opened; [`Error::Output`] if `path` has no file name, or is a directory,
    /// a block device or a socket.
    pub fn create(path: impl Into<PathBuf>) -> Result<Self> {
        let path = path.into();
        if path.file_name().is_none() && path.as_os_str() != "-" {
            return Err(Error::Output {
                path,
                message: "not a file name".into(),
            });
        }
        let inner = match Destination::of(&path)? {
            Destination::File { target, mode } => Self::temp_beside(&path, target, mode)?,
            Destination::Object { url } => {
                // In the system's temporary directory, named as the temporary files beside
                // outputs are (a run killed before its upload leaves one the next removes).
                let name = url.file_name().map_or_else(
                    || "upload".to_string(),
                    |n| n.to_string_lossy().into_owned(),
                );
                let stand_in = std::env::temp_dir().join(&name);
                remove_stale_temps(&stand_in);
                let temp = tempfile::Builder::new()
                    .prefix(&temp_prefix(&name))
                    .suffix(".tmp")
                    .rand_bytes(6)
                    .tempfile()
                    .map_err(|e| Error::write(&path, e))?;
                let registration = register_temp(temp.path(), TempKind::File);
                Inner::Replace {
                    target: url,
                    mode: None,
                    writer: BufWriter::with_capacity(WRITE_BUFFER, temp),
                    behind: (0, 0),
                    upload: true,
                    _registration: registration,
                }
            }
            Destination::Stream { fd, .. } => {
                let out = match fd {
                    Some(1) => StreamOut::Stdout(io::stdout()),
                    Some(_) => StreamOut::Stderr(io::stderr()),
                    None => StreamOut::File(
                        std::fs::OpenOptions::new()
                            .write(true)
                            .truncate(true)
                            .open(&path)
                            .map_err(|e| Error::write(&path, e))?,
                    ),
                };
                Inner::Stream {
                    writer: BufWriter::with_capacity(WRITE_BUFFER, out),
                    written: 0,
                }
            }
        };
        Ok(AtomicFile { path, inner })
    }

    /// Like [`AtomicFile::create`], for a format that needs seeking (`what`, such as "a GeoTIFF"):
    /// a FIFO, a device or standard output is refused before anything is written.
    ///
    /// # Errors
    /// As [`AtomicFile::create`]; [`Error::Options`] for a stream.
    pub fn create_seekable(path: impl Into<PathBuf>, what: &str) -> Result<Self> {
        let path = path.into();
        if let Destination::Stream { what: kind, .. } = Destination::of(&path)? {
            return Err(Error::Options(format!(
                "{}: {what} cannot be written to {kind} (the format needs seeking): write it to \
                 a file",
                path.display()
            )));
        }
        Self::create(path)
    }

    fn temp_beside(path: &Path, target: PathBuf, mode: Option<u32>) -> Result<Inner> {
        let Some(name) = target.file_name() else {
            return Err(Error::Output {
                path: path.to_path_buf(),
                message: "not a file name".into(),
            });
        };
        remove_stale_temps(&target);
        let prefix = temp_prefix(&name.to_string_lossy());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp").rand_bytes(6);
        #[cfg(unix)]
        {
            // Temporary files are owner-only by default; an output should get the usual
            // umask-restricted permissions, like any file the user creates.
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let dir = parent_dir(&target);
        let temp = builder.tempfile_in(dir).map_err(|e| {
            // tempfile's own message names the random temporary path; say what the user needs.
            if !dir.is_dir() {
                let e = io::Error::new(
                    io::ErrorKind::NotFound,
                    format!("directory {} does not exist", dir.display()),
                );
                return Error::write(path, e);
            }
            Error::write(path, e)
        })?;
        let registration = register_temp(temp.path(), TempKind::File);
        Ok(Inner::Replace {
            target,
            mode,
            writer: BufWriter::with_capacity(WRITE_BUFFER, temp),
            behind: (0, 0),
            upload: false,
            _registration: registration,
        })
    }

    /// The final path, as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Is this output written directly to a FIFO, a device or standard output (no temporary
    /// file, no seeking)?
    pub fn is_stream(&self) -> bool {
        matches!(self.inner, Inner::Stream { .. })
    }

    /// The temporary file being written (`None` for a stream).
    pub fn temp_path(&self) -> Option<&Path> {
        match &self.inner {
            Inner::Replace { writer, .. } => Some(writer.get_ref().path()),
            Inner::Stream { .. } => None,
        }
    }

    /// Wraps an I/O error with the final path.
    pub fn err(&self, e: io::Error) -> Error {
        Error::write(&self.path, e)
    }

    /// Flushes, fsyncs and renames the temporary file onto the final path (replacing any file
    /// there, keeping its permissions), or uploads it to the final object; returns the size of
    /// the file in bytes. A stream is flushed; its size is the bytes written.
    ///
    /// # Errors
    /// [`Error::Write`] naming the final path; the temporary file is then deleted.
    pub fn commit(self) -> Result<u64> {
        let AtomicFile { path, inner } = self;
        match inner {
            Inner::Stream {
                mut writer,
                written,
            } => {
                writer.flush().map_err(|e| Error::write(&path, e))?;
                Ok(written)
            }
            Inner::Replace {
                target,
                mode,
                writer,
                behind: _,
                upload,
                _registration,
            } => {
                let temp = writer
                    .into_inner()
                    .map_err(|e| Error::write(&path, e.into_error()))?;
                if upload {
                    let bytes = temp
                        .as_file()
                        .metadata()
                        .map_err(|e| Error::write(&path, e))?
                        .len();
                    crate::input::source::upload(&target, temp.as_file(), bytes)?;
                    return Ok(bytes);
                }
                #[cfg(unix)]
                if let Some(mode) = mode {
                    use std::os::unix::fs::PermissionsExt;
                    let perms = std::fs::Permissions::from_mode(mode);
                    std::fs::set_permissions(temp.path(), perms)
                        .map_err(|e| Error::write(&path, e))?;
                }
                #[cfg(not(unix))]
                let _ = mode;
                temp.as_file()
                    .sync_all()
                    .map_err(|e| Error::write(&path, e))?;
                let bytes = temp
                    .as_file()
                    .metadata()
                    .map_err(|e| Error::write(&path, e))?
                    .len();
                temp.persist(&target)
                    .map_err(|e| Error::write(&path, e.error))?;
                sync_dir(parent_dir(&target));
                Ok(bytes)
            }
        }
    }
}

/// Bytes written to a file between two starts of its write-behind.
const WRITE_BEHIND: u64 = 64 << 20;

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.inner {
            Inner::Replace { writer, behind, .. } => {
                // At most a piece at a time (see `crate::sort::WRITE_PIECE`).
                let n = writer.write(&buf[..buf.len().min(crate::sort::WRITE_PIECE)])?;
                behind.0 += n as u64;
                if behind.0 - behind.1 >= WRITE_BEHIND {
                    // Write-behind: the commit's `fsync` then finds most of a large output on
                    // disk already (a 629 MB PLY's took 0.30 s, all at the end).
                    crate::sort::mmap::start_writeback(writer.get_ref().as_file());
                    behind.1 = behind.0;
                }
                Ok(n)
            }
            Inner::Stream { writer, written } => {
                let n = writer.write(buf)?;
                *written += n as u64;
                Ok(n)
            }
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.inner {
            Inner::Replace { writer, .. } => writer.flush(),
            Inner::Stream { writer, .. } => writer.flush(),
        }
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        match &mut self.inner {
            Inner::Replace { writer, .. } => writer.seek(pos),
            Inner::Stream { .. } => Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "cannot seek in a stream (a FIFO, a device or standard output)",
            )),
        }
    }
}

/// The directory a path lives in (`.` for a bare file name).
pub(crate) fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Makes a rename durable by syncing its directory. Best effort: not every platform or file
/// system supports it, and the rename itself has already succeeded.
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = (dir, File::open);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// Write-behind (past [`WRITE_BEHIND`] bytes, twice) changes nothing of what is written, a
    /// header rewritten in place after the body included.
    #[test]
    fn write_behind_keeps_every_byte() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.bin");
        let n = 2 * WRITE_BEHIND as usize + 12_345;
        let want: Vec<u8> = (0..n).map(|i| (i * 7 + i / 4099) as u8).collect();
        let mut f = AtomicFile::create(&path).unwrap();
        f.write_all(&[0; 16]).unwrap();
        for piece in want[16..].chunks(3 << 20) {
            f.write_all(piece).unwrap();
        }
        f.seek(SeekFrom::Start(0)).unwrap();
        f.write_all(&want[..16]).unwrap();
        f.seek(SeekFrom::End(0)).unwrap();
        assert_eq!(f.commit().unwrap(), n as u64);
        assert!(std::fs::read(&path).unwrap() == want);
    }

    fn is_registered(path: &Path) -> bool {
        registered_temps().iter().any(|(p, _)| p == path)
    }

    #[test]
    #[cfg(unix)]
    fn a_symlink_is_followed_and_directories_are_never_replaced() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("precious.txt");
        std::fs::write(&target, b"keep").unwrap();
        std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o604)).unwrap();
        let link = dir.path().join("out.tif");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let mut f = AtomicFile::create(&link).unwrap();
        f.write_all(b"new").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        let mode = std::fs::metadata(&target).unwrap().permissions().mode();
        assert_eq!(mode & 0o7777, 0o604);
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        let e = AtomicFile::create(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains("directory") || e.contains("not a file name"),
            "{e}"
        );
        let null = AtomicFile::create("/dev/null").unwrap();
        assert!(null.is_stream());
        let e = AtomicFile::create_seekable("/dev/null", "a GeoTIFF")
            .unwrap_err()
            .to_string();
        assert!(e.contains("needs seeking"), "{e}");
    }

    #[test]
    fn commit_renames_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        let mut f = AtomicFile::create(&out).unwrap();
        let temp = f.temp_path().unwrap().to_path_buf();
        let temp_name = temp.file_name().unwrap().to_string_lossy().into_owned();
        assert!(temp_name.starts_with(".out.txt.sweeptin-") && temp_name.ends_with(".tmp"));
        assert!(temp_name.contains(&format!(".{}-", std::process::id())));
        assert!(is_registered(&temp));
        f.write_all(b"hello").unwrap();
        assert!(!out.exists(), "final path must not exist before commit");
        assert_eq!(f.commit().unwrap(), 5);
        assert_eq!(std::fs::read(&out).unwrap(), b"hello");
        assert_eq!(names(dir.path()), ["out.txt"]);
        assert!(!is_registered(&temp));
    }

    #[test]
    fn drop_without_commit_deletes_temp_and_keeps_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        std::fs::write(&out, b"old").unwrap();
        let mut f = AtomicFile::create(&out).unwrap();
        let temp = f.temp_path().unwrap().to_path_buf();
        f.write_all(b"partial").unwrap();
        drop(f);
        assert_eq!(std::fs::read(&out).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["out.txt"]);
        assert!(!is_registered(&temp));
    }

    #[test]
    fn missing_directory_is_an_io_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("no/such/dir/out.ply");
        let e = AtomicFile::create(&out).unwrap_err();
        assert!(
            matches!(&e, Error::Write { path, .. } if path == &out),
            "{e}"
        );
        assert!(e.to_string().contains("no/such/dir/out.ply"), "{e}");
    }

    #[test]
    fn bare_file_name_uses_current_directory() {
        assert_eq!(parent_dir(Path::new("out.ply")), Path::new("."));
        assert_eq!(parent_dir(Path::new("a/out.ply")), Path::new("a"));
    }

    #[cfg(unix)]
    #[test]
    fn committed_file_is_not_owner_only() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        AtomicFile::create(&out).unwrap().commit().unwrap();
        let mode = std::fs::metadata(&out).unwrap().permissions().mode();
        // Whatever the umask, "group/other" bits beyond the owner's are not forced to zero when the
        // umask allows them; at least the owner can read and write.
        assert_eq!(mode & 0o600, 0o600);
    }

    /// The clean-up the interrupt handler runs, without sending a signal, on a registry of its own
    /// (the process-wide one is shared with the other tests running in parallel).
    #[test]
    fn cleanup_deletes_registered_files_and_dirs() {
        static LOCAL: TempRegistry = TempRegistry::new();
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("spill.bin");
        std::fs::write(&file, b"x").unwrap();
        let sub = dir.path().join("spills");
        std::fs::create_dir(&sub).unwrap();
        std::fs::write(sub.join("a"), b"a").unwrap();
        let gone = dir.path().join("already-gone");
        let kept = dir.path().join("kept.bin");
        std::fs::write(&kept, b"k").unwrap();
        let r1 = LOCAL.register(file.clone(), TempKind::File);
        let _r2 = LOCAL.register(sub.clone(), TempKind::Dir);
        let _r3 = LOCAL.register(gone.clone(), TempKind::File);
        let r4 = LOCAL.register(kept.clone(), TempKind::File);
        drop(r4);
        assert_eq!(LOCAL.paths().len(), 3);
        assert_eq!(LOCAL.cleanup(), 2);
        assert!(!file.exists() && !sub.exists() && kept.exists());
        assert!(LOCAL.paths().is_empty());
        drop(r1); // unregistering after the clean-up is harmless
        assert_eq!(LOCAL.cleanup(), 0);
    }

    #[test]
    fn registered_temp_dir_is_deleted_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let t = RegisteredTempDir::new_in(dir.path()).unwrap();
        let p = t.path().to_path_buf();
        std::fs::write(p.join("chunk-0"), b"data").unwrap();
        assert!(is_registered(&p));
        drop(t);
        assert!(!p.exists());
        assert!(!is_registered(&p));
    }

    #[test]
    fn seek_back_and_rewrite() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.bin");
        let mut f = AtomicFile::create(&out).unwrap();
        f.write_all(b"AAAA-body").unwrap();
        f.seek(SeekFrom::Start(0)).unwrap();
        f.write_all(b"BBBB").unwrap();
        f.seek(SeekFrom::End(0)).unwrap();
        f.write_all(b"-end").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"BBBB-body-end");
    }
}
