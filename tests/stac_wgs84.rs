//! `sweeptin index` writes STAC items whose `geometry` and `bbox` are WGS 84 longitude and
//! latitude, as RFC 7946 and STAC require (issue 41, item 20): they held the files' projected
//! coordinates. The reference values are PROJ 9's (pyproj 3.7, `Transformer.from_crs(code,
//! geodetic CRS, always_xy=True)`) for the header boxes' corners.

use crate::cli;
use crate::data;

use serde_json::Value;

/// The footprint's ring, its bbox and `proj:bbox` of the item whose id starts with `id`.
fn item<'a>(v: &'a Value, id: &str) -> &'a Value {
    v["features"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["id"].as_str().unwrap().starts_with(id))
        .unwrap()
}

fn close(got: &Value, want: [f64; 2]) {
    let g = [got[0].as_f64().unwrap(), got[1].as_f64().unwrap()];
    // 1e-8 degree is about a millimetre.
    assert!(
        (g[0] - want[0]).abs() < 1e-8 && (g[1] - want[1]).abs() < 1e-8,
        "{g:?}, PROJ gives {want:?}"
    );
}

#[test]
fn stac_geometry_and_bbox_are_wgs84_longitude_and_latitude() {
    let ign = data::shared("lidar/ign_test_semis_2023_0299_6802_LA93_IGN69.laz");
    let lidr = data::shared("lidar/lidR_Topography.laz");
    let arso = data::shared("lidar/arso_TM_511_122_sw_250m.laz");
    let t = tempfile::tempdir().unwrap();
    let vpc = t.path().join("i.vpc");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let o = cli::ok(&["index", &s(&ign), &s(&lidr), &s(&arso), "-o", &s(&vpc)]);
    let v: Value = serde_json::from_slice(&std::fs::read(&vpc).unwrap()).unwrap();

    // Lambert-93 (EPSG:2154, from the file's WKT): x 299000 .. 300000, y 6801000 .. 6802000.
    let i = item(&v, "ign_test");
    let ring = &i["geometry"]["coordinates"][0];
    assert_eq!(
        ring.as_array().unwrap().len(),
        33,
        "corners and points along the edges"
    );
    close(&ring[0], [-2.3999433488, 48.1859060875]);
    close(&ring[4], [-2.3932311859, 48.1862133266]);
    close(&ring[16], [-2.3874362965, 48.1954972242]);
    assert_eq!(ring[0], ring[32]);
    let b = i["bbox"].as_array().unwrap();
    assert!(
        (b[0].as_f64().unwrap() + 2.400862972213).abs() < 1e-8,
        "{b:?}"
    );
    assert!(
        (b[4].as_f64().unwrap() - 48.1954972242).abs() < 1e-8,
        "{b:?}"
    );
    assert_eq!(
        i["properties"]["proj:bbox"][0], 299000.0,
        "the projected extent is kept"
    );

    // MTM zone 7 (EPSG:2949, GeoTIFF keys): transverse Mercator. On NAD83(CSRS), PROJ's own
    // geographic CRS (to EPSG:4326 PROJ moves it by about 1 m, which sweeptin does not).
    let l = item(&v, "lidR");
    let ring = &l["geometry"]["coordinates"][0];
    close(&ring[0], [-70.9182237851, 47.6076167180]);
    close(&ring[4], [-70.9163237002, 47.6076236296]);
    close(&ring[16], [-70.9144439161, 47.6102003794]);

    // No CRS: no geometry and no bbox (never projected numbers there), and a warning.
    let a = item(&v, "arso");
    assert!(a["geometry"].is_null(), "{a}");
    assert!(a.get("bbox").is_none(), "{a}");
    assert_eq!(a["properties"]["proj:bbox"][0], 510999.945);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("arso_TM_511_122_sw_250m.laz") && err.contains("no CRS"),
        "{err}"
    );

    // The reader still places the files by their projected extent.
    let entries = sweeptin::input::las::vpc::read(&vpc).unwrap();
    assert_eq!(entries[0].bounds.min[0], 299000.0);
}
