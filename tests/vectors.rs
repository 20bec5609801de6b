//! Breaklines and polygons from GeoPackage, OGR-SQLite and Shapefile read as the GeoJSON of the
//! same features does (GDAL's `ogr2ogr` writes the copies), give the same mesh, and
//! `--clip-breaklines` cuts the BGT lines that run outside an AHN3 crop instead of stopping.

use crate::data;

use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::breaklines::{Lines, read_file};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The polylines, bit for bit (NaN z as one value).
fn key(l: &Lines) -> Vec<Vec<[u64; 3]>> {
    l.polylines
        .iter()
        .map(|p| {
            p.iter()
                .map(|v| v.map(|c| if c.is_nan() { u64::MAX } else { c.to_bits() }))
                .collect()
        })
        .collect()
}

fn ogr2ogr(format: &str, out: &Path, src: &Path) {
    let o = Command::new("ogr2ogr")
        .args(["-f", format, s(out), s(src)])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "ogr2ogr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The BGT road polygons (OGR-SQLite, WKB) read as GDAL's GeoJSON, GeoPackage and Shapefile
/// copies of them: the same polylines and CRS.
#[test]
fn sqlite_gpkg_shapefile_and_geojson_read_the_same_lines() {
    let test = "sqlite_gpkg_shapefile_and_geojson_read_the_same_lines";
    let sqlite = data::shared("lines/bgt_delft_sqlite/bgt_wegdeel.sqlite");
    let from_sqlite = read_file(&sqlite).unwrap();
    assert!(from_sqlite.len() >= 151, "{}", from_sqlite.len());
    assert_eq!(from_sqlite.crs.as_deref(), Some("EPSG:28992"));
    if !data::tool("ogr2ogr", test) {
        return;
    }
    let t = tempfile::tempdir().unwrap();
    let copies: Vec<(&str, PathBuf)> = vec![
        ("GeoJSON", t.path().join("roads.geojson")),
        ("GPKG", t.path().join("roads.gpkg")),
        ("ESRI Shapefile", t.path().join("roads.shp")),
    ];
    for (format, path) in &copies {
        ogr2ogr(format, path, &sqlite);
        let l = read_file(path).unwrap();
        assert_eq!(
            key(&l),
            key(&from_sqlite),
            "{format} copy reads differently"
        );
        // GDAL's .prj is ESRI WKT without an EPSG code: the Shapefile declares no code then.
        if *format != "ESRI Shapefile" {
            assert_eq!(l.crs, from_sqlite.crs, "{format} CRS");
        }
    }
}

/// Real GeoPackages: a file of several layers needs one named (the error lists them); the
/// ALSroads centreline equals its GeoJSON conversion.
#[test]
fn geopackage_layers() {
    let bubenec = data::shared("lines/momepy_bubenec.gpkg");
    let e = read_file(&bubenec).unwrap_err().to_string();
    assert!(
        e.contains("4 geometry layers") && e.contains("streets"),
        "{e}"
    );
    let streets = read_file(Path::new(&format!("{}:streets", s(&bubenec)))).unwrap();
    let json = read_file(&data::shared("lines/momepy_bubenec_streets.geojson")).unwrap();
    assert_eq!(streets.len(), 35);
    assert_eq!(key(&streets), key(&json));
    assert_eq!(streets.crs.as_deref(), Some("EPSG:3857"));
    let e = read_file(Path::new(&format!("{}:roads", s(&bubenec)))).unwrap_err();
    assert!(e.to_string().contains("no geometry layer \"roads\""), "{e}");
    let roads = data::shared("lines/alsroads_j5gr_centerline_971487.gpkg");
    let original = read_file(Path::new(&format!("{}:original", s(&roads)))).unwrap();
    let json = read_file(&data::shared(
        "lines/alsroads_j5gr_centerline_971487_original.geojson",
    ))
    .unwrap();
    assert_eq!(key(&original), key(&json));
    // Polygons for --trim-boundary / volume --boundary come through the same reader.
    let plots =
        sweeptin::input::geojson::read_polygons(Path::new(&format!("{}:plots", s(&bubenec))))
            .unwrap();
    assert_eq!(plots.len(), 407);
}

/// BGT roads over an AHN3 crop: they run far outside the points, so the run stops without
/// `--clip-breaklines` and, with it, warns and gives the same mesh from the OGR-SQLite layer and
/// its GeoPackage and Shapefile copies.
#[test]
fn clipped_breaklines_give_the_same_mesh_from_every_format() {
    let test = "clipped_breaklines_give_the_same_mesh_from_every_format";
    let laz = data::shared("lidar/ahn3_delft_cropped_1.laz");
    let sqlite = data::shared("lines/bgt_delft_sqlite/bgt_wegdeel.sqlite");
    let t = tempfile::tempdir().unwrap();
    let run = |lines: &Path, out: &Path, clip: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_sweeptin"));
        c.args([
            "tin",
            s(&laz),
            "--class",
            "2",
            "--bbox",
            "84800,447541,84900,447641",
        ]);
        c.args(["--breaklines", s(lines), "-o", s(out)]);
        if clip {
            c.arg("--clip-breaklines");
        }
        c.output().unwrap()
    };
    let o = run(&sqlite, &t.path().join("refused.ply"), false);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("clip it to the point cloud"));
    let mine = t.path().join("sqlite.ply");
    let o = run(&sqlite, &mine, true);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("--clip-breaklines cut"), "{err}");
    let want = std::fs::read(&mine).unwrap();
    if !data::tool("ogr2ogr", test) {
        return;
    }
    for (format, name) in [("GPKG", "roads.gpkg"), ("ESRI Shapefile", "roads.shp")] {
        let copy = t.path().join(name);
        ogr2ogr(format, &copy, &sqlite);
        let out = t.path().join(format!("{name}.ply"));
        let o = run(&copy, &out, true);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            std::fs::read(&out).unwrap() == want,
            "{format}: a different mesh"
        );
    }
}
