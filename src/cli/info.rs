//! `sweeptin info`: what the headers of LAS/LAZ files say (and, with `--classes`, what their
//! points are). A bad file is reported and the others still shown; the exit status is then that
//! of the first failure (3 for a damaged file).

use clap::ArgAction;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use sweeptin::input::las::{
    BBox, FileInfo, Filter, FilterStats, LidarReader, Returns, parse_classes,
};

/// Arguments of `sweeptin info`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// LAS/LAZ files.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Also read every point and count the classification codes (of the points that pass the
    /// filters).
    #[arg(long)]
    pub classes: bool,
    /// Print JSON (an array with one object per file) instead of text.
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
        parse_classes(s).map(ClassList)
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
    /// Keep only points inside this box (real-world x, y; edges included).
    #[arg(long, value_name = "XMIN,YMIN,XMAX,YMAX", allow_hyphen_values = true)]
    pub bbox: Option<BBox>,
}

impl FilterArgs {
    /// The library filter these flags describe.
    pub fn to_filter(&self) -> Filter {
        Filter {
            classes: self.class.as_ref().map(|c| c.0.clone()),
            returns: self.returns,
            drop_withheld: self.drop_withheld && !self.keep_withheld,
            bbox: self.bbox,
        }
    }
}

/// One file's report.
struct Report {
    info: FileInfo,
    /// Class counts and filter statistics, with `--classes`.
    classes: Option<([u64; 256], FilterStats)>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let filter = args.filter.to_filter();
    let mut failed = 0;
    let mut first_error: Option<sweeptin::Error> = None;
    let mut json_out = Vec::new();
    for (i, path) in args.files.iter().enumerate() {
        match report(path, args.classes, &filter) {
            Ok(r) if args.json => json_out.push(to_json(&r)),
            Ok(r) => {
                if i > 0 {
                    println!();
                }
                print_text(&r);
            }
            Err(e) => {
                failed += 1;
                eprintln!("sweeptin: error: {e}");
                if args.json {
                    json_out.push(json!({ "path": path, "error": e.to_string() }));
                }
                first_error.get_or_insert(e);
            }
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&json_out)?);
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
    let info = FileInfo::read(path)?;
    let classes = if classes {
        Some(count_classes(path, filter)?)
    } else {
        None
    };
    Ok(Report { info, classes })
}

fn count_classes(path: &Path, filter: &Filter) -> sweeptin::Result<([u64; 256], FilterStats)> {
    let mut reader = LidarReader::open(&[path], filter)?;
    let mut counts = [0u64; 256];
    let mut chunk = Vec::new();
    while reader.read_chunk(&mut chunk, 1 << 20)? > 0 {
        for p in &chunk {
            counts[usize::from(p.classification)] += 1;
        }
        chunk.clear();
    }
    Ok((counts, *reader.stats()))
}

/// ASPRS standard class names (LAS 1.4 R15, table 17).
fn class_name(c: u8) -> &'static str {
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
    NAMES.get(usize::from(c)).copied().unwrap_or("user-defined")
}

/// Decimals needed to print multiples of `scale` exactly (at most 9).
fn decimals(scale: f64) -> usize {
    (0..=9)
        .find(|&d| {
            let v = scale * 10f64.powi(d as i32);
            (v - v.round()).abs() < 1e-6
        })
        .unwrap_or(9)
}

fn print_text(r: &Report) {
    let i = &r.info;
    println!("{}", i.path.display());
    let kind = if i.compressed { "LAZ" } else { "LAS" };
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
    let axes = ["x", "y", "z"];
    let bounds: Vec<String> = (0..3)
        .map(|a| {
            let d = decimals(i.scale[a]);
            format!(
                "{} {:.d$} .. {:.d$}",
                axes[a], i.bounds.min[a], i.bounds.max[a]
            )
        })
        .collect();
    println!("  bounds:   {}", bounds.join(", "));
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
    for w in &i.warnings {
        println!("  warning:  {w}");
    }
    if let Some((counts, stats)) = &r.classes {
        println!("  classes:");
        for (c, n) in counts.iter().enumerate().filter(|(_, n)| **n > 0) {
            println!("    {c:>3} {:<28} {n:>12}", class_name(c as u8));
        }
        println!(
            "  filters:  read {}, kept {}; dropped: withheld {}, class {}, returns {}, bbox {}",
            stats.read, stats.kept, stats.withheld, stats.class, stats.returns, stats.bbox
        );
    }
}

fn to_json(r: &Report) -> Value {
    let mut v = serde_json::to_value(&r.info).unwrap_or(Value::Null);
    if let Value::Object(m) = &mut v {
        let def = r.info.crs.as_ref().and_then(|c| c.definition());
        m.insert("crs_definition".into(), json!(def));
        if let Some((counts, stats)) = &r.classes {
            let classes: serde_json::Map<String, Value> = counts
                .iter()
                .enumerate()
                .filter(|(_, n)| **n > 0)
                .map(|(c, n)| (c.to_string(), json!(n)))
                .collect();
            m.insert("classes".into(), Value::Object(classes));
            m.insert("filter_stats".into(), json!(stats));
        }
    }
    v
}
