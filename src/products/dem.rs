//! DEM rasters from the triangle stream: linear interpolation inside each triangle at cell centres.
//!
//! # The grid
//!
//! Cell centres lie on whole multiples of the cell size (`x = kx × cell`, `y = ky × cell` for
//! integers `kx`, `ky`), so rasters of adjacent tiles from separate runs line up exactly and a
//! mosaic of them equals one run over the whole area. The extent is, by [`DemExtent`]:
//! - `Auto`: every centre inside the bounds of the points;
//! - `BBox`: the centres in `[xmin, xmax) × (ymin, ymax]` — the convention of IGN's LiDAR HD DTM
//!   tiles, so boxes that touch share no centre and leave none out. The box's sides must be
//!   multiples of the cell size, or are rounded outwards to them with `snap`.
//!
//! # Which triangle writes a cell
//!
//! A cell takes the value of the triangle that contains its centre, interpolated linearly
//! ([`Tri::value_at`]). A centre exactly on an edge or a vertex shared by several triangles is
//! written by exactly one of them: the one that contains the centre moved infinitesimally right,
//! then up ([`Tri::owns`]). A centre on the outer boundary of the TIN, which no triangle owns that
//! way, is still inside the closed triangle(s) it touches: they write it only if no owner wrote it.
//! Values on edges and vertices are computed from the edge's endpoints alone, so they are the same
//! bits whichever triangle writes them, and the raster does not depend on the order of the stream.
//! Cells whose centre no triangle covers keep the nodata value.
//!
//! # Memory
//!
//! Rows live in memory from the lowest row not yet written (the sweep's watermark) up to the top
//! of the highest triangle seen: a band of rows. [`TriangleSink::watermark`] writes the rows below
//! it to the file. A late triangle below the watermark writes its cells into the file (random
//! access), so it is handled exactly: its cells are queued (at most [`LATE_BATCH`] at a time)
//! and applied in arrival order, one read and one write per row span, when the queue is full and
//! at the end.

use super::geom::Tri;
use crate::error::{Error, Result};
use crate::output::raster::{GridWriter, RasterFormat, create_grid_writer};
use crate::raster::GridSpec;
use crate::sink::{StreamInfo, TriangleSink};
use serde_json::json;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};

/// Late cells queued before they are applied to the file (16 bytes each).
pub const LATE_BATCH: usize = 1 << 16;

/// Which cells the raster has (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum DemExtent {
    /// Every centre inside the bounds of the input points.
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

/// Options of a [`DemSink`].
#[derive(Clone, Debug)]
pub struct DemOptions {
    /// Cell size (> 0).
    pub cell: f64,
    /// Extent.
    pub extent: DemExtent,
    /// Value of cells without data.
    pub nodata: f32,
    /// Output format; by extension when `None`.
    pub format: Option<RasterFormat>,
}

impl Default for DemOptions {
    fn default() -> Self {
        DemOptions {
            cell: 1.0,
            extent: DemExtent::Auto,
            nodata: -9999.0,
            format: None,
        }
    }
}

/// The integer lattice of centres: columns `kx0 .. kx0 + cols`, rows `ky0 .. ky0 + rows`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lattice {
    /// Index of the western column's centre (`x = kx0 × cell`).
    pub kx0: i64,
    /// Index of the southern row's centre (`y = ky0 × cell`).
    pub ky0: i64,
    /// Columns.
    pub cols: u32,
    /// Rows.
    pub rows: u32,
}

/// How far a value may be from a multiple of the cell size and still count as one, in cells.
const MULTIPLE_TOLERANCE: f64 = 1e-6;

fn as_multiple(v: f64, cell: f64) -> Option<i64> {
    let q = v / cell;
    let k = q.round();
    ((q - k).abs() <= MULTIPLE_TOLERANCE).then_some(k as i64)
}

/// The lattice for `extent` given the points' `bounds`, or a message saying what is wrong.
///
/// # Errors
/// A bad cell size, a box side that is not a multiple of the cell size (without `snap`), an
/// empty or absurdly large grid.
pub fn lattice(
    cell: f64,
    extent: DemExtent,
    bounds: [f64; 4],
) -> std::result::Result<Lattice, String> {
    if !(cell.is_finite() && cell > 0.0) {
        return Err(format!(
            "the cell size must be a positive number, not {cell}"
        ));
    }
    let (kx0, kx1, ky0, ky1) = match extent {
        DemExtent::Auto => {
            if !bounds.iter().all(|v| v.is_finite()) {
                return Err("the input has no points".into());
            }
            (
                (bounds[0] / cell).ceil() as i64,
                (bounds[2] / cell).floor() as i64,
                (bounds[1] / cell).ceil() as i64,
                (bounds[3] / cell).floor() as i64,
            )
        }
        DemExtent::BBox { bbox, snap } => {
            let side = |v: f64, up: bool| -> std::result::Result<i64, String> {
                match as_multiple(v, cell) {
                    Some(k) => Ok(k),
                    None if snap => Ok(if up {
                        (v / cell).ceil()
                    } else {
                        (v / cell).floor()
                    } as i64),
                    None => Err(format!(
                        "the box side {v} is not a multiple of the cell size {cell} \
                         (use --snap to round the box outwards)"
                    )),
                }
            };
            let (x0, y0, x1, y1) = (
                side(bbox[0], false)?,
                side(bbox[1], false)?,
                side(bbox[2], true)?,
                side(bbox[3], true)?,
            );
            // Centres in [xmin, xmax) × (ymin, ymax].
            (x0, x1 - 1, y0 + 1, y1)
        }
    };
    if kx1 < kx0 || ky1 < ky0 {
        return Err(format!(
            "the grid would have no cell (no cell centre of size {cell} inside the extent)"
        ));
    }
    let cols = u32::try_from(kx1 - kx0 + 1).map_err(|_| "too many columns".to_string())?;
    let rows = u32::try_from(ky1 - ky0 + 1).map_err(|_| "too many rows".to_string())?;
    Ok(Lattice {
        kx0,
        ky0,
        cols,
        rows,
    })
}

/// The band of rows in memory and the writer behind it.
struct Raster {
    writer: Box<dyn GridWriter>,
    lat: Lattice,
    cell: f64,
    nodata: f32,
    /// Lowest row index (`ky`) not yet written to the file.
    band_lo: i64,
    /// Rows `band_lo, band_lo + 1, …`.
    band: VecDeque<Vec<f32>>,
    /// Row buffers for reuse.
    spare: Vec<Vec<f32>>,
    /// Cells with data in rows already written.
    cells_with_data: u64,
    /// Cells written after their row had gone to the file.
    late_cells: u64,
    /// Late cells not yet applied: `(row, column, value, weak)`, in arrival order.
    late: Vec<(u32, u32, f32, bool)>,
    /// Largest number of rows held at once.
    max_band: usize,
}

impl Raster {
    fn ky_top(&self) -> i64 {
        self.lat.ky0 + i64::from(self.lat.rows) - 1
    }

    /// Raster row (0 = north) of lattice row `ky`.
    fn row_of(&self, ky: i64) -> u32 {
        (self.ky_top() - ky) as u32
    }

    fn is_nodata(&self, v: f32) -> bool {
        v.to_bits() == self.nodata.to_bits()
    }

    fn band_row(&mut self, ky: i64) -> &mut Vec<f32> {
        let i = (ky - self.band_lo) as usize;
        while self.band.len() <= i {
            let mut row = self.spare.pop().unwrap_or_default();
            row.clear();
            row.resize(self.lat.cols as usize, self.nodata);
            self.band.push_back(row);
        }
        self.max_band = self.max_band.max(self.band.len());
        &mut self.band[i]
    }

    /// Sets cell `(kx, ky)`; a `weak` value only fills a cell that has no value yet.
    fn put(&mut self, kx: i64, ky: i64, value: f32, weak: bool) -> Result<()> {
        let col = (kx - self.lat.kx0) as usize;
        if ky >= self.band_lo {
            let nodata = self.nodata;
            let cell = &mut self.band_row(ky)[col];
            if !weak || cell.to_bits() == nodata.to_bits() {
                *cell = value;
            }
            return Ok(());
        }
        // A late triangle: the row is in the file already.
        let row = self.row_of(ky);
        self.late.push((row, col as u32, value, weak));
        if self.late.len() >= LATE_BATCH {
            self.apply_late()?;
        }
        Ok(())
    }

    /// Applies the queued late cells, in arrival order per cell, one span of a row at a time.
    fn apply_late(&mut self) -> Result<()> {
        let mut late = std::mem::take(&mut self.late);
        // Stable: the cells of one position keep their arrival order.
        late.sort_by_key(|&(row, col, ..)| (row, col));
        let mut span = Vec::new();
        for same_row in late.chunk_by(|a, b| a.0 == b.0) {
            let row = same_row[0].0;
            let c0 = same_row[0].1;
            let c1 = same_row[same_row.len() - 1].1;
            span.resize((c1 - c0 + 1) as usize, 0.0);
            self.writer.read_span(row, c0, &mut span)?;
            for &(_, col, value, weak) in same_row {
                let cell = &mut span[(col - c0) as usize];
                let empty = cell.to_bits() == self.nodata.to_bits();
                if empty || !weak {
                    *cell = value;
                    self.late_cells += 1;
                    if empty {
                        self.cells_with_data += 1;
                    }
                }
            }
            self.writer.write_span(row, c0, &span)?;
        }
        late.clear();
        self.late = late;
        Ok(())
    }

    /// Writes every row with `ky < limit` (and below the top) to the file.
    fn flush_below(&mut self, limit: i64) -> Result<()> {
        let limit = limit.min(self.ky_top() + 1);
        while self.band_lo < limit {
            let row = self.row_of(self.band_lo);
            match self.band.pop_front() {
                Some(values) => {
                    self.cells_with_data +=
                        values.iter().filter(|v| !self.is_nodata(**v)).count() as u64;
                    self.writer.write_row(row, &values)?;
                    self.spare.push(values);
                }
                None => {
                    let empty = vec![self.nodata; self.lat.cols as usize];
                    self.writer.write_row(row, &empty)?;
                }
            }
            self.band_lo += 1;
        }
        Ok(())
    }

    fn rasterise(&mut self, t: &Tri) -> Result<()> {
        let [xmin, ymin, xmax, ymax] = t.bbox();
        let c = self.cell;
        let lat = self.lat;
        // One cell of slack on each side: the exact test below decides.
        let kx_lo = ((xmin / c).floor() as i64).max(lat.kx0);
        let kx_hi = ((xmax / c).ceil() as i64).min(lat.kx0 + i64::from(lat.cols) - 1);
        let ky_lo = ((ymin / c).floor() as i64).max(lat.ky0);
        let ky_hi = ((ymax / c).ceil() as i64).min(self.ky_top());
        for ky in ky_lo..=ky_hi {
            let y = ky as f64 * c;
            for kx in kx_lo..=kx_hi {
                let p = [kx as f64 * c, y];
                let loc = t.locate(p);
                if loc == super::geom::Location::Outside {
                    continue;
                }
                let value = t.value_at(p, loc) as f32;
                self.put(kx, ky, value, !t.owns(loc))?;
            }
        }
        Ok(())
    }
}

/// A [`TriangleSink`] that writes a DEM raster (see the module docs).
pub struct DemSink {
    path: PathBuf,
    options: DemOptions,
    raster: Option<Raster>,
    triangles: u64,
}

impl DemSink {
    /// A DEM sink writing to `path`; the file is created when the stream begins (the extent may
    /// depend on the data) and appears under its name when the stream finishes.
    ///
    /// # Errors
    /// [`Error::Output`] for a bad cell size, a box that is not on the lattice (without `snap`) or
    /// an unknown format.
    pub fn new(path: &Path, options: DemOptions) -> Result<DemSink> {
        let bad = |message: String| Error::Output {
            path: path.to_path_buf(),
            message,
        };
        if let DemExtent::BBox { .. } = options.extent {
            lattice(options.cell, options.extent, [0.0; 4]).map_err(bad)?;
        } else if !(options.cell.is_finite() && options.cell > 0.0) {
            return Err(bad(format!("bad cell size {}", options.cell)));
        }
        if options.format.is_none() && RasterFormat::from_extension(path).is_none() {
            return Err(bad(
                "unknown raster format: use a .tif or .asc extension".into()
            ));
        }
        Ok(DemSink {
            path: path.to_path_buf(),
            options,
            raster: None,
            triangles: 0,
        })
    }

    fn raster(&mut self) -> Result<&mut Raster> {
        let path = &self.path;
        self.raster.as_mut().ok_or_else(|| Error::Output {
            path: path.clone(),
            message: "the DEM sink got data before begin()".into(),
        })
    }
}

impl TriangleSink for DemSink {
    fn begin(&mut self, info: &StreamInfo) -> Result<()> {
        let o = &self.options;
        let lat = lattice(o.cell, o.extent, info.bounds).map_err(|message| Error::Output {
            path: self.path.clone(),
            message,
        })?;
        let mut spec = GridSpec::aligned(o.cell, lat.kx0, lat.ky0, lat.cols, lat.rows, o.nodata);
        spec.crs = info.crs.clone();
        let writer = create_grid_writer(&self.path, o.format, &spec)?;
        self.raster = Some(Raster {
            writer,
            lat,
            cell: o.cell,
            nodata: o.nodata,
            band_lo: lat.ky0,
            band: VecDeque::new(),
            spare: Vec::new(),
            cells_with_data: 0,
            late_cells: 0,
            late: Vec::new(),
            max_band: 0,
        });
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        self.triangles += 1;
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        self.raster()?.rasterise(&t)
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        let r = self.raster()?;
        // Rows whose centre lies strictly below y.
        let limit = (y / r.cell).ceil() as i64;
        let mut limit = if limit as f64 * r.cell < y {
            limit + 1
        } else {
            limit
        };
        while (limit - 1) as f64 * r.cell >= y {
            limit -= 1;
        }
        r.flush_below(limit)
    }

    fn finish(&mut self) -> Result<serde_json::Value> {
        let mut r = self.raster.take().ok_or_else(|| Error::Output {
            path: self.path.clone(),
            message: "the DEM sink was finished before begin() or twice".into(),
        })?;
        r.flush_below(i64::MAX)?;
        r.apply_late()?;
        let spec = r.writer.spec().clone();
        let bytes = r.writer.finish()?;
        Ok(json!({
            "path": self.path,
            "cols": spec.cols,
            "rows": spec.rows,
            "cell": spec.cell,
            "origin": spec.origin,
            "extent": spec.extent(),
            "nodata": spec.nodata,
            "crs": spec.crs.as_ref().and_then(|c| c.definition()),
            "cells_with_data": r.cells_with_data,
            "late_cell_writes": r.late_cells,
            "max_rows_in_memory": r.max_band,
            "triangles": self.triangles,
            "bytes": bytes,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::products::testutil::{
        feed, grid_tin, random_tin, read_tiff, shuffled_with_watermarks,
    };

    #[test]
    fn lattice_auto_and_bbox() {
        let l = lattice(1.0, DemExtent::Auto, [0.5, 0.0, 3.0, 2.2]).unwrap();
        assert_eq!(
            l,
            Lattice {
                kx0: 1,
                ky0: 0,
                cols: 3,
                rows: 3
            }
        );
        let b = DemExtent::BBox {
            bbox: [0.0, 0.0, 4.0, 2.0],
            snap: false,
        };
        // Centres x 0..3, y 1..2.
        assert_eq!(
            lattice(1.0, b, [0.0; 4]).unwrap(),
            Lattice {
                kx0: 0,
                ky0: 1,
                cols: 4,
                rows: 2
            }
        );
        let off = DemExtent::BBox {
            bbox: [0.2, 0.0, 4.0, 2.0],
            snap: false,
        };
        assert!(lattice(1.0, off, [0.0; 4]).unwrap_err().contains("--snap"));
        let snapped = DemExtent::BBox {
            bbox: [0.2, -0.5, 3.5, 2.0],
            snap: true,
        };
        assert_eq!(
            lattice(1.0, snapped, [0.0; 4]).unwrap(),
            Lattice {
                kx0: 0,
                ky0: 0,
                cols: 4,
                rows: 3
            }
        );
        assert!(lattice(0.0, DemExtent::Auto, [0.0; 4]).is_err());
        assert!(lattice(1.0, DemExtent::Auto, [0.2, 0.2, 0.8, 0.8]).is_err());
    }

    fn plane(x: f64, y: f64) -> f64 {
        0.25 * x - 0.5 * y + 100.0
    }

    fn dem_of(tris: &[([[f64; 3]; 3], Option<f64>)], dir: &Path, name: &str) -> Vec<f32> {
        let path = dir.join(name);
        let mut sink = DemSink::new(
            &path,
            DemOptions {
                cell: 1.0,
                ..DemOptions::default()
            },
        )
        .unwrap();
        let info = StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 20.0, 20.0],
        };
        feed(&mut sink, &info, tris);
        read_tiff(&path).2
    }

    /// A plane is reproduced at every centre (up to f32 rounding), the outer boundary included, and
    /// the result is the same bits in sweep order and shuffled with late triangles.
    #[test]
    fn plane_exact_and_order_independent() {
        let tris = random_tin(300, 20.0, 1, plane);
        let dir = tempfile::tempdir().unwrap();
        let sweep = dem_of(
            &crate::products::testutil::in_sweep_order(&tris),
            dir.path(),
            "a.tif",
        );
        let shuffled = dem_of(&shuffled_with_watermarks(&tris, 3), dir.path(), "b.tif");
        assert_eq!(sweep.len(), 21 * 21);
        for (i, (a, b)) in sweep.iter().zip(&shuffled).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "cell {i}");
            let (row, col) = (i / 21, i % 21);
            let want = plane(col as f64, 20.0 - row as f64) as f32;
            assert_eq!(*a, want, "cell {i}");
        }
    }

    /// With watermarks only a band of rows is held; late triangles write into rows already in the
    /// file, and the result is the same.
    #[test]
    fn band_memory_and_late_writes() {
        let tris = crate::products::testutil::random_tin_framed(3000, 100.0, 2, plane);
        let dir = tempfile::tempdir().unwrap();
        let run = |steps: &[crate::products::testutil::Step], name: &str| {
            let path = dir.path().join(name);
            let mut sink = DemSink::new(&path, DemOptions::default()).unwrap();
            let info = StreamInfo {
                crs: None,
                bounds: [0.0, 0.0, 100.0, 100.0],
            };
            (feed(&mut sink, &info, steps), read_tiff(&path).2)
        };
        let (a, va) = run(&crate::products::testutil::in_sweep_order(&tris), "a.tif");
        let (b, vb) = run(&shuffled_with_watermarks(&tris, 7), "b.tif");
        assert_eq!(a["rows"], 101);
        assert!(a["max_rows_in_memory"].as_u64().unwrap() < 15, "{a}");
        assert_eq!(a["late_cell_writes"], 0);
        assert!(b["late_cell_writes"].as_u64().unwrap() > 0, "{b}");
        assert_eq!(a["cells_with_data"], 101 * 101);
        assert_eq!(b["cells_with_data"], 101 * 101);
        assert!(va.iter().zip(&vb).all(|(x, y)| x.to_bits() == y.to_bits()));
    }

    /// Centres outside the TIN (a triangle's worth missing) keep the nodata value.
    #[test]
    fn nodata_outside_the_tin() {
        let tris: Vec<_> = grid_tin(4, 4, 1.0, plane)
            .into_iter()
            .filter(|t| t.iter().all(|p| p[0] + p[1] <= 4.0))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("n.asc");
        let mut sink = DemSink::new(&path, DemOptions::default()).unwrap();
        let info = StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 4.0, 4.0],
        };
        feed(
            &mut sink,
            &info,
            &crate::products::testutil::in_sweep_order(&tris),
        );
        let text = std::fs::read_to_string(&path).unwrap();
        let rows: Vec<&str> = text.lines().skip(6).collect();
        assert_eq!(rows[0], "98 -9999 -9999 -9999 -9999");
        assert_eq!(rows[4], "100 100.25 100.5 100.75 101");
    }
}
