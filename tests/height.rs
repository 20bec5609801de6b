//! `sweeptin height` (issue 42, item 3): the height above the ground TIN of every point, checked
//! against an independent TIN (spade, barycentric on the containing triangle); the canopy
//! height route `dem --returns first --z-from HeightAboveGround`; `--replace-z`; refusals.

use crate::cli;
use crate::data;

use spade::{DelaunayTriangulation, FloatTriangulation as _, Point2, Triangulation as _};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use sweeptin::input::las::{Filter, LidarPoint, LidarReader};
use sweeptin::pipeline::RunOptions;
use sweeptin::pipeline::height::{Ground, HeightJob, height};

/// Runs `sweeptin ARGS…`, success or not.
fn run(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap()
}

fn read(paths: &[PathBuf], filter: &Filter) -> Vec<LidarPoint> {
    LidarReader::open(paths, filter)
        .unwrap()
        .read_all()
        .unwrap()
}

/// A TIN of `points` (x, y, value) built by spade, exact duplicates kept first (as
/// `--duplicates first`), interpolated barycentrically; `None` outside its hull.
struct SpadeTin {
    tin: DelaunayTriangulation<Point2<f64>>,
    z: Vec<f64>,
}

impl SpadeTin {
    fn new(points: impl Iterator<Item = [f64; 3]>) -> SpadeTin {
        let mut tin = DelaunayTriangulation::<Point2<f64>>::new();
        let mut z = Vec::new();
        let mut seen = HashSet::new();
        for [x, y, v] in points {
            if !seen.insert((x.to_bits(), y.to_bits())) {
                continue;
            }
            let h = tin.insert(Point2::new(x, y)).unwrap();
            if h.index() >= z.len() {
                z.resize(h.index() + 1, f64::NAN);
            }
            z[h.index()] = v;
        }
        SpadeTin { tin, z }
    }

    fn at(&self, x: f64, y: f64) -> Option<f64> {
        self.tin
            .barycentric()
            .interpolate(|v| self.z[v.fix().index()], Point2::new(x, y))
    }
}

fn ground_tin(paths: &[PathBuf]) -> SpadeTin {
    let f = Filter {
        classes: Some(vec![2]),
        ..Filter::default()
    };
    SpadeTin::new(read(paths, &f).iter().map(|p| [p.x, p.y, p.z]))
}

/// The heights written, by point index, read back through `--z-from` (points without one are
/// missing).
fn heights(path: &Path) -> HashMap<u64, f64> {
    let f = Filter {
        z_from: Some("HeightAboveGround".into()),
        ..Filter::keep_all()
    };
    read(&[path.to_path_buf()], &f)
        .iter()
        .map(|p| (p.index, p.z))
        .collect()
}

fn options() -> RunOptions {
    RunOptions {
        mem: 64 << 20,
        tiles: Some(sweeptin::TileOptions::default()),
        ..RunOptions::default()
    }
}

/// Every point's HeightAboveGround is its z minus the ground TIN (spade's, on the class-2
/// points) at its position; points outside the ground's hull have none (NaN), and only they.
/// Two files (the IGN tiles side by side) make one ground, each written to its own output.
#[test]
fn height_above_ground_equals_an_independent_tin() {
    let dir = tempfile::tempdir().unwrap();
    for inputs in [
        vec![data::shared("lidar/lidR_Topography.laz")],
        data::ign_tiles()[..2].to_vec(),
    ] {
        let outputs: Vec<PathBuf> = (0..inputs.len())
            .map(|k| dir.path().join(format!("hag{k}.laz")))
            .collect();
        let job = HeightJob {
            inputs: inputs.clone(),
            outputs: outputs.clone(),
            ground: Ground::default(),
            replace_z: false,
        };
        let s = height(&job, &options()).unwrap();
        let ground = ground_tin(&inputs);
        let (mut outside, mut differ, mut all) = (0, 0, 0);
        for (input, output) in inputs.iter().zip(&outputs) {
            let got = heights(output);
            for p in read(std::slice::from_ref(input), &Filter::keep_all()) {
                all += 1;
                match (ground.at(p.x, p.y), got.get(&p.index)) {
                    (None, None) => outside += 1,
                    (Some(g), Some(&h)) => {
                        // Exactly cocircular ground points may be split by another diagonal.
                        if (h - (p.z - g)).abs() > 1e-9 {
                            differ += 1;
                        }
                    }
                    (g, h) => panic!(
                        "{}: point {}: {g:?} against {h:?}",
                        input.display(),
                        p.index
                    ),
                }
            }
        }
        assert_eq!(all, s.points);
        assert_eq!(outside, s.outside);
        assert!(differ * 1000 <= all, "{differ} of {all} heights differ");
    }
}

/// The canopy height route: `height`, then `dem --returns first --z-from HeightAboveGround`
/// (an ASCII grid): every cell is the TIN of the first returns' heights (z − ground) at its
/// centre, within f32 rounding.
#[test]
fn canopy_height_model_from_z_from_is_the_tin_of_first_return_heights() {
    let dir = tempfile::tempdir().unwrap();
    let src = data::shared("lidar/lidR_Topography.laz");
    let hag = dir.path().join("hag.laz");
    let chm = dir.path().join("chm.asc");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    cli::ok(&["height", &s(&src), "-o", &s(&hag), "-q"]);
    cli::ok(&[
        "dem",
        &s(&hag),
        "--returns",
        "first",
        "--z-from",
        "HeightAboveGround",
        "--cell",
        "2",
        "-o",
        &s(&chm),
        "-q",
    ]);
    let ground = ground_tin(std::slice::from_ref(&src));
    let first = Filter {
        returns: sweeptin::input::las::Returns::First,
        ..Filter::default()
    };
    let want = SpadeTin::new(
        read(&[src], &first)
            .iter()
            .filter_map(|p| Some([p.x, p.y, p.z - ground.at(p.x, p.y)?])),
    );
    let text = std::fs::read_to_string(&chm).unwrap();
    let mut lines = text.lines();
    let mut head = HashMap::new();
    for _ in 0..6 {
        let l = lines.next().unwrap();
        let mut it = l.split_whitespace();
        let k = it.next().unwrap().to_ascii_lowercase();
        head.insert(k, it.next().unwrap().parse::<f64>().unwrap());
    }
    let (cols, rows) = (head["ncols"] as usize, head["nrows"] as usize);
    let cell = head["cellsize"];
    let nodata = head["nodata_value"];
    // The first cell's centre (the grid says it by its centre or by its corner).
    let (x0, y0) = match (head.get("xllcenter"), head.get("yllcenter")) {
        (Some(&x), Some(&y)) => (x, y),
        _ => (
            head["xllcorner"] + cell / 2.0,
            head["yllcorner"] + cell / 2.0,
        ),
    };
    let (mut cells, mut differ) = (0, 0);
    for (r, line) in lines.enumerate() {
        for (c, v) in line.split_whitespace().enumerate() {
            let v: f64 = v.parse().unwrap();
            if v == nodata {
                continue;
            }
            let (x, y) = (x0 + c as f64 * cell, y0 + (rows - 1 - r) as f64 * cell);
            let Some(w) = want.at(x, y) else { continue };
            cells += 1;
            if (v - w).abs() > 1e-5 * w.abs().max(1.0) {
                differ += 1;
            }
        }
    }
    assert!(cells > cols * rows / 2, "{cells} cells compared");
    assert!(differ * 1000 <= cells, "{differ} of {cells} cells differ");
}

/// `--replace-z`: z becomes the height (ground points 0, exactly), every other attribute as it
/// was; points outside the ground's hull keep their z and are flagged withheld.
#[test]
fn replace_z_normalizes_and_withholds_points_outside_the_ground() {
    let dir = tempfile::tempdir().unwrap();
    let src = data::shared("lidar/startinpy_small.laz");
    let out = dir.path().join("norm.las");
    let job = HeightJob {
        inputs: vec![src.clone()],
        outputs: vec![out.clone()],
        ground: Ground::default(),
        replace_z: true,
    };
    let s = height(&job, &options()).unwrap();
    let before = read(std::slice::from_ref(&src), &Filter::keep_all());
    let after = read(std::slice::from_ref(&out), &Filter::keep_all());
    assert_eq!(before.len(), after.len());
    let ground = ground_tin(&[src]);
    let mut withheld = 0;
    for (a, b) in before.iter().zip(&after) {
        assert_eq!((a.x, a.y, a.classification), (b.x, b.y, b.classification));
        match ground.at(a.x, a.y) {
            None => {
                assert_eq!(b.z, a.z);
                assert!(b.flags & LidarPoint::WITHHELD != 0);
                withheld += 1;
            }
            Some(g) => {
                assert!(
                    (b.z - (a.z - g)).abs() <= 0.5e-3 + 1e-9,
                    "{} {}",
                    b.z,
                    a.z - g
                );
                if a.classification == 2 {
                    assert_eq!(b.z, 0.0);
                }
            }
        }
    }
    assert_eq!(withheld, s.outside);
    let info = sweeptin::input::las::FileInfo::read(&out).unwrap();
    assert!(info.bounds.max[2] < 40.0, "the header's z bounds follow");
}

/// Refusals: several inputs to one `-o` file (exit 2), a `.copc.laz` output (exit 2 before
/// any work: `height` writes plain LAZ, which under that name passed for a COPC file), files
/// without ground points (exit 3, no output), `--z-from` an attribute the file lacks (exit 3,
/// naming those it has).
#[test]
fn height_refuses_what_it_cannot_do() {
    let dir = tempfile::tempdir().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let a = data::shared("lidar/lidR_Topography.laz");
    let b = data::shared("lidar/startinpy_small.laz");
    let out = dir.path().join("x.laz");
    let o = run(&["height", &s(&a), &s(&b), "-o", &s(&out), "-q"]);
    assert_eq!(o.status.code(), Some(2));
    let copc = dir.path().join("x.copc.laz");
    let o = run(&["height", &s(&b), "-o", &s(&copc), "-q"]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("not COPC") && e.contains("x.laz"), "{e}");
    assert!(!copc.exists());
    let o = run(&[
        "height",
        &s(&a),
        "-o",
        &s(&out),
        "--ground-class",
        "17",
        "-q",
    ]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.exists());
    let tif = dir.path().join("x.tif");
    let o = run(&["dem", &s(&a), "--z-from", "Nope", "-o", &s(&tif), "-q"]);
    assert_eq!(o.status.code(), Some(3));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("no such extra-bytes attribute"), "{e}");
    // The @list or `.vpc` given as the input is an input too: never replaced (it was, exit 0);
    // a name that says neither LAS nor LAZ is refused (LAS was written under `.txt`).
    let list = dir.path().join("l.txt");
    std::fs::write(&list, format!("{}\n", s(&b))).unwrap();
    let vpc = dir.path().join("one.vpc");
    let o = run(&["index", &s(&b), "-o", &s(&vpc)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (input, output) in [
        (format!("@{}", s(&list)), &list),
        (s(&vpc), &vpc),
        (s(&b), &dir.path().join("y.txt")),
    ] {
        let before = std::fs::read(output).ok();
        let o = run(&["height", &input, "-o", &s(output), "-q"]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {e}", output.display());
        assert_eq!(
            std::fs::read(output).ok(),
            before,
            "{} changed",
            output.display()
        );
    }
}
