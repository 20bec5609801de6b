//! `sweeptin plan` / `run` / `merge`: a job cut into tasks, run locally, through GNU parallel and
//! as a job array would (the task index from the environment), gives the same DEM (every cell,
//! bit for bit), the same contour polylines and the same volumes as one run over all the points;
//! empty tasks are not failures; what a plan cannot do exactly is refused.

use crate::data;
use crate::mesh;
use crate::plans;

use plans::{bin, cells, ok, plan_extent, records, s, sweeptin};
use std::path::{Path, PathBuf};
use std::process::Command;

#[test]
fn dem_and_contours_of_a_plan_equal_one_run() {
    // Ground of the six IGN 50 m tiles: gaps under buildings, and the data's outer edge, where
    // tasks must read farther than their first buffer.
    let files = data::ign_tiles();
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let mut args: Vec<&str> = vec!["plan", "--buffer", "2", "dem"];
    args.extend(files.iter().map(|p| s(p)));
    let contours_planned = t.path().join("planned.geojson");
    args.extend([
        "--class",
        "2",
        "--cell",
        "0.5",
        "--contours",
        s(&contours_planned),
        "--interval",
        "0.25",
        "--tile",
        "50",
        "-o",
        s(&job),
    ]);
    sweeptin(&args, "plan");
    let plan = job.join("plan.json");
    let (_, n) = plan_extent(&plan);
    assert!(n >= 6, "{n} tasks");

    // One run over all the points, on its own extent (the mosaic's: `merge --extent data`).
    let single = t.path().join("single.tif");
    let single_c = t.path().join("single.geojson");
    let mut one: Vec<&str> = vec!["dem"];
    one.extend(files.iter().map(|p| s(p)));
    one.extend([
        "--class",
        "2",
        "--cell",
        "0.5",
        "--contours",
        s(&single_c),
        "--interval",
        "0.25",
        "-o",
        s(&single),
        "-q",
    ]);
    sweeptin(&one, "single run");

    // Locally, two tasks at a time.
    sweeptin(
        &["run", s(&plan), "--all", "--jobs", "2", "-q"],
        "run --all",
    );
    let recs = records(&job, n);
    assert!(
        recs.iter().any(|r| r["runs"].as_u64().unwrap() > 1),
        "no task had to widen its buffer: {recs:?}"
    );
    let mosaic = t.path().join("mosaic.tif");
    let merged_c = t.path().join("merged.geojson");
    sweeptin(
        &[
            "merge",
            s(&plan),
            "-o",
            s(&mosaic),
            "--contours",
            s(&merged_c),
        ],
        "merge",
    );
    assert_eq!(
        cells(&mosaic),
        cells(&single),
        "the mosaic differs from one run"
    );
    // And it has every cell with data that one run on its own extent has (a centre on the data's
    // lower edge belongs to the tile below, which the plan must hold).
    let auto = t.path().join("auto.tif");
    let mut own: Vec<&str> = vec!["dem"];
    own.extend(files.iter().map(|p| s(p)));
    own.extend([
        "--class",
        "2",
        "--cell",
        "0.5",
        "--json",
        "-q",
        "-o",
        s(&auto),
    ]);
    let out = sweeptin(&own, "single run on its own extent");
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let with_data = |p: &Path| cells(p).3.iter().filter(|&&b| b != u64::MAX).count() as u64;
    assert_eq!(
        with_data(&mosaic),
        summary["dem"]["cells_with_data"].as_u64().unwrap(),
        "the mosaic lost cells that one run fills"
    );
    let one_set = mesh::contour_set(&std::fs::read(&single_c).unwrap());
    assert!(one_set.len() > 100);
    assert_eq!(
        mesh::contour_set(&std::fs::read(&merged_c).unwrap()),
        one_set,
        "stitched contours differ"
    );

    // --mem (issue 43): below what a merge's fixed buffers need, refused before any output (exit
    // 2); at that least budget, the same COG and contours as at the default.
    let m1 = t.path().join("m1.tif");
    let o = bin()
        .args(["merge", s(&plan), "-o", s(&m1), "--mem", "1M"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--mem 1.0 MiB: a merge needs at least 16.0 MiB"),
        "{e}"
    );
    assert!(!m1.exists());
    let cog = |name: &str, mem: &[&str]| {
        let (out, c) = (t.path().join(format!("{name}.tif")), t.path().join(name));
        let mut a = vec!["merge", s(&plan), "-o", s(&out), "--format", "cog"];
        a.extend(["--contours", s(&c), "-q"]);
        a.extend(mem);
        sweeptin(&a, "merge to a COG");
        (std::fs::read(&out).unwrap(), std::fs::read(&c).unwrap())
    };
    assert!(cog("default", &[]) == cog("least", &["--mem", "16M"]));

    // A VRT over the tiles: GDAL reads the same cells.
    let vrt = t.path().join("mosaic.vrt");
    sweeptin(&["merge", s(&plan), "-o", s(&vrt)], "merge to VRT");
    if data::tool("gdal_translate", "dem_and_contours_of_a_plan_equal_one_run") {
        let from_vrt = t.path().join("from_vrt.tif");
        let out = Command::new("gdal_translate")
            .args(["-q", s(&vrt), s(&from_vrt)])
            .output()
            .unwrap();
        ok(out, "gdal_translate of the VRT");
        assert_eq!(
            cells(&from_vrt),
            cells(&single),
            "GDAL reads other cells in the VRT"
        );
    }

    // Re-running is safe; --resume skips finished tasks, but not one whose output is gone.
    let recs = records(&job, n);
    let rec0 = recs.iter().find(|r| r["status"] == "done").unwrap();
    let k = rec0["index"].to_string();
    let out = sweeptin(&["run", s(&plan), "--task", &k, "--resume"], "resume");
    assert!(String::from_utf8_lossy(&out.stderr).contains("skipped"));
    let tif0 = job.join(rec0["outputs"][0][1].as_str().unwrap());
    std::fs::remove_file(&tif0).unwrap();
    let out = sweeptin(
        &["run", s(&plan), "--task", &k, "--resume"],
        "resume a lost output",
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("skipped"));
    assert!(tif0.is_file(), "the lost output was not made again");

    // GNU parallel, as in docs/SCALING.md, into a fresh copy of the plan.
    if data::tool("parallel", "dem_and_contours_of_a_plan_equal_one_run") {
        std::fs::remove_dir_all(job.join("tiles")).unwrap();
        std::fs::create_dir(job.join("tiles")).unwrap();
        let list: Vec<String> = (0..n).map(|i| i.to_string()).collect();
        let out = Command::new("parallel")
            .args(["--halt", "now,fail=1", "-j", "2"])
            .arg(env!("CARGO_BIN_EXE_sweeptin"))
            .args([
                "run",
                s(&plan),
                "--task",
                "{}",
                "--quiet",
                "--threads",
                "1",
                ":::",
            ])
            .args(&list)
            .output()
            .unwrap();
        ok(out, "GNU parallel");
        let again = t.path().join("parallel.tif");
        sweeptin(
            &["merge", s(&plan), "-o", s(&again)],
            "merge after parallel",
        );
        assert_eq!(cells(&again), cells(&single));
    }

    // A job array gives the index in the environment (Slurm, Kubernetes, AWS Batch).
    std::fs::remove_file(job.join("tiles/task_1.json")).unwrap();
    for var in [
        "SLURM_ARRAY_TASK_ID",
        "JOB_COMPLETION_INDEX",
        "AWS_BATCH_JOB_ARRAY_INDEX",
    ] {
        let out = bin()
            .args(["run", s(&plan), "--json", "-q"])
            .env(var, "1")
            .output()
            .unwrap();
        let out = ok(out, var);
        let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(r["index"], 1, "{var}");
    }
    let again = t.path().join("array.tif");
    sweeptin(
        &["merge", s(&plan), "-o", s(&again)],
        "merge after the array",
    );
    assert_eq!(cells(&again), cells(&single));
}

#[test]
fn volume_of_a_plan_equals_one_run() {
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let out = sweeptin(
        &["volume", s(&sample), "--plane", "5", "--json", "-q"],
        "volume",
    );
    let one: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    sweeptin(
        &[
            "plan",
            "volume",
            s(&sample),
            "--plane",
            "5",
            "--tile",
            "8",
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    // `run --all --json` says what it ran (it printed nothing).
    let out = sweeptin(&["run", s(&plan), "--all", "--jobs", "2", "--json"], "run");
    let ran: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(ran["tasks"].as_u64().unwrap() > 1, "{ran}");
    assert_eq!(ran["skipped"], 0, "{ran}");
    let out = sweeptin(&["merge", s(&plan), "--json"], "merge");
    let merged: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in ["cut_volume", "fill_volume", "cut_area", "fill_area", "area"] {
        assert_eq!(merged["volume"][k], one[k], "{k}: summed exactly");
    }
    // The boundary is pinned by size and SHA-256: edited between tasks, it mixed two polygons.
    let poly = t.path().join("poly.geojson");
    let ring = |x: f64| {
        format!(r#"{{"type":"Polygon","coordinates":[[[0,0],[{x},0],[{x},1e8],[0,1e8],[0,0]]]}}"#)
    };
    std::fs::write(&poly, ring(1e8)).unwrap();
    let job = t.path().join("job2");
    let args = ["plan", "volume", s(&sample), "--plane", "5", "--tile", "8"];
    sweeptin(
        &[&args[..], &["--boundary", s(&poly), "-o", s(&job)]].concat(),
        "plan",
    );
    std::fs::write(&poly, ring(2e8)).unwrap();
    let o = bin()
        .args(["run", s(&job.join("plan.json")), "--task", "0", "-q"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(
        e.contains("poly.geojson: the file changed since the plan"),
        "{e}"
    );
}

/// A TIN plan's merged mesh has the triangles of one run (each vertex once), with and without
/// `--max-edge`, in every mesh format the merge picks by extension.
#[test]
fn a_tin_plan_merges_into_the_mesh_of_one_run() {
    let dir_data = data::shared("lidar/ign_50m_tiles");
    let mut files: Vec<String> = std::fs::read_dir(&dir_data)
        .unwrap()
        .map(|e| e.unwrap().path().display().to_string())
        .filter(|p| p.ends_with(".laz"))
        .collect();
    files.sort();
    let t = tempfile::tempdir().unwrap();
    let keys = |p: &Path, whole: bool| {
        let (v, tris) = sweeptin::input::read_ply(p).unwrap();
        if whole {
            // (A mesh trimmed by --max-edge may be pinched.)
            sweeptin::validate::validate(&v, &tris).unwrap();
        }
        mesh::key_set(&v, tris.iter().map(|t| t.map(|i| i as usize)))
    };
    for (n, extra) in [(0, &[][..]), (1, &["--max-edge", "2"][..])] {
        let job = t.path().join(format!("job{n}"));
        let one = t.path().join(format!("one{n}.ply"));
        let mut args: Vec<&str> = vec!["tin"];
        args.extend(files[..4].iter().map(String::as_str));
        args.extend(["--class", "2"]);
        args.extend(extra);
        let mut single = args.clone();
        single.extend(["-o", s(&one), "-q"]);
        sweeptin(&single, "one tin run");
        let mut plan = vec!["plan"];
        plan.extend(&args);
        plan.extend(["--tile", "50", "-o", s(&job)]);
        sweeptin(&plan, "plan tin");
        let p = job.join("plan.json");
        sweeptin(&["run", s(&p), "--all", "--jobs", "2", "-q"], "run");
        let merged = t.path().join(format!("m{n}.ply"));
        let out = sweeptin(&["merge", s(&p), "-o", s(&merged), "--json"], "merge");
        let m: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(
            keys(&merged, n == 0),
            keys(&one, n == 0),
            "{extra:?}: the triangles of one run"
        );
        assert_eq!(m["tasks"].as_u64().unwrap() as usize, {
            let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
            v["tiles"].as_array().unwrap().len()
        });
        if n == 1 {
            assert!(m["tin"]["trimmed"].as_u64().unwrap() > 0, "{m}");
        }
    }
    // The plan's mesh as a streaming mesh feeds the products like one run's.
    let p = t.path().join("job0/plan.json");
    let stin = t.path().join("m.stin");
    sweeptin(&["merge", s(&p), "-o", s(&stin)], "merge to .stin");
    let (a, b) = (t.path().join("a.tif"), t.path().join("b.tif"));
    sweeptin(
        &["dem", s(&stin), "--cell", "1", "-o", s(&a), "-q"],
        "dem of the .stin",
    );
    let mut direct = vec!["dem"];
    direct.extend(files[..4].iter().map(String::as_str));
    direct.extend(["--class", "2", "--cell", "1", "-o", s(&b), "-q"]);
    sweeptin(&direct, "dem");
    assert_eq!(cells(&a), cells(&b));
    // What the merge refuses.
    let bad = bin()
        .args(["merge", s(&p), "-o", s(&t.path().join("m.tif"))])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("mesh format"));
}

#[test]
fn empty_tasks_pass_and_what_a_plan_cannot_do_is_refused() {
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    // No point of class 18: every task is empty, which is not a failure.
    sweeptin(
        &[
            "plan",
            "dem",
            s(&sample),
            "--class",
            "18",
            "--cell",
            "0.5",
            "--tile",
            "16",
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    let out = bin()
        .args(["merge", s(&plan), "-o"])
        .arg(t.path().join("early.tif"))
        .output();
    let out = out.unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("have not finished"));
    let out = sweeptin(&["run", s(&plan), "--task", "0", "--json"], "an empty task");
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning"));
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["status"], "empty");
    let out = bin()
        .args(["run", s(&plan), "--task", "999"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("does not exist"));
    let out = bin()
        .args(["run", s(&plan)])
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output();
    assert!(String::from_utf8_lossy(&out.unwrap().stderr).contains("which task"));

    let refuse = |extra: &[&str], says: &str| {
        let mut a = vec!["plan", "dem", s(&sample), "--tile", "16", "-o"];
        let d = t.path().join("refused");
        a.push(s(&d));
        a.extend_from_slice(extra);
        let out = bin().args(&a).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(err.contains(says), "{extra:?}: {err}");
        assert!(!d.join("plan.json").exists());
    };
    refuse(
        &["--no-flat-triangles"],
        "flips triangles across tile edges",
    );
    refuse(&["--bbox", "0,0,1,1"], "leave --bbox out");
    refuse(&["--cell", "3"], "whole multiple of the cell");
    refuse(&["--engine", "sweep"], "tiled engine");
    refuse(&["--cell", "0.0005"], "16384 cells a side");
    let hs = sample.to_str().unwrap().to_string();
    refuse(&["--contours", &hs], "an input of the plan");
    // The mosaic's format lives in the plan's job: an ASCII mosaic, or a predictor without
    // compression, is refused before the plan is written.
    refuse(&["--format", "asc"], "a DEM mosaic is a GeoTIFF");
    refuse(&["--predictor", "float"], "needs compression");
    // A budget in which no task's raster fits fails here, not in every task.
    refuse(&["--cell", "0.5", "--mem", "1K"], "the plan's --mem");
    // A missing input is bad input (3), as in one run.
    let out = bin()
        .args([
            "plan",
            "dem",
            "no-such.laz",
            "--cell",
            "1",
            "--tile",
            "16",
            "-o",
        ])
        .arg(t.path().join("missing"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no-such.laz"));
    // Every task empty: the merge says so with the status of one run that keeps nothing (3).
    sweeptin(&["run", s(&plan), "--all", "-q"], "empty tasks");
    let out = bin()
        .args(["merge", s(&plan), "-o"])
        .arg(t.path().join("nothing.tif"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no task found a point"));
    // Merging onto an input, the plan or a task's output is refused.
    let done = t.path().join("done");
    sweeptin(
        &[
            "plan",
            "dem",
            s(&sample),
            "--cell",
            "0.5",
            "--tile",
            "32",
            "-o",
            s(&done),
        ],
        "plan",
    );
    let plan2 = done.join("plan.json");
    sweeptin(&["run", s(&plan2), "--all", "-q"], "run");
    for (o, says) in [
        (s(&sample).to_string(), "an input of the plan"),
        (s(&plan2).to_string(), "an input of the plan"),
        (
            t.path().join("m.asc").to_str().unwrap().to_string(),
            "a .vrt or a .tif",
        ),
    ] {
        let out = bin().args(["merge", s(&plan2), "-o", &o]).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{o}");
        assert!(String::from_utf8_lossy(&out.stderr).contains(says), "{o}");
    }
    // A VRT points at the tiles as they are: no format or compression of its own; no ASCII
    // mosaic either.
    let vrt = t.path().join("m.vrt");
    let tif = t.path().join("m.tif");
    for (o, extra, says) in [
        (&vrt, ["--compress", "deflate"], "a .vrt mosaic"),
        (&tif, ["--format", "asc"], "a DEM mosaic is a GeoTIFF"),
    ] {
        let out = bin()
            .args(["merge", s(&plan2), "-o", s(o)])
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(says),
            "{extra:?}"
        );
        assert!(!o.exists());
    }
    let out = bin()
        .args(["merge", s(&plan2), "-o"])
        .arg(t.path().join("m.tif"))
        .args(["--hillshade", s(&sample)])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        std::fs::read(&sample).unwrap().starts_with(b"LASF"),
        "the input was replaced"
    );
    // Planning again into the same directory with other options is refused.
    let out = bin()
        .args([
            "plan",
            "dem",
            s(&sample),
            "--cell",
            "1",
            "--tile",
            "32",
            "-o",
            s(&done),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("already holds another plan"));
    // A TIN plan refuses trimming polygons and a mesh format (the merge picks it).
    let out = bin()
        .args([
            "plan",
            "tin",
            s(&sample),
            "--format",
            "ply",
            "--tile",
            "16",
            "-o",
        ])
        .arg(t.path().join("tin"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("sweeptin merge -o OUT.ply"));
}

#[test]
fn one_run_never_writes_over_its_input_or_one_output_over_another() {
    let t = tempfile::tempdir().unwrap();
    let input = t.path().join("in.laz");
    std::fs::copy(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz"),
        &input,
    )
    .unwrap();
    let out = t.path().join("o.tif");
    for (flag, target, says) in [
        ("--contours", &input, "an input of the run"),
        ("--hillshade", &out, "name the same file"),
    ] {
        let r = bin()
            .args([
                "dem",
                s(&input),
                "--cell",
                "1",
                "-q",
                "-o",
                s(&out),
                flag,
                s(target),
            ])
            .output()
            .unwrap();
        assert_eq!(r.status.code(), Some(2), "{flag}");
        assert!(String::from_utf8_lossy(&r.stderr).contains(says), "{flag}");
        assert!(std::fs::read(&input).unwrap().starts_with(b"LASF"));
        assert!(!out.exists(), "{flag}: an output was written");
    }
}

/// A plan over a COPC file: each task decodes only the octree nodes of its tile and buffer
/// (the rest of the file counts as unknown, like a file it does not read, and a certificate that
/// reaches it widens the buffer to cover what it reached), and the mosaic still equals one run
/// cell for cell.
#[test]
fn tasks_of_a_copc_file_read_their_area_only() {
    let copc = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lidR_Topography.copc.laz");
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    sweeptin(
        &[
            "plan",
            "--buffer",
            "8",
            "dem",
            s(&copc),
            "--cell",
            "1",
            "--tile",
            "64",
            "-o",
            s(&job),
        ],
        "plan of a COPC file",
    );
    let plan = job.join("plan.json");
    let (_, n) = plan_extent(&plan);
    assert!(n >= 9, "{n} tasks");
    sweeptin(
        &["run", s(&plan), "--all", "--jobs", "2", "--quiet"],
        "run --all",
    );
    let mosaic = t.path().join("mosaic.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&mosaic)], "merge");
    let single = t.path().join("single.tif");
    sweeptin(
        &["dem", s(&copc), "--cell", "1", "-o", s(&single), "--quiet"],
        "one run",
    );
    assert_eq!(cells(&mosaic), cells(&single), "mosaic == one run");
    // Tasks along the data's edge widened their buffers (the file's parts they did not read
    // may hold points), and every task finished.
    let recs = records(&job, n);
    assert!(recs.iter().all(|r| r["status"] == "done"));
    assert!(recs.iter().any(|r| r["runs"].as_u64().unwrap() > 1));
}

/// A plan over `files` with `--buffer 0` and 50 m tiles: its DEM mosaic equals one run, header
/// and cell for cell, and its merged TIN has the triangles of one `tin` run.
fn plan_with_no_buffer_equals_one_run(dir: &Path, files: &[PathBuf]) {
    for product in ["dem", "tin"] {
        let job = dir.join(format!("job-{product}"));
        let mut args: Vec<&str> = vec!["plan", "--buffer", "0", product];
        args.extend(files.iter().map(|p| s(p)));
        if product == "dem" {
            args.extend(["--cell", "1"]);
        }
        args.extend(["--tile", "50", "-o", s(&job)]);
        sweeptin(&args, "plan");
        let plan = job.join("plan.json");
        sweeptin(&["run", s(&plan), "--all", "-q"], "run --all");
        let ext = if product == "dem" { "tif" } else { "ply" };
        let (merged, single) = (dir.join(format!("m.{ext}")), dir.join(format!("one.{ext}")));
        sweeptin(&["merge", s(&plan), "-o", s(&merged)], "merge");
        let mut one: Vec<&str> = vec![product];
        one.extend(files.iter().map(|p| s(p)));
        if product == "dem" {
            one.extend(["--cell", "1"]);
        }
        one.extend(["-q", "-o", s(&single)]);
        sweeptin(&one, "single run");
        if product == "dem" {
            assert_eq!(cells(&merged), cells(&single), "the mosaic differs");
        } else {
            let keys = |p: &Path| {
                let (v, tris) = sweeptin::input::read_ply(p).unwrap();
                mesh::key_set(&v, tris.iter().map(|t| t.map(|i| i as usize)))
            };
            assert_eq!(keys(&merged), keys(&single), "the triangles differ");
        }
    }
}

/// What a task did not read is unknown even inside the blocks it loaded, and beyond the straight
/// edge of its data: (1) a file starting half a metre past a tile, inside the block the first
/// run rounds out to; (2) a file across a 40 m gap from a jittered straight edge on a tile's
/// edge, whose flat slivers have disks reaching into it.
#[test]
fn a_plan_without_buffer_never_certifies_against_files_it_did_not_read() {
    let mut r = sweeptin::synth::SplitMix64::uniform(5);
    let t = tempfile::tempdir().unwrap();
    let z = |x: f64, y: f64| 100.0 + 0.05 * x + 0.02 * y + (x * 0.3).sin();
    let random = |r: &mut dyn FnMut() -> f64, n: usize, x0: f64, x1: f64| -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| {
                let (x, y) = (x0 + r() * (x1 - x0), r() * 200.0);
                [x, y, z(x, y)]
            })
            .collect()
    };
    let (a, c) = (t.path().join("a.las"), t.path().join("c.las"));
    mesh::write_las(&a, &random(&mut r, 40_000, 0.0, 200.0));
    mesh::write_las(&c, &random(&mut r, 19_900, 100.5, 200.0));
    let d1 = t.path().join("overlap");
    std::fs::create_dir(&d1).unwrap();
    plan_with_no_buffer_equals_one_run(&d1, &[a, c]);

    let grid = |x0: i32, x1: i32, r: &mut dyn FnMut() -> f64| -> Vec<[f64; 3]> {
        let mut v = Vec::new();
        for i in x0..x1 {
            for j in 0..200 {
                let x = f64::from(i) + 0.01 * (r() - 0.5);
                let y = f64::from(j) + 0.01 * (r() - 0.5);
                v.push([x, y, z(x, y)]);
            }
        }
        v
    };
    let (left, right) = (t.path().join("left.las"), t.path().join("right.las"));
    mesh::write_las(&left, &grid(0, 101, &mut r));
    mesh::write_las(&right, &grid(140, 240, &mut r));
    let d2 = t.path().join("gap");
    std::fs::create_dir(&d2).unwrap();
    plan_with_no_buffer_equals_one_run(&d2, &[left, right]);
}

/// A merged output carries the CRS one run gives: a contours plan's merge dropped it, and a DEM
/// mosaic took it from the first file alone (none when that one declares none).
#[test]
fn merged_outputs_carry_the_crs_of_one_run() {
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let ahn = data::shared("lidar/ahn3_delft_cropped_1.laz");
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("jc");
    let plan = job.join("plan.json");
    let args = [
        "plan",
        "contours",
        s(&sample),
        "--interval",
        "1",
        "--tile",
        "32",
    ];
    sweeptin(&[&args[..], &["-o", s(&job)]].concat(), "plan");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    let merged = t.path().join("m.geojson");
    sweeptin(&["merge", s(&plan), "-o", s(&merged), "-q"], "merge");
    let text = std::fs::read_to_string(&merged).unwrap();
    assert!(text[..200].contains("\"crs\""), "{}", &text[..200]);
    let crs = |p: &Path| {
        sweeptin::input::raster::RasterReader::open(p)
            .unwrap()
            .spec()
            .crs
            .clone()
    };
    let one = t.path().join("one.tif");
    sweeptin(
        &[
            "dem",
            s(&ahn),
            s(&sample),
            "--cell",
            "1",
            "-o",
            s(&one),
            "-q",
        ],
        "dem",
    );
    assert!(crs(&one).is_some());
    let job = t.path().join("jd");
    let plan = job.join("plan.json");
    let args = [
        "plan",
        "dem",
        s(&ahn),
        s(&sample),
        "--cell",
        "1",
        "--tile",
        "500",
    ];
    sweeptin(&[&args[..], &["-o", s(&job)]].concat(), "plan");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    let mosaic = t.path().join("m.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&mosaic), "-q"], "merge");
    assert_eq!(crs(&mosaic), crs(&one));
}
