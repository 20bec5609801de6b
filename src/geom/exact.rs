//! Exact floating-point arithmetic tests that the stages share (the predicates themselves are in
//! [`super::predicates`]).

/// Is `a - b` exactly representable, so that subtracting `b` loses nothing? True when the TwoSum
/// error term of `a - b` is zero (Knuth's branch-free TwoSum; exact for any finite `a`, `b`).
///
/// Used to choose a local origin: moving every point by `-origin` keeps every predicate's sign
/// only when each subtraction is exact.
#[inline]
pub(crate) fn exact_diff(a: f64, b: f64) -> bool {
    let s = a - b;
    let bv = s - a;
    let av = s - bv;
    (a - av) + (-b - bv) == 0.0
}

#[cfg(test)]
mod tests {
    use super::exact_diff;

    #[test]
    fn exact_and_inexact_differences() {
        assert!(exact_diff(770_530.15, 770_530.0));
        assert!(exact_diff(1.0, 0.5));
        assert!(exact_diff(0.0, 0.0));
        assert!(exact_diff(-3.25, 1e6));
        // 1 - 2^-60 needs 61 bits.
        assert!(!exact_diff(1.0, 2f64.powi(-60)));
        assert!(!exact_diff(1e20, 0.1));
    }
}
