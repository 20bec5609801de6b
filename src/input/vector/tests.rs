use super::*;
use crate::input::geojson::Part;

fn blob_line(points: &[[f64; 2]]) -> Vec<u8> {
    let mut b = vec![1u8];
    b.extend(2u32.to_le_bytes());
    b.extend((points.len() as u32).to_le_bytes());
    for p in points {
        b.extend(p[0].to_le_bytes());
        b.extend(p[1].to_le_bytes());
    }
    b
}

#[test]
fn wkb_lines_polygons_and_z() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.sqlite");
    let mut out = GeoJson::default();
    let mut sink = wkb::Sink {
        out: &mut out,
        path: &path,
        feature: 3,
        part: 0,
        polygons: 0,
    };
    wkb::read_wkb(&blob_line(&[[0.0, 0.0], [1.0, 2.0]]), &mut sink).unwrap();
    // A big-endian Polygon Z (ISO 1003) with an unclosed ring: closed here.
    let mut p = vec![0u8];
    p.extend(1003u32.to_be_bytes());
    p.extend(1u32.to_be_bytes());
    p.extend(3u32.to_be_bytes());
    for v in [[0.0, 0.0, 5.0], [4.0, 0.0, 6.0], [0.0, 4.0, 7.0]] {
        for c in v {
            p.extend(f64::to_be_bytes(c));
        }
    }
    wkb::read_wkb(&p, &mut sink).unwrap();
    assert!(wkb::read_wkb(&p[..20], &mut sink).is_err());
    assert_eq!(out.parts.len(), 2);
    assert_eq!(out.parts[0].positions[1][..2], [1.0, 2.0]);
    assert!(out.parts[0].positions[1][2].is_nan());
    assert_eq!(
        out.parts[1],
        Part {
            feature: 3,
            part: 1,
            polygon: Some(0),
            positions: vec![
                [0.0, 0.0, 5.0],
                [4.0, 0.0, 6.0],
                [0.0, 4.0, 7.0],
                [0.0, 0.0, 5.0]
            ],
        }
    );
}

/// `read_bytes` (a plan's line files, parsed from the bytes it fingerprints) gives what `read`
/// gives from the file, for every format: an OGR-SQLite database (also in WAL mode, which SQLite
/// opens in memory only as a rollback-journal database, and by layer), a Shapefile (without its
/// `.shx` index) and GeoJSON.
#[test]
fn bytes_read_as_the_file_does() {
    let dir = tempfile::tempdir().unwrap();
    let same = |p: &Path| {
        let from_file = read(p).unwrap();
        let content = std::fs::read(split_layer(p).0).unwrap();
        // Debug: z is NaN in 2-D parts, which `==` never equals.
        assert_eq!(
            format!("{:?}", read_bytes(p, &content).unwrap()),
            format!("{from_file:?}"),
            "{}",
            p.display()
        );
        from_file
    };
    let db_path = dir.path().join("roads.sqlite");
    for (path, journal) in [(&db_path, "DELETE"), (&dir.path().join("wal.db"), "WAL")] {
        let db = rusqlite::Connection::open(path).unwrap();
        db.pragma_update(None, "journal_mode", journal).unwrap();
        db.execute_batch(
            "CREATE TABLE geometry_columns (f_table_name TEXT, f_geometry_column TEXT, \
             srid INTEGER, geometry_format TEXT);
             INSERT INTO geometry_columns VALUES ('roads', 'geom', NULL, 'WKB');
             CREATE TABLE roads (geom BLOB);",
        )
        .unwrap();
        for l in [[[0.0, 0.0], [1.0, 2.0]], [[5.0, 5.0], [6.0, 5.5]]] {
            db.execute("INSERT INTO roads VALUES (?1)", [blob_line(&l)])
                .unwrap();
        }
        drop(db);
        let header = std::fs::read(path).unwrap();
        let mode = if journal == "WAL" { [2, 2] } else { [1, 1] };
        assert_eq!(header[18..20], mode, "{journal}");
        let g = same(path);
        assert_eq!(g.parts.len(), 2);
        assert_eq!(g.parts[1].positions[1][..2], [6.0, 5.5]);
    }
    same(Path::new(&format!("{}:roads", db_path.display())));
    let shp = dir.path().join("banks.shp");
    let mut w = shapefile::ShapeWriter::from_path(&shp).unwrap();
    let p = |x, y, z| shapefile::PointZ::new(x, y, z, shapefile::NO_DATA);
    w.write_shape(&shapefile::PolylineZ::with_parts(vec![
        vec![p(0.0, 0.0, 1.0), p(3.0, 4.0, 2.0)],
        vec![p(10.0, 0.0, 3.0), p(10.0, 9.0, 4.0), p(12.0, 9.5, 5.0)],
    ]))
    .unwrap();
    drop(w);
    assert_eq!(same(&shp).parts.len(), 2);
    let gj = dir.path().join("l.geojson");
    std::fs::write(
        &gj,
        r#"{"type":"LineString","coordinates":[[0,0,1],[1,1,2]]}"#,
    )
    .unwrap();
    assert_eq!(same(&gj).parts.len(), 1);
}
