//! `sweeptin crossval`: leave-one-out accuracy of the Delaunay TIN of a point set.

use super::info::FilterArgs;
use anyhow::Context;
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::Tin;
use sweeptin::pipeline::{Input, read_points};

/// Arguments of `sweeptin crossval`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input points: LAS/LAZ or XYZ text; several files form one set.
    #[arg(required = true)]
    pub input: Vec<PathBuf>,
    /// Points to test.
    #[arg(long, default_value_t = 1000)]
    pub samples: usize,
    /// Seed of the random draw of the points to test.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Which point survives among exact (x, y) duplicates.
    #[arg(long, value_enum, default_value_t = sweeptin::DuplicatePolicy::First)]
    pub duplicates: sweeptin::DuplicatePolicy,
    #[command(flatten)]
    pub filter: FilterArgs,
    /// Print a JSON summary on standard output.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    if args.samples == 0 {
        return Err(sweeptin::Error::Options("--samples must be at least 1".into()).into());
    }
    let input = Input {
        paths: args.input.clone(),
        filter: args.filter.to_filter(),
        duplicates: args.duplicates,
        lines: Default::default(),
    };
    let (points, _crs) = read_points(&input)?;
    let tri = sweeptin::triangulate(
        &points,
        &sweeptin::Options {
            duplicates: args.duplicates,
        },
    )
    .context("cannot triangulate the points")?;
    let mut tin = Tin::from_triangulation(&tri)?;
    let cv = tin.leave_one_out(args.samples, args.seed)?;
    let zs = tri.vertices.iter().map(|p| p[2]);
    let (lo, hi) = zs.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), z| {
        (l.min(z), h.max(z))
    });
    if args.json {
        let summary = serde_json::json!({
            "input": args.input,
            "points": tin.vertex_count(),
            "height_range": [lo, hi],
            "crossval": cv,
            "seconds": start.elapsed().as_secs_f64(),
        });
        println!("{}", serde_json::to_string_pretty(&summary)?);
    }
    eprintln!(
        "sweeptin: leave-one-out on {} of {} points: mean error {:.4} ({:.2} % of the height \
         range {:.2}), RMS {:.4}, max {:.4}, bias {:+.4}; {} skipped (hull); {:.2} s",
        cv.tested,
        tin.vertex_count(),
        cv.mean_error,
        100.0 * cv.mean_error / (hi - lo).max(f64::MIN_POSITIVE),
        hi - lo,
        cv.rms_error,
        cv.max_error,
        cv.bias,
        cv.skipped,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
