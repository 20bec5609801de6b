//! Input and run options shared by every command that triangulates (`tin`, and the terrain
//! products): the files, the lidar filters, duplicates, memory budget, temporary directory,
//! progress and the JSON summary.

use super::info::FilterArgs;
use std::path::{Path, PathBuf};
use sweeptin::breaklines::CleanOptions;
use sweeptin::breaklines::clean::{ZConflict, ZConflictKind};
use sweeptin::crs::{Crs, LostCrs};
use sweeptin::input::las::BBox;
use sweeptin::output::target::Destination;
use sweeptin::pipeline::{self, Input, RunConfig, RunOptions, RunSummary, SweepAxis};
use sweeptin::sink::{Fanout, FanoutSummary, MeshSink, ProductSummary, TriangleSink};

/// Input files and how to read and run them (flattened into each command's arguments).
#[derive(clap::Args, Debug, Clone)]
pub struct InputArgs {
    /// Input points: LAS/LAZ/COPC files (adjacent tiles form one point set, whatever their
    /// scales and offsets), `.vpc` virtual point clouds, `@list.txt` (one path per line,
    /// relative to the list), quoted globs (`'tiles/*.laz'`), XYZ text files (`x y z` per
    /// line; `-` or a pipe is read once, as it comes), or one streaming mesh (.stin) written by
    /// `sweeptin tin`. With --bbox, files whose extent misses the box are not read, and COPC
    /// files read only the octree nodes it meets.
    #[arg(required = true, value_name = "FILES")]
    pub inputs: Vec<PathBuf>,
    #[command(flatten)]
    pub filter: FilterArgs,
    /// Triangulate the ground found on the fly: classify the LAS/LAZ/COPC points with the
    /// ground filter of `sweeptin ground` (its options below; no point is written), then read
    /// every point with the class `ground` would write and keep class 2 (or the classes of
    /// --class among those), so that `dem raw.laz --ground` makes the DEM of `ground raw.laz
    /// -o g.laz` then `dem g.laz --class 2`, byte for byte. The file's own classes are ignored.
    /// Needs --mem for both steps in turn (the classes wait in memory up to an eighth of it).
    #[arg(long)]
    pub ground: bool,
    #[command(flatten)]
    pub ground_options: super::ground::GroundOptions,
    /// Which point survives among exact (x, y) duplicates.
    #[arg(long, value_enum, default_value_t = sweeptin::DuplicatePolicy::First)]
    pub duplicates: sweeptin::DuplicatePolicy,
    #[command(flatten)]
    pub lines: LineArgs,
    /// Memory budget for sorting (e.g. 512M, 4G). Larger inputs are sorted in chunks spilled to
    /// --tmp-dir; the result is the same whatever the budget. Under an address-space limit
    /// (ulimit -v, h_vmem) the default is what the limit leaves beside about 128 MiB for the
    /// program itself, and a larger --mem is refused before any work.
    #[arg(long, value_name = "SIZE", default_value_t = Size(pipeline::default_mem()))]
    pub mem: Size,
    /// Directory for spill files (anonymous temporary files, never left behind): the sort's
    /// chunks, and the one sweep's held triangles when points on a line or a circle keep them
    /// all open (about 150 bytes each).
    #[arg(long, value_name = "DIR")]
    pub tmp_dir: Option<PathBuf>,
    /// Axis the sweep advances along. Memory grows with the number of points across the sweep
    /// (the advancing front), so a long strip is best swept lengthwise: `auto` sweeps along x
    /// when the LAS/LAZ headers' extent is more than 4 times wider than tall and the run makes a
    /// plain mesh (no breaklines, trimming or terrain products, which need y; not a `.stin`,
    /// whose height watermarks let the products read it back with bounded memory); `y`
    /// otherwise. A `.stin` swept along x has no watermarks: products made from it hold the
    /// whole raster.
    /// Exactly cocircular points are split by the sweep order, so the axis can change which of
    /// several equally Delaunay diagonals is chosen.
    #[arg(long, value_enum, value_name = "AXIS", default_value_t = SweepAxis::Auto)]
    pub sweep_axis: SweepAxis,
    /// How to triangulate. `auto` (the default) runs exact tiles on every core (--threads)
    /// for LAS/LAZ points without breaklines or trimming polygons, and one streaming sweep
    /// otherwise (`--engine tiles` runs lines in tiles too; not --no-flat-triangles). `tiles` cuts the data into
    /// tiles, each run with a buffer and certified triangle by triangle to equal the
    /// triangulation of all the points (a tile whose buffer is not enough reads more; a
    /// breakline that meets a tile's run goes into it whole); its memory is bounded by --mem.
    /// Dense breakline networks (a planar partition of polygons) make tiles read far beyond
    /// their buffers, and the sweep can be faster there. `sweep` runs one streaming sweep on one core, whose memory
    /// follows the advancing front. All give the same triangles (and the same DEM and volumes,
    /// byte for byte, and the same contour lines, a closed ring perhaps from another vertex or
    /// in another order); a mesh lists them in another order.
    #[arg(long, value_enum, value_name = "ENGINE", default_value_t = Engine::Auto)]
    pub engine: Engine,
    /// Threads (default: every core): the tiled engine's tile workers, and the decoding and
    /// sorting of every engine. The output is the same for any number.
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = parse_threads)]
    pub threads: usize,
    /// Tile side for the tiled engine, in the data's units (any positive size: a DEM cell belongs
    /// to the tile holding its centre, so here it need not be a multiple of the cell; a plan's
    /// tiles must be, since each task writes its own raster); default:
    /// a power-of-two multiple of the cell (of one unit without a cell) holding about 65,000
    /// points at the data's density (more above 134 million points, so that the block table
    /// stays under 2 million blocks): 64 m on a 13-points-per-m² tile. Larger tiles do not save
    /// CPU: their buffers are relatively thinner, but the runs leave the processor's caches.
    #[arg(long, value_name = "SIZE")]
    pub tile: Option<f64>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Set by `sweeptin run`: this run is one task of a plan.
    #[arg(skip)]
    pub task: Option<sweeptin::TaskScope>,
    /// The file lists (`@list.txt`) read to find `inputs` ([`InputArgs::expand`]): inputs too.
    #[arg(skip)]
    pub lists: Vec<PathBuf>,
    /// Print a one-object JSON summary on stdout (points, triangles, seconds per phase, peak
    /// memory; with --ground what the filter found, as `ground --json` prints it, under the
    /// run's `ground`) for batch jobs; on failure `{"error": {"status", "kind", "message",
    /// "causes"}}`.
    #[arg(long)]
    pub json: bool,
}

impl InputArgs {
    /// Replaces the inputs by the files they stand for (`@list.txt`, quoted globs; a `.vpc`
    /// stays, the reader knows its files and their extents), keeping the lists read.
    pub fn expand(&mut self) -> anyhow::Result<()> {
        self.lists = expand(&mut self.inputs)?;
        Ok(())
    }

    /// Every file the run reads: the points (and the lists that named them), breaklines,
    /// boundary and holes (outputs must be none of them).
    pub fn all_inputs(&self) -> Vec<PathBuf> {
        let l = &self.lines;
        let mut v = self.inputs.clone();
        v.extend(self.lists.iter().cloned());
        v.extend(l.breaklines.iter().cloned());
        v.extend(l.boundary.iter().chain(&l.holes).cloned());
        v
    }

    /// The checks every command that writes files makes before any work: `outputs` are
    /// distinct from each other and from every file read (the run's and `more`), and none goes
    /// to standard output with `--json`.
    pub fn check_outputs(&self, outputs: &[(&str, &Path)], more: &[&Path]) -> anyhow::Result<()> {
        let mut inputs = self.all_inputs();
        inputs.extend(more.iter().map(|p| p.to_path_buf()));
        distinct_outputs(outputs, &inputs, "the run")?;
        stdout_free(outputs, self.json)?;
        for (_, o) in outputs {
            check_output(o)?;
        }
        Ok(())
    }

    /// The library's description of the input.
    pub fn input(&self) -> Input {
        Input {
            paths: self.inputs.iter().map(|p| stdin_path(p)).collect(),
            filter: self.filter.to_filter(),
            duplicates: self.duplicates,
            lines: self.lines.to_options(),
        }
    }

    /// The library's run options. `--threads N` also sizes the thread pool that decodes and
    /// sorts (once per process), so that `--threads 1` runs on one core.
    pub fn options(&self) -> RunOptions {
        pipeline::size_thread_pool(self.threads);
        RunOptions {
            mem: self.mem.0,
            tmp_dir: self.tmp_dir.clone(),
            progress: !self.quiet && !self.json,
            sweep_axis: self.sweep_axis,
            // A task of a plan always runs in tiles.
            tiles: match (self.engine, self.task.is_some()) {
                (Engine::Sweep, false) => None,
                _ => Some(sweeptin::TileOptions {
                    threads: self.threads,
                    tile: self.tile,
                    base: None,
                    scope: self.task.clone(),
                }),
            },
        }
    }

    /// The run's configuration, checked.
    pub fn config(&self, input: Input) -> anyhow::Result<RunConfig> {
        if let Some(t) = self.tile {
            pipeline::check_tile_side(t)?;
        }
        let mut options = self.options();
        let l = &input.lines;
        let lines = !l.breaklines.is_empty() || l.boundary.is_some() || l.holes.is_some();
        if self.engine == Engine::Auto && self.task.is_none() && lines {
            // Exact in tiles too, but dense line networks make tiles read far beyond their
            // buffers (docs/BENCHMARKS.md: 6× the sweep's time on Delft's BGT): `auto` keeps
            // the sweep for lines; `--engine tiles` asks for tiles.
            options.tiles = None;
        }
        let (input, options, ground) = self.grounded(input, options)?;
        let config = RunConfig::new(input, options)?.with_ground(ground);
        if self.engine == Engine::Tiles && !config.runs_in_tiles() && !self.quiet {
            eprintln!(
                "sweeptin: note: --engine tiles: this input runs in one exact streaming sweep \
                 instead (the tiles are proved for LAS/LAZ points, with breaklines and trimming \
                 polygons but without --no-flat-triangles, swept along y; a plan's task takes no \
                 lines)"
            );
        }
        Ok(config)
    }
}

impl InputArgs {
    /// With `--ground`, the input that reads the ground filter's classes (the classification
    /// done here, before the run: `sweeptin::pipeline::ground`) and what the filter found (the
    /// run's summary carries it); the ground options without `--ground` are refused.
    #[allow(clippy::type_complexity)]
    fn grounded(
        &self,
        input: Input,
        options: RunOptions,
    ) -> anyhow::Result<(Input, RunOptions, Option<sweeptin::ground::GroundSummary>)> {
        if !self.ground {
            if self.ground_options.any() {
                return Err(sweeptin::Error::Options(
                    "the ground filter's options (--step, --max-angle, --town, …) apply with \
                     --ground: add --ground to triangulate the ground found on the fly"
                        .into(),
                )
                .into());
            }
            return Ok((input, options, None));
        }
        let params = self.ground_options.params();
        let g = pipeline::ground::ground_input(&input, &params, &options, &mut |_, _, _| {})
            .map_err(|e| run_error(e, &input.paths))?;
        if options.progress {
            eprintln!(
                "sweeptin: --ground: {} of {} points are ground ({} low noise; blocks of {}, \
                 {:.1} s)",
                sweeptin::fmt::count(g.summary.ground),
                sweeptin::fmt::count(g.summary.points),
                sweeptin::fmt::count(g.summary.low_noise),
                g.summary.block,
                g.summary.read_seconds + g.summary.classify_seconds
            );
        }
        Ok((g.input, g.options, Some(g.summary)))
    }
}

/// The output of `input` in directory `dir` (`--odir` of `ground` and `height`): its own name,
/// a COPC file's as plain `.laz` (its points rewritten in their order: a COPC file is written
/// only when `-o` names one).
pub fn in_dir(dir: &Path, input: &Path) -> PathBuf {
    let name = input
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    let name = match lower.strip_suffix(".copc.laz") {
        Some(_) => format!("{}.laz", &name[..name.len() - ".copc.laz".len()]),
        None => name,
    };
    dir.join(name)
}

/// `-` as an input is standard input (`/dev/stdin`), as in most command-line tools.
pub fn stdin_path(p: &Path) -> PathBuf {
    if p.as_os_str() == "-" {
        PathBuf::from("/dev/stdin")
    } else {
        p.to_path_buf()
    }
}

/// Parses `--threads N` (0: every core) and `--jobs N`, at most
/// [`sweeptin::pipeline::MAX_THREADS`], so that a typo fails before any work.
pub fn parse_threads(s: &str) -> Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a whole number of threads"))?;
    pipeline::check_threads(n).map_err(|e| e.to_string())?;
    Ok(n)
}

/// A memory size given as `512M`, `4G`, … (see [`parse_size`]); shown in the same form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size(pub u64);

impl std::str::FromStr for Size {
    type Err = String;

    fn from_str(s: &str) -> Result<Size, String> {
        parse_size(s).map(Size)
    }
}

impl std::fmt::Display for Size {
    /// The largest binary unit that divides the size: `1073741824` is `1G`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let units = [(40, "T"), (30, "G"), (20, "M"), (10, "K")];
        match units
            .iter()
            .find(|(shift, _)| self.0 >= 1 << shift && self.0.is_multiple_of(1 << shift))
        {
            Some((shift, unit)) => write!(f, "{}{unit}", self.0 >> shift),
            None => write!(f, "{}", self.0),
        }
    }
}

/// The triangulation engine (see `--engine`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// Exact tiles where the input allows it, one sweep otherwise (the default).
    Auto,
    /// Exact tiles on every core where the input allows it; one sweep otherwise.
    Tiles,
    /// One streaming sweep.
    Sweep,
}

/// Parses a human size ([`pipeline::parse_size`]).
pub fn parse_size(s: &str) -> Result<u64, String> {
    pipeline::parse_size(s).map_err(|e| e.to_string())
}

/// The input options of the terrain-product commands: [`InputArgs`] plus the CRS to record and
/// the longest edge to keep.
#[derive(clap::Args, Debug, Clone)]
pub struct ProductInput {
    #[command(flatten)]
    pub args: InputArgs,
    /// Coordinate reference system of the data (`EPSG:code`, `EPSG:code+vertical`, or WKT),
    /// recorded in the outputs instead of what the input declares (if anything).
    #[arg(long, value_name = "CRS")]
    pub crs: Option<String>,
}

/// Breaklines and trimming, shared by `tin` and the terrain products.
#[derive(clap::Args, Debug, Clone, Default)]
#[command(next_help_heading = "Breaklines and trimming")]
pub struct LineArgs {
    /// Breaklines (repeatable): GeoJSON LineString/MultiLineString/Polygon/MultiPolygon, a
    /// GeoPackage or OGR-SQLite layer (`FILE.gpkg:LAYER` when it has several), a Shapefile, or
    /// text (`x y [z]` per line, a blank line between polylines), in the points' CRS and units. They
    /// become triangle edges; crossings are split, overlaps merged. Lines without z take their
    /// heights from the points' TIN (an extra pass over the points). They run in exact tiles
    /// too (each tile's run takes every line that meets it whole), and in a plan's tasks when
    /// every vertex has a z (`sweeptin plan --help`).
    #[arg(long = "breaklines", value_name = "FILE")]
    pub breaklines: Vec<PathBuf>,
    /// Keep only the triangles inside these polygons (survey limit); the rings become breaklines.
    /// (`sweeptin tin` also accepts it as `--boundary`; in `volume` and `products`, `--boundary`
    /// is the volume's polygon.)
    #[arg(long = "trim-boundary", id = "trim_boundary", value_name = "FILE")]
    pub boundary: Option<PathBuf>,
    /// Drop the triangles inside these polygons (lakes, buildings); the rings become breaklines.
    #[arg(long, value_name = "FILE")]
    pub holes: Option<PathBuf>,
    /// Drop triangles with a horizontal edge longer than this (a concave outline; for rasters,
    /// nodata there).
    #[arg(long, value_name = "LENGTH")]
    pub max_edge: Option<f64>,
    /// Report breakline heights that disagree by more than this where lines meet or cross.
    #[arg(long, value_name = "DZ", default_value_t = CleanOptions::default().z_tolerance)]
    pub z_tolerance: f64,
    /// Flip away triangles lying flat on one contour line (Herva 2009), so that contours derived
    /// from the TIN are unambiguous. Holds the whole triangulation in memory.
    #[arg(long)]
    pub no_flat_triangles: bool,
    /// Cut the breaklines to the data (the points' convex hull, exactly) with a warning of how
    /// much was cut, instead of stopping at a line that runs outside the points (one more pass
    /// over the points).
    #[arg(long)]
    pub clip_breaklines: bool,
}

impl LineArgs {
    pub fn to_options(&self) -> pipeline::LineOptions {
        pipeline::LineOptions {
            breaklines: self.breaklines.clone(),
            boundary: self.boundary.clone(),
            holes: self.holes.clone(),
            max_edge: self.max_edge,
            z_tolerance: Some(self.z_tolerance),
            no_flat_triangles: self.no_flat_triangles,
            clip: self.clip_breaklines,
        }
    }
}

/// Prints the warning of `--clip-breaklines` when it cut anything.
pub fn warn_clipped(run: &RunSummary) {
    let Some(c) = run.breaklines.as_ref().and_then(|b| b.clipped) else {
        return;
    };
    if c.lines_cut + c.lines_dropped > 0 {
        eprintln!(
            "sweeptin: warning: --clip-breaklines cut {} of {} breaklines to the points' convex hull and left out {} lying wholly outside: {:.1} of {:.1} (xy units) of line cut ({:.1} %)",
            c.lines_cut,
            c.lines,
            c.lines_dropped,
            c.length_cut,
            c.length,
            100.0 * c.length_cut / c.length.max(f64::MIN_POSITIVE)
        );
    }
}

/// Parses `--crs` ([`Crs::parse`]).
pub fn parse_crs(s: &str) -> anyhow::Result<Crs> {
    Ok(Crs::parse(s)?)
}

impl ProductInput {
    /// The run's configuration, reading only the points inside `read_box` when given (instead
    /// of `--bbox`).
    pub fn config(&self, read_box: Option<BBox>) -> anyhow::Result<RunConfig> {
        let mut input = self.args.input();
        if read_box.is_some() {
            input.filter.bbox = read_box;
        }
        Ok(self.args.config(input)?.with_crs(self.crs()?))
    }

    /// The CRS given with `--crs`, parsed.
    pub fn crs(&self) -> anyhow::Result<Option<Crs>> {
        self.crs.as_deref().map(parse_crs).transpose()
    }

    /// The extent of the points from the LAS/LAZ headers (`LidarReader::header_extent`; `None`
    /// for other inputs).
    pub fn header_bounds(&self) -> Option<[f64; 4]> {
        if !self.all_lidar() {
            return None;
        }
        sweeptin::input::las::LidarReader::header_extent(&self.args.inputs)
    }

    /// Are all the inputs LAS/LAZ (so that the box filter applies)?
    pub fn all_lidar(&self) -> bool {
        self.args.inputs.iter().all(|p| {
            matches!(
                p.extension()
                    .and_then(|e| e.to_str())
                    .map(str::to_ascii_lowercase)
                    .as_deref(),
                Some("las" | "laz" | "vpc")
            )
        })
    }
}

/// Replaces `paths` by the files they stand for (`@list.txt`, quoted globs; a `.vpc` stays, the
/// reader knows its files and their extents); returns the lists read, which are inputs too
/// ([`sweeptin::input::files::Expansion`]).
pub fn expand(paths: &mut Vec<PathBuf>) -> anyhow::Result<Vec<PathBuf>> {
    let e = sweeptin::input::files::expand(paths, sweeptin::input::files::Expand::KeepVpc)?;
    *paths = e.files;
    Ok(e.lists)
}

/// As [`expand`], and a `.vpc` replaced by its files (for commands that need every header); the
/// `.vpc` files are among the lists returned.
pub fn expand_files(paths: &mut Vec<PathBuf>) -> anyhow::Result<Vec<PathBuf>> {
    let e = sweeptin::input::files::expand(paths, sweeptin::input::files::Expand::VpcFiles)?;
    *paths = e.files;
    Ok(e.lists)
}

/// Refuses an `--odir` that is not an existing directory: the environment (exit 4), as a
/// missing directory of `-o` is.
pub fn check_odir(dir: &Path) -> anyhow::Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    let (kind, what) = if dir.exists() {
        (std::io::ErrorKind::NotADirectory, "--odir: not a directory")
    } else {
        (
            std::io::ErrorKind::NotFound,
            "--odir: the directory does not exist (create it first)",
        )
    };
    let e = std::io::Error::new(kind, what);
    Err(sweeptin::Error::write(dir, e).into())
}

/// Fails early (before any heavy work) if an output cannot be created where asked
/// ([`sweeptin::output::check_output`]).
pub fn check_output(path: &Path) -> anyhow::Result<()> {
    Ok(sweeptin::output::check_output(path)?)
}

/// Refuses an output on standard output (`-o -`, `/dev/stdout`) together with `--json`, whose
/// summary goes there too.
pub fn stdout_free(outputs: &[(&str, &Path)], json: bool) -> anyhow::Result<()> {
    for (flag, o) in outputs {
        if json && let Ok(Destination::Stream { fd: Some(1), .. }) = Destination::of(o) {
            return Err(sweeptin::Error::Options(format!(
                "{flag} {}: the output goes to standard output, where --json prints the summary: \
                 leave --json out or write the output to a file",
                o.display()
            ))
            .into());
        }
    }
    Ok(())
}

/// Refuses, before any work, outputs that are the same file as each other or as one of the
/// `inputs` of `of` (the run, the plan): [`sweeptin::output::distinct_outputs`].
pub fn distinct_outputs(
    outputs: &[(&str, &Path)],
    inputs: &[PathBuf],
    of: &str,
) -> anyhow::Result<()> {
    Ok(sweeptin::output::distinct_outputs(outputs, inputs, of)?)
}

/// The error of a run over `inputs`: library errors name their file, line or option, and are
/// shown as they are; those about the point set as a whole (too few points, all collinear, a
/// coordinate out of range) are prefixed with the inputs' names.
pub fn run_error(e: sweeptin::Error, inputs: &[PathBuf]) -> anyhow::Error {
    use sweeptin::Error as E;
    match e {
        E::TooFewPoints { .. }
        | E::AllCollinear { .. }
        | E::NoArea { .. }
        | E::NonFinite { .. }
        | E::CoordinateOutOfRange { .. } => {
            let names: Vec<String> = inputs.iter().map(|f| f.display().to_string()).collect();
            anyhow::Error::from(e).context(format!("cannot triangulate {}", names.join(", ")))
        }
        other => other.into(),
    }
}

/// Prints where the breaklines give one place two heights more than `--z-tolerance` apart
/// (cleaning keeps the first, or the mean where lines cross): the first few of `shown`, of
/// `total` in all. The one wording for a run ([`warn`]) and for `sweeptin plan`, which cleans
/// the lines as its tasks will.
pub fn warn_z_conflicts(shown: &[ZConflict], total: u64) {
    const FIRST: usize = 5;
    if total == 0 {
        return;
    }
    let places = if total == 1 { "place" } else { "places" };
    eprintln!(
        "sweeptin: warning: the breaklines give heights more than --z-tolerance apart at \
         {total} {places} (check the lines' heights):"
    );
    for c in shown.iter().take(FIRST) {
        let [a, b] = c.z;
        let what = match c.kind {
            ZConflictKind::Duplicate => format!("a vertex given twice: {a} kept, {b} dropped"),
            ZConflictKind::OnLine => {
                format!("a vertex on another line: {a} kept, {b} along the line")
            }
            ZConflictKind::Crossing => format!("two lines crossing: {a} and {b}, the mean kept"),
        };
        eprintln!("  ({}, {}), {what}", c.at[0], c.at[1]);
    }
    let listed = shown.len().min(FIRST) as u64;
    if total > listed {
        eprintln!("  and {} more", total - listed);
    }
}

/// Prints the input headers' warnings, as `sweeptin info` does: the first few of many files.
pub fn warn_headers(warnings: &[String]) {
    const SHOWN: usize = 10;
    for w in warnings.iter().take(SHOWN) {
        eprintln!("sweeptin: warning: {w}");
    }
    if warnings.len() > SHOWN {
        eprintln!(
            "sweeptin: warning: … and {} more header warnings (all in the JSON summary, plan or \
             task record)",
            warnings.len() - SHOWN
        );
    }
}

/// Prints the run's warnings on standard error: what the input headers say (a point count
/// that disagrees with the file…), breakline heights that disagree where lines
/// meet ([`warn_z_conflicts`]) or lie far from the points'.
pub fn warn(run: &RunSummary) {
    warn_headers(&run.warnings);
    if let Some(b) = &run.breaklines {
        warn_z_conflicts(&b.z_conflicts, b.clean.z_conflicts);
    }
    if let Some(f) = run.breaklines.as_ref().and_then(|b| b.far_heights) {
        eprintln!(
            "sweeptin: warning: {} breakline vertices have heights from {} to {}, far outside \
             the points' ({} to {}): check the lines' units and vertical datum",
            f.vertices, f.lines_z[0], f.lines_z[1], f.points_z[0], f.points_z[1]
        );
    }
}

/// Runs the pipeline of `config` into `sinks` (one pass) and the optional mesh sink; returns the
/// run summary (without the products) and the products' summaries by the sinks' names.
pub fn run_products(
    p: &ProductInput,
    config: &RunConfig,
    mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: Vec<(String, Box<dyn TriangleSink>)>,
) -> anyhow::Result<(RunSummary, FanoutSummary)> {
    // GeoTIFF keys and a GeoJSON `crs` need EPSG codes; other outputs carry the WKT.
    let coded = sinks.iter().any(|(n, _)| n == "dem" || n == "contours");
    let mut fanout = Fanout::new(sinks).with_crs(p.crs()?);
    let mut run = pipeline::run(config, mesh, &mut [&mut fanout])
        .map_err(|e| run_error(e, &p.args.inputs))?;
    let products = match run.products.pop() {
        Some(ProductSummary::Fanout(s)) if run.products.is_empty() => s,
        other => {
            return Err(
                sweeptin::Error::Internal(format!("the products' summary is {other:?}")).into(),
            );
        }
    };
    run.peak_rss_bytes = pipeline::peak_rss();
    warn(&run);
    warn_clipped(&run);
    let crs = match p.crs()? {
        Some(c) => Some(c),
        None => run.crs.as_deref().and_then(|t| Crs::parse(t).ok()),
    };
    if coded {
        warn_crs(crs.as_ref());
        warn_lost_crs(crs.as_ref(), &products);
    }
    Ok((run, products))
}

/// Warns, once, when the outputs that would record a CRS carry none: the input declares none
/// (and `--crs` names none), or an ASCII grid's CRS cannot be written as a `.prj`.
fn warn_lost_crs(crs: Option<&Crs>, products: &FanoutSummary) {
    if let Some(l) = LostCrs::of(crs, false) {
        eprintln!("sweeptin: warning: {l} (name it with --crs EPSG:code)");
        return;
    }
    let lost = products.0.iter().find_map(|(_, s)| match s {
        ProductSummary::Dem(d) => d.lost_crs.as_ref(),
        _ => None,
    });
    if let Some(l) = lost {
        eprintln!("sweeptin: warning: {l}");
    }
}

/// Warns when the CRS has no EPSG code for its horizontal part, which GeoTIFF keys and a
/// GeoJSON's `crs` need (a WKT2 compound that gives a code only for the whole, a custom WKT):
/// those outputs go without a CRS, and `--crs` can name one.
fn warn_crs(crs: Option<&Crs>) {
    let Some(c) = crs else { return };
    match c.horizontal_epsg() {
        None => eprintln!(
            "sweeptin: warning: the CRS {c} gives no EPSG code for its horizontal part: GeoTIFF \
             and GeoJSON outputs carry no CRS (an ASCII grid's .prj keeps the WKT); name it with \
             --crs EPSG:code or EPSG:code+vertical"
        ),
        // GeoTIFF keys hold 16 bits (ESRI:102100 given as EPSG:102100 was dropped silently).
        Some((h, _)) if h > u32::from(u16::MAX) => eprintln!(
            "sweeptin: warning: the CRS code {h} does not fit a GeoTIFF key (16 bits): a \
             GeoTIFF output carries no CRS"
        ),
        Some(_) => {}
    }
    if let Some(v) = c.vertical_epsg.filter(|&v| v > u32::from(u16::MAX)) {
        eprintln!(
            "sweeptin: warning: the vertical CRS code {v} does not fit a GeoTIFF key (16 bits): \
             a GeoTIFF output carries no vertical CRS"
        );
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sizes() {
        use super::{Size, parse_size};
        assert_eq!(Size(sweeptin::pipeline::DEFAULT_MEM).to_string(), "1G");
        assert_eq!(Size(1536).to_string(), "1536");
        assert_eq!(Size(512 << 20).to_string(), "512M");
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("4G"), Ok(4 << 30));
        assert_eq!(parse_size("1.5K"), Ok(1536));
        assert_eq!(parse_size("100"), Ok(100));
        assert_eq!(parse_size("128 MiB"), Ok(128 << 20));
        assert!(parse_size("lots").is_err());
        assert!(parse_size("5X").is_err());
    }

    #[test]
    fn crs_forms() {
        use super::parse_crs;
        assert_eq!(parse_crs("EPSG:3794").unwrap().epsg, Some(3794));
        let c = parse_crs("epsg:28992+5709").unwrap();
        assert_eq!((c.epsg, c.vertical_epsg), (Some(28992), Some(5709)));
        let w = parse_crs(r#"PROJCS["x",AUTHORITY["EPSG","2154"]]"#).unwrap();
        assert_eq!(w.epsg, Some(2154));
        assert!(parse_crs("EPSG:abc").is_err());
        assert!(parse_crs("nonsense").is_err());
    }
}
