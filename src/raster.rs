//! The geometry of a north-up raster grid: the one place where cells, their centres and their
//! alignment are defined (writers are in [`crate::output`]).
//!
//! # Conventions
//!
//! A [`GridSpec`] describes `cols × rows` square cells of side `cell`. Row 0 is the **northern**
//! row (largest `y`), as in GeoTIFF and ESRI ASCII grids; column 0 is the western one. Cells are
//! areas ("pixel is area"): [`GridSpec::origin`] is the outer upper-left **corner** of cell
//! (0, 0), and the value of a cell is the surface's value at the cell's **centre**.
//!
//! # Alignment
//!
//! Grids that sweeptin produces are *aligned* to a lattice of the cell size ([`Align`]), so
//! rasters from separate runs over adjacent tiles line up exactly and a mosaic of them equals one
//! run over the whole area:
//! - [`Align::Edges`] (the default): cell **edges** lie on whole multiples of the cell size, and
//!   centres at `(k + ½) × cell` — the convention of GDAL's `-tap`, LAStools' `-use_tile_bb` and
//!   lasR, so a 1 km tile at 1 m has 1000 × 1000 cells that cover it exactly;
//! - [`Align::Centres`]: cell **centres** lie on whole multiples, `x = kx × cell` — the lattice of
//!   IGN's LiDAR HD DTM tiles (a 50 m tile at 0.5 m has its 100 × 100 centres on the tile's
//!   0.5 m lattice, its edges a quarter of a metre outside).
//!
//! A grid stores its lattice indices `kx`, `ky` and its alignment, and every centre is computed
//! from them ([`GridSpec::centre_x`], [`GridSpec::centre_y`]): the same bits in every run.
//!
//! Which cells a grid has is decided in one place, [`GridPlan`], from a cell size, a
//! [`GridExtent`] and an [`Align`]:
//! - [`GridExtent::Auto`]: every centre inside the bounds of the data;
//! - [`GridExtent::BBox`]: the centres in `[xmin, xmax) × (ymin, ymax]` (with edge alignment,
//!   exactly the cells that tile the box), so boxes that touch share no cell and leave none out:
//!   a cell belongs to the box that holds its centre. The box's sides must be multiples of the
//!   cell size, or are rounded outwards to them with `snap`.

use crate::crs::Crs;
use crate::error::{Error, Result};
use std::ops::Range;

/// Where a grid's lattice puts the cells (see the module docs).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Align {
    /// Cell edges on whole multiples of the cell size (GDAL `-tap`, LAStools, lasR).
    #[default]
    Edges,
    /// Cell centres on whole multiples of the cell size.
    #[value(alias = "centers")]
    Centres,
}

impl Align {
    /// The centre of lattice index `k` is `(k + offset) × cell`.
    pub(crate) fn offset(self) -> f64 {
        match self {
            Align::Edges => 0.5,
            Align::Centres => 0.0,
        }
    }
}

/// The relative margin by which [`GridSpec::around`]'s quotient must clear a lattice
/// index to decide without the exact test (2⁻⁴⁰: a thousand times its rounding error).
const QUOTIENT_MARGIN: f64 = 1.0 / (1u64 << 40) as f64;

/// A north-up grid of square cells on the lattice of the cell size ([`Align`]).
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// Side of a cell (> 0), in the units of the coordinates.
    pub cell: f64,
    /// Number of columns.
    pub cols: u32,
    /// Number of rows.
    pub rows: u32,
    /// The value stored in cells without data.
    pub nodata: f32,
    /// Coordinate reference system, when known.
    pub crs: Option<Crs>,
    /// Lattice index of the western column's centre (`x = kx0 × cell`).
    kx0: i64,
    /// Lattice index of the southern row's centre (`y = ky0 × cell`).
    ky0: i64,
    /// Where the lattice puts the cells.
    align: Align,
}

impl GridSpec {
    /// The grid whose lower-left cell centre is `(kx0 × cell, ky0 × cell)`: centres on whole
    /// multiples of the cell size ([`Align::Centres`]; [`GridSpec::with_align`] changes it).
    pub fn aligned(cell: f64, kx0: i64, ky0: i64, cols: u32, rows: u32, nodata: f32) -> GridSpec {
        GridSpec {
            cell,
            cols,
            rows,
            nodata,
            crs: None,
            kx0,
            ky0,
            align: Align::Centres,
        }
    }

    /// The same lattice indices with alignment `align`: with [`Align::Edges`] the lower-left
    /// cell covers `[kx0 × cell, (kx0 + 1) × cell] × [ky0 × cell, (ky0 + 1) × cell]`.
    pub fn with_align(mut self, align: Align) -> GridSpec {
        self.align = align;
        self
    }

    /// The grid's alignment.
    pub fn align(&self) -> Align {
        self.align
    }

    /// The coordinate of lattice index `k`: the one formula for where centres are.
    #[inline]
    fn at(&self, k: i64) -> f64 {
        match self.align {
            Align::Centres => k as f64 * self.cell,
            Align::Edges => (k as f64 + 0.5) * self.cell,
        }
    }

    /// The lower (western or southern) edge of the cells of lattice index `k`.
    fn edge(&self, k: i64) -> f64 {
        match self.align {
            Align::Centres => self.at(k) - self.cell / 2.0,
            Align::Edges => k as f64 * self.cell,
        }
    }

    /// Lattice index of the northern row's centre.
    fn ky_top(&self) -> i64 {
        self.ky0 + i64::from(self.rows) - 1
    }

    /// Upper-left outer corner `[x, y]` of cell (0, 0) (row 0 is the northern row).
    pub fn origin(&self) -> [f64; 2] {
        match self.align {
            Align::Centres => [
                self.edge(self.kx0),
                self.at(self.ky_top()) + self.cell / 2.0,
            ],
            Align::Edges => [self.edge(self.kx0), self.edge(self.ky_top() + 1)],
        }
    }

    /// `x` of the centre of column `col`.
    pub fn centre_x(&self, col: u32) -> f64 {
        self.at(self.kx0 + i64::from(col))
    }

    /// `y` of the centre of row `row` (row 0 is the northern row).
    pub fn centre_y(&self, row: u32) -> f64 {
        self.at(self.ky_top() - i64::from(row))
    }

    /// The columns whose centres may lie in `[xmin, xmax]`: all of those, and at most one more
    /// on each side (an exact test decides).
    pub fn cols_over(&self, xmin: f64, xmax: f64) -> Range<u32> {
        let (c, off) = (self.cell, self.align.offset());
        let lo = ((xmin / c - off).floor() as i64).max(self.kx0);
        let hi = ((xmax / c - off).ceil() as i64).min(self.kx0 + i64::from(self.cols) - 1);
        if hi < lo {
            return 0..0;
        }
        (lo - self.kx0) as u32..(hi - self.kx0 + 1) as u32
    }

    /// The rows whose centres may lie in `[ymin, ymax]`: all of those, and at most one more on
    /// each side (an exact test decides).
    pub fn rows_over(&self, ymin: f64, ymax: f64) -> Range<u32> {
        let (c, off) = (self.cell, self.align.offset());
        let top = self.ky_top();
        let lo = ((ymin / c - off).floor() as i64).max(self.ky0);
        let hi = ((ymax / c - off).ceil() as i64).min(top);
        if hi < lo {
            return 0..0;
        }
        (top - hi) as u32..(top - lo + 1) as u32
    }

    /// Might a cell centre lie in the closed bounding box of triangle `t`? `false` only when none
    /// does (exact comparisons with the centres' coordinates): most triangles of dense lidar hold
    /// no centre, and a DEM skips them before any exact test.
    pub fn may_hold_centre(&self, t: &[[f64; 3]; 3]) -> bool {
        let [xmin, ymin, xmax, ymax] = crate::geom::tri_bbox(t);
        let inv = 1.0 / self.cell;
        self.axis_holds(ymin, ymax, self.ky0, self.ky_top(), inv)
            && self.axis_holds(
                xmin,
                xmax,
                self.kx0,
                self.kx0 + i64::from(self.cols) - 1,
                inv,
            )
    }

    /// Where `p` lies among the centres, for [`GridSpec::keys_hold_centre`]: the first column
    /// whose centre's `x` is at least `p`'s and the last at most it, then the same for rows
    /// (from the southern one), counted from the grid's first and clamped to one beyond it.
    /// Computed once per vertex, they decide [`GridSpec::may_hold_centre`] for every triangle
    /// on it with integer comparisons: the lowest first and the highest last of a triangle's
    /// vertices are those of its box's sides, the centre coordinates being monotone. Only for
    /// grids with fewer than 2³¹ − 1 columns and rows ([`GridSpec::has_lattice_keys`]).
    pub fn lattice_keys(&self, p: &[f64; 3]) -> [i32; 4] {
        let rel = |k: i64, k0: i64, n: u32| k.saturating_sub(k0).clamp(-1, i64::from(n)) as i32;
        let inv = 1.0 / self.cell;
        let (x0, x1) = self.around(p[0], inv);
        let (y0, y1) = self.around(p[1], inv);
        [
            rel(x0, self.kx0, self.cols),
            rel(x1, self.kx0, self.cols),
            rel(y0, self.ky0, self.rows),
            rel(y1, self.ky0, self.rows),
        ]
    }

    /// The first lattice index whose coordinate is at least `v` and the last at most `v`;
    /// from the quotient `u = v / cell` (`inv` is `1 / cell`) when no index lies within a
    /// margin of it far above its rounding error (2⁻⁴⁰ × (|u| + 1) cells, about 10⁻⁶ of a 1 m
    /// cell at UTM coordinates: almost always), exactly otherwise.
    #[inline]
    fn around(&self, v: f64, inv: f64) -> (i64, i64) {
        let u = v * inv - self.align.offset();
        // The quotient's error and `at`'s rounding are below 2⁻⁵⁰ × (|u| + 1) here, so an
        // index clear of `u` by the margin is on the same side of `v`. (Beyond 2⁵² or not
        // finite: the exact test.)
        let margin = (u.abs() + 1.0) * QUOTIENT_MARGIN;
        if margin < 4096.0 {
            let (lo, hi) = ((u - margin).ceil(), (u + margin).floor());
            if lo > hi {
                let k = lo as i64;
                return (k, k - 1);
            }
        }
        (
            self.first_at_least(v),
            self.first_at_least(v.next_up()).saturating_sub(1),
        )
    }

    /// Do the grid's columns and rows fit [`GridSpec::lattice_keys`] (below `i32::MAX`)?
    pub fn has_lattice_keys(&self) -> bool {
        self.cols < i32::MAX as u32 && self.rows < i32::MAX as u32
    }

    /// [`GridSpec::may_hold_centre`] of the triangle whose vertices have the
    /// [`GridSpec::lattice_keys`] `k` (the same answer, exactly).
    #[inline]
    pub fn keys_hold_centre(&self, k: [[i32; 4]; 3]) -> bool {
        let first = |i: usize| k[0][i].min(k[1][i]).min(k[2][i]).max(0);
        let last = |i: usize, n: u32| k[0][i].max(k[1][i]).max(k[2][i]).min(n as i32 - 1);
        first(2) <= last(3, self.rows) && first(0) <= last(1, self.cols)
    }

    /// Does a lattice index in `lo..=hi` have its coordinate ([`GridSpec::at`]) in `[a, b]`?
    /// The first index at or above `a` must not pass the last at or below `b` (`inv` is
    /// `1 / cell`, see [`GridSpec::around`]).
    #[inline]
    fn axis_holds(&self, a: f64, b: f64, lo: i64, hi: i64, inv: f64) -> bool {
        self.around(a, inv).0.max(lo) <= self.around(b, inv).1.min(hi)
    }

    /// The lowest lattice index whose coordinate is at least `v` (exact: the quotient's
    /// rounding is corrected against [`GridSpec::at`]).
    #[inline]
    fn first_at_least(&self, v: f64) -> i64 {
        let mut k = (v / self.cell - self.align.offset()).ceil() as i64;
        while k < i64::MAX && self.at(k) < v {
            k += 1;
        }
        while k > i64::MIN && self.at(k - 1) >= v {
            k -= 1;
        }
        k
    }

    /// How many rows, counted from the southern one, have their centre strictly below `y`.
    pub fn rows_below(&self, y: f64) -> u32 {
        let k = self.first_at_least(y);
        k.saturating_sub(self.ky0).clamp(0, i64::from(self.rows)) as u32
    }

    /// The real-world extent `[xmin, ymin, xmax, ymax]` of the cells' areas.
    pub fn extent(&self) -> [f64; 4] {
        let o = self.origin();
        [
            o[0],
            o[1] - f64::from(self.rows) * self.cell,
            o[0] + f64::from(self.cols) * self.cell,
            o[1],
        ]
    }

    /// Number of cells.
    pub fn len(&self) -> u64 {
        u64::from(self.cols) * u64::from(self.rows)
    }

    /// Does the grid have no cell at all?
    pub fn is_empty(&self) -> bool {
        self.cols == 0 || self.rows == 0
    }

    /// Is `v` this grid's nodata value (bit for bit, so a NaN nodata works too)?
    pub fn is_nodata(&self, v: f32) -> bool {
        v.to_bits() == self.nodata.to_bits()
    }
}

/// Which cells a grid has (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum GridExtent {
    /// Every centre inside the bounds of the data.
    #[default]
    Auto,
    /// The centres in `[xmin, xmax) × (ymin, ymax]`.
    BBox {
        /// `[xmin, ymin, xmax, ymax]`.
        bbox: [f64; 4],
        /// Round the sides outwards to multiples of the cell size instead of refusing them.
        snap: bool,
    },
}

/// A cell size, an extent and an alignment, checked once ([`GridPlan::new`]); [`GridPlan::grid`]
/// then gives the grid's cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPlan {
    cell: f64,
    extent: GridExtent,
    align: Align,
    /// For a box, its lattice `(kx0, ky0, cols, rows)`, which does not depend on the data.
    fixed: Option<(i64, i64, u32, u32)>,
    /// Most cells a grid may have ([`GridPlan::limit`]; no limit by default).
    max_cells: u64,
}

/// The command line's default for `--max-cells`: 2³⁰ cells, 4 GiB of float32 (a 1 km tile at
/// 3 cm, 32 km × 32 km at 1 m); larger rasters are made by plans of tiles, or with the option
/// raised.
pub const DEFAULT_MAX_CELLS: u64 = 1 << 30;

impl Default for GridPlan {
    /// Cells of 1 over the data's bounds, edges on whole numbers.
    fn default() -> Self {
        GridPlan {
            cell: 1.0,
            extent: GridExtent::Auto,
            align: Align::Edges,
            fixed: None,
            max_cells: u64::MAX,
        }
    }
}

/// How far a value may be from a multiple of the cell size and still count as one, in cells.
const MULTIPLE_TOLERANCE: f64 = 1e-6;

impl GridPlan {
    /// Cells of side `cell` over `extent`, on the lattice `align` says.
    ///
    /// # Errors
    /// [`Error::Options`] for a cell size that is not a positive number, a box side that is not
    /// a multiple of the cell size (without `snap`), or a box holding no centre or too many.
    pub fn new(cell: f64, extent: GridExtent, align: Align) -> Result<GridPlan> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::Options(format!(
                "the cell size must be a positive number, not {cell}"
            )));
        }
        let fixed = match extent {
            GridExtent::Auto => None,
            GridExtent::BBox { bbox, snap } => {
                let side = |v: f64, up: bool| -> Result<i64> {
                    let q = exact_index(v, cell)?;
                    let k = q.round();
                    if (q - k).abs() <= MULTIPLE_TOLERANCE {
                        Ok(k as i64)
                    } else if snap {
                        Ok(if up { q.ceil() } else { q.floor() } as i64)
                    } else {
                        Err(Error::Options(format!(
                            "the box edge at {v} is not on a multiple of the cell size {cell} \
                             (use --snap to round the box outwards)"
                        )))
                    }
                };
                let (x0, y0) = (side(bbox[0], false)?, side(bbox[1], false)?);
                let (x1, y1) = (side(bbox[2], true)?, side(bbox[3], true)?);
                // Centres in [xmin, xmax) × (ymin, ymax]: with edges on the multiples, the cells
                // between them.
                Some(match align {
                    Align::Centres => lattice(cell, x0, x1 - 1, y0 + 1, y1)?,
                    Align::Edges => lattice(cell, x0, x1 - 1, y0, y1 - 1)?,
                })
            }
        };
        Ok(GridPlan {
            cell,
            extent,
            align,
            fixed,
            max_cells: u64::MAX,
        })
    }

    /// The alignment.
    pub fn align(&self) -> Align {
        self.align
    }

    /// The same plan refusing grids of more than `max_cells` cells (checked now for a box, when
    /// the data's bounds are known for [`GridExtent::Auto`]).
    ///
    /// # Errors
    /// [`Error::Options`] when the box's grid has more cells, naming its size.
    pub fn limit(mut self, max_cells: u64) -> Result<GridPlan> {
        self.max_cells = max_cells;
        if let Some((_, _, cols, rows)) = self.fixed {
            self.check_size(cols, rows)?;
        }
        Ok(self)
    }

    fn check_size(&self, cols: u32, rows: u32) -> Result<()> {
        let cells = u64::from(cols) * u64::from(rows);
        if cells > self.max_cells {
            return Err(Error::Options(format!(
                "the grid would have {cols} × {rows} = {cells} cells of {} ({:.1} GiB as \
                 float32), more than --max-cells {}: use a larger --cell or a smaller --bbox, \
                 cut the job into tiles (sweeptin plan), or raise --max-cells",
                self.cell,
                cells as f64 * 4.0 / f64::from(1u32 << 30),
                self.max_cells
            )));
        }
        Ok(())
    }

    /// The cell size.
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// The extent.
    pub fn extent(&self) -> GridExtent {
        self.extent
    }

    /// The grid for data within `bounds` (`[xmin, ymin, xmax, ymax]`; only used by
    /// [`GridExtent::Auto`]).
    ///
    /// # Errors
    /// [`Error::TooFewPoints`] when `bounds` are empty (no data) and the extent is `Auto`,
    /// [`Error::NoArea`] when they have no area (the data on one line: no triangle);
    /// [`Error::Options`] when no centre of this cell size lies inside them, or too many (more
    /// than [`GridPlan::limit`]).
    pub fn grid(&self, bounds: [f64; 4], nodata: f32) -> Result<GridSpec> {
        let (kx0, ky0, cols, rows) = match self.fixed {
            Some(l) => l,
            None => {
                if !bounds.iter().all(|v| v.is_finite()) {
                    return Err(Error::TooFewPoints {
                        distinct: 0,
                        total: 0,
                    });
                }
                if !(bounds[2] > bounds[0] && bounds[3] > bounds[1]) {
                    return Err(Error::NoArea { bounds });
                }
                for v in bounds {
                    exact_index(v, self.cell)?;
                }
                let (c, off) = (self.cell, self.align.offset());
                let first = |v: f64| first_centre(v, c, off);
                let last = |v: f64| last_centre(v, c, off);
                lattice(
                    c,
                    first(bounds[0]),
                    last(bounds[2]),
                    first(bounds[1]),
                    last(bounds[3]),
                )?
            }
        };
        self.check_size(cols, rows)?;
        Ok(GridSpec::aligned(self.cell, kx0, ky0, cols, rows, nodata).with_align(self.align))
    }
}

/// The centre of lattice index `k`: `(k + off) × c`, as [`GridSpec`] computes it.
pub(crate) fn centre(k: i64, c: f64, off: f64) -> f64 {
    (k as f64 + off) * c
}

/// The first lattice index whose centre ([`centre`]) is at or above `v`, decided on the
/// centres themselves (the quotient's rounding put 700 / 0.7 at 1000.0000000000001).
/// `v / c` must be within 2^52 ([`exact_index`]).
pub(crate) fn first_centre(v: f64, c: f64, off: f64) -> i64 {
    let mut k = (v / c - off).ceil() as i64;
    while centre(k, c, off) < v {
        k += 1;
    }
    while centre(k - 1, c, off) >= v {
        k -= 1;
    }
    k
}

/// The last lattice index whose centre is at or below `v` (see [`first_centre`]).
pub(crate) fn last_centre(v: f64, c: f64, off: f64) -> i64 {
    let mut k = (v / c - off).floor() as i64;
    while centre(k, c, off) > v {
        k -= 1;
    }
    while centre(k + 1, c, off) <= v {
        k += 1;
    }
    k
}

/// `v / cell`, the lattice index of `v`, refused beyond 2^52 cells from 0, where indices are no
/// longer exact (`--cell 1e-14` at UTM coordinates spun forever looking for its first cell).
pub(crate) fn exact_index(v: f64, cell: f64) -> Result<f64> {
    let q = v / cell;
    if q.abs() > (1u64 << 52) as f64 {
        return Err(Error::Options(format!(
            "the coordinate {v} is {q:.3e} cells of {cell:e} from 0, more than 2^52: cell \
             positions are no longer exact there; use a larger --cell"
        )));
    }
    Ok(q)
}

/// The lattice of centres with indices `kx0 ..= kx1`, `ky0 ..= ky1`: `(kx0, ky0, cols, rows)`.
fn lattice(cell: f64, kx0: i64, kx1: i64, ky0: i64, ky1: i64) -> Result<(i64, i64, u32, u32)> {
    if kx1 < kx0 || ky1 < ky0 {
        return Err(Error::Options(format!(
            "the grid would have no cell (no cell centre of size {} inside the extent)",
            crate::fmt::Figure(cell)
        )));
    }
    let count = |lo: i64, hi: i64, what: &str| {
        hi.checked_sub(lo)
            .and_then(|d| u32::try_from(d).ok())
            .and_then(|d| d.checked_add(1))
            .ok_or_else(|| Error::Options(format!("too many {what} of size {cell}")))
    };
    Ok((
        kx0,
        ky0,
        count(kx0, kx1, "columns")?,
        count(ky0, ky1, "rows")?,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `may_hold_centre` and `keys_hold_centre` against every centre, for both alignments,
    /// UTM-sized coordinates, cells that are not powers of two, and boxes ending exactly on
    /// centres.
    #[test]
    fn may_hold_centre_is_exact() {
        let mut rng = crate::geom::rng::SplitMix64::new(7);
        for (cell, kx0, ky0) in [
            (1.0, 511_000, 122_000),
            (0.3, 1_700_000, 400_000),
            (2.5, -40, 3),
            (0.001, -(1 << 40), 1 << 40),
        ] {
            for align in [Align::Centres, Align::Edges] {
                let g = GridSpec::aligned(cell, kx0, ky0, 20, 20, -9999.0).with_align(align);
                let (x0, y0) = (g.centre_x(0), g.centre_y(19));
                for _ in 0..4000 {
                    let mut p = || {
                        let snap = rng.below(4);
                        let (x, y) = (
                            x0 + rng.range(-2.0, 22.0) * cell,
                            y0 + rng.range(-2.0, 22.0) * cell,
                        );
                        let on = |v: f64| g.at((v / cell - g.align.offset()).round() as i64);
                        // On a centre, or a few units in the last place beside one (the
                        // quotients' margin leaves these to the exact test).
                        let nudge = |v: f64, n: u64| match n % 3 {
                            0 => v,
                            1 => (0..n).fold(v, |v, _| v.next_up()),
                            _ => (0..n).fold(v, |v, _| v.next_down()),
                        };
                        match snap {
                            0 => [on(x), on(y), 0.0],
                            1 => {
                                let n = rng.below(6);
                                [nudge(on(x), n), nudge(on(y), n + 1), 0.0]
                            }
                            2 => [(x / cell).round() * cell, (y / cell).round() * cell, 0.0],
                            _ => [x, y, 0.0],
                        }
                    };
                    let c = [p(), p(), p()];
                    let t = if rng.below(2) == 0 {
                        c
                    } else {
                        [
                            c[0],
                            [c[0][0] + cell * 0.3, c[0][1], 0.0],
                            [c[0][0], c[0][1] + cell * 0.2, 0.0],
                        ]
                    };
                    let (xs, ys) = (t.map(|v| v[0]), t.map(|v| v[1]));
                    let fold = |v: [f64; 3], f: fn(f64, f64) -> f64| {
                        v[1..].iter().fold(v[0], |a, &b| f(a, b))
                    };
                    let (xmin, xmax, ymin, ymax) = (
                        fold(xs, f64::min),
                        fold(xs, f64::max),
                        fold(ys, f64::min),
                        fold(ys, f64::max),
                    );
                    let brute = (0..g.rows).any(|r| {
                        let y = g.centre_y(r);
                        y >= ymin && y <= ymax
                    }) && (0..g.cols).any(|c| {
                        let x = g.centre_x(c);
                        x >= xmin && x <= xmax
                    });
                    assert_eq!(g.may_hold_centre(&t), brute, "{t:?} cell {cell} {align:?}");
                    let keys = t.map(|v| g.lattice_keys(&v));
                    assert_eq!(g.keys_hold_centre(keys), brute, "{t:?} keys {keys:?}");
                }
            }
        }
    }

    /// A grid without columns or rows holds no centre, whatever the triangle.
    #[test]
    fn empty_grids_hold_no_centre() {
        for (cols, rows) in [(0, 5), (5, 0)] {
            let g = GridSpec::aligned(1.0, 0, 0, cols, rows, -9999.0);
            let t = [[-1.0, -1.0, 0.0], [9.0, -1.0, 0.0], [-1.0, 9.0, 0.0]];
            assert!(!g.may_hold_centre(&t));
            assert!(!g.keys_hold_centre(t.map(|v| g.lattice_keys(&v))));
        }
    }

    #[test]
    fn aligned_centres_fall_on_multiples() {
        let g = GridSpec::aligned(0.5, 1_541_100, 12_555_101, 100, 100, -9999.0);
        assert_eq!(g.origin(), [770_549.75, 6_277_600.25]);
        assert_eq!(g.centre_x(0), 770_550.0);
        assert_eq!(g.centre_y(0), 6_277_600.0);
        assert_eq!(g.centre_y(99), 6_277_550.5);
        assert_eq!(
            g.extent(),
            [770_549.75, 6_277_550.25, 770_599.75, 6_277_600.25]
        );
        assert_eq!(g.len(), 10_000);
    }

    /// A centre is the same bits in every grid that has it: `k × cell`, not a sum from a corner.
    #[test]
    fn centres_do_not_depend_on_the_grid() {
        let a = GridSpec::aligned(0.1, 7_705_500, 0, 10, 1, 0.0);
        let b = GridSpec::aligned(0.1, 7_705_503, 0, 10, 1, 0.0);
        assert_eq!(a.centre_x(3).to_bits(), b.centre_x(0).to_bits());
        assert_eq!(a.centre_x(3), 7_705_503.0 * 0.1);
    }

    #[test]
    fn nan_nodata_compares_by_bits() {
        let mut g = GridSpec::aligned(1.0, 0, 0, 1, 1, f32::NAN);
        assert!(g.is_nodata(f32::NAN));
        g.nodata = -9999.0;
        assert!(!g.is_nodata(f32::NAN) && g.is_nodata(-9999.0));
    }

    #[test]
    fn rows_and_columns_over_a_span() {
        // Centres x 10..=14, y 20..=23 (row 0 is y = 23).
        let g = GridSpec::aligned(1.0, 10, 20, 5, 4, 0.0);
        assert_eq!(g.cols_over(11.5, 12.5), 1..4);
        assert_eq!(g.cols_over(0.0, 100.0), 0..5);
        assert_eq!(g.cols_over(20.0, 30.0), 0..0);
        assert_eq!(g.rows_over(20.5, 21.5), 1..4);
        assert_eq!(g.rows_over(0.0, 5.0), 0..0);
        assert_eq!(g.rows_below(20.0), 0);
        assert_eq!(g.rows_below(20.5), 1);
        assert_eq!(g.rows_below(21.0), 1);
        assert_eq!(g.rows_below(100.0), 4);
        assert_eq!(g.rows_below(-100.0), 0);
    }

    fn lat(g: &GridSpec) -> (i64, i64, u32, u32) {
        (g.kx0, g.ky0, g.cols, g.rows)
    }

    #[test]
    fn plan_auto_and_bbox() {
        let auto = GridPlan::new(1.0, GridExtent::Auto, Align::Centres).unwrap();
        let g = auto.grid([0.5, 0.0, 3.0, 2.2], 0.0).unwrap();
        assert_eq!(lat(&g), (1, 0, 3, 3));
        let b = GridExtent::BBox {
            bbox: [0.0, 0.0, 4.0, 2.0],
            snap: false,
        };
        // Centres x 0..3, y 1..2.
        let g = GridPlan::new(1.0, b, Align::Centres)
            .unwrap()
            .grid([0.0; 4], 0.0)
            .unwrap();
        assert_eq!(lat(&g), (0, 1, 4, 2));
        let off = GridExtent::BBox {
            bbox: [0.2, 0.0, 4.0, 2.0],
            snap: false,
        };
        let e = GridPlan::new(1.0, off, Align::Centres).unwrap_err();
        assert!(e.to_string().contains("--snap"), "{e}");
        let snapped = GridExtent::BBox {
            bbox: [0.2, -0.5, 3.5, 2.0],
            snap: true,
        };
        let g = GridPlan::new(1.0, snapped, Align::Centres)
            .unwrap()
            .grid([0.0; 4], 0.0)
            .unwrap();
        assert_eq!(lat(&g), (0, 0, 4, 3));
        assert!(GridPlan::new(0.0, GridExtent::Auto, Align::Edges).is_err());
        assert!(GridPlan::new(f64::NAN, GridExtent::Auto, Align::Edges).is_err());
        assert!(auto.grid([0.2, 0.2, 0.8, 0.8], 0.0).is_err());
        // Data of no area (on one line): no triangle, a fact about the data.
        let e = auto.grid([1.0, 0.0, 1.0, 5.0], 0.0).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Input, "{e}");
        let none = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        assert!(matches!(
            auto.grid(none, 0.0),
            Err(Error::TooFewPoints { .. })
        ));
    }

    /// Edges on multiples: a 1 km tile at 1 m is 1000 × 1000 cells covering it exactly, the
    /// same from the data's bounds and from the tile's box; centres at half cells.
    #[test]
    fn edge_alignment_tiles_a_box_exactly() {
        let tile = GridExtent::BBox {
            bbox: [511_000.0, 122_000.0, 512_000.0, 123_000.0],
            snap: false,
        };
        let g = GridPlan::new(1.0, tile, Align::Edges)
            .unwrap()
            .grid([0.0; 4], -9999.0)
            .unwrap();
        assert_eq!((g.cols, g.rows), (1000, 1000));
        assert_eq!(g.origin(), [511_000.0, 123_000.0]);
        assert_eq!(g.extent(), [511_000.0, 122_000.0, 512_000.0, 123_000.0]);
        assert_eq!(g.centre_x(0), 511_000.5);
        assert_eq!(g.centre_y(0), 122_999.5);
        assert_eq!(g.centre_y(999), 122_000.5);
        // ARSO's points span 510999.895 – 512000.155: the centres inside are the same cells.
        let auto = GridPlan::new(1.0, GridExtent::Auto, Align::Edges).unwrap();
        let a = auto
            .grid(
                [510_999.895, 121_999.835, 512_000.155, 123_000.055],
                -9999.0,
            )
            .unwrap();
        assert_eq!(lat(&a), lat(&g));
        // Today's lattice is one cell more each way.
        let c = GridPlan::new(1.0, GridExtent::Auto, Align::Centres)
            .unwrap()
            .grid([511_000.0, 122_000.0, 512_000.0, 123_000.0], -9999.0)
            .unwrap();
        assert_eq!((c.cols, c.rows), (1001, 1001));
        // Spans and rows below work on the half-cell centres.
        let g = GridSpec::aligned(1.0, 10, 20, 5, 4, 0.0).with_align(Align::Edges);
        assert_eq!(g.cols_over(11.6, 12.4), 1..3);
        assert_eq!(g.rows_below(20.5), 0);
        assert_eq!(g.rows_below(20.6), 1);
        assert_eq!(g.rows_below(100.0), 4);
    }
}
