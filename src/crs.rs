//! Coordinate reference systems found in LAS/LAZ headers.
//!
//! A LAS file declares its CRS in one of two ways:
//! - **GeoTIFF keys** (LAS ≤ 1.3, and legacy point formats in 1.4): a `LASF_Projection` VLR 34735
//!   holding a GeoKey directory. We read `ProjectedCSTypeGeoKey` (3072), else
//!   `GeographicTypeGeoKey` (2048), as the EPSG code, `VerticalCSTypeGeoKey` (4096) as the vertical
//!   EPSG code, and the citation keys as the name.
//! - **OGC WKT** (`LASF_Projection` record 2112, required for point formats 6–10): we keep the WKT
//!   text, and read the name of its outermost object and that object's own
//!   `AUTHORITY["EPSG", …]` (WKT1) or `ID["EPSG", …]` (WKT2) as the EPSG code. A `VERT_CS` /
//!   `VERTCRS` child of a compound CRS gives the vertical code.
//!
//! The WKT is never interpreted beyond that: outputs carry it through unchanged.

use serde::Serialize;
use std::fmt;

mod codes;
mod esri;
pub mod project;
mod wkt;

/// Is `code` in one of the sorted inclusive `ranges`?
fn in_ranges(ranges: &[(u32, u32)], code: u32) -> bool {
    let i = ranges.partition_point(|&(_, hi)| hi < code);
    ranges.get(i).is_some_and(|&(lo, _)| lo <= code)
}

/// A coordinate reference system as declared in a file's header.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Crs {
    /// EPSG code of the whole CRS (projected, geographic or compound), if the file gives one.
    pub epsg: Option<u32>,
    /// EPSG code of the vertical CRS, if the file gives one separately.
    pub vertical_epsg: Option<u32>,
    /// Human-readable name (WKT name or GeoTIFF citation), if any.
    pub name: Option<String>,
    /// The WKT text, when the CRS was declared as WKT.
    pub wkt: Option<String>,
    /// Whether [`Crs::epsg`] came from GeoTIFF keys as a projected (1) or a geographic (2) code,
    /// as `GTModelTypeGeoKey` says it in GeoTIFF outputs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_type: Option<u16>,
    /// `ProjLinearUnitsGeoKey` (9001 metre, 9002 foot, 9003 US survey foot), which overrides the
    /// projected CRS's own unit (many US files in feet say so this way).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linear_units: Option<u16>,
    /// `VerticalUnitsGeoKey`, which overrides the vertical CRS's own unit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertical_units: Option<u16>,
}

impl Crs {
    /// The CRS as one string for outputs: the WKT text when the file has one (lossless),
    /// otherwise `"EPSG:h"` or `"EPSG:h+v"` (horizontal + vertical, as PROJ spells compounds).
    /// `None` when neither a WKT nor an EPSG code is known.
    pub fn definition(&self) -> Option<String> {
        if let Some(wkt) = &self.wkt {
            return Some(wkt.clone());
        }
        match (self.epsg, self.vertical_epsg) {
            (Some(h), Some(v)) => Some(format!("EPSG:{h}+{v}")),
            (Some(h), None) => Some(format!("EPSG:{h}")),
            (None, _) => None,
        }
    }

    /// Do two declarations describe the same CRS? Equal EPSG codes when both have one (and
    /// equal vertical codes, but for a compound WKT without one: PROJ's WKT2 names the vertical
    /// part only inside the whole's code, the WKT1 spelling gives it apart; unit keys that do
    /// not differ),
    /// otherwise equal WKT text, otherwise equal names.
    pub fn same_as(&self, other: &Crs) -> bool {
        // A unit key where the other gives none may only restate the code's unit (LAStools
        // writes 3076 = metre routinely; a `.vpc` lists codes alone): two different keys differ.
        let agree = |a: Option<u16>, b: Option<u16>| a.zip(b).is_none_or(|(a, b)| a == b);
        let units = agree(self.linear_units, other.linear_units)
            && agree(self.vertical_units, other.vertical_units);
        // A compound's code alone names its vertical part too.
        let vertical = match (self.vertical_epsg, other.vertical_epsg) {
            (Some(a), Some(b)) => a == b,
            (None, Some(_)) => self.is_compound(),
            (Some(_), None) => other.is_compound(),
            (None, None) => true,
        };
        match (self.epsg, other.epsg) {
            (Some(a), Some(b)) => a == b && vertical && units,
            _ if self.wkt.is_some() || other.wkt.is_some() => self.wkt == other.wkt,
            _ => self.name == other.name && self.vertical_epsg == other.vertical_epsg && units,
        }
    }

    /// Is this a compound CRS given as WKT (`COMPD_CS`, `COMPOUNDCRS`)?
    fn is_compound(&self) -> bool {
        self.wkt
            .as_deref()
            .and_then(wkt::parse)
            .is_some_and(|r| matches!(r.keyword.as_str(), "COMPD_CS" | "COMPOUNDCRS"))
    }

    /// Of two declarations of the same CRS ([`Crs::same_as`]), the one that says more (a
    /// vertical code), with the keys only the other gives (units, model type).
    pub fn fuller(self, other: Crs) -> Crs {
        let (mut a, b) = if self.vertical_epsg.is_none() && other.vertical_epsg.is_some() {
            (other, self)
        } else {
            (self, other)
        };
        a.linear_units = a.linear_units.or(b.linear_units);
        a.vertical_units = a.vertical_units.or(b.vertical_units);
        a.model_type = a.model_type.or(b.model_type);
        a
    }

    /// Parses a CRS given by a user (`--crs`, the Python package's `crs=`): `EPSG:code`,
    /// `EPSG:code+vertical` or a WKT definition.
    ///
    /// # Errors
    /// [`crate::Error::Options`] for anything else.
    pub fn parse(s: &str) -> crate::Result<Crs> {
        let t = s.trim();
        let bad = |what: &str| crate::Error::Options(format!("--crs {s}: expected {what}"));
        if let Some(code) = t.strip_prefix("EPSG:").or_else(|| t.strip_prefix("epsg:")) {
            let mut parts = code.split('+');
            let h = parts.next().unwrap_or("").trim().parse::<u32>();
            let v = parts.next().map(|v| v.trim().parse::<u32>());
            // GeoTIFF's "undefined" (0) and "user-defined" (32767) name no CRS, nor does any
            // code below 1024 (`EPSG:0` was taken and written as if it were one).
            if let Some(c) = [h.as_ref().ok(), v.as_ref().and_then(|v| v.as_ref().ok())]
                .into_iter()
                .flatten()
                .find(|&&c| c < 1024 || c == 32767)
            {
                return Err(crate::Error::Options(format!(
                    "--crs {s}: {c} is not the EPSG code of a CRS ({})",
                    match *c {
                        0 => "0 is \"undefined\" in GeoTIFF's keys",
                        32767 => "32767 is \"user-defined\" in GeoTIFF's keys",
                        _ => "they start at 1024",
                    }
                )));
            }
            if parts.next().is_some() {
                return Err(bad("EPSG:code or EPSG:code+code"));
            }
            return match (h, v) {
                (Ok(h), None) => Ok(Crs {
                    epsg: Some(h),
                    ..Crs::default()
                }),
                (Ok(h), Some(Ok(v))) => Ok(Crs {
                    epsg: Some(h),
                    vertical_epsg: Some(v),
                    ..Crs::default()
                }),
                _ => Err(bad("EPSG:code or EPSG:code+code")),
            };
        }
        match Crs::from_wkt_bytes(t.as_bytes()) {
            Some(c) if c.name.is_some() || c.epsg.is_some() => Ok(c),
            _ => Err(bad("EPSG:code, EPSG:code+code or a WKT definition")),
        }
    }

    /// Reads the CRS from a WKT VLR payload (`None` if the text is empty).
    pub fn from_wkt_bytes(bytes: &[u8]) -> Option<Crs> {
        let text = String::from_utf8_lossy(bytes);
        let text = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
        if text.is_empty() {
            return None;
        }
        let mut crs = Crs {
            wkt: Some(text.to_string()),
            ..Crs::default()
        };
        if let Some(root) = wkt::parse(text) {
            crs.name = root.first_string().map(str::to_string);
            crs.epsg = root.epsg();
            crs.vertical_epsg = root
                .children()
                .find(|c| matches!(c.keyword.as_str(), "VERT_CS" | "VERTCRS" | "VERTICALCRS"))
                .and_then(wkt::Node::epsg);
        }
        Some(crs)
    }

    /// Reads the CRS from parsed GeoTIFF keys (`None` if they name no CRS at all).
    pub fn from_geotiff(keys: &las::crs::GeoTiffCrs) -> Option<Crs> {
        let code = |v: Option<u16>| v.filter(|k| (1024..=32766).contains(k)).map(u32::from);
        // The kind of the code is the key's that gave it (`GTModelTypeGeoKey` may disagree).
        let (epsg, model_type) = match code(keys.get_projected_crs_geo_key_value()) {
            Some(c) => (Some(c), Some(1)),
            None => match code(keys.get_geodetic_crs_geo_key_value()) {
                Some(c) => (Some(c), Some(2)),
                None => (None, None),
            },
        };
        let vertical_epsg = code(keys.get_vertical_crs_geo_key_value());
        // GTCitationGeoKey, PCSCitationGeoKey, GeogCitationGeoKey, in that order of preference.
        let name = [1026u16, 3073, 2049].iter().find_map(|id| {
            keys.entries
                .iter()
                .find(|e| e.id == *id)
                .and_then(|e| match &e.data {
                    las::crs::GeoTiffData::String(s) => {
                        let s = s.trim_end_matches(['|', '\0']).trim();
                        (!s.is_empty()).then(|| s.to_string())
                    }
                    _ => None,
                })
        });
        if epsg.is_none() && vertical_epsg.is_none() && name.is_none() {
            return None;
        }
        let short = |id: u16| {
            keys.entries
                .iter()
                .find(|e| e.id == id)
                .and_then(|e| match &e.data {
                    las::crs::GeoTiffData::U16(v) => Some(*v),
                    _ => None,
                })
        };
        // A unit key is kept only when it names a unit (not 32767, user-defined).
        let unit = |id: u16| short(id).filter(|u| (9000..9200).contains(u));
        Some(Crs {
            epsg,
            vertical_epsg,
            name,
            wkt: None,
            model_type,
            linear_units: unit(3076),
            vertical_units: unit(4099),
        })
    }
}

impl fmt::Display for Crs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        if let Some(h) = self.epsg {
            parts.push(format!("EPSG:{h}"));
        }
        if let Some(v) = self.vertical_epsg {
            parts.push(format!("vertical EPSG:{v}"));
        }
        if let Some(n) = &self.name {
            parts.push(format!("\"{n}\""));
        }
        for (what, u) in [
            ("units", self.linear_units),
            ("vertical units", self.vertical_units),
        ] {
            if let Some(u) = u {
                parts.push(format!("{what} {}", unit_name(u)));
            }
        }
        if self.wkt.is_some() {
            parts.push("(WKT)".to_string());
        } else {
            parts.push("(GeoTIFF keys)".to_string());
        }
        f.write_str(&parts.join(" "))
    }
}

/// The unit of length of a projected CRS, where it can be told without a CRS database.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthUnit {
    /// The metre.
    Metre,
    /// The international foot (0.3048 m).
    Foot,
    /// The US survey foot (1200/3937 m).
    UsSurveyFoot,
}

impl Crs {
    /// The unit of the horizontal coordinates: a GeoTIFF unit key (3076) when given, else the
    /// WKT's unit of its projected part (`UNIT` / `LENGTHUNIT` by its factor), else the unit of
    /// the projected CRS's EPSG code (feet and US survey feet from the EPSG dataset's list,
    /// `src/crs/codes.rs`; metres for the other projected codes). `None` for a geographic CRS,
    /// no CRS, or another unit.
    pub fn length_unit(&self) -> Option<LengthUnit> {
        match self.linear_units {
            Some(9001) => return Some(LengthUnit::Metre),
            Some(9002) => return Some(LengthUnit::Foot),
            Some(9003) => return Some(LengthUnit::UsSurveyFoot),
            _ => {}
        }
        self.wkt_length_unit().or_else(|| {
            let code = self.code_for_tables()?;
            if in_ranges(&codes::FOOT, code) {
                Some(LengthUnit::Foot)
            } else if in_ranges(&codes::US_SURVEY_FOOT, code) {
                Some(LengthUnit::UsSurveyFoot)
            } else if self.wkt.is_none() && !self.is_geographic() {
                Some(LengthUnit::Metre)
            } else {
                None
            }
        })
    }

    /// The horizontal EPSG code when the WKT gives it for the projected part, else the code of
    /// the whole (what the code tables are looked up by).
    fn code_for_tables(&self) -> Option<u32> {
        self.horizontal_epsg().map(|(c, _)| c).or(self.epsg)
    }

    /// The WKT's own unit of its projected part.
    fn wkt_length_unit(&self) -> Option<LengthUnit> {
        let root = wkt::parse(self.wkt.as_deref()?)?;
        let projected =
            |n: &wkt::Node| matches!(n.keyword.as_str(), "PROJCS" | "PROJCRS" | "PROJECTEDCRS");
        let node = if projected(&root) {
            &root
        } else {
            root.children().find(|c| projected(c))?
        };
        let is_unit = |n: &&wkt::Node| matches!(n.keyword.as_str(), "UNIT" | "LENGTHUNIT");
        // WKT1 and WKT2 give the unit as a child; WKT2 may give it in each AXIS instead.
        let unit = node.children().find(is_unit).or_else(|| {
            node.children()
                .filter(|c| c.keyword == "AXIS")
                .find_map(|a| a.children().find(is_unit))
        })?;
        let factor: f64 = unit.args.iter().find_map(|a| match a {
            wkt::Arg::Bare(v) => v.trim().parse().ok(),
            _ => None,
        })?;
        let near = |f: f64| (factor - f).abs() < 1e-9;
        if near(1.0) {
            Some(LengthUnit::Metre)
        } else if near(0.3048) {
            Some(LengthUnit::Foot)
        } else if near(1200.0 / 3937.0) {
            Some(LengthUnit::UsSurveyFoot)
        } else {
            None
        }
    }
}

/// Why outputs that would record a CRS go without one, for a one-line warning.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LostCrs {
    /// No CRS is known: the input declares none and none was given.
    Unknown,
    /// The CRS (as [`Crs`] displays it) is known by an EPSG code only, which sweeptin cannot
    /// write as WKT ([`Crs::prj`]): no `.prj` is written.
    NoWkt(String),
}

impl LostCrs {
    /// What the outputs lose of `crs`; `prj`: a `.prj` (or a PNG's `.aux.xml`) is among them.
    /// `None` when they carry it.
    pub fn of(crs: Option<&Crs>, prj: bool) -> Option<LostCrs> {
        match crs {
            None => Some(LostCrs::Unknown),
            Some(c) if prj && c.prj().is_none() => Some(LostCrs::NoWkt(c.to_string())),
            Some(_) => None,
        }
    }
}

impl fmt::Display for LostCrs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LostCrs::Unknown => {
                f.write_str("no coordinate reference system is declared, so the outputs carry none")
            }
            LostCrs::NoWkt(c) => write!(
                f,
                "the CRS {c} cannot be written as WKT without a CRS database (sweeptin spells \
                 the common EPSG codes only), so no .prj is written: `gdalsrsinfo -o wkt_esri \
                 EPSG:code` prints one"
            ),
        }
    }
}

/// The name of an EPSG unit of length code as GeoTIFF keys give it.
pub fn unit_name(code: u16) -> String {
    match code {
        9001 => "metre".into(),
        9002 => "foot".into(),
        9003 => "US survey foot".into(),
        c => format!("EPSG:{c}"),
    }
}

/// Whether a horizontal CRS is projected or geographic (what a GeoTIFF's `GTModelTypeGeoKey`
/// needs to know).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HorizontalKind {
    /// A projected CRS (`ProjectedCSTypeGeoKey`).
    Projected,
    /// A geographic CRS (`GeographicTypeGeoKey`).
    Geographic,
}

impl Crs {
    /// The EPSG code of the horizontal CRS and its kind, for writers that need them apart (such as
    /// GeoTIFF keys). From WKT: the root object, or for a compound CRS its first projected or
    /// geographic child. Without WKT (GeoTIFF keys in the LAS header), [`Crs::epsg`] with a guess
    /// of the kind, the header's model type, or else from the code: 4000–4999 geographic,
    /// everything else projected.
    pub fn horizontal_epsg(&self) -> Option<(u32, HorizontalKind)> {
        let kind_of = |keyword: &str| match keyword {
            "PROJCS" | "PROJCRS" | "PROJECTEDCRS" => Some(HorizontalKind::Projected),
            "GEOGCS" | "GEOGCRS" | "GEODCRS" | "GEOGRAPHICCRS" | "GEODETICCRS" => {
                Some(HorizontalKind::Geographic)
            }
            _ => None,
        };
        if let Some(root) = self.wkt.as_deref().and_then(wkt::parse) {
            if let Some(kind) = kind_of(&root.keyword) {
                return root.epsg().map(|c| (c, kind));
            }
            return root
                .children()
                .find_map(|c| kind_of(&c.keyword).map(|k| (c, k)))
                .and_then(|(c, k)| c.epsg().map(|code| (code, k)));
        }
        let code = self.epsg?;
        let kind = match self.model_type {
            Some(2) => HorizontalKind::Geographic,
            Some(_) => HorizontalKind::Projected,
            None if in_ranges(&codes::GEOGRAPHIC, code) => HorizontalKind::Geographic,
            None => HorizontalKind::Projected,
        };
        Some((code, kind))
    }

    /// The rectangle `[xmin, ymin, xmax, ymax]` in this CRS as a closed WGS 84 longitude /
    /// latitude ring (its corners and `per_edge − 1` points along each edge), for RFC 7946 and
    /// STAC footprints: through the inverse projection of the horizontal EPSG code
    /// ([`project::Projection::of_epsg`]), or as it is for WGS 84-compatible geographic codes
    /// (4326, ETRS89 4258, RGF93 4171, NAD83 4269, NAD83(CSRS) 4617; x is the longitude).
    /// Datums are taken as WGS 84 (within about 1 m; `project`'s docs). `None` for a CRS that
    /// is unknown or not in the table: never projected numbers in their place.
    pub fn wgs84_ring(&self, rect: [f64; 4], per_edge: usize) -> Option<Vec<[f64; 2]>> {
        let (code, kind) = self.horizontal_epsg()?;
        match kind {
            HorizontalKind::Geographic if matches!(code, 4326 | 4258 | 4171 | 4269 | 4617) => {
                let [x0, y0, x1, y1] = rect;
                let ok = x0 >= -180.0 && x1 <= 180.0 && y0 >= -90.0 && y1 <= 90.0;
                ok.then(|| vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])
            }
            HorizontalKind::Geographic => None,
            HorizontalKind::Projected => {
                // A unit key that overrides the code's metres (a LAS in feet under a metric
                // code) is not the code's projection.
                if self.linear_units.is_some_and(|u| u != 9001) {
                    return None;
                }
                Some(project::Projection::of_epsg(code)?.ring(rect, per_edge))
            }
        }
    }

    /// Are the horizontal coordinates latitude and longitude in degrees? From the WKT's
    /// outermost geographic object (or a compound's first child), a GeoTIFF model type, or the
    /// EPSG code's kind in the EPSG dataset (`src/crs/codes.rs`).
    pub fn is_geographic(&self) -> bool {
        let geographic = |k: &str| {
            matches!(
                k,
                "GEOGCS" | "GEOGCRS" | "GEODCRS" | "GEOGRAPHICCRS" | "GEODETICCRS"
            )
        };
        if let Some(root) = self.wkt.as_deref().and_then(wkt::parse) {
            return geographic(&root.keyword)
                || (matches!(root.keyword.as_str(), "COMPD_CS" | "COMPOUNDCRS")
                    && root
                        .children()
                        .next()
                        .is_some_and(|c| geographic(&c.keyword)));
        }
        matches!(
            self.horizontal_epsg(),
            Some((_, HorizontalKind::Geographic))
        )
    }

    /// The text of a `.prj` beside a raster: the file's own WKT when it is WKT1 (which GDAL
    /// and ESRI software read), else ESRI's WKT1 of the EPSG code as GDAL writes it, for the
    /// codes sweeptin can spell without a CRS database (`src/crs/esri.rs`: the common datums'
    /// geographic CRSs and UTM zones, MGA and MTM zones, a few national grids; a vertical code
    /// it does not know is left out). `None` when neither is possible: no CRS, another code,
    /// or a unit key that overrides the code's unit.
    pub fn prj(&self) -> Option<String> {
        if let Some(text) = &self.wkt {
            let wkt1 = wkt::parse(text).is_some_and(|r| {
                matches!(
                    r.keyword.as_str(),
                    "PROJCS" | "GEOGCS" | "COMPD_CS" | "GEOCCS" | "LOCAL_CS"
                )
            });
            if wkt1 {
                return Some(text.trim_end_matches('\0').to_string());
            }
        }
        let code = self.code_for_tables()?;
        let text = esri::wkt(code, self.vertical_epsg)?;
        // A GeoTIFF unit key that differs from the code's own unit (a LAS in feet under a
        // metric code) would make the text wrong.
        let coded = Crs {
            epsg: Some(code),
            ..Crs::default()
        };
        if self.linear_units.is_some() && self.length_unit() != coded.length_unit() {
            return None;
        }
        Some(text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RD_NAP: &str = r#"COMPD_CS["Amersfoort / RD New + NAP height",PROJCS["Amersfoort / RD New",GEOGCS["Amersfoort",AUTHORITY["EPSG","4289"]],AUTHORITY["EPSG","28992"]],VERT_CS["NAP height",VERT_DATUM["Normaal Amsterdams Peil",2005,AUTHORITY["EPSG","5109"]],AUTHORITY["EPSG","5709"]],AUTHORITY["EPSG","7415"]]"#;

    #[test]
    fn wkt2_compound_with_one_code_is_its_wkt1_spelling() {
        // PROJ's WKT2 for EPSG:7415 gives the code on the whole only; its WKT1 gives the parts'
        // codes too: one CRS (files with both were refused as in two CRSs).
        let wkt2 = Crs::from_wkt_bytes(
            b"COMPOUNDCRS[\"Amersfoort / RD New + NAP height\",PROJCRS[\"Amersfoort / RD New\"],\
              VERTCRS[\"NAP height\"],ID[\"EPSG\",7415]]",
        )
        .unwrap();
        let wkt1 = Crs::from_wkt_bytes(
            b"COMPD_CS[\"Amersfoort / RD New + NAP height\",PROJCS[\"Amersfoort / RD New\",\
              AUTHORITY[\"EPSG\",\"28992\"]],VERT_CS[\"NAP height\",AUTHORITY[\"EPSG\",\"5709\"]],\
              AUTHORITY[\"EPSG\",\"7415\"]]",
        )
        .unwrap();
        assert_eq!((wkt2.epsg, wkt2.vertical_epsg), (Some(7415), None));
        assert!(wkt2.same_as(&wkt1) && wkt1.same_as(&wkt2));
        assert_eq!(wkt2.clone().fuller(wkt1.clone()), wkt1);
        // Different vertical codes stay different.
        let other = Crs {
            vertical_epsg: Some(5710),
            ..wkt1.clone()
        };
        assert!(!other.same_as(&wkt1));
        // A unit key beside none (a `.vpc` lists codes alone; LAStools writes 3076 = metre)
        // agrees; two different keys do not; the fuller declaration keeps the key.
        let code = Crs {
            epsg: Some(26915),
            ..Crs::default()
        };
        let metre = Crs {
            linear_units: Some(9001),
            model_type: Some(1),
            ..code.clone()
        };
        let foot = Crs {
            linear_units: Some(9002),
            ..code.clone()
        };
        assert!(code.same_as(&metre) && metre.same_as(&code));
        assert!(!metre.same_as(&foot));
        assert_eq!(code.fuller(metre.clone()), metre);
    }

    #[test]
    fn wkt1_compound() {
        let crs = Crs::from_wkt_bytes(format!("{RD_NAP}\0\0").as_bytes()).unwrap();
        assert_eq!(crs.epsg, Some(7415));
        assert_eq!(crs.vertical_epsg, Some(5709));
        assert_eq!(
            crs.name.as_deref(),
            Some("Amersfoort / RD New + NAP height")
        );
        assert_eq!(crs.definition().as_deref(), Some(RD_NAP));
    }

    #[test]
    fn horizontal_part_of_compound_and_plain() {
        let crs = Crs::from_wkt_bytes(RD_NAP.as_bytes()).unwrap();
        assert_eq!(
            crs.horizontal_epsg(),
            Some((28992, HorizontalKind::Projected))
        );
        let geo = Crs::from_wkt_bytes(br#"GEOGCS["WGS 84",AUTHORITY["EPSG","4326"]]"#).unwrap();
        assert_eq!(
            geo.horizontal_epsg(),
            Some((4326, HorizontalKind::Geographic))
        );
        let keys = Crs {
            epsg: Some(2949),
            ..Crs::default()
        };
        assert_eq!(
            keys.horizontal_epsg(),
            Some((2949, HorizontalKind::Projected))
        );
        assert_eq!(Crs::default().horizontal_epsg(), None);
    }

    #[test]
    fn wkt2_id() {
        let wkt = r#"PROJCRS["RGF93 v1 / Lambert-93", BASEGEOGCRS["RGF93 v1", ID["EPSG", 4171]], ID["EPSG", 2154]]"#;
        let crs = Crs::from_wkt_bytes(wkt.as_bytes()).unwrap();
        assert_eq!(crs.epsg, Some(2154));
        assert_eq!(crs.name.as_deref(), Some("RGF93 v1 / Lambert-93"));
    }

    #[test]
    fn wkt_without_authority_or_malformed() {
        let crs = Crs::from_wkt_bytes(br#"PROJCS["local", GEOGCS["x"]]"#).unwrap();
        assert_eq!(crs.epsg, None);
        assert_eq!(crs.name.as_deref(), Some("local"));
        let bad = Crs::from_wkt_bytes(b"PROJCS[\"unterminated").unwrap();
        assert_eq!(bad.epsg, None);
        assert!(bad.wkt.is_some());
        assert!(Crs::from_wkt_bytes(b"\0\0  ").is_none());
        let deep = "A[".repeat(1000);
        assert_eq!(Crs::from_wkt_bytes(deep.as_bytes()).unwrap().epsg, None);
    }

    #[test]
    fn definitions() {
        let c = Crs {
            epsg: Some(2949),
            ..Crs::default()
        };
        assert_eq!(c.definition().as_deref(), Some("EPSG:2949"));
        let c = Crs {
            epsg: Some(2949),
            vertical_epsg: Some(5713),
            ..Crs::default()
        };
        assert_eq!(c.definition().as_deref(), Some("EPSG:2949+5713"));
        for s in [
            "EPSG:0",
            "EPSG:32767",
            "EPSG:2949+0",
            "EPSG:1+2+3",
            "EPSG:1023",
        ] {
            assert!(Crs::parse(s).is_err(), "{s}");
        }
        assert!(!c.same_as(&Crs {
            epsg: Some(2949),
            ..Crs::default()
        }));
    }

    #[test]
    fn units_and_kinds_of_codes() {
        let code = |c: u32| Crs {
            epsg: Some(c),
            ..Crs::default()
        };
        assert_eq!(code(2992).length_unit(), Some(LengthUnit::Foot));
        assert_eq!(code(2229).length_unit(), Some(LengthUnit::UsSurveyFoot));
        assert_eq!(code(3794).length_unit(), Some(LengthUnit::Metre));
        assert_eq!(code(4326).length_unit(), None);
        // A unit key overrides the code's unit.
        let keyed = Crs {
            linear_units: Some(9001),
            ..code(2992)
        };
        assert_eq!(keyed.length_unit(), Some(LengthUnit::Metre));
        assert_eq!(keyed.prj(), None);
        assert!(code(2992).prj().is_some());
        for g in [4326, 4269, 6318, 7844, 4979] {
            assert!(code(g).is_geographic(), "{g}");
        }
        // Projected codes among 4000–4999 (once guessed geographic by the range alone).
        for p in [4026, 3794, 32611, 2154] {
            assert!(!code(p).is_geographic(), "{p}");
        }
        let wkt = Crs::from_wkt_bytes(br#"GEOGCS["WGS 84",AUTHORITY["EPSG","4326"]]"#).unwrap();
        assert!(wkt.is_geographic());
        assert!(
            !Crs::from_wkt_bytes(RD_NAP.as_bytes())
                .unwrap()
                .is_geographic()
        );
        // WKT1 is written as it is; WKT2 (which GDAL does not read from a .prj) as ESRI's text.
        assert_eq!(
            Crs::from_wkt_bytes(RD_NAP.as_bytes())
                .unwrap()
                .prj()
                .as_deref(),
            Some(RD_NAP)
        );
        let wkt2 = Crs::from_wkt_bytes(
            br#"PROJCRS["RGF93 v1 / Lambert-93", BASEGEOGCRS["RGF93 v1"], ID["EPSG", 2154]]"#,
        )
        .unwrap();
        assert!(
            wkt2.prj()
                .unwrap()
                .starts_with("PROJCS[\"RGF_1993_Lambert_93\"")
        );
    }
}
