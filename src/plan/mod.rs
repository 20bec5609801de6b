//! Plans: one job cut into tasks, one per tile of a global grid, for batch engines (Slurm job
//! arrays, Kubernetes Indexed Jobs, AWS Batch array jobs, GNU parallel).
//!
//! A [`Plan`] is made from the input files' headers (no point is decoded): the product command
//! and its options, the tile grid, and for every tile the files whose extent reaches into it or
//! its buffer. Saving it writes the chunk index of every plain LAZ/LAS file (`DIR/index/`, one
//! decoding pass: [`crate::input::las::ChunkIndex`]), or over one such file its point store
//! instead ([`Plan::point_store`]: `DIR/index/points`, [`crate::PointStore`], the points its
//! tasks read, decoded once), and the data's hull band when the plan has one
//! ([`Plan::hull_band`]: `DIR/index/band`, [`crate::HullBand`]), then `DIR/plan.json`. A
//! task needs nothing else. It runs the tiled engine on its tile alone ([`crate::TaskScope`]): it reads the files
//! near its tile (only their chunks, or COPC nodes, that meet its tile and buffer), keeps the
//! points up to the buffer, and delivers exactly what its tile owns, certified to be what a run
//! over all the points gives; when a certificate needs points beyond the buffer the task runs
//! again with a wider one. Tasks write their outputs under `DIR/tiles/` atomically, with a
//! `task_<i>.json` marker last, so a task can be re-run at any time and finished tasks skipped.
//! [`merge`] then checks that every task finished and joins the outputs: a GDAL VRT or one
//! GeoTIFF for the DEM, contour lines stitched across tile edges, volumes summed exactly, the
//! TIN's pieces joined into one mesh ([`mesh`]).
//!
//! Tile edges lie on whole multiples of the tile size, which is a whole multiple of the cell, so
//! plans with the same tile size agree tile for tile, and every raster cell (by its centre) and
//! every triangle (by its lowest vertex in sweep order) has exactly one owner tile.

mod area;
mod band;
pub mod chunks;
mod dir;
mod engine;
use area::{
    centres_within, fitting_tile, grown, meets_hull, overlaps, tile_bounds, tile_count, tile_of,
    whole_multiple,
};
mod files;
mod ground;
mod ground_points;
mod lines;
pub mod merge;
pub mod mesh;
mod overview;
mod record;
pub mod report;
mod stitch;
pub mod store;
mod task;

pub use dir::PlanDir;
pub use engine::task_from_env;
pub use files::FileStamp;
pub use lines::{LineFile, PlanLines};
pub use record::TaskRecord;
pub use task::{Job, Levels, Product, TaskOptions};

use crate::error::{Error, Result};
use crate::input::las::FileInfo;
use files::{inside, write_atomic};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Format version of `plan.json` (2: the typed [`Job`]).
pub const PLAN_VERSION: u32 = 2;
/// Format version of a `plan.json` whose job has breaklines or trimming rings
/// ([`Job::lines`]): a sweeptin that reads only [`PLAN_VERSION`] refuses it instead of running
/// its tasks without the lines. This one reads both.
pub const PLAN_VERSION_LINES: u32 = 3;
/// Format version of a `plan.json` whose job finds the ground on the fly ([`Job::ground`]).
pub const PLAN_VERSION_GROUND: u32 = 4;

/// One input file of a plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanFile {
    /// The file, as given (absolute when the plan was made with absolute paths).
    pub path: PathBuf,
    /// Its extent `[xmin, ymin, xmax, ymax]`, from the header.
    pub bounds: [f64; 4],
    /// Its number of points, from the header.
    pub points: u64,
    /// Its size and modification time (seconds and nanoseconds since 1970) when the plan was
    /// made: a file rewritten in place (reclassified, heights corrected) keeps its header's
    /// count and extent, and tasks before and after the rewrite mixed old and new points.
    /// `None` in plans of older builds (not checked), and for a remote file (a URL), which
    /// [`PlanFile::version`] pins.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stamp: Option<FileStamp>,
    /// A remote file's version when the plan was made: its ETag (else its Last-Modified date)
    /// and size, as the server gave them; a task refuses another version of the object.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub version: Option<String>,
    /// A plain LAZ/LAS file with points (not COPC): saving the plan writes its chunk index
    /// (`DIR/index/<k>.chunks`, [`Plan::chunk_index_path`]), and tasks decode only the chunks
    /// that meet their tile and buffer. `false` in plans of older builds (files read whole).
    #[serde(default, skip_serializing_if = "is_false")]
    pub indexed: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// One task: a tile of the grid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanTile {
    /// Task index (0, 1, …: the `--task` of `sweeptin run`, `SLURM_ARRAY_TASK_ID`, …).
    pub index: usize,
    /// Tile coordinates: the tile is `[tx × tile, (tx + 1) × tile) × [ty × tile, (ty + 1) × tile)`.
    pub tx: i64,
    /// See `tx`.
    pub ty: i64,
    /// The tile `[xmin, ymin, xmax, ymax]`.
    pub bounds: [f64; 4],
    /// The plan's files (indices) whose extent reaches into the tile grown by the buffer.
    pub files: Vec<usize>,
    /// Points in those files (an upper bound of the task's work).
    pub points: u64,
}

/// A job cut into tiles (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// [`PLAN_VERSION`], [`PLAN_VERSION_LINES`] when the job has lines, [`PLAN_VERSION_GROUND`]
    /// when it finds the ground.
    pub version: u32,
    /// The product command (`dem`, `contours`, `volume`).
    pub command: String,
    /// The command line it was made from, for people (the tasks run [`Plan::job`]).
    pub args: Vec<String>,
    /// What every task runs.
    pub job: Job,
    /// Where the outputs of the whole job go (as given; `merge` may write elsewhere).
    pub outputs: Vec<(String, PathBuf)>,
    /// Every input file.
    pub files: Vec<PlanFile>,
    /// The file lists (`@list.txt`) and `.vpc` files the inputs were given as (absolute): read
    /// when the plan was made, so no output of the job may replace one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lists: Vec<PathBuf>,
    /// Tile side.
    pub tile: f64,
    /// The first buffer of every task: points this far around the tile are read.
    pub buffer: f64,
    /// The cell size of the DEM, when the command makes one.
    pub cell: Option<f64>,
    /// The tasks, in tile order (rows from south to north, west to east in a row).
    pub tiles: Vec<PlanTile>,
    /// The width of the data's hull band given to the tasks ([`Plan::task_band`]; `None`: none,
    /// as in plans of older builds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hull_band: Option<f64>,
    /// The cell side of the plan's point store ([`Plan::point_store_path`]: its tasks read their
    /// points from it; `None`: they decode the files, as in plans of older builds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point_store: Option<f64>,
    /// What the files' headers said when the plan was made (a point count that disagrees with
    /// the file, a CRS read as `--crs` says…), as one run warns of them; `plan` prints them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// [`Plan::id`] as written by [`Plan::save`]: [`Plan::load`] computes it again and refuses
    /// a plan whose content no longer has it (an edit: a tile deleted, a file's count changed).
    #[serde(default)]
    pub fingerprint: String,
    /// [`Plan::id`], computed once.
    #[serde(skip)]
    id: PlanId,
}

/// The fingerprint of a plan ([`Plan::id`]), computed once; plans are equal whatever it holds.
#[derive(Clone, Debug, Default)]
struct PlanId(std::sync::OnceLock<String>);

impl PartialEq for PlanId {
    fn eq(&self, _: &PlanId) -> bool {
        true
    }
}

/// Most tiles a plan may cut its data into (each a task, listed in `plan.json`): 262,144, a
/// country of 1 km tiles (England's 130,000 km²), with a `plan.json` of tens of MB. A refusal
/// names the smallest round `--tile` that fits.
pub const MAX_TASKS: u64 = 1 << 18;

fn bad(path: &Path, message: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

impl Plan {
    /// A plan for `job` over the LAS/LAZ files `paths` (`@lists`, globs and `.vpc` files
    /// expanded; stored by absolute path), tiles of side `tile` (a whole multiple
    /// of the job's cell, if any) and a first buffer of `buffer`. Only headers are read. `args`
    /// is the command line it was made from (for people); `outputs` are where the whole job's
    /// outputs go (`"dir"`, `"contours"`, …).
    ///
    /// Every tile that the convex hull of the files' extents (and the line vertices) meets has
    /// a task. Lines ([`Job::lines`]) are read and cleaned now, as every task will (see
    /// [`PlanLines`]).
    ///
    /// # Errors
    /// [`Error::Options`] for a bad tile size, buffer or job option, and for a line vertex
    /// without z (naming it); [`Error::Format`] for a file that is not
    /// LAS/LAZ; the header reader's errors, also for files that cannot be read together (CRS,
    /// formats), as a single run would refuse them; the line readers' and cleaning's errors;
    /// [`Error::Options`] for a `--mem` in which no task's DEM fits.
    pub fn new(
        job: Job,
        args: Vec<String>,
        outputs: Vec<(String, PathBuf)>,
        paths: &[PathBuf],
        tile: f64,
        buffer: f64,
    ) -> Result<Plan> {
        job.check()?;
        let outputs = job_outputs(outputs)?;
        let cell = job.cell();
        crate::pipeline::check_tile_side(tile)?;
        if let Some(c) = cell {
            let k = tile / c;
            if !whole_multiple(tile, c) {
                return Err(Error::Options(format!(
                    "--tile {tile} must be a whole multiple of the cell size {c}"
                )));
            }
            if k > 16384.0 {
                return Err(Error::Options(format!(
                    "--tile {tile} holds {k:.0} × {k:.0} cells of {c}: a task's raster is \
                     limited to 16384 cells a side (use a smaller --tile)"
                )));
            }
        }
        if !(buffer.is_finite() && buffer >= 0.0) {
            return Err(Error::Options(format!(
                "--buffer must be a distance >= 0, not {buffer}"
            )));
        }
        if paths.is_empty() {
            return Err(Error::NoInput);
        }
        // `@list.txt`, quoted globs and `.vpc` files stand for their files (each header is
        // read); every local file is named by its absolute path, so that tasks run from
        // anywhere; remote files by their URL.
        let given = crate::input::files::expand(paths, crate::input::files::Expand::VpcFiles)?;
        let canonical = |p: &PathBuf| crate::input::files::absolute(p);
        let lists = given.lists.iter().map(canonical).collect::<Result<_>>()?;
        let paths: Vec<PathBuf> = given.files.iter().map(canonical).collect::<Result<_>>()?;
        let paths = paths.as_slice();
        if let Some(p) = paths.iter().find(|p| {
            !p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| e.eq_ignore_ascii_case("las") || e.eq_ignore_ascii_case("laz"))
        }) {
            return Err(bad(
                p,
                "a plan reads LAS/LAZ files (their headers give the extents)",
            ));
        }
        // The files must make one point set (one CRS, compatible formats), as for a single run:
        // refused now, from the headers, not by every task later.
        let read = crate::input::las::ReadOptions {
            crs: job.crs()?,
            ..Default::default()
        };
        let warnings =
            crate::input::las::LidarReader::open_with(paths, &job.filter(), read)?.warnings();
        let mut files = Vec::with_capacity(paths.len());
        for p in paths {
            let info = FileInfo::read(p)?;
            let b = info.bounds;
            if info.point_count > 0 && !b.usable() {
                // Tasks find their files by these boxes: one that says nothing cannot be placed.
                return Err(bad(
                    p,
                    "its header's box says nothing (all zero, inverted or not finite): a plan \
                     places files by their headers' boxes, without reading points; repair the \
                     header (e.g. lasinfo -repair_bb) or run the job without a plan",
                ));
            }
            files.push(PlanFile {
                path: p.clone(),
                bounds: [b.min[0], b.min[1], b.max[0], b.max[1]],
                points: info.point_count,
                // A URL's version is its ETag and size (`version`), not a time.
                stamp: match crate::input::source::is_remote(p) {
                    true => None,
                    false => Some(FileStamp::of(p)?),
                },
                version: crate::input::source::remote_version(p)?,
                indexed: info.point_count > 0 && info.copc.is_none(),
            });
        }
        // Where data may be: the files' extents and the lines' vertices (the lines read and
        // cleaned now, as every task will: a bad file or a vertex without z fails here, once).
        let mut data: Vec<[f64; 3]> = Vec::new();
        for f in files.iter().filter(|f| f.points > 0) {
            let b = f.bounds;
            data.extend(
                [[b[0], b[1]], [b[2], b[1]], [b[2], b[3]], [b[0], b[3]]].map(|c| [c[0], c[1], 0.0]),
            );
        }
        if let Some(l) = &job.lines {
            data.extend(l.graph()?.vertices);
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &data {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        let hull: Vec<[f64; 2]> = crate::tiles::hull::hull(&mut data)
            .iter()
            .map(|p| [p[0], p[1]])
            .collect();
        let mut tiles = Vec::new();
        if lo[0].is_finite() {
            // A tile owns the cells whose centres lie in [x0, x1) × (y0, y1]: columns by floor,
            // rows by ceil − 1 (a centre on the data's lower edge belongs to the row below).
            let col_of = |v: f64| tile_of(v, 0.0, tile).0;
            let ty_of = |v: f64| tile_of(0.0, v, tile).1;
            // A raster alone is owned by cell centres: tiles from the first centre to the last
            // inside the data (files ending on a tile edge added a row and a column of empty
            // tasks, and the mosaic was larger than one run's raster). Triangles, contours and
            // volumes are owned by points, which may lie on the far edges.
            let (lo, hi) = match centres_within(&job.product, lo, hi) {
                Some(c) => c,
                None => (lo, hi),
            };
            // Counted first: `--tile 0.001` over a kilometre listed 10^12 tiles (an abort).
            let count = tile_count(lo, hi, tile);
            if count.is_nan() || count > MAX_TASKS as f64 {
                let fits = fitting_tile(lo, hi, MAX_TASKS, cell);
                return Err(Error::Options(format!(
                    "--tile {tile} cuts the data (x {} .. {}, y {} .. {}) into {} tiles, more \
                     than the {} tasks a plan may have: use --tile {} or larger",
                    lo[0],
                    hi[0],
                    lo[1],
                    hi[1],
                    crate::fmt::Figure(count),
                    crate::fmt::count(MAX_TASKS),
                    crate::fmt::Figure(fits)
                )));
            }
            for ty in ty_of(lo[1])..=ty_of(hi[1]) {
                for tx in col_of(lo[0])..=col_of(hi[0]) {
                    let b = tile_bounds(tx, ty, tile);
                    // A tile outside the convex hull of the data has no triangle and owns
                    // nothing: no task. (One inside it that no file reaches, in a concave corner
                    // of the files or beside a line that leaves them, lies under triangles that
                    // one run fills cells from.)
                    if !meets_hull(&hull, &b) {
                        continue;
                    }
                    let g = grown(b, buffer);
                    let near: Vec<usize> = (0..files.len())
                        .filter(|&i| files[i].points > 0 && overlaps(&files[i].bounds, &g))
                        .collect();
                    let points = near.iter().map(|&i| files[i].points).sum();
                    tiles.push(PlanTile {
                        index: tiles.len(),
                        tx,
                        ty,
                        bounds: b,
                        files: near,
                        points,
                    });
                }
            }
        }
        let hull_band = band::width_for(&job, &files);
        let point_store = store::cell_for(hull_band, tile, &files);
        let mut plan = Plan {
            version: if job.ground.is_some() {
                PLAN_VERSION_GROUND
            } else if job.lines.is_some() {
                PLAN_VERSION_LINES
            } else {
                PLAN_VERSION
            },
            command: job.command().to_string(),
            args,
            job,
            outputs,
            files,
            lists,
            tile,
            buffer,
            cell,
            tiles,
            hull_band,
            point_store,
            warnings,
            fingerprint: String::new(),
            id: PlanId::default(),
        };
        plan.check_outputs()?;
        plan.check_task_memory()?;
        plan.check_ground_blocks()?;
        plan.fingerprint = plan.id().to_string();
        Ok(plan)
    }

    /// Writes `DIR/plan.json` (atomically: a rename, or one upload to S3) and creates
    /// `DIR/tiles/`, after the chunk index of every plain LAZ/LAS file (`DIR/index/`: one
    /// decoding pass over them, on every core) and the hull band (the chunks along the edge).
    ///
    /// # Errors
    /// [`Error::Io`] naming the file; [`Error::Options`] for a directory that holds another
    /// plan, or task records without a plan.
    pub fn save(&self, dir: &PlanDir) -> Result<PathBuf> {
        let path = dir.join("plan.json");
        let text = serde_json::to_string_pretty(self).map_err(|e| bad(&path, e.to_string()))?;
        // Another plan's tasks must never be taken for this one's.
        let old = dir.read_to_string(&path)?;
        if old.as_ref().is_some_and(|old| *old != text) {
            return Err(Error::Options(format!(
                "{} already holds another plan (and maybe its tasks' outputs): plan into a new \
                 directory, or delete that one first",
                dir.display()
            )));
        }
        if old.is_none()
            && let Some(record) = dir.any_record()?
        {
            return Err(Error::Options(format!(
                "{} holds a task record ({record}) but no plan: the tasks of another plan; plan \
                 into a new directory, or delete {} first",
                dir.display(),
                dir.join("tiles").display()
            )));
        }
        dir.make_dir("tiles")?;
        // The indexes first: a plan.json is complete with everything its tasks read.
        self.write_chunk_indexes(dir)?;
        self.write_point_store(dir)?;
        self.write_band(dir)?;
        dir.write(&path, text.as_bytes())?;
        Ok(path)
    }

    /// The plan's fingerprint: the SHA-256 of its content (serialised compactly, so not what
    /// `sha256sum plan.json` prints). Task records carry it, so that a record of another plan in
    /// the same directory, or of this one before it was edited, never counts. The
    /// [`Plan::fingerprint`] field itself is left out.
    pub fn id(&self) -> &str {
        self.id.0.get_or_init(|| {
            let mut bare = self.clone();
            bare.fingerprint = String::new();
            let text = serde_json::to_string(&bare).unwrap_or_default();
            lines::fingerprint(text.as_bytes()).1
        })
    }

    /// Reads a `plan.json`, a local file or an `s3://` object.
    ///
    /// # Errors
    /// [`Error::Io`], or [`Error::Format`] for a file that is not a plan of this version.
    pub fn load(path: &Path) -> Result<Plan> {
        let text = match crate::input::source::is_remote(path) {
            true => PlanDir::of_plan(path)?
                .read_to_string(path)?
                .ok_or_else(|| Error::io(path, std::io::ErrorKind::NotFound.into()))?,
            false => std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?,
        };
        #[derive(Deserialize)]
        struct Version {
            version: u32,
        }
        let v: Version = serde_json::from_str(&text)
            .map_err(|e| bad(path, format!("not a sweeptin plan: {e}")))?;
        if !(PLAN_VERSION..=PLAN_VERSION_GROUND).contains(&v.version) {
            return Err(bad(
                path,
                format!(
                    "plan version {} (this sweeptin reads versions {PLAN_VERSION} to \
                     {PLAN_VERSION_GROUND}): make the plan again with this sweeptin",
                    v.version
                ),
            ));
        }
        let plan: Plan = serde_json::from_str(&text)
            .map_err(|e| bad(path, format!("not a sweeptin plan: {e}")))?;
        if plan.fingerprint.is_empty() {
            return Err(bad(
                path,
                "the plan has no fingerprint (made by an older sweeptin, or edited): make the \
                 plan again",
            ));
        }
        if plan.fingerprint != plan.id() {
            return Err(bad(
                path,
                "its content no longer has the fingerprint it was written with: the plan was \
                 edited (tiles, files, counts or the job), and its tasks would no longer cover \
                 its inputs as planned; make the plan again",
            ));
        }
        plan.check_consistent()
            .map_err(|m| bad(path, format!("{m}: the plan was edited; make it again")))?;
        Ok(plan)
    }

    /// Checks what a plan says twice, or what its tiles follow from: the cell against the
    /// job's, each tile's number, bounds (from its grid position and the tile side) and files
    /// (a hand-edited cell or tile side made tiles that the mosaic misplaced).
    fn check_consistent(&self) -> std::result::Result<(), String> {
        if self.cell != self.job.cell() {
            return Err(format!(
                "its cell {:?} is not its job's {:?}",
                self.cell,
                self.job.cell()
            ));
        }
        crate::pipeline::check_tile_side(self.tile).map_err(|e| e.to_string())?;
        if let Some(c) = self.cell.filter(|&c| !whole_multiple(self.tile, c)) {
            return Err(format!(
                "its tile side {} is not a whole multiple of its cell {c}",
                self.tile
            ));
        }
        for (k, t) in self.tiles.iter().enumerate() {
            if t.index != k
                || t.bounds != tile_bounds(t.tx, t.ty, self.tile)
                || t.files.iter().any(|&f| f >= self.files.len())
            {
                return Err(format!(
                    "task {k} is not tile ({}, {}) of side {} over its {} files",
                    t.tx,
                    t.ty,
                    self.tile,
                    self.files.len()
                ));
            }
        }
        Ok(())
    }

    /// The task `i`.
    ///
    /// # Errors
    /// [`Error::Options`] when there is no such task.
    pub fn task(&self, i: usize) -> Result<&PlanTile> {
        self.tiles.get(i).ok_or_else(|| {
            Error::Options(format!(
                "task {i} does not exist: the plan has {} tasks (0 to {})",
                self.tiles.len(),
                self.tiles.len().saturating_sub(1)
            ))
        })
    }

    /// The engine's scope for task `i` with a buffer of `buffer`.
    ///
    /// # Errors
    /// As [`Plan::task`].
    pub fn scope(&self, i: usize, buffer: f64) -> Result<crate::tiles::TaskScope> {
        let t = self.task(i)?;
        let g = grown(t.bounds, buffer);
        Ok(crate::tiles::TaskScope {
            tile: t.bounds,
            buffer,
            unread: self
                .files
                .iter()
                .filter(|f| f.points > 0 && !overlaps(&f.bounds, &g))
                .map(|f| f.bounds)
                .collect(),
            chunks: Vec::new(),
            by_area: self.job.ground.is_some(),
            band: None,
            store: None,
        })
    }

    /// The files task `i` reads with a buffer of `buffer` (those reaching into its grown tile).
    ///
    /// # Errors
    /// As [`Plan::task`].
    pub fn task_files(&self, i: usize, buffer: f64) -> Result<Vec<PathBuf>> {
        let g = grown(self.task(i)?.bounds, buffer);
        Ok(self
            .files
            .iter()
            .filter(|f| f.points > 0 && overlaps(&f.bounds, &g))
            .map(|f| f.path.clone())
            .collect())
    }

    /// Checks that the files within `buffer` of task `i`'s tile are still what the plan saw (the
    /// same number of points and extent in their headers): a task checks every file it reads,
    /// with `--ground` those of the ground blocks around it too (`Plan::read_reach`).
    ///
    /// # Errors
    /// [`Error::Format`] naming a file that changed; the header reader's errors.
    pub fn check_files(&self, i: usize, buffer: f64) -> Result<()> {
        let g = grown(self.task(i)?.bounds, buffer);
        for f in self
            .files
            .iter()
            .filter(|f| f.points > 0 && overlaps(&f.bounds, &g))
        {
            if let Some(then) = &f.version {
                let now = crate::input::source::remote_version(&f.path)?.unwrap_or_default();
                if &now != then {
                    return Err(bad(
                        &f.path,
                        format!(
                            "the object changed since the plan was made ({then} then; {now} \
                             now): every task must read the same points, so make the plan again"
                        ),
                    ));
                }
            }
            let info = FileInfo::read(&f.path)?;
            if let Some(then) = f.stamp {
                let now = FileStamp::of(&f.path)?;
                if now != then {
                    return Err(bad(
                        &f.path,
                        format!(
                            "the file changed since the plan was made ({} bytes, modified at \
                             {}.{:09} s then; {} bytes, {}.{:09} s now): every task must read \
                             the same points, so make the plan again",
                            then.bytes,
                            then.modified,
                            then.nanos,
                            now.bytes,
                            now.modified,
                            now.nanos
                        ),
                    ));
                }
            }
            let b = info.bounds;
            if info.point_count != f.points || [b.min[0], b.min[1], b.max[0], b.max[1]] != f.bounds
            {
                return Err(bad(
                    &f.path,
                    format!(
                        "the file changed since the plan was made ({} points then, {} now): \
                         make the plan again",
                        f.points, info.point_count
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Where task `i` writes its output `name` (extension `ext`) under `dir`.
    ///
    /// # Errors
    /// [`Error::Options`] when the path is a symbolic link or not a regular file.
    pub fn task_output(&self, dir: &PlanDir, i: usize, name: &str, ext: &str) -> Result<PathBuf> {
        let t = &self.tiles[i];
        let p = dir
            .join("tiles")
            .join(format!("{name}_{}_{}.{ext}", t.tx, t.ty));
        dir.own_file(&p)?;
        Ok(p)
    }

    /// Where task `i` records that it finished.
    pub fn marker(&self, dir: &PlanDir, i: usize) -> PathBuf {
        dir.join("tiles").join(format!("task_{i}.json"))
    }

    /// The record of task `i`, if it finished under this plan (a record of another plan is
    /// none: [`TaskRecord::plan`]).
    ///
    /// # Errors
    /// [`Error::Format`] for a damaged record.
    pub fn record(&self, dir: &PlanDir, i: usize) -> Result<Option<TaskRecord>> {
        let p = self.marker(dir, i);
        match dir.read_to_string(&p)? {
            Some(t) => {
                let r = serde_json::from_str::<TaskRecord>(&t)
                    .map_err(|e| bad(&p, format!("damaged task record: {e}")))?;
                let Some(mut r) = Some(r).filter(|r| r.plan == self.id() && r.index == i) else {
                    return Ok(None);
                };
                for (name, out) in &mut r.outputs {
                    *out = inside(dir.path(), out).ok_or_else(|| {
                        bad(
                            &p,
                            format!(
                                "the record names its {name} output {} outside its plan's \
                                 directory (records name outputs relative to it): run task \
                                 {i} again",
                                out.display()
                            ),
                        )
                    })?;
                }
                Ok(Some(r))
            }
            None => Ok(None),
        }
    }

    /// Removes the record of task `i`, if any (the task is running again).
    ///
    /// # Errors
    /// [`Error::Io`] naming the record.
    pub fn forget_task(&self, dir: &PlanDir, i: usize) -> Result<()> {
        dir.remove(&self.marker(dir, i))
    }

    /// Records that task `i` finished (last, after its outputs).
    ///
    /// # Errors
    /// [`Error::Io`].
    pub fn finish_task(&self, dir: &PlanDir, r: &TaskRecord) -> Result<()> {
        let p = self.marker(dir, r.index);
        // Outputs relative to the plan's directory: a job moved or copied elsewhere merges its
        // own tiles, never those of the place it was made in.
        let mut r = r.clone();
        for (_, out) in &mut r.outputs {
            if let Ok(rel) = out.strip_prefix(dir.path()) {
                *out = rel.to_path_buf();
            }
        }
        let text = serde_json::to_string_pretty(&r).map_err(|e| bad(&p, e.to_string()))?;
        dir.write(&p, text.as_bytes())
    }
}

/// `b` grown by `d` on every side.
/// The whole job's outputs: each but the directory (and standard output) made absolute (`merge`,
/// run from elsewhere, wrote a relative one there) and refused among the plan's own files
/// ([`files::outside_plan_dir`]), where `merge` refused it after every task ran.
fn job_outputs(outputs: Vec<(String, PathBuf)>) -> Result<Vec<(String, PathBuf)>> {
    let dir = outputs
        .iter()
        .find(|(n, _)| n == "dir")
        .map(|(_, d)| PlanDir::new(d))
        .transpose()?;
    outputs
        .into_iter()
        .map(|(name, p)| {
            if name == "dir" || p.as_os_str() == "-" {
                return Ok((name, p));
            }
            if let Some(d) = &dir {
                d.outside(&format!("--{name}"), &p)?;
            }
            let abs = std::path::absolute(&p).map_err(|e| Error::io(&p, e))?;
            Ok((name, abs))
        })
        .collect()
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
#[cfg(test)]
mod tests;
