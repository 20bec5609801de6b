//! A round's candidate pairs by a plane sweep in bounded memory (issue 40, item 3; the first
//! step of streaming the cleaned graph).
//!
//! The grid of [`Work::find`] holds every segment of the graph at once. Here the segments (and
//! isolated vertices) are sorted by their lower end in sweep order (`y`, then `x`) with the
//! crate's external sort ([`crate::sort::external`]), and swept: an item is tested against the
//! *active* items only, those whose upper end is not below its lower end, found through buckets
//! of `x` (an item is registered in every bucket its `x`-range covers; a pair is tested from the
//! first bucket both cover). Every pair whose closed bounding boxes meet is tested exactly once,
//! with the same exact tests as the grid ([`contact`], [`point_on`]), and the rule of
//! [`Work::find`] for which pairs a round tests (one of the two is new); so the non-empty results
//! are the grid's, and once sorted in pair order, the round does the same. Memory: the active
//! items and their bucket entries, plus the sort's budget; never the whole graph.
//!
//! [`SweepStats::peak_active`] counts the most items held at once.

// `clean_by_sweep` (its rounds, items and counters) is for tests and benchmarks; a run uses
// only the active set, through the streamed cleaner.
#![cfg_attr(not(any(test, feature = "dev")), allow(dead_code, unreachable_pub))]

use super::Work;
use super::intersect::{Found, PairResult, contact, point_on};
use crate::error::Result;
use crate::geom::predicates::sweep_cmp;
use crate::sort::external::{ExternalSorter, SortKey};
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;
use std::path::Path;

/// Item flag: new in this round (tested against everything it meets).
const DIRTY: u64 = 1;
/// Item flag: an isolated vertex (`lo == hi`), not a segment.
const POINT: u64 = 2;

/// A segment (ends in sweep order) or an isolated vertex, as the external sort stores it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Item {
    lo: [f64; 2],
    hi: [f64; 2],
    /// Segment index, or the number of segments plus the isolated vertex's index (as the grid's
    /// items are numbered).
    id: u64,
    flags: u64,
    /// Records are 64 bytes: the sort's sliding maps take sizes that divide their window.
    pad: [u64; 2],
}

impl SortKey for Item {
    #[inline]
    fn order(a: &Self, b: &Self) -> Ordering {
        sweep_cmp(a.lo, b.lo).then(a.id.cmp(&b.id))
    }
    // Ids are distinct: a total order.
    const STABLE: bool = false;
}

/// What a sweep held and did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SweepStats {
    /// Items swept.
    pub items: u64,
    /// Most items active at once.
    pub peak_active: u64,
    /// Most bucket entries at once (an item is in every bucket its `x`-range covers).
    pub peak_entries: u64,
    /// Pairs given the exact tests.
    pub pairs_tested: u64,
}

/// What the active set holds: something with a lower and an upper end in sweep order.
pub(super) trait Span: Copy {
    /// The lower end.
    fn lo(&self) -> [f64; 2];
    /// The upper end.
    fn hi(&self) -> [f64; 2];
}

impl Span for Item {
    fn lo(&self) -> [f64; 2] {
        self.lo
    }
    fn hi(&self) -> [f64; 2] {
        self.hi
    }
}

/// An active item: where it is in the buckets and which generation of its slot it is.
#[derive(Clone, Copy, Debug)]
pub(super) struct Active<T> {
    pub(super) item: T,
    pub(super) cols: [u32; 2],
    pub(super) generation: u32,
}

/// The items crossing the sweep line, by `x` bucket.
pub(super) struct ActiveSet<T> {
    x0: f64,
    inv: f64,
    cols: u32,
    pub(super) slots: Vec<Active<T>>,
    free: Vec<u32>,
    /// `(slot, generation)` per bucket; stale entries are dropped as buckets are scanned.
    pub(super) buckets: Vec<Vec<(u32, u32)>>,
    pub(super) entries: u64,
    live_entries: u64,
    /// Upper `y` (as ordered bits) of each active slot, soonest first.
    expiry: BinaryHeap<Reverse<(u64, u32)>>,
    pub(super) live: u64,
}

/// `y` as bits whose unsigned order is `total_cmp`'s.
fn key(y: f64) -> u64 {
    let b = y.to_bits();
    if b >> 63 == 1 { !b } else { b | (1 << 63) }
}

impl<T: Span> ActiveSet<T> {
    pub(super) fn new(lo: f64, hi: f64, cols: u32) -> ActiveSet<T> {
        let w = hi - lo;
        let inv = if w > 0.0 && w.is_finite() {
            f64::from(cols) / w
        } else {
            0.0
        };
        ActiveSet {
            x0: lo,
            inv,
            cols,
            slots: Vec::new(),
            free: Vec::new(),
            buckets: vec![Vec::new(); cols as usize],
            entries: 0,
            live_entries: 0,
            expiry: BinaryHeap::new(),
            live: 0,
        }
    }

    /// Bucket of `x`: monotone in `x`, clamped.
    #[inline]
    fn col(&self, x: f64) -> u32 {
        let c = ((x - self.x0) * self.inv).floor();
        if c >= 0.0 {
            (c as u64).min(u64::from(self.cols - 1)) as u32
        } else {
            0
        }
    }

    pub(super) fn cols_of(&self, it: &T) -> [u32; 2] {
        let (lo, hi) = (it.lo(), it.hi());
        let (a, b) = (lo[0].min(hi[0]), lo[0].max(hi[0]));
        [self.col(a), self.col(b)]
    }

    /// Calls `f` with each active item whose `x` range meets that of `it` (in buckets `cols`,
    /// [`ActiveSet::cols_of`]), once: in the first bucket both cover. Stale entries met on the
    /// way are dropped. The bucket scan of both sweeps (a round's pairs here, the streamed
    /// cleaner's contacts).
    pub(super) fn for_each_meeting(&mut self, it: &T, cols: [u32; 2], mut f: impl FnMut(&T)) {
        for c in cols[0]..=cols[1] {
            let bucket = &mut self.buckets[c as usize];
            let mut k = 0;
            while k < bucket.len() {
                let (slot, generation) = bucket[k];
                let a = &self.slots[slot as usize];
                if a.generation != generation {
                    bucket.swap_remove(k);
                    self.entries -= 1;
                    continue;
                }
                k += 1;
                if c == cols[0].max(a.cols[0]) && x_overlap(it, &a.item) {
                    f(&a.item);
                }
            }
        }
    }

    /// Drops every item whose upper end lies below `y`.
    fn expire(&mut self, y: f64) {
        self.expire_with(y, |_| {});
    }

    /// Drops every item whose upper end lies below `y`, handing each to `gone`.
    pub(super) fn expire_with(&mut self, y: f64, mut gone: impl FnMut(T)) {
        let k = key(y);
        while let Some(&Reverse((top, slot))) = self.expiry.peek() {
            if top >= k {
                break;
            }
            self.expiry.pop();
            let a = &mut self.slots[slot as usize];
            gone(a.item);
            self.live_entries -= u64::from(a.cols[1] - a.cols[0] + 1);
            a.generation = a.generation.wrapping_add(1);
            self.free.push(slot);
            self.live -= 1;
        }
        // Buckets nobody scans keep their stale entries: sweep them out now and then.
        if self.entries > 2 * self.live_entries + 4096 {
            let slots = &self.slots;
            for b in &mut self.buckets {
                b.retain(|&(s, g)| slots[s as usize].generation == g);
            }
            self.entries = self.live_entries;
        }
    }

    pub(super) fn insert(&mut self, item: T, cols: [u32; 2]) {
        let slot = match self.free.pop() {
            Some(s) => {
                let a = &mut self.slots[s as usize];
                a.item = item;
                a.cols = cols;
                s
            }
            None => {
                self.slots.push(Active {
                    item,
                    cols,
                    generation: 0,
                });
                (self.slots.len() - 1) as u32
            }
        };
        let generation = self.slots[slot as usize].generation;
        for c in cols[0]..=cols[1] {
            self.buckets[c as usize].push((slot, generation));
        }
        let n = u64::from(cols[1] - cols[0] + 1);
        self.entries += n;
        self.live_entries += n;
        self.expiry.push(Reverse((key(item.hi()[1]), slot)));
        self.live += 1;
    }
}

/// Does `a`'s closed `x`-range meet `b`'s?
#[inline]
pub(super) fn x_overlap<T: Span>(a: &T, b: &T) -> bool {
    let (al, ah, bl, bh) = (a.lo(), a.hi(), b.lo(), b.hi());
    let (a0, a1) = (al[0].min(ah[0]), al[0].max(ah[0]));
    let (b0, b1) = (bl[0].min(bh[0]), bl[0].max(bh[0]));
    a0 <= b1 && b0 <= a1
}

impl Work {
    /// [`Work::find`] by a plane sweep over the items sorted externally within `mem` bytes
    /// (spilling under `tmp_dir`): the same results in pair order, and what the sweep held.
    ///
    /// # Errors
    /// The external sort's errors (a spill that cannot be written or read back).
    pub(super) fn find_by_sweep(
        &self,
        first_round: bool,
        mem: u64,
        tmp_dir: &Path,
    ) -> Result<(Found, SweepStats)> {
        let n_seg = self.segs.len() as u64;
        let mut sorter = ExternalSorter::<Item>::new(mem / 2, tmp_dir);
        let ordered = |p: [f64; 2], q: [f64; 2]| match sweep_cmp(p, q) {
            Ordering::Greater => (q, p),
            _ => (p, q),
        };
        for (i, s) in self.segs.iter().enumerate() {
            let (lo, hi) = ordered(self.p(s[0]), self.p(s[1]));
            let flags = if self.dirty[i] { DIRTY } else { 0 };
            sorter.push(Item {
                lo,
                hi,
                id: i as u64,
                flags,
                pad: [0; 2],
            })?;
        }
        for (k, &v) in self.isolated.iter().enumerate() {
            let p = self.p(v);
            let flags = POINT | if first_round { DIRTY } else { 0 };
            sorter.push(Item {
                lo: p,
                hi: p,
                id: n_seg + k as u64,
                flags,
                pad: [0; 2],
            })?;
        }
        let mut merge = sorter.finish()?;
        let items = n_seg + self.isolated.len() as u64;
        let cols = ((items as f64).sqrt() as u32).clamp(1, 1 << 16);
        let mut act = ActiveSet::<Item>::new(self.lo[0], self.hi[0], cols);
        let mut stats = SweepStats::default();
        let mut found = Vec::new();
        for it in merge.by_ref() {
            stats.items += 1;
            act.expire(it.lo[1]);
            let cols = act.cols_of(&it);
            act.for_each_meeting(&it, cols, |&other| {
                let both_points = it.flags & other.flags & POINT != 0;
                if both_points || (it.flags | other.flags) & DIRTY == 0 {
                    return;
                }
                stats.pairs_tested += 1;
                let (s, t) = if it.id < other.id {
                    (it, other)
                } else {
                    (other, it)
                };
                if let Some(r) = self.sweep_pair(&s, &t) {
                    found.push(([s.id as u32, t.id as u32], r));
                }
            });
            act.insert(it, cols);
            stats.peak_active = stats.peak_active.max(act.live);
            stats.peak_entries = stats.peak_entries.max(act.entries);
        }
        if let Some(e) = merge.take_error() {
            return Err(e);
        }
        found.sort_unstable_by_key(|f| f.0);
        Ok((found, stats))
    }

    /// The exact tests of items `s` and `t` (`s.id < t.id`), as [`Work::find`] would give them.
    fn sweep_pair(&self, s: &Item, t: &Item) -> Option<PairResult> {
        let n_seg = self.segs.len() as u64;
        let mut r = PairResult::default();
        if t.flags & POINT != 0 {
            let v = self.isolated[(t.id - n_seg) as usize];
            let [a, b] = self.segs[s.id as usize];
            if point_on(self.p(a), self.p(b), t.lo) {
                r.splits[0] = (s.id as u32, v);
                r.n_splits = 1;
            }
        } else {
            let [a, b] = self.segs[s.id as usize];
            let [c, d] = self.segs[t.id as usize];
            let ends = [a, b, c, d];
            let k = contact([self.p(a), self.p(b), self.p(c), self.p(d)]);
            if k.is_empty() {
                return None;
            }
            r.overlap = k.overlap;
            r.cross = k.cross;
            for (n, &(seg, end)) in k.splits[..k.n_splits as usize].iter().enumerate() {
                let seg = if seg == 0 { s.id } else { t.id };
                r.splits[n] = (seg as u32, ends[end as usize]);
            }
            r.n_splits = k.n_splits;
        }
        (r.n_splits > 0 || r.cross.is_some()).then_some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{CleanOptions, Pslg, clean, clean_by_sweep};
    use crate::synth::{SplitMix64, roads};

    /// The whole graph, bit for bit (`NaN` heights compare equal), counters and warnings too.
    fn assert_same(a: &Pslg, b: &Pslg) {
        let bits = |g: &Pslg| {
            g.vertices
                .iter()
                .map(|v| v.map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(a.stats, b.stats);
        assert_eq!(bits(a), bits(b));
        assert_eq!(a.segments, b.segments);
        assert_eq!(a.lines, b.lines);
        assert_eq!(a.warnings, b.warnings);
    }

    fn both(lines: &[Vec<[f64; 3]>], mem: u64) -> super::SweepStats {
        let dir = tempfile::tempdir().unwrap();
        let want = clean(lines, &CleanOptions::default()).unwrap();
        let (got, stats) =
            clean_by_sweep(lines, &CleanOptions::default(), mem, dir.path()).unwrap();
        assert_same(&want, &got);
        got.check_planar().unwrap();
        stats
    }

    #[test]
    fn sweep_finds_the_grids_graph_on_road_networks() {
        for seed in 1..4 {
            let lines = roads(30_000, seed);
            let s = both(&lines, 64 << 20);
            assert!(s.items > 25_000, "{s:?}");
            // The sweep holds the items crossing one line, not the network.
            assert!(s.peak_active < s.items / 20, "{s:?}");
        }
        // A budget so small the items are spilled in many runs: the same graph.
        both(&roads(20_000, 9), 1 << 20);
    }

    #[test]
    fn sweep_finds_the_grids_graph_on_every_degeneracy() {
        let nan = f64::NAN;
        let lines = vec![
            // Horizontal and vertical lines crossing at a common vertex and between vertices.
            vec![[0.0, 5.0, 1.0], [5.0, 5.0, 1.0], [10.0, 5.0, 1.0]],
            vec![[5.0, 0.0, 2.0], [5.0, 5.0, 2.0], [5.0, 10.0, 2.0]],
            vec![[7.0, 0.0, 3.0], [7.0, 10.0, 3.0]],
            // A duplicate, reversed, and a collinear overlap of the horizontal line.
            vec![[10.0, 5.0, 1.0], [5.0, 5.0, 1.0]],
            vec![[2.0, 5.0, nan], [8.0, 5.0, nan], [9.0, 5.0, 4.0]],
            // A T-junction: an end on the vertical line's interior.
            vec![[5.0, 8.0, nan], [9.0, 9.0, nan]],
            // Many segments through one point, half with it as a vertex.
            vec![[1.0, 1.0, 0.0], [3.0, 3.0, 0.0]],
            vec![[1.0, 3.0, 5.0], [3.0, 1.0, 5.0]],
            vec![[2.0, 0.5, 6.0], [2.0, 2.0, nan], [2.0, 3.5, 6.0]],
            vec![[0.5, 2.0, 7.0], [3.5, 2.0, 7.0]],
            vec![[1.0, 1.5, 8.0], [3.0, 2.5, 8.0]],
            // An isolated vertex on a line, one off every line, a zero-length segment.
            vec![[6.0, 5.0, nan]],
            vec![[6.5, 6.5, 1.0]],
            vec![[4.0, 9.0, 1.0], [4.0, 9.0, 1.0], [4.0, 9.5, 1.0]],
        ];
        both(&lines, 1 << 20);
        // The same shapes scaled and shifted to UTM-sized coordinates, and random near-misses.
        let shifted: Vec<Vec<[f64; 3]>> = lines
            .iter()
            .map(|l| {
                l.iter()
                    .map(|p| [447_000.0 + p[0] * 0.25, 5_100_000.0 + p[1] * 0.25, p[2]])
                    .collect()
            })
            .collect();
        both(&shifted, 1 << 20);
        let mut rng = SplitMix64::new(5);
        let random: Vec<Vec<[f64; 3]>> = (0..400)
            .map(|_| {
                let n = 2 + rng.below(4) as usize;
                (0..n)
                    .map(|_| {
                        let q = |r: &mut SplitMix64| (r.range(0.0, 64.0) * 4.0).round() / 4.0;
                        [
                            q(&mut rng),
                            q(&mut rng),
                            if rng.below(3) == 0 { nan } else { 1.0 },
                        ]
                    })
                    .collect()
            })
            .collect();
        both(&random, 1 << 20);
    }
}
