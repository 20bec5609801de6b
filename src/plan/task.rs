//! What a plan's tasks run, typed ([`Job`], stored in `plan.json`: `task/job.rs`), and running one task
//! ([`Plan::run_task`]): the tiled engine on the task's tile, its buffer widened until every
//! triangle it owns is certified, its outputs under `DIR/tiles/` and then its record. The
//! command line (`sweeptin plan/run`) and the Python package (`sweeptin.plan/run_task`) both
//! build a [`Job`] and run tasks through here, so their plans are interchangeable.

use super::{Plan, PlanDir, TaskRecord};
use crate::error::{Error, Result};
use crate::output::pieces::PieceWriter;
use crate::output::raster::{RasterFormat, RasterOptions};
use crate::pipeline::{Input, LineOptions, RunConfig, RunOptions, RunSummary, SweepAxis};
use crate::products::contours::ContourSink;
use crate::products::dem::{DemOptions, DemSink};
use crate::products::volume::VolumeSink;
use crate::raster::{GridExtent, GridPlan};
use crate::sink::MeshSink as _;
use crate::sink::{Fanout, FanoutSummary, ProductSummary, TriangleSink};
use std::path::Path;

/// A non-finite `f32` (a NaN nodata) as a string in JSON.
mod nodata;

mod job;
pub(super) use job::check_mosaic;
pub use job::{Job, Levels, Product};

/// How to run a task (what may differ between the machines that run a plan).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TaskOptions {
    /// Worker threads (0: every core).
    pub threads: usize,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

impl Plan {
    /// The directory of the plan file `path` ([`PlanDir::of_plan`]): a local one absolute
    /// (task records then name their outputs wherever the task ran from), or an `s3://` prefix.
    ///
    /// # Errors
    /// [`Error::Io`] when the path cannot be made absolute.
    pub fn dir_of(path: &Path) -> Result<PlanDir> {
        PlanDir::of_plan(path)
    }

    /// Has task `i` finished, with its record readable and every output it names present, of the
    /// size it had then? (What a resumed run skips; anything less, a truncated tile too, runs
    /// again.)
    pub fn finished(&self, dir: &PlanDir, i: usize) -> bool {
        match self.record(dir, i) {
            Ok(Some(r)) => self.check_task_outputs(dir, &r).is_ok(),
            _ => false,
        }
    }

    /// Checks that every output the finished task's record `r` (as [`Plan::record`] reads it:
    /// its outputs already under `dir`) names is a file of the size it recorded (a record of an
    /// older build, without sizes: present). `merge` checks every tile
    /// so, whatever it writes (a VRT over a truncated tile was written, exit 0, and GDAL failed
    /// on it later).
    ///
    /// # Errors
    /// [`Error::Format`] naming the output, its size and the task to run again.
    pub fn check_task_outputs(&self, dir: &PlanDir, r: &TaskRecord) -> Result<()> {
        for (k, (name, p)) in r.outputs.iter().enumerate() {
            // Not joined to `dir` again: `report job/plan.json` looked under `job/job/`.
            let path = p.clone();
            let len = dir.size(&path)?;
            let wrong = match (len, r.bytes.get(k)) {
                (None, _) => "is missing".to_string(),
                (Some(n), Some(&b)) if n != b => format!(
                    "has {n} bytes, not the {b} its task wrote: it was truncated or changed since"
                ),
                _ => continue,
            };
            return Err(Error::Format {
                path,
                message: format!(
                    "the {name} output of task {} {wrong}; {}",
                    r.index,
                    run_again(dir, r.index, true)
                ),
            });
        }
        Ok(())
    }

    /// Runs task `i` of the plan in `dir` until its buffer is wide enough; writes its outputs
    /// and then its record, which it returns. A task with no point after the filters, or no
    /// triangle and no cell with data, writes no tile (a TIN's pieces excepted) and records
    /// `"empty"`: the merges take it as nodata.
    ///
    /// # Errors
    /// [`Error::Options`] for a task that does not exist; the pipeline's and the sinks' errors.
    /// A task that fails records why (`tiles/task_<i>.failed.json`, [`super::report`]).
    pub fn run_task(&self, dir: &PlanDir, i: usize, options: &TaskOptions) -> Result<TaskRecord> {
        let start = std::time::Instant::now();
        self.task(i)?;
        self.forget_failure(dir, i);
        let r = self.try_task(dir, i, options);
        if let Err(e) = &r {
            let _ = self.record_failure(dir, i, &e.to_string(), start.elapsed().as_secs_f64());
        }
        r
    }

    fn try_task(&self, dir: &PlanDir, i: usize, options: &TaskOptions) -> Result<TaskRecord> {
        let start = std::time::Instant::now();
        dir.tiles()?;
        // Not finished until it finishes now: a run that fails leaves no record of an earlier
        // one for `--resume` or `merge` to take (they mixed old tiles with new ones).
        self.forget_task(dir, i)?;
        let crs = self.job.crs()?;
        let points = self.job.product == Product::Ground;
        let mut buffer = if points {
            0.0
        } else {
            self.first_buffer(dir, i)?
        };
        let (mut runs, mut ground) = (0, super::ground::Cache::default());
        let mut record = if points {
            self.ground_points_task(dir, i)?
        } else {
            loop {
                runs += 1;
                // With --ground, the files of the ground blocks around too.
                self.check_files(i, self.read_reach(i, buffer)?)?;
                let config = self.task_config(dir, i, buffer, options, &mut ground)?;
                let mut fanout = Fanout::new(self.task_sinks(dir, i)?).with_crs(crs.clone());
                let mut pieces = self.task_pieces(dir, i)?;
                let mesh = pieces
                    .as_mut()
                    .map(|p| p as &mut (dyn crate::sink::MeshSink + Send));
                match crate::pipeline::run(&config, mesh, &mut [&mut fanout]) {
                    Ok(mut run) => {
                        let products = fanout_summary(run.products.pop())?;
                        // Empty: no triangle of its own, and no cell with data from the triangles
                        // of others that cover it (a tile inside a concave corner of the data).
                        let covered = products.0.iter().any(
                            |(_, s)| matches!(s, ProductSummary::Dem(d) if d.cells_with_data > 0),
                        );
                        let status = if run.triangles == 0 && !covered {
                            "empty"
                        } else {
                            "done"
                        };
                        let mut r = record_of(i, status, buffer, runs, &run, &products);
                        self.finish_pieces(dir, i, pieces, &mut r)?;
                        if status == "empty" {
                            // No tile for an empty task: the merges take it as nodata and no lines
                            // (its volume sums, all zero, stay in the record). A TIN's pieces stay:
                            // they hold the triangles the merge trims, and vertices others wait for.
                            r.outputs
                                .retain(|(name, p)| name == "tin" || dir.remove(p).is_err());
                        }
                        break r;
                    }
                    Err(Error::BufferTooSmall { reach, .. }) if runs < 40 => {
                        // Straight to the files the certificates reached, or double.
                        let step = self.tile / 16.0;
                        buffer = if reach > buffer {
                            (reach / step).ceil() * step
                        } else if buffer > 0.0 {
                            2.0 * buffer
                        } else {
                            self.tile / 8.0
                        };
                    }
                    Err(Error::TooFewPoints { .. }) => {
                        // No point near the tile: an empty task writes nothing.
                        drop(pieces);
                        let _ = dir.remove(&self.task_output(dir, i, "tin", "pieces")?);
                        let products = FanoutSummary::default();
                        let run = RunSummary::default();
                        break record_of(i, "empty", buffer, runs, &run, &products);
                    }
                    Err(e) => return Err(e),
                }
            }
        };
        record.seconds = start.elapsed().as_secs_f64();
        record.peak_memory = crate::limits::peak_rss();
        record.plan = self.id().to_string();
        record.bytes = record
            .outputs
            .iter()
            .map(|(_, p)| Ok(dir.size(p)?.unwrap_or(0)))
            .collect::<Result<_>>()?;
        // Fault injection for the tests: the task fails after its outputs, before its record
        // (a worker lost there), `SWEEPTIN_TEST_FAIL_BEFORE_RECORD=I`.
        if std::env::var("SWEEPTIN_TEST_FAIL_BEFORE_RECORD").is_ok_and(|v| v == i.to_string()) {
            return Err(Error::Internal(format!(
                "injected failure of task {i} before its record (SWEEPTIN_TEST_FAIL_BEFORE_RECORD)"
            )));
        }
        self.finish_task(dir, &record)?;
        Ok(record)
    }

    /// The first buffer of task `i`: the plan's, or, for a tile with no input file within the
    /// plan's buffer (inside the data's hull: a concave corner of the files, beside a line that
    /// leaves them), the one that reads the nearest file.
    ///
    /// # Errors
    /// As [`Plan::task`].
    fn first_buffer(&self, dir: &PlanDir, i: usize) -> Result<f64> {
        let sc = self.scope(i, self.buffer)?;
        let near_files = !self.task_files(i, self.buffer)?.is_empty();
        if near_files {
            // Indexed files (or a point store): the nearest chunk (cell), when none meets the grown
            // tile (a task in a gap of the data, or beside it, reads the points nearest it).
            let Some(boxes) = self.data_boxes(dir, i)? else {
                return Ok(self.buffer);
            };
            let g = super::area::grown(sc.tile, self.buffer);
            let rects = || boxes.iter().copied();
            if rects().any(|r| super::area::overlaps(&r, &g)) {
                return Ok(self.buffer);
            }
            let scope = crate::tiles::index::Scope {
                unknown: Vec::new(),
                beyond: Vec::new(),
                tile: sc.tile,
                buffer: sc.buffer,
                hull: None,
                inner: None,
            };
            let near = rects()
                .map(|r| scope.reach(&r))
                .fold(f64::INFINITY, f64::min);
            return Ok(if near.is_finite() {
                near.max(self.buffer)
            } else {
                self.buffer
            });
        }
        let scope = crate::tiles::index::Scope {
            unknown: sc.unread,
            beyond: Vec::new(),
            tile: sc.tile,
            buffer: sc.buffer,
            hull: None,
            inner: None,
        };
        let near = scope
            .unknown
            .iter()
            .map(|u| scope.reach(u))
            .fold(f64::INFINITY, f64::min);
        Ok(if near.is_finite() { near } else { self.buffer })
    }

    /// A task's budget: the plan's `--mem`, or what an address-space limit on this node leaves
    /// beside the program (the output is the same whatever the budget, and `run` has no --mem
    /// of its own).
    pub(super) fn task_mem(&self) -> u64 {
        crate::limits::fit_address_space(self.job.mem, 0)
    }

    /// The run of task `i` with a buffer of `buffer` (with `--ground`, the classes of its area,
    /// kept in `ground` for the next run).
    fn task_config(
        &self,
        dir: &PlanDir,
        i: usize,
        buffer: f64,
        o: &TaskOptions,
        ground: &mut super::ground::Cache,
    ) -> Result<RunConfig> {
        let lines = match &self.job.lines {
            Some(l) => l.options(self.job.max_edge),
            None => LineOptions {
                max_edge: self.job.max_edge,
                ..LineOptions::default()
            },
        };
        let mut input = Input {
            paths: self.task_files(i, buffer)?,
            filter: self.job.filter(),
            duplicates: self.job.duplicates,
            lines,
        };
        let mut options = RunOptions {
            mem: self.task_mem(),
            tmp_dir: self.job.tmp_dir.clone(),
            progress: o.progress,
            sweep_axis: SweepAxis::Auto,
            tiles: Some(crate::tiles::TileOptions {
                threads: o.threads,
                tile: Some(self.tile),
                base: None,
                scope: Some(crate::tiles::TaskScope {
                    chunks: self.task_chunks(dir, i, buffer)?,
                    band: self.task_band(dir)?,
                    store: self.task_store(dir)?,
                    ..self.scope(i, buffer)?
                }),
            }),
        };
        // `--ground`: the classes of the area the run reads, found first.
        let ground = self.ground_task(dir, (i, buffer), &mut input, &mut options, ground)?;
        let config = RunConfig::new(input, options)?
            .with_crs(self.job.crs()?)
            .with_ground(ground);
        // Each line file is read once and parsed from the bytes checked against the plan's
        // fingerprint (a file changed since the plan was made is refused).
        Ok(match &self.job.lines {
            Some(l) => config.with_line_reader(l.reader()),
            None => config,
        })
    }

    /// The DEM of a task whose tile is `tile`.
    fn dem_options(
        &self,
        tile: [f64; 4],
        cell: f64,
        align: crate::raster::Align,
        nodata: f32,
    ) -> Result<DemOptions> {
        // The raster covers the tile (on the plan's lattice), whatever is read.
        let extent = GridExtent::BBox {
            bbox: tile,
            snap: false,
        };
        Ok(DemOptions {
            grid: GridPlan::new(cell, extent, align)?,
            nodata,
            // The tasks' tiles are plain GeoTIFFs; the mosaic gets the plan's format.
            output: RasterOptions {
                format: Some(RasterFormat::GeoTiff),
                ..RasterOptions::default()
            },
            // As one run: the raster's rows hold at most a quarter of the budget.
            memory: self.task_mem() / 4,
        })
    }

    /// Refuses, when the plan is made, a budget in which no task's DEM fits (every task would
    /// fail, as one run with it fails before any work). The budget is the task's here (under
    /// this machine's address-space limit, if any; at least 16 MiB), as a task would take it.
    ///
    /// # Errors
    /// [`Error::Options`] from [`DemSink::check_size`], as one run gives it.
    pub(crate) fn check_task_memory(&self) -> Result<()> {
        let (
            Product::Dem {
                cell,
                align,
                nodata,
                ..
            },
            Some(t),
        ) = (&self.job.product, self.tiles.first())
        else {
            return Ok(());
        };
        let options = self.dem_options(t.bounds, *cell, *align, *nodata)?;
        let sink = DemSink::new(Path::new("task.tif"), options)?;
        sink.check_size(t.bounds).map_err(|e| {
            Error::Options(format!(
                "a task's DEM (one tile) does not fit the plan's --mem: {e}"
            ))
        })
    }

    /// The sinks of task `i`, writing under `dir/tiles/`.
    fn task_sinks(&self, dir: &PlanDir, i: usize) -> Result<Vec<(String, Box<dyn TriangleSink>)>> {
        let tile = self.task(i)?.bounds;
        let contours = |l: &Levels| -> Result<(String, Box<dyn TriangleSink>)> {
            let path = self.task_output(dir, i, "contours", "geojson")?;
            Ok((
                "contours".into(),
                Box::new(ContourSink::new(&path, l.options(true, self.task_mem()))?),
            ))
        };
        let mut sinks: Vec<(String, Box<dyn TriangleSink>)> = Vec::new();
        match &self.job.product {
            Product::Dem {
                cell,
                align,
                nodata,
                contours: levels,
                ..
            } => {
                let path = self.task_output(dir, i, "dem", "tif")?;
                let options = self.dem_options(tile, *cell, *align, *nodata)?;
                sinks.push(("dem".into(), Box::new(DemSink::new(&path, options)?)));
                if let Some(l) = levels {
                    sinks.push(contours(l)?);
                }
            }
            Product::Contours(l) => sinks.push(contours(l)?),
            Product::Volume { plane, boundary } => {
                let boundary = boundary
                    .as_ref()
                    .map(|f| {
                        f.check()?;
                        crate::products::boundary::Boundary::read(&f.path)
                    })
                    .transpose()?;
                sinks.push((
                    "volume".into(),
                    Box::new(VolumeSink::new(*plane, boundary)?),
                ));
            }
            // Its mesh sink: see `task_pieces`; a ground plan's tiles: `ground_points_task`.
            Product::Tin | Product::Ground => {}
        }
        Ok(sinks)
    }

    /// For a TIN plan: the pieces file task `i` writes (as its mesh sink).
    fn task_pieces(&self, dir: &PlanDir, i: usize) -> Result<Option<PieceWriter>> {
        match self.job.product {
            Product::Tin => Ok(Some(PieceWriter::create(
                &self.task_output(dir, i, "tin", "pieces")?,
            )?)),
            _ => Ok(None),
        }
    }

    /// Finishes the pieces file of task `i` (if its plan makes a TIN) and names it in `r`.
    fn finish_pieces(
        &self,
        dir: &PlanDir,
        i: usize,
        pieces: Option<PieceWriter>,
        r: &mut TaskRecord,
    ) -> Result<()> {
        if let Some(mut p) = pieces {
            p.finish()?;
            r.outputs
                .push(("tin".into(), self.task_output(dir, i, "tin", "pieces")?));
        }
        Ok(())
    }
}

fn fanout_summary(s: Option<ProductSummary>) -> Result<FanoutSummary> {
    match s {
        Some(ProductSummary::Fanout(s)) => Ok(s),
        other => Err(Error::Internal(format!(
            "the products' summary is {other:?}"
        ))),
    }
}

fn record_of(
    i: usize,
    status: &str,
    buffer: f64,
    runs: u32,
    run: &RunSummary,
    products: &FanoutSummary,
) -> TaskRecord {
    let volume = match products.get("volume") {
        Some(ProductSummary::Volume(v)) => v.partials.clone(),
        _ => None,
    };
    let outputs = products
        .0
        .iter()
        .filter_map(|(name, s)| match s {
            ProductSummary::Dem(d) => Some((name.clone(), d.path.clone())),
            ProductSummary::Contours(c) => Some((name.clone(), c.path.clone())),
            _ => None,
        })
        .collect();
    TaskRecord {
        index: i,
        status: status.to_string(),
        buffer,
        runs,
        points: run.points_kept,
        decoded: run.tiles.map_or(0, |t| t.points_decoded),
        stored: run.tiles.map_or(0, |t| t.points_stored),
        triangles: run.triangles,
        inside_uncounted: run.tiles.is_some_and(|t| t.skipped_inside),
        seconds: 0.0,
        peak_memory: None,
        outputs,
        bytes: Vec::new(),
        plan: String::new(),
        warnings: run.warnings.clone(),
        volume,
        extent: run.tiles.and_then(|t| t.extent),
        subtiles: run.tiles.map_or(0, |t| t.tiles),
    }
}

/// What to do about a damaged output of task `i` of the plan in `dir` (`resume`: one that
/// `run --all --resume` runs again, being missing or of another size).
pub(super) fn run_again(dir: &PlanDir, i: usize, resume: bool) -> String {
    format!(
        "run task {i} again (`sweeptin run {} --task {i}`{}), then merge",
        dir.join("plan.json").display(),
        if resume {
            ", or `--all --resume`, which runs every such task"
        } else {
            ""
        }
    )
}

#[cfg(test)]
mod tests;
