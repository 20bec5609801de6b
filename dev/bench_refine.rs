//! Quality refinement benchmark: `sweeptin::refine` beside Shewchuk's Triangle 1.6 (`-pzQq30`,
//! `scripts/peers/triangle_refine.c`) on the same planar straight-line graphs
//! (`scripts/bench-refine.sh` runs both and prints the table).
//!
//! ```text
//! bench_refine prep <contours|bgt> FILE [--segments N] [--seed S]
//! bench_refine sweeptin FILE [--repeat R] [--min-angle A]
//! ```
//!
//! `prep` writes a PSLG (cleaned into a planar graph by `sweeptin::breaklines::clean`, with its
//! bounding box as a closed ring, so the domain is that box for both tools):
//!
//! | input | lines |
//! |---|---|
//! | `contours` | `synth::contours(--segments, seed)` (default ~100,000 segments) |
//! | `bgt` | `$SWEEPTIN_DATA/lines/bgt_delft_all_layers.geojson` (real: 582 polygons, 13,131 vertices, a planar partition with segments down to 1 mm) |
//!
//! File layout (little-endian): `SWPSLG01`, u64 vertex count, u64 segment count, then `x, y, z`
//! f64 per vertex and two u32 per segment.
//!
//! `sweeptin` times, per repetition, what `triangle -pq` does: `refine_pslg` (the constrained
//! Delaunay triangulation of the graph and its refinement; it also interpolates every Steiner
//! point's z, which Triangle does not do). Prints one JSON line: minimum seconds, vertices,
//! triangles, smallest angle, triangles under the bound.

use anyhow::{Context, Result, bail};
use std::io::{Read, Write};
use std::time::Instant;
use sweeptin::breaklines::{CleanOptions, clean, read_files};
use sweeptin::refine::{RefineOptions, refine_pslg};

const MAGIC: &[u8; 8] = b"SWPSLG01";

fn main() -> Result<()> {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let opt = |name: &str| {
        argv.iter()
            .position(|a| a == name)
            .and_then(|i| argv.get(i + 1))
            .cloned()
    };
    match (argv.first().map(String::as_str), argv.get(1), argv.get(2)) {
        (Some("prep"), Some(kind), Some(file)) => {
            let segments: usize = opt("--segments").map_or(Ok(100_000), |s| s.parse())?;
            let seed: u64 = opt("--seed").map_or(Ok(1), |s| s.parse())?;
            prep(kind, file, segments, seed)
        }
        (Some("sweeptin"), Some(file), _) => {
            let repeat: usize = opt("--repeat").map_or(Ok(3), |s| s.parse())?;
            let angle: f64 = opt("--min-angle").map_or(Ok(30.0), |s| s.parse())?;
            run(file, repeat.max(1), angle)
        }
        _ => bail!(
            "usage: bench_refine prep <contours|bgt> FILE [--segments N] [--seed S]\n       \
             bench_refine sweeptin FILE [--repeat R] [--min-angle A]"
        ),
    }
}

fn prep(kind: &str, file: &str, segments: usize, seed: u64) -> Result<()> {
    let mut lines: Vec<Vec<[f64; 3]>> = match kind {
        "contours" => sweeptin::synth::contours(segments, seed),
        "bgt" => {
            let dir = std::env::var("SWEEPTIN_DATA").unwrap_or_else(|_| "../shared/data".into());
            let path = std::path::Path::new(&dir).join("lines/bgt_delft_all_layers.geojson");
            let l = read_files(&[path]).context("reading the BGT polygons")?;
            let g = l.clean(&CleanOptions::default())?;
            g.segments
                .iter()
                .map(|s| s.map(|v| g.vertices[v as usize]).to_vec())
                .collect()
        }
        _ => bail!("unknown input {kind}"),
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in lines.iter().flatten() {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let margin = if kind == "bgt" { 1.0 } else { 0.0 };
    let (lo, hi) = (
        [lo[0] - margin, lo[1] - margin],
        [hi[0] + margin, hi[1] + margin],
    );
    lines.push(vec![
        [lo[0], lo[1], 0.0],
        [hi[0], lo[1], 0.0],
        [hi[0], hi[1], 0.0],
        [lo[0], hi[1], 0.0],
        [lo[0], lo[1], 0.0],
    ]);
    let g = clean(&lines, &CleanOptions::default())?;
    let mut out = std::io::BufWriter::new(std::fs::File::create(file)?);
    out.write_all(MAGIC)?;
    out.write_all(&(g.vertices.len() as u64).to_le_bytes())?;
    out.write_all(&(g.segments.len() as u64).to_le_bytes())?;
    for v in &g.vertices {
        let z = if v[2].is_finite() { v[2] } else { 0.0 };
        for c in [v[0], v[1], z] {
            out.write_all(&c.to_le_bytes())?;
        }
    }
    for s in &g.segments {
        for i in s {
            out.write_all(&i.to_le_bytes())?;
        }
    }
    out.flush()?;
    eprintln!(
        "bench_refine: {kind}: {} vertices, {} segments -> {file}",
        g.vertices.len(),
        g.segments.len()
    );
    Ok(())
}

/// Vertices and segments of a PSLG.
type Graph = (Vec<[f64; 3]>, Vec<[u32; 2]>);

fn read(file: &str) -> Result<Graph> {
    let mut bytes = Vec::new();
    std::fs::File::open(file)?.read_to_end(&mut bytes)?;
    if bytes.len() < 24 || &bytes[..8] != MAGIC {
        bail!("{file}: not a bench_refine PSLG");
    }
    let u64_at = |i: usize| u64::from_le_bytes(bytes[i..i + 8].try_into().unwrap()) as usize;
    let (n, m) = (u64_at(8), u64_at(16));
    let f = |i: usize| f64::from_le_bytes(bytes[i..i + 8].try_into().unwrap());
    let pts = (0..n)
        .map(|i| {
            let o = 24 + 24 * i;
            [f(o), f(o + 8), f(o + 16)]
        })
        .collect();
    let base = 24 + 24 * n;
    let u = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
    let segs = (0..m)
        .map(|i| [u(base + 8 * i), u(base + 8 * i + 4)])
        .collect();
    Ok((pts, segs))
}

fn run(file: &str, repeat: usize, angle: f64) -> Result<()> {
    let (pts, segs) = read(file)?;
    let options = RefineOptions {
        min_angle: angle,
        ..RefineOptions::default()
    };
    // The segments again, by their coordinates, as refine takes breaklines (not timed).
    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..repeat {
        let t0 = Instant::now();
        let r = refine_pslg(&pts, &segs, &options)?;
        best = best.min(t0.elapsed().as_secs_f64());
        result = Some(r);
    }
    let r = result.expect("repeat >= 1");
    println!(
        "{}",
        serde_json::json!({
            "tool": "sweeptin",
            "input": file,
            "points": pts.len(),
            "segments": segs.len(),
            "vertices": r.stats.vertices,
            "triangles": r.stats.triangles,
            "min_angle": r.stats.min_angle,
            "skinny": r.stats.skinny,
            "seconds": best,
            "repeat": repeat,
        })
    );
    Ok(())
}
