//! Unit tests of the GeoJSON reader and its views.

use super::*;

#[test]
fn reads_polygons_and_reports_bad_ones() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.geojson");
    std::fs::write(
        &path,
        r#"{"type":"MultiPolygon","coordinates":[[[[0,0],[4,0],[4,4],[0,0]]],
           [[[10,10],[12,10],[12,12],[10,12],[10,10]],[[11,11],[11.5,11],[11.5,11.5]]]]}"#,
    )
    .unwrap();
    let p = read_polygons(&path).unwrap();
    assert_eq!(p.len(), 2);
    assert_eq!(p[0][0].len(), 3);
    assert_eq!(p[1].len(), 2);
    std::fs::write(
        &path,
        r#"{"type":"Polygon","coordinates":[[[0,0],[1,"x"],[1,1]]]}"#,
    )
    .unwrap();
    let e = read_polygons(&path).unwrap_err().to_string();
    assert!(e.contains("bad position"), "{e}");
    std::fs::write(&path, r#"{"type":"Point","coordinates":[0,0]}"#).unwrap();
    assert!(read_polygons(&path).is_err());
    std::fs::write(&path, "{").unwrap();
    assert!(matches!(read_polygons(&path), Err(Error::Parse { .. })));
}

#[test]
fn crs_forms() {
    let c = |v: &str| crs_name(&serde_json::from_str(v).unwrap());
    assert_eq!(
        c(r#"{"type":"name","properties":{"name":"urn:ogc:def:crs:OGC:1.3:CRS84"}}"#),
        Some("OGC:CRS84".into())
    );
    assert_eq!(
        c(r#"{"type":"name","properties":{"name":"EPSG:2154"}}"#),
        Some("EPSG:2154".into())
    );
    assert_eq!(
        c(r#"{"type":"EPSG","properties":{"code":3857}}"#),
        Some("EPSG:3857".into())
    );
    assert_eq!(c(r#"{"type":"link","properties":{"href":"x"}}"#), None);
}

fn parse_str(s: &str) -> Result<GeoJson> {
    parse(s.as_bytes(), Path::new("t.geojson"))
}

#[test]
fn parts_keep_their_polygons_and_labels() {
    let g = parse_str(
        r#"{"type": "FeatureCollection", "features": [
          {"type": "Feature", "geometry": {"type": "GeometryCollection", "geometries": [
            {"type": "MultiPoint", "coordinates": [[0, 0]]},
            {"type": "LineString", "coordinates": [[0, 0, 1, 7], [1, 0]]},
            {"type": "MultiPolygon", "coordinates": [
              [[[0, 0], [1, 0], [0, 1]], [[0.1, 0.1], [0.2, 0.1], [0.1, 0.2], [0.1, 0.1]]],
              [],
              [[[5, 5], [6, 5], [5, 6]]]]}]}},
          {"type": "Feature", "geometry": {"type": "MultiLineString",
           "coordinates": [[[5, 5], [6, 6]], [[7, 7], [8, 8]]]}}]}"#,
    )
    .unwrap();
    assert_eq!(g.crs, None);
    assert_eq!(g.points, vec![(0, "MultiPoint")]);
    let label = |p: &Part| (p.feature, p.part, p.polygon);
    let labels: Vec<_> = g.parts.iter().map(label).collect();
    assert_eq!(
        labels,
        [
            (0, 0, None),
            (0, 1, Some(0)),
            (0, 2, Some(0)),
            (0, 3, Some(1)),
            (1, 0, None),
            (1, 1, None)
        ]
    );
    assert_eq!(g.parts[0].positions[0], [0.0, 0.0, 1.0]);
    assert!(g.parts[0].positions[1][2].is_nan());
    assert_eq!(g.parts[1].positions.len(), 4, "closed here");
    assert_eq!(g.parts[2].positions.len(), 4, "already closed");
    assert_eq!(g.parts[5].label(), "feature 1 part 1");
}

#[test]
fn views_take_lines_or_polygons() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mixed.geojson");
    let mixed = r#"{"type": "FeatureCollection", "features": [
        {"type": "Feature", "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, 1]]}},
        {"type": "Feature", "geometry": {"type": "Polygon",
         "coordinates": [[[0, 0], [4, 0], [4, 4], [0, 0]]]}},
        {"type": "Feature", "geometry": {"type": "Point", "coordinates": [2, 2]}}]}"#;
    std::fs::write(&path, mixed).unwrap();
    assert_eq!(
        read_lines(&path).unwrap(),
        vec![vec![[0.0, 0.0], [1.0, 1.0]]]
    );
    // Not a polygon file: a point, and an open line.
    let e = read_polygons(&path).unwrap_err().to_string();
    assert!(e.contains("feature 2: a Point is not a polygon"), "{e}");
    let no_point = mixed.replace(r#"{"type": "Point", "coordinates": [2, 2]}"#, "null");
    std::fs::write(&path, no_point).unwrap();
    let e = read_polygons(&path).unwrap_err().to_string();
    assert!(
        e.contains("feature 0 part 0") && e.contains("not a closed ring"),
        "{e}"
    );
    // A closed LineString is a ring, as for `--trim-boundary`.
    std::fs::write(
        &path,
        r#"{"type": "LineString", "coordinates": [[0, 0], [4, 0], [4, 4], [0, 0]]}"#,
    )
    .unwrap();
    assert_eq!(
        read_polygons(&path).unwrap(),
        vec![vec![vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]]]]
    );
    let e = read_lines(&path).map(|_| ());
    assert!(e.is_ok());
    std::fs::write(&path, r#"{"type": "Point", "coordinates": [0, 0]}"#).unwrap();
    let e = read_polygons(&path).unwrap_err().to_string();
    assert!(e.contains("Point is not a polygon"), "{e}");
    let e = read_lines(&path).unwrap_err().to_string();
    assert!(e.contains("no LineString"), "{e}");
    std::fs::write(&path, r#"{"type": "FeatureCollection", "features": []}"#).unwrap();
    let e = read_polygons(&path).unwrap_err().to_string();
    assert!(e.contains("no Polygon"), "{e}");
}

#[test]
fn bad_values_in_positions() {
    for (coords, needle) in [
        (
            r#"[[0, 0], [1, "x"]]"#,
            "string \"x\", expected a number (bad position)",
        ),
        (
            r#"[[0, 0], ["x", 1]]"#,
            "string \"x\", expected a number or an array",
        ),
        (
            r#"[[0, 0], [1, null]]"#,
            "null, expected a number (bad position)",
        ),
        (
            r#"[[0, 0], [1, true]]"#,
            "boolean `true`, expected a number (bad position)",
        ),
        (
            r#"[[0, 0], [1, {}]]"#,
            "map, expected a number (bad position)",
        ),
        (
            r#"[[0, 0], [1, [2]]]"#,
            "sequence, expected a number (bad position)",
        ),
        (r#"[[0, 0], {"a": 1}]"#, "expected an array of coordinates"),
    ] {
        let doc = format!(r#"{{"type": "LineString", "coordinates": {coords}}}"#);
        let e = parse_str(&doc).unwrap_err();
        assert!(matches!(e, Error::Parse { .. }), "{e:?}");
        let e = e.to_string();
        assert!(e.contains(needle), "{coords}: {e}");
    }
}

/// One polygon file, two options: `--trim-boundary` (breakline rings through
/// [`crate::input::lines`], trimmed by [`crate::breaklines::Trim`]) and the volume's
/// `--boundary` ([`read_polygons`], clipped by [`crate::products::boundary::Boundary`]) accept
/// the same files, refuse the same ones, and see the same area (of valid polygons: a hole
/// outside its outline takes nothing from `Boundary`, while `Trim`'s even-odd rule counts it).
#[test]
fn trim_boundary_and_volume_boundary_accept_the_same_files() {
    use crate::breaklines::{Trim, read_file};
    use crate::products::boundary::Boundary;
    let crs = r#""crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}}"#;
    // A 10 × 10 square with a 2 × 2 hole (its ring not repeating its first position), and a
    // triangle of area 40.
    let square = "[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]], [[2, 2], [2, 4], [4, 4], [4, 2]]";
    let triangle = "[[20, 0], [30, 0], [25, 8], [20, 0]]";
    let accepted = [
        format!(
            r#"{{"type": "Feature", {crs}, "properties": {{"name": "site"}},
            "geometry": {{"type": "MultiPolygon", "coordinates": [[{square}], [{triangle}]]}}}}"#
        ),
        format!(
            r#"{{"type": "GeometryCollection", "geometries": [
            {{"type": "Polygon", "coordinates": [{square}]}},
            {{"type": "LineString", "coordinates": {triangle}}}]}}"#
        ),
        format!(
            r#"{{"type": "FeatureCollection", {crs}, "features": [
            {{"type": "Feature", "geometry": null, "properties": null}},
            {{"type": "Feature", "geometry": {{"type": "Polygon", "coordinates": [{square}]}}}},
            {{"type": "Feature", "geometry": {{"type": "Polygon", "coordinates": [{triangle}]}}}}]}}"#
        ),
    ];
    let refused = [
        r#"{"type": "LineString", "coordinates": [[0, 0], [10, 0], [10, 10]]}"#.to_string(),
        format!(
            r#"{{"type": "GeometryCollection", "geometries": [
            {{"type": "Polygon", "coordinates": [{square}]}},
            {{"type": "Point", "coordinates": [5, 5]}}]}}"#
        ),
        r#"{"type": "FeatureCollection", "features": []}"#.to_string(),
        r#"{"type": "Polygon", "coordinates": [[[0, 0], [1, 1], [0, 0]]]}"#.to_string(),
        r#"{"type": "Polygon", "coordinates": [[[0, 0], [1, "x"], [1, 1]]]}"#.to_string(),
    ];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("boundary.geojson");
    let tri = |x: f64, y: f64| [[x, y, 0.0], [x + 0.1, y, 0.0], [x, y + 0.1, 0.0]];
    for doc in &accepted {
        std::fs::write(&path, doc).unwrap();
        let lines = read_file(&path).unwrap();
        let trim = Trim::from_lines(Some(&lines), None, None).unwrap();
        let boundary = Boundary::new(&read_polygons(&path).unwrap()).unwrap();
        assert!(
            (boundary.area() - (100.0 - 4.0 + 40.0)).abs() < 1e-9,
            "{doc}"
        );
        for (x, y, inside) in [(1.0, 1.0, true), (3.0, 3.0, false), (25.0, 3.0, true)] {
            assert_eq!(trim.keep(&tri(x, y)), inside, "({x}, {y}) in {doc}");
        }
    }
    for doc in &refused {
        std::fs::write(&path, doc).unwrap();
        let trim = read_file(&path).and_then(|l| Trim::from_lines(Some(&l), None, None));
        assert!(trim.is_err(), "--trim-boundary accepts {doc}");
        assert!(read_polygons(&path).is_err(), "--boundary accepts {doc}");
    }
}
