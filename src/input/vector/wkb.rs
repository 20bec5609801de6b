//! Well-Known Binary geometries (OGC/ISO WKB, with PostGIS's EWKB flags) and SpatiaLite blobs,
//! into the parts of a [`GeoJson`].

use super::format;
use crate::error::Result;
use crate::input::geojson::{GeoJson, push_part};
use std::path::Path;

/// A cursor over a geometry blob, in the byte order its header says.
struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
    little: bool,
}

impl Cursor<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.b.get(self.at..self.at + n)?;
        self.at += n;
        Some(s)
    }

    fn u8(&mut self) -> Option<u8> {
        self.take(1).map(|s| s[0])
    }

    fn u32(&mut self) -> Option<u32> {
        let s: [u8; 4] = self.take(4)?.try_into().ok()?;
        Some(if self.little {
            u32::from_le_bytes(s)
        } else {
            u32::from_be_bytes(s)
        })
    }

    fn f64(&mut self) -> Option<f64> {
        let s: [u8; 8] = self.take(8)?.try_into().ok()?;
        Some(if self.little {
            f64::from_le_bytes(s)
        } else {
            f64::from_be_bytes(s)
        })
    }
}

/// Where the parts go and how they are labelled.
pub(super) struct Sink<'a> {
    pub out: &'a mut GeoJson,
    pub path: &'a Path,
    pub feature: u64,
    pub part: u32,
    pub polygons: u32,
}

impl Sink<'_> {
    fn bad(&self, what: &str) -> crate::error::Error {
        format(
            self.path,
            format!("feature {}: bad geometry blob ({what})", self.feature),
        )
    }

    fn push(&mut self, polygon: Option<u32>, kind: &str, line: Vec<[f64; 3]>) -> Result<()> {
        let p = self.part;
        self.part += 1;
        push_part(self.out, self.path, (self.feature, p), polygon, kind, line)
    }
}

/// Type code and dimensions of a WKB geometry header: `(base type, has z, has m)`.
fn kind_of(code: u32) -> (u32, bool, bool) {
    let (ez, em) = (code & 0x8000_0000 != 0, code & 0x4000_0000 != 0);
    let iso = code & 0x0fff_ffff;
    let (base, dims) = (iso % 1000, iso / 1000);
    (
        base,
        ez || dims == 1 || dims == 3,
        em || dims == 2 || dims == 3,
    )
}

/// Reads one WKB geometry from `blob` (the whole blob must be used, trailing bytes allowed).
pub(super) fn read_wkb(blob: &[u8], sink: &mut Sink<'_>) -> Result<()> {
    let mut c = Cursor {
        b: blob,
        at: 0,
        little: true,
    };
    geometry(&mut c, sink)
}

fn geometry(c: &mut Cursor<'_>, sink: &mut Sink<'_>) -> Result<()> {
    let order = c.u8().ok_or_else(|| sink.bad("truncated"))?;
    c.little = match order {
        0 => false,
        1 => true,
        _ => return Err(sink.bad("byte order is neither 0 nor 1")),
    };
    let code = c.u32().ok_or_else(|| sink.bad("truncated"))?;
    if code & 0x2000_0000 != 0 {
        c.u32().ok_or_else(|| sink.bad("truncated SRID"))?;
    }
    let (base, z, m) = kind_of(code);
    let count = |c: &mut Cursor<'_>, sink: &Sink<'_>| -> Result<usize> {
        let n = c.u32().ok_or_else(|| sink.bad("truncated"))? as usize;
        // Each element takes at least 16 bytes (a position) or 5 (a header): refuse absurd counts.
        if n > c.b.len() {
            return Err(sink.bad("count larger than the blob"));
        }
        Ok(n)
    };
    match base {
        1 => {
            positions(c, sink, 1, z, m)?;
            sink.out.points.push((sink.feature, "Point"));
            Ok(())
        }
        2 => {
            let n = count(c, sink)?;
            let line = positions(c, sink, n, z, m)?;
            sink.push(None, "LineString", line)
        }
        3 => {
            let rings = count(c, sink)?;
            polygon(c, sink, rings, z, m)
        }
        4 => {
            let n = count(c, sink)?;
            for _ in 0..n {
                geometry(c, sink)?;
            }
            // A MultiPoint is noted once, like GeoJSON's.
            let kept = sink.out.points.len() - n;
            sink.out.points.truncate(kept);
            sink.out.points.push((sink.feature, "MultiPoint"));
            Ok(())
        }
        5..=7 => {
            let n = count(c, sink)?;
            for _ in 0..n {
                geometry(c, sink)?;
            }
            Ok(())
        }
        other => Err(sink.bad(&format!("geometry type {other} is not supported"))),
    }
}

fn polygon(c: &mut Cursor<'_>, sink: &mut Sink<'_>, rings: usize, z: bool, m: bool) -> Result<()> {
    if rings == 0 {
        return Ok(());
    }
    let k = sink.polygons;
    sink.polygons += 1;
    for _ in 0..rings {
        let n = c.u32().ok_or_else(|| sink.bad("truncated"))? as usize;
        if n > c.b.len() {
            return Err(sink.bad("count larger than the blob"));
        }
        let ring = positions(c, sink, n, z, m)?;
        sink.push(Some(k), "Polygon", ring)?;
    }
    Ok(())
}

fn positions(
    c: &mut Cursor<'_>,
    sink: &Sink<'_>,
    n: usize,
    z: bool,
    m: bool,
) -> Result<Vec<[f64; 3]>> {
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let mut p = [f64::NAN; 3];
        p[0] = c.f64().ok_or_else(|| sink.bad("truncated"))?;
        p[1] = c.f64().ok_or_else(|| sink.bad("truncated"))?;
        if z {
            p[2] = c.f64().ok_or_else(|| sink.bad("truncated"))?;
        }
        if m {
            c.f64().ok_or_else(|| sink.bad("truncated"))?;
        }
        if !(p[0].is_finite() && p[1].is_finite() && (!z || p[2].is_finite())) {
            return Err(format(
                sink.path,
                format!(
                    "feature {} part {}, position {k}: coordinate is not finite",
                    sink.feature, sink.part
                ),
            ));
        }
        out.push(p);
    }
    Ok(out)
}

/// Reads a SpatiaLite geometry blob (uncompressed classes: `0x00`, byte order, SRID, MBR,
/// `0x7C`, then the class and its body, entities of collections marked `0x69`; `0xFE` ends it).
pub(super) fn read_spatialite(blob: &[u8], sink: &mut Sink<'_>) -> Result<()> {
    if blob.len() < 44 || blob[0] != 0 || blob[38] != 0x7C {
        return Err(sink.bad("not a SpatiaLite geometry"));
    }
    let little = match blob[1] {
        0 => false,
        1 => true,
        _ => return Err(sink.bad("byte order is neither 0 nor 1")),
    };
    let mut c = Cursor {
        b: blob,
        at: 39,
        little,
    };
    spatialite_body(&mut c, sink, false)
}

fn spatialite_body(c: &mut Cursor<'_>, sink: &mut Sink<'_>, entity: bool) -> Result<()> {
    if entity && c.u8() != Some(0x69) {
        return Err(sink.bad("missing collection entity mark"));
    }
    let code = c.u32().ok_or_else(|| sink.bad("truncated"))?;
    if code >= 1_000_000 {
        return Err(sink.bad(
            "compressed SpatiaLite geometries are not supported (write the layer as WKB: \
             ogr2ogr -f SQLite)",
        ));
    }
    let (base, z, m) = kind_of(code);
    match base {
        1 => {
            positions(c, sink, 1, z, m)?;
            sink.out.points.push((sink.feature, "Point"));
            Ok(())
        }
        2 => {
            let n = c.u32().ok_or_else(|| sink.bad("truncated"))? as usize;
            if n > c.b.len() {
                return Err(sink.bad("count larger than the blob"));
            }
            let line = positions(c, sink, n, z, m)?;
            sink.push(None, "LineString", line)
        }
        3 => {
            let rings = c.u32().ok_or_else(|| sink.bad("truncated"))? as usize;
            polygon(c, sink, rings, z, m)
        }
        4..=7 => {
            let n = c.u32().ok_or_else(|| sink.bad("truncated"))? as usize;
            for _ in 0..n {
                spatialite_body(c, sink, true)?;
            }
            Ok(())
        }
        other => Err(sink.bad(&format!("geometry class {other} is not supported"))),
    }
}

/// The WKB inside a GeoPackage geometry blob (after its header), or `None` for an empty
/// geometry.
pub(super) fn gpkg_wkb<'a>(blob: &'a [u8], sink: &Sink<'_>) -> Result<Option<&'a [u8]>> {
    if blob.len() < 8 || &blob[..2] != b"GP" {
        return Err(sink.bad("not a GeoPackage geometry (no GP header)"));
    }
    let flags = blob[3];
    if flags & 0x10 != 0 {
        return Ok(None);
    }
    let envelope = match (flags >> 1) & 0x7 {
        0 => 0,
        1 => 32,
        2 | 3 => 48,
        4 => 64,
        _ => return Err(sink.bad("bad envelope code")),
    };
    blob.get(8 + envelope..)
        .map(Some)
        .ok_or_else(|| sink.bad("truncated"))
}
