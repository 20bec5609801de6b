//! Contour lines across tasks: every task writes the contours of the triangles it owns, so a line
//! that passes from triangles of one task to those of another ends in one task's file and goes on
//! in the other's, from the same triangle edge. The tasks write the edges their open lines start
//! and end on (`start_edge`, `end_edge`), and joining each line to the one starting on the edge it
//! ends on gives the polylines of one run over all the points (that run joins its segments by
//! the same edges). Coordinates are rounded to the job's decimals, repeated points dropped and
//! degenerate lines and those shorter than the job's minimum length left out after joining, as
//! one run does.

use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::output::lines::{LineWriter, length};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

type Pt = [f64; 2];
type Key = (u64, [u64; 4]);

/// The key of an end of a line: the edge it lies on, or (from a file without edges) its point.
fn key(level: f64, edge: &Value, p: Option<&Pt>) -> Option<Key> {
    let bits = |v: &Value| v.as_f64().map(f64::to_bits);
    if let Some(e) = edge.as_array().filter(|e| e.len() == 4) {
        let mut k = [0u64; 4];
        for (slot, v) in k.iter_mut().zip(e) {
            *slot = bits(v)?;
        }
        return Some((level.to_bits(), k));
    }
    p.map(|p| (level.to_bits(), [p[0].to_bits(), p[1].to_bits(), 0, 0]))
}

/// An open contour line of one task.
struct Open {
    level: f64,
    points: Vec<Pt>,
    start: Option<Key>,
    end: Option<Key>,
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
    /// Lines left out as shorter than the minimum length.
    pub short_dropped: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// How the stitched lines are written: decimals of their coordinates (`None`: every bit) and
/// the shortest line kept.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StitchOptions {
    /// Decimals of the written coordinates.
    pub decimals: Option<u32>,
    /// Lines (rings included) shorter than this are left out.
    pub min_length: f64,
}

fn bad(path: &Path, m: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: m.into(),
    }
}

/// Stitches the contour files `parts` (in task order) into `out` (GeoJSON or GeoPackage, by
/// its extension).
///
/// # Errors
/// Reading or writing; [`Error::Format`] for a file that is not a contour output;
/// [`Error::Options`] for an output of another format.
pub fn stitch(
    parts: &[&Path],
    out: &Path,
    crs: Option<&Crs>,
    options: StitchOptions,
) -> Result<StitchSummary> {
    let mut w = LineWriter::create(out, "contours", crs, options.decimals)?;
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
                .map(|p| {
                    [
                        p[0].as_f64().unwrap_or(f64::NAN),
                        p[1].as_f64().unwrap_or(f64::NAN),
                    ]
                })
                .collect();
            let closed = f["properties"]["closed"].as_bool().unwrap_or(false);
            if closed {
                let mut ring: Vec<Pt> = Vec::with_capacity(pts.len());
                for q in pts.iter().map(|&q| w.round(q)) {
                    if ring.last() != Some(&q) {
                        ring.push(q);
                    }
                }
                if ring.len() < 4 {
                    continue;
                }
                if length(&ring) < options.min_length {
                    s.short_dropped += 1;
                    continue;
                }
                w.line_string(
                    &serde_json::json!({"elevation": level, "closed": true}),
                    &ring,
                )?;
                s.features += 1;
                s.rings += 1;
            } else {
                let p = &f["properties"];
                let start = key(level, &p["start_edge"], pts.first());
                let end = key(level, &p["end_edge"], pts.last());
                open.push(Open {
                    level,
                    points: pts,
                    start,
                    end,
                });
            }
        }
    }
    // Join ends to starts.
    let mut by_start: HashMap<Key, usize> = HashMap::with_capacity(open.len());
    for (i, l) in open.iter().enumerate() {
        if let Some(k) = l.start {
            by_start.insert(k, i);
        }
    }
    let next: Vec<Option<usize>> = open
        .iter()
        .map(|l| l.end.and_then(|k| by_start.get(&k).copied()))
        .collect();
    let mut has_prev = vec![false; open.len()];
    for j in next.iter().flatten() {
        has_prev[*j] = true;
    }
    let mut used = vec![false; open.len()];
    let mut emit = |start: usize, used: &mut Vec<bool>, w: &mut LineWriter| -> Result<()> {
        let level = open[start].level;
        let mut pts: Vec<Pt> = Vec::new();
        let mut i = start;
        let mut closed = false;
        loop {
            used[i] = true;
            if !pts.is_empty() {
                s.joins += 1;
            }
            for q in open[i].points.iter().map(|&q| w.round(q)) {
                if pts.last() != Some(&q) {
                    pts.push(q);
                }
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
        // As one run: a ring of fewer than 4 points, or a line of fewer than 2, is left out.
        if pts.len() < if closed { 4 } else { 2 } {
            return Ok(());
        }
        if length(&pts) < options.min_length {
            s.short_dropped += 1;
            return Ok(());
        }
        s.features += 1;
        if closed {
            s.rings += 1;
        }
        w.line_string(
            &serde_json::json!({"elevation": level, "closed": closed}),
            &pts,
        )
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
    s.bytes = w.finish()?;
    Ok(s)
}
