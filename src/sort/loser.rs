//! A tournament tree of losers: which of k sorted sources holds the smallest head, one
//! comparison per level when a head changes (a binary heap needs two), for the k-way merge.

/// The tree over sources `0..k`: each inner node keeps the source that lost the match played
/// there; the overall winner is kept apart. Sources are compared by a `beats(a, b)` the caller
/// passes (a strict, total order: ties broken by source index), so the tree holds no records.
#[derive(Debug)]
pub(crate) struct LoserTree {
    /// Inner nodes `1..k` (node `p`'s children are `2p` and `2p + 1`; source `j` is leaf
    /// `k + j`); `losers[0]` is the winner.
    losers: Vec<u32>,
}

impl LoserTree {
    /// Plays every match of `k` sources.
    pub(crate) fn new(k: usize, beats: impl Fn(usize, usize) -> bool) -> Self {
        assert!(u32::try_from(k).is_ok(), "too many sources");
        let mut winners = vec![0u32; 2 * k];
        let mut losers = vec![0u32; k.max(1)];
        for j in 0..k {
            winners[k + j] = j as u32;
        }
        for p in (1..k).rev() {
            let (a, b) = (winners[2 * p], winners[2 * p + 1]);
            let (w, l) = if beats(b as usize, a as usize) {
                (b, a)
            } else {
                (a, b)
            };
            winners[p] = w;
            losers[p] = l;
        }
        if k > 1 {
            losers[0] = winners[1];
        }
        LoserTree { losers }
    }

    /// The source with the smallest head.
    #[inline]
    pub(crate) fn winner(&self) -> usize {
        self.losers[0] as usize
    }

    /// Replays the winner's way up after its head changed (it moved on, or ran out).
    #[inline]
    pub(crate) fn replay(&mut self, beats: impl Fn(usize, usize) -> bool) {
        let k = self.losers.len();
        let mut cur = self.losers[0];
        let mut p = (k + cur as usize) / 2;
        while p >= 1 {
            let other = self.losers[p];
            if beats(other as usize, cur as usize) {
                self.losers[p] = cur;
                cur = other;
            }
            p /= 2;
        }
        self.losers[0] = cur;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::rng::SplitMix64;

    /// Merging random sorted lists (with equal values across lists, and empty lists) gives
    /// every value in order, equal values from the earlier list first.
    #[test]
    fn merges_like_a_stable_sort() {
        let mut rng = SplitMix64::new(7);
        for k in 1..=19 {
            let lists: Vec<Vec<u32>> = (0..k)
                .map(|_| {
                    let n = rng.below(40) as usize;
                    let mut v: Vec<u32> = (0..n).map(|_| rng.below(25) as u32).collect();
                    v.sort_unstable();
                    v
                })
                .collect();
            let mut pos = vec![0usize; k];
            let head = |pos: &[usize], j: usize| lists[j].get(pos[j]).copied();
            let beats = |pos: &[usize], a: usize, b: usize| match (head(pos, a), head(pos, b)) {
                (Some(x), Some(y)) => (x, a) < (y, b),
                (Some(_), None) => true,
                (None, Some(_)) => false,
                (None, None) => a < b,
            };
            let mut tree = LoserTree::new(k, |a, b| beats(&pos, a, b));
            let mut out = Vec::new();
            while let Some(v) = head(&pos, tree.winner()) {
                out.push((v, tree.winner()));
                pos[tree.winner()] += 1;
                tree.replay(|a, b| beats(&pos, a, b));
            }
            let mut expect: Vec<(u32, usize)> = lists
                .iter()
                .enumerate()
                .flat_map(|(j, l)| l.iter().map(move |&v| (v, j)))
                .collect();
            expect.sort_unstable();
            assert_eq!(out, expect, "k = {k}");
        }
    }
}
