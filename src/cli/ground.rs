//! `sweeptin ground`: classify the ground of lidar points (progressive TIN densification) and
//! write the points back with their new classes.

use super::input::{Size, parse_threads};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use sweeptin::ground::{GroundParams, GroundSummary, Terrain};

/// The help heading of the ground filter's options.
const HEADING: &str = "Ground filter (with --ground in the triangulating commands)";

/// The ground filter's parameters and presets, shared by `sweeptin ground` and the
/// triangulating commands' `--ground`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct GroundOptions {
    /// Seed cell side: larger than the largest building (metres, or the data's unit).
    #[arg(long, help_heading = HEADING, value_name = "S")]
    pub step: Option<f64>,
    /// Largest distance from a point to its ground triangle's plane.
    #[arg(long, help_heading = HEADING, value_name = "D")]
    pub max_distance: Option<f64>,
    /// Largest angle (degrees) from the ground triangle's plane to its corners.
    #[arg(long, help_heading = HEADING, value_name = "DEG")]
    pub max_angle: Option<f64>,
    /// Depth below the neighbouring seeds, or below the final ground, that makes low noise.
    #[arg(long, help_heading = HEADING, value_name = "H")]
    pub low_noise: Option<f64>,
    /// Points within this vertical distance of the final ground are ground too.
    #[arg(long, help_heading = HEADING, value_name = "DZ")]
    pub offset: Option<f64>,
    /// Densification cell side: only the lowest point of each C x C cell densifies the ground
    /// TIN, the others are judged once against the final TIN: faster on dense data, less
    /// ground found on rough forest floors (docs/ACCURACY.md). Default 0: every point densifies.
    #[arg(long, help_heading = HEADING, value_name = "C")]
    pub densify_cell: Option<f64>,
    /// Do not try points near steep edges mirrored through the nearest ground vertex
    /// (Axelsson's mirroring, on by default).
    #[arg(long, help_heading = HEADING)]
    pub no_mirror: bool,
    /// Preset: no buildings, fine detail (step 3).
    #[arg(long, group = "terrain", help_heading = HEADING)]
    pub wilderness: bool,
    /// Preset: open natural terrain (step 5).
    #[arg(long, group = "terrain", help_heading = HEADING)]
    pub nature: bool,
    /// Preset: villages (step 10).
    #[arg(long, group = "terrain", help_heading = HEADING)]
    pub town: bool,
    /// Preset: cities (step 25).
    #[arg(long, group = "terrain", help_heading = HEADING)]
    pub city: bool,
    /// Preset: large buildings (step 50).
    #[arg(long, group = "terrain", help_heading = HEADING)]
    pub metro: bool,
    /// Preset: forest, no buildings (step 10).
    #[arg(long, group = "terrain", help_heading = HEADING)]
    pub forest: bool,
    /// Preset: steep terrain (step 10, max-angle 12, max-distance 1.5, low-noise 10).
    #[arg(long, group = "terrain", help_heading = HEADING)]
    pub mountains: bool,
}

impl GroundOptions {
    /// The parameters: the preset's (or the default), each given value over it.
    pub fn params(&self) -> GroundParams {
        let preset = [
            (self.wilderness, Terrain::Wilderness),
            (self.nature, Terrain::Nature),
            (self.town, Terrain::Town),
            (self.city, Terrain::City),
            (self.metro, Terrain::Metro),
            (self.forest, Terrain::Forest),
            (self.mountains, Terrain::Mountains),
        ]
        .into_iter()
        .find(|p| p.0)
        .map(|p| p.1);
        let mut p = preset.map_or_else(GroundParams::default, Terrain::params);
        p.step = self.step.unwrap_or(p.step);
        p.max_distance = self.max_distance.unwrap_or(p.max_distance);
        p.max_angle = self.max_angle.unwrap_or(p.max_angle);
        p.low_noise = self.low_noise.unwrap_or(p.low_noise);
        p.offset = self.offset.unwrap_or(p.offset);
        p.densify_cell = self.densify_cell.unwrap_or(p.densify_cell);
        p.mirror = p.mirror && !self.no_mirror;
        p
    }

    /// Was any parameter or preset given?
    pub fn any(&self) -> bool {
        [
            self.step,
            self.max_distance,
            self.max_angle,
            self.low_noise,
            self.offset,
            self.densify_cell,
        ]
        .iter()
        .any(Option::is_some)
            || self.no_mirror
            || self.wilderness
            || self.nature
            || self.town
            || self.city
            || self.metro
            || self.forest
            || self.mountains
    }
}

/// Arguments of `sweeptin ground`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Progressive TIN densification (Axelsson 2000), as LAStools lasground, lidR ptd(), lasR \
classify_with_ptd and TerraScan do it, on sweeptin's exact TIN:
  1. seeds: the lowest point of every cell of a grid of side --step (cells aligned at x = 0, \
y = 0); a seed lower than the median of its neighbour seeds by more than --low-noise is low \
noise (class 7), and the next lowest point of its cell is tried;
  2. densification: a point is ground when its distance to the plane of the ground triangle \
under it is at most --max-distance and the angles from that plane to its three corners are at \
most --max-angle (a point near a steep edge that fails only on the angles is also tried \
mirrored through the nearest corner, unless --no-mirror); per triangle the closest point is added, iteration after iteration, until \
none is;
  3. the points within --offset (vertically) of the final ground are ground too; those more \
than --low-noise below it are low noise (7).
Classes written: ground 2, low noise 7; the others keep theirs (a point of class 2 that is \
not ground becomes 1), or all become 1 with --reset. Withheld points and points already \
classified noise (7, 18) take no part and keep their class. Every other attribute, the header, \
VLRs and EVLRs and the order of the points are kept; an output named .copc.laz is a COPC file \
of the same points in the order of its octree (LAS 1.4 point format 6 or 7; formats with NIR \
or waveforms are refused: docs/GROUND.md).

Exact and tiling-independent: the ground is decided in blocks of 32 steps a side (16 above \
--step 6.25, 8 above 12.5, 4 above 25: 100 to 200 units), aligned at the origin, each block from its own points and those \
within 2 steps around it. So the classes are the same for any --threads, --mem or split of the \
input into files; several inputs are classified together (adjacent tiles classify \
seamlessly) and each is written to --odir under its own name (a .copc.laz input as plain .laz, \
its points in their order; -o X.copc.laz writes a COPC file).

Memory: one read of the inputs into a block index (sorted within --mem, spilled to --tmp-dir \
beyond), then blocks on every core, at most 108 bytes a point of a block and its buffer; a \
block that does not fit what --mem leaves after the index is refused before the work (give a \
larger --mem or smaller --step). The classes wait in a temporary file of one byte a point beyond an eighth of --mem.

Default (no preset): --step 20 --max-distance 1 --max-angle 6 --offset 0.2 --low-noise 5, \
tuned on ARSO, AHN3 and IGN tiles (docs/ACCURACY.md). Terrain presets (LAStools lasground's \
steps; a value given explicitly overrides the preset's):
  --wilderness  step 3        --nature  step 5        --town  step 10
  --city  step 25             --metro  step 50        --forest  step 10
  --mountains  step 10, max-angle 12, max-distance 1.5, low-noise 10

Examples:
  sweeptin ground raw.laz -o classified.laz
  sweeptin ground raw.laz -o classified.copc.laz
  sweeptin ground tiles/*.laz --odir classified/ --city --json
  sweeptin ground raw.laz -o g.laz && sweeptin dem g.laz --class 2 --cell 1 -o dtm.tif")]
pub struct Args {
    /// Input LAS/LAZ/COPC files (classified together).
    #[arg(required = true, value_name = "FILES")]
    pub inputs: Vec<PathBuf>,
    /// Output file (.laz, .las or .copc.laz: COPC, the points in octree order) for one input.
    /// It appears only when complete and never replaces an input.
    #[arg(short, long, conflicts_with = "odir")]
    pub output: Option<PathBuf>,
    /// Output directory: each input written there under its own file name.
    #[arg(long, value_name = "DIR")]
    pub odir: Option<PathBuf>,
    #[command(flatten)]
    pub params: GroundOptions,
    /// Points that are not ground (nor noise, nor withheld) become class 1.
    #[arg(long)]
    pub reset: bool,
    /// Memory budget (e.g. 512M, 4G).
    #[arg(long, value_name = "SIZE", default_value_t = Size(sweeptin::pipeline::default_mem()))]
    pub mem: Size,
    /// Worker threads (0: one per core). The classes are the same for any count.
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = parse_threads)]
    pub threads: usize,
    /// Directory for temporary files (default: the system's).
    #[arg(long, value_name = "DIR")]
    pub tmp_dir: Option<PathBuf>,
    /// Print a JSON summary on standard output.
    #[arg(long)]
    pub json: bool,
    /// No progress on standard error.
    #[arg(long, short)]
    pub quiet: bool,
    /// The files named by @lists and .vpc files (inputs too).
    #[arg(skip)]
    pub lists: Vec<PathBuf>,
}

impl Args {
    /// The output of each input.
    fn outputs(&self) -> anyhow::Result<Vec<PathBuf>> {
        match (&self.output, &self.odir) {
            (Some(o), None) if self.inputs.len() == 1 => Ok(vec![o.clone()]),
            (Some(_), None) => Err(sweeptin::Error::Options(format!(
                "-o names one output for {} inputs: give --odir DIR (each input is written \
                 there under its own name)",
                self.inputs.len()
            ))
            .into()),
            (None, Some(dir)) => {
                super::input::check_odir(dir)?;
                self.inputs
                    .iter()
                    .map(|i| match i.file_name() {
                        Some(_) => Ok(super::input::in_dir(dir, i)),
                        None => Err(sweeptin::Error::Options(format!(
                            "{}: an input without a file name",
                            i.display()
                        ))
                        .into()),
                    })
                    .collect()
            }
            _ => Err(sweeptin::Error::Options(
                "give -o OUT.laz (one input) or --odir DIR (any number)".into(),
            )
            .into()),
        }
    }
}

/// The `--json` summary.
#[derive(serde::Serialize)]
struct Summary<'a> {
    inputs: &'a [PathBuf],
    outputs: &'a [PathBuf],
    params: GroundParams,
    #[serde(flatten)]
    ground: &'a GroundSummary,
    changed: u64,
    bytes: u64,
    write_seconds: f64,
    seconds: f64,
}

pub fn run(mut args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    args.lists = super::input::expand_files(&mut args.inputs)?;
    let mut params = args.params.params();
    params.reset = args.reset;
    params.check()?;
    let outputs = args.outputs()?;
    let pairs: Vec<(&str, &Path)> = outputs
        .iter()
        .map(|o| {
            (
                if args.odir.is_some() { "--odir" } else { "-o" },
                o.as_path(),
            )
        })
        .collect();
    let mut read = args.inputs.clone();
    read.extend(args.lists.iter().cloned());
    super::input::distinct_outputs(&pairs, &read, "ground")?;
    for o in &outputs {
        super::input::check_output(o)?;
        sweeptin::output::las::check_point_output(o, &read)?;
    }
    sweeptin::pipeline::size_thread_pool(args.threads);
    let tmp = args.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new_spinner();
        b.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("template"));
        b.enable_steady_tick(Duration::from_millis(200));
        b
    };
    let mut progress = |what: &str, done: u64, total: u64| {
        if total == 0 {
            bar.set_message(what.to_string());
        } else {
            bar.set_message(format!("{what}: {done} of {total} points"));
        }
    };
    let done = sweeptin::pipeline::ground::ground_files(
        &args.inputs,
        &outputs,
        &params,
        args.mem.0,
        &tmp,
        &mut progress,
    )
    .map_err(|e| super::input::run_error(e, &args.inputs))?;
    let summary = &done.ground;
    let (mut changed, mut bytes) = (0u64, 0u64);
    for s in &done.files {
        for note in &s.notes {
            bar.suspend(|| eprintln!("sweeptin: note: {note}"));
        }
        changed += s.changed;
        bytes += s.bytes;
    }
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    if summary.ground == 0 && !args.quiet {
        eprintln!(
            "sweeptin: warning: no ground found in {} points (no points, or none eligible: \
             withheld or noise): `dem --class 2` on the output has nothing to grid",
            summary.points
        );
    }
    if args.json {
        let s = Summary {
            inputs: &args.inputs,
            outputs: &outputs,
            params,
            ground: summary,
            changed,
            bytes,
            write_seconds: (seconds - summary.read_seconds - summary.classify_seconds).max(0.0),
            seconds,
        };
        println!("{}", serde_json::to_string(&s)?);
    } else if !args.quiet {
        eprintln!(
            "{} points: {} ground, {} low noise ({} blocks of {}), written in {:.1} s",
            summary.points,
            summary.ground,
            summary.low_noise,
            summary.blocks,
            summary.block,
            seconds
        );
    }
    Ok(())
}
