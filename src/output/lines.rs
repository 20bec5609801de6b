//! Line features (contour lines) to a file whose extension picks the format: GeoJSON
//! (`.geojson`, `.json`; [`FeatureWriter`]) or GeoPackage (`.gpkg`; [`GpkgWriter`]), with the
//! coordinates rounded to a number of decimals when asked ([`LineWriter::round`]).

use super::geojson::FeatureWriter;
use super::gpkg::GpkgWriter;
use crate::crs::Crs;
use crate::error::{Error, Result};
use serde_json::Value;
use std::path::Path;

/// The format of a line output, from its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineFormat {
    /// GeoJSON (`.geojson`, `.json`).
    GeoJson,
    /// GeoPackage (`.gpkg`).
    GeoPackage,
}

impl LineFormat {
    /// The format `path`'s extension names (any case); GeoJSON without one (a stream, `-`).
    ///
    /// # Errors
    /// [`Error::Options`] naming `path` and the formats there are.
    pub fn of(path: &Path) -> Result<LineFormat> {
        let Some(ext) = path.extension() else {
            return Ok(LineFormat::GeoJson);
        };
        let ext = ext.to_string_lossy().to_ascii_lowercase();
        match ext.as_str() {
            "geojson" | "json" => Ok(LineFormat::GeoJson),
            "gpkg" => Ok(LineFormat::GeoPackage),
            _ => Err(Error::Options(format!(
                "{}: lines are written as GeoJSON (.geojson or .json) or GeoPackage (.gpkg); \
                 convert with ogr2ogr for .{ext}",
                path.display()
            ))),
        }
    }
}

/// Most decimals `--precision` may ask for (beyond 15 a double has no more digits to give).
pub const MAX_DECIMALS: u32 = 15;

/// A line output of either format (see the module docs).
#[derive(Debug)]
pub struct LineWriter {
    out: Out,
    scale: Option<f64>,
}

#[derive(Debug)]
enum Out {
    GeoJson(FeatureWriter),
    Gpkg(Box<GpkgWriter>),
}

impl LineWriter {
    /// Starts a layer `name` at `path` in the format of its extension ([`LineFormat::of`]),
    /// with coordinates rounded to `decimals` when given (at most [`MAX_DECIMALS`]).
    ///
    /// # Errors
    /// [`Error::Options`] for another extension or too many decimals; the writers' errors.
    pub fn create(
        path: &Path,
        name: &str,
        crs: Option<&Crs>,
        decimals: Option<u32>,
    ) -> Result<LineWriter> {
        if let Some(d) = decimals.filter(|&d| d > MAX_DECIMALS) {
            return Err(Error::Options(format!(
                "--precision {d}: at most {MAX_DECIMALS} decimals (a double holds no more)"
            )));
        }
        let out = match LineFormat::of(path)? {
            LineFormat::GeoJson => Out::GeoJson(FeatureWriter::create(path, name, crs)?),
            LineFormat::GeoPackage => Out::Gpkg(Box::new(GpkgWriter::create(path, name, crs)?)),
        };
        Ok(LineWriter {
            out,
            scale: decimals.map(|d| 10f64.powi(d as i32)),
        })
    }

    /// `p` rounded to the writer's decimals (unchanged without): the double nearest the
    /// rounded decimal, which GeoJSON then prints in that many decimals or fewer.
    pub fn round(&self, p: [f64; 2]) -> [f64; 2] {
        match self.scale {
            Some(s) => p.map(|v| {
                let r = (v * s).round() / s;
                // Beyond 2^53 / s the value has no such decimals to drop.
                if r.is_finite() { r + 0.0 } else { v }
            }),
            None => p,
        }
    }

    /// Starts a line of `points` points within `bbox` (`[xmin, ymin, xmax, ymax]`) with
    /// `properties` (a JSON object; a GeoPackage keeps its `elevation` and `closed`). Give the
    /// points with [`LineWriter::point`] (as they are to be written: round them first) and close
    /// the line with [`LineWriter::end_line`].
    ///
    /// # Errors
    /// The writer's, naming the output.
    pub fn start_line(&mut self, properties: &Value, points: u64, bbox: [f64; 4]) -> Result<()> {
        match &mut self.out {
            Out::GeoJson(w) => w.start_line(properties),
            Out::Gpkg(w) => w.start_line(
                properties["elevation"].as_f64().unwrap_or(f64::NAN),
                properties["closed"].as_bool().unwrap_or(false),
                points,
                bbox,
            ),
        }
    }

    /// One point of the current line.
    ///
    /// # Errors
    /// The writer's, naming the output.
    pub fn point(&mut self, p: [f64; 2]) -> Result<()> {
        match &mut self.out {
            Out::GeoJson(w) => w.point(p),
            Out::Gpkg(w) => w.point(p),
        }
    }

    /// Ends the current line.
    ///
    /// # Errors
    /// The writer's, naming the output.
    pub fn end_line(&mut self) -> Result<()> {
        match &mut self.out {
            Out::GeoJson(w) => w.end_line(),
            Out::Gpkg(w) => w.end_line(),
        }
    }

    /// One whole line of points as they are to be written.
    ///
    /// # Errors
    /// The writer's, naming the output.
    pub fn line_string(&mut self, properties: &Value, points: &[[f64; 2]]) -> Result<()> {
        let bbox = points.iter().fold(
            [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, p| {
                [
                    b[0].min(p[0]),
                    b[1].min(p[1]),
                    b[2].max(p[0]),
                    b[3].max(p[1]),
                ]
            },
        );
        self.start_line(properties, points.len() as u64, bbox)?;
        for &p in points {
            self.point(p)?;
        }
        self.end_line()
    }

    /// Features written so far.
    pub fn features(&self) -> u64 {
        match &self.out {
            Out::GeoJson(w) => w.features(),
            Out::Gpkg(w) => w.features(),
        }
    }

    /// Closes the layer and moves the file into place; returns its size in bytes.
    ///
    /// # Errors
    /// The writer's, naming the output.
    pub fn finish(self) -> Result<u64> {
        match self.out {
            Out::GeoJson(w) => w.finish(),
            Out::Gpkg(w) => w.finish(),
        }
    }
}

/// The length of a polyline (the sum of its segments' lengths).
pub fn length(points: &[[f64; 2]]) -> f64 {
    points
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_to_the_decimals_and_prints_them_short() {
        let dir = tempfile::tempdir().unwrap();
        let w = LineWriter::create(&dir.path().join("a.geojson"), "c", None, Some(2)).unwrap();
        assert_eq!(w.round([511_000.123_456, 0.1 + 0.2]), [511_000.12, 0.3]);
        assert_eq!(format!("{}", w.round([12.345_678, -0.001])[0]), "12.35");
        assert_eq!(w.round([-0.001, 1.0])[0].to_string(), "0");
        let e = LineWriter::create(&dir.path().join("a.shp"), "c", None, None).unwrap_err();
        assert!(e.to_string().contains(".gpkg"), "{e}");
        let e = LineWriter::create(&dir.path().join("b.json"), "c", None, Some(16)).unwrap_err();
        assert!(e.to_string().contains("at most 15"), "{e}");
    }
}
