//! `sweeptin simplify`: grid DEM in, TIN within an error bound out.

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use sweeptin::input::raster::{Heights, RasterReader};
use sweeptin::output::{MeshFormat, MeshMeta, create_mesh_sink};
use sweeptin::simplify::{Options, Stop, simplify};

/// Arguments of `sweeptin simplify`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("bound").required(true).args(["max_error", "max_triangles", "max_points"])))]
pub struct Args {
    /// Input grid: GeoTIFF (single band, integer or float, GDAL_NODATA honoured) or ESRI ASCII
    /// grid (.asc).
    pub input: PathBuf,
    /// Output mesh: .ply (binary PLY), .obj (Wavefront OBJ) or .xml (LandXML 1.2).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output format, when the extension does not say it.
    #[arg(long, value_enum)]
    pub format: Option<MeshFormat>,
    /// Refine until every valid cell is within this vertical distance of the TIN (grid z units).
    #[arg(long)]
    pub max_error: Option<f64>,
    /// Stop before the TIN would have more triangles than this.
    #[arg(long)]
    pub max_triangles: Option<u64>,
    /// Stop when the TIN has this many points.
    #[arg(long)]
    pub max_points: Option<u64>,
    /// Keep every point the greedy insertion chose (no redundant-point removal pass).
    #[arg(long)]
    pub no_decimate: bool,
    /// No progress spinner.
    #[arg(short, long)]
    pub quiet: bool,
    /// Print a JSON summary on standard output (instead of the one-line summary on standard
    /// error).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let stop = match (args.max_error, args.max_triangles, args.max_points) {
        (Some(e), _, _) => Stop::MaxError(e),
        (_, Some(n), _) => Stop::MaxTriangles(n),
        (_, _, Some(n)) => Stop::MaxPoints(n),
        _ => unreachable!("clap requires one bound"),
    };
    super::input::distinct_outputs(
        &[("-o", &args.output)],
        std::slice::from_ref(&args.input),
        "simplify",
    )?;
    super::input::stdout_free(&[("-o", &args.output)], args.json)?;
    super::input::check_output(&args.output)?;
    let mut reader = RasterReader::open(&args.input)?;
    let spec = reader.spec().clone();
    let meta = MeshMeta {
        crs: spec.crs.clone(),
        comments: vec![format!(
            "simplified from {} ({stop:?})",
            args.input.display()
        )],
    };
    // Open the output first: a bad output path fails before any heavy work.
    let mut sink = create_mesh_sink(&args.output, args.format, &meta)?;
    // Kept as f32 when exact (all integer grids up to 16 bits, float32 grids): half the memory
    // and bandwidth of f64.
    let heights = reader.read_heights()?;
    let read_s = start.elapsed().as_secs_f64();
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new_spinner();
        b.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("template"));
        b.enable_steady_tick(Duration::from_millis(200));
        b
    };
    let mut progress = |points: u64, error: f64| {
        bar.set_message(format!("{points} points, worst error {error:.3}"));
    };
    let options = Options {
        stop,
        decimate: !args.no_decimate,
    };
    let result = match &heights {
        Heights::F32(h) => simplify(&spec, h, &options, Some(&mut progress)),
        Heights::F64(h) => simplify(&spec, h, &options, Some(&mut progress)),
    };
    let tin = result.with_context(|| format!("cannot simplify {}", args.input.display()))?;
    bar.finish_and_clear();
    drop(heights);
    for &v in &tin.vertices {
        sink.vertex(v)?;
    }
    for t in &tin.triangles {
        sink.triangle(t.map(u64::from))?;
    }
    let written = sink.finish()?;
    let s = &tin.stats;
    let total_s = start.elapsed().as_secs_f64();
    if args.json {
        let summary = serde_json::json!({
            "input": args.input,
            "output": args.output,
            "grid": { "cols": spec.cols, "rows": spec.rows, "crs": spec.crs },
            "sample_type": reader.sample_type(),
            "options": options,
            "stats": s,
            "bytes": written.bytes,
            "read_seconds": read_s,
            "total_seconds": total_s,
        });
        println!("{}", serde_json::to_string_pretty(&summary)?);
        return Ok(());
    }
    eprintln!(
        "sweeptin: {} ({}×{}, {} valid cells) -> {}: {} points ({:.2} %), {} triangles, \
         max error {:.4}, RMS {:.4}{} in {:.2} s (refinement {:.2} s)",
        args.input.display(),
        spec.cols,
        spec.rows,
        s.valid_cells,
        args.output.display(),
        s.points,
        100.0 * s.point_ratio,
        s.triangles,
        s.max_error,
        s.rms_error,
        if s.uncovered_cells > 0 {
            format!(", {} valid cells in no triangle", s.uncovered_cells)
        } else {
            String::new()
        },
        total_s,
        s.seconds,
    );
    Ok(())
}
