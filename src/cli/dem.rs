//! `sweeptin dem`: a DEM raster (float32 GeoTIFF or ESRI ASCII grid) by linear interpolation in
//! the TIN at cell centres, optionally with contours and a hillshade from the same pass.

use super::input::check_output;
use super::input::{ProductInput, run_products};
use super::products::{ContourArgs, DemArgs, Report, check_hillshade, finish_report, shade};
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::sink::TriangleSink;

/// Arguments of `sweeptin dem`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: ProductInput,
    /// Output raster: .tif (float32 GeoTIFF; --format cog for a Cloud Optimized GeoTIFF) or .asc
    /// (ESRI ASCII grid). With --bbox it covers the cells whose centres lie in
    /// [XMIN, XMAX) × (YMIN, YMAX] (boxes that touch share no cell). `-`, a FIFO or a device
    /// takes an ASCII grid (--raster-format asc), not a GeoTIFF (which needs seeking).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub dem: DemArgs,
    /// Also write contour lines (GeoJSON) from the same pass.
    #[arg(long, value_name = "GEOJSON")]
    pub contours: Option<PathBuf>,
    #[command(flatten)]
    pub contour: ContourArgs,
    /// Also write a hillshade of the result (GeoTIFF or COG output only): a PNG with a .pgw
    /// world file, or an 8-bit GeoTIFF (.tif).
    #[arg(long, value_name = "PNG")]
    pub hillshade: Option<PathBuf>,
}

/// The sinks of the DEM and its contours (checked before any work).
pub fn sinks(args: &Args) -> anyhow::Result<Vec<(String, Box<dyn TriangleSink>)>> {
    if let Some(png) = &args.hillshade {
        // Before the outputs' names are compared (`-o d.asc --hillshade d.png` said the two
        // .prj clash rather than what is wrong).
        check_hillshade(&args.output, args.dem.raster.format, png)?;
    }
    let mut outputs: Vec<(&str, &std::path::Path)> = vec![("-o", &args.output)];
    if let Some(c) = &args.contours {
        outputs.push(("--contours", c));
    }
    if let Some(h) = &args.hillshade {
        outputs.push(("--hillshade", h));
    }
    let prj = sweeptin::output::ascii_grid_prj(&args.output, args.dem.raster.format);
    if let Some(p) = &prj {
        outputs.push(("-o (its .prj)", p));
    }
    args.input.args.check_outputs(&outputs, &[])?;
    let bbox = args.input.args.filter.bbox;
    let mut sinks: Vec<(String, Box<dyn TriangleSink>)> = vec![(
        "dem".into(),
        args.dem.sink(
            &args.output,
            bbox,
            args.input.args.mem.0,
            args.input.header_bounds(),
        )?,
    )];
    if let Some(png) = &args.hillshade {
        check_output(png)?;
    }
    if let Some(p) = &args.contours {
        sinks.push((
            "contours".into(),
            args.contour
                .sink(p, args.input.args.mem.0, &args.input.args.inputs)?,
        ));
    }
    Ok(sinks)
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let bbox = args.input.args.filter.bbox;
    let sinks = sinks(&args)?;
    if args.dem.buffer.is_some() && !args.input.all_lidar() {
        eprintln!("sweeptin: warning: --buffer only limits the reading of LAS/LAZ files");
    }
    let config = args.input.config(args.dem.read_box(bbox)?)?;
    let (run, products) = run_products(&args.input, &config, None, sinks)?;
    let mut report = Report::new(products);
    if let Some(png) = &args.hillshade {
        report.hillshade = Some(shade(&args.output, png)?);
    }
    finish_report(&args.input, &run, &report, start)
}
