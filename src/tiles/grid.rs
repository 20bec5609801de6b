//! The global tile grid and its blocks.
//!
//! Space is cut into square **blocks** of side `block`, block `(bx, by)` holding the points with
//! `floor(x / block) = bx` and `floor(y / block) = by` (one function, [`TileGrid::block_of`], so
//! every point is in exactly one block). A **tile** is `2^shift × 2^shift` blocks: tile `(tx, ty)`
//! is the blocks with `bx >> shift = tx`, `by >> shift = ty`. Because `block = tile / 2^shift`
//! and dividing by a power of two is exact, `floor(x / block) >> shift = floor(x / tile)`: tile
//! membership is the same for any block size, so independent runs with the same tile size agree.
//!
//! Block keys are row-major (`by`, then `bx`), so a rectangle of blocks is one contiguous key
//! range per block row.

use crate::error::{Error, Result};

/// Largest block coordinate magnitude (keys pack two `i32`).
const MAX_BLOCK: f64 = (1u64 << 31) as f64 - 2.0;

/// Most halvings of a tile into blocks: `2^MAX_SHIFT` blocks a side.
pub(crate) const MAX_SHIFT: u32 = 20;

/// The largest coordinate magnitude in `bounds`.
fn magnitude(bounds: [f64; 4]) -> f64 {
    bounds.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// A rectangle of blocks: columns `x0 .. x1`, rows `y0 .. y1` (half-open).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub(crate) struct BlockRect {
    pub x0: i64,
    pub y0: i64,
    pub x1: i64,
    pub y1: i64,
}

impl BlockRect {
    /// No block at all?
    pub fn is_empty(&self) -> bool {
        self.x1 <= self.x0 || self.y1 <= self.y0
    }

    /// Grown by `n` blocks on every side.
    pub fn expand(&self, n: i64) -> BlockRect {
        BlockRect {
            x0: self.x0 - n,
            y0: self.y0 - n,
            x1: self.x1 + n,
            y1: self.y1 + n,
        }
    }

    /// The blocks in both.
    pub fn intersect(&self, o: &BlockRect) -> BlockRect {
        BlockRect {
            x0: self.x0.max(o.x0),
            y0: self.y0.max(o.y0),
            x1: self.x1.min(o.x1),
            y1: self.y1.min(o.y1),
        }
    }

    /// The smallest rectangle holding both.
    pub fn union(&self, o: &BlockRect) -> BlockRect {
        BlockRect {
            x0: self.x0.min(o.x0),
            y0: self.y0.min(o.y0),
            x1: self.x1.max(o.x1),
            y1: self.y1.max(o.y1),
        }
    }

    /// Does it hold every block of `o`?
    pub fn contains_rect(&self, o: &BlockRect) -> bool {
        o.is_empty() || (self.x0 <= o.x0 && self.y0 <= o.y0 && o.x1 <= self.x1 && o.y1 <= self.y1)
    }

    /// Does it hold block `(bx, by)`?
    pub fn contains(&self, bx: i64, by: i64) -> bool {
        self.x0 <= bx && bx < self.x1 && self.y0 <= by && by < self.y1
    }
}

/// The tile grid: tile side, and blocks of `tile / 2^shift`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct TileGrid {
    /// Side of a tile, in the units of the coordinates.
    pub tile: f64,
    /// `log2` of the blocks per tile side.
    pub shift: u32,
    /// Side of a block: `tile / 2^shift` (exact).
    pub block: f64,
}

impl TileGrid {
    /// A grid of tiles of side `tile`, cut into `2^shift` blocks per side.
    ///
    /// # Errors
    /// [`Error::Options`] for a tile side that is not a positive finite number;
    /// [`Error::Internal`] for more than `2^MAX_SHIFT` blocks a side (the callers derive fewer).
    pub fn new(tile: f64, shift: u32) -> Result<TileGrid> {
        if !(tile.is_finite() && tile > 0.0) {
            return Err(Error::Options(format!(
                "the tile size must be a positive number, not {tile}"
            )));
        }
        if shift > MAX_SHIFT {
            return Err(Error::Internal(format!(
                "tiles of {tile} cut into 2^{shift} blocks a side (at most 2^{MAX_SHIFT})"
            )));
        }
        let block = tile / f64::from(1u32 << shift);
        Ok(TileGrid { tile, shift, block })
    }

    /// Checks that the blocks of every point in `bounds` (`[xmin, ymin, xmax, ymax]`) have
    /// coordinates that fit the keys.
    ///
    /// # Errors
    /// [`Error::Options`] when the blocks are too small for coordinates this large.
    pub fn check_bounds(&self, bounds: [f64; 4]) -> Result<()> {
        if self.block < TileGrid::min_block(bounds) {
            let m = magnitude(bounds);
            return Err(Error::Options(format!(
                "tiles of {} are too small for coordinates as large as {m}",
                self.tile
            )));
        }
        Ok(())
    }

    /// The smallest block side whose keys hold the blocks of every point in `bounds`
    /// (`[xmin, ymin, xmax, ymax]`): blocks finer than this would number more than 2^31 between
    /// 0 and the coordinates (at 10^15, half a million units).
    pub fn min_block(bounds: [f64; 4]) -> f64 {
        magnitude(bounds) / MAX_BLOCK
    }

    /// The block of point `(x, y)`.
    #[inline]
    pub fn block_of(&self, x: f64, y: f64) -> (i64, i64) {
        (floor_i64(x / self.block), floor_i64(y / self.block))
    }

    /// The tile of block `(bx, by)`.
    #[inline]
    pub fn tile_of_block(&self, bx: i64, by: i64) -> (i64, i64) {
        (bx >> self.shift, by >> self.shift)
    }

    /// The tile of point `(x, y)`.
    #[inline]
    #[cfg(test)]
    pub fn tile_of(&self, x: f64, y: f64) -> (i64, i64) {
        let (bx, by) = self.block_of(x, y);
        self.tile_of_block(bx, by)
    }

    /// The blocks of tile `(tx, ty)`.
    pub fn tile_blocks(&self, tx: i64, ty: i64) -> BlockRect {
        let n = 1i64 << self.shift;
        BlockRect {
            x0: tx * n,
            y0: ty * n,
            x1: (tx + 1) * n,
            y1: (ty + 1) * n,
        }
    }

    /// The tiles covering the blocks of `r` (half-open, in tiles).
    pub fn tiles_of(&self, r: &BlockRect) -> BlockRect {
        if r.is_empty() {
            return BlockRect {
                x0: 0,
                y0: 0,
                x1: 0,
                y1: 0,
            };
        }
        let (tx0, ty0) = self.tile_of_block(r.x0, r.y0);
        let (tx1, ty1) = self.tile_of_block(r.x1 - 1, r.y1 - 1);
        BlockRect {
            x0: tx0,
            y0: ty0,
            x1: tx1 + 1,
            y1: ty1 + 1,
        }
    }

    /// The world rectangle `[xmin, ymin, xmax, ymax]` of the blocks of `r`. Points of those
    /// blocks lie in it up to the rounding of [`TileGrid::block_of`] (see [`TileGrid::margin`]).
    pub fn world(&self, r: &BlockRect) -> [f64; 4] {
        [
            r.x0 as f64 * self.block,
            r.y0 as f64 * self.block,
            r.x1 as f64 * self.block,
            r.y1 as f64 * self.block,
        ]
    }

    /// How far outside its block's world rectangle a point assigned to it may lie (the rounding of
    /// one division and one multiplication, with a wide safety factor), for coordinates up to
    /// `magnitude`.
    pub fn margin(&self, magnitude: f64) -> f64 {
        (magnitude.abs() + self.block) * 1e-12
    }

    /// The sort key of block `(bx, by)`: row-major.
    #[inline]
    pub fn key(bx: i64, by: i64) -> u64 {
        (((by + (1 << 31)) as u64) << 32) | ((bx + (1 << 31)) as u64 & 0xFFFF_FFFF)
    }

    /// The block of a key.
    #[inline]
    pub fn unkey(k: u64) -> (i64, i64) {
        (
            (k & 0xFFFF_FFFF) as i64 - (1 << 31),
            (k >> 32) as i64 - (1 << 31),
        )
    }
}

/// A power of two (`2^k`, any integer `k`) times `base` whose square holds about `per_area`
/// points at `density` points per unit area: the side of a block or tile.
pub(crate) fn side_for(base: f64, density: f64, points: f64) -> i32 {
    if !(density.is_finite() && density > 0.0) {
        return 0;
    }
    let side = (points / density).sqrt() / base;
    side.log2().round().clamp(-60.0, 60.0) as i32
}

/// `base × 2^k`.
pub(crate) fn pow2(base: f64, k: i32) -> f64 {
    base * 2f64.powi(k)
}

/// `q.floor() as i64` (saturating, NaN to 0) without a call into the C library: the float to
/// integer conversion truncates towards zero, one less below zero when that rounded up. Exact for
/// every `q` (a float beyond 2^52 in magnitude is already an integer).
#[inline]
fn floor_i64(q: f64) -> i64 {
    let t = q as i64;
    t.saturating_sub(i64::from((t as f64) > q))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_do_not_depend_on_the_block_size() {
        let a = TileGrid::new(128.0, 5).unwrap();
        let b = TileGrid::new(128.0, 0).unwrap();
        let c = TileGrid::new(128.0, 9).unwrap();
        let mut s = 0x1234_5678_9abc_def0u64;
        for _ in 0..100_000 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            let x = 511_000.0 + (s >> 11) as f64 / (1u64 << 53) as f64 * 1000.0;
            let y = 122_000.0 - (s >> 20) as f64 / (1u64 << 44) as f64 * 1000.0;
            let t = a.tile_of(x, y);
            assert_eq!(t, b.tile_of(x, y));
            assert_eq!(t, c.tile_of(x, y));
            assert_eq!(t, ((x / 128.0).floor() as i64, (y / 128.0).floor() as i64));
        }
        // Exactly on an edge: the upper tile.
        assert_eq!(a.tile_of(512.0, -128.0), (4, -1));
    }

    #[test]
    fn keys_are_row_major_and_invertible() {
        let ks: Vec<u64> = [(-3, -2), (5, -2), (-7, 0), (0, 0), (2, 0), (-1, 4)]
            .iter()
            .map(|&(x, y)| TileGrid::key(x, y))
            .collect();
        assert!(ks.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(TileGrid::unkey(TileGrid::key(-7, 3)), (-7, 3));
        assert_eq!(TileGrid::unkey(TileGrid::key(123_456, -99)), (123_456, -99));
    }

    #[test]
    fn rects() {
        let g = TileGrid::new(100.0, 2).unwrap();
        let r = g.tile_blocks(-1, 2);
        assert_eq!((r.x0, r.y0, r.x1, r.y1), (-4, 8, 0, 12));
        assert_eq!(g.world(&r), [-100.0, 200.0, 0.0, 300.0]);
        assert_eq!(
            g.tiles_of(&r.expand(1)),
            BlockRect {
                x0: -2,
                y0: 1,
                x1: 1,
                y1: 4
            }
        );
        assert!(r.expand(1).contains_rect(&r));
        assert_eq!(side_for(1.0, 13.2, 256.0), 2);
        assert_eq!(pow2(0.5, -1), 0.25);
    }

    #[test]
    fn floor_i64_is_floor() {
        let cases = [
            0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.999_999, -2.999_999, 1e15 + 0.5, -1e15 - 0.5,
            4.5e15, -4.5e15, 9.3e18, -9.3e18, 1e300, -1e300, f64::MIN_POSITIVE, -f64::MIN_POSITIVE,
            f64::INFINITY, f64::NEG_INFINITY, f64::NAN,
        ];
        for q in cases {
            assert_eq!(floor_i64(q), q.floor() as i64, "{q}");
        }
        for k in -2000..2000 {
            let q = f64::from(k) * 0.37;
            assert_eq!(floor_i64(q), q.floor() as i64, "{q}");
            let n = f64::from(k);
            for q in [n, n.next_up(), n.next_down()] {
                assert_eq!(floor_i64(q), q.floor() as i64, "{q}");
            }
        }
    }
}
