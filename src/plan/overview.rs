//! The overview of a DEM plan's mosaic in its report ([`Overview`], [`super::report`]): the
//! finished tasks' tiles read at a reduced resolution — one cell in `step` along each axis, so
//! that the long side has at most [`MAX_SIDE`] pixels — into a small grid held in memory,
//! hillshaded as `sweeptin hillshade` shades a DEM ([`hillshade_png`]) and encoded as PNG, for
//! the page to embed as a `data:` URI (nothing fetched). The memory it takes is that grid (at
//! most `MAX_SIDE²` values) and one row of one tile with the TIFF strip that holds it: a tile
//! is read only at the rows it gives a pixel.

use super::Plan;
use crate::error::Result;
use crate::input::raster::{RasterReader, RasterSpec};
use crate::products::hillshade::{HillshadeOptions, hillshade_png};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Pixels on the long side of the overview, at most (the width of the report's map).
const MAX_SIDE: u32 = 720;

/// The overview of a plan's mosaic: whether it was drawn, why not, and the PNG.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Overview {
    /// Whether an overview was drawn.
    pub drawn: bool,
    /// What it shows, or why there is none (a plan whose product has no raster, no tile
    /// finished yet, tiles that could not be read).
    pub note: String,
    /// Columns of the image (0 when none was drawn).
    pub cols: u32,
    /// Rows of the image.
    pub rows: u32,
    /// The side of a pixel, in the plan's units: a whole number of the DEM's cells.
    pub pixel: Option<f64>,
    /// `[xmin, ymin, xmax, ymax]` the image covers.
    pub bounds: Option<[f64; 4]>,
    /// Tiles read.
    pub tiles: usize,
    /// Pixels with data (shaded).
    pub shaded: u64,
    /// The PNG (grey + alpha, nodata transparent); not in the JSON.
    #[serde(skip)]
    pub png: Vec<u8>,
}

impl Overview {
    fn none(note: impl Into<String>) -> Overview {
        Overview {
            note: note.into(),
            ..Overview::default()
        }
    }

    /// The PNG as a `data:` URI.
    pub fn data_uri(&self) -> String {
        format!("data:image/png;base64,{}", base64(&self.png))
    }
}

/// The overview of `plan`'s mosaic from `tiles`, the DEM tiles of its finished tasks (task,
/// path). Never fails: a tile that cannot be read is left out and named in the note.
pub(super) fn overview(plan: &Plan, dir: &super::PlanDir, tiles: &[(usize, PathBuf)]) -> Overview {
    let Some(cell) = plan.cell else {
        return Overview::none(format!(
            "the plan's product ({}) has no raster",
            plan.command
        ));
    };
    if tiles.is_empty() {
        return Overview::none("no task has written a DEM tile yet");
    }
    let mut b = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
    for t in &plan.tiles {
        b = [
            b[0].min(t.bounds[0]),
            b[1].min(t.bounds[1]),
            b[2].max(t.bounds[2]),
            b[3].max(t.bounds[3]),
        ];
    }
    let cells = |d: f64| (d / cell).ceil().max(1.0);
    let (fc, fr) = (cells(b[2] - b[0]), cells(b[3] - b[1]));
    let step = (fc.max(fr) / f64::from(MAX_SIDE)).ceil().max(1.0);
    let (cols, rows) = (
        (fc / step).ceil().min(f64::from(MAX_SIDE)) as u32,
        (fr / step).ceil().min(f64::from(MAX_SIDE)) as u32,
    );
    let pixel = step * cell;
    let mut grid = Grid {
        origin: [b[0], b[3]],
        cell,
        step: step as u64,
        cols,
        rows,
        values: vec![f64::NAN; cols as usize * rows as usize],
    };
    let (mut read, mut crs, mut failed) = (0, None, Vec::new());
    for (i, path) in tiles {
        match dir.local(path).and_then(|copy| grid.sample(&copy.path)) {
            Ok(c) => {
                read += 1;
                crs = crs.or(c);
            }
            Err(e) => failed.push(format!("task {i}: {e}")),
        }
    }
    let mut spec = RasterSpec::north_up(cols, rows, b[0], b[3], pixel);
    spec.crs = crs;
    let (png, shaded) = match hillshade_png(&grid.values, &spec, &HillshadeOptions::default()) {
        Ok(p) => p,
        Err(e) => return Overview::none(format!("the hillshade failed: {e}")),
    };
    let mut note = format!(
        "hillshade of {read} DEM tiles, {} (pixels of {})",
        match grid.step {
            1 => "every cell".to_string(),
            k => format!("one cell in {k} along each axis"),
        },
        crate::fmt::Figure(pixel)
    );
    if let Some(first) = failed.first() {
        note += &format!(
            "; {} tiles could not be read and are left blank ({first}{})",
            failed.len(),
            if failed.len() > 1 { "; …" } else { "" }
        );
    }
    Overview {
        drawn: read > 0,
        note,
        cols,
        rows,
        pixel: Some(pixel),
        bounds: Some([
            b[0],
            b[3] - f64::from(rows) * pixel,
            b[0] + f64::from(cols) * pixel,
            b[3],
        ]),
        tiles: read,
        shaded,
        png: if read > 0 { png } else { Vec::new() },
    }
}

/// The overview's grid: pixel `(c, r)` takes the DEM cell whose global column and row (counted
/// in cells from `origin`, the north-west corner of the plan's tiles) are `c·step + step/2`
/// and `r·step + step/2`.
struct Grid {
    origin: [f64; 2],
    cell: f64,
    step: u64,
    cols: u32,
    rows: u32,
    values: Vec<f64>,
}

impl Grid {
    /// The pixel a DEM cell centred `d` from the origin (east or south) falls on along one
    /// axis of `n` pixels, if it is the one sampled.
    fn pixel(&self, d: f64, n: u32) -> Option<usize> {
        let k = (d / self.cell).floor();
        if k < 0.0 {
            return None;
        }
        let k = k as u64;
        (k % self.step == self.step / 2 && k / self.step < u64::from(n))
            .then_some((k / self.step) as usize)
    }

    /// Copies the sampled cells of the DEM tile at `path` into the grid; its CRS.
    fn sample(&mut self, path: &Path) -> Result<Option<String>> {
        let mut r = RasterReader::open(path)?;
        let spec = r.spec().clone();
        let t = spec.transform;
        let same = |c: f64| (c - self.cell).abs() <= 1e-9 * self.cell;
        if !(spec.is_axis_aligned() && same(t[1]) && same(-t[5])) {
            return Err(crate::Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "cells of {} × {} where the plan's are {}",
                    t[1], -t[5], self.cell
                ),
            });
        }
        let columns: Vec<(u32, usize)> = (0..spec.cols)
            .filter_map(|c| {
                let x = t[0] + (f64::from(c) + 0.5) * t[1];
                self.pixel(x - self.origin[0], self.cols).map(|p| (c, p))
            })
            .collect();
        let (Some(&(c0, _)), Some(&(c1, _))) = (columns.first(), columns.last()) else {
            return Ok(spec.crs);
        };
        for row in 0..spec.rows {
            let y = t[3] + (f64::from(row) + 0.5) * t[5];
            let Some(pr) = self.pixel(self.origin[1] - y, self.rows) else {
                continue;
            };
            let v = r.read_window(c0, row, c1 - c0 + 1, 1)?;
            let at = pr * self.cols as usize;
            for &(c, pc) in &columns {
                self.values[at + pc] = v[(c - c0) as usize];
            }
        }
        Ok(spec.crs)
    }
}

/// Standard base64 with padding (RFC 4648), for the `data:` URI.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::base64;

    #[test]
    fn base64_is_rfc_4648() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }
}
