//! The near part of the finalisation queue: a ring of [`RING`] buckets, each a chain of
//! fixed-size blocks in one [`SpillVec`], so that it spills with the other tables of held
//! triangles (points on a line or a circle keep every triangle waiting, a queue entry each:
//! bucket lists on the heap held 4–9 bytes a held triangle, 84 MB for a 10 M-point line).
//!
//! A bucket's entries come out in the order they went in. Blocks are recycled through a free
//! chain kept in the blocks themselves, so the table holds the most entries queued at once,
//! plus one partly filled block a bucket.

use crate::sort::mmap::SpillVec;

/// Buckets in the ring.
pub(super) const RING: usize = 1024;
/// `u32`s a block: its link (the next block of its chain, or [`NONE`]) and `BLOCK - 1` entries.
const BLOCK: usize = 256;
const PER_BLOCK: u32 = (BLOCK - 1) as u32;
const NONE: u32 = u32::MAX;

/// A chain of blocks: a bucket's entries, in order.
#[derive(Debug, Clone, Copy)]
pub(super) struct Chain {
    head: u32,
    tail: u32,
    /// Entries in the tail block.
    tail_len: u32,
}

impl Chain {
    const EMPTY: Chain = Chain {
        head: NONE,
        tail: NONE,
        tail_len: 0,
    };

    fn is_empty(&self) -> bool {
        self.head == NONE
    }
}

/// The ring of near buckets (see the module docs).
#[derive(Debug, Clone)]
pub(super) struct NearRing {
    blocks: SpillVec<u32>,
    buckets: Vec<Chain>,
    /// First free block, its link the next free one.
    free: u32,
    /// Entries queued.
    len: usize,
}

impl Default for NearRing {
    fn default() -> Self {
        NearRing {
            blocks: SpillVec::default(),
            buckets: vec![Chain::EMPTY; RING],
            free: NONE,
            len: 0,
        }
    }
}

impl NearRing {
    /// Entries queued.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Appends triangle slot `t` to bucket `k`'s list.
    #[inline]
    pub(super) fn push(&mut self, k: u64, t: u32) {
        let slot = (k % RING as u64) as usize;
        let c = self.buckets[slot];
        if c.is_empty() || c.tail_len == PER_BLOCK {
            let b = self.new_block();
            let c = &mut self.buckets[slot];
            if c.is_empty() {
                c.head = b;
            } else {
                self.blocks[c.tail as usize * BLOCK] = b;
            }
            c.tail = b;
            c.tail_len = 0;
        }
        let c = &mut self.buckets[slot];
        self.blocks[c.tail as usize * BLOCK + 1 + c.tail_len as usize] = t;
        c.tail_len += 1;
        self.len += 1;
    }

    /// A block whose link is [`NONE`]: a free one, or a new one at the end of the table.
    fn new_block(&mut self) -> u32 {
        let b = if self.free == NONE {
            let b = (self.blocks.len() / BLOCK) as u32;
            self.blocks.resize(self.blocks.len() + BLOCK, 0);
            b
        } else {
            let b = self.free;
            self.free = self.blocks[b as usize * BLOCK];
            b
        };
        self.blocks[b as usize * BLOCK] = NONE;
        b
    }

    /// Takes bucket `k`'s list out of the ring (entries pushed for `k + RING` from now on start
    /// a new list); read it with [`NearRing::next_batch`].
    pub(super) fn detach(&mut self, k: u64) -> Chain {
        let slot = (k % RING as u64) as usize;
        std::mem::replace(&mut self.buckets[slot], Chain::EMPTY)
    }

    /// Moves the first block's entries of `chain` into `out` (cleared first) and frees the
    /// block; `false` once the chain is empty.
    pub(super) fn next_batch(&mut self, chain: &mut Chain, out: &mut Vec<u32>) -> bool {
        out.clear();
        if chain.is_empty() {
            return false;
        }
        let b = chain.head;
        let at = b as usize * BLOCK;
        let n = if b == chain.tail {
            chain.tail_len
        } else {
            PER_BLOCK
        } as usize;
        out.extend_from_slice(&self.blocks[at + 1..at + 1 + n]);
        self.len -= n;
        *chain = if b == chain.tail {
            Chain::EMPTY
        } else {
            Chain {
                head: self.blocks[at],
                ..*chain
            }
        };
        self.blocks[at] = self.free;
        self.free = b;
        true
    }

    /// The blocks' table, to spill.
    pub(super) fn table(&mut self) -> &mut SpillVec<u32> {
        &mut self.blocks
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries come out of each bucket in the order they went in, across blocks, while other
    /// buckets grow and blocks are recycled; the table holds what is queued at once, not all
    /// that was ever queued.
    #[test]
    fn buckets_keep_their_order_and_blocks_are_recycled() {
        let mut r = NearRing::default();
        let mut want: Vec<Vec<u32>> = vec![Vec::new(); RING];
        let mut x = 99u64;
        let mut batch = Vec::new();
        for round in 0..4u32 {
            for i in 0..20_000u32 {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let k = (x >> 40) % 7;
                let t = round * 100_000 + i;
                r.push(k, t);
                want[k as usize].push(t);
            }
            assert_eq!(r.len(), 20_000);
            for k in 0..7u64 {
                let mut chain = r.detach(k);
                let mut got = Vec::new();
                while r.next_batch(&mut chain, &mut batch) {
                    got.extend_from_slice(&batch);
                    // Pushed while the bucket is read: kept for the ring's next turn.
                    r.push(k + RING as u64, 7);
                }
                assert_eq!(got, std::mem::take(&mut want[k as usize]), "bucket {k}");
                let mut later = r.detach(k);
                while r.next_batch(&mut later, &mut batch) {
                    assert!(batch.iter().all(|&t| t == 7));
                }
            }
            assert_eq!(r.len(), 0);
        }
        // One round's entries (20,000 in 7 buckets) in blocks of 255, and no more.
        assert!(r.blocks.len() <= (20_000 / 255 + 8 + 7) * BLOCK, "{}", r.blocks.len());
    }
}
