//! `sweeptin tin`: points in, Delaunay TIN out.

use super::input::InputArgs;
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::fmt::count;
use sweeptin::output::{MeshFormat, MeshMeta, create_mesh_sink};

/// Arguments of `sweeptin tin`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output mesh: .ply (binary PLY), .obj (Wavefront OBJ), .xml (LandXML 1.2 surface for
    /// civil-design software) or .stin (streaming mesh, for the terrain-product commands).
    /// It appears only when complete; a symbolic link's target is replaced (keeping its
    /// permissions); `-`, a FIFO or a device (with --format) is written as a stream.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output format, when the extension does not say it.
    #[arg(long, value_enum)]
    pub format: Option<MeshFormat>,
    /// Coordinate reference system recorded in the output (`EPSG:xxxx` or WKT); default: the
    /// input's, when LAS/LAZ files carry one.
    #[arg(long)]
    pub crs: Option<String>,
    /// Keep only the triangles inside these polygons (survey limit); the rings become
    /// breaklines. Same as `--trim-boundary`.
    #[arg(
        long = "boundary",
        id = "boundary_polygon",
        value_name = "FILE",
        conflicts_with = "trim_boundary"
    )]
    pub boundary_polygon: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let boundary: Vec<&std::path::Path> =
        args.boundary_polygon.iter().map(|p| p.as_path()).collect();
    args.input
        .check_outputs(&[("-o", &args.output)], &boundary)?;
    let mut input = args.input.input();
    if let Some(b) = &args.boundary_polygon {
        input.lines.boundary = Some(b.clone());
    }
    // Checked as the products check it (`tin --crs nonsense` was written as it was).
    let given = args
        .crs
        .as_deref()
        .map(super::input::parse_crs)
        .transpose()?;
    let config = args.input.config(input)?.with_crs(given);
    let crs = match &args.crs {
        Some(c) => Some(c.clone()),
        None => config.input_crs()?,
    };
    let meta = MeshMeta {
        crs,
        comments: vec![format!(
            "sweeptin {} Delaunay TIN of {}",
            env!("CARGO_PKG_VERSION"),
            args.input
                .inputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )],
    };
    // Open the output first: a bad output path fails before any heavy work, and the temporary
    // file is removed on every error below.
    let mut sink = create_mesh_sink(&args.output, args.format, &meta)?;
    let mut summary = sweeptin::pipeline::run(&config, Some(&mut *sink), &mut [])
        .map_err(|e| super::input::run_error(e, &args.input.inputs))?;
    let fin = Instant::now();
    let written = sink.finish()?;
    summary.seconds.finish += fin.elapsed().as_secs_f64();
    summary.peak_rss_bytes = sweeptin::pipeline::peak_rss();
    super::input::warn(&summary);
    super::input::warn_clipped(&summary);
    if args.input.json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        let format = args
            .format
            .or_else(|| MeshFormat::from_extension(&args.output))
            .map_or("mesh", MeshFormat::name);
        eprintln!(
            "sweeptin: {} points ({} duplicates merged) -> {}: {} vertices, {} triangles, {} {} \
             in {:.2} s (peak memory {})",
            count(summary.points_read),
            count(summary.duplicates),
            args.output.display(),
            count(written.vertices),
            count(written.triangles),
            sweeptin::human_bytes(written.bytes),
            format,
            start.elapsed().as_secs_f64(),
            summary
                .peak_rss_bytes
                .map_or("?".into(), sweeptin::human_bytes),
        );
    }
    Ok(())
}
