//! Tile plans: `plan.json` written, its tasks run and merged through the library's `plan`
//! module, the same manifest as the command line's `plan` / `run` / `merge`.

use crate::errors::value_error;
use crate::files::raster_options;
use crate::memory::{align, duplicates};
use crate::to_py;
use pyo3::prelude::*;
use std::path::PathBuf;
use sweeptin::input::las::Returns;
use sweeptin::plan::{Job, Levels, Plan, PlanLines, Product, TaskOptions};

/// The job's options (a dict built by the package).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct JobOpts {
    product: String,
    cell: f64,
    align: String,
    nodata: f32,
    format: Option<String>,
    compress: Option<String>,
    predictor: Option<String>,
    bigtiff: bool,
    contours: Option<PathBuf>,
    interval: f64,
    base: f64,
    plane: Option<f64>,
    boundary: Option<PathBuf>,
    classes: Option<Vec<u8>>,
    returns: String,
    keep_withheld: bool,
    duplicates: String,
    max_edge: Option<f64>,
    breaklines: Vec<PathBuf>,
    trim_boundary: Option<PathBuf>,
    holes: Option<PathBuf>,
    crs: Option<String>,
    mem: u64,
    tmp_dir: Option<PathBuf>,
    /// `ground=True`: the filter's parameters (every task finds the ground of its area).
    ground: Option<crate::ground::ParamsOpts>,
}

/// Writes `DIR/plan.json` for the job over `files` (`DIR` a directory or an `s3://` prefix);
/// returns its path or URL.
#[pyfunction]
#[pyo3(signature = (files, dir, tile, buffer, job, args))]
pub(crate) fn make_plan(
    py: Python<'_>,
    files: Vec<PathBuf>,
    dir: PathBuf,
    tile: f64,
    buffer: Option<f64>,
    job: JobOpts,
    args: Vec<String>,
) -> PyResult<std::ffi::OsString> {
    let levels = Levels {
        interval: job.interval,
        base: job.base,
        decimals: None,
        min_length: 0.0,
    };
    let product = match job.product.as_str() {
        "dem" => Product::Dem {
            cell: job.cell,
            align: align(&job.align)?,
            nodata: job.nodata,
            raster: raster_options(
                job.format.as_deref(),
                job.compress.as_deref(),
                job.predictor.as_deref(),
                job.bigtiff,
            )?,
            contours: job.contours.as_ref().map(|_| levels),
        },
        "contours" => Product::Contours(levels),
        "volume" => Product::Volume {
            plane: job
                .plane
                .ok_or_else(|| value_error("a volume plan needs plane=Z"))?,
            boundary: job
                .boundary
                .as_deref()
                .map(sweeptin::plan::LineFile::new)
                .transpose()
                .map_err(to_py)?,
        },
        "tin" => Product::Tin,
        // The classification itself tiled (`sweeptin plan ground`): every point kept.
        "ground" => Product::Ground,
        p => {
            return Err(value_error(format!(
                "product={p:?}: a plan makes 'dem', 'contours', 'volume', 'tin' or 'ground'"
            )));
        }
    };
    let points = product == Product::Ground;
    if points && job.ground.is_none() {
        return Err(value_error("a ground plan needs the filter (ground=True)"));
    }
    let returns = match job.returns.as_str() {
        "all" => Returns::All,
        "first" => Returns::First,
        "last" => Returns::Last,
        r => {
            return Err(value_error(format!(
                "returns={r:?}: use 'all', 'first' or 'last'"
            )));
        }
    };
    let typed = Job {
        product,
        classes: if points { None } else { job.classes },
        returns,
        drop_withheld: !(job.keep_withheld || points),
        duplicates: duplicates(&job.duplicates)?,
        max_edge: job.max_edge,
        crs: job.crs,
        mem: job.mem,
        tmp_dir: job.tmp_dir,
        lines: PlanLines::new(
            &job.breaklines,
            job.trim_boundary.as_deref(),
            job.holes.as_deref(),
        )
        .map_err(to_py)?,
        ground: job.ground.as_ref().map(|g| g.params()).transpose()?,
    };
    let mut outputs = vec![("dir".to_string(), dir.clone())];
    if let Some(c) = job.contours {
        outputs.push(("contours".to_string(), c));
    }
    crate::errors::detach_guarded(py, || -> sweeptin::Result<PathBuf> {
        // A local directory or an s3:// prefix, whose bucket is checked before any work.
        let plan_dir = sweeptin::plan::PlanDir::new(&dir)?;
        plan_dir.check_writable()?;
        // A ground plan's tasks read what their ground blocks need: no buffer.
        let buffer = if points {
            0.0
        } else {
            buffer.unwrap_or(tile / 10.0)
        };
        // `@lists`, globs and `.vpc` files expanded, every file by absolute path.
        let plan = Plan::new(typed, args, outputs, &files, tile, buffer)?;
        // A point store is written in a local plan directory only (as `plan` decides).
        let plan = match plan_dir.is_remote() {
            true => plan.without_point_store(),
            false => plan,
        };
        // The line files are inputs too: no output may replace one.
        let inputs: Vec<PathBuf> = plan
            .files
            .iter()
            .map(|f| f.path.clone())
            .chain(
                plan.job
                    .lines
                    .iter()
                    .flat_map(|l| l.files().map(|f| f.path.clone())),
            )
            .collect();
        let planned: Vec<(&str, &std::path::Path)> = plan
            .outputs
            .iter()
            .filter(|(n, _)| n != "dir")
            .map(|(n, p)| (n.as_str(), p.as_path()))
            .collect();
        sweeptin::output::distinct_outputs(&planned, &inputs, "the plan")?;
        plan.save(&plan_dir)
    })
    // A str, not a pathlib.Path: a path would fold `s3://` into `s3:/`.
    .map(PathBuf::into_os_string)
    .map_err(to_py)
}

/// The number of tasks of the plan `path`.
#[pyfunction]
pub(crate) fn task_count(path: PathBuf) -> PyResult<usize> {
    Ok(Plan::load(&path).map_err(to_py)?.tiles.len())
}

/// Runs task `i` of the plan `path` (skipped when `resume` and it finished); returns its record
/// as JSON text.
#[pyfunction]
#[pyo3(signature = (path, i, threads = 0, resume = false, progress = false))]
pub(crate) fn run_task(
    py: Python<'_>,
    path: PathBuf,
    i: i64,
    threads: i64,
    resume: bool,
    progress: bool,
) -> PyResult<String> {
    let i = crate::files::count(i, "i", 0)?;
    let threads = crate::files::count(threads, "threads", 0)?;
    crate::errors::detach_guarded(py, || -> sweeptin::Result<String> {
        let plan = Plan::load(&path)?;
        let dir = Plan::dir_of(&path)?;
        plan.task(i)?;
        let record = match plan.record(&dir, i)? {
            Some(r) if resume && plan.finished(&dir, i) => r,
            _ => plan.run_task(&dir, i, &TaskOptions { threads, progress })?,
        };
        serde_json::to_string(&record).map_err(|e| sweeptin::Error::Internal(e.to_string()))
    })
    .map_err(to_py)
}

/// Where a merge writes and how (a dict built by the package).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct MergeOpts {
    out: Option<PathBuf>,
    contours: Option<PathBuf>,
    hillshade: Option<PathBuf>,
    format: Option<String>,
    compress: Option<String>,
    predictor: Option<String>,
    bigtiff: bool,
    /// `"data"` (one run's grid) or `"tiles"`.
    extent: String,
    /// The memory budget (parsed by the package as `--mem`).
    mem: u64,
}

/// Joins the finished tasks of the plan `path`; returns the summary as JSON text.
#[pyfunction]
pub(crate) fn merge(py: Python<'_>, path: PathBuf, opts: MergeOpts) -> PyResult<String> {
    let outputs = sweeptin::plan::merge::MergeOutputs {
        out: opts.out,
        contours: opts.contours,
        hillshade: opts.hillshade,
        raster: raster_options(
            opts.format.as_deref(),
            opts.compress.as_deref(),
            opts.predictor.as_deref(),
            opts.bigtiff,
        )?,
        extent: opts.extent.parse().map_err(to_py)?,
        mem: opts.mem,
    };
    crate::errors::detach_guarded(py, || -> sweeptin::Result<String> {
        let plan = Plan::load(&path)?;
        let dir = Plan::dir_of(&path)?;
        let s = sweeptin::plan::merge::merge_plan(&plan, &dir, &outputs)?;
        serde_json::to_string(&s).map_err(|e| sweeptin::Error::Internal(e.to_string()))
    })
    .map_err(to_py)
}
