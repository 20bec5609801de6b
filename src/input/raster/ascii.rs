//! The ESRI ASCII grid side of [`RasterReader`]: the header, and windows read by scanning from the
//! nearest row start seen before (see the [parent module](super)).

use super::{RasterReader, RasterSpec, SampleType, Source, format};
use crate::error::{Error, Result};
use std::fs::File;
use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::Path;

/// An open ASCII grid: the row starts found so far.
pub(super) struct AsciiSource {
    /// Known row starts: `(row, byte offset, line number)`, increasing.
    pub(super) rows: Vec<(u32, u64, u64)>,
}

pub(super) fn open_ascii(path: &Path, file: File) -> Result<RasterReader> {
    let mut r = BufReader::new(file);
    // Each key with its value, line and text.
    let mut header: Vec<(String, f64, u64, String)> = Vec::new();
    let mut offset = 0u64;
    let mut line_no = 0u64;
    let mut line = String::new();
    loop {
        let start = offset;
        line.clear();
        let n = r.read_line(&mut line).map_err(|e| {
            if e.kind() == std::io::ErrorKind::InvalidData {
                format(path, "binary data, not text: not an ESRI ASCII grid")
            } else {
                Error::io(path, e)
            }
        })?;
        if n == 0 {
            break;
        }
        let mut it = line.split_whitespace();
        let Some(key) = it.next() else {
            offset += n as u64;
            line_no += 1;
            continue;
        };
        if !key.as_bytes()[0].is_ascii_alphabetic() {
            // First data line.
            offset = start;
            break;
        }
        line_no += 1;
        offset += n as u64;
        let text = it.next().unwrap_or_default();
        let value = Some(text)
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| Error::Parse {
                path: path.to_path_buf(),
                line: line_no,
                message: format!("header line {key:?} needs a number"),
            })?;
        header.push((key.to_ascii_lowercase(), value, line_no, text.to_string()));
    }
    let find = |k: &str| header.iter().find(|(h, ..)| h == k);
    let get = |k: &str| find(k).map(|e| e.1);
    let need = |k: &str| {
        get(k).ok_or_else(|| {
            format(
                path,
                format!("not a GeoTIFF, and not an ESRI ASCII grid: header has no {k:?}"),
            )
        })
    };
    let cols = need("ncols")?;
    let rows = need("nrows")?;
    for (k, v) in [("ncols", cols), ("nrows", rows)] {
        if !(v >= 1.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0) {
            return Err(format(path, format!("{k} {v} is not a positive integer")));
        }
    }
    let (cols, rows) = (cols as u32, rows as u32);
    let (dx, dy) = match (get("cellsize"), get("dx"), get("dy")) {
        (Some(c), _, _) => (c, c),
        (None, Some(dx), Some(dy)) => (dx, dy),
        _ => return Err(format(path, "header has no \"cellsize\" (nor dx and dy)")),
    };
    if !(dx > 0.0 && dy > 0.0 && dx.is_finite() && dy.is_finite()) {
        return Err(format(
            path,
            format!("cell size {dx} × {dy} is not positive"),
        ));
    }
    let x0 = match (get("xllcorner"), get("xllcenter")) {
        (Some(x), _) => x,
        (None, Some(x)) => x - 0.5 * dx,
        _ => {
            return Err(format(
                path,
                "header has no \"xllcorner\" nor \"xllcenter\"",
            ));
        }
    };
    let y0 = match (get("yllcorner"), get("yllcenter")) {
        (Some(y), _) => y,
        (None, Some(y)) => y - 0.5 * dy,
        _ => {
            return Err(format(
                path,
                "header has no \"yllcorner\" nor \"yllcenter\"",
            ));
        }
    };
    let top = y0 + f64::from(rows) * dy;
    // Every cell centre in the predicates' exact range (a mesh made of them is written, and
    // read back by `check`, as any other).
    let right = x0 + f64::from(cols) * dx;
    let x_key = if get("xllcorner").is_some() {
        "xllcorner"
    } else {
        "xllcenter"
    };
    let y_key = if get("yllcorner").is_some() {
        "yllcorner"
    } else {
        "yllcenter"
    };
    let size_key = if get("cellsize").is_some() {
        "cellsize"
    } else {
        "dx"
    };
    for (v, key, edge) in [
        (x0, x_key, "west"),
        (right, size_key, "east"),
        (y0, y_key, "south"),
        (top, if size_key == "dx" { "dy" } else { size_key }, "north"),
    ] {
        if !super::in_exact_range(v) {
            let (line, text) = find(key).map_or((0, ""), |e| (e.2, e.3.as_str()));
            return Err(Error::Parse {
                path: path.to_path_buf(),
                line,
                message: format!(
                    "{key} {text}: the grid's {edge} edge at {v:e} is outside the coordinates a \
                     TIN can hold exactly (|x| and |y| up to {:e}); check the header's numbers \
                     and units",
                    crate::geom::predicates::MAX_COORD
                ),
            });
        }
    }
    let crs = std::fs::read_to_string(path.with_extension("prj"))
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty());
    Ok(RasterReader {
        path: path.to_path_buf(),
        spec: RasterSpec {
            cols,
            rows,
            transform: [x0, dx, 0.0, top, 0.0, -dy],
            nodata: get("nodata_value"),
            crs,
        },
        sample: SampleType::Text,
        source: Source::Ascii(AsciiSource {
            rows: vec![(0, offset, line_no + 1)],
        }),
    })
}

pub(super) fn read_ascii_window(
    path: &Path,
    spec: &RasterSpec,
    a: &mut AsciiSource,
    w: [u32; 4],
    out: &mut [f64],
) -> Result<()> {
    let [col0, row0, cols, rows] = w;
    let &(start_row, start, start_line) = a
        .rows
        .iter()
        .rev()
        .find(|r| r.0 <= row0)
        .expect("row 0 is always known");
    let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
    file.seek(SeekFrom::Start(start))
        .map_err(|e| Error::io(path, e))?;
    let mut r = BufReader::with_capacity(1 << 16, file);
    let ncols = spec.cols as u64;
    let mut index = u64::from(start_row) * ncols; // token index of the next value
    let end = u64::from(row0 + rows) * ncols;
    // A window that reaches the last row reads on to the end of the file: nothing but
    // whitespace may follow the grid's values (an extra row, or a header line such as
    // `NODATA_value` after the data, was ignored and its nodata cells read as heights).
    let last = end == spec.cells();
    let (mut offset, mut line) = (start, start_line);
    let mut token = Vec::with_capacity(32);
    let mut token_start = offset;
    loop {
        let buf = r.fill_buf().map_err(|e| Error::io(path, e))?;
        if buf.is_empty() {
            break;
        }
        let n = buf.len();
        for &b in buf {
            if b.is_ascii_whitespace() {
                if !token.is_empty() {
                    if index >= end {
                        return Err(after_grid(path, spec, &token, line));
                    }
                    store_token(path, spec, a, &token, index, token_start, line, w, out)?;
                    index += 1;
                    token.clear();
                    if index >= end && !last {
                        return Ok(());
                    }
                }
                if b == b'\n' {
                    line += 1;
                }
            } else {
                if token.is_empty() {
                    token_start = offset;
                }
                token.push(b);
            }
            offset += 1;
        }
        r.consume(n);
    }
    if !token.is_empty() {
        if index >= end {
            return Err(after_grid(path, spec, &token, line));
        }
        store_token(path, spec, a, &token, index, token_start, line, w, out)?;
        index += 1;
    }
    if index < end {
        return Err(Error::Parse {
            path: path.to_path_buf(),
            line,
            message: format!(
                "the grid ends after {index} values; the header promises {} × {}",
                spec.cols, spec.rows
            ),
        });
    }
    let _ = (col0, cols);
    Ok(())
}

/// The error for `token`, on `line`, after the grid's last value.
fn after_grid(path: &Path, spec: &RasterSpec, token: &[u8], line: u64) -> Error {
    let token = String::from_utf8_lossy(token);
    let what = if token.as_bytes()[0].is_ascii_alphabetic() {
        "a header line after the data (header lines come before the first value)".to_string()
    } else {
        format!(
            "more values than the header's {} rows × {} columns (a row too many, or nrows or \
             ncols wrong)",
            spec.rows, spec.cols
        )
    };
    Error::Parse {
        path: path.to_path_buf(),
        line,
        message: format!("{token:?} after the grid's last value: {what}"),
    }
}

#[allow(clippy::too_many_arguments)]
fn store_token(
    path: &Path,
    spec: &RasterSpec,
    a: &mut AsciiSource,
    token: &[u8],
    index: u64,
    token_start: u64,
    line: u64,
    w: [u32; 4],
    out: &mut [f64],
) -> Result<()> {
    let [col0, row0, cols, _] = w;
    let ncols = u64::from(spec.cols);
    let (row, col) = ((index / ncols) as u32, (index % ncols) as u32);
    if col == 0 && a.rows.last().is_some_and(|r| r.0 < row) {
        a.rows.push((row, token_start, line));
    }
    if row < row0 || col < col0 || col >= col0 + cols {
        return Ok(());
    }
    let text = std::str::from_utf8(token).ok();
    let v = text
        .and_then(|t| t.parse::<f64>().ok())
        .filter(|v| !v.is_infinite())
        .ok_or_else(|| Error::Parse {
            path: path.to_path_buf(),
            line,
            message: format!(
                "value {:?} of row {row}, column {col} is not a (finite) number",
                String::from_utf8_lossy(token)
            ),
        })?;
    out[(row - row0) as usize * cols as usize + (col - col0) as usize] = v;
    Ok(())
}
