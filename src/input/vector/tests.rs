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
