//! ESRI ASCII grid output (`.asc`).
//!
//! The header uses `xllcenter`/`yllcenter` (the centre of the south-western cell), which for an
//! aligned grid are exact multiples of the cell size:
//!
//! ```text
//! ncols        3
//! nrows        2
//! xllcenter    511000
//! yllcenter    122000
//! cellsize     1
//! NODATA_value -9999
//! 1.5 2 2.5
//! …
//! ```
//!
//! Rows are text of varying length and run north to south, while a DEM is produced south to
//! north, so cells first go to a [`Scratch`] (an anonymous binary file, random access, deleted by
//! the operating system even if the process is killed) and [`GridWriter::finish`] transcribes it,
//! row by row, into the output. Values are written in the shortest form that reads back as the
//! same `f32`. The output appears under its final name only when complete; the DEM sink writes a
//! `.prj` beside it when the CRS is known as WKT.

use super::raster::{GridWriter, Scratch, check_cell};
use crate::error::{Error, Result};
use crate::output::AtomicFile;
use crate::raster::GridSpec;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// An ESRI ASCII grid being written (see the module docs).
#[derive(Debug)]
pub struct AsciiGridWriter {
    path: PathBuf,
    spec: GridSpec,
    scratch: Scratch,
}

impl AsciiGridWriter {
    /// Creates the scratch file next to `path` (the output itself is created by `finish`).
    ///
    /// # Errors
    /// [`Error::Output`] for an empty grid; [`Error::Write`] naming `path`'s directory.
    pub fn create(path: &Path, spec: &GridSpec) -> Result<AsciiGridWriter> {
        if spec.is_empty() || !(spec.cell > 0.0 && spec.cell.is_finite()) {
            return Err(Error::Output {
                path: path.to_path_buf(),
                message: format!(
                    "the grid is empty or its cell size is bad ({} × {} cells of {})",
                    spec.cols, spec.rows, spec.cell
                ),
            });
        }
        Ok(AsciiGridWriter {
            path: path.to_path_buf(),
            spec: spec.clone(),
            scratch: Scratch::new(path, spec.cols, spec.rows, spec.nodata)?,
        })
    }

    fn header(&self) -> String {
        let s = &self.spec;
        // `create` refuses an empty grid, so there is a southern row.
        let (xll, yll) = (s.centre_x(0), s.centre_y(s.rows - 1));
        format!(
            "ncols        {}\nnrows        {}\nxllcenter    {}\nyllcenter    {}\ncellsize     {}\n\
             NODATA_value {}\n",
            s.cols, s.rows, xll, yll, s.cell, s.nodata
        )
    }
}

impl GridWriter for AsciiGridWriter {
    fn spec(&self) -> &GridSpec {
        &self.spec
    }

    fn write_row(&mut self, row: u32, values: &[f32]) -> Result<()> {
        check_cell(&self.spec, &self.path, row, 0)?;
        if values.len() != self.spec.cols as usize {
            return Err(Error::Output {
                path: self.path.clone(),
                message: format!("row {row} has {} values", values.len()),
            });
        }
        self.scratch.write(row, 0, values)
    }

    fn write_cell(&mut self, row: u32, col: u32, value: f32) -> Result<()> {
        check_cell(&self.spec, &self.path, row, col)?;
        self.scratch.write(row, col, &[value])
    }

    fn read_cell(&mut self, row: u32, col: u32) -> Result<f32> {
        check_cell(&self.spec, &self.path, row, col)?;
        let mut v = [0f32];
        self.scratch.read(row, col, &mut v)?;
        Ok(v[0])
    }

    fn finish(self: Box<Self>) -> Result<u64> {
        let mut out = AtomicFile::create(&self.path)?;
        out.write_all(self.header().as_bytes())
            .map_err(|e| out.err(e))?;
        let cols = self.spec.cols as usize;
        let mut values = vec![0f32; cols];
        let mut line = String::with_capacity(cols * 8);
        let mut text = BufWriter::with_capacity(1 << 16, &mut out);
        for row in 0..self.spec.rows {
            line.clear();
            self.scratch.read(row, 0, &mut values)?;
            for (i, v) in values.iter().enumerate() {
                if i > 0 {
                    line.push(' ');
                }
                line.push_str(&v.to_string());
            }
            line.push('\n');
            text.write_all(line.as_bytes())
                .map_err(|e| Error::write(&self.path, e))?;
        }
        text.flush().map_err(|e| Error::write(&self.path, e))?;
        drop(text);
        out.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_rows_north_to_south_and_nodata_fill() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.asc");
        let spec = GridSpec::aligned(0.5, 2, 4, 2, 3, -9999.0);
        let mut w: Box<dyn GridWriter> = Box::new(AsciiGridWriter::create(&path, &spec).unwrap());
        w.write_row(2, &[1.0, 2.5]).unwrap();
        w.write_cell(0, 1, 0.1).unwrap();
        assert_eq!(w.read_cell(0, 1).unwrap(), 0.1);
        assert_eq!(w.read_cell(0, 0).unwrap(), -9999.0);
        assert_eq!(w.read_cell(1, 0).unwrap(), -9999.0);
        assert!(!path.exists());
        w.finish().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "ncols        2\nnrows        3\nxllcenter    1\nyllcenter    2\ncellsize     0.5\n\
             NODATA_value -9999\n-9999 0.1\n-9999 -9999\n1 2.5\n"
        );
    }
}
