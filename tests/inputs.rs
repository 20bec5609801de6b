//! The input side on the real files: COPC read through its octree (the same points as a plain
//! read, checked against laspy), files skipped outside a box, `.vpc` lists, `@lists` and globs,
//! files with different scales and offsets combined in world coordinates.
//!
//! COPC copies are written at run time by `scripts/make_copc.py` (copclib, independent of
//! sweeptin); a small one, `tests/data/lidR_Topography.copc.laz`, is committed.

use crate::cli;
use crate::data;

use data::{ign_tiles, shared};
use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::input::las::{BBox, FileInfo, Filter, LidarPoint, LidarReader, ReadOptions};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn read(
    paths: &[PathBuf],
    filter: &Filter,
    options: ReadOptions,
) -> (Vec<LidarPoint>, LidarReader) {
    let mut r = LidarReader::open_with(paths, filter, options).unwrap();
    let pts = r.read_all().unwrap();
    (pts, r)
}

/// Points as comparable keys: exact coordinates and attributes.
fn keys(pts: &[LidarPoint]) -> Vec<(u64, u64, u64, u8, u8, u8)> {
    let mut v: Vec<_> = pts
        .iter()
        .map(|p| {
            (
                p.x.to_bits(),
                p.y.to_bits(),
                p.z.to_bits(),
                p.classification,
                p.return_number,
                p.number_of_returns,
            )
        })
        .collect();
    v.sort_unstable();
    v
}

fn inside(p: &LidarPoint, b: &BBox) -> bool {
    let [x0, y0, x1, y1] = b.corners();
    p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1
}

/// Writes a COPC copy of `src` with copclib (`voxels` per side of a node's grid);
/// `None` (skipped) locally without the Python tools.
fn make_copc(src: &Path, dst: &Path, page_depth: u32, voxels: u32, test: &str) -> bool {
    if !data::python(&["copclib", "laspy", "lazrs"], test) {
        return false;
    }
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scripts/make_copc.py");
    let o = Command::new("python3")
        .arg(script)
        .arg(src)
        .arg(dst)
        .args(["--page-depth", &page_depth.to_string()])
        .args(["--voxels", &voxels.to_string()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    true
}

/// The committed COPC copy of lidR's Topography (copclib, hierarchy in pages): the octree read
/// keeps exactly the points, indices and order of a plain read, for boxes of every kind.
#[test]
fn copc_index_reads_what_a_plain_read_keeps() {
    let copc = [fixture("lidR_Topography.copc.laz")];
    let info = FileInfo::read(&copc[0]).unwrap();
    let c = info.copc.as_ref().expect("a COPC file");
    assert!(c.nodes > 8 && c.depth >= 2, "{c:?}");
    let plain = ReadOptions {
        copc_index: false,
        ..ReadOptions::default()
    };
    let (all, _) = read(&copc, &Filter::keep_all(), plain);
    assert_eq!(all.len(), 73_403);
    // The same points as the original LAZ (another order: the octree's).
    let original = [shared("lidar/lidR_Topography.laz")];
    let (orig, _) = read(&original, &Filter::keep_all(), ReadOptions::default());
    assert_eq!(keys(&all), keys(&orig));
    for (x0, y0, x1, y1) in [
        (273400.0, 5274400.0, 273450.0, 5274450.0),
        (273357.0, 5274357.0, 273360.0, 5274643.0),
        (273500.0, 5274500.0, 273500.0, 5274700.0),
        (0.0, 0.0, 1.0, 1.0),
        (273000.0, 5274000.0, 274000.0, 5275000.0),
    ] {
        let b = BBox::new(x0, y0, x1, y1).unwrap();
        let f = Filter {
            bbox: Some(b),
            ..Filter::keep_all()
        };
        let (got, r) = read(&copc, &f, ReadOptions::default());
        let want: Vec<LidarPoint> = all.iter().filter(|p| inside(p, &b)).copied().collect();
        assert_eq!(got, want, "box {b}");
        let s = r.stats();
        assert_eq!(s.read + s.skipped, 73_403, "box {b}: {s:?}");
        assert_eq!(s.kept, want.len() as u64);
        if (x1 - x0) < 100.0 && !want.is_empty() {
            assert!(s.skipped > 10_000, "box {b}: {s:?}");
        }
        // The area API gives the same points as the filter's box.
        let mut r = LidarReader::open_area(&copc, &Filter::keep_all(), b).unwrap();
        assert_eq!(r.read_all().unwrap(), want, "area {b}");
    }
}

/// laspy reads the same COPC points in a box as sweeptin (an independent reader's count).
#[test]
fn copc_box_agrees_with_laspy() {
    if !data::python(&["laspy", "lazrs"], "copc_box_agrees_with_laspy") {
        return;
    }
    let copc = fixture("lidR_Topography.copc.laz");
    let script = "import sys, laspy, numpy as np\n\
        r = laspy.CopcReader.open(sys.argv[1])\n\
        p = r.query()\n\
        x, y = np.asarray(p.x), np.asarray(p.y)\n\
        m = (x >= 273400) & (x <= 273450) & (y >= 5274400) & (y <= 5274450)\n\
        print(len(p), int(m.sum()), int(np.asarray(p.classification)[m].sum()))";
    let o = Command::new("python3")
        .args(["-c", script])
        .arg(&copc)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let f = Filter {
        bbox: Some(BBox::new(273400.0, 5274400.0, 273450.0, 5274450.0).unwrap()),
        ..Filter::keep_all()
    };
    let (got, _) = read(&[copc], &f, ReadOptions::default());
    let classes: u64 = got.iter().map(|p| u64::from(p.classification)).sum();
    assert_eq!(out.trim(), format!("73403 {} {classes}", got.len()));
}

/// The ARSO crop as COPC (written at run time; 32 voxels a side give its root the 7.8 m spacing
/// 128 give the whole 1 km tile): a 25 m box decodes a few percent of it and keeps exactly the
/// points a full read keeps.
#[test]
fn arso_copc_box() {
    let Some(src) = data::optional("lidar/arso_TM_511_122_sw_250m.laz", "arso_copc_box") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let copc = dir.path().join("arso.copc.laz");
    if !make_copc(&src, &copc, 3, 32, "arso_copc_box") {
        return;
    }
    let b = BBox::new(511005.0, 122005.0, 511030.0, 122030.0).unwrap();
    let f = Filter {
        bbox: Some(b),
        ..Filter::keep_all()
    };
    let (got, r) = read(std::slice::from_ref(&copc), &f, ReadOptions::default());
    let plain = ReadOptions {
        copc_index: false,
        ..ReadOptions::default()
    };
    let (want, _) = read(&[copc], &f, plain);
    assert_eq!(got, want);
    let s = r.stats();
    assert!(s.read * 10 < s.skipped, "{s:?}");
    let (orig, _) = read(&[src], &f, ReadOptions::default());
    assert_eq!(keys(&got), keys(&orig));
}

use cli::ok as sweeptin;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A DEM of `inputs` (0.5 m cells), as bytes.
fn dem(inputs: &[&str], extra: &[&str], out: &Path) -> Vec<u8> {
    let mut args = vec!["dem"];
    args.extend_from_slice(inputs);
    args.extend_from_slice(&["-o", s(out), "--cell", "0.5", "-q"]);
    args.extend_from_slice(extra);
    sweeptin(&args);
    std::fs::read(out).unwrap()
}

/// A box inside one IGN tile (77055_627760) skips the five others without decoding them, and
/// keeps exactly what a full read keeps.
#[test]
fn a_box_skips_the_files_it_misses() {
    let tiles = ign_tiles();
    let b = BBox::new(770560.0, 6277565.0, 770590.0, 6277595.0).unwrap();
    let (all, _) = read(&tiles, &Filter::default(), ReadOptions::default());
    let f = Filter {
        bbox: Some(b),
        ..Filter::default()
    };
    let (got, r) = read(&tiles, &f, ReadOptions::default());
    let want: Vec<LidarPoint> = all.iter().filter(|p| inside(p, &b)).copied().collect();
    assert_eq!(got, want);
    let inner = tiles
        .iter()
        .find(|t| s(t).contains("77055_627760"))
        .unwrap();
    let inner_points = FileInfo::read(inner).unwrap().point_count;
    let s = r.stats();
    assert_eq!(s.read, inner_points, "{s:?}");
    assert_eq!(s.read + s.skipped, r.point_count());
}

/// `sweeptin index` writes a `.vpc` of the six IGN tiles that our reader (and the STAC
/// structure wrench reads) takes back: same points as the files; with a box, files outside are
/// never opened (a missing one is not noticed), without it they are.
#[test]
fn a_vpc_of_the_ign_tiles() {
    let dir = tempfile::tempdir().unwrap();
    let tiles = ign_tiles();
    // Copies beside the .vpc, so the relative hrefs are checked.
    let local: Vec<PathBuf> = tiles
        .iter()
        .map(|t| {
            let p = dir.path().join("tiles").join(t.file_name().unwrap());
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::copy(t, &p).unwrap();
            p
        })
        .collect();
    let vpc = dir.path().join("ign.vpc");
    let pattern = dir.path().join("tiles/*.laz");
    let o = sweeptin(&["index", s(&pattern), "-o", s(&vpc), "--json"]);
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["files"], 6);
    assert_eq!(summary["points"], 405_937);
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&vpc).unwrap()).unwrap();
    assert_eq!(v["type"], "FeatureCollection");
    let item = &v["features"][0];
    assert_eq!(item["stac_version"], "1.0.0");
    assert!(
        item["assets"]["data"]["href"]
            .as_str()
            .unwrap()
            .starts_with("./tiles/")
    );
    assert_eq!(item["properties"]["proj:epsg"], 2154);
    assert!(
        item["properties"]["proj:wkt2"]
            .as_str()
            .unwrap()
            .contains("Lambert-93")
    );
    assert_eq!(item["properties"]["proj:bbox"].as_array().unwrap().len(), 6);
    let entries = sweeptin::input::las::vpc::read(&vpc).unwrap();
    for (e, t) in entries.iter().zip(&local) {
        let info = FileInfo::read(t).unwrap();
        assert_eq!(e.path.canonicalize().unwrap(), t.canonicalize().unwrap());
        assert_eq!((e.points, e.bounds), (info.point_count, info.bounds));
    }
    let (from_vpc, r) = read(
        std::slice::from_ref(&vpc),
        &Filter::default(),
        ReadOptions::default(),
    );
    let (from_files, _) = read(&local, &Filter::default(), ReadOptions::default());
    assert_eq!(from_vpc, from_files);
    assert_eq!(r.crs().and_then(|c| c.epsg), Some(2154));
    // A box inside 77055_627760: the others are not even opened.
    for t in &local {
        if !s(t).contains("77055_627760") {
            std::fs::remove_file(t).unwrap();
        }
    }
    let f = Filter {
        bbox: Some(BBox::new(770560.0, 6277565.0, 770590.0, 6277595.0).unwrap()),
        ..Filter::default()
    };
    let (got, r) = read(std::slice::from_ref(&vpc), &f, ReadOptions::default());
    assert!(!got.is_empty());
    assert_eq!(r.files().count(), 1);
    let e = LidarReader::open(std::slice::from_ref(&vpc), &Filter::default()).unwrap_err();
    assert!(e.to_string().contains("77050_627755"), "{e}");
}

/// `sweeptin index FILES -o VPC`.
/// The six IGN tiles and `ign.vpc` listing them (written by `sweeptin index`) in `dir`.
fn ign_vpc(dir: &Path) -> (Vec<PathBuf>, PathBuf) {
    let tiles = ign_tiles();
    let vpc = dir.join("ign.vpc");
    let mut args = vec!["index"];
    args.extend(tiles.iter().map(|t| s(t)));
    args.extend_from_slice(&["-o", s(&vpc)]);
    sweeptin(&args);
    (tiles, vpc)
}

/// A `.vpc` whose boxes are not the files' headers' (stale: shrunk by 20 m on the south-west; or
/// only a WGS84 `bbox`, as a STAC catalogue may give): the files it opens count with their
/// headers' boxes, so the DEM (tiled, its block index packed on the headers' lattice, or swept)
/// is the one of the files themselves.
#[test]
fn a_vpc_with_boxes_other_than_the_headers() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let (tiles, vpc) = ign_vpc(dir.path());
    let names: Vec<&str> = tiles.iter().map(|t| s(t)).collect();
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&vpc).unwrap()).unwrap();
    let (mut stale, mut wgs84) = (v.clone(), v);
    for item in stale["features"].as_array_mut().unwrap() {
        let b = item["properties"]["proj:bbox"].as_array_mut().unwrap();
        for k in [0, 1] {
            b[k] = serde_json::json!(b[k].as_f64().unwrap() + 20.0);
        }
    }
    for item in wgs84["features"].as_array_mut().unwrap() {
        let p = item["properties"].as_object_mut().unwrap();
        p.remove("proj:bbox");
        p.remove("proj:geometry");
        item["bbox"] = serde_json::json!([2.43, 48.83, 0.0, 2.44, 48.84, 100.0]);
    }
    let files = dem(&names, &[], &d("files.tif"));
    for (name, list) in [("stale.vpc", stale), ("wgs84.vpc", wgs84)] {
        std::fs::write(d(name), serde_json::to_vec(&list).unwrap()).unwrap();
        for engine in ["tiles", "sweep"] {
            let got = dem(&[s(&d(name))], &["--engine", engine], &d("x.tif"));
            assert!(
                got == files,
                "{name} through {engine} differs from the files' DEM"
            );
        }
    }
}

/// The same DEM bytes from LAZ tiles, a `.vpc` of them, an `@list` and a quoted glob (a box in
/// one of the six IGN tiles: the others are never decoded); and from COPC copies (written by
/// copclib) of two tiles. The COPC copies order the points by octree node, so there the
/// exact-(x, y) duplicates keep the lowest point (an order-free policy), on both sides.
#[test]
fn the_same_dem_from_laz_vpc_lists_globs_and_copc() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let (tiles, vpc) = ign_vpc(dir.path());
    let names: Vec<&str> = tiles.iter().map(|t| s(t)).collect();
    let bbox = ["--bbox", "770560,6277560,770590,6277590"];
    let laz_box = dem(&names, &bbox, &d("laz_box.tif"));
    assert_eq!(dem(&[s(&vpc)], &bbox, &d("vpc_box.tif")), laz_box);
    let list = d("tiles.txt");
    let rel: Vec<String> = tiles
        .iter()
        .map(|t| format!("{}", pathdiff(t, dir.path()).display()))
        .collect();
    std::fs::write(&list, rel.join("\n")).unwrap();
    let at = format!("@{}", s(&list));
    assert_eq!(dem(&[&at], &bbox, &d("list.tif")), laz_box);
    let pattern = format!("{}/*.laz", s(&shared("lidar/ign_50m_tiles")));
    assert_eq!(dem(&[&pattern], &bbox, &d("glob.tif")), laz_box);
    // Two whole tiles: LAZ, their .vpc, their COPC copies and a .vpc of those.
    let two: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| n.contains("_627760_"))
        .take(2)
        .collect();
    let pair_vpc = d("pair.vpc");
    sweeptin(&["index", two[0], two[1], "-o", s(&pair_vpc)]);
    let base = dem(&two, &[], &d("laz.tif"));
    assert_eq!(dem(&[s(&pair_vpc)], &[], &d("vpc.tif")), base);
    let test = "the_same_dem_from_laz_vpc_lists_globs_and_copc";
    let copcs = [d("a.copc.laz"), d("b.copc.laz")];
    for (t, c) in two.iter().zip(&copcs) {
        if !make_copc(Path::new(t), c, 1, 128, test) {
            return;
        }
    }
    let lowest = ["--duplicates", "lowest"];
    let laz_lowest = dem(&two, &lowest, &d("laz_lowest.tif"));
    assert_ne!(
        laz_lowest, base,
        "the duplicates policy matters on these tiles"
    );
    let copc_names = [s(&copcs[0]), s(&copcs[1])];
    assert_eq!(dem(&copc_names, &lowest, &d("copc.tif")), laz_lowest);
    let copc_vpc = d("copc.vpc");
    sweeptin(&["index", copc_names[0], copc_names[1], "-o", s(&copc_vpc)]);
    let both: Vec<&str> = lowest.iter().chain(&bbox).copied().collect();
    assert_eq!(
        dem(&[s(&copc_vpc)], &both, &d("copc_box.tif")),
        dem(&two, &both, &d("laz_lowest_box.tif"))
    );
}

/// `path` relative to `dir` (both absolute), with `..` as needed.
fn pathdiff(path: &Path, dir: &Path) -> PathBuf {
    let (p, d): (Vec<_>, Vec<_>) = (path.components().collect(), dir.components().collect());
    let common = p.iter().zip(&d).take_while(|(a, b)| a == b).count();
    let mut r = PathBuf::new();
    for _ in common..d.len() {
        r.push("..");
    }
    p[common..].iter().for_each(|c| r.push(c));
    r
}

/// Writes a copy of a LAS/LAZ file with another scale and offset (the same points), as LAS 1.4
/// point format 7 (no NIR) with the original's WKT.
fn requantise(src: &Path, dst: &Path, scale: f64, offset: [f64; 3]) {
    let mut reader = las::Reader::from_path(src).unwrap();
    let wkt = reader.header().get_wkt_crs_bytes().map(<[u8]>::to_vec);
    let mut b = las::Builder::from((1, 4));
    b.point_format = las::point::Format::new(7).unwrap();
    let t = |o: f64| las::Transform { scale, offset: o };
    b.transforms = las::Vector {
        x: t(offset[0]),
        y: t(offset[1]),
        z: t(offset[2]),
    };
    let mut header = b.into_header().unwrap();
    if let Some(w) = wkt {
        header.set_wkt_crs(w).unwrap();
    }
    let mut w = las::Writer::from_path(dst, header).unwrap();
    for p in reader.read_all().unwrap().points() {
        let mut p = p.unwrap();
        p.nir = None;
        p.extra_bytes.clear();
        w.write_point(p).unwrap();
    }
    w.close().unwrap();
}

/// A tile re-quantised at 1 mm with offsets on no common lattice with the 1 cm tiles (5 mm
/// off, as ARSO's): combined with the others, the DEM is byte for byte the single-scale one.
#[test]
fn mixed_scales_and_offsets_give_the_same_dem() {
    let dir = tempfile::tempdir().unwrap();
    let tiles = ign_tiles();
    let odd = dir.path().join("odd.las");
    requantise(&tiles[2], &odd, 0.001, [770000.005, 6277000.005, 0.005]);
    let info = FileInfo::read(&odd).unwrap();
    assert_eq!(info.scale, [0.001; 3]);
    let (a, _) = read(&tiles[2..3], &Filter::default(), ReadOptions::default());
    let (b, _) = read(
        std::slice::from_ref(&odd),
        &Filter::default(),
        ReadOptions::default(),
    );
    assert_eq!(a, b, "the same doubles whatever the encoding");
    // With its neighbour at 1 cm, offset 0.
    let names = [s(&tiles[2]), s(&tiles[3])];
    let base = dem(&names, &[], &dir.path().join("a.tif"));
    assert_eq!(
        dem(&[s(&odd), names[1]], &[], &dir.path().join("b.tif")),
        base
    );
    // A binary scale has no decimal lattice: the tiles' block index keeps its points wide, and
    // the tiled DEM is still the sweep's.
    let bin = dir.path().join("bin.las");
    requantise(&tiles[2], &bin, 1.0 / 1024.0, [770000.0, 6277000.0, 0.0]);
    let with_bin = [s(&bin), names[1]];
    assert!(
        dem(&with_bin, &["--engine", "tiles"], &dir.path().join("c.tif"))
            == dem(&with_bin, &["--engine", "sweep"], &dir.path().join("d.tif")),
        "the tiled and swept DEMs with a binary scale differ"
    );
}

/// `info --classes --json` against laspy on the same files: counts by class, return number and
/// number of returns, ranges of x, y, z, intensity and GPS time, the header's counts by return.
#[test]
fn info_agrees_with_laspy() {
    if !data::python(&["laspy", "lazrs"], "info_agrees_with_laspy") {
        return;
    }
    let script = r#"
import sys, json, laspy, numpy as np
out = []
for f in sys.argv[1:]:
    l = laspy.read(f)
    h = l.header
    cnt = lambda a: {str(int(k)): int(v) for k, v in zip(*np.unique(np.asarray(a), return_counts=True))}
    out.append({
        "points": int(h.point_count),
        "classes": cnt(l.classification),
        "by_return": cnt(l.return_number),
        "by_returns": cnt(l.number_of_returns),
        "min": [float(np.min(l.x)), float(np.min(l.y)), float(np.min(l.z))],
        "max": [float(np.max(l.x)), float(np.max(l.y)), float(np.max(l.z))],
        "intensity": [int(np.min(l.intensity)), int(np.max(l.intensity))],
        "gps_time": [float(np.min(l.gps_time)), float(np.max(l.gps_time))],
        "header_by_return": [int(v) for v in h.number_of_points_by_return],
        "vlrs": len(h.vlrs) + len(l.evlrs or []),
    })
print(json.dumps(out))
"#;
    let files = [
        shared("lidar/startinpy_small.laz"),
        shared("lidar/lidR_Topography.laz"),
        shared("lidar/ign_50m_tiles/test_data_77055_627760_LA93_IGN69.laz"),
    ];
    let o = Command::new("python3")
        .args(["-c", script])
        .args(&files)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let want: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut args = vec!["info", "--classes", "--json", "--keep-withheld"];
    args.extend(files.iter().map(|f| s(f)));
    let got: serde_json::Value = serde_json::from_slice(&sweeptin(&args).stdout).unwrap();
    for (k, w) in want.as_array().unwrap().iter().enumerate() {
        let g = &got["files"][k];
        let st = &g["stats"];
        assert_eq!(st["points"], w["points"], "{k}");
        for key in [
            "classes",
            "by_return",
            "by_returns",
            "intensity",
            "gps_time",
        ] {
            assert_eq!(st[key], w[key], "{k} {key}");
        }
        for key in ["min", "max"] {
            for a in 0..3 {
                let (x, y) = (st[key][a].as_f64().unwrap(), w[key][a].as_f64().unwrap());
                assert!((x - y).abs() < 1e-6, "{k} {key} {a}: {x} vs {y}");
            }
        }
        let hb: Vec<u64> = serde_json::from_value(g["points_by_return"].clone()).unwrap();
        let wb: Vec<u64> = serde_json::from_value(w["header_by_return"].clone()).unwrap();
        assert_eq!(
            hb[..wb.len().min(hb.len())],
            wb[..wb.len().min(hb.len())],
            "{k}"
        );
        // laspy keeps the LASzip VLR to itself.
        let vlrs = g["vlrs"].as_array().unwrap();
        let listed = vlrs
            .iter()
            .filter(|v| v["user_id"] != "laszip encoded")
            .count();
        assert_eq!(listed as u64, w["vlrs"], "{k}");
    }
    assert_eq!(got["summary"]["files"], 3);
}

/// `plan` takes a `.vpc`, an `@list` or a quoted glob like a single run: the plan names every
/// file (by absolute path, in the stored command line too).
#[test]
fn a_plan_of_a_vpc_list_or_glob_names_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let tiles = ign_tiles();
    let names: Vec<&str> = tiles.iter().map(|t| s(t)).collect();
    let vpc = dir.path().join("ign.vpc");
    let mut args = vec!["index"];
    args.extend_from_slice(&names);
    args.extend_from_slice(&["-o", s(&vpc)]);
    sweeptin(&args);
    let list = dir.path().join("l.txt");
    std::fs::write(&list, names.join("\n")).unwrap();
    let at = format!("@{}", s(&list));
    let pattern = format!("{}/*.laz", s(&shared("lidar/ign_50m_tiles")));
    for (k, input) in [s(&vpc), at.as_str(), pattern.as_str()].iter().enumerate() {
        let job = dir.path().join(format!("job{k}"));
        sweeptin(&[
            "plan",
            "dem",
            input,
            "--cell",
            "0.5",
            "--tile",
            "50",
            "-o",
            s(&job),
        ]);
        let plan: serde_json::Value =
            serde_json::from_slice(&std::fs::read(job.join("plan.json")).unwrap()).unwrap();
        let files: Vec<PathBuf> = plan["files"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| PathBuf::from(f["path"].as_str().unwrap()))
            .collect();
        let want: Vec<PathBuf> = tiles.iter().map(|t| t.canonicalize().unwrap()).collect();
        assert_eq!(files, want, "{input}");
        let stored: Vec<&str> = plan["args"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_str().unwrap())
            .collect();
        for w in &want {
            assert!(stored.contains(&s(w)), "{input}: {stored:?}");
        }
    }
}

/// Writes `n` points as LAS `version` in point format `format`, then sets the header's legacy
/// 32-bit point count (offset 107) to `legacy`.
fn las_with_legacy_count(path: &Path, version: (u8, u8), format: u8, n: u32, legacy: u32) {
    let mut b = las::Builder::from(version);
    b.point_format = las::point::Format::new(format).unwrap();
    let mut w = las::Writer::from_path(path, b.into_header().unwrap()).unwrap();
    for i in 0..n {
        w.write_point(las::Point {
            x: f64::from(i % 20),
            y: f64::from(i / 20),
            z: f64::from(i % 7),
            gps_time: Some(f64::from(i)),
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
    let mut bytes = std::fs::read(path).unwrap();
    bytes[107..111].copy_from_slice(&legacy.to_le_bytes());
    std::fs::write(path, bytes).unwrap();
}

/// A LAS 1.4 format-6 file whose legacy count (which must be 0) said 100 of its 400 points was
/// read as 100 points; a LAS 1.2 header announcing 100 of 400 records was read short without a
/// word.
#[test]
fn point_counts_that_disagree_with_the_file() {
    let d = tempfile::tempdir().unwrap();
    let wrong = d.path().join("wrong_legacy.las");
    las_with_legacy_count(&wrong, (1, 4), 6, 400, 100);
    let info = FileInfo::read(&wrong).unwrap();
    assert_eq!(info.point_count, 400);
    assert!(
        info.warnings
            .iter()
            .any(|w| w.contains("legacy point count 100") && w.contains("using 400")),
        "{:?}",
        info.warnings
    );
    let (pts, _) = read(&[wrong], &Filter::default(), ReadOptions::default());
    assert_eq!(pts.len(), 400);
    // Formats 0-5 keep the legacy count (R15), unless the file's length fits only the 64-bit
    // one (legacy 600 was "the file is truncated", legacy 100 read 100 points).
    for legacy in [100, 600] {
        let f = d.path().join(format!("pf1_{legacy}.las"));
        las_with_legacy_count(&f, (1, 4), 1, 400, legacy);
        assert_eq!(FileInfo::read(&f).unwrap().point_count, 400, "{legacy}");
        let (pts, _) = read(&[f], &Filter::default(), ReadOptions::default());
        assert_eq!(pts.len(), 400);
    }
    let short = d.path().join("short.las");
    las_with_legacy_count(&short, (1, 2), 1, 400, 100);
    let info = FileInfo::read(&short).unwrap();
    assert_eq!(info.point_count, 100);
    assert!(
        info.warnings
            .iter()
            .any(|w| w.contains("room for 300 more points")),
        "{:?}",
        info.warnings
    );
}

/// Writes a small LAS 1.4 file at `path` whose WKT says EPSG `code`.
fn las_with_crs(path: &Path, code: u32, dx: f64) {
    let mut b = las::Builder::from((1, 4));
    b.point_format = las::point::Format::new(6).unwrap();
    let mut header = b.into_header().unwrap();
    let wkt = format!(r#"PROJCS["test {code}",AUTHORITY["EPSG","{code}"]]"#);
    header.set_wkt_crs(wkt.into_bytes()).unwrap();
    let mut w = las::Writer::from_path(path, header).unwrap();
    for i in 0..100u32 {
        w.write_point(las::Point {
            x: dx + f64::from(i % 10),
            y: f64::from(i / 10),
            z: f64::from(i % 3),
            gps_time: Some(0.0),
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
}

/// Files that declare different CRSs are refused together, unless `--crs` says what they are
/// (PDAL's `override_srs`): the refusal could not be overridden.
#[test]
fn crs_given_overrides_files_that_disagree() {
    let d = tempfile::tempdir().unwrap();
    let (a, b) = (d.path().join("a.las"), d.path().join("b.las"));
    las_with_crs(&a, 2154, 0.0);
    las_with_crs(&b, 2949, 10.0);
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_sweeptin"))
            .current_dir(d.path())
            .args([
                "dem", "a.las", "b.las", "--cell", "1", "-o", "d.tif", "--json",
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&[]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("same CRS"));
    for engine in ["tiles", "sweep"] {
        let o = run(&["--crs", "EPSG:2154", "--engine", engine]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{engine}: {e}");
        assert!(
            e.contains("b.las: declares CRS") && e.contains("(--crs)"),
            "{e}"
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["run"]["points_read"], 200, "{v}");
    }
}

/// What a header says (here: records past the announced count) reaches a plan's user: `plan`
/// prints it and keeps it in `plan.json`, and each task that reads the file prints it and
/// records it; before, plan tasks said nothing of it.
#[test]
fn plans_and_their_tasks_warn_of_what_headers_say() {
    let d = tempfile::tempdir().unwrap();
    las_with_legacy_count(&d.path().join("short.las"), (1, 2), 1, 400, 100);
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
            .current_dir(d.path())
            .args(args)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{args:?}: {e}");
        (String::from_utf8_lossy(&o.stdout).into_owned(), e)
    };
    let (_, e) = run(&[
        "plan",
        "dem",
        "short.las",
        "--cell",
        "1",
        "--tile",
        "10",
        "-o",
        "job",
    ]);
    assert!(
        e.contains("short.las: the file holds room for 300 more points"),
        "{e}"
    );
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path().join("job/plan.json")).unwrap())
            .unwrap();
    assert!(
        plan["warnings"][0]
            .as_str()
            .unwrap()
            .contains("room for 300"),
        "{plan}"
    );
    let (out, e) = run(&["run", "job/plan.json", "--task", "0", "--json"]);
    assert!(
        e.contains("warning: task 0: ") && e.contains("room for 300"),
        "{e}"
    );
    let record: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        record["warnings"][0]
            .as_str()
            .unwrap()
            .contains("room for 300"),
        "{record}"
    );
}
