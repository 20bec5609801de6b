//! Arbitrary `f64` points: magnitudes from 2^-40 to 2^23 with 32 random mantissa bits (general
//! position, compared with spade when the Delaunay triangulation is unique), or raw bit patterns
//! (NaN, infinities, out-of-range values: the right error, never a panic).
#![no_main]

use libfuzzer_sys::fuzz_target;

fn coord(c: &[u8], e0: i32, spread: u8) -> f64 {
    let m = u32::from_le_bytes([c[1], c[2], c[3], c[4]]) as f64 / 4_294_967_296.0;
    let e = e0 + (c[0] & 0x7f) as i32 % (spread as i32 + 1);
    let v = (1.0 + m) * 2f64.powi(e);
    if c[0] & 0x80 != 0 { -v } else { v }
}

fuzz_target!(|data: &[u8]| {
    let (h0, h1, rest) = match data {
        [a, b, rest @ ..] => (*a, *b, rest),
        _ => return,
    };
    if h1 & 0x80 != 0 {
        // Raw bit patterns.
        let pts: Vec<[f64; 3]> = rest
            .chunks_exact(16)
            .enumerate()
            .map(|(i, c)| {
                let x = f64::from_le_bytes(c[..8].try_into().unwrap());
                let y = f64::from_le_bytes(c[8..].try_into().unwrap());
                [x, y, i as f64]
            })
            .collect();
        let first_bad = pts
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()));
        match (first_bad, sweeptin::triangulate(&pts, &Default::default())) {
            (Some(i), Err(sweeptin::Error::NonFinite { index, .. })) => assert_eq!(index, i as u64),
            (Some(_), other) => panic!(
                "non-finite input gave {:?}",
                other.map(|t| t.triangles.len())
            ),
            (None, _) => sweeptin_fuzz::check(&pts, true),
        }
        return;
    }
    let e0 = (h0 % 64) as i32 - 40;
    let spread = h1 % 8;
    let pts: Vec<[f64; 3]> = rest
        .chunks_exact(10)
        .enumerate()
        .map(|(i, c)| {
            [
                coord(&c[..5], e0, spread),
                coord(&c[5..], e0, spread),
                i as f64,
            ]
        })
        .collect();
    sweeptin_fuzz::check(&pts, true);
});
