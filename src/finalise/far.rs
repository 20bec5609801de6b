//! The far part of the finalisation queue: checks due beyond the ring of near buckets, a binary
//! min-heap of `(bucket, slot)` over a [`SpillVec`], so that it spills with the other tables of
//! held triangles (each held triangle waits here: points on a line put every one of them in).

use crate::sort::mmap::SpillVec;

/// A min-heap of `(bucket, triangle slot)` entries, popped in increasing `(bucket, slot)` order
/// (the order depends only on the entries, not on how they were pushed).
#[derive(Debug, Clone, Default)]
pub(super) struct FarQueue {
    /// `bucket << 32 | slot`: the integer order is the entries' order.
    heap: SpillVec<u128>,
}

#[inline(always)]
fn key(k: u64, t: u32) -> u128 {
    (k as u128) << 32 | t as u128
}

#[inline(always)]
fn entry(e: u128) -> (u64, u32) {
    ((e >> 32) as u64, e as u32)
}

impl FarQueue {
    pub(super) fn len(&self) -> usize {
        self.heap.len()
    }

    /// The first entry.
    #[inline]
    pub(super) fn peek(&self) -> Option<(u64, u32)> {
        self.heap.first().map(|&e| entry(e))
    }

    pub(super) fn push(&mut self, k: u64, t: u32) {
        let e = key(k, t);
        self.heap.push(e);
        let h = &mut self.heap[..];
        let mut i = h.len() - 1;
        while i > 0 {
            let p = (i - 1) / 2;
            if h[p] <= e {
                break;
            }
            h[i] = h[p];
            i = p;
        }
        h[i] = e;
    }

    /// Removes the first entry.
    pub(super) fn pop(&mut self) -> Option<(u64, u32)> {
        let first = *self.heap.first()?;
        let last = self.heap[self.heap.len() - 1];
        self.heap.resize(self.heap.len() - 1, 0);
        let h = &mut self.heap[..];
        if !h.is_empty() {
            let mut i = 0;
            loop {
                let mut c = 2 * i + 1;
                if c >= h.len() {
                    break;
                }
                if c + 1 < h.len() && h[c + 1] < h[c] {
                    c += 1;
                }
                if last <= h[c] {
                    break;
                }
                h[i] = h[c];
                i = c;
            }
            h[i] = last;
        }
        Some(entry(first))
    }

    /// The heap's table, to spill.
    pub(super) fn table(&mut self) -> &mut SpillVec<u128> {
        &mut self.heap
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_bucket_then_slot_order() {
        let mut q = FarQueue::default();
        let mut want = Vec::new();
        let mut x = 12345u64;
        for i in 0..5000u32 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let k = (x >> 40) % 300;
            q.push(k, i % 700);
            want.push((k, i % 700));
        }
        want.sort();
        let got: Vec<_> = std::iter::from_fn(|| q.pop()).collect();
        assert_eq!(got, want);
    }
}
