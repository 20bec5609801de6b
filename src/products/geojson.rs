//! GeoJSON in and out for the products: a streaming feature writer, and readers for the polygons
//! (volume boundaries) and lines (profiles) users give.
//!
//! Output follows RFC 7946 except that, like GDAL, it records the CRS of projected data in the
//! 2008 `"crs"` member (`urn:ogc:def:crs:EPSG::code`), which GDAL, QGIS and most readers honour.
//! Coordinates are written in the shortest form that reads back as the same `f64`.

use crate::error::{Error, Result};
use crate::io::AtomicFile;
use crate::lidar::Crs;
use serde_json::Value;
use std::io::Write;
use std::path::Path;

/// A GeoJSON `FeatureCollection` written feature by feature.
#[derive(Debug)]
pub struct FeatureWriter {
    file: AtomicFile,
    features: u64,
    points: u64,
    buf: String,
}

/// The `"crs"` member for `crs`, if it has an EPSG code.
pub fn crs_member(crs: Option<&Crs>) -> Option<Value> {
    let (code, _) = crs?.horizontal_epsg()?;
    let name = if code == 4326 {
        "urn:ogc:def:crs:OGC:1.3:CRS84".to_string()
    } else {
        format!("urn:ogc:def:crs:EPSG::{code}")
    };
    Some(serde_json::json!({ "type": "name", "properties": { "name": name } }))
}

impl FeatureWriter {
    /// Starts a collection named `name` at `path` (under a temporary name until `finish`).
    ///
    /// # Errors
    /// [`Error::Io`] naming `path`.
    pub fn create(path: &Path, name: &str, crs: Option<&Crs>) -> Result<FeatureWriter> {
        let mut file = AtomicFile::create(path)?;
        let mut head = format!(
            "{{\"type\":\"FeatureCollection\",\"name\":{}",
            Value::from(name)
        );
        if let Some(c) = crs_member(crs) {
            head.push_str(&format!(",\"crs\":{c}"));
        }
        head.push_str(",\"features\":[\n");
        file.write_all(head.as_bytes()).map_err(|e| file.err(e))?;
        Ok(FeatureWriter {
            file,
            features: 0,
            points: 0,
            buf: String::new(),
        })
    }

    /// Writes one `LineString` feature with `properties` (a JSON object).
    ///
    /// # Errors
    /// [`Error::Io`] naming the output.
    pub fn line_string(
        &mut self,
        properties: &Value,
        points: impl IntoIterator<Item = [f64; 2]>,
    ) -> Result<()> {
        self.start_line(properties)?;
        for p in points {
            self.point(p)?;
        }
        self.end_line()
    }

    /// Starts a `LineString` feature; give its points with [`FeatureWriter::point`] and close it
    /// with [`FeatureWriter::end_line`] (for lines too long to hold in memory).
    ///
    /// # Errors
    /// [`Error::Io`] naming the output.
    pub fn start_line(&mut self, properties: &Value) -> Result<()> {
        if self.features > 0 {
            self.buf.push_str(",\n");
        }
        self.buf.push_str("{\"type\":\"Feature\",\"properties\":");
        self.buf.push_str(&properties.to_string());
        self.buf
            .push_str(",\"geometry\":{\"type\":\"LineString\",\"coordinates\":[");
        self.points = 0;
        Ok(())
    }

    /// One point of the current line.
    ///
    /// # Errors
    /// [`Error::Io`] naming the output.
    pub fn point(&mut self, [x, y]: [f64; 2]) -> Result<()> {
        use std::fmt::Write as _;
        if self.points > 0 {
            self.buf.push(',');
        }
        let _ = write!(self.buf, "[{x},{y}]");
        self.points += 1;
        if self.buf.len() > 1 << 16 {
            self.drain()?;
        }
        Ok(())
    }

    /// Ends the current line.
    ///
    /// # Errors
    /// [`Error::Io`] naming the output.
    pub fn end_line(&mut self) -> Result<()> {
        self.buf.push_str("]}}");
        self.features += 1;
        self.drain()
    }

    fn drain(&mut self) -> Result<()> {
        self.file
            .write_all(self.buf.as_bytes())
            .map_err(|e| self.file.err(e))?;
        self.buf.clear();
        Ok(())
    }

    /// Features written so far.
    pub fn features(&self) -> u64 {
        self.features
    }

    /// Closes the collection and moves the file into place; returns its size in bytes.
    ///
    /// # Errors
    /// [`Error::Io`] naming the output.
    pub fn finish(mut self) -> Result<u64> {
        self.file
            .write_all(b"\n]}\n")
            .map_err(|e| self.file.err(e))?;
        self.file.commit()
    }
}

/// A polygon: its rings (the first is the outer one; holes follow), each a list of `[x, y]`.
pub type Polygon = Vec<Vec<[f64; 2]>>;

fn bad(path: &Path, message: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

fn read_json(path: &Path) -> Result<Value> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_str(&text).map_err(|e| Error::Parse {
        path: path.to_path_buf(),
        line: e.line() as u64,
        message: format!("not valid JSON: {e}"),
    })
}

/// Every geometry in a GeoJSON document (a `FeatureCollection`, a `Feature` or a bare geometry),
/// with a label for messages.
fn geometries(doc: &Value) -> Vec<(String, &Value)> {
    let mut out = Vec::new();
    match doc.get("type").and_then(Value::as_str) {
        Some("FeatureCollection") => {
            for (i, f) in doc
                .get("features")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .enumerate()
            {
                if let Some(g) = f.get("geometry").filter(|g| !g.is_null()) {
                    out.push((format!("feature {i}"), g));
                }
            }
        }
        Some("Feature") => {
            if let Some(g) = doc.get("geometry").filter(|g| !g.is_null()) {
                out.push(("the feature".into(), g));
            }
        }
        Some(_) => out.push(("the geometry".into(), doc)),
        None => {}
    }
    out
}

fn position(path: &Path, what: &str, v: &Value) -> Result<[f64; 2]> {
    let a = v.as_array().filter(|a| a.len() >= 2);
    let xy = a.and_then(|a| Some([a[0].as_f64()?, a[1].as_f64()?]));
    match xy {
        Some(p) if p.iter().all(|c| c.is_finite()) => Ok(p),
        _ => Err(bad(path, format!("{what}: bad position {v}"))),
    }
}

fn positions(path: &Path, what: &str, v: &Value) -> Result<Vec<[f64; 2]>> {
    v.as_array()
        .ok_or_else(|| bad(path, format!("{what}: expected an array of positions")))?
        .iter()
        .map(|p| position(path, what, p))
        .collect()
}

fn polygon(path: &Path, what: &str, v: &Value) -> Result<Polygon> {
    let rings = v
        .as_array()
        .ok_or_else(|| bad(path, format!("{what}: expected an array of rings")))?;
    let mut out = Vec::new();
    for (i, r) in rings.iter().enumerate() {
        let mut ring = positions(path, &format!("{what}, ring {i}"), r)?;
        if ring.len() > 1 && ring.first() == ring.last() {
            ring.pop();
        }
        if ring.len() < 3 {
            return Err(bad(
                path,
                format!("{what}, ring {i}: fewer than 3 distinct positions"),
            ));
        }
        out.push(ring);
    }
    Ok(out)
}

/// The polygons of a GeoJSON file (`Polygon` and `MultiPolygon` geometries, bare or in features).
///
/// # Errors
/// [`Error::Io`], [`Error::Parse`] for bad JSON, [`Error::Format`] for a bad geometry or no
/// polygon at all.
pub fn read_polygons(path: &Path) -> Result<Vec<Polygon>> {
    let doc = read_json(path)?;
    let mut out = Vec::new();
    for (what, g) in geometries(&doc) {
        let coords = g.get("coordinates").unwrap_or(&Value::Null);
        match g.get("type").and_then(Value::as_str) {
            Some("Polygon") => out.push(polygon(path, &what, coords)?),
            Some("MultiPolygon") => {
                for (j, p) in coords.as_array().into_iter().flatten().enumerate() {
                    out.push(polygon(path, &format!("{what}, polygon {j}"), p)?);
                }
            }
            _ => {}
        }
    }
    if out.is_empty() {
        return Err(bad(path, "no Polygon or MultiPolygon geometry found"));
    }
    Ok(out)
}

/// The lines of a GeoJSON file (`LineString` and `MultiLineString` geometries, bare or in
/// features), with `z` dropped.
///
/// # Errors
/// As [`read_polygons`], for lines.
pub fn read_lines(path: &Path) -> Result<Vec<Vec<[f64; 2]>>> {
    let doc = read_json(path)?;
    let mut out = Vec::new();
    for (what, g) in geometries(&doc) {
        let coords = g.get("coordinates").unwrap_or(&Value::Null);
        match g.get("type").and_then(Value::as_str) {
            Some("LineString") => out.push(positions(path, &what, coords)?),
            Some("MultiLineString") => {
                for (j, l) in coords.as_array().into_iter().flatten().enumerate() {
                    out.push(positions(path, &format!("{what}, line {j}"), l)?);
                }
            }
            _ => {}
        }
    }
    out.retain(|l| l.len() >= 2);
    if out.is_empty() {
        return Err(bad(
            path,
            "no LineString or MultiLineString with two or more positions found",
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_a_collection_with_crs_that_parses() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.geojson");
        let crs = Crs {
            epsg: Some(3794),
            ..Crs::default()
        };
        let mut w = FeatureWriter::create(&path, "contours", Some(&crs)).unwrap();
        w.line_string(
            &serde_json::json!({"elevation": 1.5}),
            [[0.0, 0.1], [2.0, 3.0]],
        )
        .unwrap();
        w.line_string(
            &serde_json::json!({"elevation": 2}),
            [[1.0, 1.0], [2.0, 2.0]],
        )
        .unwrap();
        w.finish().unwrap();
        let v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(v["crs"]["properties"]["name"], "urn:ogc:def:crs:EPSG::3794");
        assert_eq!(v["features"].as_array().unwrap().len(), 2);
        assert_eq!(v["features"][0]["geometry"]["coordinates"][0][1], 0.1);
        let lines = read_lines(&path).unwrap();
        assert_eq!(
            lines,
            vec![vec![[0.0, 0.1], [2.0, 3.0]], vec![[1.0, 1.0], [2.0, 2.0]]]
        );
    }

    #[test]
    fn reads_polygons_and_reports_bad_ones() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.geojson");
        std::fs::write(
            &path,
            r#"{"type":"MultiPolygon","coordinates":[[[[0,0],[4,0],[4,4],[0,0]]],
               [[[10,10],[12,10],[12,12],[10,12],[10,10]],[[11,11],[11.5,11],[11.5,11.5]]]]}"#,
        )
        .unwrap();
        let p = read_polygons(&path).unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0][0].len(), 3);
        assert_eq!(p[1].len(), 2);
        std::fs::write(
            &path,
            r#"{"type":"Polygon","coordinates":[[[0,0],[1,"x"],[1,1]]]}"#,
        )
        .unwrap();
        let e = read_polygons(&path).unwrap_err().to_string();
        assert!(e.contains("bad position"), "{e}");
        std::fs::write(&path, r#"{"type":"Point","coordinates":[0,0]}"#).unwrap();
        assert!(read_polygons(&path).is_err());
        std::fs::write(&path, "{").unwrap();
        assert!(matches!(read_polygons(&path), Err(Error::Parse { .. })));
    }
}
