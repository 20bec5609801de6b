//! Points on small integer grids, rotated grids rounded to `f32` or to 1 mm, UTM offsets, scaled
//! grids and cocircular lattice rings: ties, duplicates and collinear runs really happen.
#![no_main]

use libfuzzer_sys::fuzz_target;

/// Lattice points on the circle of radius 325 (many Pythagorean representations).
fn ring(r: i64) -> Vec<(i64, i64)> {
    let mut v = Vec::new();
    for x in -r..=r {
        let y2 = r * r - x * x;
        let y = (y2 as f64).sqrt() as i64;
        if y * y == y2 {
            v.push((x, y));
            if y != 0 {
                v.push((x, -y));
            }
        }
    }
    v
}

fn points(data: &[u8]) -> Vec<[f64; 3]> {
    let (mode, param, rest) = match data {
        [m, p, rest @ ..] => (*m, *p, rest),
        _ => return Vec::new(),
    };
    let side = 2 + (param % 15) as u32;
    let angle = param as f64 * std::f64::consts::FRAC_PI_2 / 256.0;
    let circle = ring(325);
    let mut out = Vec::new();
    for (i, c) in rest.chunks_exact(2).enumerate() {
        let (a, b) = (c[0] as u32, c[1] as u32);
        let (x, y) = match mode % 8 {
            0 => ((a % side) as f64, (b % side) as f64),
            1 => (a as f64, b as f64),
            2 | 3 => {
                let (u, v) = ((a % 16) as f64, (b % 16) as f64);
                let (x, y) = (
                    u * angle.cos() - v * angle.sin(),
                    u * angle.sin() + v * angle.cos(),
                );
                if mode % 8 == 2 {
                    (x as f32 as f64, y as f32 as f64)
                } else {
                    ((x * 370.0).round() / 1000.0, (y * 370.0).round() / 1000.0)
                }
            }
            4 => (
                500_000.0 + (a % side) as f64 * 0.001 * (1 + param / 16) as f64,
                4_000_000.0 + (b % side) as f64 * 0.001 * (1 + param / 16) as f64,
            ),
            5 => {
                let s = 10f64.powi((param % 19) as i32 - 9);
                ((a % side) as f64 * s, (b % side) as f64 * s)
            }
            6 => {
                let (u, v) = if a & 1 == 0 {
                    circle[(b as usize) % circle.len()]
                } else {
                    (((a >> 1) % 9) as i64 * 50 - 200, (b % 9) as i64 * 50 - 200)
                };
                (u as f64, v as f64)
            }
            _ => {
                // Long runs: horizontal, vertical and diagonal lines through the grid.
                let t = (b % side) as f64;
                match a % 4 {
                    0 => (t, (a / 4 % 3) as f64),
                    1 => ((a / 4 % 3) as f64, t),
                    2 => (t, t),
                    _ => (t, side as f64 - t),
                }
            }
        };
        out.push([x, y, i as f64]);
    }
    out
}

fuzz_target!(|data: &[u8]| {
    let pts = points(data);
    sweeptin_fuzz::check(&pts, false);
});
