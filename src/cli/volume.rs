//! `sweeptin volume`: cut and fill volumes and areas against a plane or a second surface, within
//! an optional boundary polygon.

use super::input::{ProductInput, run_products};
use super::products::read_boundary;
use anyhow::Context;
use serde_json::Value;
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::pipeline;
use sweeptin::products::overlay::{BandStore, OverlaySink};
use sweeptin::products::volume::VolumeSink;
use sweeptin::sink::TriangleSink;

/// Arguments of `sweeptin volume`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("reference").required(true).args(["plane", "surface"])))]
pub struct Args {
    #[command(flatten)]
    pub input: ProductInput,
    /// The reference is the horizontal plane z = Z.
    #[arg(long, value_name = "Z", allow_hyphen_values = true)]
    pub plane: Option<f64>,
    /// The reference is the TIN of these files (read with the same options as the input).
    #[arg(long, value_name = "FILE", num_args = 1..)]
    pub surface: Vec<PathBuf>,
    /// Restrict to this polygon (GeoJSON Polygon/MultiPolygon; holes allowed).
    #[arg(long, value_name = "GEOJSON")]
    pub boundary: Option<PathBuf>,
    /// Bands the reference surface is filed into (with --surface).
    #[arg(long, default_value_t = 1024, hide = true)]
    pub bands: usize,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let boundary = args.boundary.as_deref().map(read_boundary).transpose()?;
    let input = args.input.input(None)?;
    let sink: Box<dyn TriangleSink> = match args.plane {
        Some(z) => Box::new(VolumeSink::new(z, boundary)),
        None => {
            let dir = args
                .input
                .args
                .tmp_dir
                .clone()
                .unwrap_or_else(std::env::temp_dir);
            let mut store = BandStore::new(&dir, args.bands);
            let mut reference = input.clone();
            reference.paths = args.surface.clone();
            let names: Vec<String> = args
                .surface
                .iter()
                .map(|p| p.display().to_string())
                .collect();
            pipeline::run(
                &reference,
                &args.input.args.options(),
                None,
                &mut [&mut store],
            )
            .with_context(|| format!("cannot triangulate {}", names.join(", ")))?;
            Box::new(OverlaySink::new(store.into_reader()?, boundary))
        }
    };
    let (run, summary) = run_products(&args.input, &input, None, vec![("volume".into(), sink)])?;
    let v = &summary["volume"];
    if args.input.args.json {
        let mut out = v.clone();
        out["run"] = serde_json::to_value(&run)?;
        println!("{}", serde_json::to_string(&out)?);
        return Ok(());
    }
    let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let against = match args.plane {
        Some(z) => format!("the plane z = {z}"),
        None => "the reference surface".to_string(),
    };
    println!("against {against}:");
    println!(
        "  cut volume   {:.3}   (area {:.3})",
        f("cut_volume"),
        f("cut_area")
    );
    println!(
        "  fill volume  {:.3}   (area {:.3})",
        f("fill_volume"),
        f("fill_area")
    );
    println!("  net volume   {:.3}", f("net_volume"));
    println!("  area covered {:.3}", f("area"));
    if let Some(b) = v.get("boundary_area").and_then(Value::as_f64) {
        println!("  boundary     {b:.3}");
    }
    eprintln!(
        "sweeptin: {} points, {} triangles in {:.2} s",
        run.points_read,
        run.triangles,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
