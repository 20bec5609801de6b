//! GeoJSON input: the polygons (volume boundaries) and lines (profiles) users give.

use crate::error::{Error, Result};
use serde_json::Value;
use std::path::Path;

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
