//! Plans with breaklines and trimming rings: a DEM plan (with contours) and a TIN plan over real
//! IGN ground points with 3-D lines (text and GeoJSON), a line that leaves the files, a hole and
//! a boundary, run with `run --all --jobs 2` and merged, give one sweep's raster bit for bit, its
//! contour lines and its triangle set. What a plan cannot prove is refused before anything is
//! written (lines without z, naming the file, line and vertex; `--clip-breaklines`;
//! `--no-flat-triangles`), the recipe the refusal gives works, and a task refuses a line file
//! that changed after planning. Lines whose heights disagree are warned of by `plan` as by one
//! run.

use crate::cli;
use crate::data;
use crate::geojson;
use crate::mesh;
use crate::plans;

use plans::{cells, plan_extent, records};
use std::path::Path;
use std::process::{Command, Output};

/// Four IGN 50 m tiles of ground points (LAS), 100 m × 100 m, 116,551 points.
fn ground() -> Vec<String> {
    [
        "77050_627755",
        "77050_627760",
        "77055_627755",
        "77055_627760",
    ]
    .iter()
    .map(|t| {
        let rel = format!("lidar/ign_50m_tiles/test_data_{t}_LA93_IGN69_ground.las");
        data::shared(&rel).display().to_string()
    })
    .collect()
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// `sweeptin ARGS…` expected to fail: its output.
fn fails(args: &[String]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap();
    assert!(!o.status.success(), "{args:?} did not fail");
    o
}

/// `a → b` in `n` pieces, `[x, y, z]` interpolated.
fn line(a: [f64; 3], b: [f64; 3], n: usize) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            std::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
        })
        .collect()
}

/// Polylines as a text breakline file (`x y z` a line, a blank line between polylines).
fn write_text(path: &Path, lines: &[Vec<[f64; 3]>]) {
    let text: Vec<String> = lines
        .iter()
        .map(|l| {
            l.iter()
                .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
                .collect()
        })
        .collect();
    std::fs::write(path, text.join("\n")).unwrap();
}

/// The 3-D lines of the tests in `dir`: (breakline files, the boundary ring, the hole).
///
/// - `lines.txt`: a diagonal across the four tiles, a line along the plan's tile edge
///   x = 770 550, and a line that leaves the files eastwards by 90 m (the tiles it reaches and
///   those between it and the points have tasks without files near them);
/// - `cross.geojson`: a line crossing the diagonal (cleaning splits both; every task finds the
///   same crossing);
/// - `boundary.txt`: a 24-gon inside the tiles; `hole.geojson`: a square polygon, both with z.
fn lines(dir: &Path) -> (Vec<String>, String, String) {
    let text = dir.join("lines.txt");
    write_text(
        &text,
        &[
            line(
                [770_505.25, 6_277_503.5, 21.0],
                [770_595.75, 6_277_596.25, 21.4],
                18,
            ),
            (0..10)
                .map(|k| {
                    [
                        770_550.0,
                        6_277_505.0 + 10.0 * k as f64,
                        20.8 + 0.05 * k as f64,
                    ]
                })
                .collect(),
            line(
                [770_580.0, 6_277_550.0, 21.0],
                [770_690.0, 6_277_562.5, 21.3],
                1,
            ),
        ],
    );
    let cross = dir.join("cross.geojson");
    geojson::write_lines(
        &cross,
        &[line(
            [770_510.5, 6_277_590.5, 21.2],
            [770_590.5, 6_277_510.5, 20.9],
            16,
        )],
    );
    let boundary = dir.join("boundary.txt");
    write_text(
        &boundary,
        &[(0..=24)
            .map(|k| {
                let t = std::f64::consts::TAU * (k % 24) as f64 / 24.0 + 0.3;
                [
                    ((770_550.0 + 44.0 * t.cos()) * 100.0).round() / 100.0,
                    ((6_277_550.0 + 44.0 * t.sin()) * 100.0).round() / 100.0,
                    ((21.0 + 0.3 * t.sin()) * 100.0).round() / 100.0,
                ]
            })
            .collect()],
    );
    let hole = dir.join("hole.geojson");
    std::fs::write(
        &hole,
        r#"{"type":"Polygon","coordinates":[[[770560,6277530,21.0],[770575,6277530,21.1],
        [770575,6277545,21.2],[770560,6277545,21.1],[770560,6277530,21.0]]]}"#,
    )
    .unwrap();
    (vec![s(&text), s(&cross)], s(&boundary), s(&hole))
}

/// `--breaklines F` for each file.
fn breaklines(files: &[String]) -> Vec<String> {
    files
        .iter()
        .flat_map(|f| ["--breaklines".to_string(), f.clone()])
        .collect()
}

/// A DEM plan with 3-D breaklines (one leaving the files) and a hole, with contours: the mosaic
/// and the stitched contours equal one sweep's over the plan's extent.
///
/// A ring may pass twice through a vertex exactly at its level (a pinch); where a stitcher
/// closes it depends on triangle order, so the rings are compared as cycles
/// (`mesh::contour_set` takes the smallest rotation).
#[test]
fn dem_plan_with_3d_breaklines_and_a_hole_equals_one_sweep() {
    let t = tempfile::tempdir().unwrap();
    let (bl, _, hole) = lines(t.path());
    let d = |n: &str| s(&t.path().join(n));
    let mut job: Vec<String> = vec!["dem".into()];
    job.extend(ground());
    job.extend(breaklines(&bl));
    job.extend(["--holes".into(), hole]);
    job.extend(["--cell", "0.5", "--interval", "0.25"].map(String::from));
    let mut plan = vec!["plan".to_string()];
    plan.extend(job.iter().cloned());
    plan.extend(["--contours".into(), d("planned.geojson")]);
    plan.extend(["--tile".into(), "50".into(), "-o".into(), d("job")]);
    let out = cli::ok(&plan);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("the lines reach beyond the input files"),
        "no warning for the line beyond the files"
    );
    let p = t.path().join("job/plan.json");
    let (_, n) = plan_extent(&p);
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
    assert_eq!(v["version"], 3, "a plan with lines is version 3");
    let recorded = &v["job"]["lines"]["breaklines"][0];
    assert_eq!(recorded["path"], bl[0].as_str());
    assert_eq!(
        recorded["bytes"].as_u64().unwrap(),
        std::fs::metadata(&bl[0]).unwrap().len()
    );
    assert_eq!(recorded["sha256"].as_str().unwrap().len(), 64);
    let tiles = v["tiles"].as_array().unwrap();
    assert!(
        tiles
            .iter()
            .any(|t| t["files"].as_array().unwrap().is_empty()),
        "no task beside the line that leaves the files: {tiles:?}"
    );
    cli::ok(&["run", &s(&p), "--all", "--jobs", "2", "-q"]);
    let recs = records(&t.path().join("job"), n);
    assert!(
        recs.iter()
            .all(|r| r["status"] == "done" || r["status"] == "empty")
    );
    cli::ok(&[
        "merge",
        &s(&p),
        "-o",
        &d("mosaic.tif"),
        "--contours",
        &d("merged.geojson"),
    ]);
    // One sweep (not tiles) over all the points and lines, on its own extent (the mosaic's).
    let mut one = job.clone();
    one.extend(["--engine", "sweep", "-q"].map(String::from));
    one.extend(["--contours".into(), d("one.geojson")]);
    one.extend(["-o".into(), d("one.tif")]);
    cli::ok(&one);
    let mosaic = cells(&t.path().join("mosaic.tif"));
    assert_eq!(
        mosaic,
        cells(&t.path().join("one.tif")),
        "the mosaic differs from one sweep"
    );
    // The line east of the files gave cells beyond them.
    let east = 770_600.0;
    let (cols, _, tr, bits) = &mosaic;
    let beyond = bits
        .iter()
        .enumerate()
        .filter(|(i, b)| {
            **b != u64::MAX
                && f64::from_bits(**b) != -9999.0
                && tr[0] + (((*i as u32) % cols) as f64 + 0.5) * tr[1] > east
        })
        .count();
    assert!(beyond > 100, "{beyond} cells east of the files");
    let set = mesh::contour_set(&std::fs::read(t.path().join("one.geojson")).unwrap());
    assert!(set.len() > 50, "{} contour lines", set.len());
    assert_eq!(
        mesh::contour_set(&std::fs::read(t.path().join("merged.geojson")).unwrap()),
        set,
        "stitched contours differ"
    );
}

/// A TIN plan with 3-D breaklines, a boundary and a hole: the merge trims the tasks' pieces,
/// and the mesh has one sweep's triangles.
#[test]
fn tin_plan_with_a_boundary_and_a_hole_has_the_triangles_of_one_sweep() {
    let t = tempfile::tempdir().unwrap();
    let (bl, boundary, hole) = lines(t.path());
    let d = |n: &str| s(&t.path().join(n));
    let mut job: Vec<String> = vec!["tin".into()];
    job.extend(ground());
    job.extend(breaklines(&bl[1..]));
    let hole_path = hole.clone();
    job.extend(["--trim-boundary".into(), boundary, "--holes".into(), hole]);
    let mut plan = vec!["plan".to_string()];
    plan.extend(job.iter().cloned());
    plan.extend(["--tile".into(), "50".into(), "-o".into(), d("job")]);
    cli::ok(&plan);
    let p = d("job/plan.json");
    cli::ok(&["run", &p, "--all", "--jobs", "2", "-q"]);
    let out = cli::ok(&["merge", &p, "-o", &d("merged.ply"), "--json"]);
    let m: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(m["tin"]["trimmed"].as_u64().unwrap() > 1000, "{m}");
    let mut one = job.clone();
    one.extend(["--engine", "sweep", "-q", "-o"].map(String::from));
    one.push(d("one.ply"));
    cli::ok(&one);
    let keys = |p: &str| {
        let (v, tris) = sweeptin::input::read_ply(Path::new(p)).unwrap();
        mesh::key_set(&v, tris.iter().map(|t| t.map(|i| i as usize)))
    };
    let want = keys(&d("one.ply"));
    assert!(want.len() > 10_000, "{} triangles", want.len());
    assert!(keys(&d("merged.ply")) == want, "the triangles of one sweep");
    // The merge never writes over a line file the plan reads (exit 2, the file untouched).
    let before = std::fs::read(&hole_path).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["merge", &p, "-o", &hole_path])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("an input of the plan"), "{err}");
    assert_eq!(std::fs::read(&hole_path).unwrap(), before);
}

/// A TIN plan with breaklines alone (no trimming ring): the merged mesh says it is constrained
/// (PLY comment), so `check` tests it as one (it was written as a plain Delaunay TIN, and `check`
/// failed on the breaklines' edges).
#[test]
fn a_merged_tin_with_breaklines_is_declared_constrained() {
    let t = tempfile::tempdir().unwrap();
    let (bl, _, _) = lines(t.path());
    let d = |n: &str| s(&t.path().join(n));
    let mut plan = vec!["plan".to_string(), "tin".into()];
    plan.extend(ground());
    plan.extend(breaklines(&bl[1..]));
    plan.extend(["--tile".into(), "50".into(), "-o".into(), d("job")]);
    cli::ok(&plan);
    let p = d("job/plan.json");
    cli::ok(&["run", &p, "--all", "--jobs", "2", "-q"]);
    cli::ok(&["merge", &p, "-o", &d("merged.ply"), "-q"]);
    let ply = std::fs::read(t.path().join("merged.ply")).unwrap();
    let header = String::from_utf8_lossy(&ply[..ply.len().min(4096)]).to_string();
    assert!(header.contains("constrained"), "{header}");
    cli::ok(&["check", &d("merged.ply")]);
}

/// Lines without z are refused by `plan` (file, line, vertex; exit 2), as are
/// `--clip-breaklines` and `--no-flat-triangles`, with no plan written; `sweeptin sample` gives
/// a text file of lines their z (the refusal's recipe), and that plan is made; a task refuses
/// a line file changed after planning (exit 3).
#[test]
fn plans_refuse_lines_without_z_and_tasks_refuse_changed_lines() {
    let t = tempfile::tempdir().unwrap();
    let d = |n: &str| t.path().join(n);
    let files = ground();
    let plan = |extra: &[String], dir: &Path| {
        let mut a: Vec<String> = vec!["plan".into(), "dem".into()];
        a.extend(files.iter().cloned());
        a.extend(["--cell", "0.5", "--tile", "50", "-o"].map(String::from));
        a.push(s(dir));
        a.extend(extra.iter().cloned());
        a
    };
    let refused = |extra: &[String], says: &[&str]| {
        let o = fails(&plan(extra, &d("refused")));
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        for w in says {
            assert!(err.contains(w), "{extra:?}: {w:?} not in {err}");
        }
        assert!(!d("refused").join("plan.json").exists());
    };
    // Text: the second polyline starts on line 4; its second vertex has no z.
    let xy = d("xy.txt");
    std::fs::write(
        &xy,
        "770505.25 6277503.5 21\n770545.75 6277596.25 21.5\n\n770510 6277510 21\n770590 6277590\n",
    )
    .unwrap();
    refused(
        &["--breaklines".into(), s(&xy)],
        &[
            "xy.txt:4, vertex 1 (770590, 6277590) has no z",
            "sweeptin sample",
        ],
    );
    let gj = d("two_d.geojson");
    std::fs::write(
        &gj,
        r#"{"type":"FeatureCollection","features":[
        {"type":"Feature","properties":{},"geometry":{"type":"LineString",
         "coordinates":[[770505.25,6277503.5,21],[770545.75,6277596.25,21]]}},
        {"type":"Feature","properties":{},"geometry":{"type":"LineString",
         "coordinates":[[770520,6277510],[770590,6277590]]}}]}"#,
    )
    .unwrap();
    refused(
        &["--breaklines".into(), s(&gj)],
        &["two_d.geojson feature 1 part 0, vertex 0", "has no z"],
    );
    // A layer of a GeoPackage (`FILE:LAYER`).
    let gpkg = data::shared("lines/momepy_bubenec.gpkg");
    refused(
        &["--breaklines".into(), format!("{}:streets", gpkg.display())],
        &[
            "momepy_bubenec.gpkg:streets feature 0 part 0, vertex 0",
            "more vertices",
        ],
    );
    // A ring is inserted as a breakline: its vertices need z too.
    let ring = d("ring.txt");
    std::fs::write(
        &ring,
        "770520 6277520\n770580 6277520\n770580 6277580\n770520 6277520\n",
    )
    .unwrap();
    refused(
        &["--trim-boundary".into(), s(&ring)],
        &["ring.txt:1, vertex 0"],
    );
    let (bl, _, _) = lines(t.path());
    refused(
        &[
            "--breaklines".into(),
            bl[0].clone(),
            "--clip-breaklines".into(),
        ],
        &["--clip-breaklines", "convex hull of all the points"],
    );
    refused(
        &[
            "--breaklines".into(),
            bl[0].clone(),
            "--no-flat-triangles".into(),
        ],
        &["--no-flat-triangles", "one `sweeptin dem`"],
    );

    // The recipe: `sample` appends the TIN's height to each `x y` line, blank lines kept.
    let xy_only = d("xy_only.txt");
    std::fs::write(
        &xy_only,
        "770505.25 6277503.5\n770545.75 6277596.25\n\n770510 6277510\n770590 6277590\n",
    )
    .unwrap();
    let xyz = d("xyz.txt");
    let mut sample: Vec<String> = vec!["sample".into()];
    sample.extend(files.iter().cloned());
    sample.extend([
        "--points".into(),
        s(&xy_only),
        "-o".into(),
        s(&xyz),
        "-q".into(),
    ]);
    cli::ok(&sample);
    let job = d("job");
    cli::ok(&plan(&["--breaklines".into(), s(&xyz)], &job));

    // A task refuses the file changed since (a height 10 m up): every task must insert the
    // same lines.
    let text = std::fs::read_to_string(&xyz).unwrap();
    std::fs::write(&xyz, text.replacen(" 2", " 3", 1)).unwrap();
    let o = fails(&[
        "run".to_string(),
        s(&job.join("plan.json")),
        "--task".into(),
        "1".into(),
        "-q".into(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("xyz.txt") && err.contains("changed since the plan was made"),
        "{err}"
    );
    assert!(!job.join("tiles/task_1.json").exists());
}

/// Breaklines whose heights disagree (two lines crossing, a vertex given twice) are warned of
/// by `plan`, which cleans the lines as its tasks will, in the words of one run's warning.
#[test]
fn plans_warn_of_z_conflicts_as_one_run_does() {
    let t = tempfile::tempdir().unwrap();
    let d = |n: &str| s(&t.path().join(n));
    let x = t.path().join("x.geojson");
    geojson::write_lines(
        &x,
        &[
            line(
                [770_505.25, 6_277_505.5, 21.0],
                [770_545.75, 6_277_546.5, 21.0],
                1,
            ),
            line(
                [770_505.25, 6_277_546.5, 21.5],
                [770_545.75, 6_277_505.5, 21.5],
                1,
            ),
            line(
                [770_505.25, 6_277_505.5, 21.3],
                [770_520.0, 6_277_510.5, 21.3],
                1,
            ),
        ],
    );
    let file = ground()[0].clone();
    let warning = |stderr: &[u8]| -> Vec<String> {
        let text = String::from_utf8_lossy(stderr);
        let mut lines = text
            .lines()
            .skip_while(|l| !l.contains("--z-tolerance apart"));
        let first = lines.next().map(str::to_string);
        first
            .into_iter()
            .chain(
                lines
                    .take_while(|l| l.starts_with("  "))
                    .map(str::to_string),
            )
            .collect()
    };
    let plan = cli::ok(&[
        "plan",
        "dem",
        &file,
        "--breaklines",
        &s(&x),
        "--cell",
        "1",
        "--tile",
        "50",
        "-o",
        &d("job"),
    ]);
    let planned = warning(&plan.stderr);
    assert_eq!(planned.len(), 3, "{planned:?}");
    assert!(planned[0].contains("at 2 places"), "{planned:?}");
    assert!(
        planned[1..]
            .iter()
            .any(|l| l.ends_with("two lines crossing: 21 and 21.5, the mean kept")),
        "{planned:?}"
    );
    assert!(
        planned[1..]
            .iter()
            .any(|l| l == "  (770505.25, 6277505.5), a vertex given twice: 21 kept, 21.3 dropped"),
        "{planned:?}"
    );
    let one = cli::ok(&[
        "dem",
        &file,
        "--breaklines",
        &s(&x),
        "--cell",
        "1",
        "-q",
        "-o",
        &d("one.tif"),
    ]);
    assert_eq!(warning(&one.stderr), planned, "one run's warning");
}
