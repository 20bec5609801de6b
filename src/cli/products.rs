//! `sweeptin products`: several terrain products from one pass over the triangle stream; and the
//! option groups and sink builders the single-product commands share.

use super::input::{ProductInput, check_output, run_products};
use anyhow::{Context, bail};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweeptin::input::las::BBox;
use sweeptin::output::raster::RasterFormat;
use sweeptin::products::boundary::Boundary;
use sweeptin::products::contours::{ContourOptions, ContourSink};
use sweeptin::products::dem::{DemExtent, DemOptions, DemSink};
use sweeptin::products::hillshade::{HillshadeOptions, hillshade};
use sweeptin::products::profile::ProfileSink;
use sweeptin::products::sample::SampleSink;
use sweeptin::products::volume::VolumeSink;
use sweeptin::sink::TriangleSink;

/// DEM options.
#[derive(clap::Args, Debug, Clone)]
pub struct DemArgs {
    /// Cell size; cell centres fall on whole multiples of it.
    #[arg(long, default_value_t = 1.0, value_name = "SIZE")]
    pub cell: f64,
    /// With --bbox: round the box's sides outwards to multiples of the cell size (otherwise they
    /// must be multiples).
    #[arg(long, requires = "bbox")]
    pub snap: bool,
    /// With --bbox: also read the points up to this distance outside the box, so that the
    /// triangles near the raster's edge are those of a run over all the data (tiles then mosaic
    /// exactly). Default: 0, only the points inside the box.
    #[arg(long, requires = "bbox", value_name = "DISTANCE")]
    pub buffer: Option<f64>,
    /// Value of cells outside the TIN.
    #[arg(long, default_value_t = -9999.0, allow_hyphen_values = true)]
    pub nodata: f32,
    /// Raster format, when the extension does not say it.
    #[arg(long, value_enum)]
    pub raster_format: Option<RasterFormat>,
}

impl DemArgs {
    /// The box of points to read: `bbox` grown by `--buffer`.
    pub fn read_box(&self, bbox: Option<BBox>) -> anyhow::Result<Option<BBox>> {
        let (Some(b), Some(d)) = (bbox, self.buffer) else {
            return Ok(None);
        };
        if !(d.is_finite() && d >= 0.0) {
            bail!("--buffer must be a distance >= 0, not {d}");
        }
        let [x0, y0, x1, y1] = b.corners();
        Ok(BBox::new(x0 - d, y0 - d, x1 + d, y1 + d))
    }

    /// A DEM sink writing to `path`, over `bbox` (the `--bbox` of the input) when given.
    pub fn sink(&self, path: &Path, bbox: Option<BBox>) -> anyhow::Result<Box<dyn TriangleSink>> {
        check_output(path)?;
        let extent = match bbox {
            Some(b) => DemExtent::BBox {
                bbox: b.corners(),
                snap: self.snap,
            },
            None => DemExtent::Auto,
        };
        Ok(Box::new(DemSink::new(
            path,
            DemOptions {
                cell: self.cell,
                extent,
                nodata: self.nodata,
                format: self.raster_format,
            },
        )?))
    }
}

/// Contour options.
#[derive(clap::Args, Debug, Clone)]
pub struct ContourArgs {
    /// Distance between contour levels.
    #[arg(long, default_value_t = 1.0, value_name = "DZ")]
    pub interval: f64,
    /// A level through which the others are counted (levels are BASE + k × INTERVAL).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub base: f64,
}

impl ContourArgs {
    /// A contour sink writing to `path`.
    pub fn sink(&self, path: &Path) -> anyhow::Result<Box<dyn TriangleSink>> {
        check_output(path)?;
        Ok(Box::new(ContourSink::new(
            path,
            ContourOptions {
                interval: self.interval,
                base: self.base,
                ..ContourOptions::default()
            },
        )?))
    }
}

/// Reads a boundary polygon file.
pub fn read_boundary(path: &Path) -> anyhow::Result<Boundary> {
    let polys = sweeptin::input::geojson::read_polygons(path)?;
    Boundary::new(&polys).map_err(|m| anyhow::anyhow!("{}: {m}", path.display()))
}

/// Arguments of `sweeptin products`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub input: ProductInput,
    /// Write a DEM raster (.tif or .asc), covering --bbox when given (the cells whose centres
    /// lie in [XMIN, XMAX) × (YMIN, YMAX]).
    #[arg(long, value_name = "RASTER")]
    pub dem: Option<PathBuf>,
    #[command(flatten)]
    pub dem_options: DemArgs,
    /// Write a hillshade PNG of the DEM (needs --dem with a .tif).
    #[arg(long, value_name = "PNG", requires = "dem")]
    pub hillshade: Option<PathBuf>,
    /// Write contour lines (GeoJSON).
    #[arg(long, value_name = "GEOJSON")]
    pub contours: Option<PathBuf>,
    #[command(flatten)]
    pub contour_options: ContourArgs,
    /// Compute cut and fill against the plane z = Z.
    #[arg(long, value_name = "Z", allow_hyphen_values = true)]
    pub volume_plane: Option<f64>,
    /// Restrict the volume to this polygon (GeoJSON Polygon/MultiPolygon).
    #[arg(long, value_name = "GEOJSON", requires = "volume_plane")]
    pub boundary: Option<PathBuf>,
    /// Heights at these query points (x, y first on each line) …
    #[arg(long, value_name = "CSV", requires = "sample_out")]
    pub sample_points: Option<PathBuf>,
    /// … written here.
    #[arg(long, value_name = "CSV", requires = "sample_points")]
    pub sample_out: Option<PathBuf>,
    /// A profile along the lines of this GeoJSON file …
    #[arg(long, value_name = "GEOJSON", requires = "profile_out")]
    pub profile_line: Option<PathBuf>,
    /// … written here (CSV).
    #[arg(long, value_name = "CSV", requires = "profile_line")]
    pub profile_out: Option<PathBuf>,
    /// Also write the TIN itself (.ply, .obj, .xml or .stin).
    #[arg(long, value_name = "MESH")]
    pub mesh: Option<PathBuf>,
}

/// One line per product on standard error.
pub fn report(run: &sweeptin::pipeline::RunSummary, summary: &Value, seconds: f64) {
    let peak = run.peak_rss_bytes.map_or("?".to_string(), |b| {
        format!("{:.0} MiB", b as f64 / 1048576.0)
    });
    eprintln!(
        "sweeptin: {} points ({} duplicates merged), {} triangles in {seconds:.2} s \
         (peak memory {peak})",
        run.points_read, run.duplicates, run.triangles
    );
    let Some(m) = summary.as_object() else {
        return;
    };
    for (name, v) in m {
        let path = v.get("path").and_then(Value::as_str).unwrap_or("");
        let line = match name.as_str() {
            "dem" => format!(
                "{} × {} cells of {}, {} with data",
                v["cols"], v["rows"], v["cell"], v["cells_with_data"]
            ),
            "contours" => format!("{} lines ({} closed rings)", v["features"], v["rings"]),
            "volume" => format!(
                "cut {} fill {} (areas {} / {}, covered {})",
                v["cut_volume"], v["fill_volume"], v["cut_area"], v["fill_area"], v["area"]
            ),
            "sample" => format!(
                "{} of {} points inside the TIN",
                v["answered"], v["queries"]
            ),
            "profile" => format!("{} points", v["points"]),
            "trimmed_triangles" => {
                if v.as_u64().unwrap_or(0) > 0 {
                    format!("{v} triangles left out by --max-edge")
                } else {
                    continue;
                }
            }
            _ => v.to_string(),
        };
        if path.is_empty() {
            eprintln!("  {name}: {line}");
        } else {
            eprintln!("  {name} -> {path}: {line}");
        }
    }
}

/// Refuses a hillshade of a DEM that is not a GeoTIFF, before any work.
pub fn check_hillshade(dem: &Path, format: Option<RasterFormat>) -> anyhow::Result<()> {
    let f = format.or_else(|| RasterFormat::from_extension(dem));
    if f != Some(RasterFormat::GeoTiff) {
        bail!(
            "--hillshade needs a GeoTIFF DEM (.tif), not {}",
            dem.display()
        );
    }
    Ok(())
}

/// Shades `dem` into `png` and reports it.
pub fn shade(dem: &Path, png: &Path, o: &HillshadeOptions) -> anyhow::Result<Value> {
    let s = hillshade(dem, png, o).with_context(|| format!("cannot shade {}", dem.display()))?;
    Ok(serde_json::to_value(s)?)
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let mut sinks: Vec<(String, Box<dyn TriangleSink>)> = Vec::new();
    let bbox = args.input.args.filter.bbox;
    if let Some(p) = &args.dem {
        sinks.push(("dem".into(), args.dem_options.sink(p, bbox)?));
        if let Some(png) = &args.hillshade {
            check_output(png)?;
            check_hillshade(p, args.dem_options.raster_format)?;
        }
    }
    if let Some(p) = &args.contours {
        sinks.push(("contours".into(), args.contour_options.sink(p)?));
    }
    if let Some(z) = args.volume_plane {
        let boundary = args.boundary.as_deref().map(read_boundary).transpose()?;
        sinks.push(("volume".into(), Box::new(VolumeSink::new(z, boundary))));
    }
    if let (Some(q), Some(o)) = (&args.sample_points, &args.sample_out) {
        check_output(o)?;
        sinks.push(("sample".into(), Box::new(SampleSink::new(q, o)?)));
    }
    if let (Some(l), Some(o)) = (&args.profile_line, &args.profile_out) {
        check_output(o)?;
        let lines = sweeptin::input::geojson::read_lines(l)?;
        sinks.push(("profile".into(), Box::new(ProfileSink::new(lines, o)?)));
    }
    if sinks.is_empty() && args.mesh.is_none() {
        bail!(
            "nothing to do: give at least one of --dem, --contours, --volume-plane, \
             --sample-points, --profile-line, --mesh"
        );
    }
    let read_box = if args.dem.is_some() {
        args.dem_options.read_box(bbox)?
    } else {
        None
    };
    let input = args.input.input(read_box)?;
    let crs_text = match args.input.crs()? {
        Some(c) => c.definition(),
        None => sweeptin::pipeline::input_crs(&input)?,
    };
    let mut mesh = match &args.mesh {
        Some(p) => {
            let meta = sweeptin::output::MeshMeta {
                crs: crs_text,
                comments: vec!["sweeptin products".into()],
            };
            Some(sweeptin::output::create_mesh_sink(p, None, &meta)?)
        }
        None => None,
    };
    let mesh_ref: Option<&mut (dyn sweeptin::sink::MeshSink + Send)> = match mesh.as_mut() {
        Some(m) => Some(&mut **m),
        None => None,
    };
    let (run, mut summary) = run_products(&args.input, &input, mesh_ref, sinks)?;
    if let Some(mut m) = mesh {
        let s = m.finish()?;
        summary["mesh"] = serde_json::json!({
            "path": args.mesh, "vertices": s.vertices, "triangles": s.triangles, "bytes": s.bytes
        });
    }
    if let (Some(png), Some(dem)) = (&args.hillshade, &args.dem) {
        summary["hillshade"] = shade(dem, png, &HillshadeOptions::default())?;
        summary["hillshade"]["path"] = serde_json::json!(png);
    }
    finish_report(&args.input, &run, summary, start)
}

/// Prints the one-line-per-product report, or with `--json` the whole summary on stdout.
pub fn finish_report(
    input: &ProductInput,
    run: &sweeptin::pipeline::RunSummary,
    mut summary: Value,
    start: Instant,
) -> anyhow::Result<()> {
    if input.args.json {
        summary["run"] = serde_json::to_value(run)?;
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        report(run, &summary, start.elapsed().as_secs_f64());
    }
    Ok(())
}
