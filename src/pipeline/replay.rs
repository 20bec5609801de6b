//! A streaming mesh (`.stin`) as input: replay it into the sinks with bounded memory, without
//! triangulating again.

use super::{RunConfig, RunSummary, StreamInfo, TriangleSink, peak_rss};
use crate::crs::Crs;
use crate::error::Result;
use crate::input::stin::{StinEvent, StinReader};
use crate::sink::MeshSink;
use std::time::Instant;

/// A CRS from the text a streaming mesh records (`EPSG:n` or WKT).
fn crs_from_text(t: &str) -> Option<Crs> {
    // "EPSG:h+v" keeps its vertical part (it came back as "EPSG:h").
    if t.trim().to_ascii_uppercase().starts_with("EPSG:") {
        return Crs::parse(t).ok();
    }
    Crs::from_wkt_bytes(t.as_bytes())
}

/// Replays the one streaming mesh of `config` (checked by [`RunConfig::new`]).
pub(crate) fn replay(
    config: &RunConfig,
    mut mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<RunSummary> {
    let start = Instant::now();
    let path = &config.input().paths[0];
    // First pass over the header only for the CRS; bounds are not recorded, so sinks get the
    // extent from a quick pre-scan of the vertices (bounded memory, one extra sequential read).
    let mut bounds = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut pre = StinReader::open(path)?;
    let crs = pre.crs().and_then(crs_from_text);
    if let Some(m) = mesh.as_mut() {
        m.declare(pre.kind())?;
    }
    while let Some(ev) = pre.next()? {
        if let StinEvent::Vertex(p) = ev {
            bounds[0] = bounds[0].min(p[0]);
            bounds[1] = bounds[1].min(p[1]);
            bounds[2] = bounds[2].max(p[0]);
            bounds[3] = bounds[3].max(p[1]);
        }
    }
    let info = StreamInfo {
        crs: crs.clone(),
        bounds,
    };
    for s in sinks.iter_mut() {
        s.begin(&info)?;
    }
    let mut r = StinReader::open(path)?;
    let (mut vertices, mut triangles) = (0u64, 0u64);
    while let Some(ev) = r.next()? {
        match ev {
            StinEvent::Vertex(p) => {
                if let Some(m) = mesh.as_mut() {
                    m.vertex(p)?;
                }
                vertices += 1;
            }
            StinEvent::Triangle { ids, points } => {
                if let Some(m) = mesh.as_mut() {
                    m.triangle(ids)?;
                }
                for s in sinks.iter_mut() {
                    s.triangle(&points)?;
                }
                triangles += 1;
            }
            StinEvent::VertexDone(id) => {
                if let Some(m) = mesh.as_mut() {
                    m.vertex_done(id)?;
                }
            }
            StinEvent::Watermark(y) => {
                if let Some(m) = mesh.as_mut() {
                    m.watermark(y)?;
                }
                for s in sinks.iter_mut() {
                    s.watermark(y)?;
                }
            }
        }
    }
    let mut products = Vec::new();
    for s in sinks.iter_mut() {
        products.push(s.finish()?);
    }
    let mut summary = RunSummary {
        points_read: vertices,
        points_kept: vertices,
        triangles,
        vertices,
        peak_rss_bytes: peak_rss(),
        products,
        crs: crs.and_then(|c| c.definition()),
        ..RunSummary::default()
    };
    summary.seconds.triangulate_write = start.elapsed().as_secs_f64();
    Ok(summary)
}
