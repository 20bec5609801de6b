//! Writes a synthetic point set as XYZ text for the memory benchmark (`scripts/bench-memory.sh`):
//! `cargo run --release --example gen_points -- DIST N OUT.xyz [--order O] [--seed S]`.
//! DIST: square (`synth::uniform`), disc, disc-far, kuzmin, lidar (`synth::lidar_like`),
//! clustered, line (`synth::heavy::almost_line`), circle (`synth::ring`, 1 cm apart).
//! O: generated (the default), sorted, reversed, random, tiles, gpstime, octree
//! (`synth::heavy::Order`). Coordinates are printed as the shortest decimals that read back as the
//! same doubles; prints the extent, `xmin ymin xmax ymax`.

use std::io::Write;
use sweeptin::synth::{self, heavy};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(
        args.len() >= 4,
        "usage: gen_points DIST N OUT.xyz [--order O] [--seed S]"
    );
    let n = synth::parse_count(&args[2]).expect("a count like 10M");
    let flag = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .map(|i| args[i + 1].clone())
    };
    let seed: u64 = flag("--seed").map_or(1, |s| s.parse().expect("seed"));
    let order = flag("--order").map_or(heavy::Order::Generated, |o| {
        heavy::Order::from_name(&o)
            .expect("an order: generated, sorted, reversed, random, tiles, gpstime, octree")
    });
    let mut pts = match args[1].as_str() {
        "square" => synth::uniform(n, seed),
        "disc" => heavy::disc(n, seed),
        "disc-far" => heavy::disc_far(n, seed),
        "kuzmin" => heavy::kuzmin(n, seed),
        "lidar" => synth::lidar_like(n, seed),
        "clustered" => synth::clustered(n, seed),
        "line" => heavy::almost_line(n, seed),
        "circle" => synth::ring(n, (n as f64 * 0.01 / std::f64::consts::TAU).max(1.0)),
        d => anyhow::bail!("unknown distribution {d}"),
    };
    heavy::arrange(&mut pts, order, seed);
    let mut out = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(&args[3])?);
    for p in &pts {
        writeln!(out, "{} {} {}", p[0], p[1], p[2])?;
    }
    out.flush()?;
    // The extent, for the benchmark's choice of DEM cell.
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in &pts {
        x0 = x0.min(p[0]);
        y0 = y0.min(p[1]);
        x1 = x1.max(p[0]);
        y1 = y1.max(p[1]);
    }
    println!("{x0} {y0} {x1} {y1}");
    Ok(())
}
