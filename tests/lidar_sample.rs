//! The LAZ sample kept in the repository (`data/sample`, see docs/DATA.md): no shared data needed.

use sweeptin::input::las::{FileInfo, Filter, LidarReader};

const SAMPLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/data/sample/startinpy_small.laz"
);

#[test]
fn repository_sample_reads_as_documented() {
    let info = FileInfo::read(SAMPLE).unwrap();
    assert_eq!((info.version, info.point_format), ((1, 4), 8));
    assert_eq!(info.point_count, 39_233);
    assert_eq!(info.scale, [0.001; 3]);
    assert_eq!(info.offset, [84980.0, 446230.0, 0.0]);
    assert_eq!(info.crs.as_ref().and_then(|c| c.epsg), Some(7415));
    let ground = Filter {
        classes: Some(vec![2]),
        ..Filter::default()
    };
    let mut r = LidarReader::open(&[SAMPLE], &ground).unwrap();
    assert_eq!(r.read_all().unwrap().len(), 18_392);
    assert_eq!(r.crs().and_then(|c| c.epsg), Some(7415));
}
