//! The georeferencing of a regular grid, shared by raster readers and writers.

/// Size, georeferencing, nodata value and CRS of a single-band grid.
///
/// Cell `(col, row)` covers the parallelogram whose corners are the images of `(col, row)` and
/// `(col + 1, row + 1)` under [`GridSpec::transform`]; its value belongs to its centre
/// `(col + 0.5, row + 0.5)`. Row 0 is the first row stored in the file (the northern one for a
/// usual north-up grid).
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// Number of columns.
    pub cols: u32,
    /// Number of rows.
    pub rows: u32,
    /// Affine transform from cell-corner `(col, row)` to world `(x, y)`, in GDAL's order:
    /// `x = t[0] + col·t[1] + row·t[2]`, `y = t[3] + col·t[4] + row·t[5]`.
    pub transform: [f64; 6],
    /// The value that marks a missing cell, if any (NaN cells are always missing).
    pub nodata: Option<f64>,
    /// Coordinate reference system: `EPSG:xxxx`, or WKT, when known.
    pub crs: Option<String>,
}

impl GridSpec {
    /// A north-up grid whose top-left corner is `(x0, y_top)`, with square cells of `size`.
    pub fn north_up(cols: u32, rows: u32, x0: f64, y_top: f64, size: f64) -> Self {
        GridSpec {
            cols,
            rows,
            transform: [x0, size, 0.0, y_top, 0.0, -size],
            nodata: None,
            crs: None,
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> u64 {
        u64::from(self.cols) * u64::from(self.rows)
    }

    /// World position of cell-grid position `(col, row)` (fractional; `+0.5` is a centre).
    #[inline]
    pub fn world(&self, col: f64, row: f64) -> [f64; 2] {
        let t = &self.transform;
        [
            t[0] + col * t[1] + row * t[2],
            t[3] + col * t[4] + row * t[5],
        ]
    }

    /// World position of the centre of cell `(col, row)`.
    #[inline]
    pub fn cell_center(&self, col: u32, row: u32) -> [f64; 2] {
        self.world(f64::from(col) + 0.5, f64::from(row) + 0.5)
    }

    /// Is the transform free of rotation and shear?
    pub fn is_axis_aligned(&self) -> bool {
        self.transform[2] == 0.0 && self.transform[4] == 0.0
    }

    /// Cell width and height in world units (absolute values, along the grid's axes).
    pub fn cell_size(&self) -> (f64, f64) {
        let t = &self.transform;
        (t[1].hypot(t[4]), t[2].hypot(t[5]))
    }

    /// Does the transform flip orientation (true for a usual north-up grid, whose row index grows
    /// southwards)?
    pub fn flips_orientation(&self) -> bool {
        let t = &self.transform;
        t[1] * t[5] - t[2] * t[4] < 0.0
    }

    /// Is `v` a missing value under this grid's nodata rule?
    #[inline]
    pub fn is_nodata(&self, v: f64) -> bool {
        v.is_nan() || self.nodata == Some(v)
    }
}
