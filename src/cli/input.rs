//! The input options shared by every command that triangulates (`tin` and the products), and the
//! helper that runs the pipeline into product sinks.

use super::info::ClassList;
use anyhow::{Context, bail};
use clap::ArgAction;
use serde_json::Value;
use std::path::{Path, PathBuf};
use sweeptin::io::MeshSink;
use sweeptin::lidar::{BBox, Crs, Filter, Returns};
use sweeptin::pipeline::{self, Input, RunSummary, TriangleSink};
use sweeptin::products::Fanout;

/// Input points and how to read them.
#[derive(clap::Args, Debug, Clone)]
pub struct InputArgs {
    /// Input points: LAS/LAZ files (read together as one point set), or XYZ text files (`x y z`
    /// per line, separated by commas, semicolons, tabs or spaces; `#` comments and one header
    /// line allowed).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// LAS/LAZ: keep only these classification codes, e.g. `--class 2,9`.
    #[arg(long, value_name = "LIST")]
    pub class: Option<ClassList>,
    /// LAS/LAZ: which returns to keep: `last`, `first`, or `all`.
    #[arg(long, value_enum, default_value_t = Returns::All)]
    pub returns: Returns,
    /// LAS/LAZ: drop points flagged "withheld".
    #[arg(long, value_name = "BOOL", default_value_t = true, action = ArgAction::Set)]
    pub drop_withheld: bool,
    /// LAS/LAZ: keep withheld points (same as `--drop-withheld false`).
    #[arg(long, conflicts_with = "drop_withheld")]
    pub keep_withheld: bool,
    /// LAS/LAZ: keep only points inside this box (real-world x, y; edges included).
    #[arg(long, value_name = "XMIN,YMIN,XMAX,YMAX", allow_hyphen_values = true)]
    pub crop: Option<BBox>,
    /// Which point survives among exact (x, y) duplicates.
    #[arg(long, value_enum, default_value_t = sweeptin::DuplicatePolicy::First)]
    pub duplicates: sweeptin::DuplicatePolicy,
    /// Coordinate reference system of the data (`EPSG:code`, `EPSG:code+vertical`, or WKT),
    /// recorded in the outputs instead of what the input declares (if anything).
    #[arg(long, value_name = "CRS")]
    pub crs: Option<String>,
    /// Leave out triangles with a horizontal edge longer than this (their area has no data).
    #[arg(long, value_name = "LENGTH")]
    pub max_edge: Option<f64>,
}

/// Parses `--crs`.
pub fn parse_crs(s: &str) -> anyhow::Result<Crs> {
    let t = s.trim();
    if let Some(code) = t.strip_prefix("EPSG:").or_else(|| t.strip_prefix("epsg:")) {
        let mut parts = code.split('+');
        let h = parts.next().unwrap_or("").trim().parse::<u32>();
        let v = parts.next().map(|v| v.trim().parse::<u32>());
        return match (h, v) {
            (Ok(h), None) => Ok(Crs {
                epsg: Some(h),
                ..Crs::default()
            }),
            (Ok(h), Some(Ok(v))) => Ok(Crs {
                epsg: Some(h),
                vertical_epsg: Some(v),
                ..Crs::default()
            }),
            _ => bail!("--crs {s}: expected EPSG:code or EPSG:code+code"),
        };
    }
    match Crs::from_wkt_bytes(t.as_bytes()) {
        Some(c) if c.name.is_some() || c.epsg.is_some() => Ok(c),
        _ => bail!("--crs {s}: expected EPSG:code, EPSG:code+code or a WKT definition"),
    }
}

impl InputArgs {
    /// The pipeline input, with `crop` (from a product's own options) as the LAS/LAZ box filter
    /// when `--crop` is not given.
    pub fn to_input(&self, crop: Option<BBox>) -> anyhow::Result<Input> {
        if self.crop.is_some() && crop.is_some() {
            bail!("--crop cannot be combined with --buffer (which sets the box to read)");
        }
        if let Some(l) = self.max_edge
            && !(l.is_finite() && l > 0.0)
        {
            bail!("--max-edge must be a positive length, not {l}");
        }
        Ok(Input {
            paths: self.files.clone(),
            filter: Filter {
                classes: self.class.as_ref().map(|c| c.0.clone()),
                returns: self.returns,
                drop_withheld: self.drop_withheld && !self.keep_withheld,
                bbox: self.crop.or(crop),
            },
            duplicates: self.duplicates,
        })
    }

    /// The CRS given with `--crs`, parsed.
    pub fn crs(&self) -> anyhow::Result<Option<Crs>> {
        self.crs.as_deref().map(parse_crs).transpose()
    }

    /// Are all the inputs LAS/LAZ (so that the box filter applies)?
    pub fn all_lidar(&self) -> bool {
        self.files.iter().all(|p| {
            matches!(
                p.extension()
                    .and_then(|e| e.to_str())
                    .map(str::to_ascii_lowercase)
                    .as_deref(),
                Some("las" | "laz")
            )
        })
    }
}

/// Fails early (before any heavy work) if an output cannot be created where asked.
pub fn check_output(path: &Path) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: cannot write: the directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    if path.is_dir() {
        bail!("{}: cannot write: it is a directory", path.display());
    }
    Ok(())
}

/// Runs the pipeline on `input` into `sinks` (one pass) and the optional mesh sink; returns the
/// run summary and the products' summaries (an object keyed by the sinks' names).
pub fn run_products(
    args: &InputArgs,
    input: &Input,
    mesh: Option<&mut dyn MeshSink>,
    sinks: Vec<(String, Box<dyn TriangleSink>)>,
) -> anyhow::Result<(RunSummary, Value)> {
    let mut fanout = Fanout::new(sinks)
        .with_crs(args.crs()?)
        .with_max_edge(args.max_edge);
    let names: Vec<String> = args.files.iter().map(|p| p.display().to_string()).collect();
    let run = pipeline::run(input, mesh, &mut [&mut fanout])
        .with_context(|| format!("cannot triangulate {}", names.join(", ")))?;
    let summary = fanout.finish()?;
    Ok((run, summary))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crs_forms() {
        assert_eq!(parse_crs("EPSG:3794").unwrap().epsg, Some(3794));
        let c = parse_crs("epsg:28992+5709").unwrap();
        assert_eq!((c.epsg, c.vertical_epsg), (Some(28992), Some(5709)));
        let w = parse_crs(r#"PROJCS["x",AUTHORITY["EPSG","2154"]]"#).unwrap();
        assert_eq!(w.epsg, Some(2154));
        assert!(parse_crs("EPSG:abc").is_err());
        assert!(parse_crs("nonsense").is_err());
    }
}
