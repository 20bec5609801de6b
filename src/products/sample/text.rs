//! The query points of `sample` as text: which columns hold x and y, lines read lazily, and
//! pipes copied once to a temporary file.

use super::Query;
use crate::error::{Error, Result};
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

/// Which columns of a line hold x and y: the first two (no header, or a header naming them
/// there), or those a header names (`id,x,y`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Columns {
    pub(super) x: usize,
    pub(super) y: usize,
}

/// x and y first.
pub(super) const FIRST_TWO: Columns = Columns { x: 0, y: 1 };

/// What a line is.
pub(super) enum Line {
    Skip,
    /// A header: the columns it names, and the name of the output's height field (`z`, or
    /// `z_tin` beside a `z` of the header's).
    Header(Columns, &'static str),
    Point(f64, f64),
}

/// A line under the XYZ reader's separator rules ([`crate::input::xyz::parse_fields`]), x and y
/// read from `cols` ([`crate::input::xyz::parse_columns`] when a header put them elsewhere): the
/// first line that is not a number (`first_data`) is a header, which must name x and y.
pub(super) fn classify(
    line: &str,
    first_data: bool,
    cols: Columns,
) -> std::result::Result<Line, String> {
    use crate::input::xyz::{LineError, parse_columns, parse_fields};
    let bytes = line.trim().as_bytes();
    let parsed = if cols == FIRST_TWO {
        parse_fields::<2>(bytes)
    } else {
        parse_columns(bytes, [cols.x, cols.y])
    };
    match parsed {
        Ok(None) => Ok(Line::Skip),
        Ok(Some([x, y])) => Ok(Line::Point(x, y)),
        Err(LineError::NotANumber { .. }) if first_data => header(bytes),
        Err(e) => Err(e.to_string()),
    }
}

/// The header line `bytes`: the columns it names for x and y
/// ([`crate::input::xyz::header_axes`]).
fn header(bytes: &[u8]) -> std::result::Result<Line, String> {
    let ([x, y], has_z) = crate::input::xyz::header_axes(bytes)?;
    Ok(Line::Header(
        Columns { x, y },
        if has_z { "z_tin" } else { "z" },
    ))
}

/// Lazily reads the query points of a file.
pub(super) struct QueryReader {
    pub(super) path: PathBuf,
    lines: std::io::Lines<BufReader<File>>,
    line_no: u64,
    n: u64,
    seen_data: bool,
    cols: Columns,
}

impl QueryReader {
    pub(super) fn open(path: &Path) -> Result<QueryReader> {
        let f = File::open(path).map_err(|e| Error::io(path, e))?;
        Ok(QueryReader {
            path: path.to_path_buf(),
            lines: BufReader::with_capacity(1 << 16, f).lines(),
            line_no: 0,
            n: 0,
            seen_data: false,
            cols: FIRST_TWO,
        })
    }

    pub(super) fn next(&mut self) -> Result<Option<Query>> {
        for line in self.lines.by_ref() {
            self.line_no += 1;
            let line = line.map_err(|e| Error::io(&self.path, e))?;
            let first = !self.seen_data;
            match classify(&line, first, self.cols) {
                Ok(Line::Skip) => {}
                Ok(Line::Header(cols, _)) => {
                    self.seen_data = true;
                    self.cols = cols;
                }
                Ok(Line::Point(x, y)) => {
                    self.seen_data = true;
                    let q = Query { n: self.n, x, y };
                    self.n += 1;
                    return Ok(Some(q));
                }
                Err(message) => {
                    return Err(Error::Parse {
                        path: self.path.clone(),
                        line: self.line_no,
                        message,
                    });
                }
            }
        }
        Ok(None)
    }
}

/// A copy of `path` in the temporary directory when it is a pipe or a device (registered for
/// deletion on interruption); `None` for a regular file.
pub(super) fn spool_stream(
    path: &Path,
) -> Result<Option<(tempfile::TempPath, crate::output::atomic::TempRegistration)>> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_file() {
        return Ok(None);
    }
    if meta.is_dir() {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: "is a directory, not a file of query points".into(),
        });
    }
    let dir = std::env::temp_dir();
    let mut temp = tempfile::Builder::new()
        .prefix(".sweeptin-queries-")
        .tempfile_in(&dir)
        .map_err(|e| Error::write(&dir, e))?;
    let registration =
        crate::output::atomic::register_temp(temp.path(), crate::output::atomic::TempKind::File);
    let mut src = File::open(path).map_err(|e| Error::io(path, e))?;
    std::io::copy(&mut src, temp.as_file_mut()).map_err(|e| Error::write(&dir, e))?;
    Ok(Some((temp.into_temp_path(), registration)))
}
