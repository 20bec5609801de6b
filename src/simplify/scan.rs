//! Scanning the grid cells inside one triangle: exact integer rasterisation (a cell belongs to a
//! triangle when its centre lies in the closed triangle, decided exactly on the cell indices), and
//! the candidate of largest vertical error (Soomart & Paitoonwattanakij's equation 4 with the
//! vertical distance, as in Garland & Heckbert's greedy insertion).

/// A grid value type: `f32` (half the memory and bandwidth, when the grid's values are exactly
/// representable) or `f64`. Missing cells are NaN.
pub trait Height: Copy + Into<f64> + Send + Sync + 'static {}
impl Height for f32 {}
impl Height for f64 {}

/// A rectangle of cells, bounds included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Clip {
    /// First and last column.
    pub c0: i64,
    /// Last column.
    pub c1: i64,
    /// First row.
    pub r0: i64,
    /// Last row.
    pub r1: i64,
}

impl Clip {
    /// The whole of a `cols × rows` grid.
    pub fn all(cols: i64, rows: i64) -> Self {
        Clip {
            c0: 0,
            c1: cols - 1,
            r0: 0,
            r1: rows - 1,
        }
    }

    /// Does it hold cell `(col, row)`?
    #[inline]
    pub fn holds(&self, col: i64, row: i64) -> bool {
        col >= self.c0 && col <= self.c1 && row >= self.r0 && row <= self.r1
    }
}

/// The cells a refinement reads: `heights` row-major, `stride` values a row (cell `(col, row)`
/// at `row · stride + col`), the cells that exist (`all`) and those that may become vertices
/// (`cand`: all of them for a whole grid; a window's interior, its border lines being fixed).
#[derive(Clone, Copy, Debug)]
pub struct Cells<'a, T> {
    /// The heights, NaN = missing.
    pub heights: &'a [T],
    /// Values per row.
    pub stride: i64,
    /// The cells of the grid or window.
    pub all: Clip,
    /// The cells a scan may choose.
    pub cand: Clip,
    /// Are some cells missing?
    pub may_miss: bool,
}

impl<'a, T: Height> Cells<'a, T> {
    /// A whole `cols`-wide grid.
    pub fn grid(heights: &'a [T], cols: i64) -> Self {
        let rows = heights.len() as i64 / cols.max(1);
        let all = Clip::all(cols, rows);
        Cells {
            heights,
            stride: cols,
            all,
            cand: all,
            may_miss: heights.iter().any(|&h| h.into().is_nan()),
        }
    }

    /// Height of cell `(col, row)` (NaN when missing).
    #[inline]
    pub fn at(&self, col: i64, row: i64) -> f64 {
        self.heights[(row * self.stride + col) as usize].into()
    }
}

/// A triangle in cell-index space: three cells and their heights (NaN for a missing corner).
#[derive(Clone, Copy, Debug)]
pub struct CellTriangle {
    /// `(col, row)` of the three vertices.
    pub v: [[i64; 2]; 3],
    /// Heights of the three vertices.
    pub z: [f64; 3],
}

/// One edge's bound, stepped from row to row.
#[derive(Clone, Copy, Debug, Default)]
struct EdgeStep {
    /// +1: an upper bound on the column; -1: a lower bound; 0: horizontal (no bound).
    kind: i64,
    base: i64,
    q: i64,
    rem: i64,
    dq: i64,
    dr: i64,
    d: i64,
}

/// `(floor(n / d), n mod d)` for `d > 0`: a floating-point quotient corrected to the exact one
/// (cheaper than a 64-bit integer division; exact for every `n`, `d` in `i64` range here).
#[inline(always)]
fn floor_divmod(n: i64, d: i64) -> (i64, i64) {
    // Truncation (one instruction; `floor` is a library call on baseline x86-64), then the
    // exact correction below.
    let mut q = (n as f64 / d as f64) as i64;
    let mut r = n - q * d;
    while r < 0 {
        q -= 1;
        r += d;
    }
    while r >= d {
        q += 1;
        r -= d;
    }
    (q, r)
}

/// What a scan found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ScanResult {
    /// Largest vertical error over the valid non-vertex cells (0 if none); `+∞` when the triangle
    /// must be split because it covers missing cells.
    pub error: f64,
    /// Cell index (`row * cols + col`) of the candidate, or `u64::MAX` when there is none.
    pub cell: u64,
    /// Missing cells (or missing corners) covered.
    pub missing: u32,
}

/// No candidate.
pub const NO_CELL: u64 = u64::MAX;

impl CellTriangle {
    /// The same triangle, counter-clockwise in cell-index space.
    pub fn ccw(mut self) -> Self {
        let [a, b, c] = self.v;
        let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if cross < 0 {
            self.v.swap(1, 2);
            self.z.swap(1, 2);
        }
        self
    }

    /// Calls `f(row, first_col, last_col)` for every row with cells whose centres lie in the
    /// closed triangle (which must be counter-clockwise, see [`CellTriangle::ccw`]); rows and
    /// columns are clamped to `clip`.
    #[inline]
    pub fn rows(&self, clip: Clip, mut f: impl FnMut(i64, i64, i64)) {
        let [a, b, c] = self.v;
        let rmin = a[1].min(b[1]).min(c[1]).max(clip.r0);
        let rmax = a[1].max(b[1]).max(c[1]).min(clip.r1);
        // Inside (left of p → q, or on it): dy·(x - px) <= dx·(r - py). With D = |dy| and
        // F(r) = floor(dx·(r - py) / D): x <= px + F(r) when dy > 0, x >= px - F(r) when dy < 0.
        // F is stepped exactly from row to row (quotient and remainder), with no division.
        let mut steps = [EdgeStep::default(); 3];
        for (k, (p, q)) in [(a, b), (b, c), (c, a)].into_iter().enumerate() {
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            if dy == 0 {
                // A horizontal edge bounds no row: every row of the triangle is on its inner side.
                continue;
            }
            let d = dy.abs();
            let (q, rem) = floor_divmod(dx * (rmin - p[1]), d);
            let (dq, dr) = floor_divmod(dx, d);
            steps[k] = EdgeStep {
                kind: dy.signum(),
                base: p[0],
                q,
                rem,
                dq,
                dr,
                d,
            };
        }
        for r in rmin..=rmax {
            let (mut lo, mut hi) = (clip.c0, clip.c1);
            for s in &mut steps {
                match s.kind {
                    1 => hi = hi.min(s.base + s.q),
                    -1 => lo = lo.max(s.base - s.q),
                    _ => {}
                }
                s.q += s.dq;
                s.rem += s.dr;
                if s.rem >= s.d {
                    s.rem -= s.d;
                    s.q += 1;
                }
            }
            if lo <= hi {
                f(r, lo, hi);
            }
        }
    }

    /// The plane `z = z0 + gx·(col - c0) + gy·(row - r0)` through the vertices (NaN slopes when a
    /// corner is missing or the triangle is degenerate).
    #[inline]
    pub fn plane(&self) -> (f64, f64) {
        let [a, b, c] = self.v;
        let (ux, uy) = ((b[0] - a[0]) as f64, (b[1] - a[1]) as f64);
        let (vx, vy) = ((c[0] - a[0]) as f64, (c[1] - a[1]) as f64);
        let (uz, vz) = (self.z[1] - self.z[0], self.z[2] - self.z[0]);
        let det = ux * vy - uy * vx;
        ((uz * vy - vz * uy) / det, (ux * vz - vx * uz) / det)
    }

    /// Does the closed (counter-clockwise) triangle contain cell `c`?
    pub fn contains(&self, c: [i64; 2]) -> bool {
        let [a, b, d] = self.v;
        let side = |p: [i64; 2], q: [i64; 2]| {
            (q[0] - p[0]) * (c[1] - p[1]) - (q[1] - p[1]) * (c[0] - p[0]) >= 0
        };
        side(a, b) && side(b, d) && side(d, a)
    }

    /// Vertical error of height `h` at cell `c` (same arithmetic as the scans).
    pub fn error_at(&self, c: [i64; 2], h: f64) -> f64 {
        let (gx, gy) = self.plane();
        let a = self.v[0];
        let zr = self.z[0] + gy * (c[1] - a[1]) as f64;
        (h - (zr + gx * (c[0] - a[0]) as f64)).abs()
    }

    fn is_vertex(&self, col: i64, row: i64) -> bool {
        self.v.iter().any(|v| v[0] == col && v[1] == row)
    }

    /// Scans the cells of the closed triangle: the valid non-vertex cell of `cells.cand` with the
    /// largest vertical error; or, when the triangle covers missing cells (anywhere in
    /// `cells.all`), the valid non-vertex cell of `cells.cand` nearest to their centroid, with
    /// error `+∞`.
    pub fn scan<T: Height>(&self, cells: &Cells<'_, T>) -> ScanResult {
        let (gx, gy) = self.plane();
        let [a, ..] = self.v;
        let z0 = self.z[0];
        let corner_missing = self.z.iter().any(|z| z.is_nan());
        let mut best = ScanResult {
            error: 0.0,
            cell: NO_CELL,
            missing: u32::from(corner_missing),
        };
        let (mut sx, mut sy) = (0.0f64, 0.0f64);
        let vrows = [self.v[0][1], self.v[1][1], self.v[2][1]];
        let (heights, stride, cand) = (cells.heights, cells.stride, cells.cand);
        self.rows(cells.all, |r, lo, hi| {
            let start = (r * stride) as usize;
            if cells.may_miss {
                let row = &heights[start + lo as usize..=start + hi as usize];
                let n = row.iter().filter(|&&h| h.into().is_nan()).count();
                if n > 0 {
                    best.missing += n as u32;
                    for (k, &h) in row.iter().enumerate() {
                        if h.into().is_nan() {
                            sx += (lo + k as i64) as f64;
                            sy += r as f64;
                        }
                    }
                }
            }
            if corner_missing || best.missing > 0 || r < cand.r0 || r > cand.r1 {
                return;
            }
            let (lo, hi) = (lo.max(cand.c0), hi.min(cand.c1));
            if lo > hi {
                return;
            }
            let row = &heights[start + lo as usize..=start + hi as usize];
            let zr = z0 + gy * (r - a[1]) as f64;
            let (e, k) = row_max(row, zr, gx, (lo - a[0]) as f64, best.error);
            if e > best.error {
                let col = lo + k as i64;
                if vrows.contains(&r) && self.is_vertex(col, r) {
                    // The vertex itself (rounding noise): look again without it.
                    let (e2, k2) = row_max_skipping(row, zr, gx, (lo - a[0]) as f64, |k| {
                        self.is_vertex(lo + k as i64, r)
                    });
                    if e2 > best.error {
                        best.error = e2;
                        best.cell = (start as i64 + lo + k2 as i64) as u64;
                    }
                } else {
                    best.error = e;
                    best.cell = (start as i64 + col) as u64;
                }
            }
        });
        if best.missing > 0 {
            let n = f64::from(best.missing.max(1));
            self.nearest_valid(cells, [sx / n, sy / n], &mut best);
        }
        best
    }

    /// Does some valid cell of the closed triangle (in `cells.all`) lie farther than `bound`
    /// from its plane, or is some cell missing? Stops at the first such cell.
    pub fn exceeds<T: Height>(&self, cells: &Cells<'_, T>, bound: f64) -> bool {
        if self.z.iter().any(|z| z.is_nan()) {
            return true;
        }
        let (gx, gy) = self.plane();
        let [a, ..] = self.v;
        let mut out = false;
        self.rows(cells.all, |r, lo, hi| {
            if out {
                return;
            }
            let start = (r * cells.stride) as usize;
            let row = &cells.heights[start + lo as usize..=start + hi as usize];
            let zr = self.z[0] + gy * (r - a[1]) as f64;
            let x0 = (lo - a[0]) as f64;
            out = row.iter().enumerate().any(|(k, &h)| {
                let h: f64 = h.into();
                let e = (h - (zr + gx * (x0 + k as f64))).abs();
                e > bound || e.is_nan()
            });
        });
        out
    }

    /// For a triangle over missing cells: the valid non-vertex cell of `cells.cand` nearest to
    /// `centre`.
    fn nearest_valid<T: Height>(
        &self,
        cells: &Cells<'_, T>,
        centre: [f64; 2],
        best: &mut ScanResult,
    ) {
        let mut d_best = f64::INFINITY;
        best.cell = NO_CELL;
        best.error = 0.0;
        self.rows(cells.cand, |r, lo, hi| {
            for c in lo..=hi {
                let i = (r * cells.stride + c) as usize;
                if cells.heights[i].into().is_nan() || self.is_vertex(c, r) {
                    continue;
                }
                let d = (c as f64 - centre[0]).powi(2) + (r as f64 - centre[1]).powi(2);
                if d < d_best {
                    d_best = d;
                    best.cell = i as u64;
                    best.error = f64::INFINITY;
                }
            }
        });
    }
}

/// Largest `|h_k - (z + g·(x0 + k))|` over the row and its index (first of equals); 0 for an
/// empty row. The same expression is used everywhere an error is measured, so that the bound
/// checked while refining is the bound reported.
#[inline]
/// The largest `|h - (z + g·(x0 + k))|` over the row and its index `k`; the index is only looked
/// for when the maximum exceeds `floor` (the caller's best so far), otherwise it is 0.
fn row_max<T: Height>(row: &[T], z: f64, g: f64, x0: f64, floor: f64) -> (f64, usize) {
    // Two passes: a maximum over four lanes that the compiler vectorises (NaN never wins a
    // comparison), then, only if it beats `floor`, the index of that maximum.
    let mut lanes = [0.0f64; 4];
    let mut chunks = row.chunks_exact(4);
    let mut xb = x0;
    for c in &mut chunks {
        for l in 0..4 {
            let e = (c[l].into() - (z + g * (xb + l as f64))).abs();
            lanes[l] = if e > lanes[l] { e } else { lanes[l] };
        }
        xb += 4.0;
    }
    for (l, &h) in chunks.remainder().iter().enumerate() {
        let e = (h.into() - (z + g * (xb + l as f64))).abs();
        lanes[l] = if e > lanes[l] { e } else { lanes[l] };
    }
    let m = lanes[0].max(lanes[1]).max(lanes[2].max(lanes[3]));
    if m <= floor {
        return (m, 0);
    }
    for (k, &h) in row.iter().enumerate() {
        if (h.into() - (z + g * (x0 + k as f64))).abs() == m {
            return (m, k);
        }
    }
    (m, 0)
}

fn row_max_skipping<T: Height>(
    row: &[T],
    z: f64,
    g: f64,
    x0: f64,
    skip: impl Fn(usize) -> bool,
) -> (f64, usize) {
    let (mut m, mut at) = (0.0f64, 0);
    for (k, &h) in row.iter().enumerate() {
        let e = (h.into() - (z + g * (x0 + k as f64))).abs();
        if e > m && !skip(k) {
            m = e;
            at = k;
        }
    }
    (m, at)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells(t: &CellTriangle, cols: i64) -> Vec<(i64, i64)> {
        let mut out = Vec::new();
        t.ccw().rows(Clip::all(cols, cols), |r, lo, hi| {
            out.extend((lo..=hi).map(|c| (c, r)))
        });
        out
    }

    #[test]
    fn rasterisation_is_exact_on_the_closed_triangle() {
        for v in [
            [[0, 0], [6, 2], [2, 5]],
            [[0, 0], [7, 0], [3, 4]],
            [[1, 5], [8, 5], [3, 0]],
            [[0, 0], [1, 7], [0, 9]],
            [[2, 1], [9, 8], [4, 8]],
        ] {
            rasterise_exactly(v);
        }
    }

    fn rasterise_exactly(v: [[i64; 2]; 3]) {
        let t = CellTriangle { v, z: [0.0; 3] }.ccw();
        let got = cells(&t, 100);
        let inside = |c: i64, r: i64| {
            let ok = |p: [i64; 2], q: [i64; 2]| {
                (q[0] - p[0]) * (r - p[1]) - (q[1] - p[1]) * (c - p[0]) >= 0
            };
            let [a, b, cc] = t.v;
            ok(a, b) && ok(b, cc) && ok(cc, a)
        };
        let mut want = Vec::new();
        for r in -1..12 {
            for c in -1..12 {
                if inside(c, r) {
                    want.push((c, r));
                }
            }
        }
        assert_eq!(got, want, "{v:?}");
        // Clockwise input gives the same cells.
        let cw = CellTriangle {
            v: [v[0], v[2], v[1]],
            z: [0.0; 3],
        };
        assert_eq!(cells(&cw, 100), want);
    }

    #[test]
    fn floor_divmod_is_exact() {
        for n in -200i64..200 {
            for d in 1i64..40 {
                assert_eq!(floor_divmod(n, d), (n.div_euclid(d), n.rem_euclid(d)));
            }
        }
        for (n, d) in [(1i64 << 40, 3i64), (-(1 << 45) + 1, 7), (1 << 31, 46_341)] {
            assert_eq!(floor_divmod(n, d), (n.div_euclid(d), n.rem_euclid(d)));
        }
    }

    #[test]
    fn candidate_is_the_largest_error_and_never_a_vertex() {
        let cols = 5;
        let mut h = vec![0.0; 25];
        h[2 * 5 + 1] = 3.0; // (1, 2)
        h[5 + 3] = -4.0; // (3, 1): inside? triangle below covers it
        let t = CellTriangle {
            v: [[0, 0], [4, 0], [0, 4]],
            z: [0.0; 3],
        };
        let s = t.ccw().scan(&Cells::grid(&h, cols));
        assert_eq!(s.cell, 5 + 3);
        assert_eq!(s.error, 4.0);
        h[4] = 100.0; // a vertex: ignored
        let t2 = CellTriangle {
            v: [[0, 0], [4, 0], [0, 4]],
            z: [0.0, 0.0, 0.0],
        };
        assert_eq!(t2.ccw().scan(&Cells::grid(&h, cols)).cell, 5 + 3);
    }
}
