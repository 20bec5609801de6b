//! Writing windows in order: vertex numbers shared along the border lines (each border vertex
//! written once, by the first window that uses it), and the statistics of the whole grid (each
//! border cell counted once).

use super::SimplifyStats;
use super::refiner::ErrorSums;
use super::windows::WindowOut;
use crate::error::Result;
use crate::input::raster::RasterSpec;
use crate::sink::MeshSink;
use std::collections::HashMap;

/// The writer's state between windows.
pub(super) struct Stitch {
    cols: Vec<u32>,
    rows: Vec<u32>,
    /// Numbers of the border vertices written so far that later windows may use.
    ids: HashMap<[u32; 2], u64>,
    points: u64,
    border_points: u64,
    triangles: u64,
    /// Errors of the cells of the band's top and bottom lines (NaN: not covered yet).
    top: Vec<f64>,
    bottom: Vec<f64>,
    /// Errors of the cells of each vertical border line in the band.
    vlines: Vec<Vec<f64>>,
    sums: ErrorSums,
    valid: u64,
    insertions: u64,
    flips: u64,
    scans: u64,
    removed: u64,
    map: Vec<u64>,
}

fn fold(sums: &mut ErrorSums, line: &[f64]) {
    for &e in line.iter().filter(|e| !e.is_nan()) {
        sums.add(e);
    }
}

fn merge(line: &mut [f64], side: &[f64]) {
    for (l, &s) in line.iter_mut().zip(side) {
        if l.is_nan() {
            *l = s;
        }
    }
}

impl Stitch {
    pub(super) fn new(cols: &[u32], rows: &[u32]) -> Self {
        let width = *cols.last().expect("cuts") as usize + 1;
        Stitch {
            cols: cols.to_vec(),
            rows: rows.to_vec(),
            ids: HashMap::new(),
            points: 0,
            border_points: 0,
            triangles: 0,
            top: vec![f64::NAN; width],
            bottom: vec![f64::NAN; width],
            vlines: Vec::new(),
            sums: ErrorSums::default(),
            valid: 0,
            insertions: 0,
            flips: 0,
            scans: 0,
            removed: 0,
            map: Vec::new(),
        }
    }

    /// Bytes the writer's state holds at most, for windows at most `tallest` cells tall.
    pub(super) fn bytes(cols: &[u32], tallest: u32) -> u64 {
        let width = u64::from(*cols.last().expect("cuts")) + 1;
        let vertical = cols.len() as u64 * u64::from(tallest);
        // Two lines of errors, the vertical lines, and a map entry (with the hash table's
        // slack) per border cell at worst.
        16 * width + 8 * vertical + 64 * (width + vertical)
    }

    /// Points written so far.
    pub(super) fn points(&self) -> u64 {
        self.points
    }

    /// Writes window `j` of band `b` (windows come in order).
    pub(super) fn window(
        &mut self,
        b: usize,
        j: usize,
        out: WindowOut,
        sink: &mut dyn MeshSink,
    ) -> Result<()> {
        let (c0, r0, r1) = (self.cols[j] as usize, self.rows[b], self.rows[b + 1]);
        if j == 0 {
            let len = (r1 - r0 + 1) as usize;
            self.vlines = vec![vec![f64::NAN; len]; self.cols.len()];
            self.valid += out.valid;
        }
        let k = &out.kept;
        self.map.clear();
        for (v, cell) in k.vertices.iter().zip(&k.cells) {
            let border = self.cols.binary_search(&cell[0]).is_ok()
                || self.rows.binary_search(&cell[1]).is_ok();
            let id = if border {
                match self.ids.get(cell) {
                    Some(&id) => id,
                    None => {
                        self.ids.insert(*cell, self.points);
                        self.border_points += 1;
                        sink.vertex(*v)?;
                        self.points += 1;
                        self.points - 1
                    }
                }
            } else {
                sink.vertex(*v)?;
                self.points += 1;
                self.points - 1
            };
            self.map.push(id);
        }
        for t in &k.triangles {
            sink.triangle(t.map(|i| self.map[i as usize]))?;
        }
        self.triangles += k.triangles.len() as u64;
        let s = &out.sides;
        merge(&mut self.top[c0..], &s.top);
        merge(&mut self.bottom[c0..], &s.bottom);
        let inner = 1..s.left.len() - 1;
        merge(&mut self.vlines[j][inner.clone()], &s.left[inner.clone()]);
        merge(&mut self.vlines[j + 1][inner.clone()], &s.right[inner]);
        self.sums.merge(&out.interior);
        self.insertions += out.insertions;
        self.flips += out.flips;
        self.scans += out.scans;
        self.removed += out.removed;
        if j + 2 == self.cols.len() {
            // The band is done: its top line and vertical lines are final.
            fold(&mut self.sums, &self.top);
            for line in &self.vlines {
                fold(&mut self.sums, &line[1..line.len() - 1]);
            }
            std::mem::swap(&mut self.top, &mut self.bottom);
            self.bottom.fill(f64::NAN);
            if b + 2 == self.rows.len() {
                fold(&mut self.sums, &self.top);
            }
            self.ids.retain(|cell, _| cell[1] >= r1);
        }
        Ok(())
    }

    /// The statistics of the whole grid.
    pub(super) fn finish(&self, spec: &RasterSpec) -> SimplifyStats {
        let grid_tris = 2.0 * (f64::from(spec.cols) - 1.0) * (f64::from(spec.rows) - 1.0);
        SimplifyStats {
            cells: spec.cells(),
            valid_cells: self.valid,
            points: self.points,
            point_ratio: self.points as f64 / self.valid.max(1) as f64,
            triangles: self.triangles,
            triangle_ratio: self.triangles as f64 / grid_tris,
            insertions: self.insertions,
            flips: self.flips,
            scans: self.scans,
            removed: self.removed,
            max_error: self.sums.max,
            rms_error: (self.sums.sum_sq / self.sums.covered.max(1) as f64).sqrt(),
            uncovered_cells: self.valid - self.sums.covered.min(self.valid),
            seconds: 0.0,
            windows: ((self.cols.len() - 1) * (self.rows.len() - 1)) as u64,
            border_points: self.border_points,
        }
    }
}
