//! GeoJSON input: the one reader of the lines and polygons users give (breaklines, `--boundary`,
//! `--holes`, `--trim-boundary`, the volume's `--boundary`, `profile --line`).
//!
//! [`read`] turns a file into its lines and polygon rings ([`Part`]s), each labelled with its
//! feature and part for messages; the users take the view they need: [`crate::input::lines`]
//! every line and ring (as breaklines), [`read_polygons`] the polygons only, [`read_lines`] the
//! lines only. So every option that takes a GeoJSON file accepts the same files and reports the
//! same errors.
//!
//! # What is read
//!
//! A `FeatureCollection`, a single `Feature` or a bare geometry. Geometries: `LineString`,
//! `MultiLineString`, `Polygon`, `MultiPolygon`, `GeometryCollection` of those, and `Point` /
//! `MultiPoint` (only noted, so that a view can refuse them by name); features whose
//! `geometry` is `null` are skipped. Properties are ignored (and skipped unparsed).
//!
//! Positions with three values have `z`; with two values `z` is unknown and stored as `NaN`; values
//! beyond the third (a measure) are ignored. A line needs at least 2 positions. A polygon ring that
//! does not repeat its first position is closed here (RFC 7946 requires the repetition; some
//! writers omit it), and needs at least 3 distinct positions. The old-style `crs` member (`{"type":
//! "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}}`) is read and reported as
//! `EPSG:28992`.
//!
//! Coordinates are parsed straight into positions by a [`serde`] visitor (no `serde_json::Value`
//! tree): about 40 bytes per position while the file is walked.
//!
//! # Errors
//!
//! Syntax errors name the file and the line ([`Error::Parse`]); a well-formed file with a bad
//! geometry names the file, the feature and the part ([`Error::Format`]).

use crate::error::{Error, Result};
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use std::fmt;
use std::path::Path;

/// A polygon: its rings (the first is the outer one; holes follow), each a list of `[x, y]` that
/// does not repeat its first position.
pub type Polygon = Vec<Vec<[f64; 2]>>;

/// What a GeoJSON file holds: its lines and rings in one flat list (one allocation per part, not
/// per geometry).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GeoJson {
    /// Every line (`LineString`, `MultiLineString`) and every polygon ring (`Polygon`,
    /// `MultiPolygon`) in file order, the members of a `GeometryCollection` one by one.
    pub parts: Vec<Part>,
    /// The `Point` and `MultiPoint` geometries (not kept): feature index and type name.
    pub points: Vec<(u64, &'static str)>,
    /// The coordinate reference system the file declares (`EPSG:xxxx` when recognised), if any.
    pub crs: Option<String>,
}

/// A line, or a ring of a polygon.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// 0-based index of its feature in the collection (0 for a lone feature or geometry).
    pub feature: u64,
    /// 0-based index of the part in its feature: lines and rings are counted across the feature
    /// (a multi-geometry's members and a collection's members one after the other).
    pub part: u32,
    /// For a ring, the number of its polygon in the file (from 0; a polygon's rings are
    /// consecutive, the outer one first); `None` for a line.
    pub polygon: Option<u32>,
    /// The positions, `[x, y, z]` with `z = NaN` where not given. A line has at least 2; a ring
    /// is closed (its last position repeats the first) and has at least 4.
    pub positions: Vec<[f64; 3]>,
}

impl Part {
    /// `feature F part P`, for messages.
    pub fn label(&self) -> String {
        format!("feature {} part {}", self.feature, self.part)
    }
}

/// Reads a GeoJSON file.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Parse`] for a syntax error (file and line);
/// [`Error::Format`] for a bad geometry (file, feature and part).
pub fn read(path: &Path) -> Result<GeoJson> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(&bytes, path)
}

/// Reads any vector file users give: GeoJSON, or GeoPackage / OGR-SQLite / Shapefile through
/// [`crate::input::vector`] (a layer named as `FILE:LAYER`).
///
/// # Errors
/// As [`read`] and [`crate::input::vector::read`].
fn read_any(path: &Path) -> Result<GeoJson> {
    super::vector::read(path)
}

/// Parses the GeoJSON text `bytes` of the file `path` (named in errors).
///
/// # Errors
/// As [`read`].
pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<GeoJson> {
    let root: GeoObject = serde_json::from_slice(bytes).map_err(|e| Error::Parse {
        path: path.to_path_buf(),
        line: e.line() as u64,
        message: format!("not valid GeoJSON: {e}"),
    })?;
    let mut r = Reader {
        path,
        out: GeoJson {
            crs: root.crs.as_ref().and_then(crs_name),
            ..GeoJson::default()
        },
        polygons: 0,
    };
    match root.kind.as_str() {
        "FeatureCollection" => {
            let Some(features) = root.features else {
                return Err(r.format("a FeatureCollection without \"features\"".into()));
            };
            for (i, f) in features.into_iter().enumerate() {
                r.feature(f, i as u64)?;
            }
        }
        "Feature" => r.feature(root, 0)?,
        _ => r.geometry(root, 0, &mut 0)?,
    }
    Ok(r.out)
}

/// The polygons of a GeoJSON file (or GeoPackage, OGR-SQLite, Shapefile): `Polygon` and `MultiPolygon` geometries, and lines that are
/// closed rings (each a polygon of one ring), as `--trim-boundary` reads them; `z` dropped.
///
/// # Errors
/// As [`read`], and [`Error::Format`] for a line that is not a closed ring, a `Point` or
/// `MultiPoint`, or a file without any polygon.
pub fn read_polygons(path: &Path) -> Result<Vec<Polygon>> {
    let doc = read_any(path)?;
    if let Some((feature, kind)) = doc.points.first() {
        return Err(format(
            path,
            format!(
                "feature {feature}: a {kind} is not a polygon (polygons are Polygon, MultiPolygon, \
                 or a LineString that is a closed ring)"
            ),
        ));
    }
    let mut out: Vec<Polygon> = Vec::new();
    let mut last = None;
    for p in &doc.parts {
        match p.polygon {
            Some(k) if last == Some(k) => {
                if let Some(poly) = out.last_mut() {
                    poly.push(open_ring(&p.positions));
                }
            }
            Some(_) => out.push(vec![open_ring(&p.positions)]),
            None if is_ring(&p.positions) => out.push(vec![open_ring(&p.positions)]),
            None => return Err(format(path, not_a_ring(&p.label(), p.positions.len()))),
        }
        last = p.polygon;
    }
    if out.is_empty() {
        return Err(format(
            path,
            "no Polygon or MultiPolygon geometry found (nor a LineString that is a closed ring)",
        ));
    }
    Ok(out)
}

/// The lines of a GeoJSON file (or GeoPackage, OGR-SQLite, Shapefile) (`LineString` and `MultiLineString` geometries; polygons and points
/// are left out), with `z` dropped.
///
/// # Errors
/// As [`read`], and [`Error::Format`] for a file without any line.
pub fn read_lines(path: &Path) -> Result<Vec<Vec<[f64; 2]>>> {
    let out: Vec<_> = read_any(path)?
        .parts
        .iter()
        .filter(|p| p.polygon.is_none())
        .map(|p| xy(&p.positions))
        .collect();
    if out.is_empty() {
        return Err(format(
            path,
            "no LineString or MultiLineString geometry found",
        ));
    }
    Ok(out)
}

/// At least 4 vertices and the last equal in `x, y` to the first.
pub(crate) fn is_ring(p: &[[f64; 3]]) -> bool {
    p.len() >= 4 && p[0][0] == p[p.len() - 1][0] && p[0][1] == p[p.len() - 1][1]
}

/// The message for a line `at` of `vertices` vertices where a closed ring is needed.
pub(crate) fn not_a_ring(at: &str, vertices: usize) -> String {
    format!(
        "{at}: a polygon is needed here, but this line is not a closed ring ({vertices} vertices; \
         a ring has at least 4 and ends where it starts)"
    )
}

fn xy(p: &[[f64; 3]]) -> Vec<[f64; 2]> {
    p.iter().map(|v| [v[0], v[1]]).collect()
}

/// A closed ring without its closing position.
fn open_ring(r: &[[f64; 3]]) -> Vec<[f64; 2]> {
    xy(&r[..r.len() - 1])
}

fn format(path: &Path, message: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

// ---------------------------------------------------------------------------------------------
// Deserialising

/// Any GeoJSON object; the fields that do not apply to its type are absent.
#[derive(Deserialize)]
struct GeoObject {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default)]
    features: Option<Vec<GeoObject>>,
    #[serde(default)]
    geometry: Option<Box<GeoObject>>,
    #[serde(default)]
    geometries: Option<Vec<GeoObject>>,
    #[serde(default)]
    coordinates: Option<Tree>,
    #[serde(default)]
    crs: Option<serde_json::Value>,
}

/// Nested coordinate arrays: a position or a list of deeper arrays.
enum Tree {
    /// A position: up to three values and how many were given.
    Pos([f64; 3], usize),
    List(Vec<Tree>),
}

impl<'de> Deserialize<'de> for Tree {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Tree, D::Error> {
        d.deserialize_seq(TreeVisitor)
    }
}

struct TreeVisitor;

impl<'de> Visitor<'de> for TreeVisitor {
    type Value = Tree;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("an array of coordinates")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Tree, A::Error> {
        match seq.next_element::<Item>()? {
            None => Ok(Tree::List(Vec::new())),
            Some(Item::Num(x)) => {
                let mut p = [x, f64::NAN, f64::NAN];
                let mut n = 1;
                while let Some(Coord(v)) = seq.next_element::<Coord>()? {
                    if n < 3 {
                        p[n] = v;
                    }
                    n += 1;
                }
                Ok(Tree::Pos(p, n))
            }
            Some(Item::Tree(t)) => {
                let mut list = vec![t];
                while let Some(t) = seq.next_element::<Tree>()? {
                    list.push(t);
                }
                Ok(Tree::List(list))
            }
        }
    }
}

/// The first element of a coordinate array: a number (so the array is a position) or an array.
enum Item {
    Num(f64),
    Tree(Tree),
}

impl<'de> Deserialize<'de> for Item {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Item, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Item;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or an array of coordinates (bad position)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Item, E> {
                Ok(Item::Num(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Item, E> {
                Ok(Item::Num(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Item, E> {
                Ok(Item::Num(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> std::result::Result<Item, A::Error> {
                TreeVisitor.visit_seq(seq).map(Item::Tree)
            }
        }
        d.deserialize_any(V)
    }
}

/// A coordinate after the first one of a position (read as `f64`: serde_json's fast path for
/// numbers, measurably quicker than `deserialize_any`).
struct Coord(f64);

impl<'de> Deserialize<'de> for Coord {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Coord, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Coord;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number (bad position)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Coord, E> {
                Ok(Coord(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Coord, E> {
                Ok(Coord(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Coord, E> {
                Ok(Coord(v as f64))
            }
        }
        d.deserialize_f64(V)
    }
}

/// `EPSG:28992` from an old-style GeoJSON `crs` member.
fn crs_name(crs: &serde_json::Value) -> Option<String> {
    let props = crs.get("properties")?;
    match crs.get("type")?.as_str()? {
        "name" => {
            let name = props.get("name")?.as_str()?;
            Some(normalise_crs(name))
        }
        "EPSG" => Some(format!("EPSG:{}", props.get("code")?)),
        _ => None,
    }
}

/// `urn:ogc:def:crs:EPSG::28992` → `EPSG:28992`; `urn:ogc:def:crs:OGC:1.3:CRS84` → `OGC:CRS84`.
fn normalise_crs(name: &str) -> String {
    let lower = name.to_ascii_lowercase();
    if let Some(rest) = lower.strip_prefix("urn:ogc:def:crs:") {
        let parts: Vec<&str> = rest.split(':').collect();
        if let (Some(auth), Some(code)) = (parts.first(), parts.last()) {
            return format!(
                "{}:{}",
                auth.to_ascii_uppercase(),
                code.to_ascii_uppercase()
            );
        }
    }
    name.to_string()
}

// ---------------------------------------------------------------------------------------------
// Walking the objects

struct Reader<'a> {
    path: &'a Path,
    out: GeoJson,
    /// Polygons so far.
    polygons: u32,
}

impl Reader<'_> {
    fn format(&self, message: String) -> Error {
        format(self.path, message)
    }

    fn feature(&mut self, f: GeoObject, index: u64) -> Result<()> {
        if f.kind != "Feature" {
            return Err(self.format(format!(
                "feature {index}: type is \"{}\", expected \"Feature\"",
                f.kind
            )));
        }
        match f.geometry {
            Some(g) => self.geometry(*g, index, &mut 0),
            None => Ok(()),
        }
    }

    /// Geometry `g` of feature `index`, whose parts so far are counted in `part`.
    fn geometry(&mut self, g: GeoObject, index: u64, part: &mut u32) -> Result<()> {
        let kind = match g.kind.as_str() {
            "GeometryCollection" => {
                for sub in g.geometries.unwrap_or_default() {
                    self.geometry(sub, index, part)?;
                }
                return Ok(());
            }
            "Point" | "MultiPoint" => {
                let kind = if g.kind == "Point" {
                    "Point"
                } else {
                    "MultiPoint"
                };
                self.out.points.push((index, kind));
                return Ok(());
            }
            kind @ ("LineString" | "MultiLineString" | "Polygon" | "MultiPolygon") => kind,
            other => {
                return Err(self.format(format!(
                    "feature {index}: unknown geometry type \"{other}\""
                )));
            }
        };
        let Some(tree) = g.coordinates else {
            return Err(self.format(format!("feature {index}: {kind} without \"coordinates\"")));
        };
        let at = At { index, kind };
        match kind {
            "LineString" => self.part(tree, at, part, None),
            "MultiLineString" => {
                for l in self.list(tree, at)? {
                    self.part(l, at, part, None)?;
                }
                Ok(())
            }
            "Polygon" => self.polygon(tree, at, part),
            _ => {
                for p in self.list(tree, at)? {
                    self.polygon(p, at, part)?;
                }
                Ok(())
            }
        }
    }

    /// One level of nesting.
    fn list(&self, tree: Tree, at: At<'_>) -> Result<Vec<Tree>> {
        match tree {
            Tree::List(list) => Ok(list),
            Tree::Pos(..) => Err(self.format(format!(
                "feature {}: {} coordinates are nested too shallowly",
                at.index, at.kind
            ))),
        }
    }

    /// The rings of a polygon.
    fn polygon(&mut self, tree: Tree, at: At<'_>, part: &mut u32) -> Result<()> {
        let rings = self.list(tree, at)?;
        if rings.is_empty() {
            return Ok(());
        }
        let k = self.polygons;
        self.polygons += 1;
        for r in rings {
            self.part(r, at, part, Some(k))?;
        }
        Ok(())
    }

    /// A line, or a ring of polygon `polygon` (closed here), numbered `part` (which moves on).
    fn part(&mut self, tree: Tree, at: At<'_>, part: &mut u32, polygon: Option<u32>) -> Result<()> {
        let list = self.list(tree, at)?;
        let p = *part;
        *part += 1;
        let line = self.positions(list, at, p)?;
        push_part(
            &mut self.out,
            self.path,
            (at.index, p),
            polygon,
            at.kind,
            line,
        )
    }

    fn positions(&self, list: Vec<Tree>, at: At<'_>, part: u32) -> Result<Vec<[f64; 3]>> {
        let (index, kind) = (at.index, at.kind);
        let mut out = Vec::with_capacity(list.len());
        for (k, t) in list.into_iter().enumerate() {
            let Tree::Pos(p, n) = t else {
                return Err(self.format(format!(
                    "feature {index} part {part}: {kind} coordinates are nested too deeply \
                     (position {k} is an array of arrays)"
                )));
            };
            if n < 2 {
                return Err(self.format(format!(
                    "feature {index} part {part}, position {k}: {n} value(s), a position needs \
                     x and y"
                )));
            }
            if !p.iter().take(n.min(3)).all(|v| v.is_finite()) {
                return Err(self.format(format!(
                    "feature {index} part {part}, position {k}: coordinate is not finite"
                )));
            }
            out.push(p);
        }
        Ok(out)
    }
}

/// Adds `line` to `out` as part `at.1` of feature `at.0`: a line (at least 2 positions), or a
/// ring of polygon `polygon`, closed here if it does not repeat its first position (at least 3
/// distinct positions). The rule every vector reader applies ([`crate::input::vector`]).
///
/// # Errors
/// [`Error::Format`] naming `path`, the feature and the part.
pub(crate) fn push_part(
    out: &mut GeoJson,
    path: &Path,
    at: (u64, u32),
    polygon: Option<u32>,
    kind: &str,
    mut line: Vec<[f64; 3]>,
) -> Result<()> {
    let (index, p) = at;
    if polygon.is_some() {
        if let (Some(&first), Some(&last)) = (line.first(), line.last())
            && (first[0] != last[0] || first[1] != last[1])
        {
            line.push(first);
        }
        if line.len() < 4 {
            return Err(format(
                path,
                format!(
                    "feature {index} part {p}: a polygon ring with fewer than 3 distinct \
                     positions ({}); a ring needs at least 3 distinct positions",
                    line.len().saturating_sub(1)
                ),
            ));
        }
    } else if line.len() < 2 {
        return Err(format(
            path,
            format!(
                "feature {index} part {p}: a line needs at least 2 positions, this {kind} has {}",
                line.len()
            ),
        ));
    }
    out.parts.push(Part {
        feature: index,
        part: p,
        polygon,
        positions: line,
    });
    Ok(())
}

/// The feature and geometry type being read, for messages.
#[derive(Clone, Copy)]
struct At<'a> {
    index: u64,
    kind: &'a str,
}

#[cfg(test)]
mod tests;
