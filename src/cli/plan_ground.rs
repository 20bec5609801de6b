//! `sweeptin plan ground FILES… --tile T -o JOB`: the ground classification cut into tasks,
//! each writing the points its tile owns with one `sweeptin ground` run's classes
//! ([`sweeptin::plan::Product::Ground`]); `run` and `merge` as for the other plans.

use super::ground::GroundOptions;
use super::input::Size;
use anyhow::Context;
use clap::Parser;
use std::io::IsTerminal;
use std::path::PathBuf;
use sweeptin::fmt::{Figure, count};
use sweeptin::plan::{Job, Plan, PlanDir, Product};

// `plan ground`'s own command line (after `plan`, without `-o`); the doc line below is its
// `--help`'s first line.
/// Tile the ground classification: each task classifies the ground blocks of its tile as one
/// `sweeptin ground` run over all FILES would, and writes the points its tile owns (-o JOB).
#[derive(Parser, Debug)]
#[command(name = "sweeptin plan ground")]
struct Args {
    /// Input LAS/LAZ/COPC files (classified together, as one `sweeptin ground` run).
    #[arg(required = true, value_name = "FILES")]
    inputs: Vec<PathBuf>,
    /// The plan's tile side: each task writes the points of its tile.
    #[arg(long, value_name = "SIZE")]
    tile: f64,
    #[command(flatten)]
    params: GroundOptions,
    /// Points that are not ground (nor noise, nor withheld) become class 1.
    #[arg(long)]
    reset: bool,
    /// A task's memory budget (e.g. 512M, 4G).
    #[arg(long, value_name = "SIZE", default_value_t = Size(sweeptin::pipeline::default_mem()))]
    mem: Size,
    /// Directory for a task's temporary files (default: the system's).
    #[arg(long, value_name = "DIR")]
    tmp_dir: Option<PathBuf>,
    /// No summary on standard error.
    #[arg(short, long)]
    quiet: bool,
}

/// Makes the plan of `argv` (`ground FILES… options`, `-o` taken off) into `dir`.
pub fn plan(argv: &[String], dir: Option<PathBuf>) -> anyhow::Result<()> {
    // argv[0] is `ground`: the usage lines name the whole command.
    let named =
        std::iter::once("sweeptin plan ground").chain(argv.iter().skip(1).map(String::as_str));
    let args = match Args::try_parse_from(named) {
        Ok(a) => a,
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelp => {
            let _ = e.print();
            std::process::exit(0);
        }
        Err(e) => {
            let text = e.to_string();
            anyhow::bail!("{}", text.trim_start_matches("error: ").trim_end());
        }
    };
    let dir = dir.context("give the plan's directory with -o DIR")?;
    let plan_dir = PlanDir::new(&dir)?;
    plan_dir.check_writable()?;
    let mut params = args.params.params();
    params.reset = args.reset;
    params.check()?;
    let mut job = Job::new(Product::Ground);
    job.classes = None;
    job.drop_withheld = false;
    job.mem = args.mem.0;
    job.tmp_dir = args.tmp_dir.clone();
    job.ground = Some(params);
    let outputs = vec![("dir".to_string(), dir.clone())];
    let mut stored = vec!["ground".to_string()];
    stored.extend(argv.iter().skip(1).cloned());
    let plan = Plan::new(job, stored, outputs, &args.inputs, args.tile, 0.0)?;
    let path = plan.save(&plan_dir)?;
    super::input::warn_headers(&plan.warnings);
    let points: u64 = plan.files.iter().map(|f| f.points).sum();
    if !std::io::stdout().is_terminal() {
        println!("{}", plan.tiles.len());
    }
    if args.quiet {
        return Ok(());
    }
    eprintln!(
        "sweeptin: {} ground tasks (tiles of {}) over {} files, {} points -> {}",
        count(plan.tiles.len() as u64),
        Figure(args.tile),
        count(plan.files.len() as u64),
        count(points),
        path.display()
    );
    eprintln!(
        "  next: sweeptin run {} --all --jobs N, then sweeptin merge {} -o OUT.vpc (or OUT.laz)",
        path.display(),
        path.display()
    );
    Ok(())
}
