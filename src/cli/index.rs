//! `sweeptin index`: a virtual point cloud (`.vpc`) of LAS/LAZ/COPC files, from their headers
//! only, for QGIS, PDAL wrench and lasR, and as sweeptin's own tile index (a run with `--bbox`
//! then opens only the files that meet the box); with `--chunks`, the chunk index of each plain
//! LAZ/LAS file (`plan::chunks::store_chunk_index`), stored beside it for plans to read.

use super::input::{check_output, distinct_outputs};
use anyhow::{Context, bail};
use std::path::PathBuf;
use sweeptin::input::las::FileInfo;

/// Arguments of `sweeptin index`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  sweeptin index 'tiles/*.laz' -o tiles.vpc\n  \
                        sweeptin dem tiles.vpc --bbox 770520,6277520,770580,6277580 --cell 0.5 \
                        -o part.tif\n  \
                        sweeptin index --chunks 'flights/*.laz'    (writes flights/*.laz.chunks)"
)]
pub struct Args {
    /// LAS/LAZ/COPC files (`@list.txt`, quoted globs and `.vpc` files are expanded).
    #[arg(required = true, value_name = "FILES")]
    pub files: Vec<PathBuf>,
    /// The virtual point cloud to write (`.vpc`); local files are named relative to its folder
    /// (absolute from a `.vpc` on S3), remote files by their full URL.
    /// With --chunks: the directory to write the chunk indexes into (default: beside each file).
    #[arg(short, long, value_name = "VPC", required_unless_present = "chunks")]
    pub output: Option<PathBuf>,
    /// Write the chunk index of each plain LAZ/LAS file instead (the box and point count of
    /// every LAZ chunk or block of 50,000 LAS records, one decoding pass) to FILE.chunks beside
    /// it, as LAStools' lasindex writes .lax files: `plan` then reads it instead of decoding
    /// the file, while the file keeps its size and modification time. An index that is up to
    /// date is kept; COPC files carry their own. --json prints every chunk's box.
    #[arg(long)]
    pub chunks: bool,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
    /// The file lists and `.vpc` files read to find `files`: inputs too.
    #[arg(skip)]
    pub lists: Vec<PathBuf>,
}

/// What `index` wrote.
#[derive(serde::Serialize)]
struct Summary<'a> {
    output: &'a std::path::Path,
    files: usize,
    points: u64,
    bounds: [f64; 6],
    crs: Option<String>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if args.chunks {
        return chunks(&args);
    }
    let Some(output) = args.output.as_deref() else {
        bail!("give the virtual point cloud to write: -o FILE.vpc (or --chunks)");
    };
    if !sweeptin::input::las::vpc::is_vpc(output) {
        bail!(
            "{}: a virtual point cloud is written as .vpc",
            output.display()
        );
    }
    check_output(output)?;
    let read = [args.files.as_slice(), &args.lists].concat();
    distinct_outputs(&[("-o", output)], &read, "the index")?;
    let infos: Vec<FileInfo> = args
        .files
        .iter()
        .map(|p| FileInfo::read(p).with_context(|| format!("cannot index {}", p.display())))
        .collect::<anyhow::Result<_>>()?;
    let crs: Vec<String> = infos
        .iter()
        .filter_map(|i| i.crs.as_ref().map(|c| c.to_string()))
        .collect();
    if crs.windows(2).any(|w| w[0] != w[1]) {
        eprintln!(
            "sweeptin: warning: the files declare different CRSs ({} and {}): a run reads only \
             files in one CRS",
            crs[0],
            crs.iter()
                .find(|c| **c != crs[0])
                .map_or("", |c| c.as_str())
        );
    }
    sweeptin::output::vpc::write_vpc(output, &infos)?;
    let lost = sweeptin::output::vpc::without_footprint(&infos);
    if let Some(first) = lost.first() {
        eprintln!(
            "sweeptin: warning: {} of {} files ({}{}) have {}: their STAC items have no \
             geometry or bbox (which must be WGS 84 longitude and latitude); proj:bbox keeps \
             their extent",
            lost.len(),
            infos.len(),
            first.path.display(),
            if lost.len() > 1 { ", …" } else { "" },
            match &first.crs {
                None => "no CRS".to_string(),
                Some(c) => format!("a CRS sweeptin cannot turn into WGS 84 ({c})"),
            }
        );
    }
    let with_points: Vec<&FileInfo> = infos.iter().filter(|i| i.point_count > 0).collect();
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for i in &with_points {
        for a in 0..3 {
            b[a] = b[a].min(i.bounds.min[a]);
            b[a + 3] = b[a + 3].max(i.bounds.max[a]);
        }
    }
    let s = Summary {
        output,
        files: infos.len(),
        points: infos.iter().map(|i| i.point_count).sum(),
        bounds: if with_points.is_empty() { [0.0; 6] } else { b },
        crs: infos
            .iter()
            .find_map(|i| i.crs.as_ref().map(|c| c.to_string())),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else {
        println!(
            "{}: {} files, {} points, x {} .. {}, y {} .. {}{}",
            s.output.display(),
            s.files,
            sweeptin::fmt::count(s.points),
            s.bounds[0],
            s.bounds[3],
            s.bounds[1],
            s.bounds[4],
            s.crs
                .as_deref()
                .map_or(String::new(), |c| format!(", CRS {c}"))
        );
    }
    Ok(())
}

/// `index --chunks`: every file's chunk index, beside it or into `-o DIR`, checked first: no
/// two files' indexes the same path, none an input.
fn chunks(args: &Args) -> anyhow::Result<()> {
    use sweeptin::plan::chunks::{beside, store_chunk_index};
    if let Some(d) = &args.output {
        if d.exists() && !d.is_dir() {
            bail!(
                "-o {}: with --chunks, -o names the directory the chunk indexes go into",
                d.display()
            );
        }
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    let outs: Vec<PathBuf> = args
        .files
        .iter()
        .map(|f| match &args.output {
            None => beside(f),
            Some(d) => d.join(beside(std::path::Path::new(
                f.file_name().unwrap_or_default(),
            ))),
        })
        .collect();
    let named: Vec<(&str, &std::path::Path)> =
        outs.iter().map(|p| ("index", p.as_path())).collect();
    let read = [args.files.as_slice(), &args.lists].concat();
    distinct_outputs(&named, &read, "the chunk indexes")?;
    let mut all = Vec::with_capacity(args.files.len());
    for f in &args.files {
        let s = store_chunk_index(f, args.output.as_deref())
            .with_context(|| format!("cannot index the chunks of {}", f.display()))?;
        if !args.json {
            let what = match s.state {
                "copc" => "COPC: carries its own index".to_string(),
                "no_points" => "no points: nothing to index".to_string(),
                state => format!(
                    "{} chunks, {} points -> {}{}",
                    sweeptin::fmt::count(s.chunks.len() as u64),
                    sweeptin::fmt::count(s.points),
                    s.index
                        .as_deref()
                        .unwrap_or(std::path::Path::new(""))
                        .display(),
                    if state == "up_to_date" {
                        " (up to date, kept)"
                    } else {
                        ""
                    }
                ),
            };
            println!("{}: {what}", f.display());
        }
        all.push(s);
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({ "files": all }))?
        );
    }
    Ok(())
}
