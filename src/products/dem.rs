//! DEM rasters from the triangle stream: linear interpolation inside each triangle at cell centres.
//!
//! # The grid
//!
//! Cell edges (or, with [`crate::raster::Align::Centres`], centres) lie on whole multiples of the
//! cell size, so rasters of adjacent tiles from separate runs line up exactly and a mosaic of them
//! equals one run over the whole area; the cells are those whose centres lie inside the points'
//! bounds, or inside a box. Which cells a grid has,
//! and where their centres are, is decided in [`crate::raster`] ([`GridPlan`], [`GridSpec`]).
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
//! of the highest triangle seen: a band of rows, at most [`DemOptions::memory`] bytes of them
//! (the lowest rows go to the file early when the band would grow past it, and later cells
//! there are late writes, below). A grid whose rows (two of them, and the GeoTIFF's strip
//! tables) do not fit in that budget is refused before anything is allocated. [`TriangleSink::watermark`] writes the rows below
//! it to the file. A late triangle below the watermark writes its cells into the file (random
//! access), so it is handled exactly: its cells are queued (at most [`LATE_BATCH`] at a time)
//! and applied in arrival order, one read and one write per row span, when the queue is full and
//! at the end.

use super::geom::{Location, Tri};
use crate::error::{Error, Result};
use crate::output::raster::{
    GridWriter, MemoryGrid, RasterFormat, RasterOptions, create_grid_writer,
};
use crate::raster::{GridPlan, GridSpec};
use crate::sink::{DemSummary, Needs, ProductSummary, StreamInfo, TriangleSink, Wants};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Late cells queued before they are applied to the file (16 bytes each).
pub const LATE_BATCH: usize = 1 << 16;

/// Options of a [`DemSink`].
#[derive(Clone, Debug)]
pub struct DemOptions {
    /// Cell size and extent (checked when the plan is made).
    pub grid: GridPlan,
    /// Value of cells without data.
    pub nodata: f32,
    /// Output format (by extension when not given), compression, predictor, BigTIFF.
    pub output: RasterOptions,
    /// Bytes of rows the sink may hold in memory (its share of the run's `--mem`; by default
    /// 256 MiB, a quarter of the default budget).
    pub memory: u64,
}

impl Default for DemOptions {
    fn default() -> Self {
        DemOptions {
            grid: GridPlan::default(),
            nodata: -9999.0,
            output: RasterOptions::default(),
            memory: 256 << 20,
        }
    }
}

/// What a DEM needs: the triangles whose closed box may hold one of its cell centres (the
/// others hold none, [`GridSpec::may_hold_centre`]).
#[derive(Debug)]
struct Centres(GridSpec);

impl Wants for Centres {
    fn wants(&self, t: &[[f64; 3]; 3]) -> bool {
        self.0.may_hold_centre(t)
    }

    /// A cell takes its value from the triangles that hold its centre, and their boxes hold it.
    fn covering(&self) -> bool {
        true
    }

    fn centres(&self) -> Option<&GridSpec> {
        self.0.has_lattice_keys().then_some(&self.0)
    }
}

/// The band of rows in memory and the writer behind it.
struct Raster {
    writer: Box<dyn GridWriter>,
    spec: GridSpec,
    /// Rows already written to the file, counted from the southern one.
    written: u32,
    /// Rows `rows − 1 − written`, `rows − 2 − written`, … (northwards from the lowest row not
    /// yet written).
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
    /// Most rows the band may hold (from the memory budget).
    band_limit: usize,
}

impl Raster {
    /// Is `row` still in memory (not written to the file yet)?
    fn in_band(&self, row: u32) -> bool {
        row + self.written < self.spec.rows
    }

    fn band_row(&mut self, row: u32) -> Result<&mut Vec<f32>> {
        let mut i = (self.spec.rows - 1 - self.written - row) as usize;
        if i >= self.band_limit {
            // Over budget: the lowest rows go to the file now; their later cells are late writes.
            let extra = (i + 1 - self.band_limit) as u32;
            self.flush_below(self.written + extra)?;
            i = (self.spec.rows - 1 - self.written - row) as usize;
        }
        while self.band.len() <= i {
            let mut values = self.spare.pop().unwrap_or_default();
            values.clear();
            values.resize(self.spec.cols as usize, self.spec.nodata);
            self.band.push_back(values);
        }
        self.max_band = self.max_band.max(self.band.len());
        Ok(&mut self.band[i])
    }

    /// Sets cell `(col, row)`; a `weak` value only fills a cell that has no value yet.
    fn put(&mut self, col: u32, row: u32, value: f32, weak: bool) -> Result<()> {
        if self.in_band(row) {
            let nodata = self.spec.nodata;
            let cell = &mut self.band_row(row)?[col as usize];
            if !weak || cell.to_bits() == nodata.to_bits() {
                *cell = value;
            }
            return Ok(());
        }
        // A late triangle: the row is in the file already.
        self.late.push((row, col, value, weak));
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
                let empty = self.spec.is_nodata(*cell);
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

    /// Writes the southern `count` rows (those not written yet) to the file.
    fn flush_below(&mut self, count: u32) -> Result<()> {
        let count = count.min(self.spec.rows);
        while self.written < count {
            let row = self.spec.rows - 1 - self.written;
            // A row no triangle reached is not in the band: the writers fill rows never
            // written with nodata, so nothing is allocated or written for it.
            if let Some(values) = self.band.pop_front() {
                self.cells_with_data +=
                    values.iter().filter(|v| !self.spec.is_nodata(**v)).count() as u64;
                self.writer.write_row(row, &values)?;
                self.spare.push(values);
            }
            self.written += 1;
        }
        Ok(())
    }

    fn rasterise(&mut self, t: &Tri) -> Result<()> {
        let [xmin, ymin, xmax, ymax] = t.bbox();
        // The candidates have a cell of slack on each side; a centre outside the triangle's
        // box is outside the triangle (exact comparisons), the exact test decides the rest.
        // Slack for the crossings' rounding: a cell, and a relative margin at large coordinates.
        let slack = self.spec.cell + 1e-9 * xmin.abs().max(xmax.abs());
        for row in self.spec.rows_over(ymin, ymax).rev() {
            let y = self.spec.centre_y(row);
            if y < ymin || y > ymax {
                continue;
            }
            let (x0, x1) = t.row_span(y, slack);
            for col in self.spec.cols_over(x0.max(xmin), x1.min(xmax)) {
                let x = self.spec.centre_x(col);
                if x < xmin || x > xmax {
                    continue;
                }
                let p = [x, y];
                let loc = t.locate(p);
                if loc == Location::Outside {
                    continue;
                }
                let value = t.value_at(p, loc) as f32;
                self.put(col, row, value, !t.owns(loc))?;
            }
        }
        Ok(())
    }
}

/// Rows the band of `spec` may hold within `memory` bytes, after the writers' per-row tables
/// (the GeoTIFF's strip offsets and sizes, 16 bytes a row, and a flag a row).
///
/// # Errors
/// [`Error::Options`] when fewer than two rows fit, naming the sizes.
fn band_rows(spec: &GridSpec, memory: u64) -> Result<usize> {
    let row = u64::from(spec.cols) * 4;
    let tables = u64::from(spec.rows) * 17;
    let rows = memory.saturating_sub(tables) / row.max(1);
    if rows < 2 {
        return Err(Error::Options(format!(
            "a DEM of {} × {} cells needs at least {} ({} bytes a row, two rows, and {} \
             bytes of row tables), more than its share of --mem ({}): raise --mem, or use a \
             larger --cell or a smaller --bbox",
            spec.cols,
            spec.rows,
            crate::human_bytes(2 * row + tables),
            row,
            tables,
            crate::human_bytes(memory)
        )));
    }
    Ok(usize::try_from(rows).unwrap_or(usize::MAX))
}

impl DemSink {
    /// Checks, before any data, that the grid over `bounds` (the data's, from file headers) is
    /// within the limits: the plan's `--max-cells` and the memory budget.
    ///
    /// # Errors
    /// [`Error::Options`] naming the sizes.
    pub fn check_size(&self, bounds: [f64; 4]) -> Result<()> {
        let spec = self.options.grid.grid(bounds, self.options.nodata)?;
        band_rows(&spec, self.options.memory).map(|_| ())
    }

    /// The first half of [`DemSink::check_size`]: the grid over `bounds` alone (its cells
    /// against `--max-cells`), not yet its memory.
    ///
    /// # Errors
    /// As [`DemSink::check_size`], for the grid.
    pub fn check_grid(&self, bounds: [f64; 4]) -> Result<()> {
        self.options
            .grid
            .grid(bounds, self.options.nodata)
            .map(|_| ())
    }
}

/// A [`TriangleSink`] that writes a DEM raster (see the module docs).
pub struct DemSink {
    path: PathBuf,
    options: DemOptions,
    raster: Option<Raster>,
    triangles: u64,
    /// Kept in memory ([`DemSink::in_memory`]): the finished grid and its cells.
    memory: Option<Option<(GridSpec, Vec<f32>)>>,
}

impl DemSink {
    /// A DEM sink writing to `path`; the file is created when the stream begins (the extent may
    /// depend on the data) and appears under its name when the stream finishes.
    ///
    /// # Errors
    /// [`Error::Output`] for an unknown format or options that do not go together
    /// ([`RasterOptions::resolve`]).
    pub fn new(path: &Path, options: DemOptions) -> Result<DemSink> {
        let format = options.output.resolve(path, false)?.format;
        // `--nodata 1e40` became inf as a float32; an ASCII grid with a NaN or inf NODATA_value
        // is one GDAL cannot read.
        let nodata = options.nodata;
        if nodata.is_infinite() || (nodata.is_nan() && format == RasterFormat::Ascii) {
            return Err(Error::Options(format!(
                "{}: --nodata {nodata} cannot be written: give a finite float32 value (GeoTIFFs \
                 also take nan)",
                path.display()
            )));
        }
        Ok(DemSink {
            path: path.to_path_buf(),
            options,
            raster: None,
            triangles: 0,
            memory: None,
        })
    }

    /// A DEM sink that keeps the raster in memory ([`MemoryGrid`]) instead of writing a file;
    /// [`DemSink::take_grid`] gives it after [`TriangleSink::finish`].
    pub fn in_memory(options: DemOptions) -> DemSink {
        DemSink {
            path: PathBuf::from("(memory)"),
            options,
            raster: None,
            triangles: 0,
            memory: Some(None),
        }
    }

    /// The grid and its cells (row 0 north first) of a finished [`DemSink::in_memory`] sink,
    /// once.
    pub fn take_grid(&mut self) -> Option<(GridSpec, Vec<f32>)> {
        self.memory.as_mut().and_then(Option::take)
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
        let mut spec = o.grid.grid(info.bounds, o.nodata)?;
        spec.crs = info.crs.clone();
        let band_limit = band_rows(&spec, o.memory)?;
        let writer: Box<dyn GridWriter> = match self.memory {
            Some(_) => Box::new(MemoryGrid::new(&spec)?),
            None => create_grid_writer(&self.path, &o.output, &spec)?,
        };
        self.raster = Some(Raster {
            writer,
            spec,
            written: 0,
            band: VecDeque::new(),
            spare: Vec::new(),
            cells_with_data: 0,
            late_cells: 0,
            late: Vec::new(),
            max_band: 0,
            band_limit,
        });
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        self.triangles += 1;
        let r = self.raster()?;
        // Most triangles of dense lidar hold no cell centre: skip them before any exact test.
        if !r.spec.may_hold_centre(t) {
            return Ok(());
        }
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        r.rasterise(&t)
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        let r = self.raster()?;
        let below = r.spec.rows_below(y);
        r.flush_below(below)
    }

    fn grid_cell(&self) -> Option<f64> {
        Some(self.options.grid.cell())
    }

    fn memory_share(&self) -> u64 {
        self.options.memory
    }

    fn boundary_triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        self.triangle(t)
    }

    fn wants_boundary(&self) -> bool {
        true
    }

    fn needs(&self) -> Needs {
        match &self.raster {
            Some(r) => Needs::Only(vec![Arc::new(Centres(r.spec.clone()))]),
            None => Needs::All,
        }
    }

    fn skipped(&mut self, n: u64) {
        self.triangles += n;
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        let mut r = self.raster.take().ok_or_else(|| Error::Output {
            path: self.path.clone(),
            message: "the DEM sink was finished before begin() or twice".into(),
        })?;
        r.flush_below(u32::MAX)?;
        r.apply_late()?;
        let spec = r.writer.spec().clone();
        if let (Some(slot), Some(values)) = (self.memory.as_mut(), r.writer.take_values()) {
            *slot = Some((spec.clone(), values));
        }
        let bytes = r.writer.finish()?;
        let ascii = self.memory.is_none()
            && self.options.output.resolve(&self.path, false)?.format == RasterFormat::Ascii;
        if ascii {
            crate::output::world::write_prj(&self.path, spec.crs.as_ref())?;
        }
        Ok(ProductSummary::Dem(DemSummary {
            path: self.path.clone(),
            cols: spec.cols,
            rows: spec.rows,
            cell: spec.cell,
            origin: spec.origin(),
            extent: spec.extent(),
            nodata: spec.nodata,
            crs: spec.crs.as_ref().and_then(|c| c.definition()),
            lost_crs: crate::crs::LostCrs::of(spec.crs.as_ref(), ascii),
            cells_with_data: r.cells_with_data,
            late_cell_writes: r.late_cells,
            max_rows_in_memory: r.max_band as u64,
            triangles: self.triangles,
            bytes,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::products::testutil::{
        feed, grid_tin, random_tin, read_tiff, shuffled_with_watermarks,
    };

    fn plane(x: f64, y: f64) -> f64 {
        0.25 * x - 0.5 * y + 100.0
    }

    fn dem_of(tris: &[([[f64; 3]; 3], Option<f64>)], dir: &Path, name: &str) -> Vec<f32> {
        let path = dir.join(name);
        let mut sink = DemSink::new(
            &path,
            DemOptions {
                grid: GridPlan::new(
                    1.0,
                    crate::raster::GridExtent::Auto,
                    crate::raster::Align::Centres,
                )
                .unwrap(),
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
            let ProductSummary::Dem(s) = feed(&mut sink, &info, steps) else {
                panic!("not a DEM summary")
            };
            (s, read_tiff(&path).2)
        };
        let (a, va) = run(&crate::products::testutil::in_sweep_order(&tris), "a.tif");
        let (b, vb) = run(&shuffled_with_watermarks(&tris, 7), "b.tif");
        // Edges on whole numbers by default: 100 × 100 cells over [0, 100]².
        assert_eq!((a.cols, a.rows), (100, 100));
        assert_eq!(a.origin, [0.0, 100.0]);
        assert!(a.max_rows_in_memory < 15, "{a:?}");
        assert_eq!(a.late_cell_writes, 0);
        assert!(b.late_cell_writes > 0, "{b:?}");
        assert_eq!(a.cells_with_data, 100 * 100);
        assert_eq!(b.cells_with_data, 100 * 100);
        assert!(va.iter().zip(&vb).all(|(x, y)| x.to_bits() == y.to_bits()));
    }

    /// A raster kept in memory has the same cells as the file, late triangles included.
    #[test]
    fn in_memory_equals_the_file() {
        let tris = crate::products::testutil::random_tin_framed(500, 30.0, 5, plane);
        let steps = shuffled_with_watermarks(&tris, 11);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.tif");
        let info = StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 30.0, 30.0],
        };
        feed(
            &mut DemSink::new(&path, DemOptions::default()).unwrap(),
            &info,
            &steps,
        );
        let mut mem = DemSink::in_memory(DemOptions::default());
        feed(&mut mem, &info, &steps);
        let (spec, values) = mem.take_grid().unwrap();
        // Edges on whole numbers (the default lattice): 30 × 30 cells over [0, 30]².
        assert_eq!((spec.cols, spec.rows), (30, 30));
        let file = read_tiff(&path).2;
        assert!(
            values
                .iter()
                .zip(&file)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        assert_eq!(values.len(), file.len());
        assert!(mem.take_grid().is_none());
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
        let options = DemOptions {
            grid: GridPlan::new(
                1.0,
                crate::raster::GridExtent::Auto,
                crate::raster::Align::Centres,
            )
            .unwrap(),
            ..DemOptions::default()
        };
        let mut sink = DemSink::new(&path, options).unwrap();
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
