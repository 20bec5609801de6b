//! XYZ text points: `x y z` per line.
//!
//! The format accepted:
//! - fields are separated by commas, semicolons, tabs or spaces; a run of white space counts as
//!   one (so `1, 2, 3` and `1  2  3` work); two commas or semicolons in a run before the third
//!   number (an empty field: `1,2,,5`), a line with both (`0,15;0,29;10,00`, decimal commas)
//!   and one whose y, z and a further column follow different kinds of separator
//!   (`0,15\t0,29\t10,00`: a comma before y, a tab before z; `1\t2\t12,75`) are errors, never
//!   a column read in the wrong place;
//! - blank lines, and lines whose first non-blank character is `#`, are skipped;
//! - **header**: if the first line that is neither blank nor a comment has a first field that is
//!   not a number (`x,y,z`, `X Y Z`, `Easting;Northing;Height`), that line is skipped as a header.
//!   Only that one line can be a header; later non-numeric lines are errors. A header that names
//!   x, y or z (or easting, northing, height…) in another column than the one it is read from
//!   (`id,x,y,z`) is an error;
//! - the first three fields are `x`, `y`, `z`; further fields (intensity, class, colour…) are
//!   ignored without being read;
//! - numbers are anything Rust's `f64` parser reads (`12`, `-1.5`, `.5`, `3e2`, `+4`); the value
//!   must be finite;
//! - line ends may be `\n` or `\r\n`; the last line needs no line end; a UTF-8 byte-order mark at
//!   the start is skipped; a `\r` with more of the line after it is an error (lines ended by `\r`
//!   alone read as one line).
//!
//! A line with fewer than three fields, a field that is not a number, or a non-finite value is an
//! [`Error::Parse`] naming the file, the 1-based line number and the offending token.
//!
//! [`XyzReader`] reads in chunks with one reusable buffer and no allocation per line, for inputs
//! far larger than memory; [`read_xyz`] reads a whole file.

mod line;

use crate::error::{Error, Result};
pub(crate) use line::{LineError, header_axes, parse_columns, parse_fields};
use line::{check_header, parse_line};
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Size of the read buffer.
const BUFFER: usize = 2 << 20;

/// Longest line accepted (a guard against binary input growing the buffer without bound).
pub const MAX_LINE: usize = 1 << 20;

/// Reads every point of an XYZ file into memory.
///
/// # Errors
/// [`Error::Io`] if the file cannot be read; [`Error::Parse`] naming the first bad line.
pub fn read_xyz(path: impl AsRef<Path>) -> Result<Vec<[f64; 3]>> {
    let mut reader = XyzReader::open(path)?;
    let mut points = Vec::new();
    reader.read_chunk(&mut points, usize::MAX)?;
    Ok(points)
}

/// A chunked, streaming XYZ reader. See the [module docs](self) for the format.
///
/// ```no_run
/// # fn main() -> sweeptin::Result<()> {
/// let mut reader = sweeptin::input::xyz::XyzReader::open("points.xyz")?;
/// let mut chunk = Vec::new();
/// loop {
///     chunk.clear();
///     if reader.read_chunk(&mut chunk, 1 << 20)? == 0 {
///         break;
///     }
///     // … sort and spill `chunk` …
/// }
/// # Ok(()) }
/// ```
#[derive(Debug)]
pub struct XyzReader<R = File> {
    path: PathBuf,
    src: R,
    buf: Box<[u8]>,
    start: usize,
    end: usize,
    line: u64,
    seen_data: bool,
    eof: bool,
}

impl XyzReader<File> {
    /// Opens an XYZ file.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file if it cannot be opened.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        Ok(Self::from_reader(file, path))
    }
}

impl<R: Read> XyzReader<R> {
    /// Reads XYZ text from any reader; `name` is the file name used in error messages.
    pub fn from_reader(src: R, name: impl Into<PathBuf>) -> Self {
        XyzReader {
            path: name.into(),
            src,
            buf: vec![0u8; BUFFER].into_boxed_slice(),
            start: 0,
            end: 0,
            line: 0,
            seen_data: false,
            eof: false,
        }
    }

    /// The file being read.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of lines consumed so far (blank, comment and header lines included).
    pub fn lines_read(&self) -> u64 {
        self.line
    }

    /// Appends up to `max` points to `out` (which it does not clear); returns how many it
    /// appended. `0` means the end of the file (for `max > 0`).
    ///
    /// # Errors
    /// [`Error::Io`] if reading fails; [`Error::Parse`] naming the file, line and token of the
    /// first bad line. After an error the reader should not be used further.
    pub fn read_chunk(&mut self, out: &mut Vec<[f64; 3]>, max: usize) -> Result<usize> {
        let mut n = 0;
        while n < max {
            let Some((from, to)) = self.next_line()? else {
                break;
            };
            self.line += 1;
            let mut bytes = &self.buf[from..to];
            if self.line == 1 {
                if let Some(kind) = super::sniff(&self.buf[from..self.end]) {
                    return Err(Error::Format {
                        path: self.path.clone(),
                        message: format!("is {kind}, not XYZ text (x y z per line)"),
                    });
                }
                bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
            }
            match parse_line(bytes) {
                Ok(None) => {}
                Ok(Some(p)) => {
                    self.seen_data = true;
                    out.push(p);
                    n += 1;
                }
                Err(LineError::NotANumber { field: 0, .. }) if !self.seen_data => {
                    self.seen_data = true; // a header line
                    check_header(bytes).map_err(|m| self.parse_error(m))?;
                }
                Err(_) if is_binary(bytes) => {
                    return Err(self.parse_error(
                        "binary data, not text: this is not an XYZ text file".into(),
                    ));
                }
                Err(e) => return Err(self.parse_error(e.to_string())),
            }
        }
        Ok(n)
    }

    /// The byte range in `buf` of the next line, without its `\n`; `None` at the end of input.
    fn next_line(&mut self) -> Result<Option<(usize, usize)>> {
        loop {
            if let Some(k) = memchr::memchr(b'\n', &self.buf[self.start..self.end]) {
                let from = self.start;
                self.start += k + 1;
                return Ok(Some((from, from + k)));
            }
            if self.eof {
                if self.start < self.end {
                    let from = self.start;
                    self.start = self.end;
                    return Ok(Some((from, self.end)));
                }
                return Ok(None);
            }
            self.refill()?;
        }
    }

    /// Moves the unfinished line to the front of the buffer and reads more after it.
    fn refill(&mut self) -> Result<()> {
        let pending = self.end - self.start;
        if pending >= MAX_LINE {
            self.line += 1;
            let line = &self.buf[self.start..self.end];
            return Err(self.parse_error(if memchr::memchr(b'\r', line).is_some() {
                line::CR_ONLY.to_string()
            } else {
                format!("line is longer than {MAX_LINE} bytes: is this really an XYZ text file?")
            }));
        }
        self.buf.copy_within(self.start..self.end, 0);
        self.start = 0;
        self.end = pending;
        loop {
            match self.src.read(&mut self.buf[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(());
                }
                Ok(k) => {
                    self.end += k;
                    return Ok(());
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Error::io(&self.path, e)),
            }
        }
    }

    fn parse_error(&self, message: String) -> Error {
        Error::Parse {
            path: self.path.clone(),
            line: self.line,
            message,
        }
    }
}

/// Does a line hold bytes no text file has (NUL and other control characters, or invalid
/// UTF-8)?
fn is_binary(line: &[u8]) -> bool {
    line.iter()
        .any(|&b| b < 0x20 && !matches!(b, b'\t' | b'\r' | 0x0c))
        || std::str::from_utf8(line).is_err()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_str(s: impl AsRef<[u8]>) -> Result<Vec<[f64; 3]>> {
        let mut r = XyzReader::from_reader(s.as_ref(), "test.xyz");
        let mut v = Vec::new();
        r.read_chunk(&mut v, usize::MAX)?;
        Ok(v)
    }

    fn err_of(s: impl AsRef<[u8]>) -> (u64, String) {
        match read_str(s).unwrap_err() {
            Error::Parse {
                path,
                line,
                message,
            } => {
                assert_eq!(path, Path::new("test.xyz"));
                (line, message)
            }
            e => panic!("unexpected error {e}"),
        }
    }

    #[test]
    fn separators_comments_header_extra_columns() {
        let text = "\u{feff}# comment\n\nX;Y;Z;Intensity\n1,2,3\n4\t5\t6\t99 class\n  7 8 9\r\n\
                    1e1; -2.5 ; .5\n  # indented comment\n+1,2,3,,,\n10 20 30";
        let v = read_str(text).unwrap();
        assert_eq!(
            v,
            vec![
                [1.0, 2.0, 3.0],
                [4.0, 5.0, 6.0],
                [7.0, 8.0, 9.0],
                [10.0, -2.5, 0.5],
                [1.0, 2.0, 3.0],
                [10.0, 20.0, 30.0]
            ]
        );
    }

    #[test]
    fn empty_fields_and_decimal_commas_are_errors() {
        // A missing z took the class column's value; decimal commas made nonsense points.
        let (line, e) = err_of("1,2,3\n0.15,0.28,,2\n");
        assert_eq!(line, 2);
        assert!(e.starts_with("z is an empty field"), "{e}");
        let (line, e) = err_of("0,15;0,29;10,00\n");
        assert_eq!(line, 1);
        assert!(e.contains("mixes ',' and ';'"), "{e}");
        assert!(err_of(",1,2,3\n").1.starts_with("x is an empty field"));
        // White space around one separator, and extra empty columns after z, are fine.
        assert!(err_of("1 , 2 ;\t3\n").1.contains("mixes"));
        assert_eq!(read_str("1 ,  2 ,\t3,,,\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        // Decimal commas between tabs or spaces were read as x = 0, y = 15, z = 0.
        for line in ["0,15\t0,29\t10,00\n", "0,15 0,29 10,00\n", "1 2,3\n"] {
            assert!(err_of(line).1.contains("decimal commas"), "{line:?}");
        }
        // A decimal comma in z alone: z was read as 12.
        assert!(
            err_of("480000\t6200000\t12,75\n")
                .1
                .contains("decimal commas")
        );
        assert!(err_of("480000;6200000;12,75\n").1.contains("mixes"));
        // Blanks, or commas, throughout, extra columns and a comment after z are fine.
        assert_eq!(
            read_str("1\t2\t3\t7 # c\n1,2,3,,7\n1;2;3\r\n").unwrap(),
            vec![[1.0, 2.0, 3.0]; 3]
        );
    }

    /// Lines ended by `\r` alone read as one line: one point from a whole file.
    #[test]
    fn carriage_returns_inside_a_line_are_refused() {
        for text in [
            "0 0 1\r1 0 2\r0 1 3\r",
            "x y z\r0 0 1\r1 0 2\r",
            "# c\r0 0 1\r1 0 2\r",
            "0,0,1\r\n1,0\r,2\n",
            "0 0 1 5\r1 0 2 6\r",
            "0,0,1,5\r1,0,2,6\r",
            "0 0 1 # c\r1 0 2\r",
        ] {
            assert!(err_of(text).1.contains("tr '\\r' '\\n'"), "{text:?}");
        }
        // A file longer than a line may be says why too.
        let long = "480000.00 6200000.00 12.75 7\r".repeat(50_000);
        assert!(err_of(long).1.contains("tr '\\r' '\\n'"));
        assert_eq!(
            read_str("x y z \r\n# c\r\n0 0 1\r\n1 0 2 \r\n")
                .unwrap()
                .len(),
            2
        );
    }

    /// A header naming the axes in other columns: `id,x,y,z` was read with x = id.
    #[test]
    fn headers_that_name_other_columns_are_refused() {
        for h in [
            "id,x,y,z",
            "z y x",
            "Northing;Easting;Height",
            "x,y,class,z",
        ] {
            let (line, e) = err_of(format!("{h}\n1,2,3,4\n"));
            assert_eq!(line, 1, "{h}");
            assert!(e.contains("put x, y and z first"), "{h}: {e}");
        }
        for h in [
            "x,y,z,class",
            "X Y Z",
            "Easting;Northing;Height",
            "a,b,c",
            "\"x\",\"y\",\"z\"",
        ] {
            assert_eq!(read_str(format!("{h}\n1,2,3,4\n")).unwrap().len(), 1, "{h}");
        }
    }

    #[test]
    fn header_only_on_first_data_line() {
        assert_eq!(read_str("x y z\n1 2 3\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(
            err_of("1 2 3\nx y z\n"),
            (2, "x is not a number: \"x\"".into())
        );
        // A numeric first field makes it a data line, which then must be fully numeric.
        assert_eq!(err_of("1 y z\n"), (1, "y is not a number: \"y\"".into()));
        assert!(read_str("").unwrap().is_empty());
        assert!(read_str("x,y,z\n").unwrap().is_empty());
    }

    #[test]
    fn errors_name_line_and_token() {
        assert_eq!(
            err_of("1 2 3\n\n4 5\n"),
            (3, "expected 3 numbers (x y z), found 2 fields".into())
        );
        assert_eq!(
            err_of("1 2 3\n4\n"),
            (2, "expected 3 numbers (x y z), found 1 field".into())
        );
        assert_eq!(
            err_of("1 2 3\n4 5 abc\n"),
            (2, "z is not a number: \"abc\"".into())
        );
        assert_eq!(
            err_of("1 2 3\n4 NaN 6\n"),
            (2, "y is not a finite number: \"NaN\"".into())
        );
        assert_eq!(
            err_of("1 2 inf"),
            (1, "z is not a finite number: \"inf\"".into())
        );
        assert_eq!(
            err_of("1 2 1e999"),
            (1, "z is not a finite number: \"1e999\"".into())
        );
        // Bytes no text has: said so, not quoted back.
        assert_eq!(
            err_of(b"1 2 3\n4 5 6\xff\n").1,
            "binary data, not text: this is not an XYZ text file"
        );
    }

    #[test]
    fn long_tokens_are_truncated_in_messages() {
        let (_, m) = err_of(format!("1 2 {}\n", "a".repeat(100)));
        assert!(m.chars().count() < 70 && m.contains('…'), "{m}");
    }

    #[test]
    fn chunks_cover_everything_in_order() {
        let mut text = String::from("x y z\n");
        for i in 0..1000 {
            text.push_str(&format!("{i} {} {}\n", i * 2, i % 7));
        }
        let mut r = XyzReader::from_reader(text.as_bytes(), "t.xyz");
        let mut all = Vec::new();
        let mut chunk = Vec::new();
        loop {
            chunk.clear();
            let n = r.read_chunk(&mut chunk, 64).unwrap();
            assert_eq!(n, chunk.len());
            if n == 0 {
                break;
            }
            assert!(n <= 64);
            all.extend_from_slice(&chunk);
        }
        assert_eq!(all.len(), 1000);
        assert_eq!(all[999], [999.0, 1998.0, 5.0]);
        assert_eq!(r.lines_read(), 1001);
    }

    /// A reader that hands out one byte at a time, so every line straddles a buffer refill.
    struct Trickle<'a>(&'a [u8]);
    impl Read for Trickle<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.0.is_empty() || buf.is_empty() {
                return Ok(0);
            }
            buf[0] = self.0[0];
            self.0 = &self.0[1..];
            Ok(1)
        }
    }

    #[test]
    fn lines_split_across_reads() {
        let text = b"x y z\r\n1.25 2 3\r\n4 5 6";
        let mut r = XyzReader::from_reader(Trickle(text), "t.xyz");
        let mut v = Vec::new();
        r.read_chunk(&mut v, 10).unwrap();
        assert_eq!(v, vec![[1.25, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    }

    #[test]
    fn overlong_line_is_an_error_not_unbounded_memory() {
        let text = vec![b'1'; MAX_LINE + 10];
        let mut r = XyzReader::from_reader(&text[..], "t.xyz");
        let e = r.read_chunk(&mut Vec::new(), 10).unwrap_err();
        assert!(matches!(e, Error::Parse { line: 1, .. }), "{e}");
    }

    #[test]
    fn round_trips_shortest_decimal() {
        let vals: [f64; 5] = [0.1, 1.0 / 3.0, 511_500.025, -1e-300, 123_456_789.123_456_79];
        let text: String = vals.iter().map(|v| format!("{v} {v} {v}\n")).collect();
        let v = read_str(&text).unwrap();
        for (p, want) in v.iter().zip(vals) {
            assert_eq!(p[0].to_bits(), want.to_bits());
        }
    }
}
