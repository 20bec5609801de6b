//! `sweeptin profile`: the section of the TIN along polylines, with chainage.

use super::input::{InputArgs, check_output, run_products};
use super::products::report;
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::products::profile::ProfileSink;

/// Arguments of `sweeptin profile`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,
    /// The line(s): GeoJSON LineString or MultiLineString geometries, bare or in features.
    #[arg(long, value_name = "GEOJSON")]
    pub line: PathBuf,
    /// Output CSV: line,chainage,x,y,z — a point at every triangle edge crossed.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print the summary as JSON on standard output.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    check_output(&args.output)?;
    let lines = sweeptin::products::geojson::read_lines(&args.line)?;
    let sink = ProfileSink::new(lines, &args.output)?;
    let input = args.input.to_input(None)?;
    let (run, summary) = run_products(
        &args.input,
        &input,
        None,
        vec![("profile".into(), Box::new(sink))],
    )?;
    report(&run, &summary, start.elapsed().as_secs_f64());
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    }
    Ok(())
}
