//! `sweeptin sample`: heights of the TIN at query points.

use super::input::{ProductInput, run_products};
use super::products::{Report, finish_report};
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::products::sample::SampleSink;

/// Arguments of `sweeptin sample`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: ProductInput,
    /// Query points: x and y as the first two fields of each line, or the columns a header
    /// names (`id,x,y`; also easting, northing, any case); sorted by y for bounded memory;
    /// other columns are kept.
    #[arg(long, value_name = "CSV")]
    pub points: PathBuf,
    /// Output: every query line with one more field, z (empty outside the TIN; `z_tin` when
    /// the header has a z column).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    args.input
        .args
        .check_outputs(&[("-o", &args.output)], &[&args.points])?;
    let sink = SampleSink::new(&args.points, &args.output)?;
    if !sink.sorted() {
        eprintln!(
            "sweeptin: warning: {} is not sorted by y: all queries are held in memory",
            args.points.display()
        );
    }
    let config = args.input.config(None)?;
    let (run, products) = run_products(
        &args.input,
        &config,
        None,
        vec![("sample".into(), Box::new(sink))],
    )?;
    finish_report(&args.input, &run, &Report::new(products), start)
}
