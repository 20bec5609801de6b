//! What a plan pins on disk: its input files' size and modification time ([`FileStamp`]), and
//! its own files (`plan.json`, the tasks' outputs and records), written atomically and never
//! through a link ([`own_file`]).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

impl super::Plan {
    /// The paths of the plan's files that hold points, in the plan's order.
    pub(super) fn paths_with_points(&self) -> Vec<PathBuf> {
        self.files
            .iter()
            .filter(|f| f.points > 0)
            .map(|f| f.path.clone())
            .collect()
    }

    /// Every file the job reads, or was made from: the points' files and the lists and `.vpc`
    /// files that named them, the line files (a GeoPackage without its layer) and a volume's
    /// boundary. No output of the plan or of its merge may replace one.
    pub fn read_files(&self) -> Vec<PathBuf> {
        let mut read: Vec<PathBuf> = self.files.iter().map(|f| f.path.clone()).collect();
        read.extend(self.lists.iter().cloned());
        let boundary = match &self.job.product {
            super::Product::Volume { boundary, .. } => boundary.as_ref(),
            _ => None,
        };
        let lines = self
            .job
            .lines
            .iter()
            .flat_map(|l| l.files())
            .chain(boundary);
        read.extend(lines.map(|f| crate::input::vector::split_layer(&f.path).0));
        read
    }

    /// Refuses, when the plan is made, outputs of the job (`--contours`, `--hillshade`) that
    /// are files it reads ([`Plan::read_files`]) or each other.
    ///
    /// # Errors
    /// [`crate::output::distinct_outputs`]'.
    pub(super) fn check_outputs(&self) -> Result<()> {
        let planned: Vec<(&str, &Path)> = self
            .outputs
            .iter()
            .filter(|(n, _)| n != "dir")
            .map(|(n, p)| (n.as_str(), p.as_path()))
            .collect();
        // An input named as an output is said first (it is the graver mistake).
        crate::output::distinct_outputs(&planned, &self.read_files(), "the plan")?;
        if let Some((_, c)) = planned.iter().find(|(n, _)| *n == "contours") {
            crate::output::lines::LineFormat::of(c)?;
        }
        Ok(())
    }
}

/// A file's size and modification time ([`super::PlanFile::stamp`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileStamp {
    /// Bytes.
    pub bytes: u64,
    /// Seconds since 1970-01-01 UTC.
    pub modified: i64,
    /// And nanoseconds.
    pub nanos: u32,
}

impl FileStamp {
    /// The stamp of the file at `path` now.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn of(path: &Path) -> Result<FileStamp> {
        let m = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        let t = m.modified().map_err(|e| Error::io(path, e))?;
        let (modified, nanos) = match t.duration_since(std::time::UNIX_EPOCH) {
            Ok(d) => (
                i64::try_from(d.as_secs()).unwrap_or(i64::MAX),
                d.subsec_nanos(),
            ),
            Err(e) => (
                -i64::try_from(e.duration().as_secs()).unwrap_or(i64::MAX),
                e.duration().subsec_nanos(),
            ),
        };
        Ok(FileStamp {
            bytes: m.len(),
            modified,
            nanos,
        })
    }
}

/// Refuses a file of the plan's directory (the plan, a task's output or record) that is a
/// symbolic link or not a regular file: the directory holds only what sweeptin writes there, and
/// writing through a link replaced what it pointed at (an input, once).
///
/// # Errors
/// [`Error::Options`] naming the path.
pub(super) fn own_file(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.file_type().is_file() => Err(Error::Options(format!(
            "{}: {} where the plan keeps its own file: sweeptin writes only regular files in a \
             plan's directory (remove it)",
            path.display(),
            if m.file_type().is_symlink() {
                "a symbolic link"
            } else {
                "not a regular file"
            }
        ))),
        _ => Ok(()),
    }
}

pub(super) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    own_file(path)?;
    let mut f = crate::output::AtomicFile::create(path)?;
    f.write_all(bytes).map_err(|e| Error::write(path, e))?;
    f.commit()?;
    Ok(())
}

/// Refuses an output of the whole job (`what` at `p`: the mosaic, `--contours`, `--hillshade`)
/// that would be written among the plan's own files in `dir`: `plan.json`, or under `tiles/`
/// (with `..` and links resolved, `..` lexically where a directory is not made yet).
///
/// # Errors
/// [`Error::Options`] naming the output.
pub(crate) fn outside_plan_dir(dir: &Path, what: &str, p: &Path) -> Result<()> {
    let written = lexical(&crate::output::target::written_path(p));
    let own = std::path::absolute(dir).map_err(|e| Error::io(dir, e))?;
    let own = std::fs::canonicalize(&own).unwrap_or_else(|_| lexical(&own));
    let tiles = std::fs::canonicalize(own.join("tiles")).unwrap_or(own.join("tiles"));
    if written == own.join("plan.json") || written.starts_with(&tiles) {
        return Err(among_plan_files(what, p));
    }
    Ok(())
}

/// The refusal of an output of the whole job (`what` at `p`) among the plan's own files.
pub(super) fn among_plan_files(what: &str, p: &Path) -> Error {
    Error::Options(format!(
        "{what} {}: that is where the tasks' outputs are, or the plan: a plan's directory keeps \
         its own files (plan.json, tiles/); write the job's outputs elsewhere",
        p.display()
    ))
}

/// `p` with `.` and `..` taken lexically.
fn lexical(p: &Path) -> std::path::PathBuf {
    let mut out = std::path::PathBuf::new();
    for c in p.components() {
        match c {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

/// `out`, a task's output as its record names it, under the plan's directory `dir`; `None`
/// when it is absolute or climbs out of `dir` (`..`): a record names only its own tiles.
pub(super) fn inside(dir: &Path, out: &Path) -> Option<PathBuf> {
    use std::path::Component;
    let plain = out
        .components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    (plain && out.components().next().is_some()).then(|| dir.join(out))
}

/// Makes `DIR/tiles/` again when it is missing (deleted to start over: every task then
/// failed, exit 4); refuses one that is not a directory of its own.
///
/// # Errors
/// [`Error::Options`] for a symbolic link or a file there; [`Error::Io`].
pub(super) fn tiles_dir(dir: &Path) -> Result<()> {
    let t = dir.join("tiles");
    match std::fs::symlink_metadata(&t) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(Error::Options(format!(
            "{}: not a directory of the plan's own (a symbolic link or a file): sweeptin \
             writes its tiles only into a directory it made (remove it)",
            t.display()
        ))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::create_dir_all(&t).map_err(|e| Error::write(&t, e))
        }
        Err(e) => Err(Error::io(&t, e)),
    }
}
