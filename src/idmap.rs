//! Maps keyed by the mesh's own vertex numbers (0, 1, 2, … in stream order), hashed with one
//! multiplication instead of SipHash: the keys are our numbers, not attacker-chosen, and the
//! writer looks one up for every triangle corner. Iteration order is never used for output.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Fibonacci hashing of a `u64`: multiplication by 2^64 / φ. Sequential keys get distinct low bits
/// (the bucket) and well-mixed high bits (the map's tag bits).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct IdHasher(u64);

impl Hasher for IdHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    #[inline]
    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(5) ^ n).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

/// A `HashMap` from vertex numbers.
pub(crate) type IdMap<V> = HashMap<u64, V, BuildHasherDefault<IdHasher>>;

/// A `HashMap` keyed by our own integers or coordinate bits (positions of points, triangles as
/// their corners' positions), hashed as [`IdMap`] is.
pub(crate) type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<IdHasher>>;

/// A set keyed as [`FastMap`].
pub(crate) type FastSet<K> = std::collections::HashSet<K, BuildHasherDefault<IdHasher>>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn behaves_as_a_map() {
        let mut m: IdMap<u64> = IdMap::default();
        for i in 0..100_000u64 {
            m.insert(i, i * 3);
        }
        for i in (0..100_000u64).step_by(2) {
            assert_eq!(m.remove(&i), Some(i * 3));
        }
        assert_eq!(m.len(), 50_000);
        assert_eq!(m.get(&99_999), Some(&299_997));
        assert_eq!(m.get(&4), None);
    }
}
