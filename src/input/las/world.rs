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

/// One decimal lattice for the points of several files, so that a point is three unsigned 32-bit
/// integers instead of three doubles (the tiles' block index stores points this way: half the
/// bytes written to and read from temporary files).
///
/// Every file's scale and offset must be short decimals ([`Quantization`]'s decimal form, with
/// `10^k_f`) and its header must bound its points (the reader refuses a point outside its
/// header's box rounded out to the file's integers and [`HEADER_SLACK`] more: `PointCheck`).
/// With `k` the largest `k_f`, a point's
/// value on an axis is `K / 10^k` for an integer `K` (`(S × N + O) × 10^(k − k_f)`), and its
/// double `x` is that quotient correctly rounded. Then `x × 10^k`, rounded, is `K` again when
/// `|K| < 2^51` (two roundings of relative error `2^-53` each move it by less than a half), and
/// `K / 10^k`, rounded once, is `x` again (the same quotient, `K` and `10^k` exact doubles): so
/// [`Lattice::encode`] and [`Lattice::decode`] round-trip every point bit for bit. Stored is
/// `K − base` (the box's lower corner, with a margin), which must fit in 32 bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Lattice {
    /// `10^k`.
    pow: f64,
    /// `K` of stored zero, per axis.
    base: [i64; 3],
    /// Stored integers of the box's upper corner, per axis.
    extent: [u32; 3],
}

/// Integers of its file a point may lie beyond its header's box rounded out to them, and still
/// be read (the reader's check, `PointCheck`, and the lattice's margin share it).
pub(crate) const HEADER_SLACK: i64 = 1;

/// `|K|` below which [`Lattice::encode`] is exact.
const MAX_LATTICE: f64 = (1u64 << 51) as f64;

impl Lattice {
    /// The lattice of files with quantizations and header boxes `files` (`[min, max]` per
    /// axis), or `None` when a scale or offset is no short decimal, a box is not usable (empty,
    /// all zero, not finite) or the points would not fit in 32 bits per axis.
    pub(crate) fn of(files: &[(Quantization, [[f64; 3]; 2])]) -> Option<Lattice> {
        let mut pow = 1.0f64;
        let mut scale = 0.0f64;
        for (q, b) in files {
            if !(super::header::Bounds3 {
                min: b[0],
                max: b[1],
            })
            .usable()
            {
                return None;
            }
            for d in &q.decimal {
                pow = pow.max(d.as_ref()?.pow);
            }
            scale = q.scale.iter().fold(scale, |m, &v| m.max(v));
        }
        // Rounding the box out to a file's integers, the slack, and one more for the doubles.
        let margin = (HEADER_SLACK + 2) as f64 * scale;
        let (mut base, mut extent) = ([0i64; 3], [0u32; 3]);
        for k in 0..3 {
            let lo = files
                .iter()
                .map(|f| f.1[0][k])
                .fold(f64::INFINITY, f64::min)
                - margin;
            let hi = files
                .iter()
                .map(|f| f.1[1][k])
                .fold(f64::NEG_INFINITY, f64::max)
                + margin;
            let (lo, hi) = ((lo * pow).floor() - 1.0, (hi * pow).ceil() + 1.0);
            if !(lo.abs() < MAX_LATTICE && hi.abs() < MAX_LATTICE && hi - lo < u32::MAX as f64) {
                return None;
            }
            base[k] = lo as i64;
            extent[k] = (hi - lo) as u32;
        }
        Some(Lattice { pow, base, extent })
    }

    /// The box of the lattice in `x` and `y` (`[xmin, ymin, xmax, ymax]`): the headers' boxes
    /// with a margin, holding every point the reader lets through.
    pub(crate) fn xy_box(&self) -> [f64; 4] {
        let at = |k: usize, q: u32| (self.base[k] + i64::from(q)) as f64 / self.pow;
        [
            at(0, 0),
            at(1, 0),
            at(0, self.extent[0]),
            at(1, self.extent[1]),
        ]
    }

    /// The stored integers of point `p` (a point of one of the files), or `None` when it lies
    /// outside the lattice's box (the reader lets no such point through).
    #[inline]
    pub(crate) fn encode(&self, p: [f64; 3]) -> Option<[u32; 3]> {
        let mut q = [0u32; 3];
        for k in 0..3 {
            let n = (p[k] * self.pow).round() as i64 - self.base[k];
            q[k] = u32::try_from(n).ok().filter(|&n| n <= self.extent[k])?;
        }
        Some(q)
    }

    /// The lattice's numbers (`10^k`, the stored zero and the upper corner per axis), as a
    /// file that stores points on it keeps them ([`crate::tiles::PointStore`]).
    pub(crate) fn parts(&self) -> (f64, [i64; 3], [u32; 3]) {
        (self.pow, self.base, self.extent)
    }

    /// The lattice of [`Lattice::parts`] (`None` for numbers no lattice has).
    pub(crate) fn from_parts(pow: f64, base: [i64; 3], extent: [u32; 3]) -> Option<Lattice> {
        let ok = pow >= 1.0 && pow.is_finite() && base.iter().all(|b| b.unsigned_abs() < 1 << 52);
        ok.then_some(Lattice { pow, base, extent })
    }

    /// The point of stored integers `q`.
    #[inline]
    pub(crate) fn decode(&self, q: [u32; 3]) -> [f64; 3] {
        std::array::from_fn(|k| (self.base[k] + i64::from(q[k])) as f64 / self.pow + 0.0)
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

    #[test]
    fn lattice_round_trips_every_encoding_bit_for_bit() {
        let files = [
            (
                Quantization::new([0.01; 3], [0.0; 3]),
                [[510_000.0, 121_000.0, -20.0], [513_000.0, 124_000.0, 900.0]],
            ),
            (
                Quantization::new([0.01; 3], [511_500.025, 122_499.965, 747.255]),
                [[511_000.0, 122_000.0, 200.0], [512_000.0, 123_000.0, 300.0]],
            ),
            (
                Quantization::new([0.001, 0.00025, 0.001], [0.005, 0.0, -0.5]),
                [[511_200.0, 122_100.0, 0.0], [511_300.0, 122_200.0, 10.0]],
            ),
        ];
        let l = Lattice::of(&files).unwrap();
        assert_eq!(l.pow, 1e5);
        let mut rng = crate::geom::rng::SplitMix64::new(11);
        for (q, b) in &files {
            for _ in 0..20_000 {
                let n: [i32; 3] = std::array::from_fn(|k| {
                    let lo = ((b[0][k] - q.offset[k]) / q.scale[k]).ceil();
                    let hi = ((b[1][k] - q.offset[k]) / q.scale[k]).floor();
                    (lo + (rng.range(0.0, 1.0) * (hi - lo)).floor()) as i32
                });
                let p = q.to_world(n);
                let back = l.decode(l.encode(p).unwrap());
                assert_eq!(back.map(f64::to_bits), p.map(f64::to_bits), "{n:?} {q:?}");
            }
        }
        // Near the bound of exactness: |K| just under 2^51 at 1 mm.
        let far = Quantization::new([0.001; 3], [2.2e12, 2.2e12, 0.0]);
        let fb = [
            [2.2e12, 2.2e12, 0.0],
            [2.2e12 + 1000.0, 2.2e12 + 1000.0, 10.0],
        ];
        let l = Lattice::of(&[(far, fb)]).unwrap();
        for _ in 0..20_000 {
            let n = [
                rng.below(1_000_000) as i32,
                rng.below(1_000_000) as i32,
                rng.below(10_000) as i32,
            ];
            let p = far.to_world(n);
            assert_eq!(
                l.decode(l.encode(p).unwrap()).map(f64::to_bits),
                p.map(f64::to_bits),
                "{n:?}"
            );
        }
        // Zero stays a positive zero.
        let z = Lattice::of(&[(
            Quantization::new([0.01; 3], [0.0; 3]),
            [[-1.0; 3], [1.0; 3]],
        )])
        .unwrap();
        assert!(z.decode(z.encode([0.0; 3]).unwrap())[0].is_sign_positive());
        assert_eq!(
            z.decode(z.encode([-0.03, 0.99, 0.0]).unwrap()),
            [-0.03, 0.99, 0.0]
        );
        // Out of the box, binary scales, unusable headers, too wide a box: no lattice.
        assert_eq!(z.encode([-5.0, 0.0, 0.0]), None);
        assert_eq!(z.encode([5.0, 0.0, 0.0]), None);
        assert_eq!(
            z.encode([1.04, -1.04, 0.0]).map(|q| z.decode(q)),
            Some([1.04, -1.04, 0.0])
        );
        let binary = Quantization::new([1.0 / 1024.0; 3], [0.0; 3]);
        assert_eq!(Lattice::of(&[(binary, [[0.0; 3], [1.0; 3]])]), None);
        let cm = Quantization::new([0.01; 3], [0.0; 3]);
        assert_eq!(Lattice::of(&[(cm, [[0.0; 3], [0.0; 3]])]), None);
        assert_eq!(Lattice::of(&[(cm, [[0.0; 3], [5e7; 3]])]), None);
        assert!(Lattice::of(&[(cm, [[0.0; 3], [4e7; 3]])]).is_some());
    }
}
