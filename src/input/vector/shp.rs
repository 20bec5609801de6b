//! ESRI Shapefiles, through the `shapefile` crate.

use super::{epsg_of_wkt, format};
use crate::error::Result;
use crate::input::geojson::{GeoJson, push_part};
use shapefile::{Shape, ShapeReader};
use std::io::{Cursor, Read, Seek};
use std::path::Path;

/// The rings of a polygon shape, grouped: an outer ring starts a polygon, inner rings follow.
fn polygons<P: Copy>(
    rings: &[shapefile::PolygonRing<P>],
    xyz: impl Fn(&P) -> [f64; 3],
) -> Vec<Vec<Vec<[f64; 3]>>> {
    let mut out: Vec<Vec<Vec<[f64; 3]>>> = Vec::new();
    for r in rings {
        let pts: Vec<[f64; 3]> = r.points().iter().map(&xyz).collect();
        match r {
            shapefile::PolygonRing::Outer(_) => out.push(vec![pts]),
            shapefile::PolygonRing::Inner(_) => match out.last_mut() {
                Some(p) => p.push(pts),
                None => out.push(vec![pts]),
            },
        }
    }
    out
}

fn bad(path: &Path, e: shapefile::Error) -> crate::error::Error {
    match e {
        shapefile::Error::IoError(io) => crate::error::Error::io(path, io),
        other => format(path, format!("cannot read the Shapefile: {other}")),
    }
}

/// The shapes of the Shapefile `path`: read from the file (and its `.shx` index), or parsed
/// from `bytes`, its content (shapes in file order, without the index). The CRS comes from the
/// `.prj` beside it either way.
pub(super) fn read(path: &Path, bytes: Option<&[u8]>) -> Result<GeoJson> {
    match bytes {
        Some(b) => shapes(
            path,
            ShapeReader::new(Cursor::new(b)).map_err(|e| bad(path, e))?,
        ),
        None => shapes(
            path,
            ShapeReader::from_path(path).map_err(|e| bad(path, e))?,
        ),
    }
}

fn shapes<T: Read + Seek>(path: &Path, mut reader: ShapeReader<T>) -> Result<GeoJson> {
    let bad = |e| bad(path, e);
    let crs = std::fs::read(path.with_extension("prj"))
        .ok()
        .and_then(|w| epsg_of_wkt(&w));
    let mut out = GeoJson {
        crs,
        ..GeoJson::default()
    };
    let mut polygon_count = 0u32;
    for (feature, shape) in reader.iter_shapes().enumerate() {
        let feature = feature as u64;
        let shape = shape.map_err(bad)?;
        let mut part = 0u32;
        let mut line = |out: &mut GeoJson, polygon: Option<u32>, kind: &str, pts: Vec<[f64; 3]>| {
            let p = part;
            part += 1;
            push_part(out, path, (feature, p), polygon, kind, pts)
        };
        let nan = f64::NAN;
        match shape {
            Shape::NullShape => {}
            Shape::Point(_) | Shape::PointM(_) | Shape::PointZ(_) => {
                out.points.push((feature, "Point"))
            }
            Shape::Multipoint(_) | Shape::MultipointM(_) | Shape::MultipointZ(_) => {
                out.points.push((feature, "MultiPoint"))
            }
            Shape::Polyline(l) => {
                for p in l.parts() {
                    line(
                        &mut out,
                        None,
                        "PolyLine",
                        p.iter().map(|q| [q.x, q.y, nan]).collect(),
                    )?;
                }
            }
            Shape::PolylineM(l) => {
                for p in l.parts() {
                    line(
                        &mut out,
                        None,
                        "PolyLineM",
                        p.iter().map(|q| [q.x, q.y, nan]).collect(),
                    )?;
                }
            }
            Shape::PolylineZ(l) => {
                for p in l.parts() {
                    line(
                        &mut out,
                        None,
                        "PolyLineZ",
                        p.iter().map(|q| [q.x, q.y, q.z]).collect(),
                    )?;
                }
            }
            Shape::Polygon(g) => {
                for poly in polygons(g.rings(), |q| [q.x, q.y, nan]) {
                    let k = polygon_count;
                    polygon_count += 1;
                    for r in poly {
                        line(&mut out, Some(k), "Polygon", r)?;
                    }
                }
            }
            Shape::PolygonM(g) => {
                for poly in polygons(g.rings(), |q| [q.x, q.y, nan]) {
                    let k = polygon_count;
                    polygon_count += 1;
                    for r in poly {
                        line(&mut out, Some(k), "PolygonM", r)?;
                    }
                }
            }
            Shape::PolygonZ(g) => {
                for poly in polygons(g.rings(), |q| [q.x, q.y, q.z]) {
                    let k = polygon_count;
                    polygon_count += 1;
                    for r in poly {
                        line(&mut out, Some(k), "PolygonZ", r)?;
                    }
                }
            }
            Shape::Multipatch(_) => {
                return Err(format(
                    path,
                    format!("feature {feature}: a MultiPatch is neither a line nor a polygon"),
                ));
            }
        }
    }
    Ok(out)
}
