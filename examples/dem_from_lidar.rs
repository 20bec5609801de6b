//! The library's streaming pipeline from Rust: the points of LAS/LAZ tiles to a 1 m DEM
//! GeoTIFF and contour lines in one pass, in bounded memory, on every core (exact tiles).
//!
//! ```sh
//! cargo run --release --example dem_from_lidar -- data/sample/startinpy_small.laz dem.tif c.geojson
//! ```

use std::path::PathBuf;
use sweeptin::TileOptions;
use sweeptin::input::las::Filter;
use sweeptin::pipeline::{Input, RunConfig, RunOptions, run};
use sweeptin::products::contours::{ContourOptions, ContourSink};
use sweeptin::products::dem::{DemOptions, DemSink};
use sweeptin::raster::{Align, GridExtent, GridPlan};
use sweeptin::sink::{Fanout, ProductSummary, TriangleSink};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [laz, dem, contours] = args.as_slice() else {
        return Err("usage: dem_from_lidar INPUT.laz DEM.tif CONTOURS.geojson".into());
    };
    let input = Input {
        paths: vec![PathBuf::from(laz)],
        // Every point (`classes: Some(vec![2])` keeps the ground only, as `--class 2`).
        filter: Filter::default(),
        duplicates: sweeptin::DuplicatePolicy::Lowest,
        lines: Default::default(),
    };
    let options = RunOptions {
        mem: 256 << 20,
        tiles: Some(TileOptions::default()),
        ..RunOptions::default()
    };
    let config = RunConfig::new(input, options)?;
    let dem_sink = DemSink::new(
        dem.as_ref(),
        DemOptions {
            grid: GridPlan::new(1.0, GridExtent::Auto, Align::Edges)?,
            ..DemOptions::default()
        },
    )?;
    let contour_sink = ContourSink::new(
        contours.as_ref(),
        ContourOptions {
            interval: 0.5,
            ..ContourOptions::default()
        },
    )?;
    let sinks: Vec<(String, Box<dyn TriangleSink>)> = vec![
        ("dem".into(), Box::new(dem_sink)),
        ("contours".into(), Box::new(contour_sink)),
    ];
    let mut fanout = Fanout::new(sinks);
    let summary = run(&config, None, &mut [&mut fanout])?;
    println!(
        "{} points, {} triangles",
        summary.points_read, summary.triangles
    );
    if let Some(ProductSummary::Fanout(products)) = summary.products.first() {
        for (name, s) in &products.0 {
            println!("{name}: {s:?}");
        }
    }
    Ok(())
}
