//! A stable least-significant-digit radix sort by a `u64` key, for the external sort's chunks
//! of records ordered by a key alone (the tiles' block keys).
//!
//! Only the key bits that differ within the chunk are sorted on, in digits of up to
//! [`DIGIT_BITS`] bits starting at the lowest such bit: a tile grid's key (block row above block
//! column) over a survey of a few thousand blocks a side takes two or three passes, each one
//! read and one write of the records, against the twenty-odd of a merge sort. Stable: records
//! with equal keys keep their order (a block's points stay in input order).

/// Bits per digit: 2048 buckets, whose counts and write positions stay in the first-level cache.
const DIGIT_BITS: u32 = 11;

/// Below this, the standard library's stable sort (no scratch to fill).
const SMALL: usize = 1 << 12;

/// Sorts `v` by `key`, stably, with `scratch` (grown to `v`'s length, and kept for the next
/// call).
pub(crate) fn sort_by_key<R: bytemuck::Pod>(
    v: &mut [R],
    scratch: &mut Vec<R>,
    key: impl Fn(&R) -> u64,
) {
    if v.len() < SMALL {
        v.sort_by_key(|r| key(r));
        return;
    }
    let first = key(&v[0]);
    let differ = v.iter().fold(0u64, |d, r| d | (key(r) ^ first));
    let shifts = digits(differ);
    if shifts.is_empty() {
        return;
    }
    let mask = (1u64 << DIGIT_BITS) - 1;
    let mut counts = vec![[0usize; 1 << DIGIT_BITS]; shifts.len()];
    for r in v.iter() {
        let k = key(r);
        for (c, &s) in counts.iter_mut().zip(&shifts) {
            c[((k >> s) & mask) as usize] += 1;
        }
    }
    scratch.clear();
    scratch.resize(v.len(), R::zeroed());
    let mut in_v = true;
    for (c, &s) in counts.iter_mut().zip(&shifts) {
        // Write positions: the counts' exclusive prefix sums.
        let mut at = 0;
        for n in c.iter_mut() {
            (*n, at) = (at, at + *n);
        }
        let (src, dst): (&[R], &mut [R]) = if in_v {
            (&*v, &mut scratch[..])
        } else {
            (&scratch[..], &mut *v)
        };
        for r in src {
            let d = ((key(r) >> s) & mask) as usize;
            dst[c[d]] = *r;
            c[d] += 1;
        }
        in_v = !in_v;
    }
    if !in_v {
        v.copy_from_slice(scratch);
    }
}

/// The shifts of the digits covering every set bit of `differ`, lowest first.
fn digits(mut differ: u64) -> Vec<u32> {
    let mut shifts = Vec::new();
    while differ != 0 {
        let s = differ.trailing_zeros();
        shifts.push(s);
        differ = if s + DIGIT_BITS >= 64 {
            0
        } else {
            differ & !((1u64 << (s + DIGIT_BITS)) - 1)
        };
    }
    shifts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::rng::SplitMix64;

    #[test]
    fn digits_cover_the_differing_bits() {
        assert_eq!(digits(0), Vec::<u32>::new());
        assert_eq!(digits(0b1_1111_1111 | (0x1ff << 32)), vec![0, 32]);
        assert_eq!(digits(1 << 63), vec![63]);
        assert_eq!(digits(u64::MAX).len(), 6);
    }

    #[test]
    fn equals_a_stable_sort() {
        let mut rng = SplitMix64::new(7);
        for (n, spread) in [(10, 5u64), (5000, 3), (40_000, 1 << 20), (70_000, u64::MAX)] {
            let mut v: Vec<[u64; 2]> = (0..n)
                .map(|i| {
                    let k = rng.next_u64() % spread.max(1);
                    // Keys like a tile grid's: row in the high half, column in the low.
                    [((k >> 7) << 32) ^ (k & 0x7f) ^ (1 << 40), i as u64]
                })
                .collect();
            let mut want = v.clone();
            want.sort_by_key(|r| r[0]);
            let mut scratch = Vec::new();
            sort_by_key(&mut v, &mut scratch, |r| r[0]);
            assert_eq!(v, want, "{n} records");
        }
    }
}
