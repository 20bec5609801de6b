//! The advancing front: an x-monotone polyline from `P-1` to `P-2` over the triangulated region
//! (Domiter & Žalik 2008, section 3.4.1), as a doubly linked list of nodes in a pool, with a bucket
//! index over `x` to find the segment under a new point.
//!
//! The front is strictly increasing in `x` (`P-1` sits at `x = -∞`, `P-2` at `+∞`), so the segment
//! under a point is unique: the bucket index only decides where the search starts, never what it
//! finds, and the result does not depend on the number of buckets.
//!
//! Beside the buckets the front keeps a tree of groups over them: level 0 is the buckets, each
//! group of level `j + 1` covers [`FAN`] groups of level `j`, up to one group over all. Each group
//! `g` keeps its first and last real node and the lowest `y` of its real nodes (the nodes of one
//! group are consecutive: the key is monotone in `x`). Invariant: `lead[g]` and `last[g]` are both
//! [`NIL`] (and `low[g]` is `+∞`) when no real node's key falls in the group; otherwise they are
//! its leftmost and rightmost such node, and `low[g]` is their lowest `y` exactly, or NaN (stale)
//! once a node at that height was removed; a stale minimum is recomputed (from the groups below,
//! or from the bucket's nodes) when [`Front::min_y_indexed`] needs it, and
//! [`Front::rebuild_buckets`] recomputes all. Only that long scan reads them.

use crate::mesh::{EdgeId, VertexId};
use crate::sort::mmap::SpillVec;

/// Groups of one level of the bucket tree under a group of the level above.
const FAN: usize = 16;
const FAN_SHIFT: u32 = FAN.trailing_zeros();

/// Id of a front node.
pub type NodeId = u32;

const NIL: NodeId = u32::MAX;
/// Empty buckets [`Front::locate`] steps back over before it asks the groups.
const NEAR_BUCKETS: usize = 16;
/// Nodes walked by a rebuild of the x index between drops of a spilled node table's pages.
const RELEASE_EVERY: usize = 1 << 16;

/// Empties `v` and fills it with `n` copies of `value`, dropping its pages every million
/// elements when it is spilled: a line's front indexes millions of buckets, and one `resize`
/// brought every page of the x index's tables into memory at once (200 MB for 10 M points).
fn refill<T: bytemuck::Pod>(v: &mut SpillVec<T>, n: usize, value: T) {
    const STEP: usize = 1 << 20;
    v.resize(0, value);
    while v.len() < n {
        v.resize((v.len() + STEP).min(n), value);
        v.release();
    }
}

/// One vertex of the front and the segment to its right.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Node {
    /// The vertex's x (−∞ for `P-1`, +∞ for `P-2`).
    pub x: f64,
    /// The vertex's y (−∞ for `P-1` and `P-2`).
    pub y: f64,
    /// The vertex.
    pub v: VertexId,
    /// Next node to the right.
    pub next: NodeId,
    /// Previous node to the left.
    pub prev: NodeId,
    /// Boundary half-edge under the segment `self → next` (it runs right to left).
    pub edge: EdgeId,
}

/// The advancing front.
#[derive(Debug, Clone)]
pub struct Front {
    nodes: SpillVec<Node>,
    free: Vec<NodeId>,
    len: usize,
    peak_len: usize,
    /// Node of `P-1`.
    pub head: NodeId,
    /// Node of `P-2`.
    pub tail: NodeId,
    buckets: SpillVec<NodeId>,
    /// Leftmost real node of each group of the bucket tree, level after level (see the module's
    /// invariant).
    lead: SpillVec<NodeId>,
    /// Rightmost real node of each group.
    last: SpillVec<NodeId>,
    /// Lowest y of each group's real nodes, NaN when stale, `+∞` when empty.
    low: SpillVec<f64>,
    /// Where each level of the tree starts in `lead`, `last` and `low`, and where the last ends.
    levels: Vec<usize>,
    xmap: XMap,
    nb: f64,
}

/// A monotone map of x onto `[0, 1]`, piecewise linear through quantiles of a sample of the
/// data's x, so that buckets of equal width in the mapped value hold similar numbers of front
/// nodes even when the points are clustered. Only speed depends on it, never the result.
/// Evaluated through a table of [`XMap::CELLS`] equal cells: one multiply-add per lookup.
#[derive(Clone, Debug)]
pub struct XMap {
    lo: f64,
    inv_step: f64,
    /// The exact piecewise-linear map at the cell boundaries (`CELLS + 1` values).
    at: Vec<f64>,
}

impl XMap {
    const SEGMENTS: usize = 256;
    /// Resolution of the lookup table.
    pub const CELLS: usize = 4096;

    /// From a sample of x values (any order; empty or degenerate gives a unit map).
    pub fn from_sample(mut xs: Vec<f64>) -> XMap {
        xs.retain(|x| x.is_finite());
        xs.sort_by(f64::total_cmp);
        let mut q: Vec<f64> = if xs.is_empty() {
            Vec::new()
        } else {
            (0..=Self::SEGMENTS)
                .map(|i| xs[(i * (xs.len() - 1)) / Self::SEGMENTS])
                .collect()
        };
        q.dedup();
        if q.len() < 2 {
            let lo = q.first().copied().unwrap_or(0.0);
            q = vec![lo, lo + 1.0];
        }
        let (lo, hi) = (q[0], q[q.len() - 1]);
        let last = (q.len() - 1) as f64;
        let step = (hi - lo) / Self::CELLS as f64;
        let mut seg = 0usize;
        let at = (0..=Self::CELLS)
            .map(|i| {
                let x = if i == Self::CELLS {
                    hi
                } else {
                    lo + step * i as f64
                };
                while seg + 2 < q.len() && q[seg + 1] <= x {
                    seg += 1;
                }
                let f = ((x - q[seg]) / (q[seg + 1] - q[seg])).clamp(0.0, 1.0);
                ((seg as f64 + f) / last).clamp(0.0, 1.0)
            })
            .collect();
        XMap {
            lo,
            inv_step: 1.0 / step,
            at,
        }
    }

    /// The unit map over `[lo, hi]`.
    pub fn linear(lo: f64, hi: f64) -> XMap {
        XMap::from_sample(vec![lo, hi])
    }

    /// `x` mapped into `[0, 1]` (clamped), monotone non-decreasing.
    #[inline(always)]
    pub fn unit(&self, x: f64) -> f64 {
        let t = (x - self.lo) * self.inv_step;
        if t.is_nan() || t <= 0.0 {
            return 0.0;
        }
        let c = t as usize;
        if c >= Self::CELLS {
            return 1.0;
        }
        let (a, b) = (self.at[c], self.at[c + 1]);
        a + (b - a) * (t - c as f64)
    }
}

impl Front {
    /// A front `P-1 → v → P-2` over the first triangle, whose half-edges under the two segments
    /// are `left_edge` (under `P-1 → v`) and `right_edge` (under `v → P-2`). `xmap` spreads the
    /// data's x over the bucket index.
    pub fn new(
        p_left: VertexId,
        p_right: VertexId,
        v: VertexId,
        xy: [f64; 2],
        left_edge: EdgeId,
        right_edge: EdgeId,
        xmap: XMap,
    ) -> Self {
        let nodes = SpillVec::from_vec(vec![
            Node {
                x: f64::NEG_INFINITY,
                y: f64::NEG_INFINITY,
                v: p_left,
                next: 2,
                prev: NIL,
                edge: left_edge,
            },
            Node {
                x: f64::INFINITY,
                y: f64::NEG_INFINITY,
                v: p_right,
                next: NIL,
                prev: 2,
                edge: EdgeId(u32::MAX),
            },
            Node {
                x: xy[0],
                y: xy[1],
                v,
                next: 1,
                prev: 0,
                edge: right_edge,
            },
        ]);
        let mut f = Front {
            nodes,
            free: Vec::new(),
            len: 3,
            peak_len: 3,
            head: 0,
            tail: 1,
            buckets: SpillVec::default(),
            lead: SpillVec::default(),
            last: SpillVec::default(),
            low: SpillVec::default(),
            levels: Vec::new(),
            xmap,
            nb: 0.0,
        };
        f.rebuild_buckets(64);
        f
    }

    /// The node with id `n`.
    #[inline(always)]
    pub fn node(&self, n: NodeId) -> &Node {
        &self.nodes[n as usize]
    }

    /// Next node to the right of `n`.
    #[inline(always)]
    pub fn next(&self, n: NodeId) -> NodeId {
        self.nodes[n as usize].next
    }

    /// Previous node to the left of `n`.
    #[inline(always)]
    pub fn prev(&self, n: NodeId) -> NodeId {
        self.nodes[n as usize].prev
    }

    /// Vertex of node `n`.
    #[inline(always)]
    pub fn vertex(&self, n: NodeId) -> VertexId {
        self.nodes[n as usize].v
    }

    /// Boundary half-edge under the segment right of `n`.
    #[inline(always)]
    pub fn edge(&self, n: NodeId) -> EdgeId {
        self.nodes[n as usize].edge
    }

    /// Sets the boundary half-edge under the segment right of `n`.
    #[inline(always)]
    pub fn set_edge(&mut self, n: NodeId, e: EdgeId) {
        self.nodes[n as usize].edge = e;
    }

    /// Number of nodes, `P-1` and `P-2` included.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// The front always holds at least `P-1` and `P-2`.
    #[cfg(any(test, feature = "dev"))]
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Largest number of nodes the front ever had.
    pub fn peak_len(&self) -> usize {
        self.peak_len
    }

    #[inline(always)]
    fn key(&self, x: f64) -> usize {
        let k = self.xmap.unit(x) * self.nb;
        (k as usize).min(self.buckets.len() - 1)
    }

    /// The node table and the x index (the buckets' start nodes, first and last nodes and
    /// minima), to move them elsewhere (the streaming sweep's spill).
    #[allow(clippy::type_complexity)]
    pub(crate) fn tables_mut(
        &mut self,
    ) -> (
        &mut SpillVec<Node>,
        &mut SpillVec<NodeId>,
        &mut SpillVec<NodeId>,
        &mut SpillVec<NodeId>,
        &mut SpillVec<f64>,
    ) {
        (
            &mut self.nodes,
            &mut self.buckets,
            &mut self.lead,
            &mut self.last,
            &mut self.low,
        )
    }

    /// Rebuilds the x index with `count` buckets: the start nodes, and the tree of groups with
    /// their first and last nodes and exact minima.
    fn rebuild_buckets(&mut self, count: usize) {
        refill(&mut self.buckets, count, NIL);
        self.nb = count as f64;
        self.levels = vec![0];
        let mut m = count;
        loop {
            let end = self.levels[self.levels.len() - 1] + m;
            self.levels.push(end);
            if m <= 1 {
                break;
            }
            m = m.div_ceil(FAN);
        }
        let total = self.levels[self.levels.len() - 1];
        refill(&mut self.lead, total, NIL);
        refill(&mut self.last, total, NIL);
        refill(&mut self.low, total, f64::INFINITY);
        let mut n = self.next(self.head);
        let mut walked = 0usize;
        while n != self.tail {
            let Node { x, y, .. } = self.nodes[n as usize];
            let k = self.key(x);
            if self.buckets[k] == NIL {
                self.buckets[k] = n;
                self.lead[k] = n;
            }
            self.last[k] = n;
            self.low[k] = self.low[k].min(y);
            n = self.next(n);
            walked += 1;
            // A front of millions of nodes (a line of points) spilled to a temporary file: the
            // walk would bring the whole node table into memory at once.
            if walked.is_multiple_of(RELEASE_EVERY) {
                self.release_index();
            }
        }
        for j in 1..self.levels.len() - 1 {
            let (below, here, end) = (self.levels[j - 1], self.levels[j], self.levels[j + 1]);
            for g in here..end {
                if g.is_multiple_of(RELEASE_EVERY) {
                    self.release_index();
                }
                let first = below + (g - here) * FAN;
                for c in first..(first + FAN).min(here) {
                    if self.lead[c] != NIL {
                        if self.lead[g] == NIL {
                            self.lead[g] = self.lead[c];
                        }
                        self.last[g] = self.last[c];
                        self.low[g] = self.low[g].min(self.low[c]);
                    }
                }
            }
        }
    }

    /// The rightmost real node whose bucket lies left of bucket `k`, or `P-1`: found through the
    /// groups' last nodes (exact at all times, see the module's doc), level by level, scanning
    /// at most `FAN - 1` groups a level.
    fn last_before(&self, k: usize) -> NodeId {
        let mut g = k;
        for j in 0..self.levels.len() - 1 {
            let base = self.levels[j];
            for c in (g & !(FAN - 1)..g).rev() {
                let n = self.last[base + c];
                if n != NIL {
                    return n;
                }
            }
            g >>= FAN_SHIFT;
        }
        self.head
    }

    /// Drops the resident pages of the node table and the x index when they are spilled
    /// (a no-op on the heap).
    fn release_index(&mut self) {
        self.nodes.release();
        self.buckets.release();
        self.lead.release();
        self.last.release();
        self.low.release();
    }

    /// The node `n` with `n.x <= x < next(n).x`: the left end of the segment under `x`.
    #[inline]
    pub fn locate(&self, x: f64) -> NodeId {
        let k0 = self.key(x);
        let (mut k, mut n) = (k0, self.buckets[k0]);
        while n == NIL {
            if k == 0 {
                n = self.head;
                break;
            }
            if k0 - k == NEAR_BUCKETS {
                // A long run of empty buckets (the front has shrunk under an index sized for
                // its peak, as over the top of a ring of points; a gap in the data): the
                // groups find the nearest node on the left in O(levels) steps, where the
                // bucket walk took one step a bucket at every point (quadratic).
                n = self.last_before(k0);
                break;
            }
            k -= 1;
            n = self.buckets[k];
        }
        let nodes = &self.nodes;
        if nodes[n as usize].x <= x {
            loop {
                let m = nodes[n as usize].next;
                if nodes[m as usize].x > x {
                    return n;
                }
                n = m;
            }
        } else {
            loop {
                n = nodes[n as usize].prev;
                if nodes[n as usize].x <= x {
                    return n;
                }
            }
        }
    }

    /// Inserts vertex `v` at `xy` right after node `left`; returns the new node.
    pub fn insert_after(&mut self, left: NodeId, v: VertexId, xy: [f64; 2]) -> NodeId {
        let right = self.next(left);
        let x = xy[0];
        let node = Node {
            x,
            y: xy[1],
            v,
            next: right,
            prev: left,
            edge: EdgeId(u32::MAX),
        };
        let n = match self.free.pop() {
            Some(n) => {
                self.nodes[n as usize] = node;
                n
            }
            None => {
                self.nodes.push(node);
                (self.nodes.len() - 1) as NodeId
            }
        };
        self.nodes[left as usize].next = n;
        self.nodes[right as usize].prev = n;
        self.len += 1;
        if self.len > self.peak_len {
            self.peak_len = self.len;
            if self.len > 2 * self.buckets.len() {
                self.rebuild_buckets(2 * self.buckets.len());
            }
        }
        let k = self.key(x);
        self.buckets[k] = n;
        let mut g = k;
        for j in 0..self.levels.len() - 1 {
            let i = self.levels[j] + g;
            let (first, end) = (self.lead[i], self.last[i]);
            if first == NIL {
                self.lead[i] = n;
                self.last[i] = n;
                self.low[i] = xy[1];
            } else {
                // The group's nodes are consecutive: `n` is its new first node when it comes just
                // before the old one, its new last when just after.
                if first == right {
                    self.lead[i] = n;
                }
                if end == left {
                    self.last[i] = n;
                }
                let m = self.low[i];
                if !m.is_nan() {
                    self.low[i] = m.min(xy[1]);
                }
            }
            g >>= FAN_SHIFT;
        }
        n
    }

    /// Removes node `n` (never `P-1` or `P-2`).
    pub fn remove(&mut self, n: NodeId) {
        debug_assert!(n != self.head && n != self.tail);
        let Node {
            prev, next, x, y, ..
        } = self.nodes[n as usize];
        self.nodes[prev as usize].next = next;
        self.nodes[next as usize].prev = prev;
        let k = self.key(x);
        if self.buckets[k] == n {
            // Invariant: a bucket holds NIL or a live node whose x falls in that bucket.
            let px = self.nodes[prev as usize].x;
            self.buckets[k] = if prev != self.head && self.key(px) == k {
                prev
            } else {
                NIL
            };
        }
        let mut g = k;
        for j in 0..self.levels.len() - 1 {
            let i = self.levels[j] + g;
            let (first, end) = (self.lead[i], self.last[i]);
            if first == n && end == n {
                self.lead[i] = NIL;
                self.last[i] = NIL;
                self.low[i] = f64::INFINITY;
            } else {
                if first == n {
                    self.lead[i] = next;
                }
                if end == n {
                    self.last[i] = prev;
                }
                if y <= self.low[i] {
                    self.low[i] = f64::NAN;
                }
            }
            g >>= FAN_SHIFT;
        }
        self.nodes[n as usize].next = NIL;
        self.nodes[n as usize].prev = NIL;
        self.free.push(n);
        self.len -= 1;
    }

    /// Lowest y of the front over `[x0, x1]`, conservatively: the minimum over the real nodes
    /// inside the span and the front's height where it enters and leaves the span, interpolated
    /// along the segment there and lowered by a bound on the rounding error (so floating point can
    /// only delay a finalisation; never below the lower end of that segment). Parts of the span
    /// left of the first real node or right of the last are ignored: no point exists there (the end
    /// nodes are the extreme points so far) and every later point lies above the sweep line.
    ///
    /// The scan stops as soon as the minimum so far is at or below `enough` (the caller only
    /// needs to know whether the front stays above it): a triangle whose disk spans a long front
    /// (the fan of a line of points and one point beside it) is then checked in O(1), not in
    /// O(front) each time (quadratic: 200,000 points took 430 s).
    ///
    /// At most `steps` nodes are scanned (`steps` is decreased by the nodes scanned): `None` when
    /// they were not enough to find a height at or below `enough` or to reach the span's end.
    pub fn min_y_within(&self, x0: f64, x1: f64, enough: f64, steps: &mut usize) -> Option<f64> {
        let nodes = &self.nodes;
        let mut n = self.locate(x0);
        if n == self.head {
            n = self.next(n);
        }
        let mut lo = f64::INFINITY;
        while n != self.tail && lo > enough {
            if *steps == 0 {
                return None;
            }
            *steps -= 1;
            let a = &nodes[n as usize];
            if a.x >= x0 {
                lo = lo.min(a.y);
            }
            if a.next == self.tail {
                break;
            }
            let b = &nodes[a.next as usize];
            if a.x < x0 && x0 < b.x {
                lo = lo.min(segment_low(a, b, x0));
            }
            if a.x < x1 && x1 < b.x {
                lo = lo.min(segment_low(a, b, x1));
                break;
            }
            if b.x > x1 {
                break;
            }
            n = a.next;
        }
        Some(lo)
    }

    /// [`Front::min_y_within`] without a step limit, the same value, in fewer steps: a group of
    /// buckets of the x index (see the module's doc) that lies inside the span and whose nodes all
    /// stay above `enough` counts by its minimum at once (then the walk goes on from its last
    /// node), where the node walk would visit each of its nodes (on a ring's steep sides,
    /// thousands under a small disk). The nodes of the buckets at the span's ends, and of a group
    /// that reaches `enough`, are walked one by one as there, so the early stop happens at the
    /// same node with the same minimum so far. `scanned` grows by the nodes and groups visited.
    pub fn min_y_indexed(&mut self, x0: f64, x1: f64, enough: f64, scanned: &mut u64) -> f64 {
        let k1 = self.key(x1);
        let mut n = self.locate(x0);
        if n == self.head {
            n = self.next(n);
        }
        let mut lo = f64::INFINITY;
        'walk: while n != self.tail && lo > enough {
            *scanned += 1;
            let a = self.nodes[n as usize];
            if a.x >= x0 {
                // The groups that start at `a` and end left of `x1`'s bucket: every node of one
                // is at or right of `a` and left of `x1`, so no segment between them crosses the
                // span's ends. The largest whose minimum stays above `enough` is skipped.
                let k = self.key(a.x);
                let mut top = 0;
                while top + 1 < self.levels.len() {
                    let g = k >> (FAN_SHIFT as usize * top);
                    if self.lead[self.levels[top] + g] != n || (g + 1) << (FAN_SHIFT as usize * top) > k1
                    {
                        break;
                    }
                    top += 1;
                }
                for j in (0..top).rev() {
                    let i = self.levels[j] + (k >> (FAN_SHIFT as usize * j));
                    if self.last[i] == n {
                        break;
                    }
                    let m = self.group_low(j, i, scanned);
                    if m > enough {
                        lo = lo.min(m);
                        n = self.last[i];
                        continue 'walk;
                    }
                }
                lo = lo.min(a.y);
            }
            if a.next == self.tail {
                break;
            }
            let b = &self.nodes[a.next as usize];
            if a.x < x0 && x0 < b.x {
                lo = lo.min(segment_low(&a, b, x0));
            }
            if a.x < x1 && x1 < b.x {
                lo = lo.min(segment_low(&a, b, x1));
                break;
            }
            if b.x > x1 {
                break;
            }
            n = a.next;
        }
        // The node walk's value, bit for bit: `tests::the_indexed_long_scan_returns_what_the_node_walk_returns`
        // (asserting it here on every call made the debug test suite walk every span again).
        lo
    }

    /// The lowest y of group `i` (of level `j`), recomputed if stale from the groups below or
    /// the bucket's nodes (`scanned` grows by what is visited).
    fn group_low(&mut self, j: usize, i: usize, scanned: &mut u64) -> f64 {
        let m = self.low[i];
        if !m.is_nan() || self.lead[i] == NIL {
            return m;
        }
        let mut m = f64::INFINITY;
        if j == 0 {
            let (mut n, end) = (self.lead[i], self.last[i]);
            loop {
                *scanned += 1;
                let a = &self.nodes[n as usize];
                m = m.min(a.y);
                if n == end {
                    break;
                }
                n = a.next;
            }
        } else {
            let (below, here) = (self.levels[j - 1], self.levels[j]);
            let first = below + (i - here) * FAN;
            for c in first..(first + FAN).min(here) {
                *scanned += 1;
                m = m.min(self.group_low(j - 1, c, scanned));
            }
        }
        self.low[i] = m;
        m
    }

    /// Is vertex `v`, at `x`, a node of the front?
    pub fn holds(&self, v: VertexId, x: f64) -> bool {
        self.nodes[self.locate(x) as usize].v == v
    }

    /// Iterates the nodes from `P-1` to `P-2`.
    #[cfg(any(test, feature = "dev"))]
    pub fn iter(&self) -> impl Iterator<Item = NodeId> + '_ {
        let mut n = self.head;
        std::iter::from_fn(move || {
            if n == NIL {
                return None;
            }
            let cur = n;
            n = self.next(n);
            Some(cur)
        })
    }
}

/// A lower bound of the height of the front segment `a`–`b` at `x` (`a.x < x < b.x`): the
/// interpolated height minus a bound on its rounding error, and never below the lower end.
#[inline]
fn segment_low(a: &Node, b: &Node, x: f64) -> f64 {
    let w = b.x - a.x;
    let dy = b.y - a.y;
    let y = a.y + (x - a.x) / w * dy;
    let err = 8.0 * f64::EPSILON * ((x.abs() + a.x.abs()) / w * dy.abs() + a.y.abs() + b.y.abs());
    (y - err).max(a.y.min(b.y))
}

#[cfg(test)]
mod tests;
