//! `sweeptin hillshade`: shaded relief of a DEM, as a PNG with a world file or a georeferenced
//! GeoTIFF / COG.

use super::input::check_output;
use std::path::PathBuf;
use sweeptin::crs::LostCrs;
use sweeptin::fmt::{Figure, count};
use sweeptin::products::hillshade::{HillshadeOptions, HillshadeSummary, hillshade};

/// Arguments of `sweeptin hillshade`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A single-band DEM (GeoTIFF, COG or ESRI ASCII grid).
    pub dem: PathBuf,
    /// Output: .png (grey + alpha, nodata transparent, with a .pgw world file, and a .prj and
    /// GDAL's .png.aux.xml holding the CRS as WKT: the DEM's WKT1, or ESRI's WKT for the common
    /// EPSG codes) or .tif (8-bit GeoTIFF, 0 = nodata, as gdaldem writes; --format cog for a
    /// Cloud Optimized GeoTIFF).
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
    /// Vertical exaggeration (> 0; default 1).
    #[arg(long)]
    pub z_factor: Option<f64>,
    /// Horizontal units per unit of height, as `gdaldem hillshade -s` (> 0; default 1). For a
    /// DEM in a geographic CRS (degrees) with neither this nor --z-factor given, the metres a
    /// degree spans east and north at the DEM's centre latitude (what `-s 111120` approximates).
    #[arg(long)]
    pub scale: Option<f64>,
    /// No summary line on standard error (errors are still printed).
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let o = HillshadeOptions {
        azimuth: args.azimuth,
        altitude: args.altitude,
        z_factor: args.z_factor,
        scale: args.scale,
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
    warn(&args.dem, &s, true);
    if args.quiet {
        return Ok(());
    }
    eprintln!(
        "sweeptin: {} -> {}: {}",
        args.dem.display(),
        args.output.display(),
        describe(&s)
    );
    Ok(())
}

/// `1,000 × 800 pixels, 790,000 shaded`, and the scale taken from a geographic CRS.
pub fn describe(s: &HillshadeSummary) -> String {
    let mut line = format!(
        "{} × {} pixels, {} shaded",
        count(u64::from(s.cols)),
        count(u64::from(s.rows)),
        count(s.shaded)
    );
    if let Some([east, north]) = s.metres_per_degree {
        line.push_str(&format!(
            " (a geographic CRS: a degree taken as {} m east and {} m north, at the DEM's \
             centre latitude; --scale or --z-factor sets it)",
            Figure(east),
            Figure(north)
        ));
    }
    line
}

/// Prints the hillshade's warnings, once each; `no_crs`: also that the DEM declares no CRS
/// (not when the run that made the DEM has said so).
pub fn warn(dem: &std::path::Path, s: &HillshadeSummary, no_crs: bool) {
    for w in &s.warnings {
        eprintln!("sweeptin: warning: {w}");
    }
    match &s.lost_crs {
        // The warning about degrees says it already.
        Some(LostCrs::Unknown) if !no_crs || !s.warnings.is_empty() => {}
        Some(LostCrs::Unknown) => eprintln!(
            "sweeptin: warning: {}: {} (gdal_edit.py -a_srs EPSG:code names a GeoTIFF's)",
            dem.display(),
            LostCrs::Unknown
        ),
        Some(l) => eprintln!("sweeptin: warning: {l}"),
        None => {}
    }
}
