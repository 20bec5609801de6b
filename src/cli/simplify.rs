//! `sweeptin simplify`: grid DEM in, TIN within an error bound out.

use super::input::Size;
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use sweeptin::input::raster::RasterReader;
use sweeptin::output::{MeshFormat, MeshMeta, create_mesh_sink};
use sweeptin::simplify::{
    DEFAULT_WINDOW, GridOptions, GridProgress, Options, Stop, simplify_raster,
};

/// Arguments of `sweeptin simplify`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("bound").required(true).args(["max_error", "max_triangles", "max_points"])))]
#[command(after_help = "\
Greedy insertion (Garland & Heckbert, as hmm and delatin): start from the grid's corners, insert \
the cell farthest (vertically) from the TIN with exact Delaunay insertion, repeat until every \
valid cell is within --max-error, then remove the points the bound does not need. Missing cells \
(nodata) are never covered by a triangle.

Memory: a grid wider or taller than --window cells is cut into windows of at most --window × \
--window cell intervals that share their border lines. Each border line is first simplified on \
its own (in 1-D, to the same bound), so both windows on it keep the same vertices there and the \
TIN is conforming; then every window is refined from its border vertices, on every core \
(--threads), and written as soon as it and the windows before it are done. The grid is read a \
band of windows at a time (tiled or striped GeoTIFF, ESRI ASCII), so memory is about one band \
of heights (12 bytes a cell at most) plus up to 256 bytes a cell of each window in progress, \
checked against --mem before anything is read. The output depends on --window only, never on \
--mem or --threads; a grid that fits in one window is simplified whole (as before windows). \
Point and triangle budgets (--max-points, --max-triangles) need the whole grid in one window.

Example: a 1 m lidar DTM within 10 cm, in 2 GB:
  sweeptin simplify dtm.tif --max-error 0.1 -o tin.ply --mem 2G --json")]
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
    /// Window side in cells (cell intervals): larger grids are simplified window by window with
    /// shared border lines (a few more points than one window: the borders are simplified in
    /// 1-D). The output depends on it, never on --mem or --threads.
    #[arg(long, value_name = "CELLS", default_value_t = DEFAULT_WINDOW)]
    pub window: u32,
    /// Memory budget (e.g. 512M, 4G): a job whose band of windows cannot fit is refused before
    /// reading; with room, more windows run at once and the next band is read ahead.
    #[arg(long, value_name = "SIZE", default_value_t = Size(sweeptin::pipeline::default_mem()))]
    pub mem: Size,
    /// Threads refining windows (default: every core). The output is the same for any number.
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = super::input::parse_threads)]
    pub threads: usize,
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
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new_spinner();
        b.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("template"));
        b.enable_steady_tick(Duration::from_millis(200));
        b
    };
    let mut progress = |p: GridProgress| match p {
        GridProgress::Refining { points, error } => {
            bar.set_message(format!("{points} points, worst error {error:.3}"))
        }
        GridProgress::Windows {
            done,
            total,
            points,
        } => bar.set_message(format!("window {done}/{total}, {points} points")),
    };
    let grid = GridOptions {
        options: Options {
            stop,
            decimate: !args.no_decimate,
        },
        window: args.window,
        mem: args.mem.0,
        threads: args.threads,
    };
    let result = simplify_raster(&mut reader, &grid, sink.as_mut(), Some(&mut progress));
    let s = result.with_context(|| format!("cannot simplify {}", args.input.display()))?;
    bar.finish_and_clear();
    let written = sink.finish()?;
    let s = &s;
    let total_s = start.elapsed().as_secs_f64();
    if args.json {
        let summary = serde_json::json!({
            "input": args.input,
            "output": args.output,
            "grid": { "cols": spec.cols, "rows": spec.rows, "crs": spec.crs },
            "sample_type": reader.sample_type(),
            "options": grid,
            "stats": s,
            "bytes": written.bytes,
            "total_seconds": total_s,
            "peak_rss_bytes": sweeptin::pipeline::peak_rss(),
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
