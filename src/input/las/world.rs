//! From a file's stored integers to real-world doubles, the same for every encoding of a point.
//!
//! A LAS file stores `real = offset + scale × N` per axis, with its own scale and offset. The
//! reader turns every point into real-world doubles **once, file by file**, so files with any
//! scales and offsets combine into one point set (no common integer lattice is needed, and
//! nothing overflows 32 bits).
//!
//! The double is the one **nearest to the decimal value** the file means: scales and offsets are
//! decimals in practice (`0.01`, `0.00025`, `511500.025`), so when `scale = S / 10^k` and
//! `offset = O / 10^k` for integers `S`, `O` (checked exactly: the doubles round-trip), the value
//! is `(S × N + O) / 10^k`, an exact integer divided by an exact power of ten, which IEEE
//! division rounds correctly. The result depends only on the point, not on how its file encodes
//! it: a tile stored at 1 cm with offset 0 and a copy re-quantised at 1 mm with offset 0.005 give
//! the same doubles, hence the same triangulation and the same output bytes. (The textbook
//! `offset + scale × N` rounds twice and can land one unit in the last place away, differently
//! for each encoding: `0.01 × 3` is `0.030000000000000002`.) Scales that are no short decimal
//! fall back to `offset + scale × N`.

use serde::Serialize;

/// Largest decimal exponent tried (`10^k` must be an exact double: `k <= 22`).
const MAX_DECIMALS: i32 = 15;
/// Largest decimal scale numerator: `S × N` with `|N| < 2^31` stays below `2^52`.
const MAX_NUMERATOR: i64 = 1 << 21;
/// Largest decimal offset numerator: `S × N + O` stays below `2^53`, so it is an exact double.
const MAX_OFFSET: i64 = 1 << 52;

/// A file's scale and offset per axis (the LAS header's), and how its integers become
/// real-world doubles (see the [module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Quantization {
    /// Scale factors for x, y, z.
    pub scale: [f64; 3],
    /// Offsets for x, y, z.
    pub offset: [f64; 3],
    #[serde(skip)]
    decimal: [Option<Decimal>; 3],
}

/// `value = (s × N + o) / 10^k`, exactly rounded.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Decimal {
    s: i64,
    o: i64,
    pow: f64,
}

impl Decimal {
    /// The shortest decimal form of `scale` and `offset`, when both are short decimals.
    fn of(scale: f64, offset: f64) -> Option<Decimal> {
        let mut pow = 1.0;
        for _ in 0..=MAX_DECIMALS {
            let (s, o) = ((scale * pow).round(), (offset * pow).round());
            if s >= 1.0
                && s <= MAX_NUMERATOR as f64
                && o.abs() < MAX_OFFSET as f64
                && s / pow == scale
                && o / pow == offset
            {
                return Some(Decimal {
                    s: s as i64,
                    o: o as i64,
                    pow,
                });
            }
            pow *= 10.0;
        }
        None
    }
}

impl Quantization {
    /// The quantization of a header's scale and offset.
    pub fn new(scale: [f64; 3], offset: [f64; 3]) -> Quantization {
        Quantization {
            scale,
            offset,
            decimal: std::array::from_fn(|a| Decimal::of(scale[a], offset[a])),
        }
    }

    /// Real-world coordinate of integer `n` on `axis` (0 = x, 1 = y, 2 = z).
    #[inline]
    pub fn axis_to_world(&self, axis: usize, n: i32) -> f64 {
        match self.decimal[axis] {
            Some(d) => (d.s * i64::from(n) + d.o) as f64 / d.pow,
            None => self.offset[axis] + self.scale[axis] * f64::from(n),
        }
    }

    /// Real-world `[x, y, z]` of stored integers (`-0.0` becomes `0.0`).
    #[inline]
    pub fn to_world(&self, n: [i32; 3]) -> [f64; 3] {
        [
            self.axis_to_world(0, n[0]) + 0.0,
            self.axis_to_world(1, n[1]) + 0.0,
            self.axis_to_world(2, n[2]) + 0.0,
        ]
    }

    /// Decimals needed to print every value of `axis` exactly (the scale's and offset's, at
    /// most 9 for scales that are no short decimal).
    pub fn decimals(&self, axis: usize) -> usize {
        match self.decimal[axis] {
            Some(d) => d.pow.log10().round() as usize,
            None => 9,
        }
    }

    /// `v` rounded to the file's precision on `axis` (for printing header values without
    /// binary noise: `-0.5680000000000001` is `-0.568` at 1 mm).
    pub fn round(&self, axis: usize, v: f64) -> f64 {
        match self.decimal[axis] {
            Some(d) => ((v * d.pow).round() / d.pow) + 0.0,
            None => v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_forms() {
        let q = Quantization::new([0.01, 0.00025, 0.001], [511500.025, 5270000.0, 0.0]);
        assert_eq!(q.decimal[0].map(|d| (d.s, d.o)), Some((10, 511500025)));
        assert_eq!(q.decimal[1].map(|d| (d.s, d.o)), Some((25, 527000000000)));
        assert_eq!(q.decimal[2].map(|d| (d.s, d.o)), Some((1, 0)));
        assert_eq!((q.decimals(0), q.decimals(1), q.decimals(2)), (3, 5, 3));
        // A binary scale with no short decimal form falls back to offset + scale × N.
        let b = Quantization::new([1.0 / 3.0; 3], [0.0; 3]);
        assert_eq!(b.decimal, [None; 3]);
        assert_eq!(b.axis_to_world(0, 3), 1.0);
    }

    #[test]
    fn the_nearest_double_whatever_the_encoding() {
        // 0.01 × 3 = 0.030000000000000002 in doubles; the decimal form gives 0.03.
        let cm = Quantization::new([0.01; 3], [0.0; 3]);
        assert_eq!(cm.axis_to_world(0, 3), 0.03);
        // The same point at 1 mm with offset 0.005, and at 1 cm with ARSO's 0.005 shift.
        let mm = Quantization::new([0.001; 3], [0.005; 3]);
        let arso = Quantization::new([0.01; 3], [511500.025; 3]);
        for n in [-77_053_015i32, -1, 0, 1, 3, 77_053_015, 62_776_012] {
            let want: f64 = format!("{}e-2", n).parse().unwrap();
            assert_eq!(cm.axis_to_world(0, n), want, "{n}");
            // n cm = 0.005 + 0.001 × (10 n - 5)
            assert_eq!(mm.axis_to_world(0, 10 * n - 5), want, "{n}");
        }
        // 511500.025 + 0.01 × N is the decimal 511500.025 + N/100 rounded once.
        assert_eq!(arso.axis_to_world(0, -50_013), 510_999.895);
        assert_eq!(cm.to_world([0, 0, 0]), [0.0; 3]);
        assert!(cm.to_world([0, 0, 0])[0].is_sign_positive());
    }

    #[test]
    fn rounding_for_display() {
        let q = Quantization::new([0.001; 3], [0.0; 3]);
        assert_eq!(q.round(2, -0.5680000000000001), -0.568);
        assert_eq!(q.round(2, -0.0), 0.0);
        assert!(q.round(2, -0.0).is_sign_positive());
    }
}
