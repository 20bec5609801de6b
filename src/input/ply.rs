//! PLY mesh reader: ASCII, binary little-endian and binary big-endian.
//!
//! [`read_ply`] returns the vertices (`x`, `y`, `z` of the `vertex` element, of any numeric
//! type, in any position among other properties, which are skipped) and the triangles (the
//! `vertex_indices` or `vertex_index` list of the `face` element, with any integer count and index
//! types). Other elements (edges, materials…) are skipped. Faces that are not triangles, indices
//! outside the vertex element, non-finite coordinates, unknown types, a damaged header and
//! truncated data are [`Error::Format`] errors saying what is wrong and where; no input makes it
//! panic.

use crate::error::{Error, Result};
use crate::validate::MeshKind;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// Largest header accepted, in bytes.
const MAX_HEADER: u64 = 1 << 20;

/// Longest ASCII data line accepted, in bytes.
const MAX_ASCII_LINE: u64 = 1 << 20;

/// Vertices `[x, y, z]` and triangles of indices into them, as [`read_ply`] returns them.
pub type Mesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// Reads a PLY mesh: vertices `[x, y, z]` and triangles of vertex indices.
///
/// # Errors
/// [`Error::Io`] if the file cannot be read; [`Error::Format`] if it is not a PLY file, is damaged
/// or truncated, has faces that are not triangles, indices out of range, non-finite coordinates,
/// or more vertices than 32-bit indices can address.
pub fn read_ply(path: impl AsRef<Path>) -> Result<Mesh> {
    let path = path.as_ref();
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    read_ply_from(BufReader::with_capacity(1 << 20, file), len, path)
}

/// What a PLY mesh says it is: its `comment sweeptin: …` line ([`MeshKind`], as sweeptin's
/// writer records it), or the default (a Delaunay triangulation of its vertices' convex hull)
/// when it has none. Reads the header only.
///
/// # Errors
/// As [`read_ply`] for the header; [`Error::Format`] for a kind word this version does not
/// know.
pub fn read_ply_kind(path: impl AsRef<Path>) -> Result<MeshKind> {
    let path = path.as_ref();
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let header = parse_header(&mut BufReader::new(file), path)?;
    Ok(header.kind)
}

/// [`read_ply`] from any buffered reader; `len` is the total input size in bytes (used only to
/// bound allocations and report truncation early), `name` is used in error messages.
///
/// # Errors
/// As [`read_ply`].
pub fn read_ply_from<R: BufRead>(mut src: R, len: u64, name: impl Into<PathBuf>) -> Result<Mesh> {
    let path = name.into();
    let header = parse_header(&mut src, &path)?;
    let mut body = Body {
        src,
        path,
        encoding: header.encoding,
        remaining: len.saturating_sub(header.bytes),
        line_buf: Vec::new(),
        line_pos: 0,
        line: header.lines,
    };
    body.read(&header.elements)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> u64 {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Property {
    Scalar {
        name: String,
        ty: Scalar,
    },
    List {
        name: String,
        count: Scalar,
        item: Scalar,
    },
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar { name, .. } | Property::List { name, .. } => name,
        }
    }
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

impl Element {
    /// Smallest size of one instance in the file (lists counted as empty).
    fn min_bytes(&self, encoding: Encoding) -> u64 {
        let sum = self
            .props
            .iter()
            .map(|p| match (encoding, p) {
                // At least one character and one separator per value in ASCII.
                (Encoding::Ascii, _) => 2,
                (_, Property::Scalar { ty, .. }) => ty.size(),
                (_, Property::List { count, .. }) => count.size(),
            })
            .sum::<u64>();
        sum.max(1)
    }

    fn has_lists(&self) -> bool {
        self.props
            .iter()
            .any(|p| matches!(p, Property::List { .. }))
    }
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Size of the header in bytes.
    bytes: u64,
    /// Lines in the header.
    lines: u64,
    /// The `comment sweeptin: …` line's kind.
    kind: MeshKind,
}

fn format_error(path: &Path, message: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

fn parse_header<R: BufRead>(src: &mut R, path: &Path) -> Result<Header> {
    let mut bytes = 0u64;
    let mut lines = 0u64;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut kind = MeshKind::default();
    let mut raw = Vec::new();
    loop {
        raw.clear();
        let n = src
            .by_ref()
            .take(MAX_HEADER + 1 - bytes)
            .read_until(b'\n', &mut raw)
            .map_err(|e| Error::io(path, e))?;
        bytes += n as u64;
        lines += 1;
        if bytes > MAX_HEADER {
            return Err(format_error(
                path,
                format!("the PLY header is longer than {MAX_HEADER} bytes"),
            ));
        }
        if lines == 1 {
            if raw
                .strip_suffix(b"\n")
                .map(|l| l.strip_suffix(b"\r").unwrap_or(l))
                != Some(b"ply")
            {
                return Err(format_error(
                    path,
                    "not a PLY file: it does not start with \"ply\"",
                ));
            }
            continue;
        }
        if raw.last() != Some(&b'\n') {
            return Err(format_error(
                path,
                "truncated PLY header: no end_header line",
            ));
        }
        let text = String::from_utf8_lossy(&raw);
        let line = text.trim_end_matches(['\n', '\r']);
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let at = |m: String| format_error(path, format!("PLY header line {lines}: {m}"));
        match words.as_slice() {
            ["comment", "sweeptin:", words @ ..] => {
                kind = MeshKind::from_words(&words.join(" ")).map_err(|w| {
                    at(format!(
                        "\"{w}\" in the comment that says what the mesh is: a later version's \
                         word? (the mesh cannot be checked as this version knows)"
                    ))
                })?;
            }
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", fmt, _version] => {
                encoding = Some(match *fmt {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLe,
                    "binary_big_endian" => Encoding::BinaryBe,
                    other => return Err(at(format!("unknown format \"{other}\""))),
                });
            }
            ["element", name, count] => {
                let count = count
                    .parse::<u64>()
                    .map_err(|_| at(format!("bad element count \"{count}\"")))?;
                elements.push(Element {
                    name: (*name).to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", count, item, name] => {
                let ty = |t: &str| {
                    Scalar::parse(t)
                        .filter(|s| s.is_integer())
                        .ok_or_else(|| at(format!("bad list type \"{t}\"")))
                };
                let prop = Property::List {
                    name: (*name).to_string(),
                    count: ty(count)?,
                    item: Scalar::parse(item)
                        .ok_or_else(|| at(format!("unknown type \"{item}\"")))?,
                };
                let Some(el) = elements.last_mut() else {
                    return Err(at("property before any element".into()));
                };
                el.props.push(prop);
            }
            ["property", ty, name] => {
                let ty = Scalar::parse(ty).ok_or_else(|| at(format!("unknown type \"{ty}\"")))?;
                let Some(el) = elements.last_mut() else {
                    return Err(at("property before any element".into()));
                };
                el.props.push(Property::Scalar {
                    name: (*name).to_string(),
                    ty,
                });
            }
            ["end_header"] => break,
            _ => return Err(at(format!("cannot read \"{}\"", shorten(line)))),
        }
    }
    let Some(encoding) = encoding else {
        return Err(format_error(path, "PLY header has no format line"));
    };
    Ok(Header {
        encoding,
        elements,
        bytes,
        lines,
        kind,
    })
}

/// At most 60 characters of `s`, for messages.
fn shorten(s: &str) -> String {
    if s.chars().count() > 60 {
        s.chars().take(60).chain("…".chars()).collect()
    } else {
        s.to_string()
    }
}

/// Which element instance is being read, for messages.
#[derive(Clone, Copy)]
struct Where<'a> {
    element: &'a str,
    index: u64,
}

/// The data after the header.
struct Body<R> {
    src: R,
    path: PathBuf,
    encoding: Encoding,
    /// Bytes after the header (an upper bound used for sanity checks).
    remaining: u64,
    /// ASCII: the current line and the read position in it.
    line_buf: Vec<u8>,
    line_pos: usize,
    /// ASCII: 1-based number of the current line.
    line: u64,
}

impl<R: BufRead> Body<R> {
    fn error(&self, at: Where<'_>, message: impl std::fmt::Display) -> Error {
        let line = if self.encoding == Encoding::Ascii {
            format!("line {}: ", self.line)
        } else {
            String::new()
        };
        format_error(
            &self.path,
            format!("{line}{} {}: {message}", at.element, at.index),
        )
    }

    fn read(&mut self, elements: &[Element]) -> Result<Mesh> {
        let vertex_count = match elements.iter().find(|e| e.name == "vertex") {
            Some(e) => e.count,
            None => return Err(format_error(&self.path, "PLY file has no vertex element")),
        };
        if vertex_count > u64::from(u32::MAX) + 1 {
            return Err(format_error(
                &self.path,
                format!("{vertex_count} vertices: more than 32-bit indices can address"),
            ));
        }
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for el in elements {
            self.check_size(el)?;
            if self.encoding != Encoding::Ascii && !el.has_lists() {
                let size = el.count.saturating_mul(el.min_bytes(self.encoding));
                self.remaining -= size; // check_size made sure it fits
            }
            match el.name.as_str() {
                "vertex" => self.read_vertices(el, &mut vertices)?,
                "face" => self.read_faces(el, vertex_count, &mut triangles)?,
                _ => self.skip_element(el)?,
            }
        }
        Ok((vertices, triangles))
    }

    /// Fails early when a fixed-size binary element cannot fit in what is left of the file.
    fn check_size(&self, el: &Element) -> Result<()> {
        if self.encoding == Encoding::Ascii || el.has_lists() {
            return Ok(());
        }
        let need = el.count.saturating_mul(el.min_bytes(self.encoding));
        if need > self.remaining {
            return Err(format_error(
                &self.path,
                format!(
                    "truncated: the header announces {} {} elements ({need} bytes) but only {} \
                     bytes of data follow",
                    el.count, el.name, self.remaining
                ),
            ));
        }
        Ok(())
    }

    /// How many instances to reserve room for: the announced count, capped by what the file
    /// can hold and by a fixed amount (beyond it the vectors grow as they fill), so that a lying
    /// header cannot make us allocate much.
    fn capacity(&self, el: &Element) -> usize {
        const MAX_RESERVE: u64 = 1 << 24;
        let fit = self.remaining / el.min_bytes(self.encoding);
        el.count.min(fit).min(MAX_RESERVE) as usize
    }

    fn read_vertices(&mut self, el: &Element, out: &mut Vec<[f64; 3]>) -> Result<()> {
        let mut slot = Vec::with_capacity(el.props.len());
        for axis in ["x", "y", "z"] {
            match el.props.iter().position(|p| p.name() == axis) {
                Some(i) if matches!(el.props[i], Property::Scalar { .. }) => slot.push(i),
                Some(_) => {
                    return Err(format_error(
                        &self.path,
                        format!("vertex property \"{axis}\" is a list"),
                    ));
                }
                None => {
                    return Err(format_error(
                        &self.path,
                        format!("the vertex element has no property \"{axis}\""),
                    ));
                }
            }
        }
        out.reserve(self.capacity(el));
        for index in 0..el.count {
            let at = Where {
                element: "vertex",
                index,
            };
            let mut p = [0.0; 3];
            for (k, prop) in el.props.iter().enumerate() {
                match prop {
                    Property::Scalar { ty, .. } => {
                        let v = self.scalar(*ty, at)?;
                        if let Some(axis) = slot.iter().position(|&s| s == k) {
                            p[axis] = v;
                        }
                    }
                    Property::List { count, item, .. } => self.skip_list(*count, *item, at)?,
                }
            }
            if !p.iter().all(|c| c.is_finite()) {
                return Err(self.error(
                    at,
                    format!("coordinate is not finite ({}, {}, {})", p[0], p[1], p[2]),
                ));
            }
            out.push(p);
            self.end_instance(at)?;
        }
        Ok(())
    }

    fn read_faces(
        &mut self,
        el: &Element,
        vertex_count: u64,
        out: &mut Vec<[u32; 3]>,
    ) -> Result<()> {
        let Some(list) = el.props.iter().position(|p| {
            matches!(p, Property::List { name, .. } if name == "vertex_indices" || name == "vertex_index")
        }) else {
            return Err(format_error(
                &self.path,
                "the face element has no vertex_indices list",
            ));
        };
        if let Property::List { item, .. } = el.props[list]
            && !item.is_integer()
        {
            return Err(format_error(
                &self.path,
                "face vertex indices have a floating-point type",
            ));
        }
        out.reserve(self.capacity(el));
        for index in 0..el.count {
            let at = Where {
                element: "face",
                index,
            };
            let mut tri = None;
            for (k, prop) in el.props.iter().enumerate() {
                match prop {
                    Property::Scalar { ty, .. } => {
                        self.scalar(*ty, at)?;
                    }
                    Property::List { count, item, .. } if k == list => {
                        tri = Some(self.triangle(*count, *item, vertex_count, at)?);
                    }
                    Property::List { count, item, .. } => self.skip_list(*count, *item, at)?,
                }
            }
            out.extend(tri);
            self.end_instance(at)?;
        }
        Ok(())
    }

    fn triangle(
        &mut self,
        count: Scalar,
        item: Scalar,
        vertices: u64,
        at: Where<'_>,
    ) -> Result<[u32; 3]> {
        let n = self.scalar(count, at)?;
        if n != 3.0 {
            return Err(self.error(
                at,
                format!("has {n} vertices; only triangles are supported"),
            ));
        }
        let mut t = [0u32; 3];
        for slot in &mut t {
            let v = self.scalar(item, at)?;
            if !(v >= 0.0 && v < vertices as f64) {
                return Err(self.error(
                    at,
                    format!("refers to vertex {v}, but there are {vertices} vertices"),
                ));
            }
            // In range and integral (integer type): the conversion is exact.
            *slot = v as u32;
        }
        Ok(t)
    }

    fn skip_list(&mut self, count: Scalar, item: Scalar, at: Where<'_>) -> Result<()> {
        let n = self.scalar(count, at)?;
        if n < 0.0 {
            return Err(self.error(at, format!("negative list length {n}")));
        }
        for _ in 0..n as u64 {
            self.scalar(item, at)?;
        }
        Ok(())
    }

    fn skip_element(&mut self, el: &Element) -> Result<()> {
        for index in 0..el.count {
            let at = Where {
                element: &el.name,
                index,
            };
            for prop in &el.props {
                match prop {
                    Property::Scalar { ty, .. } => {
                        self.scalar(*ty, at)?;
                    }
                    Property::List { count, item, .. } => self.skip_list(*count, *item, at)?,
                }
            }
            self.end_instance(at)?;
        }
        Ok(())
    }

    /// One value, widened to `f64` (exact for every PLY type).
    fn scalar(&mut self, ty: Scalar, at: Where<'_>) -> Result<f64> {
        match self.encoding {
            Encoding::Ascii => self.ascii_scalar(ty, at),
            Encoding::BinaryLe => self.binary_scalar(ty, at, false),
            Encoding::BinaryBe => self.binary_scalar(ty, at, true),
        }
    }

    fn binary_scalar(&mut self, ty: Scalar, at: Where<'_>, big: bool) -> Result<f64> {
        let mut b = [0u8; 8];
        let n = ty.size() as usize;
        if let Err(e) = self.src.read_exact(&mut b[..n]) {
            return Err(if e.kind() == std::io::ErrorKind::UnexpectedEof {
                self.error(at, "truncated: the file ends here")
            } else {
                Error::io(&self.path, e)
            });
        }
        if big {
            b[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    fn ascii_scalar(&mut self, ty: Scalar, at: Where<'_>) -> Result<f64> {
        let token = self.ascii_token(at)?;
        let text = std::str::from_utf8(&self.line_buf[token.0..token.1]).unwrap_or("");
        let value = if ty.is_integer() {
            text.parse::<i64>().ok().and_then(|v| {
                let (lo, hi) = match ty {
                    Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
                    Scalar::U8 => (0, u8::MAX.into()),
                    Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
                    Scalar::U16 => (0, u16::MAX.into()),
                    Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
                    _ => (0, u32::MAX.into()),
                };
                (lo..=hi).contains(&v).then_some(v as f64)
            })
        } else if ty == Scalar::F32 {
            text.parse::<f32>().ok().map(f64::from)
        } else {
            text.parse::<f64>().ok()
        };
        value.ok_or_else(|| {
            let shown = shorten(&String::from_utf8_lossy(&self.line_buf[token.0..token.1]));
            self.error(at, format!("\"{shown}\" is not a valid {ty:?} value"))
        })
    }

    /// The byte range of the next whitespace-separated token in `line_buf`, reading lines as
    /// needed. In ASCII PLY every element instance is on its own line.
    fn ascii_token(&mut self, at: Where<'_>) -> Result<(usize, usize)> {
        loop {
            let buf = &self.line_buf;
            let mut i = self.line_pos;
            while i < buf.len() && buf[i].is_ascii_whitespace() {
                i += 1;
            }
            if i < buf.len() {
                let from = i;
                while i < buf.len() && !buf[i].is_ascii_whitespace() {
                    i += 1;
                }
                self.line_pos = i;
                return Ok((from, i));
            }
            if !self.next_ascii_line(at)? {
                return Err(self.error(at, "truncated: the file ends here"));
            }
        }
    }

    fn next_ascii_line(&mut self, at: Where<'_>) -> Result<bool> {
        self.line_buf.clear();
        self.line_pos = 0;
        let n = self
            .src
            .by_ref()
            .take(MAX_ASCII_LINE)
            .read_until(b'\n', &mut self.line_buf)
            .map_err(|e| Error::io(&self.path, e))?;
        self.line += 1;
        if n as u64 == MAX_ASCII_LINE && self.line_buf.last() != Some(&b'\n') {
            return Err(self.error(at, format!("line longer than {MAX_ASCII_LINE} bytes")));
        }
        Ok(n > 0)
    }

    /// ASCII: an element instance must not have more values on its line.
    fn end_instance(&mut self, at: Where<'_>) -> Result<()> {
        if self.encoding != Encoding::Ascii {
            return Ok(());
        }
        let rest = &self.line_buf[self.line_pos.min(self.line_buf.len())..];
        if rest.iter().any(|b| !b.is_ascii_whitespace()) {
            return Err(self.error(at, "more values on the line than the header declares"));
        }
        self.line_buf.clear();
        self.line_pos = 0;
        Ok(())
    }
}
