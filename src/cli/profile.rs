//! `sweeptin profile`: the section of the TIN along polylines, with chainage.

use super::input::{ProductInput, run_products};
use super::products::{Report, finish_report};
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::products::profile::ProfileSink;

/// Arguments of `sweeptin profile`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: ProductInput,
    /// The line(s): GeoJSON LineString or MultiLineString geometries, bare or in features.
    #[arg(long, value_name = "GEOJSON")]
    pub line: PathBuf,
    /// Output CSV: line,chainage,x,y,z — a point at every triangle edge crossed.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    args.input
        .args
        .check_outputs(&[("-o", &args.output)], &[&args.line])?;
    let lines = sweeptin::input::geojson::read_lines(&args.line)?;
    let sink = ProfileSink::new(lines, &args.output)?;
    let config = args.input.config(None)?;
    let (run, products) = run_products(
        &args.input,
        &config,
        None,
        vec![("profile".into(), Box::new(sink))],
    )?;
    finish_report(&args.input, &run, &Report::new(products), start)
}
