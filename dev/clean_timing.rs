//! Times breakline cleaning on synthetic inputs:
//! `cargo run --release --example clean_timing -- [segments] [contours|coastline|random|roads|all]`
//! (default 1,000,000, all).
//!
//! Inputs: contour lines (no crossings: the common case), a fractal coastline (simple rings), and
//! random short segments (a crossing-heavy stress case), each about `segments` segments; `roads`
//! (`synth::roads`) is also cleaned with each round's pairs found by the plane sweep
//! (`clean_by_sweep`, `--mem 128M`), and says how many items that sweep held at once.
//! `roads-grid` runs `clean()` alone on the roads and `roads-stream` the streamed cleaner alone
//! (`clean_streamed`, `--mem 128M`, its pieces counted as they are read back), one per process,
//! so that `/usr/bin/time -v` measures each one's peak RSS (the polylines, held whole, included);
//! `roads-both` runs both and checks the streamed pieces against `clean()`'s graph, bit for bit.
use std::time::Instant;
use sweeptin::breaklines::clean::{CleanOptions, clean};
use sweeptin::synth::{self, SplitMix64};

fn time(name: &str, lines: &[Vec<[f64; 3]>]) {
    let segs: usize = lines.iter().map(|l| l.len().saturating_sub(1)).sum();
    let t0 = Instant::now();
    let g = clean(lines, &CleanOptions::default()).expect("clean");
    let t = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    g.check_planar().expect("planar");
    let tc = t1.elapsed().as_secs_f64();
    println!(
        "{name}: {} polylines, {segs} segments -> clean {t:.3} s ({:.2} M segments/s), check {tc:.3} s\n  {:?}",
        lines.len(),
        segs as f64 / t / 1e6,
        g.stats
    );
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("a segment count"))
        .unwrap_or(1_000_000);
    let which = std::env::args().nth(2).unwrap_or_else(|| "all".into());
    let run = |name: &str| which == "all" || which == name;
    println!("threads {}", rayon::current_num_threads());
    if run("contours") {
        let t0 = Instant::now();
        let contours = synth::contours(n, 1);
        println!("contours generated in {:.2} s", t0.elapsed().as_secs_f64());
        time("contours", &contours);
    }
    if run("coastline") {
        let t0 = Instant::now();
        let coast = synth::coastline(n, 1);
        println!("coastline generated in {:.2} s", t0.elapsed().as_secs_f64());
        time("coastline", &coast);
    }
    if run("roads") {
        let t0 = Instant::now();
        let roads = synth::roads(n, 1);
        println!("roads generated in {:.2} s", t0.elapsed().as_secs_f64());
        time("roads", &roads);
        let t1 = Instant::now();
        let dir = std::env::temp_dir();
        let (g, s) = sweeptin::breaklines::clean::clean_by_sweep(
            &roads,
            &CleanOptions::default(),
            128 << 20,
            &dir,
        )
        .expect("clean by sweep");
        println!(
            "roads by sweep: {:.3} s, {} segments out, {s:?}",
            t1.elapsed().as_secs_f64(),
            g.segments.len()
        );
    }
    if which == "roads-both" {
        roads_both(n);
        return;
    }
    if which == "roads-grid" || which == "roads-stream" {
        let roads = synth::roads(n, 1);
        let t0 = Instant::now();
        if which == "roads-grid" {
            let g = clean(&roads, &CleanOptions::default()).expect("clean");
            println!(
                "roads, clean(): {:.3} s, {} segments out\n  {:?}",
                t0.elapsed().as_secs_f64(),
                g.segments.len(),
                g.stats
            );
            return;
        }
        let dir = std::env::temp_dir();
        let mut c = sweeptin::breaklines::clean::stream::clean_streamed(
            &roads,
            &CleanOptions::default(),
            128 << 20,
            &dir,
        )
        .expect("streamed clean");
        let pieces = c.by_ref().count();
        assert!(c.take_error().is_none());
        println!(
            "roads, streamed: {:.3} s, {pieces} pieces out, held {:?}\n  {:?}",
            t0.elapsed().as_secs_f64(),
            c.held,
            c.stats
        );
        return;
    }
    if !run("random") {
        return;
    }
    // Random segments about 3 times the mean spacing long: several crossings each.
    let mut rng = SplitMix64::new(9);
    let side = 1000.0;
    let len = 3.0 * side / (n as f64).sqrt();
    let random: Vec<Vec<[f64; 3]>> = (0..n)
        .map(|_| {
            let a = [
                rng.range(0.0, side),
                rng.range(0.0, side),
                rng.range(0.0, 10.0),
            ];
            let t = rng.range(0.0, std::f64::consts::TAU);
            let b = [
                a[0] + len * t.cos(),
                a[1] + len * t.sin(),
                rng.range(0.0, 10.0),
            ];
            vec![a, b]
        })
        .collect();
    time("random", &random);
}

/// `clean()` and `clean_streamed` on the same roads: every piece equal, bit for bit.
fn roads_both(n: usize) {
    use sweeptin::geom::predicates::sweep_cmp;
    let roads = synth::roads(n, 1);
    let g = clean(&roads, &CleanOptions::default()).expect("clean");
    let bits =
        |a: [f64; 3], b: [f64; 3], line: u32| (a.map(f64::to_bits), b.map(f64::to_bits), line);
    let xy = |p: [f64; 3]| [p[0], p[1]];
    let mut used = vec![false; g.vertices.len()];
    let mut want: Vec<([f64; 3], [f64; 3], u32)> = Vec::with_capacity(g.segments.len());
    for (s, &line) in g.segments.iter().zip(&g.lines) {
        used[s[0] as usize] = true;
        used[s[1] as usize] = true;
        let (mut a, mut b) = (g.vertices[s[0] as usize], g.vertices[s[1] as usize]);
        if sweep_cmp(xy(a), xy(b)).is_gt() {
            std::mem::swap(&mut a, &mut b);
        }
        want.push((a, b, line));
    }
    for (v, _) in g.vertices.iter().zip(&used).filter(|(_, u)| !**u) {
        want.push((*v, *v, 0));
    }
    want.sort_by(|a, b| {
        sweep_cmp(xy(a.0), xy(b.0))
            .then(sweep_cmp(xy(a.1), xy(b.1)))
            .then((a.0 == a.1).cmp(&(b.0 == b.1)))
            .then(a.2.cmp(&b.2))
    });
    let dir = std::env::temp_dir();
    let mut c = sweeptin::breaklines::clean::stream::clean_streamed(
        &roads,
        &CleanOptions::default(),
        128 << 20,
        &dir,
    )
    .expect("streamed clean");
    let mut k = 0usize;
    for p in c.by_ref() {
        let w = want.get(k).expect("more pieces than clean() has");
        assert_eq!(bits(p.lo, p.hi, p.line), bits(w.0, w.1, w.2), "piece {k}");
        k += 1;
    }
    assert!(c.take_error().is_none());
    assert_eq!(k, want.len(), "fewer pieces than clean() has");
    assert_eq!(c.stats, g.stats);
    assert_eq!(c.warnings, g.warnings);
    println!(
        "roads-both: {k} pieces, counters and warnings equal; held {:?}",
        c.held
    );
}
