//! `sweeptin plan`, `sweeptin run` and `sweeptin merge`: one product job cut into exact tiles,
//! run as tasks of a batch engine (or locally), and joined into one seamless result. See
//! [`sweeptin::plan`] and `docs/SCALING.md`.

use super::input::{InputArgs, ProductInput};
use super::{Cli, Command};
use anyhow::{Context, bail};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use sweeptin::fmt::{Figure, count};
use sweeptin::plan::{
    Levels, Plan, PlanDir, Product, TaskOptions, TaskRecord, merge, task_from_env,
};

/// What `sweeptin plan --help` ends with.
const PLAN_HELP: &str = "\
Example:
  sweeptin plan dem tiles/*.laz --cell 1 --class 2 --tile 1000 -o job
  sweeptin run job/plan.json --all --jobs 2
  sweeptin merge job/plan.json -o dtm.tif

Breaklines and trimming rings (--breaklines, --trim-boundary, --holes) go into every task when
every vertex has a z (3-D lines; the rings too: they become edges of the TIN). The plan reads and
cleans them once to check, and records each file by absolute path with its size and SHA-256; each
task cleans them again (the same graph in every task) and refuses a file that changed. Lines
without z take their heights from all the points, which no task reads: give them z, e.g. for a
text file of `x y` lines (a blank line between lines)
  sweeptin sample tiles/*.laz --class 2 --points lines.txt -o lines_z.txt
and plan with --breaklines lines_z.txt (the result is one run's with those 3-D lines), or run the
job as one command. --clip-breaklines (the hull of all the points) and --no-flat-triangles (flips
across tiles) are refused.

--ground (the ground found on the fly, with the filter's options) goes into every task: each
classifies the ground of the area it reads as one run over all the files would, then reads only
that area; the merge is one `dem --ground` run's, byte for byte.

`plan ground FILES… --tile T -o JOB [--step S, --town, …, --reset, --mem, --tmp-dir]` tiles the
classification itself: each task classifies the ground blocks of its tile as one `sweeptin
ground` run over all FILES would and writes the points its tile owns ([x0, x1) × (y0, y1]), every
attribute kept, to JOB/tiles/ground_f<K>_<tx>_<ty>.laz (one file per input K with points there).
  sweeptin plan ground raw/*.laz --tile 1000 --town -o job
  sweeptin run job/plan.json --all --jobs 2
  sweeptin merge job/plan.json -o ground.vpc   # a VPC of the tiles, where they are
  sweeptin merge job/plan.json -o ground.laz   # one file: tasks in order, files in order
The single file needs the inputs' point formats, extra bytes and scales to agree; its points
are in tile order, not the inputs' order (compare points by x, y, z and GPS time).";

/// Arguments of `sweeptin plan`.
#[derive(clap::Args, Debug)]
#[command(after_help = PLAN_HELP)]
pub struct PlanArgs {
    /// The first buffer of every task: points this far around its tile are read (default: a
    /// tenth of the tile). A task whose triangles need points farther out doubles it and runs
    /// again, so this only tunes the work, never the result.
    #[arg(long, value_name = "DISTANCE")]
    pub buffer: Option<f64>,
    /// Give the tasks no hull band: by default, over one plain LAZ/LAS file (no breaklines, no
    /// `--ground`), the plan decodes the chunks along the data's edge once more and stores the
    /// points within 2 units of its convex hull, so that the tasks along the edge run once. The
    /// outputs are the same either way (for comparison). Implies --no-store.
    #[arg(long)]
    pub no_hull_band: bool,
    /// Make no point store: by default, where the hull band is used and the plan's directory is
    /// local, the plan's decoding pass writes the points after the filters into
    /// `DIR/index/points` (by cells of a quarter tile: about 12 bytes a point) instead of a
    /// chunk index, and every task reads the points of its tile and buffer from it instead of
    /// decoding the LAZ chunks there. The outputs are the same either way (for comparison, or
    /// to save the disk).
    #[arg(long)]
    pub no_store: bool,
    /// The product command (`dem`, `contours`, `volume --plane Z`, `tin` or `ground`) with its input files and
    /// options as for a single run, plus `--tile SIZE` (the plan's tile side, a multiple of the
    /// cell) and `-o DIR` (where the plan and the tiles' outputs go: a local directory, or
    /// `s3://BUCKET/JOB/` for workers that share no disk).
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
    /// The plan (`DIR/plan.json`, written by `sweeptin plan`, or `s3://BUCKET/JOB/plan.json`).
    pub plan: PathBuf,
    /// The task to run (0-based). Default: from SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX
    /// (Kubernetes Indexed Job), AWS_BATCH_JOB_ARRAY_INDEX, PBS_ARRAY_INDEX or SGE_TASK_ID.
    #[arg(long, value_name = "I", conflicts_with = "all")]
    pub task: Option<usize>,
    /// Run every task here, --jobs at a time. The exit status is the lowest failed task's; a
    /// task killed by a signal is named with it (SIGKILL, the out-of-memory killer's: 4; a
    /// crash: 5).
    #[arg(long)]
    pub all: bool,
    /// With --all: tasks run at once (each on cores / jobs threads).
    #[arg(long, value_name = "N", default_value_t = 1, requires = "all",
          value_parser = super::input::parse_threads)]
    pub jobs: usize,
    /// Skip tasks that already finished: their record `tiles/task_<i>.json` exists and their
    /// outputs have the sizes it records.
    #[arg(long)]
    pub resume: bool,
    /// Threads per task (default: every core, divided among --jobs).
    #[arg(long, value_name = "N", value_parser = super::input::parse_threads)]
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
    /// The plan (`DIR/plan.json`, or `s3://BUCKET/JOB/plan.json`).
    pub plan: PathBuf,
    /// The mosaic: `OUT.vrt` (a GDAL VRT over the tile GeoTIFFs) or `OUT.tif` (one GeoTIFF) for
    /// a DEM plan; `OUT.geojson` for a contour plan; `OUT.ply`, `.obj`, `.xml` (LandXML) or
    /// `.stin` for a TIN plan (one mesh, each vertex once); `OUT.vpc` (the tiles, where they are)
    /// or `OUT.laz`/`OUT.las` (one file) for a ground plan; not needed for a volume plan.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// For a DEM plan made with --contours: the stitched contour lines (default: the path the
    /// plan was given). Refused for other plans, whose tasks drew no lines to stitch.
    #[arg(long, value_name = "GEOJSON")]
    pub contours: Option<PathBuf>,
    /// For a DEM plan merged into one GeoTIFF: a hillshade of the whole mosaic (no seams), a
    /// PNG with a .pgw world file or an 8-bit GeoTIFF (.tif) (default: the path the plan was
    /// given).
    #[arg(long, value_name = "PNG")]
    pub hillshade: Option<PathBuf>,
    /// For a DEM plan: the mosaic's format (`tif`, `cog`) and compression (default: the plan's).
    #[command(flatten)]
    pub raster: super::products::RasterArgs,
    /// For a DEM plan: the mosaic's cells. `data`: the grid one `sweeptin dem` run over the
    /// plan's files and filters writes (every cell whose centre lies inside the points kept),
    /// the same header and cells; `tiles`: the whole tiles of the plan (nodata beyond the data).
    #[arg(long, value_name = "data|tiles", default_value = "data",
          value_parser = |s: &str| s.parse::<merge::MosaicExtent>())]
    pub extent: merge::MosaicExtent,
    /// Memory budget (e.g. 64M, 1G; at least 16M): every merge holds fixed buffers of a few MiB
    /// whatever the output's size; a compressed GeoTIFF or COG, or a ground plan's one point
    /// file, is compressed a quarter of it at a time, and the contour lines open at the tasks'
    /// edges may hold half of it (refused beyond, exit 4: give more).
    #[arg(long, value_name = "SIZE",
          default_value_t = super::input::Size(sweeptin::pipeline::default_mem()))]
    pub mem: super::input::Size,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
    /// No summary line on stderr (a volume plan's totals still go to stdout).
    #[arg(short, long)]
    pub quiet: bool,
}

/// The plan's command, parsed back from its stored command line.
enum Job {
    Dem(Box<super::dem::Args>),
    Contours(Box<super::contours::Args>),
    Volume(Box<super::volume::Args>),
    Tin(Box<super::tin::Args>),
}

impl Job {
    fn product_input(&self) -> Option<&ProductInput> {
        match self {
            Job::Dem(a) => Some(&a.input),
            Job::Contours(a) => Some(&a.input),
            Job::Volume(a) => Some(&a.input),
            Job::Tin(_) => None,
        }
    }

    /// The input options.
    fn args(&self) -> &InputArgs {
        match self {
            Job::Dem(a) => &a.input.args,
            Job::Contours(a) => &a.input.args,
            Job::Volume(a) => &a.input.args,
            Job::Tin(a) => &a.input,
        }
    }

    fn args_mut(&mut self) -> &mut InputArgs {
        match self {
            Job::Dem(a) => &mut a.input.args,
            Job::Contours(a) => &mut a.input.args,
            Job::Volume(a) => &mut a.input.args,
            Job::Tin(a) => &mut a.input,
        }
    }

    /// `--crs`.
    fn crs(&self) -> Option<String> {
        match self {
            Job::Tin(a) => a.crs.clone(),
            _ => self.product_input().and_then(|p| p.crs.clone()),
        }
    }

    /// `--trim-boundary` (for `tin`, also as `--boundary`).
    fn trim_boundary(&self) -> Option<PathBuf> {
        match self {
            Job::Tin(t) => t.boundary_polygon.clone(),
            _ => None,
        }
        .or_else(|| self.args().lines.boundary.clone())
    }

    fn name(&self) -> &'static str {
        match self {
            Job::Dem(_) => "dem",
            Job::Contours(_) => "contours",
            Job::Volume(_) => "volume",
            Job::Tin(_) => "tin",
        }
    }

    /// The library's job: what every task runs.
    fn typed(&self) -> anyhow::Result<sweeptin::plan::Job> {
        let levels = |c: &super::products::ContourArgs| Levels {
            interval: c.interval,
            base: c.base,
            decimals: c.precision,
            min_length: c.min_length,
        };
        let product = match self {
            Job::Dem(d) => Product::Dem {
                cell: d.dem.cell,
                align: d.dem.align,
                nodata: d.dem.nodata,
                raster: d.dem.raster.options(),
                contours: d.contours.as_ref().map(|_| levels(&d.contour)),
            },
            Job::Contours(c) => Product::Contours(levels(&c.contour)),
            Job::Volume(v) => Product::Volume {
                plane: v.plane.context("a plan's volume needs --plane")?,
                // Absolute, so that tasks run from anywhere.
                boundary: v
                    .boundary
                    .as_deref()
                    .map(sweeptin::plan::LineFile::new)
                    .transpose()?,
            },
            Job::Tin(_) => Product::Tin,
        };
        let a = self.args();
        let f = a.filter.to_filter();
        let l = &a.lines;
        Ok(sweeptin::plan::Job {
            // Absolute and fingerprinted: every task reads the same lines.
            lines: sweeptin::plan::PlanLines::new(
                &l.breaklines,
                self.trim_boundary().as_deref(),
                l.holes.as_deref(),
            )?
            .map(|p| p.with_z_tolerance(l.z_tolerance)),
            product,
            classes: f.classes,
            returns: f.returns,
            drop_withheld: f.drop_withheld,
            duplicates: a.duplicates,
            max_edge: a.lines.max_edge,
            crs: self.crs(),
            mem: a.mem.0,
            tmp_dir: a.tmp_dir.clone(),
            ground: a.ground.then(|| a.ground_options.params()),
        })
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
    if !matches!(name, "dem" | "contours" | "volume" | "tin") {
        bail!("a plan runs `dem`, `contours`, `volume --plane Z`, `tin` or `ground`, not `{name}`");
    }
    let mut full = vec!["sweeptin".to_string()];
    full.extend(argv.iter().cloned());
    if matches!(name, "dem" | "contours" | "tin") {
        // A placeholder: every task writes under the plan's directory.
        full.extend(["-o".to_string(), "plan-output".to_string()]);
    }
    // The job's `--io-timeout`/`--io-concurrency` hold for the plan's own reads (a remote `.vpc`).
    let parsed = <Cli as clap::CommandFactory>::command()
        .try_get_matches_from(&full)
        .and_then(|m| {
            super::apply_io_options(&m);
            <Cli as clap::FromArgMatches>::from_arg_matches(&m)
        });
    let cli = match parsed {
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
        Command::Tin(a) => Job::Tin(Box::new(a)),
        _ => unreachable!("checked above"),
    })
}

/// Refuses what a plan cannot run exactly, before anything is written.
fn check_job(job: &Job) -> anyhow::Result<()> {
    let a = job.args();
    if !a.ground && a.ground_options.any() {
        bail!(sweeptin::Error::Options(
            "the ground filter's options (--step, --max-angle, --town, …) apply with --ground: \
             add --ground to plan on the ground found on the fly"
                .into()
        ));
    }
    if a.filter.bbox.is_some() {
        bail!("a plan covers its files whole: leave --bbox out (the tiles cut the area)");
    }
    let l = &a.lines;
    if l.no_flat_triangles {
        bail!(
            "--no-flat-triangles flips triangles across tile edges, which no tile's certificate \
             covers, so a plan refuses it: run the job as one `sweeptin {}` (one sweep)",
            job.name()
        );
    }
    if l.clip_breaklines {
        bail!(sweeptin::pipeline::PLAN_REFUSES_CLIP);
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
        Job::Tin(t) if t.format.is_some() => {
            bail!("a TIN plan's mesh format is chosen at `sweeptin merge -o OUT.ply|obj|xml|stin`")
        }
        _ => {}
    }
    Ok(())
}

pub fn plan(args: PlanArgs) -> anyhow::Result<()> {
    let (argv, dir) = take_output(&args.command);
    if argv.first().map(String::as_str) == Some("ground") {
        if args.buffer.is_some() {
            bail!("a ground plan has no --buffer: each task reads what its ground blocks need");
        }
        return super::plan_ground::plan(&argv, dir);
    }
    let mut job = parse_job(&argv)?;
    let dir = dir.context("give the plan's directory with -o DIR")?;
    // A local directory or an S3 prefix, whose bucket is checked before any header is read.
    let plan_dir = PlanDir::new(&dir)?;
    plan_dir.check_writable()?;
    // `@list.txt`, quoted globs and `.vpc` files: the plan names every file (it reads each
    // header), each given input standing for its files in the stored command line.
    let given = job.args().inputs.clone();
    let groups: Vec<Vec<PathBuf>> = given
        .iter()
        .map(|g| {
            sweeptin::input::files::expand(
                std::slice::from_ref(g),
                sweeptin::input::files::Expand::VpcFiles,
            )
            .map(|e| e.files)
        })
        .collect::<Result<_, _>>()?;
    job.args_mut().inputs = groups.iter().flatten().cloned().collect();
    check_job(&job)?;
    let a = job.args();
    let tile = a
        .tile
        .context("give the plan's tile side with --tile SIZE (e.g. --tile 1000)")?;
    let mut outputs = Vec::new();
    if let Job::Dem(d) = &job {
        if let Some(c) = &d.contours {
            outputs.push(("contours".to_string(), c.clone()));
        }
        if let Some(h) = &d.hillshade {
            outputs.push(("hillshade".to_string(), h.clone()));
        }
    }
    outputs.insert(0, ("dir".to_string(), dir.clone()));
    let buffer = args.buffer.unwrap_or(tile / 10.0);
    let quiet = a.quiet;
    let canonical = |p: &PathBuf| sweeptin::input::files::absolute(p).map_err(anyhow::Error::from);
    let abs_groups: Vec<Vec<PathBuf>> = groups
        .iter()
        .map(|g| g.iter().map(canonical).collect::<anyhow::Result<_>>())
        .collect::<anyhow::Result<_>>()?;
    // The stored command line (for people) names the inputs by absolute path.
    let argv = absolute_inputs(&argv, &given, &abs_groups);
    let typed = job.typed()?;
    // The inputs as given: the plan keeps the lists and `.vpc` files among what it reads, which
    // no output may replace (checked there, with the line files).
    let plan = Plan::new(typed, argv, outputs, &given, tile, buffer)?;
    let plan = match args.no_hull_band {
        true => plan.without_hull_band(),
        false => plan,
    };
    let plan = match args.no_store || plan_dir.is_remote() {
        true => plan.without_point_store(),
        false => plan,
    };
    // The lines cleaned as every task will (checked on the bytes read): their z conflicts,
    // warned of as one run warns of them.
    let lines = plan.job.lines.as_ref().map(|l| l.graph()).transpose()?;
    if let (Job::Dem(d), Some(t)) = (&job, plan.tiles.first()) {
        // A task's raster (one tile) against --max-cells, as one run checks its raster.
        let extent = sweeptin::raster::GridExtent::BBox {
            bbox: t.bounds,
            snap: false,
        };
        sweeptin::raster::GridPlan::new(d.dem.cell, extent, d.dem.align)?
            .limit(d.dem.max_cells)
            .with_context(|| {
                format!(
                    "a task's raster covers one tile ({tile} a side): use a smaller --tile, or \
                     raise --max-cells"
                )
            })?;
    }
    let path = plan.save(&plan_dir)?;
    super::input::warn_headers(&plan.warnings);
    for (index, stored) in plan.stored_chunk_indexes() {
        match stored {
            Ok(()) => eprintln!("sweeptin: read the chunk index {}", index.display()),
            Err(why) => eprintln!(
                "sweeptin: warning: the chunk index {} {why}: the plan indexed the file again \
                 (`sweeptin index --chunks` stores a new one)",
                index.display()
            ),
        }
    }
    if let Some(g) = &lines {
        super::input::warn_z_conflicts(&g.warnings, g.stats.z_conflicts);
    }
    if plan.tiles.len() > 1000 {
        eprintln!(
            "sweeptin: warning: {} tasks: Slurm's default MaxArraySize is 1001; a larger --tile \
             makes fewer, longer tasks",
            plan.tiles.len()
        );
    }
    let lone = plan.tiles.iter().filter(|t| t.files.is_empty()).count();
    if lone > 0 && plan.job.lines.is_some() {
        eprintln!(
            "sweeptin: warning: the lines reach beyond the input files: as in one run, the TIN \
             extends to them, and {lone} of the {} tasks have no file within their buffer (they \
             read the nearest); cut the lines to the data if that is not meant",
            plan.tiles.len()
        );
    }
    let points: u64 = plan.files.iter().map(|f| f.points).sum();
    // A tenth of 24.9 is 2.4899999999999998 in full: shown to six digits.
    if !quiet {
        eprintln!(
            "sweeptin: {} tasks (tiles of {}, first buffer {}) over {} files, {} points -> {}",
            count(plan.tiles.len() as u64),
            Figure(tile),
            Figure(buffer),
            count(plan.files.len() as u64),
            count(points),
            path.display()
        );
    }
    // The number of tasks for a script (`N=$(sweeptin plan …)`); on a terminal the line above
    // says it (a bare number among the messages read as one of them).
    if !std::io::stdout().is_terminal() {
        println!("{}", plan.tiles.len());
    }
    if !quiet {
        eprintln!(
            "  next: sweeptin run {} --all --jobs N   (or a job array of {} tasks: --array=0-{})",
            path.display(),
            plan.tiles.len(),
            plan.tiles.len().saturating_sub(1)
        );
    }
    Ok(())
}

/// `argv` with each input replaced by the absolute paths of its files.
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

pub fn run(args: RunArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.plan)?;
    let dir = Plan::dir_of(&args.plan)?;
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
    super::run_all::end_with_parent(i)?;
    // Tests: this task's process dies of SIGKILL, as under the out-of-memory killer.
    #[cfg(target_os = "linux")]
    if std::env::var("SWEEPTIN_TEST_KILL_TASK").is_ok_and(|v| v == i.to_string()) {
        use rustix::process::{Signal, getpid, kill_process};
        let _ = kill_process(getpid(), Signal::KILL);
    }
    // Tests: this task waits (still running when its `run --all` is killed).
    if std::env::var("SWEEPTIN_TEST_TASK_WAITS").is_ok_and(|v| v == i.to_string()) {
        eprintln!("sweeptin: task {i} waits (SWEEPTIN_TEST_TASK_WAITS)");
        std::thread::sleep(std::time::Duration::from_secs(120));
    }
    if args.resume
        && plan.finished(&dir, i)
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
            "sweeptin: task {i} {}: {} points, {} triangles{}, buffer {} after {} run(s), {:.2} s",
            r.status,
            count(r.points),
            count(r.triangles),
            if r.inside_uncounted {
                " certified (those no cell needs skipped)"
            } else {
                ""
            },
            Figure(r.buffer),
            r.runs,
            r.seconds
        );
    }
    Ok(())
}

/// Runs task `i` ([`Plan::run_task`]).
fn run_task(plan: &Plan, dir: &PlanDir, i: usize, args: &RunArgs) -> anyhow::Result<TaskRecord> {
    let quiet = args.quiet || args.json || args.all;
    let options = TaskOptions {
        threads: args.threads.unwrap_or(0),
        progress: !quiet,
    };
    // As for one run (`InputArgs::options`): --threads also sizes the pool that decodes and
    // sorts, so that `--threads 1` runs on one core (once per process).
    sweeptin::pipeline::size_thread_pool(args.threads.unwrap_or(0));
    let r = plan
        .run_task(dir, i, &options)
        .with_context(|| format!("task {i} of {}", plan.tiles.len()))?;
    let warnings: Vec<String> = r
        .warnings
        .iter()
        .map(|w| format!("task {i}: {w}"))
        .collect();
    super::input::warn_headers(&warnings);
    if r.status == "empty" && r.points == 0 {
        eprintln!(
            "sweeptin: warning: task {i} has no point after the filters: its outputs are empty \
             ({}), which is not a failure",
            plan.job.empty_outputs()
        );
    }
    Ok(r)
}

pub fn merge(args: MergeArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.plan)?;
    let dir = Plan::dir_of(&args.plan)?;
    for o in [&args.output, &args.hillshade].into_iter().flatten() {
        super::input::check_output(o)?;
    }
    let outputs = merge::MergeOutputs {
        out: args.output.clone(),
        contours: args.contours.clone(),
        hillshade: args.hillshade.clone(),
        raster: args.raster.options(),
        extent: args.extent,
        mem: args.mem.0,
    };
    let s = merge::merge_plan(&plan, &dir, &outputs)?;
    for w in &s.warnings {
        eprintln!("sweeptin: warning: {w}");
    }
    if let (Some(h), Some(out)) = (&s.hillshade, &args.output) {
        super::hillshade::warn(out, &h.summary, true);
    }
    if let Some(t) = &s.volume
        && !args.json
    {
        println!("the tasks' volumes, summed:");
        super::volume::print_totals(t);
    }
    if args.json {
        println!("{}", serde_json::to_string(&s)?);
    } else if !args.quiet {
        eprintln!(
            "sweeptin: merged {} tasks ({} empty){}",
            count(s.tasks as u64),
            count(s.empty_tasks as u64),
            args.output
                .as_ref()
                .map(|p| format!(" -> {}", p.display()))
                .unwrap_or_default()
        );
    }
    Ok(())
}

/// The lower-case extension of `p`.
fn extension(p: &Path) -> Option<String> {
    p.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}
