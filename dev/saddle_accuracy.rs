//! Reproduces the trend of Herva (2009), tables 7.2 and 7.3 and section 7.3.4, on the saddle
//! `z = 15 sin(πx/20) − 15 sin(πy/20)` over [0, 100]² (see `tests/support/saddle.rs`), and prints
//! the Markdown tables of `docs/ACCURACY.md`.
//!
//! ```text
//! cargo run --release --example saddle_accuracy [SEEDS]
//! ```

#[path = "../tests/support/saddle.rs"]
mod saddle;

use saddle::{interpolation_error, points, saddle, tilted, tin, volume, volume_difference};

fn main() {
    let seeds: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10);
    println!(
        "Seeds 1..={seeds}; the first seed's value, then mean |value| and max |value| over the seeds.\n"
    );
    println!(
        "| N | triangles | V vs z = 0 (seed 1) | mean \\|V\\| | max \\|V\\| | ΔV between surfaces (seed 1) | mean \\|ΔV\\| | max \\|ΔV\\| | mean height error | max height error |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for n in [1000usize, 2000, 5000, 10_000, 50_000, 100_000] {
        let (mut v, mut d, mut e, mut em) = (Vec::new(), Vec::new(), Vec::new(), 0.0f64);
        let mut triangles = 0;
        for s in 1..=seeds {
            let a = tin(&points(n, 2 * s - 1, saddle));
            let b = tin(&points(n, 2 * s, tilted));
            triangles = a.len();
            v.push(volume(&a));
            d.push(volume_difference(&a, &b));
            let (avg, max) = interpolation_error(&a, 1000, 1000 + s);
            e.push(avg);
            em = em.max(max);
        }
        let mean_abs = |x: &[f64]| x.iter().map(|v| v.abs()).sum::<f64>() / x.len() as f64;
        let max_abs = |x: &[f64]| x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        println!(
            "| {n} | {triangles} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.4} | {:.3} |",
            v[0],
            mean_abs(&v),
            max_abs(&v),
            d[0],
            mean_abs(&d),
            max_abs(&d),
            e.iter().sum::<f64>() / e.len() as f64,
            em
        );
    }
}
