//! `sweeptin contours`: contour lines of the TIN, stitched into polylines, as GeoJSON.

use super::input::{InputArgs, run_products};
use super::products::{ContourArgs, report};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `sweeptin contours`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output GeoJSON (LineString features with an `elevation` property).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub contour: ContourArgs,
    /// Print the summary as JSON on standard output.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let sinks = vec![("contours".to_string(), args.contour.sink(&args.output)?)];
    let input = args.input.to_input(None)?;
    let (run, summary) = run_products(&args.input, &input, None, sinks)?;
    report(&run, &summary, start.elapsed().as_secs_f64());
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    }
    Ok(())
}
