//! Breaklines and trimming rings in a plan ([`PlanLines`]).

use crate::breaklines::{Lines, Pslg};
use crate::error::{Error, Result};
use crate::pipeline::{LineOptions, ReadLines};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A line or polygon file of a plan (breaklines, trimming rings, a volume's boundary): where it
/// is and what it held when the plan was made.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LineFile {
    /// The file, absolute, as the readers take it (`FILE.gpkg:LAYER` keeps its layer).
    pub path: PathBuf,
    /// Its size in bytes.
    pub bytes: u64,
    /// The SHA-256 of its bytes, lower-case hex (what `sha256sum` prints).
    pub sha256: String,
}

impl LineFile {
    /// The file at `path` (made absolute) with its fingerprint.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn new(path: &Path) -> Result<LineFile> {
        let (file, layer) = crate::input::vector::split_layer(path);
        let mut abs = std::fs::canonicalize(&file).map_err(|e| Error::io(&file, e))?;
        let (bytes, sha256) = fingerprint(&read_all(&abs)?);
        if let Some(l) = layer {
            let mut s = abs.into_os_string();
            s.push(format!(":{l}"));
            abs = s.into();
        }
        Ok(LineFile {
            path: abs,
            bytes,
            sha256,
        })
    }

    /// Checks that the file still holds what it held when the plan was made.
    ///
    /// # Errors
    /// [`Error::Format`] naming the file when it changed; [`Error::Io`] when it cannot be read.
    pub fn check(&self) -> Result<()> {
        self.holds(&read_all(&self.file())?)
    }

    /// The file's lines, parsed from the bytes that were checked against its fingerprint: the
    /// file is read once, so the lines are those of the bytes the plan recorded.
    ///
    /// # Errors
    /// As [`LineFile::check`]; the readers' errors.
    pub(crate) fn read(&self) -> Result<Lines> {
        let content = read_all(&self.file())?;
        self.holds(&content)?;
        crate::input::lines::read_bytes(&self.path, &content)
    }

    /// The file without its layer (`FILE` of `FILE.gpkg:LAYER`).
    fn file(&self) -> PathBuf {
        crate::input::vector::split_layer(&self.path).0
    }

    /// Checks that `content`, the file's bytes now, are what the plan recorded.
    fn holds(&self, content: &[u8]) -> Result<()> {
        let (bytes, sha256) = fingerprint(content);
        if bytes != self.bytes || sha256 != self.sha256 {
            return Err(Error::Format {
                path: self.path.clone(),
                message: format!(
                    "the file changed since the plan was made ({} bytes, sha256 {} then; \
                     {bytes} bytes, sha256 {sha256} now): every task must read the same lines \
                     or polygon, so make the plan again",
                    self.bytes, self.sha256
                ),
            });
        }
        Ok(())
    }
}

/// The bytes of the file at `path`.
fn read_all(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// The size and SHA-256 (hex) of `content`.
pub(super) fn fingerprint(content: &[u8]) -> (u64, String) {
    use sha2::Digest;
    let hex = sha2::Sha256::digest(content)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    (content.len() as u64, hex)
}

/// The breaklines and trimming rings of a plan.
///
/// A plan stores its line files by absolute path with a fingerprint (size and SHA-256 of the
/// bytes, as `sha256sum` prints it), and every task reads and cleans them itself, each file
/// read once and parsed from the very bytes checked against its fingerprint (so the plan, which
/// reads them the same way, and every task clean the recorded bytes): cleaning is
/// deterministic ([`crate::breaklines::clean()`]), so every task holds the same planar graph, the
/// one a single run holds, and hands it to the tiled engine exactly as one tiled run does
/// (`pipeline::tiled`). Which segments a tile's run loads is the engine's business
/// (`tiles::lines`).
///
/// What a task cannot do is anything that needs all the points: drape vertices without `z`
/// (they take their height from the TIN of every point) or cut the lines to the points' hull
/// (`--clip-breaklines`). So a plan takes lines whose every vertex has a `z` after cleaning
/// (boundary and hole rings too: they are inserted as breaklines, and their vertices are vertices
/// of the TIN), and checks it when it is made, so that a bad file fails `sweeptin plan` once
/// rather than every task.
///
/// Line vertices are data like points, but every task knows all of them: the extents of the
/// files a task does not read stay the only places where it may not know the data, so the files
/// a task reads do not depend on the lines. The tiles do: the plan has a task for every tile the
/// convex hull of the files' extents and the line vertices meets, so a line that leaves the
/// files has the tiles it reaches, and the triangles between it and the points have theirs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanLines {
    /// Breakline files (`--breaklines`), in the order given.
    pub breaklines: Vec<LineFile>,
    /// Keep only the triangles inside these rings (`--trim-boundary`).
    pub boundary: Option<LineFile>,
    /// Drop the triangles inside these rings (`--holes`).
    pub holes: Option<LineFile>,
    /// Heights of one vertex given twice that differ by more than this are a conflict
    /// (`--z-tolerance`); absent: the default of [`crate::breaklines::CleanOptions`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z_tolerance: Option<f64>,
}

impl PlanLines {
    /// The plan's lines from these files (absolute, fingerprinted); `None` when there are none.
    ///
    /// # Errors
    /// [`Error::Io`] naming a file that cannot be read.
    pub fn new(
        breaklines: &[PathBuf],
        boundary: Option<&Path>,
        holes: Option<&Path>,
    ) -> Result<Option<PlanLines>> {
        if breaklines.is_empty() && boundary.is_none() && holes.is_none() {
            return Ok(None);
        }
        Ok(Some(PlanLines {
            breaklines: breaklines
                .iter()
                .map(|p| LineFile::new(p))
                .collect::<Result<_>>()?,
            boundary: boundary.map(LineFile::new).transpose()?,
            holes: holes.map(LineFile::new).transpose()?,
            z_tolerance: None,
        }))
    }

    /// The same lines cleaned with `z_tolerance` (recorded only when it is not the default,
    /// so a plan made with the default is the same whoever made it).
    pub fn with_z_tolerance(mut self, z_tolerance: f64) -> PlanLines {
        let default = crate::breaklines::CleanOptions::default().z_tolerance;
        self.z_tolerance = (z_tolerance != default).then_some(z_tolerance);
        self
    }

    /// Every file, breaklines first.
    pub fn files(&self) -> impl Iterator<Item = &LineFile> {
        self.breaklines
            .iter()
            .chain(self.boundary.iter())
            .chain(self.holes.iter())
    }

    /// Checks that no file changed since the plan was made ([`LineFile::check`]).
    ///
    /// # Errors
    /// As [`LineFile::check`].
    pub fn check(&self) -> Result<()> {
        self.files().try_for_each(LineFile::check)
    }

    /// The run's line options: these files, with `max_edge` (never draped, never clipped).
    pub(crate) fn options(&self, max_edge: Option<f64>) -> LineOptions {
        LineOptions {
            breaklines: self.breaklines.iter().map(|f| f.path.clone()).collect(),
            boundary: self.boundary.as_ref().map(|f| f.path.clone()),
            holes: self.holes.as_ref().map(|f| f.path.clone()),
            max_edge,
            z_tolerance: self.z_tolerance,
            ..LineOptions::default()
        }
    }

    /// The lines of the plan's file `path` (one of [`PlanLines::files`]), read once and
    /// checked against its fingerprint ([`LineFile::read`]).
    fn read(&self, path: &Path) -> Result<Lines> {
        match self.files().find(|f| f.path == path) {
            Some(f) => f.read(),
            None => Err(Error::Internal(format!(
                "{}: not a line file of the plan",
                path.display()
            ))),
        }
    }

    /// How a task's run reads the line files ([`PlanLines::read`]).
    pub(crate) fn reader(&self) -> Arc<ReadLines<'static>> {
        let lines = self.clone();
        Arc::new(move |p: &Path| lines.read(p))
    }

    /// The cleaned graph (vertices, segments, and the `z` conflicts cleaning found), read and
    /// cleaned as every task will, each file checked on the bytes parsed: what the plan checks
    /// when it is made.
    ///
    /// # Errors
    /// As [`PlanLines::check`]; the readers' and cleaning's errors; [`Error::Options`] naming
    /// the first vertex without `z`.
    pub fn graph(&self) -> Result<Pslg> {
        let p = crate::pipeline::prepare(&self.options(None), &|p: &Path| self.read(p), None)?;
        Ok(p.pslg.unwrap_or_default())
    }

    /// The trimming rules (boundary, holes, `max_edge`), the rings read as [`PlanLines::graph`]
    /// reads them: what a TIN plan's merge applies to the pieces.
    ///
    /// # Errors
    /// As [`PlanLines::check`]; the readers' errors.
    pub(crate) fn trim(&self, max_edge: Option<f64>) -> Result<crate::breaklines::Trim> {
        crate::pipeline::trim(&self.options(max_edge), &|p: &Path| self.read(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--z-tolerance` reaches every task through the plan; the default is not written, so a
    /// plan made with it is the same as one made without the option (or from Python).
    #[test]
    fn the_z_tolerance_is_carried_and_the_default_left_out() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l.txt");
        std::fs::write(&p, "0 0 1\n1 1 2\n").unwrap();
        let l = PlanLines::new(&[p], None, None).unwrap().unwrap();
        let default = crate::breaklines::CleanOptions::default().z_tolerance;
        let d = l.clone().with_z_tolerance(default);
        assert_eq!(d.z_tolerance, None);
        assert!(!serde_json::to_string(&d).unwrap().contains("z_tolerance"));
        let t = l.with_z_tolerance(0.25);
        assert_eq!(t.options(None).z_tolerance, Some(0.25));
        let back: PlanLines = serde_json::from_str(&serde_json::to_string(&t).unwrap()).unwrap();
        assert_eq!(back, t);
    }

    /// A plan's lines are read once per file and parsed from the bytes checked against the
    /// fingerprint: what the plan cleans, and what a task's run reads, are the recorded bytes;
    /// a changed file is refused, never parsed.
    #[test]
    fn lines_are_parsed_from_the_checked_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l.txt");
        std::fs::write(&p, "0 0 1\n1 1 2\n").unwrap();
        let l = PlanLines::new(std::slice::from_ref(&p), None, None)
            .unwrap()
            .unwrap();
        assert_eq!(
            l.graph().unwrap().vertices,
            [[0.0, 0.0, 1.0], [1.0, 1.0, 2.0]]
        );
        let read = l.reader();
        let path = l.breaklines[0].path.clone();
        assert_eq!(read(&path).unwrap().polylines[0][1], [1.0, 1.0, 2.0]);
        std::fs::write(&p, "0 0 1\n1 1 3\n").unwrap();
        for e in [l.graph().unwrap_err(), read(&path).unwrap_err()] {
            assert!(e.to_string().contains("changed since the plan"), "{e}");
        }
        let e = read(&dir.path().join("other.txt")).unwrap_err();
        assert!(matches!(e, Error::Internal(_)), "{e}");
    }

    #[test]
    fn fingerprints_name_a_changed_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l.txt");
        std::fs::write(&p, "0 0 1\n1 1 2\n").unwrap();
        let f = LineFile::new(&p).unwrap();
        assert_eq!(f.bytes, 12);
        // What `sha256sum` prints for the same bytes.
        assert_eq!(
            f.sha256,
            "c70eef8c2074ce1de7eb2cebf2bf75d735e2eda4ec04fe4083270da77c0b232d"
        );
        assert!(f.check().is_ok());
        std::fs::write(&p, "0 0 1\n1 1 3\n").unwrap();
        let e = f.check().unwrap_err().to_string();
        assert!(
            e.contains("l.txt") && e.contains("changed since the plan"),
            "{e}"
        );
    }
}
