//! `sweeptin volume`: cut and fill volumes and areas against a plane or a second surface, within
//! an optional boundary polygon.

use super::input::{ProductInput, run_products};
use super::products::read_boundary;
use std::path::PathBuf;
use std::time::Instant;
use sweeptin::fmt::{Decimals, Figure, count};
use sweeptin::input::las::{Filter, Returns};
use sweeptin::pipeline::RunConfig;
use sweeptin::products::overlay::{OverlaySink, reference_surface};
use sweeptin::products::volume::VolumeSink;
use sweeptin::sink::{ProductSummary, TriangleSink};

/// Arguments of `sweeptin volume`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("reference").required(true).args(["plane", "surface"])))]
pub struct Args {
    #[command(flatten)]
    pub input: ProductInput,
    /// The reference is the horizontal plane z = Z.
    #[arg(long, value_name = "Z", allow_hyphen_values = true)]
    pub plane: Option<f64>,
    /// The reference is the TIN of these files (read with the same options as the input, but
    /// for --surface-class and --surface-returns).
    #[arg(long, value_name = "FILE", num_args = 1..)]
    pub surface: Vec<PathBuf>,
    /// Keep only these classes in the reference surface, e.g. `--surface-class 2` for a DTM
    /// under a DSM of `--returns first`. With this or --surface-returns, the reference's class
    /// and returns filters are these two alone (all classes, all returns when left out);
    /// without either, the input's --class and --returns.
    #[arg(long, value_name = "LIST")]
    pub surface_class: Option<super::info::ClassList>,
    /// Which returns the reference surface keeps (`last`, `first`, `all`); see --surface-class.
    #[arg(long, value_enum, value_name = "RETURNS")]
    pub surface_returns: Option<sweeptin::input::las::Returns>,
    /// Restrict to this polygon (GeoJSON Polygon/MultiPolygon; holes allowed).
    #[arg(long, value_name = "GEOJSON")]
    pub boundary: Option<PathBuf>,
    /// Bands the reference surface is filed into (with --surface).
    #[arg(long, default_value_t = 1024, hide = true)]
    pub bands: usize,
}

/// The volume sink against the plane (`None` when the reference is a surface).
pub fn plane_sink(args: &Args) -> anyhow::Result<Option<Box<dyn TriangleSink>>> {
    let Some(z) = args.plane else {
        return Ok(None);
    };
    let boundary = args.boundary.as_deref().map(read_boundary).transpose()?;
    Ok(Some(Box::new(VolumeSink::new(z, boundary)?)))
}

/// The reference surface's point filter: the input's, with its classes and returns taken from
/// `--surface-class` and `--surface-returns` when either is given.
fn surface_filter(args: &Args, config: &RunConfig) -> Filter {
    let mut f = config.input().filter.clone();
    if args.surface_class.is_some() || args.surface_returns.is_some() {
        f.classes = args.surface_class.as_ref().map(|c| c.0.clone());
        f.returns = args.surface_returns.unwrap_or(Returns::All);
    }
    f
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    if args.surface.is_empty() && (args.surface_class.is_some() || args.surface_returns.is_some()) {
        return Err(sweeptin::Error::Options(
            "--surface-class and --surface-returns filter the reference surface: give it with \
             --surface FILE (against --plane they have nothing to filter)"
                .into(),
        )
        .into());
    }
    let config = args.input.config(None)?;
    let sink: Box<dyn TriangleSink> = match plane_sink(&args)? {
        Some(s) => s,
        None => {
            let boundary = args.boundary.as_deref().map(read_boundary).transpose()?;
            let dir = args
                .input
                .args
                .tmp_dir
                .clone()
                .unwrap_or_else(std::env::temp_dir);
            let reader = reference_surface(
                &config,
                &args.surface,
                surface_filter(&args, &config),
                &dir,
                args.bands,
            )
            .map_err(|e| super::input::run_error(e, &args.surface))?;
            // A quarter of the budget for the reference's pieces in memory.
            let budget = usize::try_from(config.options().mem / 4).unwrap_or(usize::MAX);
            Box::new(OverlaySink::new(reader, boundary, budget))
        }
    };
    let (run, products) = run_products(&args.input, &config, None, vec![("volume".into(), sink)])?;
    let Some(ProductSummary::Volume(v)) = products.get("volume") else {
        return Err(sweeptin::Error::Internal(format!("no volume summary in {products:?}")).into());
    };
    if let Some(w) = coverage_warning(v, args.plane.is_none()) {
        eprintln!("sweeptin: warning: {w}");
    }
    if args.input.args.json {
        let mut out = serde_json::to_value(v)?;
        out["run"] = serde_json::to_value(&run)?;
        println!("{}", serde_json::to_string(&out)?);
        return Ok(());
    }
    let t = &v.totals;
    let against = match args.plane {
        Some(z) => format!("the plane z = {}", Figure(z)),
        None => "the reference surface".to_string(),
    };
    println!("against {against}:");
    print_totals(t);
    if let Some(b) = v.boundary_area {
        println!("  boundary     {}", Decimals(b, 3));
    }
    eprintln!(
        "sweeptin: {} points, {} triangles in {:.2} s",
        count(run.points_read),
        count(run.triangles),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// What to warn about when the volumes cover less than asked: nothing at all (a boundary in
/// another CRS than the points gave zeros without a word), or only part of the boundary.
pub fn coverage_warning(v: &sweeptin::sink::VolumeSummary, surface: bool) -> Option<String> {
    let covered = v.totals.area;
    let (none, some) = if surface {
        (
            "the surface and the reference do not overlap",
            "the surface and the reference overlap on",
        )
    } else {
        ("the TIN does not meet", "the TIN covers")
    };
    match v.boundary_area {
        Some(_) if covered == 0.0 => Some(format!(
            "{none}{} the boundary (or only along edges): every volume and area is 0 (is the \
             boundary in the points' CRS?)",
            if surface { " within" } else { "" }
        )),
        // Less than 99 % of the boundary: worth a word, volumes outside are not guessed.
        Some(b) if covered < 0.99 * b => Some(format!(
            "{some} {covered:.3} of the boundary's {b:.3} ({:.1} %): the volumes count only that \
             part",
            100.0 * covered / b
        )),
        None if surface && covered == 0.0 => Some(format!(
            "{none} (or only along edges): every volume and area is 0"
        )),
        _ => None,
    }
}

/// Cut, fill, net volume and the areas, one per line (as `sweeptin volume` prints them).
pub fn print_totals(t: &sweeptin::sink::CutFillTotals) {
    let d = |v: f64| Decimals(v, 3);
    println!(
        "  cut volume   {}   (area {})",
        d(t.cut_volume),
        d(t.cut_area)
    );
    println!(
        "  fill volume  {}   (area {})",
        d(t.fill_volume),
        d(t.fill_area)
    );
    println!("  net volume   {}", d(t.net_volume));
    println!("  area covered {}", d(t.area));
}
