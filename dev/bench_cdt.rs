//! Constrained Delaunay triangulation benchmark: sweeptin's batch CDT beside `spade` and `cdt`, on
//! synthetic breaklines plus points, one process per (tool, input), for peak memory
//! (`scripts/bench-cdt.sh` runs them all and prints the table).
//!
//! ```text
//! bench_cdt prep <contours|coastline> FILE [--points N] [--lines N] [--seed S] [--repeat R]
//! bench_cdt <sweeptin|spade|cdt> FILE [--repeat R] [--threads T]
//! ```
//!
//! `prep` generates the lines and points, cleans the lines into a planar graph with
//! `sweeptin::breaklines::clean::clean` (timed: minimum of `--repeat` runs), checks that graph
//! with `Pslg::check_planar` (not timed), and writes the cleaned input to `FILE`:
//!
//! | input | lines | points |
//! |---|---|---|
//! | `contours` | `synth::contours(--lines, seed)` (default ~1,000,000 segments) | `synth::contour_points(--points, seed)` (default 1,000,000) |
//! | `coastline` | `synth::coastline(--lines, seed)` (default ~2,900,000 vertices) | `synth::coastline_points(--points, seed)` (default 1,000,000) |
//!
//! The vertex array is the graph's vertices followed by the points; segments index it. All three
//! tools get exactly this input, in their own layout:
//!
//! | tool | what is timed | input it is given |
//! |---|---|---|
//! | `sweeptin` | `triangulate_cdt(&pts, &segs, &Options::default())` | `&[[f64; 3]]`, `&[[u32; 2]]` |
//! | `spade` | `ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(pts, edges)` | `Vec<Point2<f64>>`, `Vec<[usize; 2]>` (moved in) |
//! | `cdt` | `Triangulation::new_with_edges(&pts, &edges)`, one `step()` per point, `triangles().collect()` | `&[(f64, f64)]`, `&[(usize, usize)]` |
//!
//! The conversion into each layout (a plain element-wise copy) is not timed.
//!
//! `cdt`'s public `triangulate_with_edges` treats the edges as closed boundaries and, after the
//! sweep, erases every triangle outside them by even-odd flood fill. Contour lines are open, so
//! its output would not be comparable. The runner therefore makes the same calls as
//! `triangulate_with_edges` but stops one step early: it runs exactly one `step()` per distinct
//! point after the seed triangle, and leaves out the last `step()` (the flood fill). The result
//! is then the whole constrained triangulation of the convex hull, whose triangle count can be
//! compared. Leaving out the flood fill can only make cdt faster.
//!
//! A panic inside a tool is caught and reported (`"error"` in the JSON line), not hidden.
//! Peak memory: as in `examples/bench_core.rs`, the kernel's peak-RSS mark is reset
//! (`/proc/self/clear_refs`) once the input is in the tool's layout, and `VmHWM` is read after the
//! first repetition.

use anyhow::{Context, Result, bail};
use std::io::Write;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;
use sweeptin::breaklines::clean::{CleanOptions, clean};
use sweeptin::synth;

/// First 8 bytes of a prepared input file.
const MAGIC: &[u8; 8] = b"SWCDT\0\0\x01";

/// Command-line arguments.
struct Args {
    pos: Vec<String>,
    repeat: usize,
    seed: u64,
    points: usize,
    lines: Option<usize>,
    threads: Option<usize>,
}

fn usage() -> String {
    "usage: bench_cdt prep <contours|coastline> FILE [--points N] [--lines N] [--seed S] [--repeat R]\n       \
     bench_cdt <sweeptin|spade|cdt> FILE [--repeat R] [--threads T]"
        .to_string()
}

fn parse_args() -> Result<Args> {
    let mut a = Args {
        pos: Vec::new(),
        repeat: 3,
        seed: 1,
        points: 1_000_000,
        lines: None,
        threads: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(s) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .with_context(|| format!("{name} needs a value\n{}", usage()))
        };
        match s.as_str() {
            "--repeat" => a.repeat = value("--repeat")?.parse::<usize>()?.max(1),
            "--seed" => a.seed = value("--seed")?.parse()?,
            "--points" => a.points = parse_count(&value("--points")?)?,
            "--lines" => a.lines = Some(parse_count(&value("--lines")?)?),
            "--threads" => a.threads = Some(value("--threads")?.parse()?),
            "-h" | "--help" => bail!("{}", usage()),
            _ => a.pos.push(s),
        }
    }
    let want = if a.pos.first().map(String::as_str) == Some("prep") {
        3
    } else {
        2
    };
    if a.pos.len() != want {
        bail!("{}", usage());
    }
    Ok(a)
}

/// A field of `/proc/self/status` in bytes (`VmHWM`, `VmRSS`).
fn status_bytes(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets the peak-RSS mark to the current RSS (Linux ≥ 4.0).
fn reset_hwm() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The cleaned input: vertices (graph vertices, then points), segments, and the number of
/// distinct `(x, y)` positions among the vertices.
struct Prepared {
    pts: Vec<[f64; 3]>,
    segs: Vec<[u32; 2]>,
    distinct: u64,
}

fn write_prepared(path: &str, p: &Prepared) -> Result<()> {
    let file = std::fs::File::create(path).with_context(|| format!("cannot create {path}"))?;
    let mut w = std::io::BufWriter::new(file);
    w.write_all(MAGIC)?;
    for n in [p.pts.len() as u64, p.segs.len() as u64, p.distinct] {
        w.write_all(&n.to_le_bytes())?;
    }
    for v in p.pts.iter().flatten() {
        w.write_all(&v.to_le_bytes())?;
    }
    for i in p.segs.iter().flatten() {
        w.write_all(&i.to_le_bytes())?;
    }
    w.flush().with_context(|| format!("cannot write {path}"))?;
    Ok(())
}

fn read_prepared(path: &str) -> Result<Prepared> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {path}"))?;
    if bytes.len() < 32 || &bytes[..8] != MAGIC {
        bail!("{path} is not a bench_cdt input (run `bench_cdt prep` first)");
    }
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"));
    let (np, ns, distinct) = (u64_at(8) as usize, u64_at(16) as usize, u64_at(24));
    if bytes.len() != 32 + np * 24 + ns * 8 {
        bail!("{path} has the wrong size for {np} points and {ns} segments");
    }
    let f = |c: &[u8]| f64::from_le_bytes(c.try_into().expect("8 bytes"));
    let u = |c: &[u8]| u32::from_le_bytes(c.try_into().expect("4 bytes"));
    let pts = bytes[32..32 + np * 24]
        .chunks_exact(24)
        .map(|c| [f(&c[..8]), f(&c[8..16]), f(&c[16..])])
        .collect();
    let segs = bytes[32 + np * 24..]
        .chunks_exact(8)
        .map(|c| [u(&c[..4]), u(&c[4..])])
        .collect();
    Ok(Prepared {
        pts,
        segs,
        distinct,
    })
}

/// Generates, cleans (timed) and writes one input.
fn prep(args: &Args) -> Result<()> {
    let (name, path) = (args.pos[1].as_str(), args.pos[2].as_str());
    let t0 = Instant::now();
    let (lines, points) = match name {
        "contours" => (
            synth::contours(args.lines.unwrap_or(1_000_000), args.seed),
            synth::contour_points(args.points, args.seed),
        ),
        "coastline" => (
            synth::coastline(args.lines.unwrap_or(2_900_000), args.seed),
            synth::coastline_points(args.points, args.seed),
        ),
        _ => bail!("unknown input {name:?}\n{}", usage()),
    };
    let generate_s = t0.elapsed().as_secs_f64();
    let polylines = lines.len();
    let line_vertices: usize = lines.iter().map(Vec::len).sum();
    let line_segments: usize = lines.iter().map(|l| l.len().saturating_sub(1)).sum();
    let mut clean_times = Vec::with_capacity(args.repeat);
    let mut pslg = None;
    for _ in 0..args.repeat {
        drop(pslg.take());
        let t = Instant::now();
        let g = clean(&lines, &CleanOptions::default()).context("clean")?;
        clean_times.push(t.elapsed().as_secs_f64());
        pslg = Some(g);
    }
    let pslg = pslg.expect("repeat >= 1");
    drop(lines);
    pslg.check_planar()
        .map_err(|e| anyhow::anyhow!("cleaned lines are not planar: {e}"))?;
    let graph_vertices = pslg.vertices.len();
    let mut pts = pslg.vertices;
    pts.extend_from_slice(&points);
    let mut keys: Vec<(u64, u64)> = pts
        .iter()
        .map(|p| ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    let prepared = Prepared {
        pts,
        segs: pslg.segments,
        distinct: keys.len() as u64,
    };
    write_prepared(path, &prepared)?;
    let line = serde_json::json!({
        "input": name,
        "seed": args.seed,
        "generate_s": generate_s,
        "polylines": polylines,
        "line_vertices": line_vertices,
        "line_segments": line_segments,
        "graph_vertices": graph_vertices,
        "points": points.len(),
        "vertices": prepared.pts.len(),
        "distinct": prepared.distinct,
        "segments": prepared.segs.len(),
        "clean_min_s": clean_times.iter().copied().fold(f64::INFINITY, f64::min),
        "clean_times_s": clean_times,
        "clean_stats": pslg.stats,
        "threads": rayon::current_num_threads(),
    });
    println!("{line}");
    Ok(())
}

/// One tool's input, in its own layout.
enum Input {
    Sweeptin(Vec<[f64; 3]>, Vec<[u32; 2]>),
    Spade(Vec<spade::Point2<f64>>, Vec<[usize; 2]>),
    Cdt(Vec<(f64, f64)>, Vec<(usize, usize)>, u64),
}

impl Input {
    fn new(tool: &str, p: Prepared) -> Result<Input> {
        Ok(match tool {
            "sweeptin" => Input::Sweeptin(p.pts, p.segs),
            "spade" => Input::Spade(
                p.pts
                    .iter()
                    .map(|q| spade::Point2::new(q[0], q[1]))
                    .collect(),
                p.segs
                    .iter()
                    .map(|s| [s[0] as usize, s[1] as usize])
                    .collect(),
            ),
            "cdt" => Input::Cdt(
                p.pts.iter().map(|q| (q[0], q[1])).collect(),
                p.segs
                    .iter()
                    .map(|s| (s[0] as usize, s[1] as usize))
                    .collect(),
                p.distinct,
            ),
            _ => bail!("unknown tool {tool:?}\n{}", usage()),
        })
    }

    fn bytes(&self) -> usize {
        use std::mem::size_of_val;
        match self {
            Input::Sweeptin(p, s) => size_of_val(p.as_slice()) + size_of_val(s.as_slice()),
            Input::Spade(p, s) => size_of_val(p.as_slice()) + size_of_val(s.as_slice()),
            Input::Cdt(p, s, _) => size_of_val(p.as_slice()) + size_of_val(s.as_slice()),
        }
    }
}

/// What a run gave: triangle count, constraint edges in the result (when the tool says), and the
/// result itself (dropped outside the timed region).
struct Done {
    triangles: usize,
    constraints: Option<usize>,
    _result: Box<dyn std::any::Any>,
}

/// The timed part. Spade's input is moved out.
fn run(input: &mut Input) -> Result<Done, String> {
    match input {
        Input::Sweeptin(pts, segs) => {
            let t = sweeptin::triangulate_cdt(pts, segs, &sweeptin::Options::default())
                .map_err(|e| e.to_string())?;
            if t.constraint_stats.crossing_skipped > 0 {
                return Err(format!(
                    "{} segments skipped as crossing",
                    t.constraint_stats.crossing_skipped
                ));
            }
            Ok(Done {
                triangles: t.triangles.len(),
                constraints: None,
                _result: Box::new(t),
            })
        }
        Input::Spade(pts, segs) => {
            use spade::Triangulation as _;
            let t = spade::ConstrainedDelaunayTriangulation::<spade::Point2<f64>>::bulk_load_cdt(
                std::mem::take(pts),
                std::mem::take(segs),
            )
            .map_err(|e| format!("{e:?}"))?;
            Ok(Done {
                triangles: t.num_inner_faces(),
                constraints: Some(t.num_constraints()),
                _result: Box::new(t),
            })
        }
        Input::Cdt(pts, segs, distinct) => {
            // What `cdt::triangulate_with_edges` does, without its last step (module docs).
            let mut t = cdt::Triangulation::new_with_edges(pts, segs.as_slice())
                .map_err(|e| e.to_string())?;
            for _ in 3..*distinct {
                t.step().map_err(|e| e.to_string())?;
            }
            if t.done() {
                return Err("cdt finished early (it merged points sweeptin keeps apart)".into());
            }
            let tris: Vec<(usize, usize, usize)> = t.triangles().collect();
            Ok(Done {
                triangles: tris.len(),
                constraints: None,
                _result: Box::new((t, tris)),
            })
        }
    }
}

/// Runs `tool` `--repeat` times on the input in `FILE`, one JSON line out.
fn bench(args: &Args) -> Result<()> {
    let (tool, path) = (args.pos[0].as_str(), args.pos[1].as_str());
    let mut times = Vec::new();
    let mut peaks = Vec::new();
    let (mut triangles, mut constraints, mut input_bytes) = (0, None, 0);
    let (mut vertices, mut segments) = (0, 0);
    let mut error = None;
    let mut hwm_reset = true;
    for _ in 0..args.repeat {
        let p = read_prepared(path)?;
        (vertices, segments) = (p.pts.len(), p.segs.len());
        let mut input = Input::new(tool, p)?;
        input_bytes = input.bytes();
        hwm_reset &= reset_hwm();
        let t0 = Instant::now();
        let done = catch_unwind(AssertUnwindSafe(|| run(&mut input)));
        let dt = t0.elapsed().as_secs_f64();
        let done = match done {
            Ok(Ok(d)) => d,
            Ok(Err(e)) => {
                error = Some(format!("error after {dt:.3} s: {e}"));
                break;
            }
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "(no message)".into());
                error = Some(format!("panic after {dt:.3} s: {msg}"));
                break;
            }
        };
        peaks.push(status_bytes("VmHWM").unwrap_or(0));
        times.push(dt);
        triangles = done.triangles;
        constraints = done.constraints;
        drop(done);
        drop(input);
    }
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let line = serde_json::json!({
        "tool": tool,
        "file": path,
        "threads": rayon::current_num_threads(),
        "repeat": args.repeat,
        "vertices": vertices,
        "segments": segments,
        "min_s": sorted.first(),
        "median_s": sorted.get(sorted.len() / 2),
        "first_s": times.first(),
        "times_s": times,
        "triangles": triangles,
        "constraints": constraints,
        "input_bytes": input_bytes,
        "peak_rss_bytes": peaks.first(),
        "peaks_bytes": peaks,
        "hwm_reset": hwm_reset,
        "error": error,
    });
    println!("{line}");
    Ok(())
}

fn main() -> Result<()> {
    let args = parse_args()?;
    if let Some(t) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("cannot build the thread pool")?;
    }
    if args.pos[0] == "prep" {
        prep(&args)
    } else {
        bench(&args)
    }
}

fn parse_count(s: &str) -> Result<usize> {
    sweeptin::synth::parse_count(s)
        .with_context(|| format!("bad count {s:?} (like 1000, 100k, 4M)"))
}
