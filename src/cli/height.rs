//! `sweeptin height`: height above ground of every point, written back into the points.

use super::input::{Size, parse_threads};
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::input::las::parse_classes;
use sweeptin::pipeline::height::{Ground, HeightJob, height};
use sweeptin::pipeline::{self, RunOptions};

const EXAMPLES: &str = "\
Examples:
  sweeptin height tile.laz -o tile_hag.laz
      adds HeightAboveGround (a double, PDAL's name) from the TIN of the class-2 points
  sweeptin dem tile_hag.laz --returns first --z-from HeightAboveGround --cell 0.5 -o chm.tif
      a canopy height model from those heights
  sweeptin height raw.laz --ground -o raw_hag.laz
      the ground found on the fly by the ground filter (`sweeptin ground`'s options)
  sweeptin height tiles/*.laz --odir normalized/ --replace-z
      z replaced by the height (lidR's normalize_height), one output per input, the ground
      made from the class-2 points of all the tiles together

Points outside the ground TIN's hull (the convex hull of the ground points of all the inputs)
get no height: HeightAboveGround is NaN there (--z-from skips them); with --replace-z their z
is kept and they are flagged withheld (every command skips withheld points by default).";

/// Arguments of `sweeptin height`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct Args {
    /// LAS/LAZ/COPC files: their ground points together make one ground TIN; each file is
    /// written to an output of its own, every attribute kept.
    #[arg(required = true, value_name = "FILES")]
    pub inputs: Vec<PathBuf>,
    /// Output file (one input), or a directory (ending in `/`, or existing) as --odir.
    /// `.laz` is written compressed, `.las` as LAS (other names are refused).
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Output directory: each input written there under its own name (a `.copc.laz` as
    /// `.laz`), as LAStools' -odir.
    #[arg(long, value_name = "DIR", conflicts_with = "output")]
    pub odir: Option<PathBuf>,
    /// Replace z by the height above ground instead of adding a HeightAboveGround attribute.
    #[arg(long)]
    pub replace_z: bool,
    /// Classes of the ground points (their TIN is the ground).
    #[arg(long, value_name = "LIST", default_value = "2")]
    pub ground_class: String,
    /// Find the ground on the fly instead: the points the ground filter of `sweeptin ground`
    /// classifies as ground (with the options below; the files' own classes are ignored and
    /// kept in the outputs), so that `height raw.laz --ground` equals `ground raw.laz -o g.laz`
    /// then `height g.laz` (but the classes are not written).
    #[arg(long, conflicts_with = "ground_class")]
    pub ground: bool,
    #[command(flatten)]
    pub ground_options: super::ground::GroundOptions,
    /// Memory budget (half sorts the points, half makes the ground TIN), e.g. 512M.
    #[arg(long, value_name = "SIZE", default_value_t = Size(pipeline::default_mem()))]
    pub mem: Size,
    /// Directory for spill files.
    #[arg(long, value_name = "DIR")]
    pub tmp_dir: Option<PathBuf>,
    /// Threads (default: every core).
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = parse_threads)]
    pub threads: usize,
    /// No progress on stderr.
    #[arg(short, long)]
    pub quiet: bool,
    /// Print a one-object JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
    /// The files named by @lists and .vpc files (inputs too: no output may replace them).
    #[arg(skip)]
    pub lists: Vec<PathBuf>,
}

fn outputs(args: &Args) -> anyhow::Result<Vec<PathBuf>> {
    let dir = match (&args.odir, &args.output) {
        (Some(d), _) => Some(d.clone()),
        (None, Some(o)) if o.to_string_lossy().ends_with('/') || o.is_dir() => Some(o.clone()),
        (None, Some(o)) => {
            if args.inputs.len() != 1 {
                anyhow::bail!(sweeptin::Error::Options(format!(
                    "-o {}: {} inputs need an output directory (-o DIR/ or --odir DIR), one \
                     output per input",
                    o.display(),
                    args.inputs.len()
                )));
            }
            return Ok(vec![o.clone()]);
        }
        (None, None) => anyhow::bail!(sweeptin::Error::Options(
            "height: give -o OUT.laz (one input) or --odir DIR".into()
        )),
    };
    let dir = dir.expect("set above");
    super::input::check_odir(&dir)?;
    Ok(args
        .inputs
        .iter()
        .map(|i| super::input::in_dir(&dir, i))
        .collect())
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let ground = if args.ground {
        let params = args.ground_options.params();
        params.check()?;
        Ground::Classify(params)
    } else if args.ground_options.any() {
        anyhow::bail!(sweeptin::Error::Options(
            "the ground filter's options (--step, --max-angle, --town, …) apply with --ground: \
             add --ground to measure heights above the ground found on the fly"
                .into()
        ));
    } else {
        Ground::Classes(parse_classes(&args.ground_class)?)
    };
    let outputs = outputs(&args)?;
    // The lists and `.vpc` files named are inputs too (the library sees the files they name).
    let mut read = args.inputs.clone();
    read.extend(args.lists.iter().cloned());
    for o in &outputs {
        sweeptin::output::las::check_point_output(o, &read)?;
    }
    let job = HeightJob {
        outputs,
        inputs: args.inputs.clone(),
        ground,
        replace_z: args.replace_z,
    };
    pipeline::size_thread_pool(args.threads);
    let options = RunOptions {
        mem: args.mem.0,
        tmp_dir: args.tmp_dir.clone(),
        progress: !args.quiet && !args.json,
        tiles: Some(sweeptin::TileOptions {
            threads: args.threads,
            tile: None,
            base: None,
            scope: None,
        }),
        ..RunOptions::default()
    };
    let summary = height(&job, &options)?;
    let seconds = start.elapsed().as_secs_f64();
    if args.json {
        let v = serde_json::json!({
            "points": summary.points,
            "ground_points": summary.ground_points,
            "outside": summary.outside,
            "files": summary.files,
            "seconds": seconds,
        });
        println!("{v}");
    } else {
        for f in &summary.files {
            for n in &f.notes {
                eprintln!("sweeptin: note: {n}");
            }
            println!(
                "{}: {} points, {} bytes",
                f.output.display(),
                f.points,
                f.bytes
            );
        }
        println!(
            "height: {} points above a TIN of {} ground points, {} outside it (no height), \
             {seconds:.2} s",
            summary.points, summary.ground_points, summary.outside
        );
    }
    Ok(())
}
