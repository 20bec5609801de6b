//! Terrain products computed from the stream of final triangles, each a
//! [`TriangleSink`], so that several run in one pass with bounded
//! memory:
//!
//! - [`dem`]: DEM rasters (float32 GeoTIFF, ESRI ASCII grid) by linear interpolation at cell
//!   centres.
//! - [`contours`]: contour lines stitched into polylines across the stream (GeoJSON).
//! - [`volume`]: cut and fill volumes and areas against a plane, within an optional
//!   [`boundary`] polygon; [`overlay`]: the same against a second surface.
//! - [`sample`]: heights at query points; [`profile`]: sections along polylines.
//! - [`hillshade`]: a shaded-relief PNG of a DEM GeoTIFF (not a sink: it reads a raster).
//!
//! Every product handles triangles in any order: the watermark is only used to release memory,
//! and a late triangle (below the watermark) is still taken into account exactly. Shared geometry
//! (exact point location, interpolation that is the same from every triangle, the ownership rule
//! for points on edges, exact sums) is in [`geom`].

pub mod boundary;
pub mod contours;
pub mod dem;

pub mod geom;
pub mod hillshade;
pub mod overlay;
pub mod profile;
pub mod sample;
pub mod volume;

#[cfg(test)]
pub(crate) mod testutil;

use crate::crs::Crs;
use crate::error::Result;
use crate::sink::{StreamInfo, TriangleSink};

/// Several products fed by one pass: forwards the stream to every sink, after assigning a CRS
/// (when given) and dropping triangles with an edge longer than `max_edge` (when given; their
/// area is then outside the TIN for every product, e.g. nodata in a DEM).
///
/// [`TriangleSink::finish`] returns an object with each sink's summary under its name (and
/// `trimmed_triangles`); calling it again returns the same object.
pub struct Fanout {
    sinks: Vec<(String, Box<dyn TriangleSink>)>,
    crs: Option<Crs>,
    max_edge: Option<f64>,
    trimmed: u64,
    summary: Option<serde_json::Value>,
}

impl Fanout {
    /// Forwards to `sinks` (name, sink).
    pub fn new(sinks: Vec<(String, Box<dyn TriangleSink>)>) -> Fanout {
        Fanout {
            sinks,
            crs: None,
            max_edge: None,
            trimmed: 0,
            summary: None,
        }
    }

    /// Products say that the data are in `crs`, whatever the input declares.
    pub fn with_crs(mut self, crs: Option<Crs>) -> Fanout {
        self.crs = crs;
        self
    }

    /// Triangles with a horizontal edge longer than `max_edge` are left out.
    pub fn with_max_edge(mut self, max_edge: Option<f64>) -> Fanout {
        self.max_edge = max_edge;
        self
    }
}

impl TriangleSink for Fanout {
    fn begin(&mut self, info: &StreamInfo) -> Result<()> {
        let mut info = info.clone();
        if self.crs.is_some() {
            info.crs = self.crs.clone();
        }
        for (_, s) in &mut self.sinks {
            s.begin(&info)?;
        }
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        if let Some(limit) = self.max_edge {
            let too_long = (0..3).any(|i| {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                (b[0] - a[0]).hypot(b[1] - a[1]) > limit
            });
            if too_long {
                self.trimmed += 1;
                return Ok(());
            }
        }
        for (_, s) in &mut self.sinks {
            s.triangle(t)?;
        }
        Ok(())
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        for (_, s) in &mut self.sinks {
            s.watermark(y)?;
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<serde_json::Value> {
        if let Some(v) = &self.summary {
            return Ok(v.clone());
        }
        let mut m = serde_json::Map::new();
        for (name, s) in &mut self.sinks {
            m.insert(name.clone(), s.finish()?);
        }
        m.insert("trimmed_triangles".into(), self.trimmed.into());
        let v = serde_json::Value::Object(m);
        self.summary = Some(v.clone());
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// Records what it is given.
    #[derive(Default)]
    struct Probe {
        crs: Option<Crs>,
        triangles: u64,
        watermarks: u64,
    }

    impl TriangleSink for Probe {
        fn begin(&mut self, info: &StreamInfo) -> Result<()> {
            self.crs = info.crs.clone();
            Ok(())
        }
        fn triangle(&mut self, _t: &[[f64; 3]; 3]) -> Result<()> {
            self.triangles += 1;
            Ok(())
        }
        fn watermark(&mut self, _y: f64) -> Result<()> {
            self.watermarks += 1;
            Ok(())
        }
        fn finish(&mut self) -> Result<serde_json::Value> {
            Ok(
                json!({ "crs": self.crs.as_ref().and_then(Crs::definition), "triangles": self.triangles, "watermarks": self.watermarks }),
            )
        }
    }

    #[test]
    fn fanout_assigns_crs_trims_long_edges_and_finishes_once() {
        let crs = Crs {
            epsg: Some(3794),
            ..Crs::default()
        };
        let mut f = Fanout::new(vec![
            ("a".into(), Box::new(Probe::default())),
            ("b".into(), Box::new(Probe::default())),
        ])
        .with_crs(Some(crs))
        .with_max_edge(Some(2.0));
        f.begin(&StreamInfo::default()).unwrap();
        f.triangle(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            .unwrap();
        f.triangle(&[[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            .unwrap();
        f.watermark(1.0).unwrap();
        let s = f.finish().unwrap();
        assert_eq!(
            s["a"],
            json!({"crs": "EPSG:3794", "triangles": 1, "watermarks": 1})
        );
        assert_eq!(s["b"]["triangles"], 1);
        assert_eq!(s["trimmed_triangles"], 1);
        assert_eq!(f.finish().unwrap(), s);
    }
}
