//! `sweeptin products`: several terrain products from one pass over the triangle stream; and the
//! option groups and sink builders the single-product commands share.

use super::input::{ProductInput, check_output, run_products};
use anyhow::{Context, bail};
use serde_json::{Map, Value, json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweeptin::fmt::{Decimals, Figure, count as thousands};
use sweeptin::input::las::BBox;
use sweeptin::output::raster::{Compression, Predictor, RasterFormat, RasterOptions};
use sweeptin::pipeline::RunSummary;
use sweeptin::products::boundary::Boundary;
use sweeptin::products::contours::{ContourOptions, ContourSink};
use sweeptin::products::dem::{DemOptions, DemSink};
use sweeptin::products::hillshade::{HillshadeOptions, HillshadeSummary, hillshade};
use sweeptin::products::profile::ProfileSink;
use sweeptin::products::sample::SampleSink;
use sweeptin::products::volume::VolumeSink;
use sweeptin::raster::{Align, GridExtent, GridPlan};
use sweeptin::sink::{FanoutSummary, MeshSummary, ProductSummary, TriangleSink};

/// Compression options of GeoTIFF outputs (DEM, mosaic, hillshade).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct TiffArgs {
    /// GeoTIFF compression (default: deflate for --format cog, none for a plain GeoTIFF).
    #[arg(long, value_enum, value_name = "METHOD")]
    pub compress: Option<Compression>,
    /// Predictor applied before compression (GDAL's PREDICTOR=1|2|3; default: float for a
    /// compressed DEM, horizontal for a compressed hillshade).
    #[arg(long, value_enum, value_name = "KIND")]
    pub predictor: Option<Predictor>,
    /// Write BigTIFF even below 4 GiB (chosen by itself beyond).
    #[arg(long)]
    pub bigtiff: bool,
}

/// Raster output options: format and compression.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct RasterArgs {
    /// Raster format, when the extension does not say it: `tif` (GeoTIFF), `cog` (Cloud
    /// Optimized GeoTIFF: tiled 512 × 512, compressed, internal overviews; written in bounded
    /// memory), `asc` (ESRI ASCII grid, with a .prj beside it when the CRS is known as WKT).
    #[arg(
        long = "format",
        visible_alias = "raster-format",
        value_enum,
        value_name = "FORMAT"
    )]
    pub format: Option<RasterFormat>,
    #[command(flatten)]
    pub tiff: TiffArgs,
}

impl RasterArgs {
    /// The library's options.
    pub fn options(&self) -> RasterOptions {
        RasterOptions {
            format: self.format,
            compress: self.tiff.compress,
            predictor: self.tiff.predictor,
            bigtiff: self.tiff.bigtiff,
        }
    }
}

/// DEM options.
#[derive(clap::Args, Debug, Clone)]
pub struct DemArgs {
    /// Cell size; cell edges (or centres, with --align centres) fall on whole multiples of it.
    #[arg(long, default_value_t = GridPlan::default().cell(), value_name = "SIZE")]
    pub cell: f64,
    /// Where the cells lie: `edges` puts cell edges on multiples of --cell (GDAL -tap,
    /// LAStools -use_tile_bb, lasR: a 1 km tile at 1 m gives 1000 × 1000 cells); `centres` puts
    /// cell centres there (IGN's LiDAR HD DTM lattice; a 1 km tile gives 1001 × 1001 cells).
    #[arg(long, value_enum, default_value_t = Align::Edges)]
    pub align: Align,
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
    #[arg(long, default_value_t = DemOptions::default().nodata, allow_hyphen_values = true)]
    pub nodata: f32,
    #[command(flatten)]
    pub raster: RasterArgs,
    /// Refuse a raster of more cells than this (before reading anything when the extent is
    /// known from --bbox or LAS/LAZ headers). The raster's rows in memory also count against
    /// --mem (a quarter of it).
    #[arg(long, value_name = "N", default_value_t = sweeptin::raster::DEFAULT_MAX_CELLS,
          value_parser = parse_count)]
    pub max_cells: u64,
    /// Set by `sweeptin run`: the raster covers this box (a plan's tile), whatever is read.
    #[arg(skip)]
    pub grid_bbox: Option<[f64; 4]>,
}

/// Parses a count: `4294967296`, `4e9`, `4G` (decimal multiples k, M, G, T).
fn parse_count(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, mult) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 1e3),
        Some('M') => (&t[..t.len() - 1], 1e6),
        Some('G') => (&t[..t.len() - 1], 1e9),
        Some('T') => (&t[..t.len() - 1], 1e12),
        _ => (t, 1.0),
    };
    match num.parse::<f64>() {
        Ok(v) if v.is_finite() && v * mult >= 1.0 && v * mult <= 1.8e19 => Ok((v * mult) as u64),
        _ => Err(format!("'{s}' is not a count like 100000000, 1e8 or 100M")),
    }
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

    /// A DEM sink writing to `path`, over `bbox` (the `--bbox` of the input) when given, holding
    /// at most a quarter of `mem` in memory; its size is checked against `--max-cells` and the
    /// memory now when the extent is known (`bbox`, or the data's `bounds` from headers).
    pub fn sink(
        &self,
        path: &Path,
        bbox: Option<BBox>,
        mem: u64,
        bounds: Option<[f64; 4]>,
    ) -> anyhow::Result<Box<dyn TriangleSink>> {
        check_output(path)?;
        let extent = match (self.grid_bbox, bbox) {
            (Some(b), _) => GridExtent::BBox {
                bbox: b,
                snap: false,
            },
            (None, Some(b)) => GridExtent::BBox {
                bbox: b.corners(),
                snap: self.snap,
            },
            (None, None) => GridExtent::Auto,
        };
        let sink = DemSink::new(
            path,
            DemOptions {
                grid: GridPlan::new(self.cell, extent, self.align)?.limit(self.max_cells)?,
                nodata: self.nodata,
                output: self.raster.options(),
                memory: mem / 4,
            },
        )?;
        // A box of no area holds points on one line (or one point): the run reads them and
        // says so (exit 3), where a grid of no cell would blame the options.
        let area = |b: &[f64; 4]| b[2] > b[0] && b[3] > b[1];
        if let Some(b) = bounds.filter(|b| extent == GridExtent::Auto && area(b)) {
            // A grid too large may come from headers that claim too much; its memory, from
            // --mem.
            sink.check_grid(b).with_context(|| {
                format!(
                    "no DEM over x {} .. {}, y {} .. {} (the union of the inputs' usable header \
                     boxes; no point is read before this check): if the points cover less, \
                     repair the headers (e.g. lasinfo -repair_bb) or give --bbox",
                    b[0], b[2], b[1], b[3]
                )
            })?;
            sink.check_size(b)?;
        } else if extent != GridExtent::Auto {
            sink.check_size([0.0; 4])?;
        }
        Ok(Box::new(sink))
    }
}

/// Contour options.
#[derive(clap::Args, Debug, Clone)]
pub struct ContourArgs {
    /// Distance between contour levels.
    #[arg(long, default_value_t = ContourOptions::default().interval, value_name = "DZ")]
    pub interval: f64,
    /// A level through which the others are counted (levels are BASE + k × INTERVAL).
    #[arg(long, default_value_t = ContourOptions::default().base, allow_hyphen_values = true)]
    pub base: f64,
    /// Decimals of the written coordinates (default: those of the LAS/LAZ scale, 2 for 0.01;
    /// 3 for other inputs).
    #[arg(long, value_name = "N",
          value_parser = clap::value_parser!(u32).range(0..=i64::from(sweeptin::output::lines::MAX_DECIMALS)))]
    pub precision: Option<u32>,
    /// Leave out lines, closed rings included, shorter than this (map units); the summary says
    /// how many.
    #[arg(long, value_name = "LENGTH", default_value_t = 0.0)]
    pub min_length: f64,
    /// Set by `sweeptin run`: open lines keep their end edges for the merge.
    #[arg(skip)]
    pub edges: bool,
}

impl ContourArgs {
    /// A contour sink writing to `path`, holding its open lines' points within an eighth of
    /// `mem` ([`ContourOptions::within`]).
    /// `inputs` give the default `--precision`.
    pub fn sink(
        &self,
        path: &Path,
        mem: u64,
        inputs: &[PathBuf],
    ) -> anyhow::Result<Box<dyn TriangleSink>> {
        check_output(path)?;
        let decimals = self
            .precision
            .unwrap_or_else(|| sweeptin::products::contours::default_decimals(inputs));
        Ok(Box::new(ContourSink::new(
            path,
            ContourOptions {
                interval: self.interval,
                base: self.base,
                edges: self.edges,
                decimals: Some(decimals),
                min_length: self.min_length,
                ..ContourOptions::default()
            }
            .within(mem),
        )?))
    }
}

/// Reads a boundary polygon file.
pub fn read_boundary(path: &Path) -> anyhow::Result<Boundary> {
    Ok(Boundary::read(path)?)
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
    /// Write contour lines (GeoJSON, or GeoPackage for .gpkg).
    #[arg(long, value_name = "GEOJSON|GPKG")]
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

/// What a product command made: the sinks' summaries by name, and the mesh and hillshade
/// written beside them.
pub struct Report {
    pub products: FanoutSummary,
    pub mesh: Option<(PathBuf, MeshSummary)>,
    pub hillshade: Option<(PathBuf, HillshadeSummary)>,
}

impl Report {
    /// The products of one pass, without mesh or hillshade yet.
    pub fn new(products: FanoutSummary) -> Report {
        Report {
            products,
            mesh: None,
            hillshade: None,
        }
    }

    /// The `--json` object: each product under its name, `mesh`, `hillshade`,
    /// `trimmed_triangles` and the `run`, keys in alphabetical order.
    fn to_json(&self, run: &RunSummary) -> anyhow::Result<Value> {
        let mut m = Map::new();
        for (name, s) in &self.products.0 {
            m.insert(name.clone(), serde_json::to_value(s)?);
        }
        m.insert("trimmed_triangles".into(), json!(trimmed(run)));
        if let Some((path, s)) = &self.mesh {
            m.insert(
                "mesh".into(),
                json!({
                    "path": path, "vertices": s.vertices, "triangles": s.triangles, "bytes": s.bytes
                }),
            );
        }
        if let Some((path, s)) = &self.hillshade {
            let mut v = serde_json::to_value(s)?;
            v["path"] = json!(path);
            m.insert("hillshade".into(), v);
        }
        m.insert("run".into(), serde_json::to_value(run)?);
        Ok(Value::Object(m))
    }

    /// One line per product on standard error, by name.
    fn print(&self, run: &RunSummary, seconds: f64) {
        let peak = run.peak_rss_bytes.map_or("?".to_string(), |b| {
            format!("{:.0} MiB", b as f64 / 1048576.0)
        });
        eprintln!(
            "sweeptin: {} points ({} duplicates merged), {} triangles in {seconds:.2} s \
             (peak memory {peak})",
            thousands(run.points_read),
            thousands(run.duplicates),
            thousands(run.triangles)
        );
        let mut lines: BTreeMap<&str, (Option<&Path>, String)> = BTreeMap::new();
        for (name, s) in &self.products.0 {
            lines.insert(name, describe(s));
        }
        if let Some((path, s)) = &self.mesh {
            let line = format!(
                "{} vertices, {} triangles",
                thousands(s.vertices),
                thousands(s.triangles)
            );
            lines.insert("mesh", (Some(path), line));
        }
        if let Some((path, s)) = &self.hillshade {
            let line = super::hillshade::describe(s);
            lines.insert("hillshade", (Some(path), line));
        }
        let trimmed = trimmed(run);
        if trimmed > 0 {
            let line = format!("{} triangles left out by trimming", thousands(trimmed));
            lines.insert("trimmed_triangles", (None, line));
        }
        for (name, (path, line)) in lines {
            match path {
                Some(p) => eprintln!("  {name} -> {}: {line}", p.display()),
                None => eprintln!("  {name}: {line}"),
            }
        }
    }
}

/// Triangles that trimming (`--trim-boundary`, `--holes`, `--max-edge`) kept from the products.
fn trimmed(run: &RunSummary) -> u64 {
    run.breaklines.as_ref().map_or(0, |b| b.trimmed_triangles)
}

/// The file a product wrote and a line about it.
fn describe(s: &ProductSummary) -> (Option<&Path>, String) {
    match s {
        ProductSummary::Dem(d) => (
            Some(&d.path),
            format!(
                "{} × {} cells of {}, {} with data",
                thousands(u64::from(d.cols)),
                thousands(u64::from(d.rows)),
                Figure(d.cell),
                thousands(d.cells_with_data)
            ),
        ),
        ProductSummary::Contours(c) => {
            let mut line = format!(
                "{} lines ({} closed rings), {}",
                thousands(c.features),
                thousands(c.rings),
                sweeptin::human_bytes(c.bytes)
            );
            if c.short_dropped > 0 {
                line.push_str(&format!(
                    "; {} shorter than --min-length {} left out",
                    thousands(c.short_dropped),
                    Figure(c.min_length)
                ));
            }
            (Some(&c.path), line)
        }
        ProductSummary::Volume(v) => {
            let t = &v.totals;
            let d = |v: f64| Decimals(v, 3);
            let line = format!(
                "cut {}, fill {}, net {} (cubic units of the data; cut area {}, fill area {}, \
                 covered {} square units)",
                d(t.cut_volume),
                d(t.fill_volume),
                d(t.net_volume),
                d(t.cut_area),
                d(t.fill_area),
                d(t.area)
            );
            (None, line)
        }
        ProductSummary::Sample(s) => (
            Some(&s.path),
            format!(
                "{} of {} points inside the TIN",
                thousands(s.answered),
                thousands(s.queries)
            ),
        ),
        ProductSummary::Profile(p) => (Some(&p.path), format!("{} points", thousands(p.points))),
        ProductSummary::None | ProductSummary::SurfaceStore(_) | ProductSummary::Fanout(_) => {
            (None, "done".to_string())
        }
    }
}

/// Refuses a hillshade of a DEM that is not a GeoTIFF, before any work.
pub fn check_hillshade(
    dem: &Path,
    format: Option<RasterFormat>,
    shade: &Path,
) -> anyhow::Result<()> {
    let f = format.or_else(|| RasterFormat::from_extension(dem));
    if !matches!(f, Some(RasterFormat::GeoTiff | RasterFormat::Cog)) {
        bail!(
            "--hillshade needs a GeoTIFF DEM (.tif), not {}",
            dem.display()
        );
    }
    // Found before the DEM is made (`--hillshade h.pgw` failed after writing it).
    let ext = shade
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("png" | "tif" | "tiff")) {
        bail!(
            "--hillshade {}: a hillshade is written as PNG (.png) or GeoTIFF (.tif)",
            shade.display()
        );
    }
    Ok(())
}

/// Shades `dem` into `png`.
pub fn shade(dem: &Path, png: &Path) -> anyhow::Result<(PathBuf, HillshadeSummary)> {
    let s = hillshade(dem, png, &HillshadeOptions::default())
        .with_context(|| format!("cannot shade {}", dem.display()))?;
    // The run has warned of a missing CRS already.
    super::hillshade::warn(dem, &s, false);
    Ok((png.to_path_buf(), s))
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    if let (Some(d), Some(png)) = (&args.dem, &args.hillshade) {
        check_hillshade(d, args.dem_options.raster.format, png)?;
    }
    let mut outputs: Vec<(&str, &Path)> = Vec::new();
    for (flag, p) in [
        ("--dem", &args.dem),
        ("--hillshade", &args.hillshade),
        ("--contours", &args.contours),
        ("--sample-out", &args.sample_out),
        ("--profile-out", &args.profile_out),
        ("--mesh", &args.mesh),
    ] {
        if let Some(p) = p {
            outputs.push((flag, p));
        }
    }
    let prj = args
        .dem
        .as_deref()
        .and_then(|d| sweeptin::output::ascii_grid_prj(d, args.dem_options.raster.format));
    if let Some(p) = &prj {
        outputs.push(("--dem (its .prj)", p));
    }
    let read: Vec<&Path> = [&args.sample_points, &args.profile_line, &args.boundary]
        .into_iter()
        .flatten()
        .map(PathBuf::as_path)
        .collect();
    args.input.args.check_outputs(&outputs, &read)?;
    let mut sinks: Vec<(String, Box<dyn TriangleSink>)> = Vec::new();
    let bbox = args.input.args.filter.bbox;
    if let Some(p) = &args.dem {
        let (mem, bounds) = (args.input.args.mem.0, args.input.header_bounds());
        sinks.push(("dem".into(), args.dem_options.sink(p, bbox, mem, bounds)?));
        if let Some(png) = &args.hillshade {
            check_output(png)?;
        }
    }
    if let Some(p) = &args.contours {
        let mem = args.input.args.mem.0;
        let inputs = &args.input.args.inputs;
        sinks.push((
            "contours".into(),
            args.contour_options.sink(p, mem, inputs)?,
        ));
    }
    if let Some(z) = args.volume_plane {
        let boundary = args.boundary.as_deref().map(read_boundary).transpose()?;
        sinks.push(("volume".into(), Box::new(VolumeSink::new(z, boundary)?)));
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
    let config = args.input.config(read_box)?;
    let crs_text = match args.input.crs()? {
        Some(c) => c.definition(),
        None => config.input_crs()?,
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
    let (run, products) = run_products(&args.input, &config, mesh_ref, sinks)?;
    if let Some(sweeptin::sink::ProductSummary::Volume(v)) = products.get("volume")
        && let Some(w) = super::volume::coverage_warning(v, false)
    {
        eprintln!("sweeptin: warning: {w}");
    }
    let mut report = Report::new(products);
    if let (Some(mut m), Some(path)) = (mesh, &args.mesh) {
        report.mesh = Some((path.clone(), m.finish()?));
    }
    if let (Some(png), Some(dem)) = (&args.hillshade, &args.dem) {
        report.hillshade = Some(shade(dem, png)?);
    }
    finish_report(&args.input, &run, &report, start)
}

/// Prints the one-line-per-product report, or with `--json` the whole summary on stdout.
pub fn finish_report(
    input: &ProductInput,
    run: &RunSummary,
    report: &Report,
    start: Instant,
) -> anyhow::Result<()> {
    if input.args.json {
        println!("{}", serde_json::to_string(&report.to_json(run)?)?);
    } else {
        report.print(run, start.elapsed().as_secs_f64());
    }
    Ok(())
}
