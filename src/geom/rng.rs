//! The crate's one small deterministic random generator: SplitMix64.
//!
//! The library draws with it where a run must be reproducible (the leave-one-out sample of
//! `crossval`); tests and the synthetic data sets (`synth`, which re-exports it) use it
//! for everything random. Implemented here rather than taken from a crate, so that no sequence can
//! change under a dependency update.

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, fast, statistically good 64-bit generator.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator seeded with `seed` (any value, zero included).
    pub fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// Draws that only tests and the synthetic data use.
#[cfg(any(test, feature = "dev"))]
impl SplitMix64 {
    /// Uniform in `[0, 1)` with 53 random bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A closure drawing [`SplitMix64::next_f64`] values from `seed` (the tests' `r()`).
    pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut s = SplitMix64::new(seed);
        move || s.next_f64()
    }

    /// Uniform in `[lo, hi)`.
    #[inline]
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    /// Uniform integer in `0..n` (`n > 0`; the tiny modulo bias is irrelevant here).
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }

    /// Standard normal deviate (Box–Muller, one value per call).
    pub fn normal(&mut self) -> f64 {
        // 1 - u is in (0, 1], so the logarithm is finite.
        let u = 1.0 - self.next_f64();
        let v = self.next_f64();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    #[test]
    fn splitmix_known_values() {
        // Reference values of SplitMix64 seeded with 0 (as in Vigna's splitmix64.c).
        let mut r = SplitMix64::new(0);
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        let mut r = SplitMix64::new(7);
        for _ in 0..1000 {
            let v = r.next_f64();
            assert!((0.0..1.0).contains(&v));
            assert!(r.below(10) < 10);
        }
    }

    #[test]
    fn next_f64_is_the_top_53_bits() {
        // `* 2^-53` and `/ 2^53` are the same exact scaling (the products' tests used the latter).
        let (mut a, mut b) = (SplitMix64::new(3), SplitMix64::new(3));
        for _ in 0..1000 {
            assert_eq!(
                a.next_f64(),
                (b.next_u64() >> 11) as f64 / (1u64 << 53) as f64
            );
        }
    }
}
