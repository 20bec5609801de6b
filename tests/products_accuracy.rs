//! Accuracy on the analytic saddle of Herva (2009), chapter 7.3 (see `tests/support/saddle.rs`
//! and `docs/ACCURACY.md`, section "Terrain products"): the volume against z = 0 and the volume
//! difference against a second surface shrink with N, and the average height error at N = 10000 is
//! the thesis's 0.057 within sampling noise.

use crate::saddle;

use saddle::{interpolation_error, points, saddle, tilted, tin, volume, volume_difference};

#[test]
fn volume_errors_shrink_with_n() {
    let mut plane = Vec::new();
    let mut diff = Vec::new();
    for n in [1000, 10_000] {
        let a = tin(&points(n, 1, saddle));
        let b = tin(&points(n, 2, tilted));
        plane.push(volume(&a).abs());
        diff.push(volume_difference(&a, &b).abs());
    }
    eprintln!("|V| against z = 0: {plane:?}; |ΔV| between surfaces: {diff:?}");
    // The thesis: 447 and 11 (table 7.2), 353 and 5.8 (table 7.3), of a 300 000 m³ box.
    assert!(plane[0] < 3000.0 && plane[1] < 100.0, "{plane:?}");
    assert!(plane[1] < plane[0]);
    assert!(diff[0] < 3000.0 && diff[1] < 100.0, "{diff:?}");
}

#[test]
fn interpolation_error_at_10000_points_matches_the_thesis() {
    let t = tin(&points(10_000, 3, saddle));
    let (avg, max) = interpolation_error(&t, 1000, 4);
    eprintln!("average {avg:.4}, maximum {max:.4}");
    // Thesis: average 0.057 at N = 10000 (0.19 % of the 30 m range).
    assert!((0.045..0.07).contains(&avg), "average error {avg}");
    assert!(max < 0.6, "maximum error {max}");
}
