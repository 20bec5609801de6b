//! Virtual point clouds (`.vpc`): a list of LAS/LAZ/COPC files with their extents, point counts
//! and CRS, as written by PDAL wrench, lasR and QGIS and by `sweeptin index`.
//!
//! A `.vpc` is a STAC API ItemCollection (a GeoJSON FeatureCollection of STAC items) with the
//! pointcloud (`pc:count`) and projection (`proj:bbox`, `proj:wkt2`, `proj:epsg`) extensions; each
//! item's `data` asset names one file, relative to the `.vpc`'s folder (`./tile.laz`) or absolute.
//! A reader learns the files and their extents without opening them, so a run with a box never
//! opens the files outside it. The native extent is `proj:bbox` (3-D or 2-D), else `bbox`; it only
//! decides which files to open: a file opened counts with its own header's box (a list may be
//! stale, and a STAC `bbox` is in WGS84).
//!
//! The items sweeptin writes carry `geometry` and `bbox` in WGS 84 longitude and latitude, as
//! RFC 7946 and STAC require: the header box's corners and points along its edges through the
//! inverse projection of the file's CRS ([`Crs::wgs84_ring`]: UTM, national TM grids, Lambert-93;
//! datums taken as WGS 84, within about 1 m), `bbox` the box of that ring with the header's
//! heights. When the CRS is unknown or not one sweeptin can invert, `geometry` is null and
//! `bbox` left out (STAC's items without geometry), never projected numbers there.
//! `proj:bbox` and `proj:geometry`, which QGIS and wrench prefer, are the exact header box in the
//! file's own CRS.

use super::header::{Bounds3, FileInfo, format_error};
use crate::crs::Crs;
use crate::error::Result;
use crate::input::source;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

/// One file of a virtual point cloud.
#[derive(Clone, Debug, PartialEq)]
pub struct VpcEntry {
    /// The file (resolved against the `.vpc`'s folder).
    pub path: PathBuf,
    /// Its number of points (`pc:count`).
    pub points: u64,
    /// Its extent in its own CRS (`proj:bbox`; z is 0 when only 2-D is given).
    pub bounds: Bounds3,
    /// Its CRS (`proj:wkt2` or `proj:epsg`), when given.
    pub crs: Option<Crs>,
}

/// Is `path` a virtual point cloud (by its `.vpc` extension)?
pub fn is_vpc(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("vpc"))
}

/// A STAC ItemCollection.
#[derive(Debug, Serialize, Deserialize)]
pub struct ItemCollection {
    /// `FeatureCollection`.
    #[serde(rename = "type")]
    pub kind: String,
    /// One item per file.
    pub features: Vec<Item>,
}

/// A STAC item describing one point-cloud file.
#[derive(Debug, Serialize, Deserialize)]
pub struct Item {
    /// `Feature`.
    #[serde(rename = "type")]
    pub kind: String,
    /// `1.0.0`.
    #[serde(default)]
    pub stac_version: String,
    /// The pointcloud and projection extensions' schema addresses.
    #[serde(default)]
    pub stac_extensions: Vec<String>,
    /// The file's name without its extension.
    #[serde(default)]
    pub id: String,
    /// The extent as a WGS 84 polygon (null when the CRS cannot be inverted; module docs).
    #[serde(default)]
    pub geometry: Option<Polygon>,
    /// The WGS 84 extent, `[west, south, zmin, east, north, zmax]` (left out with `geometry`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bbox: Option<Vec<f64>>,
    /// The extensions' fields.
    pub properties: Properties,
    /// No links.
    #[serde(default)]
    pub links: Vec<serde_json::Map<String, serde_json::Value>>,
    /// `data`: the file.
    pub assets: BTreeMap<String, Asset>,
}

/// A GeoJSON polygon.
#[derive(Debug, Serialize, Deserialize)]
pub struct Polygon {
    /// `Polygon`.
    #[serde(rename = "type")]
    pub kind: String,
    /// One ring.
    pub coordinates: Vec<Vec<[f64; 2]>>,
}

/// The properties of an item.
#[derive(Debug, Serialize, Deserialize)]
pub struct Properties {
    /// Acquisition date (the header's creation date), or null.
    pub datetime: Option<String>,
    /// Number of points.
    #[serde(rename = "pc:count")]
    pub count: u64,
    /// `lidar`.
    #[serde(rename = "pc:type", default)]
    pub kind: String,
    /// The file's format, e.g. `LAZ 1.4 point format 8`.
    #[serde(rename = "pc:encoding", default)]
    pub encoding: String,
    /// The point record's dimensions.
    #[serde(rename = "pc:schemas", default)]
    pub schemas: Vec<Dimension>,
    /// The extent in the file's CRS.
    #[serde(rename = "proj:bbox", default)]
    pub proj_bbox: Option<Vec<f64>>,
    /// The extent as a polygon in the file's CRS.
    #[serde(rename = "proj:geometry", default)]
    pub proj_geometry: Option<Polygon>,
    /// The CRS as WKT (empty when unknown, as wrench writes it).
    #[serde(rename = "proj:wkt2", default, skip_serializing_if = "Option::is_none")]
    pub wkt2: Option<String>,
    /// The horizontal CRS's EPSG code, when known.
    #[serde(rename = "proj:epsg", default, skip_serializing_if = "Option::is_none")]
    pub epsg: Option<u32>,
}

/// One dimension of the point record (PDAL's names).
#[derive(Debug, Serialize, Deserialize)]
pub struct Dimension {
    /// e.g. `Classification`.
    pub name: String,
    /// `floating`, `signed` or `unsigned`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Bytes.
    pub size: u32,
}

/// An asset: the file.
#[derive(Debug, Serialize, Deserialize)]
pub struct Asset {
    /// The file, relative to the `.vpc` (`./x.laz`) or absolute.
    pub href: String,
    /// `data`.
    #[serde(default)]
    pub roles: Vec<String>,
}

/// Reads the files a `.vpc` lists, in its order.
///
/// # Errors
/// [`crate::Error::Io`] if it cannot be read; [`crate::Error::Format`] if it is not a STAC
/// ItemCollection of point-cloud items, or an item lacks its count, extent or data file, or
/// names a URL of another scheme than `http`, `https` or `s3`. A remote `.vpc`'s relative paths
/// are URLs beside it.
pub fn read(path: &Path) -> Result<Vec<VpcEntry>> {
    let text = crate::input::source::read_to_string(path)?;
    let c: ItemCollection = serde_json::from_str(&text).map_err(|e| {
        format_error(
            path,
            format!("not a virtual point cloud (a STAC ItemCollection): {e}"),
        )
    })?;
    if c.kind != "FeatureCollection" {
        return Err(format_error(
            path,
            format!("its type is {:?}, not \"FeatureCollection\"", c.kind),
        ));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    c.features
        .into_iter()
        .enumerate()
        .map(|(i, item)| entry(path, dir, i, item))
        .collect()
}

fn entry(path: &Path, dir: &Path, i: usize, item: Item) -> Result<VpcEntry> {
    let bad = |what: &str| format_error(path, format!("item {i} ({:?}): {what}", item.id));
    let asset = item
        .assets
        .values()
        .find(|a| a.roles.iter().any(|r| r == "data"))
        .or_else(|| item.assets.get("data"))
        .or_else(|| {
            item.assets
                .values()
                .next()
                .filter(|_| item.assets.len() == 1)
        })
        .ok_or_else(|| bad("no data asset"))?;
    let href = asset.href.as_str();
    let file = if source::is_remote(Path::new(href)) {
        PathBuf::from(href)
    } else if href.contains("://") {
        return Err(bad(&format!(
            "{href}: only http://, https:// and s3:// URLs and local files are read"
        )));
    } else {
        let file = Path::new(href.strip_prefix("./").unwrap_or(href));
        if file.is_absolute() {
            file.to_path_buf()
        } else {
            source::beside(dir, href)
        }
    };
    let b = item
        .properties
        .proj_bbox
        .as_ref()
        .or(item.bbox.as_ref())
        .ok_or_else(|| bad("no proj:bbox nor bbox"))?;
    let bounds = match b.as_slice() {
        [x0, y0, z0, x1, y1, z1] => Bounds3 {
            min: [*x0, *y0, *z0],
            max: [*x1, *y1, *z1],
        },
        [x0, y0, x1, y1] => Bounds3 {
            min: [*x0, *y0, 0.0],
            max: [*x1, *y1, 0.0],
        },
        _ => return Err(bad("its bbox has neither 4 nor 6 numbers")),
    };
    let p = &item.properties;
    let crs = match (&p.wkt2, p.epsg) {
        (Some(w), _) if !w.trim().is_empty() => Crs::from_wkt_bytes(w.as_bytes()),
        (_, Some(code)) => Some(Crs {
            epsg: Some(code),
            ..Crs::default()
        }),
        _ => None,
    };
    Ok(VpcEntry {
        path: file,
        points: p.count,
        bounds,
        crs,
    })
}

/// Points along each edge of a footprint in degrees (the edges of a projected box are curves).
const FOOTPRINT_EDGE_POINTS: usize = 8;

/// The STAC item of a file, with its path relative to `dir` (the `.vpc`'s folder) when that is
/// possible. Its `geometry` and `bbox` are `None` when the file's CRS cannot be turned into WGS
/// 84 (see the module docs).
pub fn item(info: &FileInfo, dir: &Path) -> Item {
    // A file without points may have any box; a `.vpc` holds numbers (never a NaN's null).
    let none = super::Bounds3 {
        min: [0.0; 3],
        max: [0.0; 3],
    };
    let b = if info.bounds.usable() {
        &info.bounds
    } else {
        &none
    };
    let rect = [b.min[0], b.min[1], b.max[0], b.max[1]];
    let ring = vec![
        [rect[0], rect[1]],
        [rect[2], rect[1]],
        [rect[2], rect[3]],
        [rect[0], rect[3]],
        [rect[0], rect[1]],
    ];
    let polygon = || Polygon {
        kind: "Polygon".into(),
        coordinates: vec![ring.clone()],
    };
    let bbox = vec![b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]];
    let footprint = info
        .crs
        .as_ref()
        .and_then(|c| c.wgs84_ring(rect, FOOTPRINT_EDGE_POINTS));
    let wgs84_bbox = footprint.as_ref().map(|ring| {
        let (mut w, mut s, mut e, mut n) =
            (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
        for p in ring {
            (w, s, e, n) = (w.min(p[0]), s.min(p[1]), e.max(p[0]), n.max(p[1]));
        }
        vec![w, s, b.min[2], e, n, b.max[2]]
    });
    let geometry = footprint.map(|ring| Polygon {
        kind: "Polygon".into(),
        coordinates: vec![ring],
    });
    let href = href(&info.path, dir);
    let id = info
        .path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let id = id
        .strip_suffix(".copc.laz")
        .or_else(|| id.rsplit_once('.').map(|(s, _)| s))
        .unwrap_or(&id)
        .to_string();
    Item {
        kind: "Feature".into(),
        stac_version: "1.0.0".into(),
        stac_extensions: vec![
            "https://stac-extensions.github.io/pointcloud/v1.0.0/schema.json".into(),
            "https://stac-extensions.github.io/projection/v1.1.0/schema.json".into(),
        ],
        id,
        geometry,
        bbox: wgs84_bbox,
        properties: Properties {
            datetime: info.creation.and_then(|(d, y)| date(y, d)),
            count: info.point_count,
            kind: "lidar".into(),
            encoding: format!(
                "{} {}.{} point format {}",
                if info.copc.is_some() {
                    "COPC"
                } else if info.compressed {
                    "LAZ"
                } else {
                    "LAS"
                },
                info.version.0,
                info.version.1,
                info.point_format
            ),
            schemas: schema(info.point_format),
            proj_bbox: Some(bbox),
            proj_geometry: Some(polygon()),
            wkt2: Some(
                info.crs
                    .as_ref()
                    .and_then(|c| c.wkt.clone())
                    .unwrap_or_default(),
            ),
            epsg: info.crs.as_ref().and_then(|c| c.epsg),
        },
        links: Vec::new(),
        assets: BTreeMap::from([(
            "data".to_string(),
            Asset {
                href,
                roles: vec!["data".into()],
            },
        )]),
    }
}

/// How an item names `path` from a `.vpc` in `dir`, as PDAL wrench and QGIS write and read it:
/// a remote file (`s3://`, `http(s)://`) by its full URL, whatever the `.vpc`'s place (a
/// reader resolves no `..` in a URL, and a `.vpc` copied elsewhere still finds it); a local file
/// by its path relative to a local `dir` (`./tile.laz`, `./../x/tile.laz`), or absolute when the
/// `.vpc` is remote or on another root.
fn href(path: &Path, dir: &Path) -> String {
    if source::is_remote(path) {
        return path.display().to_string();
    }
    let rel = (!source::is_remote(dir))
        .then(|| relative(path, dir))
        .flatten();
    match rel {
        Some(r) => format!("./{}", r.display()),
        None => std::path::absolute(path)
            .unwrap_or_else(|_| path.to_path_buf())
            .display()
            .to_string(),
    }
}

/// `path` relative to `dir`, when both are absolute-able and share a root.
fn relative(path: &Path, dir: &Path) -> Option<PathBuf> {
    let p = std::path::absolute(path).ok()?;
    let d = std::path::absolute(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    })
    .ok()?;
    fn norm(p: &Path) -> Vec<Component<'_>> {
        p.components()
            .filter(|c| !matches!(c, Component::CurDir))
            .collect()
    }
    let (pc, dc) = (norm(&p), norm(&d));
    if pc.first() != dc.first() {
        return None;
    }
    let common = pc.iter().zip(&dc).take_while(|(a, b)| a == b).count();
    let mut r = PathBuf::new();
    for _ in common..dc.len() {
        r.push("..");
    }
    for c in &pc[common..] {
        r.push(c.as_os_str());
    }
    Some(r)
}

/// `YYYY-MM-DDT00:00:00Z` of a day of the year (1-based), when valid.
fn date(year: u16, day: u16) -> Option<String> {
    let leap = (year.is_multiple_of(4) && !year.is_multiple_of(100)) || year.is_multiple_of(400);
    let months = [
        31,
        if leap { 29 } else { 28 },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    let mut d = day;
    if !(1..=(365 + u16::from(leap))).contains(&d) || year < 1900 {
        return None;
    }
    for (m, len) in months.iter().enumerate() {
        if d <= *len {
            return Some(format!("{year:04}-{:02}-{d:02}T00:00:00Z", m + 1));
        }
        d -= len;
    }
    None
}

/// The dimensions of a point format, with PDAL's names and types.
fn schema(format: u8) -> Vec<Dimension> {
    let d = |name: &str, kind: &str, size: u32| Dimension {
        name: name.into(),
        kind: kind.into(),
        size,
    };
    let extended = format >= 6;
    let mut v = vec![
        d("X", "floating", 8),
        d("Y", "floating", 8),
        d("Z", "floating", 8),
        d("Intensity", "unsigned", 2),
        d("ReturnNumber", "unsigned", 1),
        d("NumberOfReturns", "unsigned", 1),
        d("ScanDirectionFlag", "unsigned", 1),
        d("EdgeOfFlightLine", "unsigned", 1),
        d("Classification", "unsigned", 1),
        d("Synthetic", "unsigned", 1),
        d("KeyPoint", "unsigned", 1),
        d("Withheld", "unsigned", 1),
    ];
    if extended {
        v.push(d("Overlap", "unsigned", 1));
        v.push(d("ScanChannel", "unsigned", 1));
        v.push(d("ScanAngleRank", "floating", 4));
    } else {
        v.push(d("ScanAngleRank", "floating", 4));
    }
    v.push(d("UserData", "unsigned", 1));
    v.push(d("PointSourceId", "unsigned", 2));
    if format != 0 && format != 2 {
        v.push(d("GpsTime", "floating", 8));
    }
    if matches!(format, 2 | 3 | 5 | 7 | 8 | 10) {
        for c in ["Red", "Green", "Blue"] {
            v.push(d(c, "unsigned", 2));
        }
    }
    if matches!(format, 8 | 10) {
        v.push(d("Infrared", "unsigned", 2));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_and_relative_paths() {
        assert_eq!(date(2022, 184).as_deref(), Some("2022-07-03T00:00:00Z"));
        assert_eq!(date(2024, 60).as_deref(), Some("2024-02-29T00:00:00Z"));
        assert_eq!(date(2023, 366), None);
        assert_eq!(date(0, 1), None);
        assert_eq!(
            relative(Path::new("/a/b/c.laz"), Path::new("/a/b")),
            Some(PathBuf::from("c.laz"))
        );
        assert_eq!(
            relative(Path::new("/a/x/c.laz"), Path::new("/a/b")),
            Some(PathBuf::from("../x/c.laz"))
        );
        // Remote files by their full URL, wherever the `.vpc` is; local ones relative to a
        // local `.vpc`, absolute from a remote one.
        let h = |p: &str, d: &str| href(Path::new(p), Path::new(d));
        assert_eq!(h("s3://bkt/t/a.laz", "/out"), "s3://bkt/t/a.laz");
        assert_eq!(h("s3://bkt/t/a.laz", "s3://bkt/t"), "s3://bkt/t/a.laz");
        assert_eq!(h("s3://bkt/t/a.laz", "s3://bkt/u"), "s3://bkt/t/a.laz");
        assert_eq!(h("https://h/t/a.laz", ""), "https://h/t/a.laz");
        assert_eq!(h("/a/b/c.laz", "/a/b"), "./c.laz");
        assert_eq!(h("/a/x/c.laz", "/a/b"), "./../x/c.laz");
        assert_eq!(h("/a/b/c.laz", "s3://bkt/u"), "/a/b/c.laz");
        assert_eq!(schema(1).len(), 16);
        assert_eq!(schema(8).last().map(|d| d.name.as_str()), Some("Infrared"));
    }

    #[test]
    fn reads_wrench_style_items() {
        let dir = tempfile::tempdir().unwrap();
        let vpc = dir.path().join("t.vpc");
        let text = r#"{"type":"FeatureCollection","features":[
          {"type":"Feature","stac_version":"1.0.0","id":"a","geometry":null,
           "bbox":[1,2,3,4,5,6],
           "properties":{"datetime":null,"pc:count":10,"proj:bbox":[10,20,1,30,40,2],
                         "proj:wkt2":"","proj:epsg":2154},
           "assets":{"data":{"href":"./sub/a.laz","roles":["data"]}}},
          {"type":"Feature","stac_version":"1.0.0","id":"b",
           "properties":{"datetime":null,"pc:count":0,"proj:bbox":[0,0,1,1]},
           "assets":{"x":{"href":"/abs/b.copc.laz"}}}]}"#;
        std::fs::write(&vpc, text).unwrap();
        let e = read(&vpc).unwrap();
        assert_eq!(e[0].path, dir.path().join("sub/a.laz"));
        assert_eq!(e[0].points, 10);
        assert_eq!(e[0].bounds.max, [30.0, 40.0, 2.0]);
        assert_eq!(e[0].crs.as_ref().and_then(|c| c.epsg), Some(2154));
        assert_eq!(e[1].path, PathBuf::from("/abs/b.copc.laz"));
        assert_eq!(e[1].bounds.min, [0.0, 0.0, 0.0]);
        std::fs::write(
            &vpc,
            r#"{"type":"FeatureCollection","features":[{"type":"Feature",
            "properties":{"pc:count":1,"proj:bbox":[0,0,1,1]},
            "assets":{"data":{"href":"https://x/a.laz"}}}]}"#,
        )
        .unwrap();
        assert_eq!(
            read(&vpc).unwrap()[0].path,
            PathBuf::from("https://x/a.laz")
        );
        std::fs::write(
            &vpc,
            r#"{"type":"FeatureCollection","features":[{"type":"Feature",
            "properties":{"pc:count":1,"proj:bbox":[0,0,1,1]},
            "assets":{"data":{"href":"ftp://x/a.laz"}}}]}"#,
        )
        .unwrap();
        assert!(read(&vpc).unwrap_err().to_string().contains("s3://"));
        std::fs::write(&vpc, "[]").unwrap();
        assert!(read(&vpc).unwrap_err().to_string().contains("STAC"));
    }
}
