//! `sweeptin plan`, `sweeptin run` and `sweeptin merge`: one product job cut into exact tiles,
//! run as tasks of a batch engine (or locally), and joined into one seamless result. See
//! [`sweeptin::plan`] and `docs/SCALING.md`.

use super::input::{ProductInput, distinct_outputs, run_products};
use super::products::shade;
use super::{Cli, Command};
use anyhow::{Context, bail};
use clap::Parser;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweeptin::Error;
use sweeptin::output::raster::RasterFormat;
use sweeptin::plan::{Plan, TaskRecord, merge, task_from_env};
use sweeptin::sink::{Fanout, FanoutSummary, ProductSummary, StreamInfo, TriangleSink};

/// Arguments of `sweeptin plan`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  sweeptin plan dem tiles/*.laz --cell 1 --class 2 --tile 1000 \
                        -o job\n  sweeptin run job/plan.json --all --jobs 2\n  sweeptin merge \
                        job/plan.json -o dtm.tif"
)]
pub struct PlanArgs {
    /// The first buffer of every task: points this far around its tile are read (default: a
    /// tenth of the tile). A task whose triangles need points farther out doubles it and runs
    /// again, so this only tunes the work, never the result.
    #[arg(long, value_name = "DISTANCE")]
    pub buffer: Option<f64>,
    /// The product command (`dem`, `contours` or `volume --plane Z`) with its input files and
    /// options as for a single run, plus `--tile SIZE` (the plan's tile side, a multiple of the
    /// cell) and `-o DIR` (where the plan and the tiles' outputs go).
    #[arg(
        trailing_var_arg = true,
        allow_hyphen_values = true,
        required = true,
        value_name = "COMMAND"
    )]
    pub command: Vec<String>,
}

/// Arguments of `sweeptin run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The plan (`DIR/plan.json`, written by `sweeptin plan`).
    pub plan: PathBuf,
    /// The task to run (0-based). Default: from SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX
    /// (Kubernetes Indexed Job), AWS_BATCH_JOB_ARRAY_INDEX, PBS_ARRAY_INDEX or SGE_TASK_ID.
    #[arg(long, value_name = "I", conflicts_with = "all")]
    pub task: Option<usize>,
    /// Run every task here, --jobs at a time.
    #[arg(long)]
    pub all: bool,
    /// With --all: tasks run at once (each on cores / jobs threads).
    #[arg(long, value_name = "N", default_value_t = 1, requires = "all")]
    pub jobs: usize,
    /// Skip tasks that already finished (their record `tiles/task_<i>.json` exists).
    #[arg(long)]
    pub resume: bool,
    /// Threads per task (default: every core, divided among --jobs).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the task's record as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `sweeptin merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The plan (`DIR/plan.json`).
    pub plan: PathBuf,
    /// The mosaic: `OUT.vrt` (a GDAL VRT over the tile GeoTIFFs) or `OUT.tif` (one GeoTIFF) for
    /// a DEM plan; `OUT.geojson` for a contour plan; not needed for a volume plan.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// For a DEM plan made with --contours: the stitched contour lines (default: the path the
    /// plan was given).
    #[arg(long, value_name = "GEOJSON")]
    pub contours: Option<PathBuf>,
    /// For a DEM plan merged into one GeoTIFF: a hillshade PNG of the whole mosaic (no seams).
    #[arg(long, value_name = "PNG")]
    pub hillshade: Option<PathBuf>,
    /// For a DEM plan: the mosaic's format (`tif`, `cog`) and compression (default: the plan's).
    #[command(flatten)]
    pub raster: super::products::RasterArgs,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

/// The plan's command, parsed back from its stored command line.
enum Job {
    Dem(Box<super::dem::Args>),
    Contours(Box<super::contours::Args>),
    Volume(Box<super::volume::Args>),
}

impl Job {
    fn input(&self) -> &ProductInput {
        match self {
            Job::Dem(a) => &a.input,
            Job::Contours(a) => &a.input,
            Job::Volume(a) => &a.input,
        }
    }

    fn input_mut(&mut self) -> &mut ProductInput {
        match self {
            Job::Dem(a) => &mut a.input,
            Job::Contours(a) => &mut a.input,
            Job::Volume(a) => &mut a.input,
        }
    }
}

/// Splits `-o X`, `--output X`, `--output=X` or `-oX` off a command line.
fn take_output(argv: &[String]) -> (Vec<String>, Option<PathBuf>) {
    let mut rest = Vec::with_capacity(argv.len());
    let mut out = None;
    let mut it = argv.iter();
    while let Some(a) = it.next() {
        if a == "-o" || a == "--output" {
            out = it.next().map(PathBuf::from);
        } else if let Some(v) = a.strip_prefix("--output=") {
            out = Some(PathBuf::from(v));
        } else if let Some(v) = a
            .strip_prefix("-o")
            .filter(|v| !v.is_empty() && !a.starts_with("--"))
        {
            out = Some(PathBuf::from(v));
        } else {
            rest.push(a.clone());
        }
    }
    (rest, out)
}

/// Parses a plan's command line (`dem FILES… options`, without `-o`) into its command.
fn parse_job(argv: &[String]) -> anyhow::Result<Job> {
    let name = argv.first().map(String::as_str).unwrap_or("");
    if !matches!(name, "dem" | "contours" | "volume") {
        bail!(
            "a plan runs `dem`, `contours` or `volume --plane Z`, not `{name}` (a single mesh \
             of many tiles is made by one `sweeptin tin` run, on every core)"
        );
    }
    let mut full = vec!["sweeptin".to_string()];
    full.extend(argv.iter().cloned());
    if matches!(name, "dem" | "contours") {
        // A placeholder: every task writes under the plan's directory.
        full.extend(["-o".to_string(), "plan-output".to_string()]);
    }
    let cli = match Cli::try_parse_from(&full) {
        Ok(c) => c,
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelp => {
            // `sweeptin plan dem --help`: the command's own help, then stop.
            let _ = e.print();
            std::process::exit(0);
        }
        Err(e) => {
            let text = e.to_string();
            let text = text.trim_start_matches("error: ").trim_end();
            bail!("{text}");
        }
    };
    Ok(match cli.command {
        Command::Dem(a) => Job::Dem(Box::new(a)),
        Command::Contours(a) => Job::Contours(Box::new(a)),
        Command::Volume(a) => Job::Volume(Box::new(a)),
        _ => unreachable!("checked above"),
    })
}

/// Refuses what a plan cannot run exactly, before anything is written.
fn check_job(job: &Job) -> anyhow::Result<()> {
    let a = &job.input().args;
    if a.filter.bbox.is_some() {
        bail!("a plan covers its files whole: leave --bbox out (the tiles cut the area)");
    }
    let l = &a.lines;
    if !l.breaklines.is_empty() || l.boundary.is_some() || l.holes.is_some() || l.no_flat_triangles
    {
        bail!(
            "breaklines, --trim-boundary, --holes and --no-flat-triangles are not yet proved exact \
             in tiles, so a plan refuses them: run the job as one `sweeptin {}` (one sweep)",
            match job {
                Job::Dem(_) => "dem",
                Job::Contours(_) => "contours",
                Job::Volume(_) => "volume",
            }
        );
    }
    if a.engine == super::input::Engine::Sweep {
        bail!("a plan runs the tiled engine: leave --engine sweep out");
    }
    if a.sweep_axis == sweeptin::pipeline::SweepAxis::X {
        bail!("a plan sweeps along y: leave --sweep-axis x out");
    }
    if let Some(p) = a
        .inputs
        .iter()
        .find(|p| !matches!(extension(p).as_deref(), Some("las" | "laz")))
    {
        bail!(
            "{}: a plan reads LAS/LAZ files (their headers give the extents)",
            p.display()
        );
    }
    match job {
        Job::Dem(d) if d.dem.snap || d.dem.buffer.is_some() => {
            bail!("a plan's DEM covers the tiles: leave --snap and --buffer out");
        }
        Job::Volume(v) if v.plane.is_none() => {
            bail!("a plan computes volumes against a plane (--plane Z); --surface needs one run")
        }
        _ => {}
    }
    Ok(())
}

pub fn plan(args: PlanArgs) -> anyhow::Result<()> {
    let (argv, dir) = take_output(&args.command);
    let mut job = parse_job(&argv)?;
    let dir = dir.context("give the plan's directory with -o DIR")?;
    // `@list.txt`, quoted globs and `.vpc` files: the plan names every file (it reads each
    // header), each given input standing for its files in the stored command line.
    let given = job.input().args.inputs.clone();
    let groups: Vec<Vec<PathBuf>> = given
        .iter()
        .map(|g| {
            sweeptin::input::files::expand(
                std::slice::from_ref(g),
                sweeptin::input::files::Expand::VpcFiles,
            )
        })
        .collect::<Result<_, _>>()?;
    job.input_mut().args.inputs = groups.iter().flatten().cloned().collect();
    check_job(&job)?;
    let a = &job.input().args;
    let tile = a
        .tile
        .context("give the plan's tile side with --tile SIZE (e.g. --tile 1000)")?;
    let (cell, mut outputs) = match &job {
        Job::Dem(d) => {
            let mut o = Vec::new();
            if let Some(c) = &d.contours {
                o.push(("contours".to_string(), c.clone()));
            }
            if let Some(h) = &d.hillshade {
                o.push(("hillshade".to_string(), h.clone()));
            }
            (Some(d.dem.cell), o)
        }
        _ => (None, Vec::new()),
    };
    outputs.insert(0, ("dir".to_string(), dir.clone()));
    if let Some(c) = cell
        && tile / c > 16384.0
    {
        bail!(
            "--tile {tile} holds {:.0} × {:.0} cells of {c}: a task's raster is limited to 16384 \
             cells a side (use a smaller --tile)",
            tile / c,
            tile / c
        );
    }
    let buffer = args.buffer.unwrap_or(tile / 10.0);
    let canonical = |p: &PathBuf| {
        std::fs::canonicalize(p).with_context(|| format!("cannot read {}", p.display()))
    };
    let inputs: Vec<PathBuf> = a
        .inputs
        .iter()
        .map(canonical)
        .collect::<anyhow::Result<_>>()?;
    let abs_groups: Vec<Vec<PathBuf>> = groups
        .iter()
        .map(|g| g.iter().map(canonical).collect::<anyhow::Result<_>>())
        .collect::<anyhow::Result<_>>()?;
    // The stored command line names the inputs by absolute path, so tasks run from anywhere.
    let argv = absolute_inputs(&argv, &given, &abs_groups);
    // The files must make one point set (one CRS, compatible formats), as for a single run:
    // refused now, from the headers, not by every task later.
    sweeptin::input::las::LidarReader::open(&inputs, &a.filter.to_filter())?;
    let plan = Plan::new(&argv[0], argv.clone(), outputs, &inputs, tile, buffer, cell)?;
    if dir.exists() && !dir.is_dir() {
        bail!("{}: not a directory", dir.display());
    }
    // Outputs the plan will write later must not be its inputs.
    let mut planned_outputs: Vec<(&str, &Path)> = vec![];
    for (name, p) in plan.outputs.iter().filter(|(n, _)| n != "dir") {
        planned_outputs.push((name.as_str(), p.as_path()));
    }
    distinct_outputs(&planned_outputs, &inputs, "the plan")?;
    let path = plan.save(&dir)?;
    if plan.tiles.len() > 1000 {
        eprintln!(
            "sweeptin: warning: {} tasks: Slurm's default MaxArraySize is 1001; a larger --tile \
             makes fewer, longer tasks",
            plan.tiles.len()
        );
    }
    let points: u64 = plan.files.iter().map(|f| f.points).sum();
    eprintln!(
        "sweeptin: {} tasks (tiles of {tile}, first buffer {buffer}) over {} files, {points} \
         points -> {}",
        plan.tiles.len(),
        plan.files.len(),
        path.display()
    );
    println!("{}", plan.tiles.len());
    eprintln!(
        "  next: sweeptin run {} --all --jobs N   (or a job array of {} tasks: --array=0-{})",
        path.display(),
        plan.tiles.len(),
        plan.tiles.len().saturating_sub(1)
    );
    Ok(())
}

/// `argv` with each input replaced by its absolute path.
fn absolute_inputs(argv: &[String], given: &[PathBuf], abs: &[Vec<PathBuf>]) -> Vec<String> {
    argv.iter()
        .flat_map(|s| {
            given
                .iter()
                .position(|g| g.as_os_str() == s.as_str())
                .map_or_else(
                    || vec![s.clone()],
                    |i| abs[i].iter().map(|p| p.display().to_string()).collect(),
                )
        })
        .collect()
}

/// The directory of a plan file.
/// The directory of a plan file, absolute (task records then name their outputs wherever the
/// task ran from).
fn plan_dir(path: &Path) -> anyhow::Result<PathBuf> {
    let abs = std::path::absolute(path)
        .with_context(|| format!("{}: cannot resolve the path", path.display()))?;
    Ok(match abs.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    })
}

pub fn run(args: RunArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.plan)?;
    let dir = plan_dir(&args.plan)?;
    if args.all {
        return super::run_all::run_all(&plan, &dir, &args);
    }
    let from_env = match args.task {
        Some(_) => None,
        None => task_from_env()?,
    };
    let i = match args.task.or(from_env) {
        Some(i) => i,
        None => bail!(
            "which task? give --task I (0 to {}) or --all, or run under a job array \
             (SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX, \
             PBS_ARRAY_INDEX, SGE_TASK_ID)",
            plan.tiles.len().saturating_sub(1)
        ),
    };
    plan.task(i)?;
    if args.resume
        && finished(&plan, &dir, i)
        && let Some(r) = plan.record(&dir, i)?
    {
        eprintln!(
            "sweeptin: task {i} already finished ({}): skipped",
            r.status
        );
        return Ok(());
    }
    let r = run_task(&plan, &dir, i, &args)?;
    if args.json {
        println!("{}", serde_json::to_string(&r)?);
    } else if !args.quiet {
        eprintln!(
            "sweeptin: task {i} {}: {} points, {} triangles, buffer {} after {} run(s), {:.2} s",
            r.status, r.points, r.triangles, r.buffer, r.runs, r.seconds
        );
    }
    Ok(())
}

/// Runs task `i` until its buffer is wide enough; writes its outputs and then its record.
fn run_task(plan: &Plan, dir: &Path, i: usize, args: &RunArgs) -> anyhow::Result<TaskRecord> {
    let start = Instant::now();
    let mut buffer = plan.buffer;
    let mut runs = 0;
    let mut job = parse_job(&plan.args)?;
    let record = loop {
        runs += 1;
        plan.check_files(i, buffer)?;
        let sinks = task_sinks(plan, dir, i, buffer, args, &mut job)?;
        let input = job.input();
        let config = input.config(None)?;
        match run_products(input, &config, None, sinks) {
            Ok((run, products)) => {
                let status = if run.triangles == 0 { "empty" } else { "done" };
                break record_of(
                    i,
                    status,
                    buffer,
                    runs,
                    &run,
                    &products,
                    job_outputs(&products),
                );
            }
            Err(e) => match e.downcast_ref::<Error>() {
                Some(Error::BufferTooSmall { reach, .. }) if runs < 40 => {
                    // Straight to the files the certificates reached, or double.
                    let step = plan.tile / 16.0;
                    buffer = if *reach > buffer {
                        (*reach / step).ceil() * step
                    } else if buffer > 0.0 {
                        2.0 * buffer
                    } else {
                        plan.tile / 8.0
                    };
                }
                Some(Error::TooFewPoints { .. }) => {
                    let sinks = task_sinks(plan, dir, i, buffer, args, &mut job)?;
                    let products = empty_task(plan, i, job.input(), sinks)?;
                    let run = sweeptin::pipeline::RunSummary::default();
                    eprintln!(
                        "sweeptin: warning: task {i} has no point after the filters: its \
                         outputs are empty (a nodata raster), which is not a failure"
                    );
                    break record_of(
                        i,
                        "empty",
                        buffer,
                        runs,
                        &run,
                        &products,
                        job_outputs(&products),
                    );
                }
                _ => return Err(e.context(format!("task {i} of {}", plan.tiles.len()))),
            },
        }
    };
    let mut record = record;
    record.seconds = start.elapsed().as_secs_f64();
    plan.finish_task(dir, &record)?;
    Ok(record)
}

/// The outputs the sinks wrote, by name.
fn job_outputs(products: &FanoutSummary) -> Vec<(String, PathBuf)> {
    products
        .0
        .iter()
        .filter_map(|(name, s)| match s {
            ProductSummary::Dem(d) => Some((name.clone(), d.path.clone())),
            ProductSummary::Contours(c) => Some((name.clone(), c.path.clone())),
            _ => None,
        })
        .collect()
}

fn record_of(
    i: usize,
    status: &str,
    buffer: f64,
    runs: u32,
    run: &sweeptin::pipeline::RunSummary,
    products: &FanoutSummary,
    outputs: Vec<(String, PathBuf)>,
) -> TaskRecord {
    let volume = match products.get("volume") {
        Some(ProductSummary::Volume(v)) => v.partials.clone(),
        _ => None,
    };
    TaskRecord {
        index: i,
        status: status.to_string(),
        buffer,
        runs,
        points: run.points_kept,
        triangles: run.triangles,
        seconds: 0.0,
        outputs,
        volume,
    }
}

/// Points the job at task `i` with a buffer of `buffer` and builds its sinks.
fn task_sinks(
    plan: &Plan,
    dir: &Path,
    i: usize,
    buffer: f64,
    args: &RunArgs,
    job: &mut Job,
) -> anyhow::Result<Vec<(String, Box<dyn TriangleSink>)>> {
    let tile = plan.task(i)?.bounds;
    {
        let a = &mut job.input_mut().args;
        a.inputs = plan.task_files(i, buffer)?;
        a.task = Some(plan.scope(i, buffer)?);
        a.engine = super::input::Engine::Tiles;
        a.tile = Some(plan.tile);
        a.quiet = args.quiet || args.json || args.all;
        a.json = false;
        if let Some(t) = args.threads {
            a.threads = t;
        }
    }
    Ok(match job {
        Job::Dem(d) => {
            d.output = plan.task_output(dir, i, "dem", "tif");
            // The tasks' tiles are plain GeoTIFFs; the mosaic gets the plan's --format.
            d.dem.raster = super::products::RasterArgs {
                format: Some(RasterFormat::GeoTiff),
                ..Default::default()
            };
            d.dem.grid_bbox = Some(tile);
            d.hillshade = None;
            if d.contours.is_some() {
                d.contours = Some(plan.task_output(dir, i, "contours", "geojson"));
                d.contour.edges = true;
            }
            super::dem::sinks(d)?
        }
        Job::Contours(c) => {
            c.output = plan.task_output(dir, i, "contours", "geojson");
            c.contour.edges = true;
            vec![("contours".to_string(), c.contour.sink(&c.output)?)]
        }
        Job::Volume(v) => {
            let s = super::volume::plane_sink(v)?.context("a plan's volume needs --plane")?;
            vec![("volume".to_string(), s)]
        }
    })
}

/// The outputs of a task with no point: a nodata raster over its tile, no contours, no volume.
fn empty_task(
    plan: &Plan,
    i: usize,
    input: &ProductInput,
    sinks: Vec<(String, Box<dyn TriangleSink>)>,
) -> anyhow::Result<FanoutSummary> {
    let crs = match input.crs()? {
        Some(c) => Some(c),
        None if !input.args.inputs.is_empty() => sweeptin::input::las::LidarReader::open(
            &input.args.inputs,
            &input.args.filter.to_filter(),
        )?
        .crs()
        .cloned(),
        None => None,
    };
    let mut fanout = Fanout::new(sinks);
    fanout.begin(&StreamInfo {
        crs,
        bounds: plan.task(i)?.bounds,
    })?;
    match fanout.finish()? {
        ProductSummary::Fanout(s) => Ok(s),
        other => {
            Err(sweeptin::Error::Internal(format!("the products' summary is {other:?}")).into())
        }
    }
}

pub fn merge(args: MergeArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.plan)?;
    let dir = plan_dir(&args.plan)?;
    let job = parse_job(&plan.args)?;
    let crs = job.input().crs()?;
    let mut outs: Vec<(&str, &Path)> = Vec::new();
    if let Some(o) = &args.output {
        outs.push(("-o", o));
    }
    let contours = args.contours.clone().or_else(|| planned(&plan, "contours"));
    let hillshade = args
        .hillshade
        .clone()
        .or_else(|| planned(&plan, "hillshade"));
    if let Some(c) = &contours {
        outs.push(("--contours", c));
    }
    if let Some(h) = &hillshade {
        outs.push(("--hillshade", h));
    }
    let mut protected: Vec<PathBuf> = plan.files.iter().map(|f| f.path.clone()).collect();
    protected.push(args.plan.clone());
    distinct_outputs(&outs, &protected, "the plan")?;
    for (flag, o) in &outs {
        let abs = std::path::absolute(o).unwrap_or_else(|_| o.to_path_buf());
        if abs.starts_with(dir.join("tiles")) {
            bail!(
                "{flag} {}: that is where the tasks' outputs are",
                o.display()
            );
        }
    }
    let recs = merge::records(&plan, &dir)?;
    if !recs.is_empty() && recs.iter().all(|r| r.points == 0) {
        bail!(
            "no task found a point after the filters: nothing to merge (check --class and the \
             other filters of the plan)"
        );
    }
    let mut summary = serde_json::Map::new();
    match &job {
        Job::Dem(d) => {
            let out = args
                .output
                .as_deref()
                .context("give the mosaic with -o OUT.vrt or OUT.tif")?;
            if !matches!(extension(out).as_deref(), Some("vrt" | "tif" | "tiff")) {
                bail!("-o {}: a DEM mosaic is a .vrt or a .tif", out.display());
            }
            if args.raster.format == Some(RasterFormat::Ascii) {
                bail!("--format asc: a DEM mosaic is a GeoTIFF (tif, cog) or a VRT");
            }
            super::input::check_output(out)?;
            let crs = match crs {
                Some(c) => Some(c),
                None => plan_crs(&plan)?,
            };
            let mut output = args.raster.options();
            if output == Default::default() && extension(out).as_deref() != Some("vrt") {
                // The plan's own --format / --compress, as one run would have written.
                output = d.dem.raster.options();
            }
            let options = merge::MosaicOptions {
                nodata: d.dem.nodata,
                align: d.dem.align,
                output,
            };
            let s = merge::merge_dem(&plan, &dir, out, &options, crs.as_ref())?;
            summary.insert("dem".into(), serde_json::to_value(&s)?);
            if let (Some(c), true) = (&contours, d.contours.is_some()) {
                let s = merge::merge_contours(&plan, &dir, c, crs.as_ref())?;
                summary.insert("contours".into(), serde_json::to_value(s)?);
            }
            if let Some(png) = args
                .hillshade
                .clone()
                .or_else(|| planned(&plan, "hillshade"))
            {
                if RasterFormat::from_extension(out) != Some(RasterFormat::GeoTiff)
                    || output.format == Some(RasterFormat::Ascii)
                {
                    bail!("--hillshade shades a GeoTIFF mosaic: merge with -o OUT.tif");
                }
                let (p, h) = shade(out, &png)?;
                let mut v = serde_json::to_value(h)?;
                v["path"] = serde_json::json!(p);
                summary.insert("hillshade".into(), v);
            }
        }
        Job::Contours(_) => {
            let out = args
                .output
                .as_deref()
                .context("give the contours with -o OUT.geojson")?;
            if !matches!(extension(out).as_deref(), Some("geojson" | "json")) {
                bail!(
                    "-o {}: contours are written as GeoJSON (.geojson)",
                    out.display()
                );
            }
            super::input::check_output(out)?;
            let s = merge::merge_contours(&plan, &dir, out, crs.as_ref())?;
            summary.insert("contours".into(), serde_json::to_value(s)?);
        }
        Job::Volume(_) => {
            if let Some(o) = &args.output {
                bail!(
                    "-o {}: a volume plan writes no file (its totals are printed; --json for a \
                     summary)",
                    o.display()
                );
            }
            let t = merge::merge_volume(&plan, &dir)?;
            if !args.json {
                println!("the tasks' volumes, summed:");
                super::volume::print_totals(&t);
            }
            summary.insert("volume".into(), serde_json::to_value(t)?);
        }
    }
    let empty = recs.iter().filter(|r| r.status == "empty").count();
    summary.insert("tasks".into(), serde_json::json!(recs.len()));
    summary.insert("empty_tasks".into(), serde_json::json!(empty));
    summary.insert(
        "max_buffer".into(),
        serde_json::json!(recs.iter().map(|r| r.buffer).fold(0.0, f64::max)),
    );
    if args.json {
        println!("{}", serde_json::Value::Object(summary));
    } else {
        eprintln!(
            "sweeptin: merged {} tasks ({empty} empty){}",
            recs.len(),
            args.output
                .as_ref()
                .map(|p| format!(" -> {}", p.display()))
                .unwrap_or_default()
        );
    }
    Ok(())
}

/// An output the plan's command was given (`--contours`, `--hillshade`).
fn planned(plan: &Plan, name: &str) -> Option<PathBuf> {
    plan.outputs
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, p)| p.clone())
}

/// The CRS of the plan's first file (as a single run takes it from the headers).
fn plan_crs(plan: &Plan) -> anyhow::Result<Option<sweeptin::crs::Crs>> {
    let Some(f) = plan.files.first() else {
        return Ok(None);
    };
    let r = sweeptin::input::las::LidarReader::open(
        std::slice::from_ref(&f.path),
        &sweeptin::input::las::Filter::default(),
    )?;
    Ok(r.crs().cloned())
}

/// The lower-case extension of `p`.
fn extension(p: &Path) -> Option<String> {
    p.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// Has task `i` finished, with its record readable and every output it names present? (What
/// `--resume` skips; anything less runs again.)
pub(super) fn finished(plan: &Plan, dir: &Path, i: usize) -> bool {
    match plan.record(dir, i) {
        Ok(Some(r)) => r.outputs.iter().all(|(_, p)| dir.join(p).is_file()),
        _ => false,
    }
}
