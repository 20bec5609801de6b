//! Streaming LandXML 1.2 TIN surface writer (what Civil 3D, Novapoint and other civil tools
//! import).
//!
//! ```xml
//! <LandXML xmlns="http://www.landxml.org/schema/LandXML-1.2" version="1.2" date=… time=…>
//!   <Units><Metric linearUnit="meter" …/></Units>
//!   <CoordinateSystem epsgCode="3794"/>          (or ogcWktCode="…"; only with a CRS)
//!   <Application name="sweeptin" version="…"/>
//!   <Surfaces><Surface name="STEM"><Definition surfType="TIN">
//!     <Pnts><P id="1">NORTHING EASTING ELEVATION</P>…</Pnts>
//!     <Faces><F>1 2 3</F>…</Faces>
//!   </Definition></Surface></Surfaces>
//! </LandXML>
//! ```
//!
//! **Coordinate order.** LandXML writes every point as "northing easting elevation", that is
//! `y x z` (LandXML 1.2 schema: `PointType` is "north east elev"; Autodesk's Civil 3D LandXML
//! notes: "all coordinate locations are always treated as Northing, Easting, Elevation (or Y, X,
//! Z)"). This writer follows that: `<P>` holds `y x z`.
//!
//! Point ids are 1-based vertex numbers; a face lists the ids of its three points in the order
//! given to [`MeshSink::triangle`] (counter-clockwise seen from above in `x, y`). Units are
//! the CRS's: metres, or feet / US survey feet as `<Imperial>`. Comments from [`MeshMeta`] become XML comments.
//!
//! `<Pnts>` must precede `<Faces>`, so faces are spooled (binary, 24 bytes each) to an anonymous
//! temporary file and appended at [`finish`](MeshSink::finish); vertices are written straight
//! away. Memory use is bounded by the I/O buffers.

use super::atomic::AtomicFile;
use super::mesh::{
    MeshMeta, SinkState, SpooledOutput, face_record, one_line, read_face_record, rewind_spool,
};
use crate::error::Result;
use crate::sink::{MeshSink, MeshSummary};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// A [`MeshSink`] writing a LandXML 1.2 TIN surface.
#[derive(Debug)]
pub struct LandXmlWriter {
    state: SinkState,
    out: Option<AtomicFile>,
    faces: Option<BufWriter<File>>,
    line: Vec<u8>,
}

impl LandXmlWriter {
    /// Starts writing `path`; the surface is named after the file stem; faces are spooled to the
    /// output's directory.
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming `path` if the output or the spool file cannot be created.
    pub fn create(path: &Path, meta: &MeshMeta) -> Result<Self> {
        Self::create_with_spool_dir(path, meta, &super::target::scratch_dir(path))
    }

    /// Like [`create`](Self::create), with the face spool file in `spool_dir`.
    ///
    /// # Errors
    /// [`crate::Error::Write`] if the output or the spool file cannot be created.
    pub fn create_with_spool_dir(path: &Path, meta: &MeshMeta, spool_dir: &Path) -> Result<Self> {
        let SpooledOutput {
            state,
            mut out,
            faces,
        } = SpooledOutput::create(path, spool_dir)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "TIN".into());
        let head = prologue(&name, meta, utc_now());
        out.write_all(head.as_bytes()).map_err(|e| state.io(e))?;
        Ok(LandXmlWriter {
            state,
            out: Some(out),
            faces: Some(faces),
            line: Vec::with_capacity(128),
        })
    }

    fn finish_inner(&mut self) -> Result<MeshSummary> {
        self.state.finish()?;
        let (Some(mut out), Some(faces)) = (self.out.take(), self.faces.take()) else {
            return Err(self.state.error("the mesh writer was already finished"));
        };
        let mut reader = rewind_spool(&self.state, faces)?;
        let io = |e| self.state.io(e);
        out.write_all(b"</Pnts>\n<Faces>\n").map_err(io)?;
        let mut digits = itoa::Buffer::new();
        for _ in 0..self.state.triangles {
            let face = read_face_record(&mut reader).map_err(io)?;
            self.line.clear();
            self.line.extend_from_slice(b"<F>");
            for (k, v) in face.into_iter().enumerate() {
                if k > 0 {
                    self.line.push(b' ');
                }
                self.line.extend_from_slice(digits.format(v + 1).as_bytes());
            }
            self.line.extend_from_slice(b"</F>\n");
            out.write_all(&self.line).map_err(io)?;
        }
        out.write_all(EPILOGUE.as_bytes()).map_err(io)?;
        let bytes = out.commit()?;
        Ok(self.state.summary(bytes))
    }
}

const EPILOGUE: &str = "</Faces>\n</Definition>\n</Surface>\n</Surfaces>\n</LandXML>\n";

impl MeshSink for LandXmlWriter {
    fn vertex(&mut self, p: [f64; 3]) -> Result<()> {
        self.state.vertex(p)?;
        self.line.clear();
        // Writing into a Vec cannot fail. LandXML order: northing (y), easting (x), elevation.
        let _ = writeln!(
            self.line,
            "<P id=\"{}\">{} {} {}</P>",
            self.state.vertices, p[1], p[0], p[2]
        );
        self.state.put(self.out.as_mut(), &self.line)
    }

    fn triangle(&mut self, t: [u64; 3]) -> Result<()> {
        self.state.triangle(t, u64::MAX - 1)?;
        self.state.put(self.faces.as_mut(), &face_record(t))
    }

    fn finish(&mut self) -> Result<MeshSummary> {
        let result = self.finish_inner();
        self.out = None;
        self.faces = None;
        result
    }
}

/// The `<Units>` element: `Imperial` with `linearUnit="foot"` or `"USSurveyFoot"` (LandXML 1.2's
/// names) when the CRS counts in feet — its WKT's unit, a GeoTIFF unit key, or the unit of its
/// EPSG code ([`crate::crs::Crs::length_unit`]) —, `Metric` otherwise.
fn units(meta: &MeshMeta) -> String {
    use crate::crs::{Crs, LengthUnit};
    let unit = meta
        .crs
        .as_deref()
        .and_then(|c| Crs::parse(c).ok())
        .and_then(|c| c.length_unit());
    let feet = match unit {
        Some(LengthUnit::Foot) => "foot",
        Some(LengthUnit::UsSurveyFoot) => "USSurveyFoot",
        _ => {
            return "<Units><Metric areaUnit=\"squareMeter\" linearUnit=\"meter\" \
                    volumeUnit=\"cubicMeter\" temperatureUnit=\"celsius\" \
                    pressureUnit=\"milliBars\" diameterUnit=\"millimeter\" \
                    angularUnit=\"decimal degrees\" directionUnit=\"decimal degrees\"/></Units>\n"
                .into();
        }
    };
    format!(
        "<Units><Imperial areaUnit=\"squareFoot\" linearUnit=\"{feet}\" volumeUnit=\"cubicFeet\" \
         temperatureUnit=\"fahrenheit\" pressureUnit=\"inHG\" diameterUnit=\"inch\" \
         angularUnit=\"decimal degrees\" directionUnit=\"decimal degrees\"/></Units>\n"
    )
}

/// Everything up to and including `<Pnts>`.
fn prologue(surface: &str, meta: &MeshMeta, (date, time): (String, String)) -> String {
    let mut s = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    s.push_str(&format!(
        "<LandXML xmlns=\"http://www.landxml.org/schema/LandXML-1.2\" \
         xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
         xsi:schemaLocation=\"http://www.landxml.org/schema/LandXML-1.2 \
         http://www.landxml.org/schema/LandXML-1.2/LandXML-1.2.xsd\" \
         date=\"{date}\" time=\"{time}\" version=\"1.2\" language=\"English\" readOnly=\"false\">\n"
    ));
    for c in meta.comment_lines() {
        s.push_str(&format!("<!-- {} -->\n", xml_comment(&c)));
    }
    s.push_str(&units(meta));
    if let Some(code) = meta.epsg_code() {
        s.push_str(&format!(
            "<CoordinateSystem name=\"EPSG:{code}\" epsgCode=\"{code}\"/>\n"
        ));
    } else if let Some(crs) = &meta.crs {
        s.push_str(&format!(
            "<CoordinateSystem ogcWktCode=\"{}\"/>\n",
            super::escape_markup(&one_line(crs))
        ));
    }
    s.push_str(&format!(
        "<Application name=\"sweeptin\" manufacturer=\"sweeptin\" version=\"{}\"/>\n",
        env!("CARGO_PKG_VERSION")
    ));
    s.push_str(&format!(
        "<Surfaces>\n<Surface name=\"{}\">\n<Definition surfType=\"TIN\">\n<Pnts>\n",
        super::escape_markup(surface)
    ));
    s
}

/// Text safe inside `<!-- … -->`: no `--`, and not ending in `-`.
fn xml_comment(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c == '-' && out.ends_with('-') {
            out.push(' ');
        }
        out.push(if (c as u32) < 0x20 { ' ' } else { c });
    }
    if out.ends_with('-') {
        out.push(' ');
    }
    out
}

/// Current UTC date (`YYYY-MM-DD`) and time (`HH:MM:SS`).
fn utc_now() -> (String, String) {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_from_unix(secs)
}

/// Date and time of a Unix timestamp (proleptic Gregorian calendar, UTC).
fn utc_from_unix(secs: u64) -> (String, String) {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    // Days to civil date (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    (
        format!("{year:04}-{month:02}-{day:02}"),
        format!("{:02}:{:02}:{:02}", rem / 3600, rem / 60 % 60, rem % 60),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates() {
        assert_eq!(utc_from_unix(0), ("1970-01-01".into(), "00:00:00".into()));
        assert_eq!(
            utc_from_unix(951_782_400 + 3661),
            ("2000-02-29".into(), "01:01:01".into())
        );
        assert_eq!(
            utc_from_unix(1_798_761_599),
            ("2026-12-31".into(), "23:59:59".into())
        );
    }

    #[test]
    fn escaping() {
        assert_eq!(
            crate::output::escape_markup("a<b>&\"c'"),
            "a&lt;b&gt;&amp;&quot;c&#39;"
        );
        assert_eq!(xml_comment("a--b-"), "a- -b- ");
        assert_eq!(xml_comment("a---b"), "a- - -b");
    }

    #[test]
    fn prologue_records_crs() {
        let date = ("2026-01-02".to_string(), "03:04:05".to_string());
        let epsg = MeshMeta {
            crs: Some("EPSG:3794".into()),
            comments: vec!["made -- here".into()],
        };
        let p = prologue("my <tin>", &epsg, date.clone());
        assert!(
            p.contains("<CoordinateSystem name=\"EPSG:3794\" epsgCode=\"3794\"/>"),
            "{p}"
        );
        assert!(p.contains("<!-- made - - here -->"), "{p}");
        assert!(p.contains("<Surface name=\"my &lt;tin&gt;\">"), "{p}");
        assert!(p.contains("date=\"2026-01-02\" time=\"03:04:05\""), "{p}");
        let wkt = MeshMeta {
            crs: Some("PROJCS[\"D96 / TM\",\n GEOGCS[\"x\"]]".into()),
            comments: vec![],
        };
        let p = prologue("t", &wkt, date.clone());
        assert!(
            p.contains("<CoordinateSystem ogcWktCode=\"PROJCS[&quot;D96 / TM&quot;, GEOGCS[&quot;x&quot;]]\"/>"),
            "{p}"
        );
        assert!(
            p.contains("<Metric ") && p.contains("linearUnit=\"meter\""),
            "{p}"
        );
        // Feet from the WKT's unit: WKT1's UNIT, WKT2's LENGTHUNIT in the axes.
        let feet = |crs: &str| MeshMeta {
            crs: Some(crs.into()),
            comments: vec![],
        };
        let wkt1 = "PROJCS[\"NAD83 / NY Long Island (ftUS)\",GEOGCS[\"NAD83\"],\
                    UNIT[\"US survey foot\",0.304800609601219]]";
        let p = prologue("t", &feet(wkt1), date.clone());
        assert!(
            p.contains("<Imperial areaUnit=\"squareFoot\" linearUnit=\"USSurveyFoot\""),
            "{p}"
        );
        let wkt2 = "COMPOUNDCRS[\"x\",PROJCRS[\"y\",BASEGEOGCRS[\"z\"],CS[Cartesian,2],\
                    AXIS[\"easting\",east,LENGTHUNIT[\"foot\",0.3048]]],VERTCRS[\"v\"]]";
        let p = prologue("t", &feet(wkt2), date);
        assert!(
            p.contains("<Imperial ") && p.contains("linearUnit=\"foot\""),
            "{p}"
        );
    }

    /// Issue 41, item 17: a CRS in feet known by its EPSG code alone (EPSG:2992, Oregon
    /// Lambert in international feet) was declared metric.
    #[test]
    fn units_of_an_epsg_code_in_feet_are_imperial() {
        let date = ("2026-01-02".to_string(), "03:04:05".to_string());
        let units = |crs: &str| {
            let meta = MeshMeta {
                crs: Some(crs.into()),
                comments: vec![],
            };
            let p = prologue("t", &meta, date.clone());
            let start = p.find("<Units>").unwrap();
            p[start..p.find("</Units>").unwrap()].to_string()
        };
        let ft = units("EPSG:2992");
        assert!(
            ft.contains("<Imperial ") && ft.contains("linearUnit=\"foot\""),
            "{ft}"
        );
        // NAD83 / California zone 5 (ftUS).
        let us = units("EPSG:2229");
        assert!(us.contains("linearUnit=\"USSurveyFoot\""), "{us}");
        for metric in ["EPSG:3794", "EPSG:32611", "EPSG:7415"] {
            assert!(units(metric).contains("<Metric "), "{metric}");
        }
    }
}
