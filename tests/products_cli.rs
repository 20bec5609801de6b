//! The terrain-product commands end to end: tiles that mosaic exactly into the single run's
//! raster (real LAS data), several products in one pass equal to the separate commands, volumes
//! from the command line, and clear errors.

use crate::data;
use data::data_dir;

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(args: &[&str]) -> Output {
    let o = run(args);
    assert!(
        o.status.success(),
        "sweeptin {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `(cols, rows, values)` of a float32 TIFF.
fn read_tiff(path: &Path) -> (usize, usize, Vec<f32>) {
    let mut d = tiff::decoder::Decoder::new(std::fs::File::open(path).unwrap()).unwrap();
    let (w, h) = d.dimensions().unwrap();
    let tiff::decoder::DecodingResult::F32(v) = d.read_image().unwrap() else {
        panic!("{} is not float32", path.display());
    };
    (w as usize, h as usize, v)
}

/// A real AHN3 tile (ground points) split into two tiles at x = 84900, each rasterised with
/// `--bbox` and a 40 m buffer: the two rasters side by side are the single run's raster, bit for
/// bit.
#[test]
fn tiles_mosaic_equals_the_single_run() {
    let laz = data_dir().join("lidar/ahn3_delft_cropped_1.laz");
    let dir = tempfile::tempdir().unwrap();
    let (full, a, b) = (
        dir.path().join("full.tif"),
        dir.path().join("a.tif"),
        dir.path().join("b.tif"),
    );
    let common = ["--class", "2", "--buffer", "40", "-q"];
    for (out, bbox) in [
        (&full, "84810,447415,84990,447640"),
        (&a, "84810,447415,84900,447640"),
        (&b, "84900,447415,84990,447640"),
    ] {
        let mut args = vec!["dem", s(&laz), "-o", s(out), "--bbox", bbox];
        args.extend_from_slice(&common);
        ok(&args);
    }
    let (fw, fh, f) = read_tiff(&full);
    let (aw, ah, av) = read_tiff(&a);
    let (bw, bh, bv) = read_tiff(&b);
    assert_eq!((fw, fh), (180, 225));
    assert_eq!((aw, ah, bw, bh), (90, 225, 90, 225));
    let mut with_data = 0;
    for row in 0..fh {
        for col in 0..fw {
            let tile = if col < aw {
                av[row * aw + col]
            } else {
                bv[row * bw + col - aw]
            };
            let single = f[row * fw + col];
            assert_eq!(tile.to_bits(), single.to_bits(), "row {row}, column {col}");
            with_data += usize::from(single != -9999.0);
        }
    }
    assert!(with_data > 40_000, "{with_data}");
}

fn write_points(path: &Path, f: impl Fn(f64, f64) -> f64, seed: u64) {
    let mut r = seed;
    let mut next = || {
        r ^= r << 13;
        r ^= r >> 7;
        r ^= r << 17;
        (r % 1_000_000) as f64 / 1_000_000.0
    };
    let mut text = String::new();
    let mut pts = vec![(0.0, 0.0), (60.0, 0.0), (0.0, 40.0), (60.0, 40.0)];
    for _ in 0..1500 {
        pts.push((next() * 60.0, next() * 40.0));
    }
    for (x, y) in pts {
        text.push_str(&format!("{x},{y},{}\n", f(x, y)));
    }
    std::fs::write(path, text).unwrap();
}

fn bumps(x: f64, y: f64) -> f64 {
    10.0 + 3.0 * (x / 7.0).sin() * (y / 5.0).cos()
}

/// `sweeptin products` writes, in one pass, the same files as the single-product commands.
#[test]
fn one_pass_products_equal_separate_commands() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let pts = d("pts.xyz");
    write_points(&pts, bumps, 7);
    std::fs::write(d("q.csv"), "x,y,id\n1,1,a\n30.5,20.25,b\n70,10,c\n").unwrap();
    std::fs::write(
        d("road.geojson"),
        r#"{"type":"LineString","coordinates":[[-5,3],[30,20],[59,39]]}"#,
    )
    .unwrap();
    std::fs::write(
        d("area.geojson"),
        r#"{"type":"Polygon","coordinates":[[[5,5],[50,5],[50,35],[5,35],[5,5]]]}"#,
    )
    .unwrap();
    let o = ok(&[
        "products",
        s(&pts),
        "--dem",
        s(&d("all.tif")),
        "--cell",
        "0.5",
        "--contours",
        s(&d("all.geojson")),
        "--interval",
        "0.5",
        "--volume-plane",
        "10",
        "--boundary",
        s(&d("area.geojson")),
        "--sample-points",
        s(&d("q.csv")),
        "--sample-out",
        s(&d("all_q.csv")),
        "--profile-line",
        s(&d("road.geojson")),
        "--profile-out",
        s(&d("all_p.csv")),
        "--mesh",
        s(&d("all.ply")),
        "--json",
    ]);
    let all: Value = serde_json::from_slice(&o.stdout).unwrap();
    ok(&[
        "dem",
        s(&pts),
        "-o",
        s(&d("dem.tif")),
        "--cell",
        "0.5",
        "-q",
    ]);
    ok(&[
        "contours",
        s(&pts),
        "-o",
        s(&d("c.geojson")),
        "--interval",
        "0.5",
        "-q",
    ]);
    ok(&[
        "sample",
        s(&pts),
        "--points",
        s(&d("q.csv")),
        "-o",
        s(&d("q_out.csv")),
        "-q",
    ]);
    ok(&[
        "profile",
        s(&pts),
        "--line",
        s(&d("road.geojson")),
        "-o",
        s(&d("p.csv")),
        "-q",
    ]);
    let v = ok(&[
        "volume",
        s(&pts),
        "--plane",
        "10",
        "--boundary",
        s(&d("area.geojson")),
        "--json",
    ]);
    let vol: Value = serde_json::from_slice(&v.stdout).unwrap();
    let same = |a: &str, b: &str| {
        assert_eq!(
            std::fs::read(d(a)).unwrap(),
            std::fs::read(d(b)).unwrap(),
            "{a} vs {b}"
        )
    };
    same("all.tif", "dem.tif");
    same("all.geojson", "c.geojson");
    same("all_q.csv", "q_out.csv");
    same("all_p.csv", "p.csv");
    for k in ["cut_volume", "fill_volume", "cut_area", "fill_area", "area"] {
        assert_eq!(all["volume"][k], vol[k], "{k}");
    }
    assert!((vol["area"].as_f64().unwrap() - 1350.0).abs() < 1e-9);
    assert_eq!(all["mesh"]["triangles"], all["run"]["triangles"]);
    let q = std::fs::read_to_string(d("q_out.csv")).unwrap();
    let lines: Vec<&str> = q.lines().collect();
    assert_eq!(lines[0], "x,y,id,z");
    assert!(lines[3].ends_with("c,"), "outside → empty: {q}");
}

/// Volumes from the command line against a plane and against a second surface (planes on
/// different point sets: exact answers).
#[test]
fn volume_against_plane_and_surface() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.xyz");
    let b = dir.path().join("b.xyz");
    write_points(&a, |x, y| 0.1 * x + 0.2 * y, 3);
    write_points(&b, |x, _| 0.1 * x + 1.0, 4);
    let o = ok(&["volume", s(&a), "--plane", "2", "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    // d = 0.1x + 0.2y − 2 over [0,60]×[0,40]: ∫ = 2400 × (3 + 4 − 2) = 12000.
    let net = v["net_volume"].as_f64().unwrap();
    assert!((net - 12_000.0).abs() < 1e-6, "{v}");
    let o = ok(&["volume", s(&a), "--surface", s(&b), "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    // d = 0.2y − 1: fill for y < 5 (60 × 5 × 0.5 = 150), cut for y > 5 (60 × 35 × 3.5 = 7350).
    let f = |k: &str| v[k].as_f64().unwrap();
    assert!((f("cut_volume") - 7350.0).abs() < 1e-6, "{v}");
    assert!((f("fill_volume") - 150.0).abs() < 1e-6, "{v}");
    assert!((f("cut_area") - 2100.0).abs() < 1e-6, "{v}");
    assert!((f("fill_area") - 300.0).abs() < 1e-6, "{v}");
    let text = ok(&["volume", s(&a), "--plane", "2"]);
    let out = String::from_utf8_lossy(&text.stdout);
    assert!(out.contains("net volume   12000.000"), "{out}");
}

/// DSM minus DTM from one LAS file with a filter per surface (`--returns first` for the
/// surface, `--surface-class 2` for the reference): `--surface-class` did not exist, and the
/// reference took the input's filters, so this took two `.stin` files. The volumes are those of
/// the two-`.stin` route, bit for bit.
#[test]
fn volume_with_a_filter_per_surface_equals_the_two_stin_route() {
    let laz = data_dir().join("lidar/arso_TM_511_122_sw_250m.laz");
    let t = tempfile::tempdir().unwrap();
    let bbox = "511050,122050,511130,122130";
    let o = ok(&[
        "volume",
        s(&laz),
        "--bbox",
        bbox,
        "--returns",
        "first",
        "--surface",
        s(&laz),
        "--surface-class",
        "2",
        "--json",
    ]);
    let direct: Value = serde_json::from_slice(&o.stdout).unwrap();
    let (dsm, dtm) = (t.path().join("dsm.stin"), t.path().join("dtm.stin"));
    ok(&[
        "tin",
        s(&laz),
        "--bbox",
        bbox,
        "--returns",
        "first",
        "-o",
        s(&dsm),
        "-q",
    ]);
    ok(&[
        "tin",
        s(&laz),
        "--bbox",
        bbox,
        "--class",
        "2",
        "-o",
        s(&dtm),
        "-q",
    ]);
    let o = ok(&["volume", s(&dsm), "--surface", s(&dtm), "--json"]);
    let two: Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in [
        "cut_volume",
        "fill_volume",
        "net_volume",
        "cut_area",
        "fill_area",
        "area",
    ] {
        assert!(direct[k].is_f64());
        assert_eq!(direct[k], two[k], "{k}: {direct} vs {two}");
    }
    // Vegetation and buildings stand above the ground.
    assert!(direct["cut_volume"].as_f64().unwrap() > 1000.0, "{direct}");
    // A surface filter without a surface is a usage error.
    let o = run(&["volume", s(&laz), "--plane", "0", "--surface-class", "2"]);
    assert_eq!(o.status.code(), Some(2));
}

/// Two surfaces that agree except in a raised patch: where they agree there is no cut and no
/// fill (the planes' rounding made ±1e-16 differences that counted 10 % of the area as cut and
/// as fill, and any level piece counted as fill); a surface against itself gives zeros.
#[test]
fn volume_areas_count_only_where_the_surfaces_differ() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.xyz");
    let b = dir.path().join("b.xyz");
    write_points(&a, bumps, 1);
    let patch = |x: f64, y: f64| (20.0..30.0).contains(&x) && (10.0..20.0).contains(&y);
    write_points(
        &b,
        |x, y| bumps(x, y) + if patch(x, y) { 1.0 } else { 0.0 },
        1,
    );
    let volume = |top: &Path, base: &Path| -> Value {
        let o = ok(&["volume", s(top), "--surface", s(base), "--json"]);
        serde_json::from_slice(&o.stdout).unwrap()
    };
    // Zero but for the slivers where triangles of the two surfaces meet at a vertex, whose
    // corners are computed crossings (1e-31 here; it was 10 % of the area).
    let nothing = |v: &Value, k: &str| assert!(v[k].as_f64().unwrap() < 1e-12, "{k}: {v}");
    let v = volume(&a, &a);
    for k in ["cut_volume", "fill_volume", "cut_area", "fill_area"] {
        nothing(&v, k);
    }
    assert!((v["area"].as_f64().unwrap() - 2400.0).abs() < 1e-9, "{v}");
    let v = volume(&b, &a);
    nothing(&v, "fill_area");
    nothing(&v, "fill_volume");
    // The patch (100) and the ring of triangles around it, far from the 2400 covered.
    let cut = v["cut_area"].as_f64().unwrap();
    assert!((100.0..200.0).contains(&cut), "{v}");
}

/// A line whose first vertex is repeated (digitised lines often are) has a height there: the
/// first row was empty ("outside the TIN") where `sample` gives one. A line of no length is
/// refused, naming it.
#[test]
fn profile_heights_at_repeated_vertices() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    write_points(&d("p.xyz"), bumps, 1);
    let line = |name: &str, coords: &str| {
        std::fs::write(
            d(name),
            format!(r#"{{"type":"LineString","coordinates":{coords}}}"#),
        )
        .unwrap();
    };
    line("rep.geojson", "[[10,10],[10,10],[20,20],[30,10]]");
    line("one.geojson", "[[10,10],[20,20],[30,10]]");
    let profile = |l: &str, out: &str| {
        ok(&[
            "profile",
            s(&d("p.xyz")),
            "--line",
            s(&d(l)),
            "-o",
            s(&d(out)),
            "-q",
        ]);
        std::fs::read_to_string(d(out)).unwrap()
    };
    let rep = profile("rep.geojson", "rep.csv");
    assert_eq!(rep, profile("one.geojson", "one.csv"));
    assert!(!rep.lines().nth(1).unwrap().ends_with(','), "{rep}");
    line("dot.geojson", "[[10,10],[10,10]]");
    let o = run(&[
        "profile",
        s(&d("p.xyz")),
        "--line",
        s(&d("dot.geojson")),
        "-o",
        s(&d("x.csv")),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no length"));
    assert!(!d("x.csv").exists());
}

#[test]
fn clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let pts = dir.path().join("p.xyz");
    write_points(&pts, bumps, 1);
    let out = dir.path().join("d.tif");
    let o = run(&["dem", s(&pts), "-o", s(&out), "--bbox", "0.3,0,10,10", "-q"]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--snap") && e.contains("0.3"), "{e}");
    ok(&[
        "dem",
        s(&pts),
        "-o",
        s(&out),
        "--bbox",
        "0.3,0,10,10",
        "--snap",
        "-q",
    ]);
    let (w, h, _) = read_tiff(&out);
    assert_eq!((w, h), (10, 10));
    let o = run(&["dem", s(&pts), "-o", "/no/such/dir/d.tif", "-q"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("/no/such/dir") && e.contains("does not exist"),
        "{e}"
    );
    let bad = dir.path().join("bad.geojson");
    std::fs::write(&bad, r#"{"type":"Polygon","coordinates":[[[0,0],[1,1]]]}"#).unwrap();
    let o = run(&["volume", s(&pts), "--plane", "0", "--boundary", s(&bad)]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("bad.geojson") && e.contains("fewer than 3"),
        "{e}"
    );
    let o = run(&["volume", s(&pts)]);
    assert_eq!(o.status.code(), Some(2));
    let asc = dir.path().join("d.asc");
    let png = dir.path().join("s.png");
    let o = run(&["dem", s(&pts), "-o", s(&asc), "--hillshade", s(&png), "-q"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("GeoTIFF") && !asc.exists(), "{e}");
}

/// A streaming mesh written by `sweeptin tin` gives the same products as the points themselves
/// (the mesh is replayed into the sinks, with its CRS).
#[test]
fn streaming_mesh_input_gives_the_same_products() {
    let laz = data_dir().join("lidar/lidR_Topography.laz");
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    ok(&["tin", s(&laz), "--class", "2", "-o", s(&d("t.stin")), "-q"]);
    ok(&["dem", s(&d("t.stin")), "-o", s(&d("a.tif")), "-q"]);
    ok(&["dem", s(&laz), "--class", "2", "-o", s(&d("b.tif")), "-q"]);
    // A `.stin` does not carry the LAS scale that sets the default decimals of contour
    // coordinates (3 from a mesh, the scale's from the points): the same decimals are given.
    let p = ["--precision", "5"];
    ok(&[
        &["contours", s(&d("t.stin")), "-o", s(&d("a.geojson")), "-q"][..],
        &p,
    ]
    .concat());
    ok(&[
        &[
            "contours",
            s(&laz),
            "--class",
            "2",
            "-o",
            s(&d("b.geojson")),
            "-q",
        ][..],
        &p,
    ]
    .concat());
    for (a, b) in [("a.tif", "b.tif"), ("a.geojson", "b.geojson")] {
        assert_eq!(
            std::fs::read(d(a)).unwrap(),
            std::fs::read(d(b)).unwrap(),
            "{a}"
        );
    }
    let c = std::fs::read_to_string(d("a.geojson")).unwrap();
    assert!(
        c.contains("urn:ogc:def:crs:EPSG::2949"),
        "the CRS is carried"
    );
}

/// One polygon file for every option that takes one: `tin --trim-boundary` keeps exactly its area
/// and `volume --boundary` integrates over exactly that area, for a `Feature` holding a
/// `MultiPolygon` with a `crs` member and for a `GeometryCollection` (a polygon whose hole does not
/// repeat its first position, and a closed `LineString`); a file with a `Point` is refused by both.
#[test]
fn one_polygon_file_for_trim_boundary_and_volume_boundary() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let pts = d("pts.xyz");
    write_points(&pts, |x, y| 0.1 * x + 0.2 * y, 5);
    // A 20 × 20 square with a 5 × 5 hole, and a triangle of area 40.
    let square = "[[10, 10], [30, 10], [30, 30], [10, 30], [10, 10]], \
                  [[15, 15], [15, 20], [20, 20], [20, 15]]";
    let triangle = "[[40, 10], [50, 10], [45, 18], [40, 10]]";
    let files = [
        format!(
            r#"{{"type": "Feature", "properties": {{"name": "site"}},
            "crs": {{"type": "name", "properties": {{"name": "urn:ogc:def:crs:EPSG::28992"}}}},
            "geometry": {{"type": "MultiPolygon", "coordinates": [[{square}], [{triangle}]]}}}}"#
        ),
        format!(
            r#"{{"type": "GeometryCollection", "geometries": [
            {{"type": "Polygon", "coordinates": [{square}]}},
            {{"type": "LineString", "coordinates": {triangle}}}]}}"#
        ),
    ];
    // z = 0.1x + 0.2y is linear: each piece contributes its area times z at its centroid.
    let z = |x: f64, y: f64| 0.1 * x + 0.2 * y;
    let want = 400.0 * z(20.0, 20.0) - 25.0 * z(17.5, 17.5) + 40.0 * z(45.0, 38.0 / 3.0);
    for (k, text) in files.iter().enumerate() {
        let poly = d(&format!("poly{k}.geojson"));
        std::fs::write(&poly, text).unwrap();
        let o = ok(&[
            "volume",
            s(&pts),
            "--plane",
            "0",
            "--boundary",
            s(&poly),
            "--json",
        ]);
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        let net = v["net_volume"].as_f64().unwrap();
        assert!((net - want).abs() < 1e-6, "{k}: {net} vs {want}: {v}");
        let mesh = d(&format!("trim{k}.ply"));
        ok(&[
            "tin",
            s(&pts),
            "--trim-boundary",
            s(&poly),
            "-o",
            s(&mesh),
            "-q",
        ]);
        let (vertices, triangles) = sweeptin::input::read_ply(&mesh).unwrap();
        let area: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs() / 2.0
            })
            .sum();
        assert!((area - 415.0).abs() < 1e-6, "{k}: kept area {area}");
    }
    let bad = d("point.geojson");
    std::fs::write(
        &bad,
        format!(
            r#"{{"type": "GeometryCollection", "geometries": [
            {{"type": "Polygon", "coordinates": [{square}]}},
            {{"type": "Point", "coordinates": [5, 5]}}]}}"#
        ),
    )
    .unwrap();
    let o = run(&["volume", s(&pts), "--plane", "0", "--boundary", s(&bad)]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(e.contains("point.geojson") && e.contains("Point"), "{e}");
    let o = run(&[
        "tin",
        s(&pts),
        "--trim-boundary",
        s(&bad),
        "-o",
        s(&d("x.ply")),
        "-q",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(e.contains("point.geojson") && e.contains("Point"), "{e}");
}

/// `--max-edge` in a product run is applied once, by the writer's trimming: the products get
/// exactly the triangles that are kept, and the summary counts the others once.
#[test]
fn max_edge_is_applied_once() {
    let laz = data_dir().join("lidar/lidR_Topography.laz");
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("d.tif");
    let o = ok(&[
        "dem",
        s(&laz),
        "--class",
        "2",
        "-o",
        s(&dem),
        "--max-edge",
        "20",
        "--json",
    ]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let trimmed = v["run"]["breaklines"]["trimmed_triangles"]
        .as_u64()
        .unwrap();
    assert!(trimmed > 0, "{v}");
    assert_eq!(v["trimmed_triangles"], trimmed, "{v}");
    assert_eq!(v["dem"]["triangles"], v["run"]["triangles"], "{v}");
    // Checked once, before any point is read.
    let bad = dir.path().join("bad.tif");
    let o = run(&["dem", s(&laz), "-o", s(&bad), "--max-edge=-1", "-q"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!bad.exists());
}

/// A `--boundary` in another CRS than the points gave zeros without a word, one half outside
/// the data gave half the volume without one, and a hole lying outside its outline added its
/// own area to the boundary's.
#[test]
fn volume_boundaries_that_miss_the_data_say_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let mut xyz = String::new();
    for i in 0..=10 {
        for j in 0..=10 {
            xyz += &format!("{i} {j} {}\n", i + j);
        }
    }
    std::fs::write(d("g.xyz"), xyz).unwrap();
    let square = |x: f64, y: f64, s: f64| {
        format!(
            "[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]",
            x + s,
            x + s,
            y + s,
            y + s
        )
    };
    let polygon = |rings: &[String]| {
        format!(
            r#"{{"type":"Polygon","coordinates":[{}]}}"#,
            rings.join(",")
        )
    };
    let cases = [
        (
            "far.geojson",
            polygon(&[square(1000.0, 1000.0, 10.0)]),
            "does not meet the boundary",
        ),
        (
            "half.geojson",
            polygon(&[square(5.0, 0.0, 10.0)]),
            "covers 50.000 of the boundary's 100.000 (50.0 %)",
        ),
        ("inside.geojson", polygon(&[square(1.0, 1.0, 8.0)]), ""),
    ];
    for (name, text, warning) in cases {
        std::fs::write(d(name), text).unwrap();
        let o = ok(&[
            "volume",
            s(&d("g.xyz")),
            "--plane",
            "0",
            "--boundary",
            s(&d(name)),
            "-q",
        ]);
        let e = String::from_utf8_lossy(&o.stderr);
        if warning.is_empty() {
            assert!(!e.contains("warning"), "{name}: {e}");
        } else {
            assert!(e.contains(warning), "{name}: {e}");
        }
    }
    // A hole outside its outline takes nothing and adds nothing.
    let astray = polygon(&[square(0.0, 0.0, 10.0), square(20.0, 20.0, 5.0)]);
    std::fs::write(d("astray.geojson"), astray).unwrap();
    let o = ok(&[
        "volume",
        s(&d("g.xyz")),
        "--plane",
        "0",
        "--boundary",
        s(&d("astray.geojson")),
        "--json",
    ]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["boundary_area"], 100.0, "{v}");
    assert_eq!(v["area"], 100.0, "{v}");
}
