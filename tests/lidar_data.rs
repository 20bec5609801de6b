//! LAS/LAZ input on the real data in `tests/data/lidar` (facts from docs/DATA.md).

use crate::data;
use data::data_dir;

use std::collections::BTreeMap;
use std::path::PathBuf;
use sweeptin::input::las::{BBox, FileInfo, Filter, LidarPoint, LidarReader, Returns};

fn lidar(name: &str) -> PathBuf {
    data_dir().join("lidar").join(name)
}

fn ign_tile(x: u32, y: u32, ground: bool) -> PathBuf {
    let suffix = if ground { "_ground.las" } else { ".laz" };
    lidar(&format!(
        "ign_50m_tiles/test_data_{x}_{y}_LA93_IGN69{suffix}"
    ))
}

fn ign_tiles(ground: bool) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for x in [77050, 77055, 77060] {
        for y in [627755, 627760] {
            v.push(ign_tile(x, y, ground));
        }
    }
    v
}

/// One row of the README's header table.
struct Facts {
    file: &'static str,
    version: (u8, u8),
    format: u8,
    points: u64,
    scale: f64,
    offset: [f64; 3],
    bounds: [[f64; 2]; 3],
    epsg: Option<u32>,
}

const FACTS: &[Facts] = &[
    Facts {
        file: "ahn3_delft_cropped_1.laz",
        version: (1, 2),
        format: 1,
        points: 640_510,
        scale: 0.001,
        offset: [0.0; 3],
        bounds: [
            [84808.300, 84999.999],
            [447412.800, 447641.299],
            [-0.568, 19.398],
        ],
        epsg: None,
    },
    Facts {
        file: "ahn3_delft_cropped_2.laz",
        version: (1, 2),
        format: 1,
        points: 208_432,
        scale: 0.001,
        offset: [0.0; 3],
        bounds: [
            [85000.001, 85072.299],
            [447412.800, 447641.299],
            [-0.606, 26.329],
        ],
        epsg: None,
    },
    Facts {
        file: "ign_test_semis_2023_0299_6802_LA93_IGN69.laz",
        version: (1, 4),
        format: 6,
        points: 278_810,
        scale: 0.01,
        offset: [0.0; 3],
        bounds: [
            [299000.0, 300000.0],
            [6801000.0, 6802000.0],
            [124.03, 177.85],
        ],
        epsg: Some(2154),
    },
    Facts {
        file: "ign_test_semis_2023_0300_6802_LA93_IGN69.laz",
        version: (1, 4),
        format: 6,
        points: 240_482,
        scale: 0.01,
        offset: [0.0; 3],
        bounds: [
            [300000.0, 301000.0],
            [6801000.01, 6802000.0],
            [124.51, 190.45],
        ],
        epsg: Some(2154),
    },
    Facts {
        file: "lidR_Topography.laz",
        version: (1, 2),
        format: 1,
        points: 73_403,
        scale: 0.00025,
        offset: [270000.0, 5270000.0, 0.0],
        bounds: [
            [273357.145, 273642.857],
            [5274357.144, 5274642.848],
            [788.993, 829.758],
        ],
        epsg: Some(2949),
    },
    Facts {
        file: "startinpy_small.laz",
        version: (1, 4),
        format: 8,
        points: 39_233,
        scale: 0.001,
        offset: [84980.0, 446230.0, 0.0],
        bounds: [
            [85699.665, 85740.506],
            [447195.328, 447243.504],
            [-0.574, 15.966],
        ],
        epsg: Some(7415),
    },
];

/// The README rounds bounds to 3 decimals (and some headers store them as f32).
const BOUNDS_TOL: f64 = 1e-3;

fn check_facts(info: &FileInfo, f: &Facts) {
    let name = f.file;
    assert_eq!(info.version, f.version, "{name}");
    assert_eq!(info.point_format, f.format, "{name}");
    assert!(info.compressed, "{name}");
    assert_eq!(info.point_count, f.points, "{name}");
    assert_eq!(info.scale, [f.scale; 3], "{name}");
    assert_eq!(info.offset, f.offset, "{name}");
    for a in 0..3 {
        assert!(
            (info.bounds.min[a] - f.bounds[a][0]).abs() < BOUNDS_TOL,
            "{name} min {a}"
        );
        assert!(
            (info.bounds.max[a] - f.bounds[a][1]).abs() < BOUNDS_TOL,
            "{name} max {a}"
        );
    }
    assert_eq!(info.crs.as_ref().and_then(|c| c.epsg), f.epsg, "{name}");
    assert!(info.warnings.is_empty(), "{name}: {:?}", info.warnings);
}

fn class_counts(points: &[LidarPoint]) -> BTreeMap<u8, u64> {
    let mut m = BTreeMap::new();
    for p in points {
        *m.entry(p.classification).or_insert(0) += 1;
    }
    m
}

fn read_all(paths: &[PathBuf], filter: &Filter) -> (Vec<LidarPoint>, LidarReader) {
    let mut r = LidarReader::open(paths, filter).unwrap();
    let pts = r.read_all().unwrap();
    (pts, r)
}

#[test]
fn headers_match_the_readme() {
    for f in FACTS {
        let info = FileInfo::read(lidar(f.file)).unwrap();
        check_facts(&info, f);
    }
}

#[test]
fn legacy_and_extended_counts() {
    let ign = FileInfo::read(lidar(FACTS[2].file)).unwrap();
    assert_eq!(ign.extended_point_count, Some(278_810));
    let ahn = FileInfo::read(lidar(FACTS[0].file)).unwrap();
    assert_eq!(ahn.legacy_point_count, 640_510);
    assert_eq!(ahn.extended_point_count, None);
}

#[test]
fn crs_declarations() {
    let small = FileInfo::read(lidar("startinpy_small.laz")).unwrap();
    let crs = small.crs.unwrap();
    assert_eq!(crs.vertical_epsg, Some(5709));
    assert_eq!(
        crs.name.as_deref(),
        Some("Amersfoort / RD New + NAP height")
    );
    assert!(
        crs.definition()
            .unwrap()
            .starts_with("COMPD_CS[\"Amersfoort")
    );
    let topo = FileInfo::read(lidar("lidR_Topography.laz")).unwrap();
    let crs = topo.crs.unwrap();
    assert_eq!(crs.wkt, None);
    assert_eq!(crs.definition().as_deref(), Some("EPSG:2949"));
    let ground = FileInfo::read(ign_tile(77050, 627755, true)).unwrap();
    let crs = ground.crs.unwrap();
    assert_eq!(crs.definition().as_deref(), Some("EPSG:2154"));
    assert_eq!(crs.name.as_deref(), Some("RGF93 v1 / Lambert-93"));
}

#[test]
fn ign_tiles_and_ground_las_open() {
    let mut total = 0;
    for p in ign_tiles(false) {
        let info = FileInfo::read(&p).unwrap();
        assert_eq!((info.version, info.point_format), ((1, 4), 8), "{p:?}");
        assert!((56_035..=83_518).contains(&info.point_count), "{p:?}");
        assert_eq!(info.crs.unwrap().epsg, Some(2154));
        total += info.point_count;
    }
    assert_eq!(total, 405_937);
    for p in ign_tiles(true) {
        let info = FileInfo::read(&p).unwrap();
        assert_eq!((info.version, info.point_format), ((1, 2), 3), "{p:?}");
        assert!(!info.compressed);
        assert!((21_172..=39_468).contains(&info.point_count), "{p:?}");
        assert_eq!(info.crs.unwrap().epsg, Some(2154));
    }
}

/// Every point of every small file is read, its class histogram matches the README, and the
/// points' real-world bounds agree with the header's.
#[test]
fn class_counts_match_the_readme() {
    let expected: &[(&str, &[(u8, u64)])] = &[
        (
            "ahn3_delft_cropped_1.laz",
            &[
                (1, 196_137),
                (2, 195_988),
                (6, 246_753),
                (9, 267),
                (26, 1_365),
            ],
        ),
        (
            "ahn3_delft_cropped_2.laz",
            &[(1, 86_308), (2, 87_130), (6, 33_312), (9, 568), (26, 1_114)],
        ),
        (
            "ign_test_semis_2023_0299_6802_LA93_IGN69.laz",
            &[
                (1, 2_711),
                (2, 198_626),
                (3, 4_277),
                (4, 3_783),
                (5, 62_376),
                (6, 6_772),
                (17, 209),
                (66, 7),
                (67, 49),
            ],
        ),
        (
            "ign_test_semis_2023_0300_6802_LA93_IGN69.laz",
            &[
                (1, 1_871),
                (2, 199_624),
                (3, 5_742),
                (4, 5_871),
                (5, 19_431),
                (6, 7_940),
                (67, 3),
            ],
        ),
        (
            "lidR_Topography.laz",
            &[(1, 61_347), (2, 8_159), (9, 3_897)],
        ),
        (
            "startinpy_small.laz",
            &[(1, 11_302), (2, 18_392), (6, 9_532), (9, 7)],
        ),
    ];
    for (file, classes) in expected {
        let (pts, r) = read_all(&[lidar(file)], &Filter::keep_all());
        let want: BTreeMap<u8, u64> = classes.iter().copied().collect();
        assert_eq!(class_counts(&pts), want, "{file}");
        assert_eq!(pts.len() as u64, r.point_count(), "{file}");
        assert!(
            pts.iter().enumerate().all(|(i, p)| p.index == i as u64),
            "{file}"
        );
        assert!(
            pts.iter().all(|p| p.flags & LidarPoint::WITHHELD == 0),
            "{file}"
        );
        let hb = r.bounds();
        for a in 0..3 {
            let vals = pts.iter().map(|p| [p.x, p.y, p.z][a]);
            let (lo, hi) = vals.fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)));
            assert!(
                (lo - hb.min[a]).abs() < BOUNDS_TOL,
                "{file} axis {a}: {lo} vs {}",
                hb.min[a]
            );
            assert!(
                (hi - hb.max[a]).abs() < BOUNDS_TOL,
                "{file} axis {a}: {hi} vs {}",
                hb.max[a]
            );
        }
    }
}

#[test]
fn class_filter_keeps_the_readme_counts() {
    let ground = Filter {
        classes: Some(vec![2]),
        ..Filter::default()
    };
    for (file, kept, total) in [
        ("ahn3_delft_cropped_1.laz", 195_988, 640_510),
        ("startinpy_small.laz", 18_392, 39_233),
    ] {
        let (pts, r) = read_all(&[lidar(file)], &ground);
        assert_eq!(pts.len(), kept, "{file}");
        assert!(pts.iter().all(|p| p.classification == 2));
        let s = r.stats();
        assert_eq!(
            (s.read, s.kept, s.class),
            (total, kept as u64, total - kept as u64)
        );
        assert_eq!((s.withheld, s.returns, s.bbox), (0, 0, 0));
    }
    let water_and_ground = Filter {
        classes: Some(vec![2, 9]),
        ..Filter::default()
    };
    let (pts, _) = read_all(&[lidar("lidR_Topography.laz")], &water_and_ground);
    assert_eq!(pts.len(), 8_159 + 3_897);
}

/// Small chunks give the same points as one big read, and never more than asked for.
#[test]
fn chunking_does_not_change_the_points() {
    let path = [lidar("startinpy_small.laz")];
    let filter = Filter {
        classes: Some(vec![2]),
        ..Filter::default()
    };
    let (all, _) = read_all(&path, &filter);
    let options = sweeptin::input::las::ReadOptions {
        parallel: false,
        batch_points: 777,
        ..Default::default()
    };
    let mut r = LidarReader::open_with(&path, &filter, options).unwrap();
    let mut chunked = Vec::new();
    loop {
        let before = chunked.len();
        let n = r.read_chunk(&mut chunked, 1000).unwrap();
        assert!(n <= 1000);
        assert_eq!(chunked.len(), before + n);
        if n == 0 {
            break;
        }
    }
    assert_eq!(all, chunked);
    assert_eq!(r.read_chunk(&mut chunked, 10).unwrap(), 0);
    assert_eq!(r.read_chunk(&mut chunked, 0).unwrap(), 0);
}

#[test]
fn returns_filters() {
    let path = [lidar("ign_test_semis_2023_0300_6802_LA93_IGN69.laz")];
    let (all, _) = read_all(&path, &Filter::default());
    for (returns, keep) in [
        (
            Returns::First,
            Box::new(|p: &LidarPoint| p.return_number == 1) as Box<dyn Fn(&LidarPoint) -> bool>,
        ),
        (
            Returns::Last,
            Box::new(|p: &LidarPoint| p.return_number == p.number_of_returns),
        ),
    ] {
        let want: Vec<_> = all.iter().copied().filter(|p| keep(p)).collect();
        let (got, r) = read_all(
            &path,
            &Filter {
                returns,
                ..Filter::default()
            },
        );
        assert!(!got.is_empty() && got.len() < all.len(), "{returns:?}");
        assert_eq!(got, want, "{returns:?}");
        assert_eq!(r.stats().returns, (all.len() - got.len()) as u64);
    }
}

/// The box is inclusive in real-world coordinates: put its edges exactly on points.
#[test]
fn bbox_filter_is_inclusive() {
    let path = [lidar("startinpy_small.laz")];
    let (all, r) = read_all(&path, &Filter::keep_all());
    let _ = r;
    let world: Vec<[f64; 3]> = all.iter().map(|p| [p.x, p.y, p.z]).collect();
    // Point `a` sits on the (xmin, ymin) corner and point `b` on the (xmax, ymax) corner.
    let a = world[100];
    let b = *world
        .iter()
        .find(|w| w[0] > a[0] + 5.0 && w[1] > a[1] + 5.0)
        .unwrap();
    let (xmin, ymin, xmax, ymax) = (a[0], a[1], b[0], b[1]);
    let want: Vec<LidarPoint> = all
        .iter()
        .zip(&world)
        .filter(|(_, w)| w[0] >= xmin && w[0] <= xmax && w[1] >= ymin && w[1] <= ymax)
        .map(|(p, _)| *p)
        .collect();
    let filter = Filter {
        bbox: Some(BBox::new(xmin, ymin, xmax, ymax).unwrap()),
        ..Filter::keep_all()
    };
    let (got, r) = read_all(&path, &filter);
    assert!(!got.is_empty() && got.len() < all.len());
    assert_eq!(got, want);
    assert!(got.iter().any(|p| [p.x, p.y, p.z] == a));
    assert!(got.iter().any(|p| [p.x, p.y, p.z] == b));
    assert_eq!(r.stats().bbox, (all.len() - got.len()) as u64);
}

/// Adjacent AHN3 crops read as one set: indices continue across files.
#[test]
fn adjacent_files_form_one_point_set() {
    let paths = [
        lidar("ahn3_delft_cropped_1.laz"),
        lidar("ahn3_delft_cropped_2.laz"),
    ];
    let ground = Filter {
        classes: Some(vec![2]),
        ..Filter::default()
    };
    let (pts, r) = read_all(&paths, &ground);
    assert_eq!(pts.len(), 195_988 + 87_130);
    assert_eq!(r.point_count(), 640_510 + 208_432);
    assert!(pts.windows(2).all(|w| w[0].index < w[1].index));
    let second = &pts[195_988..];
    assert!(second.iter().all(|p| p.index >= 640_510));
    assert!(pts[..195_988].iter().all(|p| p.index < 640_510));
    // The two crops share the edge x = 85000 m: x < 85000 in the first, > 85000 in the second.
    assert!(pts[..195_988].iter().all(|p| p.x < 85000.0));
    assert!(second.iter().all(|p| p.x > 85000.0));
    assert_eq!(r.crs(), None);
}

/// The six IGN 50 m tiles read as one mosaic, and the ground-only LAS 1.2 files hold exactly the
/// class-2 points of the LAZ 1.4 tiles (except the cropped tile 77050_627755).
#[test]
fn ign_mosaic_and_ground_files_agree() {
    let laz = ign_tiles(false);
    let (pts, r) = read_all(&laz, &Filter::default());
    assert_eq!(pts.len(), 405_937);
    assert_eq!(r.crs().and_then(|c| c.epsg), Some(2154));
    let b = r.bounds();
    assert_eq!(
        (b.min[0], b.max[0], b.min[1], b.max[1]),
        (770500.0, 770650.0, 6277500.0, 6277600.0)
    );
    let ground = Filter {
        classes: Some(vec![2]),
        ..Filter::default()
    };
    for (x, y) in [(77055, 627755), (77060, 627760)] {
        let (g_laz, rl) = read_all(&[ign_tile(x, y, false)], &ground);
        let (g_las, rs) = read_all(&[ign_tile(x, y, true)], &Filter::default());
        assert_eq!(rl.quantization(), rs.quantization());
        let xyz = |v: &[LidarPoint]| {
            v.iter()
                .map(|p| (p.x.to_bits(), p.y.to_bits(), p.z.to_bits()))
                .collect::<Vec<_>>()
        };
        let (mut a, mut b) = (xyz(&g_laz), xyz(&g_las));
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "tile {x}_{y}");
    }
    let (cropped, _) = read_all(&[ign_tile(77050, 627755, false)], &ground);
    assert_eq!(cropped.len(), 13_881);
    assert_eq!(
        FileInfo::read(ign_tile(77050, 627755, true))
            .unwrap()
            .point_count,
        21_172
    );
}

/// Files with any scales and offsets combine in world coordinates: each point keeps the doubles
/// its own file gives it, whatever it is read with; files declaring different CRSs are refused.
#[test]
fn multi_file_combination_rules() {
    // startinpy_small (offset 84980, 446230) then AHN3 (offset 0), both at 1 mm.
    let small = lidar("startinpy_small.laz");
    let ahn = lidar("ahn3_delft_cropped_2.laz");
    let (both, r) = read_all(&[small.clone(), ahn.clone()], &Filter::default());
    // One file declares EPSG:7415, the other nothing: accepted, the declared CRS is kept.
    assert_eq!(r.crs().and_then(|c| c.epsg), Some(7415));
    let (alone, _) = read_all(std::slice::from_ref(&ahn), &Filter::default());
    let shifted = &both[39_233..];
    assert_eq!(shifted.len(), alone.len());
    for (s, a) in shifted.iter().zip(&alone) {
        assert_eq!((s.x, s.y, s.z), (a.x, a.y, a.z));
        assert_eq!(s.index, a.index + 39_233);
    }
    // AHN3 (1 mm) with IGN (1 cm, y = 6.8e6 m: 6.8e9 steps of 1 mm, more than 32 bits), and
    // ARSO (1 cm shifted by 5 mm) with IGN: refused before, combined now (the CRSs differ in
    // the real world, but AHN3 and ARSO declare none).
    let ign = lidar(FACTS[3].file);
    let (mixed, _) = read_all(&[ahn.clone(), ign.clone()], &Filter::default());
    let (ign_alone, _) = read_all(std::slice::from_ref(&ign), &Filter::default());
    assert_eq!(mixed.len(), alone.len() + ign_alone.len());
    assert_eq!(&mixed[alone.len()..].len(), &ign_alone.len());
    assert!(
        mixed[alone.len()..]
            .iter()
            .zip(&ign_alone)
            .all(|(m, i)| (m.x, m.y, m.z) == (i.x, i.y, i.z))
    );
    // Files declaring different CRSs are refused (IGN: EPSG:2154, Topography: EPSG:2949).
    let e = LidarReader::open(&[ign, lidar("lidR_Topography.laz")], &Filter::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("CRS") && e.contains("lidR_Topography.laz"),
        "{e}"
    );
}

/// The ARSO crop (the 250 m × 250 m south-west corner of the 13.2 M-point tile, docs/DATA.md):
/// the header, and the class counts laspy finds, read in parallel and not. The throughput on
/// the whole tile is measured by scripts/bench-info.sh.
#[test]
fn arso_crop_classes_in_parallel_and_not() {
    let path = [lidar("arso_TM_511_122_sw_250m.laz")];
    let info = FileInfo::read(&path[0]).unwrap();
    assert_eq!(info.point_count, 910_797);
    assert_eq!(info.offset, [511500.025, 122499.965, 747.255]);
    assert_eq!(info.crs, None);
    for parallel in [true, false] {
        let options = sweeptin::input::las::ReadOptions {
            parallel,
            ..Default::default()
        };
        let start = std::time::Instant::now();
        let mut r = LidarReader::open_with(&path, &Filter::default(), options).unwrap();
        let mut chunk = Vec::new();
        let mut classes = [0u64; 256];
        while r.read_chunk(&mut chunk, 1 << 20).unwrap() > 0 {
            for p in &chunk {
                classes[usize::from(p.classification)] += 1;
            }
            chunk.clear();
        }
        let secs = start.elapsed().as_secs_f64();
        eprintln!(
            "arso: {} points in {secs:.2} s = {:.2} M points/s (parallel: {parallel})",
            r.stats().read,
            r.stats().read as f64 / secs / 1e6
        );
        let want = [75_078, 3_169, 439_851, 84_371, 65_184, 242_394, 0, 750];
        assert_eq!(&classes[..8], &want);
        assert_eq!(classes[8..].iter().sum::<u64>(), 0);
    }
}
