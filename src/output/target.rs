//! Where an output's bytes go, decided once from what is at the output path
//! ([`Destination::of`]), and the temporary files of dead runs.
//!
//! | at the path | what happens |
//! |---|---|
//! | nothing, or a regular file | a temporary file beside it, renamed onto it when complete; an existing file keeps its permissions |
//! | a symbolic link | followed (links to links too): its **target** is replaced as above, the link stays; a dangling link's target is created |
//! | a FIFO, a character device (`/dev/null`, a terminal), `-` (standard output), `/dev/stdout`, `/dev/stderr` | written directly, as the bytes are produced ([`Destination::Stream`]); formats that need seeking (GeoTIFF) refuse it |
//! | a directory, a block device, a socket | refused: an output never replaces them |
//! | `s3://bucket/key` | its bucket checked before the work ([`check_output`]); a temporary file in the system's temporary directory, uploaded when complete (one `PUT`, or a multipart upload above 64 MiB) ([`Destination::Object`]): the object appears whole or not at all |
//! | `http://…`, `https://…` | refused: outputs go to files or S3 objects |
//!
//! Temporary files are named `.NAME.sweeptin-HOST.PID-XXXXXX.tmp` ([`temp_prefix`]). A run that
//! was killed (`kill -9`, the OOM killer) cannot delete its own; the next run writing the same
//! output does ([`remove_stale_temps`]), when the file was made on this host by a process that is
//! no longer running.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Where the bytes of an output go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Destination {
    /// A regular file (existing or not): written under a temporary name beside it and renamed
    /// onto it when complete.
    File {
        /// The file to replace (a symbolic link's target, resolved).
        target: PathBuf,
        /// Permission bits of the existing file, kept by the replacement.
        mode: Option<u32>,
    },
    /// An `s3://` object: written to a temporary file, uploaded when complete.
    Object {
        /// The object's URL.
        url: PathBuf,
    },
    /// A FIFO, a character device or standard output: written directly, in order.
    Stream {
        /// Standard output or standard error (`-`, `/dev/stdout`, `/dev/stderr`): the process's
        /// own descriptor (1 or 2), not a new opening of it.
        fd: Option<u8>,
        /// What it is, for messages ("a FIFO", "a character device", "standard output").
        what: &'static str,
    },
}

impl Destination {
    /// Decides where `path`'s bytes go (see the module docs).
    ///
    /// # Errors
    /// [`Error::Output`] for a directory, a block device or a socket (or a link to one), or a
    /// chain of more than 40 symbolic links; [`Error::Write`] when the path cannot be examined.
    pub fn of(path: &Path) -> Result<Destination> {
        match crate::input::source::Location::of(path) {
            crate::input::source::Location::Local(_) => {}
            crate::input::source::Location::S3 { bucket, key } => {
                if bucket.is_empty() || key.is_empty() || key.ends_with('/') {
                    return Err(Error::Output {
                        path: path.to_path_buf(),
                        message: "not an S3 object name: write s3://BUCKET/KEY, the key \
                                  naming a file (not ending in /)"
                            .into(),
                    });
                }
                return Ok(Destination::Object {
                    url: path.to_path_buf(),
                });
            }
            crate::input::source::Location::Http(_) => {
                return Err(Error::Output {
                    path: path.to_path_buf(),
                    message: "an HTTP URL: outputs go to local files or s3:// objects".into(),
                });
            }
        }
        if path.as_os_str() == "-" {
            return Ok(Destination::Stream {
                fd: Some(1),
                what: "standard output",
            });
        }
        let refuse = |what: &str| Error::Output {
            path: path.to_path_buf(),
            message: format!("it is {what}: an output never replaces one (give a file name)"),
        };
        let mut at = path.to_path_buf();
        for _ in 0..40 {
            let meta = match std::fs::symlink_metadata(&at) {
                Ok(m) => m,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    return Ok(Destination::File {
                        target: at,
                        mode: None,
                    });
                }
                Err(e) => return Err(Error::write(path, e)),
            };
            let t = meta.file_type();
            if t.is_symlink() {
                let link = std::fs::read_link(&at).map_err(|e| Error::write(path, e))?;
                if let Some(fd) = std_descriptor(&link) {
                    return Ok(Destination::Stream {
                        fd: Some(fd),
                        what: if fd == 1 {
                            "standard output"
                        } else {
                            "standard error"
                        },
                    });
                }
                at = match at.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
                continue;
            }
            if t.is_file() {
                return Ok(Destination::File {
                    target: at,
                    mode: mode_of(&meta),
                });
            }
            if t.is_dir() {
                return Err(refuse("a directory"));
            }
            #[cfg(unix)]
            {
                use std::os::unix::fs::FileTypeExt;
                if t.is_fifo() {
                    return Ok(Destination::Stream {
                        fd: None,
                        what: "a FIFO",
                    });
                }
                if t.is_char_device() {
                    return Ok(Destination::Stream {
                        fd: None,
                        what: "a character device",
                    });
                }
                if t.is_block_device() {
                    return Err(refuse("a block device"));
                }
            }
            return Err(refuse("a socket or special file"));
        }
        Err(refuse("a chain of more than 40 symbolic links"))
    }

    /// Is it written directly (no temporary file, no seeking)?
    pub fn is_stream(&self) -> bool {
        matches!(self, Destination::Stream { .. })
    }

    /// Is it a whole file (local or an object): side files can go beside it?
    pub fn is_whole(&self) -> bool {
        !self.is_stream()
    }
}

/// `Some(1)` / `Some(2)` for a link to this process's standard output / error
/// (`/proc/self/fd/1`, `/dev/fd/2`, …).
fn std_descriptor(link: &Path) -> Option<u8> {
    let s = link.to_str()?;
    let fd = s
        .strip_prefix("/proc/self/fd/")
        .or_else(|| s.strip_prefix("/dev/fd/"))?;
    match fd {
        "1" => Some(1),
        "2" => Some(2),
        _ => None,
    }
}

#[cfg(unix)]
fn mode_of(meta: &std::fs::Metadata) -> Option<u32> {
    use std::os::unix::fs::PermissionsExt;
    Some(meta.permissions().mode() & 0o7777)
}

#[cfg(not(unix))]
fn mode_of(_meta: &std::fs::Metadata) -> Option<u32> {
    None
}

/// The directory where scratch files of the output `path` go: beside a regular file (so a
/// large scratch file is on the disk the output goes to), the system's temporary directory for
/// a stream (never `/dev`).
pub fn scratch_dir(path: &Path) -> PathBuf {
    match Destination::of(path) {
        Ok(Destination::File { target, .. }) => super::atomic::parent_dir(&target).to_path_buf(),
        _ => std::env::temp_dir(),
    }
}

/// Fails early (before any heavy work) if an output cannot be created at `path`: a directory,
/// block device or socket in the way ([`Destination::of`]), a missing directory, an `s3://`
/// object's missing bucket or silent endpoint (one `HEAD` on the bucket,
/// [`crate::input::source::check_destination`]). Streams pass.
///
/// # Errors
/// [`Error::Output`] for what is in the way, [`Error::Write`] for a missing directory or
/// bucket.
pub fn check_output(path: &Path) -> Result<()> {
    let target = match Destination::of(path)? {
        Destination::File { target, .. } => target,
        Destination::Object { url } => return crate::input::source::check_destination(&url),
        Destination::Stream { .. } => return Ok(()),
    };
    let dir = super::atomic::parent_dir(&target);
    if !dir.is_dir() {
        let e = std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!(
                "cannot write: the directory {} does not exist",
                dir.display()
            ),
        );
        return Err(Error::write(path, e));
    }
    Ok(())
}

/// The file an output at `path` writes, as a canonical path: through symbolic links, its
/// directory's `..` and links resolved (what `starts_with` can compare with a canonical
/// directory). A stream, or a path that cannot be resolved, is returned absolute; an `s3://`
/// object as given.
pub fn written_path(path: &Path) -> PathBuf {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let target = match Destination::of(path) {
        Ok(Destination::File { target, .. }) => target,
        Ok(Destination::Object { url }) => return url,
        _ => return abs(path),
    };
    let dir = super::atomic::parent_dir(&target);
    match (std::fs::canonicalize(dir), target.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => abs(&target),
    }
}

/// Is `a` the same file as `b`: the same absolute path, the same file (device and inode) when
/// both exist, or the same file an output there would write (through symbolic links)?
fn same_file(a: &Path, b: &Path) -> bool {
    use crate::input::source::Location;
    let (la, lb) = (Location::of(a), Location::of(b));
    if la.is_remote() || lb.is_remote() {
        // Objects are the same when their scheme (any case), bucket and key are.
        return la == lb;
    }
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    if abs(a) == abs(b) {
        return true;
    }
    #[cfg(unix)]
    if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        use std::os::unix::fs::MetadataExt;
        return (x.dev(), x.ino()) == (y.dev(), y.ino());
    }
    let target = |p: &Path| match Destination::of(p) {
        Ok(Destination::File { target, .. }) => Some(abs(&target)),
        _ => std::fs::canonicalize(p).ok(),
    };
    matches!((target(a), target(b)), (Some(x), Some(y)) if x == y)
}

/// Is `p` a character device (`/dev/null`): several outputs may all go there.
fn is_char_device(p: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        std::fs::metadata(p).is_ok_and(|m| m.file_type().is_char_device())
    }
    #[cfg(not(unix))]
    {
        let _ = p;
        false
    }
}

/// The side files an output at `path` writes beside it: an ESRI ASCII grid's `.prj`, a PNG's
/// world file, `.prj` and `.png.aux.xml` (none beside a stream).
pub fn side_files(path: &Path) -> Vec<PathBuf> {
    if !Destination::of(path).is_ok_and(|d| d.is_whole()) {
        return Vec::new();
    }
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    match ext.to_ascii_lowercase().as_str() {
        "asc" => vec![path.with_extension("prj")],
        "png" => vec![
            super::world::world_file_path(path),
            path.with_extension("prj"),
            super::world::aux_xml_path(path),
        ],
        _ => Vec::new(),
    }
}

/// The files read beside an input at `path`: a shapefile's `.prj`, `.shx`, `.dbf` and `.cpg`,
/// an ESRI ASCII grid's `.prj`; beside the path as given and beside the file a symbolic link
/// leads to (for `--breaklines link.shp` with `link.shp -> lines.shp`, `-o lines.asc` replaced
/// `lines.prj`). And the files a virtual point cloud names, which the reader opens through it
/// (`tin tiles.vpc -o a.laz` replaced a tile); one that cannot be read names none here (the run
/// reports it).
fn input_side_files(path: &Path) -> Vec<PathBuf> {
    if crate::input::las::vpc::is_vpc(path) {
        return crate::input::las::vpc::read(path)
            .map(|v| v.into_iter().map(|e| e.path).collect())
            .unwrap_or_default();
    }
    let mut names = vec![path.to_path_buf()];
    if let Ok(real) = std::fs::canonicalize(path)
        && real != path
    {
        names.push(real);
    }
    let mut out = Vec::new();
    for p in names {
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
        let others: &[&str] = match ext.to_ascii_lowercase().as_str() {
            "shp" => &["prj", "shx", "dbf", "cpg"],
            "asc" => &["prj"],
            _ => &[],
        };
        out.extend(others.iter().map(|e| p.with_extension(e)));
    }
    out
}

/// The `.prj` an ESRI ASCII grid asked for by `--format asc` writes beside `path` when its
/// extension is not `.asc` (which [`side_files`] finds by itself): `dem --format asc -o x.txt`
/// writes `x.prj`, which the callers list among the outputs.
pub fn ascii_grid_prj(path: &Path, format: Option<super::raster::RasterFormat>) -> Option<PathBuf> {
    let by_extension = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("asc"));
    let file = Destination::of(path).is_ok_and(|d| d.is_whole());
    (format == Some(super::raster::RasterFormat::Ascii) && !by_extension && file)
        .then(|| path.with_extension("prj"))
}

/// Refuses, before any work, outputs (`(flag, path)`) that are the same file as each other or
/// as one of the `inputs` of `of` (the run, the plan): compared by absolute path, by device and
/// inode where they exist, and through symbolic links. Several outputs may go to one character
/// device (`/dev/null`). An output never overwrites an input or another output. The outputs'
/// side files ([`side_files`]) count as outputs, and one in the way (a directory, a FIFO) is
/// refused too: a `.prj` through a symbolic link replaced an input.
///
/// # Errors
/// [`Error::Options`] naming the clash; [`Error::Output`] for a side file in the way.
pub fn distinct_outputs(outputs: &[(&str, &Path)], inputs: &[PathBuf], of: &str) -> Result<()> {
    let mut all: Vec<(String, PathBuf)> = outputs
        .iter()
        .map(|(f, o)| (f.to_string(), o.to_path_buf()))
        .collect();
    for (flag, o) in outputs {
        for side in side_files(o) {
            if !Destination::of(&side)?.is_whole() {
                return Err(Error::Output {
                    path: side,
                    message: format!(
                        "the side file of {flag} {} is not a regular file: a side file never \
                         replaces one",
                        o.display()
                    ),
                });
            }
            all.push((format!("the side file of {flag}"), side));
        }
    }
    // An input's own side files are read with it: a shapefile's `.prj`, `.shx` and `.dbf`, an
    // ASCII grid's `.prj` (`dem -o lines.asc --breaklines lines.shp` replaced the lines' CRS).
    let read: Vec<PathBuf> = inputs
        .iter()
        .flat_map(|i| std::iter::once(i.clone()).chain(input_side_files(i)))
        .collect();
    for (k, (flag, o)) in all.iter().enumerate() {
        if let Some(i) = read.iter().find(|i| same_file(o, i)) {
            return Err(Error::Options(format!(
                "{flag} {}: that is an input of {of} ({}); an output never overwrites one",
                o.display(),
                i.display()
            )));
        }
        if is_char_device(o) {
            continue;
        }
        if let Some((other, _)) = all[..k].iter().find(|(_, p)| same_file(o, p)) {
            return Err(Error::Options(format!(
                "{flag} and {other} name the same file {}",
                o.display()
            )));
        }
    }
    Ok(())
}

/// This host's name, reduced to `[A-Za-z0-9-]` (from `/proc/sys/kernel/hostname`; `host`
/// when unknown).
fn host() -> String {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let clean: String = name
        .trim()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .take(64)
        .collect();
    if clean.is_empty() {
        "host".into()
    } else {
        clean
    }
}

/// The name prefix of the temporary files of `file_name` made by this process:
/// `.NAME.sweeptin-HOST.PID-` (six random characters and `.tmp` follow).
pub fn temp_prefix(file_name: &str) -> String {
    format!(".{file_name}.sweeptin-{}.{}-", host(), std::process::id())
}

/// Is the process `pid` of this host still running? (`/proc/PID` exists; without `/proc`,
/// every process counts as running, so nothing is removed.)
fn running(pid: u32) -> bool {
    if !Path::new("/proc/self").exists() {
        return true;
    }
    Path::new("/proc").join(pid.to_string()).exists()
}

/// Deletes the temporary files that runs of this host, now dead, left beside `target` (see the
/// module docs); returns how many. Files of live processes, of other hosts, and anything not
/// named like a temporary file of `target` are left alone. Errors are ignored: this is
/// housekeeping.
pub fn remove_stale_temps(target: &Path) -> usize {
    let (Some(name), dir) = (target.file_name(), super::atomic::parent_dir(target)) else {
        return 0;
    };
    let lead = format!(".{}.sweeptin-", name.to_string_lossy());
    let (me, here) = (std::process::id(), host());
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(rest) = file
            .to_str()
            .and_then(|f| f.strip_prefix(&lead))
            .and_then(|f| f.strip_suffix(".tmp"))
        else {
            continue;
        };
        // HOST.PID-XXXXXX
        let Some((host_pid, _random)) = rest.rsplit_once('-') else {
            continue;
        };
        let Some((h, pid)) = host_pid.rsplit_once('.') else {
            continue;
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if h == here && pid != me && is_file && !running(pid) {
            removed += usize::from(std::fs::remove_file(entry.path()).is_ok());
        }
    }
    removed
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn what_is_at_the_path_decides() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let file = d.join("a.ply");
        assert_eq!(
            Destination::of(&file).unwrap(),
            Destination::File {
                target: file.clone(),
                mode: None
            }
        );
        std::fs::write(&file, b"x").unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o640)).unwrap();
        assert_eq!(
            Destination::of(&file).unwrap(),
            Destination::File {
                target: file.clone(),
                mode: Some(0o640)
            }
        );
        // A link to a link to the file; a dangling relative link.
        std::os::unix::fs::symlink("a.ply", d.join("l1")).unwrap();
        std::os::unix::fs::symlink(d.join("l1"), d.join("l2")).unwrap();
        let Destination::File { target, .. } = Destination::of(&d.join("l2")).unwrap() else {
            panic!("not a file")
        };
        assert_eq!(target, file);
        std::os::unix::fs::symlink("new.ply", d.join("dangling")).unwrap();
        let Destination::File { target, mode } = Destination::of(&d.join("dangling")).unwrap()
        else {
            panic!("not a file")
        };
        assert_eq!((target, mode), (d.join("new.ply"), None));
        assert!(Destination::of(Path::new("-")).unwrap().is_stream());
        assert!(Destination::of(Path::new("/dev/null")).unwrap().is_stream());
        let e = Destination::of(d).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        std::os::unix::fs::symlink("l3", d.join("l3")).unwrap();
        let e = Destination::of(&d.join("l3")).unwrap_err().to_string();
        assert!(e.contains("symbolic links"), "{e}");
    }

    #[test]
    fn stale_temps_of_dead_processes_only() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("dem.tif");
        let h = host();
        // pid 0 is never a user process; our own pid is running.
        let dead = dir
            .path()
            .join(format!(".dem.tif.sweeptin-{h}.4000000000-abcdef.tmp"));
        let mine = dir
            .path()
            .join(format!("{}xyzxyz.tmp", temp_prefix("dem.tif")));
        let other_host = dir
            .path()
            .join(".dem.tif.sweeptin-elsewhere.4000000000-abcdef.tmp");
        let other_output = dir
            .path()
            .join(format!(".x.tif.sweeptin-{h}.4000000000-abcdef.tmp"));
        for f in [&dead, &mine, &other_host, &other_output] {
            std::fs::write(f, b"x").unwrap();
        }
        assert_eq!(remove_stale_temps(&out), 1);
        assert!(!dead.exists());
        assert!(mine.exists() && other_host.exists() && other_output.exists());
    }
}
