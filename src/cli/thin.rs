//! `sweeptin thin`: points in, the fewest-point TIN within a vertical tolerance out.

use super::input::InputArgs;
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::output::{MeshFormat, MeshMeta, create_mesh_sink};
use sweeptin::simplify::ThinOptions;

/// Arguments of `sweeptin thin`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Greedy insertion (Garland & Heckbert) over the points themselves: start from the points' convex \
hull and the breaklines, insert the point farthest (vertically) from the TIN, repeat until every \
point is within --max-error, then remove the vertices that are not needed. Every point left out \
lies within --max-error of the plane of its triangle, decided exactly. The result is the \
(constrained) Delaunay triangulation of the kept points, the same for any --mem or --threads.

Memory: the global run holds every point (about 64 bytes each at the peak, checked against --mem \
from the headers before reading, refused when it does not fit); --tile bounds it by one tile.

--tile T (the tiled engine's tile side, here also the thinning's tiles): bounded memory for inputs of any size (LAS/LAZ/COPC, no breaklines or trimming). A \
first pass streams the exact TIN and simplifies it in 1-D along the grid lines x = i*T, y = j*T \
into border vertices both neighbours share; then each tile (points with i*T <= x < (i+1)*T, the \
same for y) is thinned alone, from its borders, on every core, and written in tile order. Memory \
is about one tile's points (about 112 bytes each) per thread; the output is one conforming TIN, \
the same bytes for any --mem or --threads, every point still within --max-error (exactly). It \
keeps about as many points as the global run (the default), border vertices included: on a \
13 M-point tile's ground at 0.1 m, 309,562 vertices with T = 250 against 310,358 (see \
docs/ACCURACY.md); the triangles along the grid lines follow the borders, so the whole TIN is \
not Delaunay across them. A tile must be larger than a point's neighbourhood: when the grid \
lines cut the points' TIN at more places than it has points (tiles below about 4.3 mean point \
spacings), every cut may become a vertex, and the run is refused (exit 2) with the smallest \
side that works. The summary counts the vertices written: the points kept and the border \
vertices.

Example: the ground of a tile within 5 cm, with a road's edges as breaklines:
  sweeptin thin tile.laz --class 2 --max-error 0.05 --breaklines road.geojson -o ground.ply --json
Example: a whole survey in bounded memory, tiles of 500 m:
  sweeptin thin survey/*.laz --class 2 --max-error 0.1 --tile 500 -o ground.ply --json")]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output mesh: .ply (binary PLY), .obj (Wavefront OBJ), .xml (LandXML 1.2 surface) or .stin
    /// (streaming mesh). It appears only when complete.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output format, when the extension does not say it.
    #[arg(long, value_enum)]
    pub format: Option<MeshFormat>,
    /// Every input point (after filters and duplicates) ends within this vertical distance of
    /// the TIN (z units, e.g. 0.05 for 5 cm).
    #[arg(long, value_name = "DZ")]
    pub max_error: f64,
    /// Keep every point the greedy insertion chose (no redundant-point removal pass: faster,
    /// about 10 % more points).
    #[arg(long)]
    pub no_decimate: bool,
    /// Coordinate reference system recorded in the output (`EPSG:xxxx` or WKT); default: the
    /// input's, when LAS/LAZ files carry one.
    #[arg(long)]
    pub crs: Option<String>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    if !(args.max_error >= 0.0 && args.max_error.is_finite()) {
        return Err(sweeptin::Error::Options(format!(
            "--max-error {}: give a finite vertical distance >= 0",
            args.max_error
        ))
        .into());
    }
    args.input.check_outputs(&[("-o", &args.output)], &[])?;
    let given = args
        .crs
        .as_deref()
        .map(super::input::parse_crs)
        .transpose()?;
    let config = args.input.config(args.input.input())?.with_crs(given);
    let options = ThinOptions {
        max_error: args.max_error,
        decimate: !args.no_decimate,
        mem: Some(args.input.mem.0),
    };
    let crs = match &args.crs {
        Some(c) => Some(c.clone()),
        None => config.input_crs()?,
    };
    let meta = MeshMeta {
        crs,
        comments: vec![format!(
            "sweeptin {} TIN of {} thinned within {} vertically",
            env!("CARGO_PKG_VERSION"),
            args.input
                .inputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            args.max_error
        )],
    };
    // Open the output first: a bad output path fails before any heavy work.
    let mut sink = create_mesh_sink(&args.output, args.format, &meta)?;
    let mut summary = match args.input.tile {
        Some(tile) => sweeptin::pipeline::thin_tiled(&config, &options, tile, sink.as_mut())
            .map_err(|e| super::input::run_error(e, &args.input.inputs))?,
        None => {
            let (tin, summary) = sweeptin::pipeline::thin(&config, &options)
                .map_err(|e| super::input::run_error(e, &args.input.inputs))?;
            sink.declare(summary.mesh)?;
            for &v in &tin.vertices {
                sink.vertex(v)?;
            }
            for t in &tin.triangles {
                sink.triangle(t.map(u64::from))?;
            }
            summary
        }
    };
    let written = sink.finish()?;
    summary.peak_rss_bytes = sweeptin::pipeline::peak_rss();
    super::input::warn_headers(&summary.warnings);
    let s = &summary.thin;
    if args.input.json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        // What is written: the vertices, of which the points kept are a part.
        let others = match (&summary.tiles, s.line_vertices) {
            (_, 0) => String::new(),
            (Some(_), n) => format!(", {n} added on the tile borders"),
            (None, n) => format!(", {n} breakline vertices"),
        };
        eprintln!(
            "sweeptin: {} points ({} duplicates merged) -> {}: {} vertices ({:.2} % of the \
             points; {} points kept{others}), {} triangles, max error {:.4}, RMS {:.4} (bound \
             {}) in {:.2} s",
            summary.points_read,
            summary.duplicates,
            args.output.display(),
            written.vertices,
            100.0 * written.vertices as f64 / s.points.max(1) as f64,
            s.kept,
            written.triangles,
            s.max_error,
            s.rms_error,
            args.max_error,
            start.elapsed().as_secs_f64(),
        );
    }
    if s.vertices > s.points && !args.input.quiet {
        eprintln!(
            "sweeptin: warning: {} vertices written for {} points: {}",
            s.vertices,
            s.points,
            if summary.tiles.is_some() {
                "the tile borders add more vertices than thinning leaves out; a larger --tile \
                 (or --max-error) thins more"
            } else {
                "the breaklines add more vertices than thinning leaves out"
            }
        );
    }
    Ok(())
}
