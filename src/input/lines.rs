//! Reading breaklines: GeoJSON and a simple text format.
//!
//! # GeoJSON
//!
//! Read by [`crate::input::geojson`], the one GeoJSON reader (its docs say what is accepted):
//! every line and every ring of every polygon (outer and inner) becomes a polyline, a ring closed
//! (its last vertex repeats the first). `Point` and `MultiPoint` are refused (they are not lines).
//! Positions with three values are hard breaklines (`z` given); with two values `z` is unknown
//! (`NaN`). The file's `crs` member becomes [`Lines::crs`].
//!
//! # Text
//!
//! One vertex per line, `x y` or `x y z`, separated by spaces, tabs or commas. A blank line ends a
//! polyline; `#` starts a comment (a line holding only a comment does not end the polyline). A
//! closed ring repeats its first vertex. See `docs/FORMATS.md`.
//!
//! A file is GeoJSON when its first non-blank character is `{`, text otherwise. A text file is
//! parsed as it is read, one polyline held at a time ([`LineStream`] hands them on without
//! keeping them).
//!
//! # GeoPackage, OGR-SQLite, Shapefile
//!
//! Read by [`crate::input::vector`] (a layer named as `FILE:LAYER`) into the same parts as
//! GeoJSON, and taken the same way.
//!
//! # Errors
//!
//! Syntax errors name the file and the line ([`Error::Parse`]); a well-formed file with something
//! that is not a breakline names the file and the feature ([`Error::Format`]).

use super::geojson::{self, is_ring, not_a_ring};
use super::vector;
use crate::error::{Error, Result};
use std::fmt;
use std::io::{BufRead, Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a polyline comes from, for error messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Source {
    /// The file.
    pub path: Arc<Path>,
    /// The place in the file.
    pub location: Location,
}

/// A place in a breakline file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// GeoJSON: the feature's index in the collection (0 for a lone feature or geometry) and the
    /// part within it (line of a multi-line, ring of a polygon, counted across the feature).
    Feature {
        /// 0-based feature index.
        index: u64,
        /// 0-based part index within the feature.
        part: u32,
    },
    /// Text: the 1-based line of the polyline's first vertex.
    Line(u64),
}

impl fmt::Display for Source {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Location::Feature { index, part } => {
                write!(f, "{} feature {index} part {part}", self.path.display())
            }
            Location::Line(line) => write!(f, "{}:{line}", self.path.display()),
        }
    }
}

/// Polylines read from breakline files.
#[derive(Clone, Debug, Default)]
pub struct Lines {
    /// The polylines, `[x, y, z]` with `z = NaN` where unknown; a closed ring repeats its first
    /// vertex at the end.
    pub polylines: Vec<Vec<[f64; 3]>>,
    /// Where each polyline comes from (same length as `polylines`).
    pub sources: Vec<Source>,
    /// The coordinate reference system the files declare (`EPSG:xxxx` when recognised), if any.
    pub crs: Option<String>,
}

impl Lines {
    /// Number of polylines.
    pub fn len(&self) -> usize {
        self.polylines.len()
    }

    /// No polylines?
    pub fn is_empty(&self) -> bool {
        self.polylines.is_empty()
    }

    /// Number of vertices over all polylines.
    pub fn vertex_count(&self) -> usize {
        self.polylines.iter().map(Vec::len).sum()
    }

    /// Number of segments (consecutive vertex pairs) over all polylines.
    pub fn segment_count(&self) -> usize {
        self.polylines
            .iter()
            .map(|p| p.len().saturating_sub(1))
            .sum()
    }

    /// Is polyline `i` a closed ring (at least 4 vertices, the last equal in `x, y` to the first)?
    pub fn is_ring(&self, i: usize) -> bool {
        is_ring(&self.polylines[i])
    }

    /// Appends `other`.
    ///
    /// # Errors
    /// [`Error::Format`] when both declare a CRS and they differ.
    pub fn append(&mut self, other: Lines) -> Result<()> {
        agree_crs(&mut self.crs, &other)?;
        self.polylines.extend(other.polylines);
        self.sources.extend(other.sources);
        Ok(())
    }

    /// Applies `f` to every `(x, y)` (for instance into the point cloud's local frame); `z` is kept.
    pub fn map_xy(&mut self, mut f: impl FnMut([f64; 2]) -> [f64; 2]) {
        for p in self.polylines.iter_mut().flatten() {
            let [x, y] = f([p[0], p[1]]);
            p[0] = x;
            p[1] = y;
        }
    }

    /// Checks that every polyline is a closed ring (for `--boundary` and `--holes`).
    ///
    /// # Errors
    /// [`Error::Format`] naming the first polyline that is not.
    pub fn require_rings(&self) -> Result<()> {
        for (i, p) in self.polylines.iter().enumerate() {
            if !is_ring(p) {
                let s = &self.sources[i];
                return Err(Error::Format {
                    path: s.path.to_path_buf(),
                    message: not_a_ring(&s.to_string(), p.len()),
                });
            }
        }
        Ok(())
    }
}

/// Reads one breakline file (GeoJSON or text, told apart by the first non-blank character).
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Parse`] for a syntax error (file and
/// line); [`Error::Format`] for content that is not breaklines (file and feature).
pub fn read_file(path: &Path) -> Result<Lines> {
    let mut lines = Lines::default();
    let text = |l: &[[f64; 3]], s: &Source| {
        lines.polylines.push(l.to_vec());
        lines.sources.push(s.clone());
        Ok(())
    };
    match open(path, text)? {
        Some(whole) => Ok(whole),
        None => Ok(lines),
    }
}

/// Opens the breakline file `path`: a text file is parsed here, each polyline given to `text`
/// as it is read (`None` returned); any other is read whole.
///
/// # Errors
/// As [`read_file`], and `text`'s.
fn open(
    path: &Path,
    mut text: impl FnMut(&[[f64; 3]], &Source) -> Result<()>,
) -> Result<Option<Lines>> {
    let (file, _) = vector::split_layer(path);
    if vector::format_of(&file) != vector::VectorFormat::GeoJson {
        // The SQLite and Shapefile readers open the file themselves (and what lies beside it:
        // a database's `-wal`, a Shapefile's `.shx`).
        return from_parts(vector::read(path)?, Arc::from(path)).map(Some);
    }
    let io = |e| Error::io(path, e);
    let mut f = std::fs::File::open(path).map_err(io)?;
    // The first non-blank byte tells GeoJSON from text.
    let mut chunk = [0u8; 4096];
    let first = loop {
        let n = f.read(&mut chunk).map_err(io)?;
        if n == 0 {
            break None;
        }
        if let Some(b) = chunk[..n].iter().find(|b| !b.is_ascii_whitespace()) {
            break Some(*b);
        }
    };
    f.rewind().map_err(io)?;
    if first == Some(b'{') {
        let mut bytes = Vec::new();
        f.read_to_end(&mut bytes).map_err(io)?;
        return read_geojson(&bytes, Arc::from(path)).map(Some);
    }
    let reader = std::io::BufReader::with_capacity(1 << 16, f);
    parse_text(reader, Arc::from(path), &mut text)?;
    Ok(None)
}

/// What is called with each polyline read and where it comes from.
pub type EachLine<'a> = dyn FnMut(&[[f64; 3]], &Source) -> Result<()> + 'a;

/// Breakline files read polyline by polyline, as often as asked, then polylines already in
/// memory (the boundary and hole rings): what a run's streamed cleaning reads
/// ([`crate::breaklines::clean::stream::PolylineSource`]). A text file is parsed as it is read,
/// one polyline held at a time; a GeoJSON, GeoPackage or Shapefile file is read whole, one file
/// at a time.
#[derive(Clone, Debug, Default)]
pub struct LineStream {
    /// The files, read in this order.
    pub paths: Vec<PathBuf>,
    /// Polylines after those of the files.
    pub then: Lines,
}

impl LineStream {
    /// Calls `f` with every polyline and its source, in order; returns the most vertices held at
    /// once (the longest polyline of a text file, every vertex of a file read whole, those of
    /// [`LineStream::then`] all along).
    ///
    /// # Errors
    /// As [`read_files`] (the files' CRSs must agree), and `f`'s.
    pub fn for_each(&self, f: &mut EachLine<'_>) -> Result<u64> {
        let mut crs = None;
        let then = self.then.vertex_count() as u64;
        let mut held = 0u64;
        for p in &self.paths {
            let mut text = |l: &[[f64; 3]], s: &Source| {
                held = held.max(l.len() as u64);
                f(l, s)
            };
            if let Some(whole) = open(p, &mut text)? {
                held = held.max(whole.vertex_count() as u64);
                agree_crs(&mut crs, &whole)?;
                for (l, s) in whole.polylines.iter().zip(&whole.sources) {
                    f(l, s)?;
                }
            }
        }
        agree_crs(&mut crs, &self.then)?;
        for (l, s) in self.then.polylines.iter().zip(&self.then.sources) {
            f(l, s)?;
        }
        Ok(held + then)
    }

    /// Where polyline `i` (in [`LineStream::for_each`]'s order) comes from (reading the files
    /// again up to it: for error messages).
    pub fn source(&self, i: u64) -> Option<Source> {
        let mut k = 0u64;
        let mut found = None;
        // An error ends the walk: the source found, or a reading error (no source to name).
        let _ = self.for_each(&mut |_, s| {
            if k == i {
                found = Some(s.clone());
                return Err(Error::Internal(String::new()));
            }
            k += 1;
            Ok(())
        });
        found
    }
}

/// A cleaning error of a polyline ([`Error::BadLine`]) named by the file and place it comes
/// from (`source` of its index), when known; other errors as they are.
pub(crate) fn name_bad_line(e: Error, source: impl FnOnce(u64) -> Option<Source>) -> Error {
    match e {
        Error::BadLine {
            polyline,
            vertex,
            message,
        } => match source(polyline) {
            Some(s) => Error::Format {
                path: s.path.to_path_buf(),
                message: format!("{s}, vertex {vertex}: {message}"),
            },
            None => Error::BadLine {
                polyline,
                vertex,
                message,
            },
        },
        other => other,
    }
}

/// Takes the CRS `other` declares into `crs`.
///
/// # Errors
/// [`Error::Format`] naming `other`'s file when both declare a CRS and they differ.
fn agree_crs(crs: &mut Option<String>, other: &Lines) -> Result<()> {
    match (&*crs, &other.crs) {
        (Some(a), Some(b)) if a != b => {
            let path = other
                .sources
                .first()
                .map_or_else(PathBuf::new, |s| s.path.to_path_buf());
            Err(Error::Format {
                path,
                message: format!("declares CRS {b}, but the breaklines read before declare {a}"),
            })
        }
        (None, Some(_)) => {
            crs.clone_from(&other.crs);
            Ok(())
        }
        _ => Ok(()),
    }
}

/// As [`read_file`], from `bytes`, the content of the file `path` names (`FILE:LAYER` picks a
/// layer as there): what a caller that read the file itself parses, so that it can fingerprint
/// exactly the bytes parsed (a plan's line files, `plan::lines`). Errors name `path`.
///
/// # Errors
/// As [`read_file`] (no [`Error::Io`] for the file itself).
pub(crate) fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Lines> {
    let (file, _) = vector::split_layer(path);
    if vector::format_of_bytes(&file, bytes) != vector::VectorFormat::GeoJson {
        return from_parts(vector::read_bytes(path, bytes)?, Arc::from(path));
    }
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    let path: Arc<Path> = Arc::from(path);
    if first == Some(&b'{') {
        read_geojson(bytes, path)
    } else {
        read_text(bytes, path)
    }
}

/// Reads several breakline files into one [`Lines`].
///
/// # Errors
/// As [`read_file`], and [`Error::Format`] when two files declare different CRSs.
pub fn read_files<P: AsRef<Path>>(paths: &[P]) -> Result<Lines> {
    let mut all = Lines::default();
    for p in paths {
        all.append(read_file(p.as_ref())?)?;
    }
    Ok(all)
}

// ---------------------------------------------------------------------------------------------
// GeoJSON

/// Every line and ring of a GeoJSON file ([`geojson::parse`]) as a polyline; points are refused.
fn read_geojson(bytes: &[u8], path: Arc<Path>) -> Result<Lines> {
    from_parts(geojson::parse(bytes, &path)?, path)
}

/// The lines and rings of a vector file's parts as polylines; points are refused.
fn from_parts(doc: geojson::GeoJson, path: Arc<Path>) -> Result<Lines> {
    if let Some((feature, kind)) = doc.points.first() {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "feature {feature}: a {kind} is not a line (breaklines are LineString, \
                 MultiLineString, Polygon or MultiPolygon)"
            ),
        });
    }
    let sources = doc
        .parts
        .iter()
        .map(|p| Source {
            path: path.clone(),
            location: Location::Feature {
                index: p.feature,
                part: p.part,
            },
        })
        .collect();
    Ok(Lines {
        polylines: doc.parts.into_iter().map(|p| p.positions).collect(),
        sources,
        crs: doc.crs,
    })
}

// ---------------------------------------------------------------------------------------------
// Text

fn read_text(bytes: &[u8], path: Arc<Path>) -> Result<Lines> {
    let mut lines = Lines::default();
    parse_text(bytes, path, &mut |l, s| {
        lines.polylines.push(l.to_vec());
        lines.sources.push(s.clone());
        Ok(())
    })?;
    Ok(lines)
}

/// The text format read from `reader` (the file `path`), each polyline given to `f` as soon as
/// it ends; only the current polyline and line are held.
fn parse_text(mut reader: impl BufRead, path: Arc<Path>, f: &mut EachLine<'_>) -> Result<()> {
    let mut current: Vec<[f64; 3]> = Vec::new();
    let mut source = Source {
        path,
        location: Location::Line(0),
    };
    let mut flush = |current: &mut Vec<[f64; 3]>, source: &Source| {
        let r = if current.is_empty() {
            Ok(())
        } else {
            f(current, source)
        };
        current.clear();
        r
    };
    let mut buf = Vec::new();
    let mut n = 0u64;
    loop {
        buf.clear();
        if reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| Error::io(source.path.to_path_buf(), e))?
            == 0
        {
            break;
        }
        n += 1;
        let raw = std::str::from_utf8(&buf).map_err(|_| Error::Parse {
            path: source.path.to_path_buf(),
            line: n,
            message: "not UTF-8 text (nor GeoJSON)".into(),
        })?;
        let raw = raw.strip_suffix('\n').unwrap_or(raw);
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        let (content, comment) = match raw.find('#') {
            Some(k) => (&raw[..k], true),
            None => (raw, false),
        };
        if content.trim().is_empty() {
            if !comment {
                flush(&mut current, &source)?;
            }
            continue;
        }
        let v = parse_vertex(content).map_err(|message| Error::Parse {
            path: source.path.to_path_buf(),
            line: n,
            message,
        })?;
        if current.is_empty() {
            source.location = Location::Line(n);
        }
        current.push(v);
    }
    flush(&mut current, &source)
}

/// `x y [z]`, separated by whitespace or commas.
fn parse_vertex(s: &str) -> std::result::Result<[f64; 3], String> {
    let fields: Vec<&str> = s
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|f| !f.is_empty())
        .collect();
    if !(2..=3).contains(&fields.len()) {
        return Err(format!(
            "expected \"x y\" or \"x y z\", found {} value(s): {:?}",
            fields.len(),
            s.trim()
        ));
    }
    let mut v = [f64::NAN; 3];
    for (k, f) in fields.iter().enumerate() {
        let x: f64 = f.parse().map_err(|_| format!("{:?} is not a number", f))?;
        if !x.is_finite() {
            return Err(format!("{:?} is not a finite number", f));
        }
        v[k] = x;
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn file(content: &str, ext: &str) -> tempfile::NamedTempFile {
        let mut f = tempfile::Builder::new().suffix(ext).tempfile().unwrap();
        f.write_all(content.as_bytes()).unwrap();
        f
    }

    fn read(content: &str) -> Result<Lines> {
        let f = file(content, ".geojson");
        read_file(f.path())
    }

    fn xy(l: &[[f64; 3]]) -> Vec<[f64; 2]> {
        l.iter().map(|p| [p[0], p[1]]).collect()
    }

    #[test]
    fn feature_collection_of_every_geometry() {
        let g = r#"{"type": "FeatureCollection",
          "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}},
          "features": [
            {"type": "Feature", "properties": {"a": [1, {"b": 2}]},
             "geometry": {"type": "LineString", "coordinates": [[0, 0, 1.5], [1, 0, 2]]}},
            {"type": "Feature", "properties": null, "geometry": null},
            {"type": "Feature", "geometry": {"type": "MultiLineString",
              "coordinates": [[[0, 1], [1, 1]], [[0, 2], [1, 2], [2, 3]]]}},
            {"type": "Feature", "geometry": {"type": "Polygon",
              "coordinates": [[[0, 0], [4, 0], [4, 4], [0, 4], [0, 0]],
                              [[1, 1], [1, 2], [2, 2]]]}},
            {"type": "Feature", "geometry": {"type": "MultiPolygon",
              "coordinates": [[[[10, 0], [11, 0], [11, 1], [10, 0]]]]}},
            {"type": "Feature", "geometry": {"type": "GeometryCollection", "geometries": [
              {"type": "LineString", "coordinates": [[5, 5, 1, 99], [6, 6, 2, 99]]}]}}
          ]}"#;
        let l = read(g).unwrap();
        assert_eq!(l.crs.as_deref(), Some("EPSG:28992"));
        assert_eq!(l.len(), 7);
        assert_eq!(l.polylines[0], vec![[0., 0., 1.5], [1., 0., 2.]]);
        assert!(l.polylines[1][0][2].is_nan());
        assert_eq!(xy(&l.polylines[2]), vec![[0., 2.], [1., 2.], [2., 3.]]);
        // Outer ring as given, the inner ring closed here.
        assert_eq!(l.polylines[3].len(), 5);
        assert_eq!(
            xy(&l.polylines[4]),
            vec![[1., 1.], [1., 2.], [2., 2.], [1., 1.]]
        );
        assert!(l.is_ring(3) && l.is_ring(4) && l.is_ring(5) && !l.is_ring(0));
        // The measure of the last line is ignored.
        assert_eq!(l.polylines[6], vec![[5., 5., 1.], [6., 6., 2.]]);
        let loc: Vec<Location> = l.sources.iter().map(|s| s.location).collect();
        assert_eq!(loc[0], Location::Feature { index: 0, part: 0 });
        assert_eq!(loc[2], Location::Feature { index: 2, part: 1 });
        assert_eq!(loc[4], Location::Feature { index: 3, part: 1 });
        assert_eq!(loc[6], Location::Feature { index: 5, part: 0 });
        assert_eq!(l.segment_count(), 1 + 1 + 2 + 4 + 3 + 3 + 1);
        l.require_rings().unwrap_err();
    }

    #[test]
    fn lone_feature_and_bare_geometry() {
        let l = read(
            r#"{"type": "Feature", "geometry": {"type": "LineString",
            "coordinates": [[0, 0], [1, 1]]}, "properties": {}}"#,
        )
        .unwrap();
        assert_eq!(l.len(), 1);
        assert_eq!(l.crs, None);
        let l =
            read(r#" {"coordinates": [[0, 0], [1, 1], [2, 0]], "type": "LineString"}"#).unwrap();
        assert_eq!(xy(&l.polylines[0]), vec![[0., 0.], [1., 1.], [2., 0.]]);
    }

    fn error_text(r: Result<Lines>) -> String {
        match r {
            Ok(_) => panic!("expected an error"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn geojson_errors_name_file_and_feature_or_line() {
        let e = error_text(read(
            "{\"type\": \"FeatureCollection\",\n \"features\": [1, 2]}",
        ));
        assert!(e.contains(":2:") && e.contains("not valid GeoJSON"), "{e}");
        let e = error_text(read(
            r#"{"type": "FeatureCollection", "features": [
               {"type": "Feature", "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, 1]]}},
               {"type": "Feature", "geometry": {"type": "Point", "coordinates": [0, 0]}}]}"#,
        ));
        assert!(
            e.contains("feature 1") && e.contains("Point is not a line"),
            "{e}"
        );
        let e = error_text(read(r#"{"type": "LineString", "coordinates": [[0, 0]]}"#));
        assert!(e.contains("at least 2 positions"), "{e}");
        let e = error_text(read(
            r#"{"type": "LineString", "coordinates": [[0], [1, 1]]}"#,
        ));
        assert!(e.contains("position 0") && e.contains("x and y"), "{e}");
        let e = error_text(read(
            r#"{"type": "Polygon", "coordinates": [[[0, 0], [1, 1], [0, 0]]]}"#,
        ));
        assert!(e.contains("at least 3 distinct"), "{e}");
        let e = error_text(read(
            r#"{"type": "Polygon", "coordinates": [[0, 0], [1, 1]]}"#,
        ));
        assert!(e.contains("too shallowly"), "{e}");
        let e = error_text(read(
            r#"{"type": "LineString", "coordinates": [[[0, 0]], [[1, 1]]]}"#,
        ));
        assert!(e.contains("too deeply"), "{e}");
        let e = error_text(read(r#"{"type": "Curve", "coordinates": []}"#));
        assert!(e.contains("unknown geometry type"), "{e}");
        let e = error_text(read(r#"{"type": "FeatureCollection"}"#));
        assert!(e.contains("without \"features\""), "{e}");
        let e = error_text(read(
            r#"{"type": "FeatureCollection", "features": [{"type": "LineString", "coordinates": []}]}"#,
        ));
        assert!(e.contains("expected \"Feature\""), "{e}");
    }

    #[test]
    fn text_format() {
        let t = "# a header\n0 0 1\n1,0,2\n2 1 # trailing comment\n\n\n# comment only\n5 5\n6 6 3\n\
                 # does not end the line\n7 7\n";
        let f = file(t, ".txt");
        let l = read_file(f.path()).unwrap();
        assert_eq!(l.len(), 2);
        assert_eq!(l.polylines[0][..2], [[0., 0., 1.], [1., 0., 2.]]);
        assert!(l.polylines[0][2][2].is_nan());
        assert_eq!(xy(&l.polylines[1]), vec![[5., 5.], [6., 6.], [7., 7.]]);
        assert_eq!(l.sources[0].location, Location::Line(2));
        assert_eq!(l.sources[1].location, Location::Line(8));
        assert!(l.sources[1].to_string().ends_with(":8"));
    }

    #[test]
    fn text_errors_name_the_line() {
        for (t, needle) in [
            ("0 0\n1 1 1 1\n", ":2: expected"),
            ("0 0\n\n1 x\n", ":3: \"x\" is not a number"),
            ("0 inf\n", ":1: \"inf\" is not a finite"),
            ("5\n", "found 1 value"),
        ] {
            let f = file(t, ".txt");
            let e = read_file(f.path()).unwrap_err().to_string();
            assert!(e.contains(needle), "{e} lacks {needle}");
        }
    }

    #[test]
    fn files_append_and_crs_must_agree() {
        let a = file(
            r#"{"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "EPSG:1"}}, "features": []}"#,
            ".json",
        );
        let b = file("0 0\n1 1\n", ".txt");
        let c = file(
            r#"{"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "EPSG:2"}}, "features": []}"#,
            ".json",
        );
        let l = read_files(&[b.path(), a.path()]).unwrap();
        assert_eq!(l.crs.as_deref(), Some("EPSG:1"));
        assert_eq!(l.len(), 1);
        let e = read_files(&[a.path(), c.path()]).unwrap_err().to_string();
        assert!(e.contains("EPSG:2") && e.contains("EPSG:1"), "{e}");
        let e = read_file(Path::new("/nonexistent/lines.geojson")).unwrap_err();
        assert!(matches!(e, Error::Io { .. }));
    }

    #[test]
    fn rings_required() {
        let f = file("0 0\n1 0\n1 1\n0 0\n\n5 5\n6 6\n", ".txt");
        let l = read_file(f.path()).unwrap();
        assert!(l.is_ring(0));
        let e = l.require_rings().unwrap_err().to_string();
        assert!(e.contains(":6") && e.contains("not a closed ring"), "{e}");
    }
}
