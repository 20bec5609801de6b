//! `sweeptin refine`: a TIN (a mesh file, or points triangulated as `tin` does) refined into a
//! quality mesh: every angle at least --min-angle, every area at most --max-area.

use super::input::InputArgs;
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweeptin::breaklines::{CleanOptions, read_files};
use sweeptin::output::{MeshFormat, MeshMeta, create_mesh_sink};
use sweeptin::refine::{RefineOptions, RefineStats, refine};
use sweeptin::sink::MemoryMesh;

/// Arguments of `sweeptin refine`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
How: Ruppert's Delaunay refinement with Üngör's off-centres, as Triangle's -q (Shewchuk). The
domain is the input TIN's triangles: its outline and holes (--trim-boundary, --boundary, --holes,
--max-edge trimming of point inputs) stay exactly, and so do the breaklines. Steiner points go to
the circumcentre or off-centre of a bad triangle (those with the shortest edge first, in
Triangle's order), or to the middle of a breakline or boundary segment they would encroach (a
power of two from the end where two segments meet). A point inside takes the height of the input
TIN at its position; a point on a segment the height of the segment's line. Exact orientation and
in-circle tests keep the mesh constrained Delaunay; the same input gives the same mesh.

Small angles: an angle between two input segments below --min-angle cannot be fixed; near input
angles below 60° a few triangles are left under the bound (as Triangle does), and counted as
\"skinny\" in the summary. A bound up to 20.7° is proved to finish; up to ~33.8° finishes in
practice.

Memory: the input TIN and the refined mesh are held in memory, about 750 bytes an input vertex
at the peak (ARSO ground, 1.9 M vertices refined to 3.2 M at 25°: 1.4 GB): refine tile-sized
inputs, or `tin` first with trimming. Under an address-space limit (ulimit -v, a batch job's
h_vmem), each step checks for room first and fails with exit 4, writing nothing. --max-area
implies an output size (at least the domain's area / max-area triangles): it is checked against
--mem and --max-steiner before refining, and refused (exit 2) with the smallest bound that fits.

Examples:
  sweeptin refine ground.ply --min-angle 30 -o mesh.2dm
  sweeptin refine tile.laz --class 2 --breaklines banks.geojson --boundary reach.geojson \\
      --min-angle 28 --max-area 25 -o reach.2dm")]
pub struct Args {
    /// Input: one mesh (.ply, as `sweeptin tin` writes it, or any triangle PLY; a .stin streaming
    /// mesh), or points and their options exactly as for `sweeptin tin` (triangulated first).
    #[command(flatten)]
    pub input: InputArgs,
    /// Output mesh: .ply, .obj, .xml (LandXML), .stin or .2dm (SMS 2DM, for HEC-RAS, TELEMAC,
    /// TUFLOW and QGIS).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output format, when the extension does not say it.
    #[arg(long, value_enum)]
    pub format: Option<MeshFormat>,
    /// Coordinate reference system recorded in the output (`EPSG:xxxx` or WKT); default: the
    /// input's, when LAS/LAZ files carry one.
    #[arg(long)]
    pub crs: Option<String>,
    /// Keep only the triangles inside these polygons (point inputs); the rings become
    /// breaklines. Same as `--trim-boundary`.
    #[arg(
        long = "boundary",
        id = "boundary_polygon",
        value_name = "FILE",
        conflicts_with = "trim_boundary"
    )]
    pub boundary_polygon: Option<PathBuf>,
    /// Smallest angle of every triangle, in degrees (Triangle's -q; at most 34).
    #[arg(long, value_name = "DEGREES", default_value_t = 30.0)]
    pub min_angle: f64,
    /// Largest triangle area, in the data's xy units squared.
    #[arg(long, value_name = "AREA")]
    pub max_area: Option<f64>,
    /// Give up (exit 3, nothing written) past this many Steiner points; default: 20 per input
    /// vertex plus one million.
    #[arg(long, value_name = "N")]
    pub max_steiner: Option<u64>,
}

/// The `--json` summary.
#[derive(serde::Serialize)]
struct Summary<'a> {
    inputs: &'a [PathBuf],
    output: &'a Path,
    options: RefineOptions,
    stats: RefineStats,
    bytes: u64,
    read_seconds: f64,
    refine_seconds: f64,
    total_seconds: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let options = RefineOptions {
        min_angle: args.min_angle,
        max_area: args.max_area,
        max_steiner: args.max_steiner,
        mem: Some(args.input.mem.0),
    };
    options.validate()?;
    let boundary: Vec<&Path> = args.boundary_polygon.iter().map(|p| p.as_path()).collect();
    args.input
        .check_outputs(&[("-o", &args.output)], &boundary)?;
    let mut input = args.input.input();
    if let Some(b) = &args.boundary_polygon {
        input.lines.boundary = Some(b.clone());
    }
    let ply = args.input.inputs.len() == 1
        && args.input.inputs[0]
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    let lines_opts = &input.lines;
    if ply && (lines_opts.boundary.is_some() || lines_opts.holes.is_some()) {
        return Err(sweeptin::Error::Options(
            "--boundary, --trim-boundary and --holes trim point inputs; a mesh's domain is its \
             triangles (trim it with `sweeptin tin`, or give the points)"
                .into(),
        )
        .into());
    }
    // Every constraint the TIN was made with: breaklines, boundary and hole rings.
    let mut line_files = lines_opts.breaklines.clone();
    line_files.extend(lines_opts.boundary.iter().cloned());
    line_files.extend(lines_opts.holes.iter().cloned());
    let mut crs = args.crs.clone();
    // Open the output first: a bad output path fails before any heavy work.
    let (vertices, triangles, mut sink, kind) = if ply {
        let meta = meta(&args, crs.clone());
        let sink = create_mesh_sink(&args.output, args.format, &meta)?;
        let kind = sweeptin::input::read_ply_kind(&args.input.inputs[0])?;
        let (v, t) = sweeptin::input::read_ply(&args.input.inputs[0])?;
        (v, t, sink, kind)
    } else {
        let config = args.input.config(input.clone())?;
        if crs.is_none() {
            crs = config.input_crs()?;
        }
        let meta = meta(&args, crs.clone());
        let sink = create_mesh_sink(&args.output, args.format, &meta)?;
        let mut collect = MemoryMesh::default();
        let run = sweeptin::pipeline::run(&config, Some(&mut collect), &mut [])
            .map_err(|e| super::input::run_error(e, &args.input.inputs))?;
        super::input::warn(&run);
        (collect.vertices, collect.triangles, sink, collect.kind)
    };
    let lines: Vec<[[f64; 3]; 2]> = if line_files.is_empty() {
        Vec::new()
    } else {
        let g = read_files(&line_files)?.clean(&CleanOptions::default())?;
        g.segments
            .iter()
            .map(|s| s.map(|v| g.vertices[v as usize]))
            .collect()
    };
    let read_s = start.elapsed().as_secs_f64();
    let name = args.input.inputs[0].display().to_string();
    let refined = refine(&vertices, &triangles, &lines, &options)
        .with_context(|| format!("cannot refine the TIN of {name}"))?;
    let refine_s = start.elapsed().as_secs_f64() - read_s;
    drop((vertices, triangles));
    sink.declare(refined.kind(kind))?;
    for &p in &refined.vertices {
        sink.vertex(p)?;
    }
    for t in &refined.triangles {
        sink.triangle(t.map(u64::from))?;
    }
    let written = sink.finish()?;
    let s = refined.stats;
    if args.input.json {
        let summary = Summary {
            inputs: &args.input.inputs,
            output: &args.output,
            options,
            stats: s,
            bytes: written.bytes,
            read_seconds: read_s,
            refine_seconds: refine_s,
            total_seconds: start.elapsed().as_secs_f64(),
        };
        println!("{}", serde_json::to_string(&summary)?);
        return Ok(());
    }
    eprintln!(
        "sweeptin: {name}: {} vertices, {} triangles (smallest angle {:.2}°) -> {}: {} vertices \
         ({} on segments, {} inside), {} triangles, smallest angle {:.2}°{} in {:.2} s",
        s.input_vertices,
        s.input_triangles,
        s.input_min_angle,
        args.output.display(),
        s.vertices,
        s.segment_points,
        s.free_points,
        s.triangles,
        s.min_angle,
        if s.skinny > 0 {
            format!(
                " ({} triangles under {}° at small input angles)",
                s.skinny, options.min_angle
            )
        } else {
            String::new()
        },
        start.elapsed().as_secs_f64()
    );
    if s.breakline_segments_outside > 0 {
        eprintln!(
            "sweeptin: warning: {} breakline segments lie outside the mesh and were left out",
            s.breakline_segments_outside
        );
    }
    Ok(())
}

fn meta(args: &Args, crs: Option<String>) -> MeshMeta {
    MeshMeta {
        crs,
        comments: vec![format!(
            "sweeptin {} quality mesh (min angle {} degrees{}) of {}",
            env!("CARGO_PKG_VERSION"),
            args.min_angle,
            args.max_area
                .map_or(String::new(), |a| format!(", max area {a}")),
            args.input
                .inputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )],
    }
}
