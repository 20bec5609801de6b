//! Interoperability of the terrain products with GDAL (Debian package `gdal-bin`): `gdalinfo`
//! reads the GeoTIFF's and the ASCII grid's origin, cell size, nodata and CRS, and the values sit at
//! the cell centres; `ogrinfo` reads the contours; `gdaldem hillshade` agrees with ours.
//!
//! Without the GDAL tool (`apt-get install -y gdal-bin`) each test fails under `CI=true`; locally
//! it is skipped with a message.

use crate::cli;
use crate::data;
use data::data_dir;

use serde_json::Value;
use std::path::Path;
use std::process::Command;

use cli::ok as sweeptin;

/// Runs a GDAL tool; `None` (and a message) when it is not installed.
fn gdal(tool: &str, args: &[&str]) -> Option<String> {
    match Command::new(tool).args(args).output() {
        Ok(o) => {
            assert!(
                o.status.success(),
                "{tool} {args:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            Some(String::from_utf8_lossy(&o.stdout).into_owned())
        }
        Err(_) => {
            // A test that did not run must not pass under CI.
            assert!(
                !data::in_ci(),
                "{tool} is required under CI=true (apt-get install -y gdal-bin)"
            );
            eprintln!("SKIPPED: {tool} not found (install GDAL: apt-get install -y gdal-bin)");
            None
        }
    }
}

fn plane(x: f64, y: f64) -> f64 {
    250.0 + 0.02 * (x - 511_000.0) - 0.05 * (y - 122_000.0)
}

/// Random points on a plane over [511000, 511100] × [122000, 122080], corners included.
fn write_plane_points(path: &Path) {
    let mut s = String::new();
    let mut r = 99u64;
    let mut next = || {
        r ^= r << 13;
        r ^= r >> 7;
        r ^= r << 17;
        (r % 1_000_000) as f64 / 1_000_000.0
    };
    let corners = [(0.0, 0.0), (100.0, 0.0), (0.0, 80.0), (100.0, 80.0)];
    let mut pts: Vec<(f64, f64)> = corners.to_vec();
    for _ in 0..3000 {
        pts.push((next() * 100.0, next() * 80.0));
    }
    for (dx, dy) in pts {
        let (x, y) = (511_000.0 + dx, 122_000.0 + dy);
        s.push_str(&format!("{x} {y} {}\n", plane(x, y)));
    }
    std::fs::write(path, s).unwrap();
}

fn geotransform(info: &Value) -> Vec<f64> {
    info["geoTransform"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

#[test]
fn geotiff_and_ascii_grid_read_by_gdal() {
    let dir = tempfile::tempdir().unwrap();
    let pts = dir.path().join("plane.xyz");
    write_plane_points(&pts);
    let tif = dir.path().join("dem.tif");
    let asc = dir.path().join("dem.asc");
    let p = |x: &Path| x.to_str().unwrap().to_string();
    for out in [&tif, &asc] {
        sweeptin(&[
            "dem",
            &p(&pts),
            "-o",
            &p(out),
            "--cell",
            "0.5",
            "--crs",
            "EPSG:3794",
            "-q",
        ]);
    }
    let Some(text) = gdal("gdalinfo", &["-json", &p(&tif)]) else {
        return;
    };
    let info: Value = serde_json::from_str(&text).unwrap();
    // Points from 511000 to 511100 and 122000 to 122080: cell edges on multiples of 0.5 (the
    // default alignment), so the grid covers exactly that box.
    assert_eq!(
        geotransform(&info),
        [511_000.0, 0.5, 0.0, 122_080.0, 0.0, -0.5]
    );
    assert_eq!(info["size"], serde_json::json!([200, 160]));
    assert_eq!(info["bands"][0]["noDataValue"].as_f64(), Some(-9999.0));
    assert_eq!(info["bands"][0]["type"], "Float32");
    let wkt = info["coordinateSystem"]["wkt"].as_str().unwrap();
    assert!(wkt.contains("ID[\"EPSG\",3794]"), "{wkt}");
    assert_eq!(info["metadata"][""]["AREA_OR_POINT"], "Area");
    // Values at cell centres (GDAL's pixel at a georeferenced point is the cell containing it).
    for (x, y) in [
        (511_000.25, 122_000.25),
        (511_037.75, 122_012.25),
        (511_099.75, 122_079.75),
    ] {
        let v = gdal(
            "gdallocationinfo",
            &[
                "-valonly",
                "-geoloc",
                &p(&tif),
                &x.to_string(),
                &y.to_string(),
            ],
        )
        .unwrap();
        let v: f64 = v.trim().parse().unwrap();
        assert!((v - plane(x, y)).abs() < 1e-4, "at ({x}, {y}): {v}");
    }
    let text = gdal("gdalinfo", &["-json", &p(&asc)]).unwrap();
    let info: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        geotransform(&info),
        [511_000.0, 0.5, 0.0, 122_080.0, 0.0, -0.5]
    );
    assert_eq!(info["bands"][0]["noDataValue"].as_f64(), Some(-9999.0));
}

#[test]
fn contours_read_by_ogrinfo() {
    let dir = tempfile::tempdir().unwrap();
    let pts = dir.path().join("plane.xyz");
    write_plane_points(&pts);
    let out = dir.path().join("c.geojson");
    let o = sweeptin(&[
        "contours",
        pts.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--interval",
        "0.5",
        "--crs",
        "EPSG:3794",
        "--json",
    ]);
    let summary: Value = serde_json::from_slice(&o.stdout).unwrap();
    let features = summary["contours"]["features"].as_u64().unwrap();
    assert!(features > 5);
    let Some(text) = gdal("ogrinfo", &["-so", "-al", out.to_str().unwrap()]) else {
        return;
    };
    assert!(
        text.contains(&format!("Feature Count: {features}")),
        "{text}"
    );
    assert!(text.contains("Line String"), "{text}");
    assert!(text.contains("elevation: Real"), "{text}");
    assert!(text.contains("3794") || text.contains("Slovene"), "{text}");
}

/// `-o c.gpkg` writes a GeoPackage that GDAL opens: one line layer in the data's CRS, every
/// feature with its elevation (contours could only be written as GeoJSON).
#[test]
fn contours_as_geopackage_read_by_ogrinfo() {
    let dir = tempfile::tempdir().unwrap();
    let laz = data_dir().join("lidar/lidR_Topography.laz");
    let out = dir.path().join("c.gpkg");
    let o = sweeptin(&[
        "contours",
        laz.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--interval",
        "5",
        "--min-length",
        "20",
        "--json",
    ]);
    let summary: Value = serde_json::from_slice(&o.stdout).unwrap();
    let features = summary["contours"]["features"].as_u64().unwrap();
    assert!(features > 100, "{features}");
    let Some(text) = gdal("ogrinfo", &["-al", "-q", out.to_str().unwrap()]) else {
        return;
    };
    let elevations: Vec<f64> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("elevation (Real) = "))
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(elevations.len() as u64, features, "{}", &text[..2000]);
    assert!(elevations.iter().all(|e| e % 5.0 == 0.0));
    assert_eq!(text.matches("LINESTRING (").count() as u64, features);
    let head = gdal("ogrinfo", &["-so", "-al", out.to_str().unwrap()]).unwrap();
    assert!(head.contains("using driver `GPKG'"), "{head}");
    assert!(head.contains("Line String"), "{head}");
    assert!(head.contains("MTM zone 7"), "the CRS (EPSG:2949): {head}");
}

/// Our hillshade against `gdaldem hillshade` on a real DEM: every cell where gdaldem computes a
/// value (it leaves the edges and the cells next to nodata out) agrees within one grey level.
#[test]
fn hillshade_agrees_with_gdaldem() {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("topo.tif");
    let laz = data_dir().join("lidar/lidR_Topography.laz");
    let png = dir.path().join("ours.png");
    sweeptin(&[
        "dem",
        laz.to_str().unwrap(),
        "-o",
        dem.to_str().unwrap(),
        "--class",
        "2",
        "--hillshade",
        png.to_str().unwrap(),
        "-q",
    ]);
    let theirs = dir.path().join("gdal.tif");
    if gdal(
        "gdaldem",
        &[
            "hillshade",
            "-q",
            dem.to_str().unwrap(),
            theirs.to_str().unwrap(),
        ],
    )
    .is_none()
    {
        return;
    }
    let mut d = tiff::decoder::Decoder::new(std::fs::File::open(&theirs).unwrap()).unwrap();
    let (w, h) = d.dimensions().unwrap();
    let tiff::decoder::DecodingResult::U8(g) = d.read_image().unwrap() else {
        panic!("gdaldem writes bytes");
    };
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    r.next_frame(&mut buf).unwrap();
    let (mut compared, mut off) = (0, 0);
    for i in 0..(w * h) as usize {
        if g[i] == 0 {
            continue;
        }
        compared += 1;
        let ours = buf[2 * i];
        assert_eq!(buf[2 * i + 1], 255);
        let diff = (i32::from(ours) - i32::from(g[i])).abs();
        assert!(diff <= 1, "pixel {i}: ours {ours}, gdaldem {}", g[i]);
        off += usize::from(diff > 0);
    }
    assert!(compared > 50_000, "{compared}");
    assert!(off * 100 < compared, "{off} of {compared} differ by one");
}

/// Issue 41, item 18: the `.prj` of a CRS known by its EPSG code alone (`--crs EPSG:…`, GeoTIFF
/// keys in a LAS header) was not written, and a hillshade PNG never had one: each is ESRI's
/// WKT1 as GDAL writes it, and GDAL reads the CRS back (from the PNG's `.aux.xml`).
#[test]
fn prj_of_an_epsg_code_is_written_and_read_by_gdal() {
    let dir = tempfile::tempdir().unwrap();
    let p = |x: &Path| x.to_str().unwrap().to_string();
    // ESRI's text for one or two codes of every family sweeptin spells, against GDAL's.
    for code in [
        4326, 4269, 4617, 6318, 4258, 4171, 4289, 4283, 7844, 4765, 32601, 32631, 32660, 32701,
        32755, 26901, 26915, 26923, 6328, 6329, 6330, 6348, 25828, 25832, 28348, 28355, 7846, 7859,
        2945, 2949, 2952, 3154, 2958, 3761, 3794, 2154, 2992, 28992, 3857, 7415,
    ] {
        let ours = ::sweeptin::crs::Crs {
            epsg: Some(code),
            ..Default::default()
        }
        .prj()
        .unwrap_or_else(|| panic!("EPSG:{code} not spelled"));
        let Some(theirs) = gdal(
            "gdalsrsinfo",
            &["-o", "wkt_esri", "--single-line", &format!("EPSG:{code}")],
        ) else {
            return;
        };
        assert_eq!(ours, theirs.trim(), "EPSG:{code}");
    }
    // --crs EPSG:3794 on an ASCII grid.
    let pts = dir.path().join("plane.xyz");
    write_plane_points(&pts);
    let asc = dir.path().join("dem.asc");
    sweeptin(&[
        "dem",
        &p(&pts),
        "-o",
        &p(&asc),
        "--cell",
        "0.5",
        "--crs",
        "EPSG:3794",
        "-q",
    ]);
    let info: Value =
        serde_json::from_str(&gdal("gdalinfo", &["-json", &p(&asc)]).unwrap()).unwrap();
    let wkt = info["coordinateSystem"]["wkt"].as_str().unwrap_or("");
    assert!(wkt.contains("Slovene National Grid"), "{info}");
    // GeoTIFF keys in the LAS header (EPSG:2949), an ASCII grid and a hillshade PNG.
    let laz = data_dir().join("lidar/lidR_Topography.laz");
    let (tif, asc, png) = (
        dir.path().join("t.tif"),
        dir.path().join("t.asc"),
        dir.path().join("h.png"),
    );
    sweeptin(&["dem", &p(&laz), "-o", &p(&asc), "-q"]);
    sweeptin(&[
        "dem",
        &p(&laz),
        "-o",
        &p(&tif),
        "--hillshade",
        &p(&png),
        "-q",
    ]);
    for f in [&asc, &png] {
        let text = gdal("gdalinfo", &["-json", &p(f)]).unwrap();
        let info: Value = serde_json::from_str(&text).unwrap();
        let wkt = info["coordinateSystem"]["wkt"].as_str().unwrap_or("");
        assert!(wkt.contains("MTM zone 7"), "{}: {info}", f.display());
    }
    let prj = std::fs::read_to_string(dir.path().join("h.prj")).unwrap();
    assert!(prj.starts_with("PROJCS[\"NAD_1983_CSRS_MTM_7\""), "{prj}");
    // A code sweeptin cannot spell: no .prj, and a warning that says so.
    let asc = dir.path().join("swiss.asc");
    let o = sweeptin(&[
        "dem",
        &p(&pts),
        "-o",
        &p(&asc),
        "--cell",
        "0.5",
        "--crs",
        "EPSG:2056",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!dir.path().join("swiss.prj").exists());
    assert_eq!(err.matches("no .prj is written").count(), 1, "{err}");
}

/// Issue 41, item 18: a run over points that declare no CRS says once that its outputs carry
/// none.
#[test]
fn outputs_without_a_crs_are_warned_of_once() {
    let dir = tempfile::tempdir().unwrap();
    let p = |x: &Path| x.to_str().unwrap().to_string();
    let pts = dir.path().join("plane.xyz");
    write_plane_points(&pts);
    let (tif, png, c) = (
        dir.path().join("d.tif"),
        dir.path().join("d.png"),
        dir.path().join("c.geojson"),
    );
    let o = sweeptin(&[
        "dem",
        &p(&pts),
        "-o",
        &p(&tif),
        "--hillshade",
        &p(&png),
        "--contours",
        &p(&c),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        err.matches("no coordinate reference system").count(),
        1,
        "{err}"
    );
    assert!(!dir.path().join("d.prj").exists());
    let o = sweeptin(&["hillshade", &p(&tif), "-o", &p(&dir.path().join("h.png"))]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        err.matches("no coordinate reference system").count(),
        1,
        "{err}"
    );
    // With the CRS, no warning.
    let o = sweeptin(&["dem", &p(&pts), "-o", &p(&tif), "--crs", "EPSG:3794"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("warning"), "{err}");
}

/// Mean grey level of an 8-bit GeoTIFF's cells with data (not 0).
fn mean_shade(path: &Path) -> f64 {
    let mut d = tiff::decoder::Decoder::new(std::fs::File::open(path).unwrap()).unwrap();
    let tiff::decoder::DecodingResult::U8(v) = d.read_image().unwrap() else {
        panic!("not 8-bit: {}", path.display());
    };
    let shaded: Vec<f64> = v
        .iter()
        .filter(|&&g| g > 0)
        .map(|&g| f64::from(g))
        .collect();
    shaded.iter().sum::<f64>() / shaded.len() as f64
}

/// Issue 41, item 19: a DEM in degrees (EPSG:4326) with heights in metres was shaded as if both
/// were one unit (dark and saturated): the metres a degree spans come from the CRS, as
/// `gdaldem hillshade -s 111120` does by hand; without a CRS, cells that look like degrees are
/// warned of.
#[test]
fn hillshade_of_a_geographic_dem_scales_degrees_to_metres() {
    let dir = tempfile::tempdir().unwrap();
    let p = |x: &Path| x.to_str().unwrap().to_string();
    let srtm = data_dir().join("dem/landlab_SRTMGL3_40.09_-105.55_40.21_-105.35.asc");
    let geo = dir.path().join("geo.tif");
    if gdal(
        "gdal_translate",
        &["-q", "-a_srs", "EPSG:4326", &p(&srtm), &p(&geo)],
    )
    .is_none()
    {
        return;
    }
    let (ours, theirs, flat) = (
        dir.path().join("ours.tif"),
        dir.path().join("theirs.tif"),
        dir.path().join("flat.tif"),
    );
    let o = sweeptin(&["hillshade", &p(&geo), "-o", &p(&ours)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("a geographic CRS: a degree taken as"), "{err}");
    gdal(
        "gdaldem",
        &["hillshade", "-q", "-s", "111120", &p(&geo), &p(&theirs)],
    )
    .unwrap();
    let (m_ours, m_theirs) = (mean_shade(&ours), mean_shade(&theirs));
    assert!((m_ours - m_theirs).abs() < 5.0, "{m_ours} vs {m_theirs}");
    // A z factor given by the user is taken as it is (and the scale with it: 1).
    sweeptin(&["hillshade", &p(&geo), "-o", &p(&flat), "--z-factor", "1"]);
    assert!(mean_shade(&flat) < m_theirs - 50.0, "{}", mean_shade(&flat));
    // --scale as gdaldem's -s.
    sweeptin(&["hillshade", &p(&geo), "-o", &p(&flat), "--scale", "111120"]);
    assert!((mean_shade(&flat) - m_theirs).abs() < 5.0);
    // The same grid with no CRS: a warning, once.
    let asc = dir.path().join("srtm.asc");
    std::fs::copy(&srtm, &asc).unwrap();
    let o = sweeptin(&["hillshade", &p(&asc), "-o", &p(&dir.path().join("s.tif"))]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.matches("look like degrees").count(), 1, "{err}");
    assert_eq!(err.matches("warning").count(), 1, "{err}");
}
