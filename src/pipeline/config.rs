//! One validated configuration per run: [`RunConfig::new`] checks a run's [`Input`] and
//! [`RunOptions`] once, before anything is read, and every stage of the pipeline reads the
//! result instead of checking again.
//!
//! What is checked here: that there is an input and what kind of files it is (LAS/LAZ, XYZ, or
//! one streaming mesh, decided once from the names), that a streaming mesh comes without
//! breaklines or trimming, and that the temporary directory exists. The breakline and trimming
//! options are checked where they are turned into their types (`--max-edge` by
//! [`crate::breaklines::Trim::new`]), and a terrain product's options when its sink is made (the
//! DEM's cell size and extent by [`crate::raster::GridPlan::new`]); the one rule that depends on
//! the sinks of a run (`--sweep-axis x` only for a plain mesh) is checked when the run starts.

use super::lines::ReadLines;
use super::{Input, RunOptions};
use crate::error::{Error, Result};
use crate::input::las::{Filter, Returns};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What kind of files the points come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Source {
    /// LAS/LAZ files, forming one point set.
    Lidar,
    /// XYZ text files.
    Xyz,
    /// One streaming mesh (`.stin`), replayed instead of triangulated.
    Stream,
}

fn has_extension(p: &Path, names: &[&str]) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| names.iter().any(|n| e.eq_ignore_ascii_case(n)))
}

impl Source {
    /// The kind of `paths`, by extension (`.las`/`.laz`/`.vpc`, `.stin`, anything else is XYZ).
    ///
    /// # Errors
    /// [`Error::NoInput`] for no path; [`Error::Format`] for a streaming mesh among other files,
    /// or LAS/LAZ files mixed with XYZ.
    pub(crate) fn of(paths: &[PathBuf]) -> Result<Source> {
        let Some(first) = paths.first() else {
            return Err(Error::NoInput);
        };
        let bad = |message: &str| Error::Format {
            path: first.clone(),
            message: message.into(),
        };
        if paths.iter().any(|p| has_extension(p, &["stin"])) {
            if paths.len() != 1 {
                return Err(bad("a streaming mesh (.stin) must be the only input"));
            }
            return Ok(Source::Stream);
        }
        let lidar = paths
            .iter()
            .filter(|p| has_extension(p, &["las", "laz", "vpc"]))
            .count();
        if lidar == paths.len() {
            Ok(Source::Lidar)
        } else if lidar > 0 {
            Err(bad("cannot mix LAS/LAZ and XYZ inputs in one run"))
        } else {
            Ok(Source::Xyz)
        }
    }
}

/// Refuses filters that do not apply to `source`: `--class` and `--returns` need LAS/LAZ
/// attributes that XYZ text does not have; a streaming mesh (`.stin`) holds triangles, not
/// points to filter.
///
/// # Errors
/// [`Error::Options`] naming the filter and the file.
pub(crate) fn check_filter(source: Source, f: &Filter, paths: &[PathBuf]) -> Result<()> {
    let name = paths
        .first()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    let mut lidar_only = Vec::new();
    if f.classes.is_some() {
        lidar_only.push("--class");
    }
    if f.returns != Returns::All {
        lidar_only.push("--returns");
    }
    if f.z_from.is_some() {
        lidar_only.push("--z-from");
    }
    match source {
        Source::Xyz if !lidar_only.is_empty() => Err(Error::Options(format!(
            "{}: {} need(s) the LAS/LAZ point attributes, which XYZ text does not have",
            name,
            lidar_only.join(" and ")
        ))),
        Source::Stream if !lidar_only.is_empty() || f.bbox.is_some() => {
            Err(Error::Options(format!(
                "{name}: a streaming mesh holds triangles, not points: --bbox, --class and \
                 --returns apply to LAS/LAZ and XYZ points"
            )))
        }
        _ => Ok(()),
    }
}

/// Refuses numeric options that mean nothing: a `--max-edge` that is not a positive length, a
/// `--z-tolerance` that is not a distance, a `--tile` that is not a positive size.
///
/// # Errors
/// [`Error::Options`] naming the option and the value.
fn check_numbers(input: &Input, options: &RunOptions) -> Result<()> {
    let l = &input.lines;
    if let Some(m) = l.max_edge.filter(|m| !(m.is_finite() && *m > 0.0)) {
        return Err(Error::Options(format!(
            "--max-edge {m}: must be a positive length"
        )));
    }
    if let Some(t) = l.z_tolerance.filter(|t| !(t.is_finite() && *t >= 0.0)) {
        return Err(Error::Options(format!(
            "--z-tolerance {t}: must be a height difference >= 0"
        )));
    }
    if let Some(t) = options.tiles.as_ref().and_then(|t| t.tile) {
        check_tile_side(t)?;
    }
    Ok(())
}

/// Refuses a tile side that is not a positive size (`--tile`), whatever the engine: a value the
/// sweep would ignore is still a mistake.
///
/// # Errors
/// [`Error::Options`] naming the value.
pub fn check_tile_side(t: f64) -> Result<()> {
    if t.is_finite() && t > 0.0 {
        return Ok(());
    }
    Err(Error::Options(format!(
        "--tile {t}: must be a positive size"
    )))
}

/// The inputs among `paths` that are pipes or devices (readable once, no seeking).
fn streams(paths: &[PathBuf]) -> Vec<PathBuf> {
    paths
        .iter()
        .filter(|p| std::fs::metadata(p).is_ok_and(|m| !m.is_file() && !m.is_dir()))
        .cloned()
        .collect()
}

/// A run's input and options, checked (see the module docs). Build it with [`RunConfig::new`]
/// and hand it to [`super::run`].
#[derive(Clone, Debug)]
pub struct RunConfig {
    input: Input,
    options: RunOptions,
    source: Source,
    tmp_dir: PathBuf,
    /// Inputs that are pipes or devices: they can be read once only.
    streams: Vec<PathBuf>,
    /// How the line files are read ([`RunConfig::read_lines`]).
    line_reader: LineReader,
    /// The CRS the user declares for the files ([`RunConfig::with_crs`]).
    crs: Option<crate::crs::Crs>,
    /// What `--ground` found before the run ([`RunConfig::with_ground`]).
    ground: Option<crate::ground::GroundSummary>,
}

/// How a run reads its line files: as they are ([`crate::breaklines::read_file`]), or, in a
/// plan's task, checked against the plan's fingerprints ([`RunConfig::with_line_reader`]).
#[derive(Clone)]
struct LineReader(Option<Arc<ReadLines<'static>>>);

impl std::fmt::Debug for LineReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self.0 {
            Some(_) => "LineReader(checked)",
            None => "LineReader(read_file)",
        })
    }
}

/// Refuses a temporary directory that is not one (missing, or a file) before any work, whether
/// or not the job will spill there ([`Error::Write`], exit 4).
pub(crate) fn check_tmp_dir(tmp_dir: &std::path::Path) -> Result<()> {
    if tmp_dir.is_dir() {
        return Ok(());
    }
    // Named as the user set it: --tmp-dir, or else $TMPDIR.
    let env = if tmp_dir == std::env::temp_dir() {
        " ($TMPDIR)"
    } else {
        ""
    };
    let (kind, what) = if tmp_dir.exists() {
        (
            std::io::ErrorKind::NotADirectory,
            format!("the temporary directory{env} is not a directory"),
        )
    } else {
        (
            std::io::ErrorKind::NotFound,
            format!("temporary directory{env} does not exist"),
        )
    };
    Err(Error::write(tmp_dir, std::io::Error::new(kind, what)))
}

impl RunConfig {
    /// Checks `input` and `options`.
    ///
    /// # Errors
    /// [`Error::NoInput`]; [`Error::Format`] for a streaming mesh that is not the only input or
    /// comes with breaklines or trimming, or LAS/LAZ files mixed with XYZ; [`Error::Io`] for a
    /// temporary directory that does not exist; [`Error::OutOfMemory`] when an address-space
    /// limit leaves less than `mem` beside what the program maps itself.
    pub fn new(input: Input, options: RunOptions) -> Result<RunConfig> {
        let source = Source::of(&input.paths)?;
        check_filter(source, &input.filter, &input.paths)?;
        check_numbers(&input, &options)?;
        let threads = options.tiles.as_ref().map_or(0, |t| t.threads);
        super::check_threads(threads)?;
        crate::limits::check_address_space(
            options.mem,
            threads,
            "the job's memory budget (--mem)",
        )?;
        let streams = streams(&input.paths);
        if let (Some(s), Source::Lidar | Source::Stream) = (streams.first(), source) {
            return Err(Error::Options(format!(
                "{}: is a pipe or a device, which can be read only once: a LAS/LAZ file or a \
                 streaming mesh is read more than once (headers, then points), so give a file",
                s.display()
            )));
        }
        if source == Source::Stream && !input.lines.is_empty() {
            return Err(Error::Format {
                path: input.paths[0].clone(),
                message: "breaklines and trimming need the points: give the LAS/LAZ or XYZ \
                          input, not a streaming mesh"
                    .into(),
            });
        }
        let tmp_dir = options.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
        check_tmp_dir(&tmp_dir)?;
        Ok(RunConfig {
            input,
            options,
            source,
            tmp_dir,
            streams,
            line_reader: LineReader(None),
            crs: None,
            ground: None,
        })
    }

    /// The same run with the files declared to be in `crs` (`--crs`): LAS/LAZ files that
    /// declare another are read as in it, with a warning, instead of refused
    /// ([`crate::input::las::ReadOptions::crs`]).
    pub fn with_crs(mut self, crs: Option<crate::crs::Crs>) -> RunConfig {
        self.crs = crs;
        self
    }

    /// The same run, its input classified by the ground filter first (`--ground`,
    /// [`super::ground::ground_input`]) as `ground` says: its summary carries it
    /// ([`super::RunSummary::ground`]).
    pub fn with_ground(mut self, ground: Option<crate::ground::GroundSummary>) -> RunConfig {
        self.ground = ground;
        self
    }

    /// What `--ground` found before the run ([`RunConfig::with_ground`]).
    pub fn ground(&self) -> Option<&crate::ground::GroundSummary> {
        self.ground.as_ref()
    }

    /// Opens the LAS/LAZ files of the run with `options` and the declared CRS.
    ///
    /// # Errors
    /// As [`crate::input::las::LidarReader::open_with`].
    pub(crate) fn open_lidar(
        &self,
        options: crate::input::las::ReadOptions,
    ) -> Result<crate::input::las::LidarReader> {
        let options = crate::input::las::ReadOptions {
            crs: self.crs.clone(),
            ..options
        };
        crate::input::las::LidarReader::open_with(&self.input.paths, &self.input.filter, options)
    }

    /// The CRS declared for the files ([`RunConfig::with_crs`]).
    pub(crate) fn declared_crs(&self) -> Option<&crate::crs::Crs> {
        self.crs.as_ref()
    }

    /// The same run reading its line files with `read` (a plan's task: each file checked
    /// against the plan's fingerprint on the bytes it parses).
    pub(crate) fn with_line_reader(mut self, read: Arc<ReadLines<'static>>) -> RunConfig {
        self.line_reader = LineReader(Some(read));
        self
    }

    /// How the run reads its line files: [`crate::breaklines::read_file`] unless
    /// [`RunConfig::with_line_reader`] said otherwise.
    pub(crate) fn read_lines(&self) -> &ReadLines<'static> {
        match &self.line_reader.0 {
            Some(r) => r.as_ref(),
            None => &crate::breaklines::read_file,
        }
    }

    /// What the run's lines get ([`super::lines::prepare_with`]): `--mem`, the scratch
    /// directory, and whether the line files may be read again by path (not with a plan's
    /// reader).
    pub(crate) fn line_budget(&self) -> super::lines::LineBudget<'_> {
        super::lines::LineBudget {
            mem: self.options.mem,
            tmp: self.tmp_dir(),
            reread: self.line_reader.0.is_none(),
        }
    }

    /// What to triangulate.
    pub fn input(&self) -> &Input {
        &self.input
    }

    /// How to run.
    pub fn options(&self) -> &RunOptions {
        &self.options
    }

    /// Does this run use the exact tiles (asked for, and the input allows them: LAS/LAZ points
    /// without breaklines, trimming polygons or `--no-flat-triangles`, swept along y)? When it
    /// does not, it runs one exact streaming sweep.
    pub fn runs_in_tiles(&self) -> bool {
        self.options.tiles.is_some() && super::tiled::applies(self)
    }

    /// The kind of input files.
    pub(crate) fn source(&self) -> Source {
        self.source
    }

    /// The first input that is a pipe or a device (read once only), if any.
    pub(crate) fn stream_input(&self) -> Option<&Path> {
        self.streams.first().map(PathBuf::as_path)
    }

    /// Where spill files go (an existing directory).
    pub(crate) fn tmp_dir(&self) -> &Path {
        &self.tmp_dir
    }

    /// The same run on the points alone (no breaklines, no trimming) without a progress bar:
    /// the draping pass of lines without z.
    pub(crate) fn points_only(&self) -> RunConfig {
        let mut c = self.clone();
        c.input.lines = Default::default();
        c.options.progress = false;
        c
    }

    /// The same run with the tiled engine's own tile side (from the data's density), whatever
    /// `--tile` says: `thin --tile T` takes `T` for its thinning tiles, and the TIN of its first
    /// pass (the same triangles for any tile side) must not run in tiles of, say, one point.
    pub(crate) fn engine_tiles(mut self) -> RunConfig {
        if let Some(t) = self.options.tiles.as_mut() {
            t.tile = None;
        }
        self
    }

    /// The CRS of the input, from LAS/LAZ headers or a streaming mesh's header, without reading
    /// the points (`None` for XYZ).
    ///
    /// # Errors
    /// The reader's errors when a header cannot be read.
    pub fn input_crs(&self) -> Result<Option<String>> {
        match self.source {
            Source::Stream => {
                let r = crate::input::stin::StinReader::open(&self.input.paths[0])?;
                Ok(r.crs().map(str::to_string))
            }
            Source::Lidar => {
                let r = self.open_lidar(crate::input::las::ReadOptions::default())?;
                Ok(r.crs().and_then(|c| c.definition()))
            }
            Source::Xyz => Ok(None),
        }
    }

    /// The extent of the points from the LAS/LAZ headers
    /// ([`crate::input::las::LidarReader::header_extent`]; `None` for other inputs).
    pub fn header_bounds(&self) -> Option<[f64; 4]> {
        if self.source != Source::Lidar {
            return None;
        }
        crate::input::las::LidarReader::header_extent(&self.input.paths)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::las::Filter;

    fn input(paths: &[&str]) -> Input {
        Input {
            paths: paths.iter().map(PathBuf::from).collect(),
            filter: Filter::keep_all(),
            duplicates: Default::default(),
            lines: Default::default(),
        }
    }

    #[test]
    fn the_kind_of_input_is_decided_once() {
        let kind = |p: &[&str]| Source::of(&input(p).paths);
        assert_eq!(kind(&["a.LAZ", "b.las"]).unwrap(), Source::Lidar);
        assert_eq!(kind(&["a.vpc", "b.copc.laz"]).unwrap(), Source::Lidar);
        assert_eq!(kind(&["a.xyz", "b.txt"]).unwrap(), Source::Xyz);
        assert_eq!(kind(&["a.stin"]).unwrap(), Source::Stream);
        assert!(matches!(kind(&[]), Err(Error::NoInput)));
        let e = kind(&["a.las", "b.xyz"]).unwrap_err();
        assert!(e.to_string().contains("cannot mix"), "{e}");
        let e = kind(&["a.stin", "b.stin"]).unwrap_err();
        assert!(e.to_string().contains("only input"), "{e}");
    }

    #[test]
    fn a_streaming_mesh_has_no_breaklines_and_the_temporary_directory_exists() {
        let mut i = input(&["a.stin"]);
        i.lines.max_edge = Some(5.0);
        let e = RunConfig::new(i, RunOptions::default()).unwrap_err();
        assert!(e.to_string().contains("need the points"), "{e}");
        let o = RunOptions {
            tmp_dir: Some("/no/such/dir".into()),
            ..RunOptions::default()
        };
        let e = RunConfig::new(input(&["a.xyz"]), o).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        assert!(RunConfig::new(input(&["a.xyz"]), RunOptions::default()).is_ok());
    }
}
