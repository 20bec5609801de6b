//! Contour lines across tile edges: every task writes the contours of the triangles it owns, so a
//! line that crosses a tile edge ends there in one task's file and goes on in another's, from the
//! same point (the crossing of the same triangle edge, computed the same way). Joining lines whose
//! end is another's start gives the polylines of one run over all the points.

use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::output::geojson::FeatureWriter;
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

type Pt = [f64; 2];
type Key = (u64, u64, u64);

fn key(level: f64, p: &Pt) -> Key {
    (level.to_bits(), p[0].to_bits(), p[1].to_bits())
}

/// An open contour line of one task.
struct Open {
    level: f64,
    points: Vec<Pt>,
}

/// What stitching wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct StitchSummary {
    /// Features written.
    pub features: u64,
    /// Closed rings among them.
    pub rings: u64,
    /// Pieces of lines joined across tile edges.
    pub joins: u64,
}

fn bad(path: &Path, m: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: m.into(),
    }
}

/// Stitches the contour files `parts` (in task order) into `out`.
///
/// # Errors
/// Reading or writing; [`Error::Format`] for a file that is not a contour output.
pub fn stitch(parts: &[&Path], out: &Path, crs: Option<&Crs>) -> Result<StitchSummary> {
    let mut w = FeatureWriter::create(out, "contours", crs)?;
    let mut s = StitchSummary::default();
    let mut open: Vec<Open> = Vec::new();
    for path in parts {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(*path, e))?;
        let doc: Value =
            serde_json::from_str(&text).map_err(|e| bad(path, format!("not GeoJSON: {e}")))?;
        let features = doc["features"]
            .as_array()
            .ok_or_else(|| bad(path, "no features"))?;
        for f in features {
            let level = f["properties"]["elevation"]
                .as_f64()
                .ok_or_else(|| bad(path, "a feature without elevation"))?;
            let pts: Vec<Pt> = f["geometry"]["coordinates"]
                .as_array()
                .ok_or_else(|| bad(path, "a feature without coordinates"))?
                .iter()
                .map(|p| [p[0].as_f64().unwrap_or(f64::NAN), p[1].as_f64().unwrap_or(f64::NAN)])
                .collect();
            if pts.len() > 1 && pts.first() == pts.last() {
                w.line_string(&serde_json::json!({"elevation": level, "closed": true}), pts)?;
                s.features += 1;
                s.rings += 1;
            } else {
                open.push(Open { level, points: pts });
            }
        }
    }
    // Join ends to starts.
    let mut by_start: HashMap<Key, usize> = HashMap::with_capacity(open.len());
    for (i, l) in open.iter().enumerate() {
        if let Some(p) = l.points.first() {
            by_start.insert(key(l.level, p), i);
        }
    }
    let next: Vec<Option<usize>> = open
        .iter()
        .enumerate()
        .map(|(i, l)| {
            l.points
                .last()
                .and_then(|p| by_start.get(&key(l.level, p)).copied())
                .filter(|&j| j != i)
        })
        .collect();
    let mut has_prev = vec![false; open.len()];
    for j in next.iter().flatten() {
        has_prev[*j] = true;
    }
    let mut used = vec![false; open.len()];
    let mut emit = |start: usize, used: &mut Vec<bool>, w: &mut FeatureWriter| -> Result<()> {
        let level = open[start].level;
        let mut pts: Vec<Pt> = Vec::new();
        let mut i = start;
        let mut closed = false;
        loop {
            used[i] = true;
            let p = &open[i].points;
            if pts.is_empty() {
                pts.extend_from_slice(p);
            } else {
                pts.extend_from_slice(&p[1..]);
                s.joins += 1;
            }
            match next[i] {
                Some(j) if j == start => {
                    closed = true;
                    break;
                }
                Some(j) if !used[j] => i = j,
                _ => break,
            }
        }
        s.features += 1;
        if closed {
            s.rings += 1;
        }
        w.line_string(&serde_json::json!({"elevation": level, "closed": closed}), pts)
    };
    for i in 0..open.len() {
        if !has_prev[i] && !used[i] {
            emit(i, &mut used, &mut w)?;
        }
    }
    // What is left are cycles: rings cut by tile edges.
    for i in 0..open.len() {
        if !used[i] {
            emit(i, &mut used, &mut w)?;
        }
    }
    w.finish()?;
    Ok(s)
}
