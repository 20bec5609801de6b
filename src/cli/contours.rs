//! `sweeptin contours`: contour lines of the TIN, stitched into polylines, as GeoJSON or
//! GeoPackage.

use super::input::{ProductInput, run_products};
use super::products::{ContourArgs, Report, finish_report};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `sweeptin contours`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: ProductInput,
    /// Output: GeoJSON (.geojson, .json) or GeoPackage (.gpkg), LineString features with an
    /// `elevation` (and `closed`) attribute.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub contour: ContourArgs,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    args.input
        .args
        .check_outputs(&[("-o", &args.output)], &[])?;
    let sinks = vec![(
        "contours".to_string(),
        args.contour
            .sink(&args.output, args.input.args.mem.0, &args.input.args.inputs)?,
    )];
    let config = args.input.config(None)?;
    let (run, products) = run_products(&args.input, &config, None, sinks)?;
    finish_report(&args.input, &run, &Report::new(products), start)
}
