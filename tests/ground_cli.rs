//! `sweeptin ground` on the command line: the points written back with their new classes,
//! byte for byte the same for any `--threads` and `--mem`, several files classified together,
//! the output rules, the empty file, and COPC output.

use crate::cli;
use crate::data;

use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::ground::{GroundParams, classify_files};
use sweeptin::input::las::{Filter, LidarPoint, LidarReader};

fn read(path: &Path) -> Vec<LidarPoint> {
    LidarReader::open(&[path], &Filter::keep_all())
        .unwrap()
        .read_all()
        .unwrap()
}

fn status(args: &[&std::ffi::OsStr]) -> (i32, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn ground_writes_every_point_back_with_the_library_classes() {
    let input = data::shared("lidar/startinpy_small.laz");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("classified.laz");
    let args: [&std::ffi::OsStr; 5] = [
        "ground".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ];
    let o = cli::ok(&args);
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (before, after) = (read(&input), read(&out));
    assert_eq!(before.len(), after.len());
    let (mut store, s) = classify_files(
        std::slice::from_ref(&input),
        &GroundParams::default(),
        1 << 30,
        &std::env::temp_dir(),
        &mut |_, _, _| {},
    )
    .unwrap();
    assert_eq!(summary["ground"], s.ground);
    assert_eq!(summary["points"], before.len() as u64);
    for (i, (a, b)) in before.iter().zip(&after).enumerate() {
        assert_eq!((a.x, a.y, a.z), (b.x, b.y, b.z), "point {i} moved");
        assert_eq!(
            (a.return_number, a.number_of_returns, a.flags),
            (b.return_number, b.number_of_returns, b.flags)
        );
        assert_eq!(b.classification, store.get(i as u64).unwrap(), "point {i}");
    }
}

fn ground_odir(files: &[PathBuf], odir: &Path, extra: &[&str]) {
    let mut args: Vec<&std::ffi::OsStr> = vec!["ground".as_ref()];
    args.extend(files.iter().map(|f| f.as_os_str()));
    args.extend(["--odir".as_ref(), odir.as_os_str(), "--quiet".as_ref()]);
    args.extend(extra.iter().map(|s| std::ffi::OsStr::new(*s)));
    cli::ok(&args);
}

#[test]
fn adjacent_tiles_classified_together_are_byte_identical_for_any_threads_and_mem() {
    let files = data::ign_tiles();
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    // 24 MiB: the block index spills and the blocks run in small batches.
    ground_odir(
        &files,
        a.path(),
        &["--step", "2", "--threads", "1", "--mem", "24M"],
    );
    ground_odir(
        &files,
        b.path(),
        &["--step", "2", "--threads", "2", "--mem", "1G"],
    );
    let mut ground = 0;
    for f in &files {
        let name = f.file_name().unwrap();
        let (x, y) = (a.path().join(name), b.path().join(name));
        assert_eq!(
            std::fs::read(&x).unwrap(),
            std::fs::read(&y).unwrap(),
            "{name:?}"
        );
        ground += read(&x).iter().filter(|p| p.classification == 2).count();
    }
    // The files were classified together: the classes are those of the whole set.
    let params = GroundParams {
        step: 2.0,
        ..GroundParams::default()
    };
    let (_, s) = classify_files(
        &files,
        &params,
        1 << 30,
        &std::env::temp_dir(),
        &mut |_, _, _| {},
    )
    .unwrap();
    assert_eq!(ground as u64, s.ground);
}

/// Writes `pts` as a LAS 1.2 file (point format 1) with classes `classes`.
fn write_las(path: &Path, pts: &[[f64; 3]], classes: &[u8]) {
    use las::{Builder, Point, Transform, Vector, Writer};
    let mut b = Builder::from((1, 2));
    b.point_format = las::point::Format::new(1).unwrap();
    let t = |offset| Transform {
        scale: 0.001,
        offset,
    };
    b.transforms = Vector {
        x: t(500_000.0),
        y: t(4_000_000.0),
        z: t(0.0),
    };
    let mut w = Writer::from_path(path, b.into_header().unwrap()).unwrap();
    for (p, &c) in pts.iter().zip(classes) {
        w.write_point(Point {
            x: 500_000.0 + p[0],
            y: 4_000_000.0 + p[1],
            z: p[2],
            classification: las::point::Classification::new(c).unwrap(),
            gps_time: Some(0.0),
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
}

/// `sweeptin ground INPUT -o OUT --quiet`, which must succeed.
fn ground_to(input: &Path, out: &Path) {
    cli::ok(&[
        "ground".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--quiet".as_ref(),
    ]);
}

#[test]
fn a_low_outlier_is_written_as_class_7_in_a_las_output() {
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = (dir.path().join("in.las"), dir.path().join("out.las"));
    let mut pts = Vec::new();
    for i in 0..80 {
        for j in 0..80 {
            pts.push([i as f64 * 0.5, j as f64 * 0.5, 100.0 + 0.05 * i as f64]);
        }
    }
    pts.push([20.1, 20.1, 51.0]);
    write_las(&input, &pts, &vec![1; pts.len()]);
    ground_to(&input, &out);
    let got = read(&out);
    assert_eq!(got.last().unwrap().classification, 7);
    assert!(got[..got.len() - 1].iter().all(|p| p.classification == 2));
}

#[test]
fn an_empty_file_is_written_with_no_ground() {
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = (dir.path().join("empty.las"), dir.path().join("out.laz"));
    write_las(&input, &[], &[]);
    let o = cli::ok(&[
        "ground".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("no ground"));
    assert!(read(&out).is_empty());
}

#[test]
fn ground_output_never_replaces_an_input_nor_a_directory() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.las");
    write_las(
        &input,
        &[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]],
        &[0, 0, 0],
    );
    let before = std::fs::read(&input).unwrap();
    let (code, err) = status(&[
        "ground".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        input.as_os_str(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(std::fs::read(&input).unwrap(), before);
    let (code, err) = status(&[
        "ground".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        dir.path().as_os_str(),
    ]);
    assert_eq!(code, 4, "{err}");
    // Several inputs need --odir; --odir must be a directory.
    let (code, err) = status(&[
        "ground".as_ref(),
        input.as_os_str(),
        input.as_os_str(),
        "-o".as_ref(),
        dir.path().join("x.laz").as_os_str(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--odir"), "{err}");
    // --odir where the inputs are: the output would be the input itself.
    let (code, err) = status(&[
        "ground".as_ref(),
        input.as_os_str(),
        "--odir".as_ref(),
        dir.path().as_os_str(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(std::fs::read(&input).unwrap(), before);
    // An --odir that is missing or a file: the environment, exit 4, as a missing directory of
    // -o is (it was exit 2).
    for odir in [dir.path().join("missing"), input.clone()] {
        let (code, err) = status(&[
            "ground".as_ref(),
            input.as_os_str(),
            "--odir".as_ref(),
            odir.as_os_str(),
        ]);
        assert_eq!(code, 4, "{err}");
        assert!(err.contains("--odir"), "{err}");
    }
    // A --tmp-dir that does not exist, refused before the work as other jobs do (it ran,
    // exit 0, when nothing spilled).
    let out = dir.path().join("t.laz");
    let (code, err) = status(&[
        "ground".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--tmp-dir".as_ref(),
        dir.path().join("none").as_os_str(),
    ]);
    assert_eq!(code, 4, "{err}");
    assert!(err.contains("does not exist") && !out.exists(), "{err}");
    // Seed cells too small for coordinates this far out: the file and --step named (the
    // message named neither the file nor, checked over all the points, the option).
    let far = dir.path().join("far.las");
    let p = |x: f64, y: f64| [x, y, 300.0]; // at (500,000, 4,000,000)
    write_las(
        &far,
        &[p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0), p(1.0, 1.0)],
        &[0; 4],
    );
    for step in ["1e-4", "1e-3"] {
        let (code, err) = status(&[
            "ground".as_ref(),
            far.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "--step".as_ref(),
            step.as_ref(),
        ]);
        assert_eq!(code, 2, "--step {step}: {err}");
        assert!(
            err.contains("far.las") && err.contains("--step") && !out.exists(),
            "{err}"
        );
    }
    // A ground plan over them is refused when made (it was made, and every task failed).
    let job = dir.path().join("job");
    let (code, err) = status(&[
        "plan".as_ref(),
        "ground".as_ref(),
        far.as_os_str(),
        "--step".as_ref(),
        "1e-3".as_ref(),
        "--tile".as_ref(),
        "25".as_ref(),
        "-o".as_ref(),
        job.as_os_str(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("far.las") && err.contains("--step"), "{err}");
    assert!(!job.join("plan.json").exists());
}

/// The points of a LAS/LAZ/COPC file as a sorted multiset: position, class, returns, flags.
fn multiset(points: &[LidarPoint]) -> Vec<(u64, u64, u64, u8, u8, u8, u8)> {
    let mut v: Vec<_> = points
        .iter()
        .map(|p| {
            let (x, y, z) = (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
            let (c, r, n, f) = (
                p.classification,
                p.return_number,
                p.number_of_returns,
                p.flags,
            );
            (x, y, z, c, r, n, f)
        })
        .collect();
    v.sort_unstable();
    v
}

/// `ground -o X.copc.laz` (issue 42) writes the points `-o X.laz` writes, reordered into a COPC
/// octree: the same multiset of points and classes through sweeptin's COPC reader and through
/// copclib (every node's points in its voxel of the info's cube), the CRS kept (GeoTIFF
/// keys become WKT with the code); several nodes on a larger file; a point format with NIR is
/// refused before the work, naming `-o X.laz`. (About 6 s in a debug build.)
#[test]
fn ground_copc_output_holds_the_points_of_the_laz_output() {
    let name = "ground_copc_output_holds_the_points_of_the_laz_output";
    let dir = tempfile::tempdir().unwrap();
    let ground = ground_to;
    let topo = data::shared("lidar/lidR_Topography.laz");
    let (laz, copc) = (dir.path().join("t.laz"), dir.path().join("t.copc.laz"));
    ground(&topo, &laz);
    ground(&topo, &copc);
    assert_eq!(multiset(&read(&copc)), multiset(&read(&laz)));
    let info = |p: &Path| -> serde_json::Value {
        let o = cli::ok(&["info".as_ref(), "--json".as_ref(), p.as_os_str()]);
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["files"][0].clone()
    };
    let i = info(&copc);
    assert!(i["copc"]["nodes"].as_u64().unwrap() >= 1, "{i}");
    assert_eq!(i["point_format"], 6);
    assert_eq!(i["crs"]["epsg"], info(&laz)["crs"]["epsg"]);
    assert_eq!(i["creation"], info(&laz)["creation"]);
    // A file of several octree nodes: the points of the input, with classes.
    let ahn = data::shared("lidar/ahn3_delft_cropped_2.laz");
    let ahn_copc = dir.path().join("a.copc.laz");
    ground(&ahn, &ahn_copc);
    assert!(info(&ahn_copc)["copc"]["nodes"].as_u64().unwrap() > 1);
    let strip = |v: Vec<LidarPoint>| {
        let mut v: Vec<_> = v
            .iter()
            .map(|p| (p.x.to_bits(), p.y.to_bits(), p.z.to_bits(), p.flags))
            .collect();
        v.sort_unstable();
        v
    };
    assert_eq!(strip(read(&ahn_copc)), strip(read(&ahn)));
    if data::python(&["copclib", "laspy", "lazrs"], name) {
        let script = "import sys, copclib, laspy, numpy as np\n\
            def rows(x, y, z, c):\n\
            \x20   a = np.stack([np.round(np.asarray(v, dtype=float) * 1000) for v in (x, y, z, c)])\n\
            \x20   return a[:, np.lexsort(a[::-1])]\n\
            for copc, laz in ((sys.argv[1], sys.argv[2]), (sys.argv[3], None)):\n\
            \x20   r = copclib.FileReader(copc)\n\
            \x20   i, t = r.copc_config.copc_info, r.copc_config.las_header.scale\n\
            \x20   s = (t.x, t.y, t.z)\n\
            \x20   for n in r.GetAllNodes():\n\
            \x20       q, side = r.GetPoints(n), 2 * i.halfsize / 2 ** n.key.d\n\
            \x20       for v, c, k, e in zip((q.x, q.y, q.z), (i.center_x, i.center_y, i.center_z), (n.key.x, n.key.y, n.key.z), s):\n\
            \x20           lo = c - i.halfsize + k * side\n\
            \x20           assert lo - e <= min(v) and max(v) <= lo + side + e, (copc, n.key)\n\
            \x20   p = r.GetAllPoints()\n\
            \x20   got = rows(p.x, p.y, p.z, p.classification)\n\
            \x20   assert got.shape[1] == r.copc_config.las_header.point_count\n\
            \x20   if laz:\n\
            \x20       q = laspy.read(laz)\n\
            \x20       assert np.array_equal(got, rows(q.x, q.y, q.z, q.classification)), copc\n\
            print(len(r.GetAllNodes()))";
        let o = Command::new("python3")
            .args(["-c", script])
            .args([&copc, &laz, &ahn_copc])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    // Point format 8 (NIR): refused before the work, no file.
    let nir = dir.path().join("s.copc.laz");
    let (code, err) = status(&[
        "ground".as_ref(),
        data::shared("lidar/startinpy_small.laz").as_os_str(),
        "-o".as_ref(),
        nir.as_os_str(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("NIR") && err.contains("s.laz"), "{err}");
    assert!(!nir.exists());
    // `--odir` writes a COPC input as plain `.laz` under its name (as `height --odir` and
    // Python's `odir=`): a COPC file only when `-o` names one.
    let od = dir.path().join("od");
    std::fs::create_dir(&od).unwrap();
    let copc_in = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/lidR_Topography.copc.laz");
    cli::ok(&[
        "ground".as_ref(),
        copc_in.as_os_str(),
        "--odir".as_ref(),
        od.as_os_str(),
        "--quiet".as_ref(),
    ]);
    assert!(od.join("lidR_Topography.laz").exists());
    assert!(!od.join("lidR_Topography.copc.laz").exists());
    // copc-writer's index files go to $TMPDIR: one where no file can be made is refused before
    // the work (exit 4, naming it), no output.
    let none = dir.path().join("n.copc.laz");
    let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .env("TMPDIR", dir.path().join("none"))
        .args([
            "ground".as_ref(),
            copc_in.as_os_str(),
            "-o".as_ref(),
            none.as_os_str(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(err.contains("TMPDIR") && !none.exists(), "{err}");
}
