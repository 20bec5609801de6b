//! `sweeptin hillshade`: shaded relief of a DEM, as a PNG with a world file or a georeferenced
//! GeoTIFF / COG.

use super::input::check_output;
use std::path::PathBuf;
use sweeptin::products::hillshade::{HillshadeOptions, hillshade};

/// Arguments of `sweeptin hillshade`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A single-band DEM (GeoTIFF, COG or ESRI ASCII grid).
    pub dem: PathBuf,
    /// Output: .png (grey + alpha, nodata transparent, with a .pgw world file and a .prj when
    /// the CRS is known as WKT) or .tif (8-bit GeoTIFF, 0 = nodata, as gdaldem writes; --format
    /// cog for a Cloud Optimized GeoTIFF).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub raster: super::products::RasterArgs,
    /// Direction the light comes from, in degrees clockwise from north.
    #[arg(long, default_value_t = 315.0)]
    pub azimuth: f64,
    /// Height of the light above the horizon, in degrees (0 to 90).
    #[arg(long, default_value_t = 45.0)]
    pub altitude: f64,
    /// Vertical exaggeration (> 0; for a DEM in degrees of latitude/longitude, about
    /// 0.00001 so that metres of height match degrees of extent).
    #[arg(long, default_value_t = 1.0)]
    pub z_factor: f64,
    /// No summary line on standard error (errors are still printed).
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let o = HillshadeOptions {
        azimuth: args.azimuth,
        altitude: args.altitude,
        z_factor: args.z_factor,
        output: args.raster.options(),
    };
    o.check()?;
    super::input::distinct_outputs(
        &[("-o", &args.output)],
        std::slice::from_ref(&args.dem),
        "hillshade",
    )?;
    check_output(&args.output)?;
    let s = hillshade(&args.dem, &args.output, &o)?;
    if args.quiet {
        return Ok(());
    }
    eprintln!(
        "sweeptin: {} -> {}: {} × {} pixels, {} shaded",
        args.dem.display(),
        args.output.display(),
        s.cols,
        s.rows,
        s.shaded
    );
    Ok(())
}
