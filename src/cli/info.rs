//! `sweeptin info`: what the headers of LAS/LAZ/COPC files say, lasinfo-style (and, with
//! `--classes`, what their points are, read on every core), with a summary over many files. A
//! bad file is reported and the others still shown; the exit status is then that of the first
//! failure (3 for a damaged file).

use clap::ArgAction;
use serde::Serialize;
use std::path::{Path, PathBuf};
use sweeptin::fmt::count;
use sweeptin::input::las::{
    BBox, FileInfo, Filter, FilterStats, PointStats, Quantization, Returns, parse_classes, scan,
};

/// Arguments of `sweeptin info`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  sweeptin info tiles/*.laz          # headers, and a summary\n  \
                        sweeptin info --classes tile.laz   # also read the points (all cores)"
)]
pub struct Args {
    /// LAS/LAZ/COPC files (`@list.txt`, quoted globs and `.vpc` files are expanded).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Also read every point (of those that pass the filters): counts by classification, return
    /// number and number of returns, flags, x/y/z, intensity and GPS-time ranges, covered area
    /// and density.
    #[arg(long, visible_alias = "stats")]
    pub classes: bool,
    /// Print JSON (`{"files": [...], "summary": {...}}`) instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub filter: FilterArgs,
}

/// A classification list such as `2,9`.
#[derive(Clone, Debug)]
pub struct ClassList(pub Vec<u8>);

impl std::str::FromStr for ClassList {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_classes(s).map(ClassList).map_err(|e| e.to_string())
    }
}

/// Point filters, shared by the commands that read lidar (flatten into their arguments).
#[derive(clap::Args, Debug, Clone)]
pub struct FilterArgs {
    /// Keep only these classification codes, e.g. `--class 2,9`.
    #[arg(long, value_name = "LIST")]
    pub class: Option<ClassList>,
    /// Which returns to keep: `last` (return number = number of returns), `first`, or `all`.
    #[arg(long, value_enum, default_value_t = Returns::All)]
    pub returns: Returns,
    /// Drop points flagged "withheld".
    #[arg(long, value_name = "BOOL", default_value_t = true, action = ArgAction::Set)]
    pub drop_withheld: bool,
    /// Keep withheld points (same as `--drop-withheld false`).
    #[arg(long, conflicts_with = "drop_withheld")]
    pub keep_withheld: bool,
    /// Keep only points inside this box (real-world x, y; edges included). Files whose header
    /// extent misses it are not decoded, nor the COPC octree nodes that miss it.
    #[arg(long, value_name = "XMIN,YMIN,XMAX,YMAX", allow_hyphen_values = true)]
    pub bbox: Option<BBox>,
    /// Take z from this extra-bytes attribute of the LAS/LAZ records instead of their z, e.g.
    /// `--z-from HeightAboveGround` (written by `sweeptin height`): a canopy height model is
    /// `dem hag.laz --returns first --z-from HeightAboveGround`. Points without a finite value
    /// (outside the ground, see `height --help`) are dropped.
    #[arg(long, value_name = "NAME")]
    pub z_from: Option<String>,
    /// Range requests in flight for each remote input (an `https://`, `http://` or `s3://`
    /// URL): the LAZ chunks or COPC nodes a run reads are fetched this many at a time,
    /// neighbouring ones in one request (docs/REMOTE.md).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_IO_CONCURRENCY as u16,
          value_parser = clap::value_parser!(u16).range(1..=256))]
    pub io_concurrency: u16,
    /// Seconds a request to a remote input may wait to connect and for the answer to start
    /// (twice as long for its body); a request that times out is retried (5 attempts in all)
    /// like a dropped connection, then the run stops naming the URL (docs/REMOTE.md).
    #[arg(long, value_name = "SECS", default_value_t = DEFAULT_IO_TIMEOUT,
          value_parser = clap::value_parser!(u64).range(1..=3600))]
    pub io_timeout: u64,
}

use sweeptin::input::source::{DEFAULT_IO_CONCURRENCY, DEFAULT_IO_TIMEOUT};

impl FilterArgs {
    /// The library filter these flags describe (`--io-concurrency` and `--io-timeout` are set
    /// for the process when the command line is parsed: `cli::apply_io_options`).
    pub fn to_filter(&self) -> Filter {
        Filter {
            classes: self.class.as_ref().map(|c| c.0.clone()),
            returns: self.returns,
            drop_withheld: self.drop_withheld && !self.keep_withheld,
            bbox: self.bbox,
            z_from: self.z_from.clone(),
            classes_from: None,
        }
    }
}

/// One file's report (the JSON object of a file).
#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    info: FileInfo,
    /// Points per square unit over the header extent.
    density: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stats: Option<PointStats>,
}

/// A failed file (in the JSON list).
#[derive(Serialize)]
struct Failed {
    path: PathBuf,
    error: String,
}

#[derive(Serialize)]
#[serde(untagged)]
enum Entry {
    Ok(Box<Report>),
    Failed(Failed),
}

/// Over all the files read.
#[derive(Serialize, Default)]
struct Summary {
    files: usize,
    failed: usize,
    points: u64,
    /// `[xmin, ymin, zmin, xmax, ymax, zmax]` of the header extents.
    bounds: Option<[f64; 6]>,
    /// The CRS, when the files agree.
    crs: Option<String>,
    /// Files that declare another CRS than the first.
    other_crs: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    stats: Option<PointStats>,
}

#[derive(Serialize)]
struct Output {
    files: Vec<Entry>,
    summary: Summary,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let filter = args.filter.to_filter();
    let mut entries = Vec::new();
    let mut summary = Summary::default();
    let mut first_error: Option<sweeptin::Error> = None;
    for (i, path) in args.files.iter().enumerate() {
        match report(path, args.classes, &filter) {
            Ok(r) => {
                add(&mut summary, &r);
                if !args.json {
                    if i > 0 {
                        println!();
                    }
                    print_text(&r);
                }
                entries.push(Entry::Ok(Box::new(r)));
            }
            Err(e) => {
                summary.failed += 1;
                eprintln!("sweeptin: error: {e}");
                entries.push(Entry::Failed(Failed {
                    path: path.clone(),
                    error: e.to_string(),
                }));
                first_error.get_or_insert(e);
            }
        }
    }
    summary.files = args.files.len();
    let failed = summary.failed;
    if args.json {
        let out = Output {
            files: entries,
            summary,
        };
        println!("{}", serde_json::to_string_pretty(&out)?);
        super::SUMMARY_PRINTED.store(true, std::sync::atomic::Ordering::Relaxed);
    } else if args.files.len() > 1 {
        println!();
        print_summary(&summary);
    }
    if let Some(e) = first_error {
        // The first failure's kind is the exit status (3 for a bad file).
        return Err(anyhow::Error::from(e).context(format!(
            "{failed} of {} files could not be read",
            args.files.len()
        )));
    }
    Ok(())
}

fn report(path: &Path, classes: bool, filter: &Filter) -> sweeptin::Result<Report> {
    let mut info = FileInfo::read(path)?;
    // Header values at the file's precision: no binary noise such as -0.5680000000000001.
    let q = info.quantization();
    for a in 0..3 {
        info.bounds.min[a] = q.round(a, info.bounds.min[a]);
        info.bounds.max[a] = q.round(a, info.bounds.max[a]);
    }
    let r = info.rect();
    let area = (r[2] - r[0]) * (r[3] - r[1]);
    let density = (area > 0.0).then(|| round_to(info.point_count as f64 / area, 3));
    let stats = if classes {
        let mut s = scan(path, filter, true)?;
        for a in 0..3 {
            s.min[a] = q.round(a, s.min[a]);
            s.max[a] = q.round(a, s.max[a]);
        }
        Some(s)
    } else {
        None
    };
    Ok(Report {
        info,
        density,
        stats,
    })
}

fn round_to(v: f64, decimals: i32) -> f64 {
    let p = 10f64.powi(decimals);
    (v * p).round() / p
}

fn add(s: &mut Summary, r: &Report) {
    let i = &r.info;
    s.points += i.point_count;
    if i.point_count > 0 {
        let b = i.bounds;
        let nb = [b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]];
        s.bounds = Some(match s.bounds {
            None => nb,
            Some(o) => std::array::from_fn(|k| {
                if k < 3 {
                    o[k].min(nb[k])
                } else {
                    o[k].max(nb[k])
                }
            }),
        });
    }
    let crs = i.crs.as_ref().map(|c| c.to_string());
    match (&s.crs, crs) {
        (None, Some(c)) if s.other_crs == 0 => s.crs = Some(c),
        (Some(a), Some(c)) if *a != c => s.other_crs += 1,
        _ => {}
    }
    if let Some(st) = &r.stats {
        match &mut s.stats {
            None => s.stats = Some(st.clone()),
            Some(t) => t.merge(st),
        }
    }
}

/// ASPRS standard class names (LAS 1.4 R15, table 17).
fn class_name(c: usize) -> &'static str {
    const NAMES: [&str; 23] = [
        "created, never classified",
        "unclassified",
        "ground",
        "low vegetation",
        "medium vegetation",
        "high vegetation",
        "building",
        "low point (noise)",
        "reserved / model key-point",
        "water",
        "rail",
        "road surface",
        "reserved / overlap",
        "wire guard (shield)",
        "wire conductor (phase)",
        "transmission tower",
        "wire-structure connector",
        "bridge deck",
        "high noise",
        "overhead structure",
        "ignored ground",
        "snow",
        "temporal exclusion",
    ];
    NAMES.get(c).copied().unwrap_or("user-defined")
}

/// `v` with the decimals of the file's precision on `axis`.
fn coord(q: &Quantization, axis: usize, v: f64) -> String {
    let d = q.decimals(axis);
    format!("{:.d$}", q.round(axis, v))
}

fn print_text(r: &Report) {
    let i = &r.info;
    let q = i.quantization();
    println!("{}", i.path.display());
    let kind = match (&i.copc, i.compressed) {
        (Some(_), _) => "COPC",
        (None, true) => "LAZ",
        (None, false) => "LAS",
    };
    let extra = if i.extra_bytes > 0 {
        format!(" ({} extra bytes)", i.extra_bytes)
    } else {
        String::new()
    };
    println!(
        "  format:   {kind}, LAS {}.{}, point format {}, {} bytes per point{extra}",
        i.version.0, i.version.1, i.point_format, i.record_length
    );
    let extended = i
        .extended_point_count
        .map_or(String::new(), |n| format!(", LAS 1.4 field {n}"));
    println!(
        "  points:   {} (legacy field {}{extended})",
        i.point_count, i.legacy_point_count
    );
    let by_return: Vec<String> = i
        .points_by_return
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > 0)
        .map(|(k, n)| format!("{}: {}", k + 1, count(*n)))
        .collect();
    if !by_return.is_empty() {
        println!("  returns:  {} (header)", by_return.join(", "));
    }
    let axes = ["x", "y", "z"];
    let bounds: Vec<String> = (0..3)
        .map(|a| {
            format!(
                "{} {} .. {}",
                axes[a],
                coord(&q, a, i.bounds.min[a]),
                coord(&q, a, i.bounds.max[a])
            )
        })
        .collect();
    println!("  bounds:   {}", bounds.join(", "));
    if let Some(d) = r.density {
        let rr = i.rect();
        println!(
            "  density:  {d:.2} points per square unit over the header extent ({:.0} square \
             units)",
            (rr[2] - rr[0]) * (rr[3] - rr[1])
        );
    }
    println!(
        "  scale:    {} {} {}   offset: {} {} {}",
        i.scale[0], i.scale[1], i.scale[2], i.offset[0], i.offset[1], i.offset[2]
    );
    match &i.crs {
        Some(crs) => println!("  CRS:      {crs}"),
        None => println!("  CRS:      none declared"),
    }
    let software: Vec<&str> = [i.generating_software.as_str(), i.system_identifier.as_str()]
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect();
    if !software.is_empty() {
        println!("  software: {}", software.join(" / "));
    }
    if let Some((day, year)) = i.creation {
        println!("  created:  day {day} of {year}");
    }
    if i.file_source_id != 0 {
        println!("  source:   file source id {}", i.file_source_id);
    }
    if let Some(c) = &i.copc {
        println!(
            "  COPC:     {} octree nodes, depth {}, root spacing {:.3}, cube of side {:.3} centred \
             on {}",
            c.nodes,
            c.depth,
            c.spacing,
            2.0 * c.halfsize,
            (0..3)
                .map(|a| coord(&q, a, c.center[a]))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    for v in &i.vlrs {
        println!(
            "  {:<9} {} {} \"{}\" ({} bytes)",
            if v.extended { "EVLR:" } else { "VLR:" },
            v.user_id,
            v.record_id,
            v.description,
            v.bytes
        );
    }
    for w in &i.warnings {
        println!("  warning:  {w}");
    }
    if let Some(s) = &r.stats {
        print_stats(s, &q);
    }
}

fn print_stats(s: &PointStats, q: &Quantization) {
    println!("  points kept: {} (read and counted)", count(s.points));
    println!("  classes:");
    for (c, n) in s.classes.iter().enumerate().filter(|(_, n)| **n > 0) {
        println!("    {c:>3} {:<28} {:>12}", class_name(c), count(*n));
    }
    let list = |v: &[u64]| -> String {
        v.iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(k, n)| format!("{k}: {}", count(*n)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!("  return number:      {}", list(&s.by_return));
    println!("  number of returns:  {}", list(&s.by_returns));
    println!(
        "  first {}, last {}, single {}",
        count(s.first),
        count(s.last),
        count(s.single)
    );
    let flags = ["synthetic", "key-point", "withheld", "overlap"];
    let set: Vec<String> = (0..4)
        .filter(|&k| s.flags[k] > 0)
        .map(|k| format!("{} {}", flags[k], count(s.flags[k])))
        .collect();
    if !set.is_empty() {
        println!("  flags:    {}", set.join(", "));
    }
    if s.points > 0 {
        let axes = ["x", "y", "z"];
        let r: Vec<String> = (0..3)
            .map(|a| {
                format!(
                    "{} {} .. {}",
                    axes[a],
                    coord(q, a, s.min[a]),
                    coord(q, a, s.max[a])
                )
            })
            .collect();
        println!("  points span: {}", r.join(", "));
        println!("  intensity: {} .. {}", s.intensity[0], s.intensity[1]);
    }
    if let Some([a, b]) = s.gps_time {
        println!("  GPS time: {a:.6} .. {b:.6}");
    }
    if s.covered_area > 0.0 {
        println!(
            "  covered:  {:.0} square units ({} unit cells); density {:.2} points, {:.2} last \
             returns per square unit",
            s.covered_area,
            s.cell,
            s.points as f64 / s.covered_area,
            s.last as f64 / s.covered_area
        );
    }
    print_filter(&s.filter);
}

fn print_filter(f: &FilterStats) {
    println!(
        "  filters:  read {}, kept {}; dropped: withheld {}, class {}, returns {}, bbox {}; \
         skipped without decoding {}",
        f.read, f.kept, f.withheld, f.class, f.returns, f.bbox, f.skipped
    );
}

fn print_summary(s: &Summary) {
    println!(
        "summary of {} files ({} could not be read)",
        s.files, s.failed
    );
    println!("  points:   {}", count(s.points));
    if let Some(b) = s.bounds {
        println!(
            "  bounds:   x {} .. {}, y {} .. {}, z {} .. {}",
            b[0], b[3], b[1], b[4], b[2], b[5]
        );
        let area = (b[3] - b[0]) * (b[4] - b[1]);
        if area > 0.0 {
            println!(
                "  density:  {:.2} points per square unit over the extent",
                s.points as f64 / area
            );
        }
    }
    match (&s.crs, s.other_crs) {
        (Some(c), 0) => println!("  CRS:      {c}"),
        (Some(c), n) => println!("  CRS:      {c}, and {n} files declare another"),
        (None, _) => println!("  CRS:      none declared"),
    }
    if let Some(st) = &s.stats {
        println!("  classes:");
        for (c, n) in st.classes.iter().enumerate().filter(|(_, n)| **n > 0) {
            println!("    {c:>3} {:<28} {:>12}", class_name(c), count(*n));
        }
        print_filter(&st.filter);
    }
}
