//! A uniform grid over a bounding box, and buckets of items (segments, points) per cell.
//!
//! Registration is *conservative*: a segment is put into every cell it touches, and perhaps a few
//! neighbours. The cell of a point is `(col(x), row(y))` with [`Grid::col`] and [`Grid::row`], both
//! monotone in their argument (they are a subtraction, a multiplication and a floor, each correctly
//! rounded, clamped into the grid), so cells are half-open intervals of the reals and every
//! argument below only needs "a segment is in every cell that contains one of its points". The
//! segment's x-range over a row is computed in floating point and widened by a margin far above
//! its rounding error (the cell side is kept above `2^-30` times the coordinate magnitude, so the
//! margin stays a tiny fraction of a cell).
//!
//! Buckets are built by sorting `(cell, item)` pairs, so each bucket lists its items in increasing
//! order whatever the thread count.

use rayon::prelude::*;

/// Smallest cell side relative to the largest coordinate magnitude.
const MIN_CELL_REL: f64 = 1.0 / (1u64 << 30) as f64;

/// Geometry of a uniform grid.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    x0: f64,
    y0: f64,
    side: f64,
    inv: f64,
    nx: u32,
    ny: u32,
    /// Absolute part of the registration margin (rounding error of coordinates this large).
    margin_abs: f64,
}

impl Grid {
    /// A grid over `[lo, hi]` with about `cells` square cells (at least one).
    pub fn new(lo: [f64; 2], hi: [f64; 2], cells: usize) -> Grid {
        let cells = cells.clamp(1, 1 << 28) as f64;
        let (w, h) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
        let mag = lo[0]
            .abs()
            .max(lo[1].abs())
            .max(hi[0].abs())
            .max(hi[1].abs());
        let mut side = (w * h / cells).sqrt();
        if side.is_nan() || side <= 0.0 {
            side = w.max(h) / cells;
        }
        side = side.max(mag * MIN_CELL_REL).max(f64::MIN_POSITIVE * 1e10);
        if !side.is_finite() {
            side = 1.0;
        }
        // Never more than ~2x the cells asked for, even when rounding the sides up.
        let mut nx = (w / side).floor() + 1.0;
        let mut ny = (h / side).floor() + 1.0;
        while nx * ny > 2.0 * cells + 4.0 {
            side *= 1.25;
            nx = (w / side).floor() + 1.0;
            ny = (h / side).floor() + 1.0;
        }
        Grid {
            x0: lo[0],
            y0: lo[1],
            side,
            inv: 1.0 / side,
            nx: nx as u32,
            ny: ny as u32,
            margin_abs: 64.0 * f64::EPSILON * (mag + side),
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.nx as usize * self.ny as usize
    }

    /// Number of columns.
    pub fn nx(&self) -> u32 {
        self.nx
    }

    /// Column of `x` (clamped into the grid).
    #[inline]
    pub fn col(&self, x: f64) -> u32 {
        let c = ((x - self.x0) * self.inv).floor();
        if c >= 0.0 {
            (c as u32).min(self.nx - 1)
        } else {
            0
        }
    }

    /// Row of `y` (clamped into the grid).
    #[inline]
    pub fn row(&self, y: f64) -> u32 {
        let r = ((y - self.y0) * self.inv).floor();
        if r >= 0.0 {
            (r as u32).min(self.ny - 1)
        } else {
            0
        }
    }

    /// Cell index of `(col, row)`.
    #[inline]
    pub fn cell(&self, col: u32, row: u32) -> u32 {
        row * self.nx + col
    }

    /// Cell of a point.
    #[inline]
    pub fn cell_of(&self, p: [f64; 2]) -> u32 {
        self.cell(self.col(p[0]), self.row(p[1]))
    }

    /// A point of cell `(col, row)` (its centre, if that rounds into the cell).
    pub fn centre(&self, col: u32, row: u32) -> Option<[f64; 2]> {
        let x = self.x0 + (col as f64 + 0.5) * self.side;
        let y = self.y0 + (row as f64 + 0.5) * self.side;
        (self.col(x) == col && self.row(y) == row).then_some([x, y])
    }

    /// Calls `f` for every cell meeting the box `[lo, hi]`.
    pub fn box_cells(&self, lo: [f64; 2], hi: [f64; 2], mut f: impl FnMut(u32)) {
        for r in self.row(lo[1])..=self.row(hi[1]) {
            for c in self.col(lo[0])..=self.col(hi[0]) {
                f(self.cell(c, r));
            }
        }
    }

    /// Calls `f` for every cell the closed segment `a-b` touches (and maybe a few more), each once.
    pub fn segment_cells(&self, a: [f64; 2], b: [f64; 2], mut f: impl FnMut(u32)) {
        let (xmin, xmax) = (a[0].min(b[0]), a[0].max(b[0]));
        let (ymin, ymax) = (a[1].min(b[1]), a[1].max(b[1]));
        let (c0, c1) = (self.col(xmin), self.col(xmax));
        let (r0, r1) = (self.row(ymin), self.row(ymax));
        if c0 == c1 || r0 == r1 {
            return self.box_cells([xmin, ymin], [xmax, ymax], f);
        }
        let m = self.side * 1e-3
            + self.margin_abs
            + 64.0 * f64::EPSILON * (a[0].abs() + a[1].abs() + b[0].abs() + b[1].abs());
        let slope = (b[0] - a[0]) / (b[1] - a[1]);
        let x_at = |y: f64| a[0] + (y - a[1]) * slope;
        for r in r0..=r1 {
            let ylo = (self.y0 + r as f64 * self.side - m).max(ymin);
            let yhi = (self.y0 + (r + 1) as f64 * self.side + m).min(ymax);
            let (xa, xb) = (x_at(ylo), x_at(yhi));
            let cl = self.col(xa.min(xb) - m).max(c0);
            let ch = self.col(xa.max(xb) + m).min(c1);
            for c in cl..=ch {
                f(self.cell(c, r));
            }
        }
    }
}

/// Fewest pairs [`Buckets::from_pairs`] sorts on every core.
const PAR_SORT_MIN: usize = 1 << 16;

/// Where each of `cells` cells starts in a list of items grouped by cell, from the items' cells.
fn starts(cells: usize, of: impl Iterator<Item = usize>) -> Vec<u32> {
    let mut start = vec![0u32; cells + 1];
    for c in of {
        start[c + 1] += 1;
    }
    for c in 0..cells {
        start[c + 1] += start[c];
    }
    start
}

/// Items per cell, in compressed rows: the items of cell `c` are `items[start[c]..start[c + 1]]`,
/// increasing.
#[derive(Clone, Debug, Default)]
pub(crate) struct Buckets {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Buckets {
    /// Builds the buckets from `(cell << 32) | item` words (any order, duplicates allowed).
    pub fn from_pairs(cells: usize, mut pairs: Vec<u64>) -> Buckets {
        // Small sets sort on the calling thread: rayon's split and join cost more than they
        // save there, and far more when the caller (a tile worker) is outside rayon's pool.
        if pairs.len() < PAR_SORT_MIN {
            pairs.sort_unstable();
        } else {
            pairs.par_sort_unstable();
        }
        pairs.dedup();
        let start = starts(cells, pairs.iter().map(|&w| (w >> 32) as usize));
        let items = pairs.into_iter().map(|w| w as u32).collect();
        Buckets { start, items }
    }

    /// Builds the buckets of items `0..n`, where `cells_of(i, f)` calls `f` once with each cell
    /// of item `i`: the same buckets as [`Buckets::from_pairs`], by two passes of counting,
    /// holding 4 bytes a pair instead of the pairs' 8 (and their growth) and a sort.
    pub fn counted(cells: usize, n: usize, cells_of: impl Fn(usize, &mut dyn FnMut(u32))) -> Buckets {
        let mut start = vec![0u32; cells + 1];
        for i in 0..n {
            cells_of(i, &mut |c| start[c as usize + 1] += 1);
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut fill = start[..cells].to_vec();
        let mut items = vec![0u32; start[cells] as usize];
        for i in 0..n {
            cells_of(i, &mut |c| {
                items[fill[c as usize] as usize] = i as u32;
                fill[c as usize] += 1;
            });
        }
        Buckets { start, items }
    }

    /// Buckets of the segments `segs` (endpoints looked up in `pts`) over `grid`.
    pub fn segments(grid: &Grid, pts: &[[f64; 2]], segs: &[[u32; 2]]) -> Buckets {
        let pairs: Vec<u64> = segs
            .par_iter()
            .enumerate()
            .flat_map_iter(|(i, s)| {
                let mut cells = Vec::new();
                grid.segment_cells(pts[s[0] as usize], pts[s[1] as usize], |c| {
                    cells.push((u64::from(c) << 32) | i as u64)
                });
                cells
            })
            .collect();
        Buckets::from_pairs(grid.len(), pairs)
    }

    /// Buckets of points.
    pub fn points(grid: &Grid, pts: &[[f64; 2]]) -> Buckets {
        let pairs: Vec<u64> = pts
            .par_iter()
            .enumerate()
            .map(|(i, &p)| (u64::from(grid.cell_of(p)) << 32) | i as u64)
            .collect();
        Buckets::from_pairs(grid.len(), pairs)
    }

    /// The items of cell `c`.
    #[inline]
    pub fn cell(&self, c: u32) -> &[u32] {
        &self.items[self.start[c as usize] as usize..self.start[c as usize + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact test of "segment touches the closed cell" would need the cells' real bounds; instead
    /// check on many points of the segment that their cell is registered.
    #[test]
    fn segment_cells_cover_the_segment() {
        let g = Grid::new([0.0, 0.0], [10.0, 7.0], 300);
        let mut s = 12345u64;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            let a = [rnd() * 10.0, rnd() * 7.0];
            let b = [rnd() * 10.0, rnd() * 7.0];
            let mut cells = Vec::new();
            g.segment_cells(a, b, |c| cells.push(c));
            let n = cells.len();
            cells.sort_unstable();
            cells.dedup();
            assert_eq!(cells.len(), n, "a cell reported twice");
            for k in 0..=1000 {
                let t = k as f64 / 1000.0;
                let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                assert!(cells.binary_search(&g.cell_of(p)).is_ok());
            }
            // Not much more than the cells crossed.
            let len = ((b[0] - a[0]).hypot(b[1] - a[1])) * g.inv;
            assert!(n as f64 <= 4.0 * len + 8.0, "{n} cells for length {len}");
        }
    }

    #[test]
    fn degenerate_boxes() {
        let g = Grid::new([5.0, 5.0], [5.0, 5.0], 100);
        assert_eq!(g.len(), 1);
        let g = Grid::new([0.0, 5.0], [10.0, 5.0], 100);
        assert!(g.len() >= 50 && g.len() <= 204, "{}", g.len());
        assert_eq!(g.row(5.0), 0);
        assert_eq!(g.col(-1.0), 0);
        assert_eq!(g.col(1e9), g.nx - 1);
    }

    #[test]
    fn buckets_sorted() {
        let g = Grid::new([0.0, 0.0], [4.0, 4.0], 16);
        let pts = [[0.5, 0.5], [3.5, 3.5], [0.6, 0.6], [0.5, 3.5]];
        let b = Buckets::points(&g, &pts);
        assert_eq!(b.cell(g.cell_of([0.5, 0.5])), &[0, 2]);
        let segs = [[0u32, 1], [3, 1]];
        let b = Buckets::segments(&g, &pts, &segs);
        assert_eq!(b.cell(g.cell_of([3.5, 3.5])), &[0, 1]);
    }

    #[test]
    fn counted_buckets_equal_sorted_ones() {
        let g = Grid::new([0.0, 0.0], [10.0, 10.0], 50);
        let mut pairs = Vec::new();
        for i in 0..200u32 {
            let (x, y) = (f64::from(i * 37 % 97) / 10.0, f64::from(i * 53 % 89) / 9.0);
            g.box_cells([x, y], [x + 1.5, y + 0.5], |c| pairs.push((c, i)));
        }
        let a = Buckets::counted(g.len(), 200, |i, f| {
            pairs.iter().filter(|p| p.1 == i as u32).for_each(|p| f(p.0))
        });
        let b = Buckets::from_pairs(
            g.len(),
            pairs.iter().map(|&(c, i)| (u64::from(c) << 32) | u64::from(i)).collect(),
        );
        assert_eq!((a.start, a.items), (b.start, b.items));
    }
}
