//! Where a plan keeps its own files ([`PlanDir`]): `plan.json`, the chunk indexes
//! (`index/K.chunks`), the tasks' tiles and records (`tiles/`). A local directory, or an `s3://`
//! prefix for workers that share no disk: `plan`, `run`, `merge`, `report` and `--resume` read,
//! write, size and delete the plan's files only through it.
//!
//! - **Local**: each file written through a temporary file and a rename ([`AtomicFile`]), never
//!   through a symbolic link (one replaced what it pointed at, an input, once).
//! - **S3**: each object uploaded whole when complete (one `PUT`, or a multipart upload above
//!   64 MiB: [`crate::input::source::upload`]), read fresh (S3 reads are strongly consistent
//!   after writes), sized by `HEAD`, removed by `DeleteObject`. The task protocol is the local
//!   one: a task deletes its record, uploads its tiles, then its record; a record present means
//!   its tiles are complete.
//!
//! [`AtomicFile`]: crate::output::AtomicFile

use crate::error::{Error, Result};
use crate::input::source;
use std::path::{Path, PathBuf};

/// A plan's directory: a local directory or an `s3://BUCKET/PREFIX` (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PlanDir {
    /// A local directory.
    Local(PathBuf),
    /// An `s3://BUCKET/PREFIX` prefix (without its trailing `/`): the plan's files are the
    /// objects `PREFIX/plan.json`, `PREFIX/tiles/…`.
    S3(PathBuf),
}

impl PlanDir {
    /// The directory `dir` a plan is made into (`plan -o DIR`): a local path, or
    /// `s3://BUCKET/PREFIX/`.
    ///
    /// # Errors
    /// [`Error::Options`] for an `http(s)://` URL (a server cannot be written), and for an
    /// `s3://` URL without a bucket or a prefix.
    pub fn new(dir: &Path) -> Result<PlanDir> {
        match source::Location::of(dir) {
            source::Location::Local(p) => Ok(PlanDir::Local(p)),
            source::Location::Http(u) => Err(Error::Options(format!(
                "{u}: a plan's directory is a local directory or an s3://BUCKET/PREFIX/ (an \
                 HTTP server cannot be written)"
            ))),
            source::Location::S3 { bucket, key } => {
                let prefix = key.trim_end_matches('/');
                if bucket.is_empty() || prefix.is_empty() {
                    return Err(Error::Options(format!(
                        "{}: a plan's directory on S3 is a prefix in a bucket: write \
                         s3://BUCKET/JOB/",
                        dir.display()
                    )));
                }
                Ok(PlanDir::S3(PathBuf::from(format!(
                    "s3://{bucket}/{prefix}"
                ))))
            }
        }
    }

    /// The directory of the plan file `path` (`DIR/plan.json`, or
    /// `s3://BUCKET/PREFIX/plan.json`), a local one made absolute (task records then name their
    /// outputs wherever the task ran from).
    ///
    /// # Errors
    /// [`Error::Io`] when a local path cannot be made absolute; [`PlanDir::new`]'s.
    pub fn of_plan(path: &Path) -> Result<PlanDir> {
        if source::is_remote(path) {
            let text = path.to_string_lossy();
            let parent = text.rsplit_once('/').map_or("", |(d, _)| d);
            return PlanDir::new(Path::new(parent));
        }
        let abs = std::path::absolute(path).map_err(|e| Error::io(path, e))?;
        Ok(PlanDir::Local(match abs.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }))
    }

    /// The directory as a path (an `s3://` URL for S3).
    pub fn path(&self) -> &Path {
        match self {
            PlanDir::Local(p) | PlanDir::S3(p) => p,
        }
    }

    /// The plan's file `rel` (`plan.json`, `tiles/task_0.json`): a path, or an `s3://` URL.
    pub fn join(&self, rel: impl AsRef<Path>) -> PathBuf {
        self.path().join(rel)
    }

    /// For messages.
    pub fn display(&self) -> std::path::Display<'_> {
        self.path().display()
    }

    /// Whether the plan's files are `s3://` objects.
    pub fn is_remote(&self) -> bool {
        matches!(self, PlanDir::S3(_))
    }

    /// Checks, before any work, that the plan's files can be written there: an S3 prefix's
    /// bucket exists ([`source::check_destination`]); a local path is not a file.
    ///
    /// # Errors
    /// [`Error::Write`] for no such bucket (exit 4); [`Error::Options`] for a local file.
    pub fn check_writable(&self) -> Result<()> {
        match self {
            PlanDir::S3(_) => source::check_destination(&self.join("plan.json")),
            PlanDir::Local(d) if d.exists() && !d.is_dir() => Err(Error::Options(format!(
                "{}: not a directory (a plan is made into a directory)",
                d.display()
            ))),
            PlanDir::Local(_) => Ok(()),
        }
    }

    /// Makes the directory `rel` of a local plan (`tiles`, `index`); nothing on S3, whose
    /// prefixes need no making.
    ///
    /// # Errors
    /// [`Error::Write`].
    pub(super) fn make_dir(&self, rel: &str) -> Result<()> {
        match self {
            PlanDir::S3(_) => Ok(()),
            PlanDir::Local(_) => {
                let d = self.join(rel);
                std::fs::create_dir_all(&d).map_err(|e| Error::write(&d, e))
            }
        }
    }

    /// Makes `DIR/tiles/` again when it is missing (deleted to start over); refuses one that
    /// is not a directory of its own. Nothing on S3.
    ///
    /// # Errors
    /// [`Error::Options`] for a symbolic link or a file there; [`Error::Io`].
    pub(super) fn tiles(&self) -> Result<()> {
        match self {
            PlanDir::S3(_) => Ok(()),
            PlanDir::Local(d) => super::files::tiles_dir(d),
        }
    }

    /// Refuses a local file of the plan that is a symbolic link or not a regular file
    /// ([`super::files::own_file`]); an S3 object is always the plan's own.
    ///
    /// # Errors
    /// [`Error::Options`] naming the path.
    pub(super) fn own_file(&self, p: &Path) -> Result<()> {
        match self {
            PlanDir::S3(_) => Ok(()),
            PlanDir::Local(_) => super::files::own_file(p),
        }
    }

    /// The bytes of the plan's file `p`, `None` when there is none.
    ///
    /// # Errors
    /// [`Error::Io`] naming it; [`PlanDir::own_file`]'s.
    pub(super) fn read(&self, p: &Path) -> Result<Option<Vec<u8>>> {
        self.own_file(p)?;
        match self {
            PlanDir::S3(_) => source::read_object(p),
            PlanDir::Local(_) => match std::fs::read(p) {
                Ok(b) => Ok(Some(b)),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
                Err(e) => Err(Error::io(p, e)),
            },
        }
    }

    /// The text of the plan's file `p` (a record, the plan), `None` when there is none.
    ///
    /// # Errors
    /// As [`PlanDir::read`]; [`Error::Io`] for text that is not UTF-8.
    pub(super) fn read_to_string(&self, p: &Path) -> Result<Option<String>> {
        self.read(p)?
            .map(|b| {
                String::from_utf8(b).map_err(|e| {
                    Error::io(p, std::io::Error::new(std::io::ErrorKind::InvalidData, e))
                })
            })
            .transpose()
    }

    /// Writes the plan's file `p` whole or not at all (a local rename, or an upload).
    ///
    /// # Errors
    /// [`PlanDir::own_file`]'s; [`Error::Write`] naming it.
    pub(super) fn write(&self, p: &Path, bytes: &[u8]) -> Result<()> {
        use std::io::Write;
        self.own_file(p)?;
        let mut f = crate::output::AtomicFile::create(p)?;
        f.write_all(bytes).map_err(|e| Error::write(p, e))?;
        f.commit()?;
        Ok(())
    }

    /// The size of the plan's file `p` (a regular file, an object: `HEAD`), `None` when there
    /// is none.
    ///
    /// # Errors
    /// [`Error::Io`] for an S3 request that fails (access denied, no answer).
    pub(super) fn size(&self, p: &Path) -> Result<Option<u64>> {
        match self {
            PlanDir::S3(_) => source::object_size(p),
            PlanDir::Local(_) => Ok(std::fs::metadata(p)
                .ok()
                .filter(|m| m.is_file())
                .map(|m| m.len())),
        }
    }

    /// Removes the plan's file `p`, if there is one.
    ///
    /// # Errors
    /// [`PlanDir::own_file`]'s; [`Error::Write`] naming it.
    pub(super) fn remove(&self, p: &Path) -> Result<()> {
        self.own_file(p)?;
        match self {
            PlanDir::S3(_) => source::delete_object(p),
            PlanDir::Local(_) => match std::fs::remove_file(p) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::write(p, e)),
                _ => Ok(()),
            },
        }
    }

    /// A task record (`tiles/task_…`) there, of whatever plan, if any: the name of one.
    ///
    /// # Errors
    /// [`Error::Io`] for an S3 listing that fails.
    pub(super) fn any_record(&self) -> Result<Option<String>> {
        let name = |p: &Path| {
            p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        match self {
            PlanDir::S3(_) => Ok(source::first_object(&self.join("tiles/task_"))?
                .as_deref()
                .map(name)),
            PlanDir::Local(_) => Ok(std::fs::read_dir(self.join("tiles"))
                .into_iter()
                .flatten()
                .flatten()
                .map(|e| name(&e.path()))
                .find(|n| n.starts_with("task_"))),
        }
    }

    /// The plan's file `p` as a local file to open (a tile the merge reads): itself, or for an
    /// S3 object a copy in the temporary directory, removed when the copy is dropped.
    ///
    /// # Errors
    /// [`Error::Io`] naming the object; [`Error::Write`] for the temporary copy.
    pub(super) fn local(&self, p: &Path) -> Result<LocalCopy> {
        if !self.is_remote() {
            return Ok(LocalCopy {
                path: p.to_path_buf(),
                _temp: None,
            });
        }
        let tmp = std::env::temp_dir();
        let mut temp = tempfile::Builder::new()
            .prefix(".sweeptin-tile-")
            .tempfile_in(&tmp)
            .map_err(|e| Error::write(&tmp, e))?;
        let _registered = crate::output::atomic::register_temp(
            temp.path().to_path_buf(),
            crate::output::atomic::TempKind::File,
        );
        let src = source::Source::open(p)?;
        std::io::copy(&mut src.reader(), temp.as_file_mut()).map_err(|e| Error::io(p, e))?;
        Ok(LocalCopy {
            path: temp.path().to_path_buf(),
            _temp: Some((temp, _registered)),
        })
    }

    /// Refuses an output of the whole job (`what` at `p`: the mosaic, `--contours`, the
    /// report) that would be written among the plan's own files: `plan.json`, or under
    /// `tiles/` (for a local directory with `..` and links resolved).
    ///
    /// # Errors
    /// [`Error::Options`] naming the output.
    pub(crate) fn outside(&self, what: &str, p: &Path) -> Result<()> {
        match self {
            PlanDir::Local(d) => super::files::outside_plan_dir(d, what, p),
            PlanDir::S3(d) => {
                // By bucket and key (the scheme in any case: `S3://` is the same object).
                let (
                    source::Location::S3 { bucket, key },
                    source::Location::S3 {
                        bucket: b,
                        key: written,
                    },
                ) = (source::Location::of(d), source::Location::of(p))
                else {
                    return Ok(());
                };
                let written = written.trim_end_matches('/');
                let tiles = format!("{key}/tiles");
                if b == bucket
                    && (written == format!("{key}/plan.json")
                        || written == tiles
                        || written.starts_with(&format!("{tiles}/")))
                {
                    return Err(super::files::among_plan_files(what, p));
                }
                Ok(())
            }
        }
    }
}

/// A local file of a plan's S3 object ([`PlanDir::local`]): deleted when dropped.
pub(super) struct LocalCopy {
    /// The file to open.
    pub(super) path: PathBuf,
    _temp: Option<(
        tempfile::NamedTempFile,
        crate::output::atomic::TempRegistration,
    )>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_s3_plan_dir_is_a_prefix_and_its_files_are_keys_under_it() {
        let d = PlanDir::new(Path::new("s3://jobs/a/job/")).unwrap();
        assert_eq!(d, PlanDir::S3(PathBuf::from("s3://jobs/a/job")));
        assert_eq!(
            d.join("tiles").join("task_3.json"),
            Path::new("s3://jobs/a/job/tiles/task_3.json")
        );
        let of = PlanDir::of_plan(Path::new("s3://jobs/a/job/plan.json")).unwrap();
        assert_eq!(of, d);
        // A record names its outputs relative to the directory.
        let tile = d.join("tiles/dem_1_2.tif");
        assert_eq!(
            tile.strip_prefix(d.path()).unwrap(),
            Path::new("tiles/dem_1_2.tif")
        );
        for bad in ["s3://jobs/", "s3://jobs", "https://host/job/"] {
            assert!(
                matches!(PlanDir::new(Path::new(bad)), Err(Error::Options(_))),
                "{bad}"
            );
        }
    }

    #[test]
    fn outputs_among_an_s3_plans_files_are_refused() {
        let d = PlanDir::new(Path::new("s3://jobs/job")).unwrap();
        for own in [
            "s3://jobs/job/plan.json",
            "s3://jobs/job/tiles/m.tif",
            "S3://jobs/job/tiles/m.tif",
            "s3://jobs/job/tiles",
        ] {
            assert!(d.outside("the mosaic", Path::new(own)).is_err(), "{own}");
        }
        for other in [
            "s3://jobs/job/m.tif",
            "s3://jobs/jobs/tiles/m.tif",
            "s3://other/job/tiles/m.tif",
            "m.tif",
        ] {
            assert!(d.outside("the mosaic", Path::new(other)).is_ok(), "{other}");
        }
    }
}
