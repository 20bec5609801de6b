//! GeoJSON output: a streaming feature writer (contours, and anything else written as features).
//!
//! Output follows RFC 7946 except that, like GDAL, it records the CRS of projected data in the
//! 2008 `"crs"` member (`urn:ogc:def:crs:EPSG::code`), which GDAL, QGIS and most readers honour.
//! Coordinates are written in the shortest form that reads back as the same `f64`.

use super::atomic::AtomicFile;
use crate::crs::Crs;
use crate::error::Result;
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
    /// [`crate::Error::Write`] naming `path`.
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
    /// [`crate::Error::Write`] naming the output.
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
    /// [`crate::Error::Write`] naming the output.
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
    /// [`crate::Error::Write`] naming the output.
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
    /// [`crate::Error::Write`] naming the output.
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
    /// [`crate::Error::Write`] naming the output.
    pub fn finish(mut self) -> Result<u64> {
        self.file
            .write_all(b"\n]}\n")
            .map_err(|e| self.file.err(e))?;
        self.file.commit()
    }
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
        let lines = crate::input::geojson::read_lines(&path).unwrap();
        assert_eq!(
            lines,
            vec![vec![[0.0, 0.1], [2.0, 3.0]], vec![[1.0, 1.0], [2.0, 2.0]]]
        );
    }
}
