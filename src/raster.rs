//! The geometry of a north-up raster grid: the one place where cells, their centres and their
//! alignment are defined (writers are in [`crate::output`]).
//!
//! # Conventions
//!
//! A [`GridSpec`] describes `cols × rows` square cells of side `cell`. Row 0 is the **northern**
//! row (largest `y`), as in GeoTIFF and ESRI ASCII grids; column 0 is the western one. Cells are
//! areas ("pixel is area"): `origin` is the outer upper-left **corner** of cell (0, 0), and the
//! value of a cell is the surface's value at the cell's **centre**.
//!
//! Grids that sweeptin produces are *aligned*: every centre lies on a whole multiple of the cell
//! size, so rasters from separate runs over adjacent tiles line up exactly ([`GridSpec::aligned`]).

use crate::crs::Crs;

/// A north-up grid of square cells.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// Upper-left outer corner `[x, y]` of cell (0, 0) (row 0 is the northern row).
    pub origin: [f64; 2],
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
}

impl GridSpec {
    /// The grid whose lower-left cell centre is `(kx0 × cell, ky0 × cell)`: centres on whole
    /// multiples of the cell size.
    pub fn aligned(cell: f64, kx0: i64, ky0: i64, cols: u32, rows: u32, nodata: f32) -> GridSpec {
        let top = ky0 + i64::from(rows) - 1;
        GridSpec {
            origin: [
                kx0 as f64 * cell - cell / 2.0,
                top as f64 * cell + cell / 2.0,
            ],
            cell,
            cols,
            rows,
            nodata,
            crs: None,
        }
    }

    /// `x` of the centre of column `col`.
    pub fn centre_x(&self, col: u32) -> f64 {
        self.origin[0] + (f64::from(col) + 0.5) * self.cell
    }

    /// `y` of the centre of row `row` (row 0 is the northern row).
    pub fn centre_y(&self, row: u32) -> f64 {
        self.origin[1] - (f64::from(row) + 0.5) * self.cell
    }

    /// The real-world extent `[xmin, ymin, xmax, ymax]` of the cells' areas.
    pub fn extent(&self) -> [f64; 4] {
        [
            self.origin[0],
            self.origin[1] - f64::from(self.rows) * self.cell,
            self.origin[0] + f64::from(self.cols) * self.cell,
            self.origin[1],
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_centres_fall_on_multiples() {
        let g = GridSpec::aligned(0.5, 1_541_100, 12_555_101, 100, 100, -9999.0);
        assert_eq!(g.origin, [770_549.75, 6_277_600.25]);
        assert_eq!(g.centre_x(0), 770_550.0);
        assert_eq!(g.centre_y(0), 6_277_600.0);
        assert_eq!(g.centre_y(99), 6_277_550.5);
        assert_eq!(
            g.extent(),
            [770_549.75, 6_277_550.25, 770_599.75, 6_277_600.25]
        );
        assert_eq!(g.len(), 10_000);
    }

    #[test]
    fn nan_nodata_compares_by_bits() {
        let mut g = GridSpec::aligned(1.0, 0, 0, 1, 1, f32::NAN);
        assert!(g.is_nodata(f32::NAN));
        g.nodata = -9999.0;
        assert!(!g.is_nodata(f32::NAN) && g.is_nodata(-9999.0));
    }
}
