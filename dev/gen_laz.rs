//! Writes `synth::lidar_like(n, seed)` as a LAZ (or LAS) file, for the streaming benchmark:
//! `cargo run --release --example gen_laz -- 10M /tmp/lidar10m.laz [--seed 1]`.
//! Points keep the generator's acquisition order (scan rows, then the second flight line), with
//! LAS scale 0.01 and the generator's offsets; the integers are exactly the generated coordinates.
//! `--strip K` cuts the square tile into K horizontal bands (whole metres) and lays them side by
//! side along x: a corridor K² times wider than tall, with the same density and scan pattern.
//! `--offset DX,DY` moves the tile by whole metres (the LAS offsets move with it), so that several
//! files with other seeds make a mosaic of generated tiles (`scripts/bench-billion.sh`).

use las::{Builder, Point, Transform, Vector, Writer};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(
        args.len() >= 3,
        "usage: gen_laz <n> <out.laz|out.las> [--seed S] [--strip K] [--offset DX,DY]"
    );
    let n = sweeptin::synth::parse_count(&args[1]).expect("a count like 10M");
    let seed = args
        .iter()
        .position(|a| a == "--seed")
        .map_or(1, |i| args[i + 1].parse().expect("seed"));
    let strip = args
        .iter()
        .position(|a| a == "--strip")
        .map_or(1, |i| args[i + 1].parse::<u32>().expect("strip factor"));
    let (dx, dy) = args
        .iter()
        .position(|a| a == "--offset")
        .map_or((0.0, 0.0), |i| {
            let v: Vec<f64> = args[i + 1]
                .split(',')
                .map(|s| s.parse().expect("offset DX,DY in whole metres"))
                .collect();
            assert!(
                v.len() == 2 && v.iter().all(|d| d.fract() == 0.0),
                "offset DX,DY in whole metres"
            );
            (v[0], v[1])
        });
    let mut pts = sweeptin::synth::lidar_like(n, seed);
    if strip > 1 {
        let (y0, x0) = (sweeptin::synth::LIDAR_Y0, sweeptin::synth::LIDAR_X0);
        let side = pts.iter().map(|p| p[1] - y0).fold(0.0, f64::max);
        let width = pts.iter().map(|p| p[0] - x0).fold(0.0, f64::max);
        let band = (side / f64::from(strip)).ceil();
        for p in &mut pts {
            let k = ((p[1] - y0) / band).floor();
            // Shifts by whole metres: the 1 cm grid of the coordinates is kept exactly.
            p[0] += k * (width + 1.0).ceil();
            p[1] -= k * band;
        }
    }
    // Whole metres: the 1 cm grid of the coordinates is kept exactly.
    for p in &mut pts {
        p[0] += dx;
        p[1] += dy;
    }
    let mut b = Builder::from((1, 2));
    b.point_format = las::point::Format::new(1)?;
    b.transforms = Vector {
        x: Transform {
            scale: 0.01,
            offset: sweeptin::synth::LIDAR_X0 + dx,
        },
        y: Transform {
            scale: 0.01,
            offset: sweeptin::synth::LIDAR_Y0 + dy,
        },
        z: Transform {
            scale: 0.01,
            offset: 0.0,
        },
    };
    b.generating_software = "sweeptin gen_laz".into();
    let mut w = Writer::from_path(&args[2], b.into_header()?)?;
    for (i, p) in pts.iter().enumerate() {
        w.write_point(Point {
            x: p[0],
            y: p[1],
            z: p[2],
            gps_time: Some(i as f64 * 1e-5),
            classification: las::point::Classification::Ground,
            return_number: 1,
            number_of_returns: 1,
            ..Default::default()
        })?;
    }
    w.close()?;
    eprintln!("wrote {n} points to {}", args[2]);
    Ok(())
}
