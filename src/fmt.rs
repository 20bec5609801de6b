//! Figures in messages, written one way everywhere: counts with thousands separators
//! ([`count`], `321,159`), measured values with six significant digits at most and the
//! exponent form outside 1e-4 … 1e15 ([`Figure`]: `0.5`, `1234.57`, `1e-300`, never three hundred
//! digits), values in a table with fixed decimals ([`Decimals`]: `12.500`, and `1e300` rather
//! than 300 digits), sizes in binary units ([`crate::human_bytes`]).

use std::fmt;

/// `1234567` as `1,234,567`.
pub fn count(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::with_capacity(s.len() + s.len() / 3);
    for (k, c) in s.chars().enumerate() {
        if k > 0 && (s.len() - k).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A measured value (a length, a height, a cell size, an area) for a message: at most six
/// significant digits (all the digits of the whole part below 1e15), trailing zeros dropped,
/// and the exponent form (`1.5e-7`, `1e300`) for magnitudes under 1e-4 or from 1e15.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Figure(pub f64);

impl fmt::Display for Figure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if !v.is_finite() || v == 0.0 {
            // `inf`, `-inf`, `NaN`, `0` (and `-0` as `0`).
            return if v == 0.0 {
                f.write_str("0")
            } else {
                write!(f, "{v}")
            };
        }
        let a = v.abs();
        if !(1e-4..1e15).contains(&a) {
            let s = format!("{v:.5e}");
            let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
            return write!(f, "{}e{exponent}", trim(mantissa));
        }
        let whole_digits = a.log10().floor() as i32 + 1;
        let decimals = (6 - whole_digits).max(0) as usize;
        let s = format!("{v:.decimals$}");
        f.write_str(trim(&s))
    }
}

/// A value with a fixed number of decimals (volumes and areas in a table: `12.500`), in the
/// exponent form ([`Figure`]'s) from 1e15 on, where the decimals mean nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decimals(pub f64, pub usize);

impl fmt::Display for Decimals {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Decimals(v, d) = *self;
        if v.is_finite() && v.abs() < 1e15 {
            write!(f, "{v:.d$}")
        } else {
            write!(f, "{}", Figure(v))
        }
    }
}

/// `1.500` → `1.5`, `2.000` → `2` (only after a decimal point).
fn trim(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_have_separators() {
        assert_eq!(count(0), "0");
        assert_eq!(count(999), "999");
        assert_eq!(count(1000), "1,000");
        assert_eq!(count(321_159), "321,159");
        assert_eq!(count(1_234_567), "1,234,567");
    }

    #[test]
    fn extreme_values_are_short() {
        let f = |v: f64| Figure(v).to_string();
        assert_eq!(f(1e300), "1e300");
        assert_eq!(f(1e-300), "1e-300");
        assert_eq!(f(-1.5e-300), "-1.5e-300");
        assert_eq!(f(0.5), "0.5");
        assert_eq!(f(2.0), "2");
        assert_eq!(f(1234.5678), "1234.57");
        assert_eq!(f(0.000833333333), "0.000833333");
        assert_eq!(f(123_456_789.4), "123456789");
        assert_eq!(f(0.0), "0");
        assert_eq!(f(-0.0), "0");
        assert_eq!(f(f64::INFINITY), "inf");
        assert_eq!(f(1.0 / 3.0), "0.333333");
        assert!(f(f64::MAX).len() < 16, "{}", f(f64::MAX));
        assert_eq!(Decimals(12.5, 3).to_string(), "12.500");
        assert_eq!(Decimals(1e300, 3).to_string(), "1e300");
        assert_eq!(Decimals(-8.158e304, 3).to_string(), "-8.158e304");
        assert_eq!(Decimals(1e-300, 3).to_string(), "0.000");
    }
}
