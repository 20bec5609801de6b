//! The input side on the real files: COPC read through its octree (the same points as a plain
//! read, checked against laspy), files skipped outside a box, `.vpc` lists, `@lists` and globs,
//! files with different scales and offsets combined in world coordinates.
//!
//! COPC copies are written at run time by `scripts/make_copc.py` (copclib, independent of
//! sweeptin); a small one, `tests/data/lidR_Topography.copc.laz`, is committed.

#[path = "support/data.rs"]
mod data;

use data::shared;
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

/// Writes a COPC copy of `src` with copclib; `None` (skipped) locally without the Python tools.
fn make_copc(src: &Path, dst: &Path, page_depth: u32, test: &str) -> bool {
    if !data::python(&["copclib", "laspy", "lazrs"], test) {
        return false;
    }
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scripts/make_copc.py");
    let o = Command::new("python3")
        .arg(script)
        .arg(src)
        .arg(dst)
        .args(["--page-depth", &page_depth.to_string()])
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

/// The big ARSO tile as COPC (written at run time): a 100 m box decodes a few percent of it and
/// keeps exactly the points a full read keeps. (Slow in debug builds: ignored; run with
/// `cargo test --release --test inputs -- --ignored`.)
#[test]
#[ignore]
fn arso_copc_box() {
    let Some(src) = data::optional("lidar/arso_TM_511_122_from_ept.laz", "arso_copc_box") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let copc = dir.path().join("arso.copc.laz");
    if !make_copc(&src, &copc, 3, "arso_copc_box") {
        return;
    }
    let b = BBox::new(511400.0, 122400.0, 511500.0, 122500.0).unwrap();
    let f = Filter {
        bbox: Some(b),
        ..Filter::keep_all()
    };
    let (got, r) = read(&[copc.clone()], &f, ReadOptions::default());
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
