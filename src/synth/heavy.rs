//! The distributions of the memory-bounded benchmark (`scripts/bench-memory.sh`): inputs whose
//! bounding box says little about where the points are, and the orders points arrive in.
//!
//! | generator | what it looks like | why |
//! |---|---|---|
//! | [`disc`] | uniform in the unit disc | the plain case |
//! | [`disc_far`] | [`disc`] plus one point 10⁶ units south | one far outlier: the bounding box is 10⁶ × 2 |
//! | [`kuzmin`] | Kuzmin's heavy-tailed disc (PBBS `2DKuzmin`) | a dense core and points out to ~`n` units |
//! | [`almost_line`] | points on a line, one beside it | all but one collinear |
//!
//! Orders ([`Order`]) rearrange any point set the way files deliver them.

use super::SplitMix64;
use std::f64::consts::TAU;

/// `n` points uniform in the unit disc about the origin, `z` uniform in `[0, 1)`.
pub fn disc(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed ^ 0x4449_5343);
    (0..n)
        .map(|_| {
            let r = rng.next_f64().sqrt();
            let a = TAU * rng.next_f64();
            [r * a.cos(), r * a.sin(), rng.next_f64()]
        })
        .collect()
}

/// [`disc`] of `n - 1` points plus one point 1,000,000 units south of the disc's centre (last).
pub fn disc_far(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut pts = disc(n.saturating_sub(1), seed);
    if n > 0 {
        pts.push([0.0, -1.0e6, 0.0]);
    }
    pts
}

/// `n` points of Kuzmin's distribution (the PBBS 2-D Delaunay benchmark's `2DKuzmin`): a random
/// direction and the radius `√(1/(1−s)² − 1)` for `s` uniform in `[0, 1)`, so half the points lie
/// within radius √3 and the farthest of `n` near radius `n`; `z` is the radius.
pub fn kuzmin(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed ^ 0x4B55_5A4D);
    (0..n)
        .map(|_| {
            let a = TAU * rng.next_f64();
            let s = rng.next_f64();
            let r = (1.0 / ((1.0 - s) * (1.0 - s)) - 1.0).sqrt();
            [r * a.cos(), r * a.sin(), r]
        })
        .collect()
}

/// `n − 1` points on the line `y = x / 2` at whole-number `x` in shuffled order, and one point
/// beside the line (last): a triangulation of `n − 2` thin triangles fanning out from it.
pub fn almost_line(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let m = n.saturating_sub(1);
    let mut pts: Vec<[f64; 3]> = (0..m)
        .map(|i| {
            let x = i as f64;
            [x, x / 2.0, 0.0]
        })
        .collect();
    shuffle(&mut pts, seed);
    if n > 0 {
        pts.push([m as f64 / 2.0, -1.0, 1.0]);
    }
    pts
}

/// The order in which points reach the tool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// As generated.
    Generated,
    /// By `y`, then `x` (the sweep's own order).
    Sorted,
    /// By `y` descending, then `x` descending.
    Reversed,
    /// Shuffled.
    Random,
    /// By square tiles of 1/8 of the extent, row by row, points in generated order within a tile.
    Tiles,
    /// Flight lines: strips along `y` of 1/16 of the extent, alternately north- and southbound,
    /// each strip in scan rows along `x` (a GPS-time order).
    Flightlines,
    /// Octree (EPT/COPC): every 4^k-th point first, level by level, each level in Morton order.
    Octree,
}

impl Order {
    /// All orders, by name.
    pub const ALL: [(&'static str, Order); 7] = [
        ("generated", Order::Generated),
        ("sorted", Order::Sorted),
        ("reversed", Order::Reversed),
        ("random", Order::Random),
        ("tiles", Order::Tiles),
        ("gpstime", Order::Flightlines),
        ("octree", Order::Octree),
    ];

    /// The order named `name` (see [`Order::ALL`]).
    pub fn from_name(name: &str) -> Option<Order> {
        Order::ALL.iter().find(|(n, _)| *n == name).map(|(_, o)| *o)
    }
}

/// Rearranges `pts` into `order` (deterministic for a seed).
pub fn arrange(pts: &mut [[f64; 3]], order: Order, seed: u64) {
    let cmp_yx = |a: &[f64; 3], b: &[f64; 3]| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0]));
    match order {
        Order::Generated => {}
        Order::Sorted => pts.sort_by(cmp_yx),
        Order::Reversed => pts.sort_by(|a, b| cmp_yx(b, a)),
        Order::Random => shuffle(pts, seed),
        Order::Tiles => {
            let cell = Cells::new(pts, 8);
            pts.sort_by_key(|p| {
                let (i, j) = cell.of(p);
                (j, i)
            });
        }
        Order::Flightlines => {
            let strips = Cells::new(pts, 16);
            let rows = Cells::new(pts, 1 << 12);
            pts.sort_by_key(|p| {
                let (s, _) = strips.of(p);
                let (_, row) = rows.of(p);
                let row = if s % 2 == 0 { row } else { u64::MAX - row };
                (s, row, ordered(p[0]))
            });
        }
        Order::Octree => {
            let cells = Cells::new(pts, 1 << 16);
            let mut keyed: Vec<(u32, u64, [f64; 3])> = pts
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let (x, y) = cells.of(p);
                    (octree_level(i as u64), morton(x, y), *p)
                })
                .collect();
            keyed.sort_by_key(|k| (k.0, k.1));
            for (p, k) in pts.iter_mut().zip(keyed) {
                *p = k.2;
            }
        }
    }
}

/// Level of the `i`-th point in an octree-like order: level k holds points `4^k - 1 ..`.
fn octree_level(i: u64) -> u32 {
    let mut level = 0;
    let mut first = 0u64;
    let mut size = 1u64;
    while i >= first + size {
        first += size;
        size = size.saturating_mul(4);
        level += 1;
    }
    level
}

/// `v`'s bits as an unsigned key in `f64::total_cmp` order.
fn ordered(v: f64) -> u64 {
    let b = v.to_bits();
    if b >> 63 == 1 { !b } else { b | 1 << 63 }
}

/// Interleaves the bits of `x` and `y` (each below 2^32).
fn morton(x: u64, y: u64) -> u64 {
    let spread = |mut v: u64| {
        v &= 0xFFFF_FFFF;
        v = (v | (v << 16)) & 0x0000_FFFF_0000_FFFF;
        v = (v | (v << 8)) & 0x00FF_00FF_00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    spread(x) | (spread(y) << 1)
}

/// A `k × k` grid of cells over the points' extent.
struct Cells {
    x0: f64,
    y0: f64,
    sx: f64,
    sy: f64,
    k: u64,
}

impl Cells {
    fn new(pts: &[[f64; 3]], k: u64) -> Cells {
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in pts {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
        let side = |lo: f64, hi: f64| if hi > lo { (hi - lo) / k as f64 } else { 1.0 };
        Cells {
            x0,
            y0,
            sx: side(x0, x1),
            sy: side(y0, y1),
            k,
        }
    }

    fn of(&self, p: &[f64; 3]) -> (u64, u64) {
        let c = |v: f64, lo: f64, s: f64| (((v - lo) / s) as u64).min(self.k - 1);
        (c(p[0], self.x0, self.sx), c(p[1], self.y0, self.sy))
    }
}

/// Fisher–Yates with the crate's generator.
fn shuffle<T>(v: &mut [T], seed: u64) {
    let mut rng = SplitMix64::new(seed ^ 0x5348_5546);
    for i in (1..v.len()).rev() {
        let j = rng.below(i as u64 + 1) as usize;
        v.swap(i, j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_are_permutations() {
        let pts = kuzmin(5000, 3);
        let mut want = pts.clone();
        want.sort_by(|a, b| {
            a.iter()
                .map(|v| v.to_bits())
                .cmp(b.iter().map(|v| v.to_bits()))
        });
        for (name, order) in Order::ALL {
            let mut got = pts.clone();
            arrange(&mut got, order, 1);
            got.sort_by(|a, b| {
                a.iter()
                    .map(|v| v.to_bits())
                    .cmp(b.iter().map(|v| v.to_bits()))
            });
            assert_eq!(got, want, "{name}");
        }
    }

    #[test]
    fn shapes() {
        let d = disc_far(1000, 1);
        assert_eq!(d.len(), 1000);
        assert!(d[..999].iter().all(|p| p[0].hypot(p[1]) <= 1.0));
        assert_eq!(d[999][1], -1.0e6);
        let k = kuzmin(100_000, 1);
        let inner = k.iter().filter(|p| p[2] < 3f64.sqrt()).count();
        assert!((45_000..55_000).contains(&inner), "{inner}");
        assert_eq!(octree_level(0), 0);
        assert_eq!(octree_level(1), 1);
        assert_eq!(octree_level(4), 1);
        assert_eq!(octree_level(5), 2);
        let l = almost_line(100, 1);
        assert_eq!(l.iter().filter(|p| p[1] * 2.0 != p[0]).count(), 1);
    }
}
