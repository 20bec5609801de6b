//! One benchmark run of one triangulator on one synthetic input, for `scripts/bench-core.sh`.
//!
//! ```text
//! cargo run --release --example bench_core -- <algo> <dist> <n> [--repeat 3] [--seed 1] [--threads T] [--phases]
//! cargo run --release --example bench_core -- dump <dist> <n> FILE [--seed 1]
//! ```
//!
//! `algo` is `sweeptin`, `delaunator`, `spade` or `cdt`; `dist` is `uniform`, `lidar-like` or
//! `clustered`; `n` accepts `k`/`M` suffixes (`4M` = 4,000,000). Prints one JSON line:
//!
//! `{"algo", "dist", "n", "seed", "threads", "repeat", "median_s", "min_s", "triangles",
//!   "input_bytes", "peak_rss_bytes", "bytes_per_point", "hwm_reset", "times_s", "peaks_bytes"}`
//!
//! Each repetition regenerates the input (not timed), converts it into the algorithm's layout
//! (see `benches/support/peers.rs`), drops everything else, resets the kernel's peak-RSS mark
//! (`echo 5 > /proc/self/clear_refs`), then times only the triangulation. `peak_rss_bytes` is
//! `VmHWM` (from `/proc/self/status`) after the *first* repetition: the input in the algorithm's
//! layout plus everything the algorithm allocated, plus the process's small baseline (about
//! 2 MB). Later repetitions can show more, because the allocator keeps freed memory of the
//! previous one resident (glibc raises its mmap threshold after large frees); all marks are in
//! `peaks_bytes`. For the same reason the first repetition is the slowest (it pays the page
//! faults of fresh memory); `times_s` lists every repetition, the first one is the cold run of a
//! one-shot tool. If the mark cannot be reset it also covers the input generation and
//! `"hwm_reset": false` says so. One process per (algo, dist, n).
//!
//! `--phases` (sweeptin only) adds `"phases_s"`: the first repetition's time split into
//! `prepare` (validation, sort, de-duplication), `sweep` (`Sweep::new` + `run`) and `finish`
//! (hull closing, output), measured by a second, untimed-for-the-total run of the same steps
//! [`sweeptin::triangulate`] takes.
//!
//! `threads` is the size of rayon's pool (only sweeptin uses it, for its sort); set it with
//! `--threads` or `RAYON_NUM_THREADS`.
//!
//! `dump` writes the points' `x, y` as little-endian `f64` pairs (16 bytes per point, no header)
//! for the external peers in `scripts/peers/`.

#[path = "../benches/support/peers.rs"]
mod peers;

use anyhow::{Context, Result, bail};
use peers::{Algo, Dist};
use std::io::Write;
use std::time::Instant;

struct Args {
    first: String,
    dist: Dist,
    n: usize,
    file: Option<String>,
    repeat: usize,
    seed: u64,
    threads: Option<usize>,
    phases: bool,
}

fn usage() -> String {
    "usage: bench_core <sweeptin|delaunator|spade|cdt> <uniform|lidar-like|clustered> <n> \
     [--repeat R] [--seed S] [--threads T] [--phases]\n       bench_core dump <dist> <n> FILE [--seed S]"
        .to_string()
}

fn parse_args() -> Result<Args> {
    let mut pos = Vec::new();
    let (mut repeat, mut seed, mut threads, mut phases) = (3, 1, None, false);
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .with_context(|| format!("{name} needs a value\n{}", usage()))
        };
        match a.as_str() {
            "--repeat" => repeat = value("--repeat")?.parse()?,
            "--seed" => seed = value("--seed")?.parse()?,
            "--threads" => threads = Some(value("--threads")?.parse()?),
            "--phases" => phases = true,
            "-h" | "--help" => bail!("{}", usage()),
            _ => pos.push(a),
        }
    }
    if pos.len() < 3 || pos.len() > 4 || (pos.len() == 4) != (pos[0] == "dump") {
        bail!("{}", usage());
    }
    let dist = Dist::parse(&pos[1])
        .with_context(|| format!("unknown distribution {:?}\n{}", pos[1], usage()))?;
    Ok(Args {
        first: pos[0].clone(),
        dist,
        n: parse_count(&pos[2])?,
        file: pos.get(3).cloned(),
        repeat: repeat.max(1),
        seed,
        threads,
        phases,
    })
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

fn dump(args: &Args) -> Result<()> {
    let path = args.file.as_deref().expect("checked in parse_args");
    let pts = args.dist.generate(args.n, args.seed);
    let file = std::fs::File::create(path).with_context(|| format!("cannot create {path}"))?;
    let mut w = std::io::BufWriter::new(file);
    for p in &pts {
        w.write_all(&p[0].to_le_bytes())?;
        w.write_all(&p[1].to_le_bytes())?;
    }
    w.flush().with_context(|| format!("cannot write {path}"))?;
    Ok(())
}

fn bench(args: &Args, algo: Algo) -> Result<()> {
    let mut times = Vec::with_capacity(args.repeat);
    let mut peaks = Vec::with_capacity(args.repeat);
    let (mut triangles, mut input_bytes, mut hwm_reset) = (0, 0, true);
    for _ in 0..args.repeat {
        let mut input = algo.input(args.dist.generate(args.n, args.seed));
        input_bytes = input.bytes();
        hwm_reset &= reset_hwm();
        let t0 = Instant::now();
        let done = peers::run(&mut input).map_err(anyhow::Error::msg)?;
        let dt = t0.elapsed().as_secs_f64();
        peaks.push(status_bytes("VmHWM").unwrap_or(0));
        triangles = done.triangles;
        times.push(dt);
        drop(done);
        drop(input);
    }
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let peak = peaks[0];
    let mut line = serde_json::json!({
        "algo": algo.name(),
        "dist": args.dist.name(),
        "n": args.n,
        "seed": args.seed,
        "threads": rayon::current_num_threads(),
        "repeat": args.repeat,
        "median_s": median,
        "min_s": sorted[0],
        "triangles": triangles,
        "input_bytes": input_bytes,
        "peak_rss_bytes": peak,
        "bytes_per_point": peak as f64 / args.n.max(1) as f64,
        "hwm_reset": hwm_reset,
        "times_s": times,
        "peaks_bytes": peaks,
    });
    if args.phases && algo == Algo::Sweeptin {
        line["phases_s"] = sweeptin_phases(args.dist.generate(args.n, args.seed))?;
    }
    println!("{line}");
    Ok(())
}

/// The steps of `sweeptin::triangulate`, timed one by one.
fn sweeptin_phases(pts: Vec<[f64; 3]>) -> Result<serde_json::Value> {
    use sweeptin::sort::memory::{DuplicatePolicy, prepare};
    let t0 = Instant::now();
    let prepared = prepare(&pts, DuplicatePolicy::First)?;
    let t1 = Instant::now();
    let mut sweep = sweeptin::sweep::Sweep::new(prepared.xy)?;
    sweep.run()?;
    let t2 = Instant::now();
    let (triangles, _xy, stats) = sweep.finish();
    let vertices: Vec<[f64; 3]> = prepared.index.iter().map(|&i| pts[i as usize]).collect();
    let t3 = Instant::now();
    std::hint::black_box((triangles.len(), vertices.len()));
    Ok(serde_json::json!({
        "prepare": (t1 - t0).as_secs_f64(),
        "sweep": (t2 - t1).as_secs_f64(),
        "finish": (t3 - t2).as_secs_f64(),
        "stats": stats,
    }))
}

fn main() -> Result<()> {
    let args = parse_args()?;
    if let Some(t) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("cannot build the thread pool")?;
    }
    if args.first == "dump" {
        return dump(&args);
    }
    let algo = Algo::parse(&args.first)
        .with_context(|| format!("unknown algorithm {:?}\n{}", args.first, usage()))?;
    bench(&args, algo)
}

fn parse_count(s: &str) -> Result<usize> {
    sweeptin::synth::parse_count(s)
        .with_context(|| format!("bad point count {s:?} (like 1000, 100k, 4M)"))
}
