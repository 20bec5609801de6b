//! A plan's job directory as nightly operations treat it (issue 43): moved or copied, it merges
//! its own tiles from its new place; its `tiles/` deleted, `run` makes it again; a task record
//! that names an output outside its directory is refused; records count only for their plan,
//! an edited plan is refused; failed tasks set the exit status and `run --all` says how far it
//! came; `plan` says what each product writes.

use crate::data;
use crate::plans;

use plans::{bin, cells, ok, plan_and_run, plan_extent, records, s, sweeptin};
use std::path::{Path, PathBuf};
use std::process::Command;

fn sample() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz")
}

/// Plans and runs a DEM job over the sample into `job`; returns the plan file.
fn planned_and_run(job: &Path) -> PathBuf {
    let input = sample();
    sweeptin(
        &[
            "plan",
            "dem",
            s(&input),
            "--cell",
            "0.5",
            "--tile",
            "32",
            "-o",
            s(job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    plan
}

fn merged(plan: &Path, out: &Path) -> (u32, u32, [f64; 6], Vec<u64>) {
    sweeptin(&["merge", s(plan), "-o", s(out)], "merge");
    cells(out)
}

fn failing(args: &[&str], code: i32, says: &str) {
    let o = bin().args(args).output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {e}");
    assert!(e.contains(says), "{args:?}: {e}");
}

/// Records named their tiles by absolute path: `mv job job2; merge job2/plan.json` failed naming
/// `job/tiles/…`, and after `cp -a job job2` a merge of `job2` read `job`'s tiles.
#[test]
fn a_job_moved_or_copied_merges_its_own_tiles() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    planned_and_run(&job);
    let record = std::fs::read_to_string(job.join("tiles/task_0.json")).unwrap();
    assert!(
        !record.contains(s(t.path())),
        "a record names a path of the place it was made in: {record}"
    );
    let moved = t.path().join("moved");
    std::fs::rename(&job, &moved).unwrap();
    let one = merged(&moved.join("plan.json"), &t.path().join("a.tif"));
    // --resume in the new place finds every task finished: no record is rewritten.
    let stamp = |d: &Path| {
        std::fs::metadata(d.join("tiles/task_0.json"))
            .unwrap()
            .modified()
            .unwrap()
    };
    let before = stamp(&moved);
    sweeptin(
        &[
            "run",
            s(&moved.join("plan.json")),
            "--all",
            "--resume",
            "-q",
        ],
        "resume",
    );
    assert_eq!(
        stamp(&moved),
        before,
        "a finished task ran again after a move"
    );
    // A copy merges its own tiles: the original's deleted, the copy still merges, and equal.
    let copy = t.path().join("copy");
    let status = std::process::Command::new("cp")
        .args(["-a", s(&moved), s(&copy)])
        .status()
        .unwrap();
    assert!(status.success());
    std::fs::remove_dir_all(moved.join("tiles")).unwrap();
    let two = merged(&copy.join("plan.json"), &t.path().join("b.tif"));
    assert_eq!(one, two, "the copy's mosaic differs");
    // The moved job lost its tiles: merge says which task to run again...
    failing(
        &[
            "merge",
            s(&moved.join("plan.json")),
            "-o",
            s(&t.path().join("c.tif")),
        ],
        2,
        "have not finished",
    );
    // ... and `run --all` makes `tiles/` again (every task failed, exit 4, before).
    sweeptin(&["run", s(&moved.join("plan.json")), "--all", "-q"], "run");
    assert_eq!(
        merged(&moved.join("plan.json"), &t.path().join("d.tif")),
        one
    );
}

/// A record is the task's own word on its outputs, which lie in `tiles/`: one naming a file
/// elsewhere (hand-edited, or written by an older sweeptin with absolute paths) is refused.
#[test]
fn a_record_naming_an_output_outside_its_job_is_refused() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let plan = planned_and_run(&job);
    let rec = job.join("tiles/task_0.json");
    let text = std::fs::read_to_string(&rec).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let tile = v["outputs"][0][1].as_str().unwrap().to_string();
    assert!(tile.starts_with("tiles/"), "{tile}");
    for outside in [
        format!("../{tile}"),
        s(&job.join(&tile)).to_string(),
        "tiles/../../x.tif".to_string(),
    ] {
        v["outputs"][0][1] = serde_json::json!(outside);
        std::fs::write(&rec, v.to_string()).unwrap();
        failing(
            &["merge", s(&plan), "-o", s(&t.path().join("m.tif"))],
            3,
            "outside its plan's directory",
        );
    }
    std::fs::write(&rec, text).unwrap();
    merged(&plan, &t.path().join("m.tif"));
}

/// The job directory's bookkeeping (a hostile tester's findings, each a mosaic wrong with exit
/// 0 before): a task that runs again forgets its old record first, so a failed re-run is not
/// taken as finished; records carry the plan's fingerprint, so records of a plan edited or made
/// before in the same directory never count; a plan whose tiles do not follow from its tile
/// side and cell is refused; a link among the plan's own files is refused, never written
/// through (it replaced an input).
#[test]
fn records_count_only_for_their_plan_and_links_are_refused() {
    let t = tempfile::tempdir().unwrap();
    let input = t.path().join("in.laz");
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    std::fs::copy(&sample, &input).unwrap();
    let job = t.path().join("job");
    let plan = job.join("plan.json");
    let plan_args = ["plan", "dem", s(&input), "--cell", "0.5", "--tile", "32"];
    let failing = |args: &[&str], code: i32, says: &str| {
        let o = bin().args(args).output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {e}");
        assert!(e.contains(says), "{args:?}: {e}");
    };
    // An output that merge would refuse after every task ran is refused now.
    let inside = job.join("tiles/c.geojson");
    let contours = ["--contours", s(&inside), "--interval", "1", "-o", s(&job)];
    failing(
        &[&plan_args[..], &contours].concat(),
        2,
        "keeps its own files",
    );
    sweeptin(&[&plan_args[..], &["-o", s(&job)]].concat(), "plan");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    // A nightly re-run that fails leaves no record of the night before.
    let away = t.path().join("away.laz");
    std::fs::rename(&input, &away).unwrap();
    failing(&["run", s(&plan), "--task", "0", "-q"], 3, "in.laz");
    assert!(!job.join("tiles/task_0.json").exists());
    let m = t.path().join("m.tif");
    failing(&["merge", s(&plan), "-o", s(&m)], 2, "have not finished");
    std::fs::rename(&away, &input).unwrap();
    sweeptin(&["run", s(&plan), "--all", "--resume", "-q"], "resume");
    // An edited plan is refused by `run` and `merge` (its fingerprint no longer matches):
    // a deleted tile or a file's count set to 0 gave a mosaic with holes, exit 0.
    let text = std::fs::read_to_string(&plan).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let edits: [&dyn Fn(&mut serde_json::Value); 4] = [
        &|v| v["args"].as_array_mut().unwrap().push("(edited)".into()),
        &|v| v["files"][0]["points"] = serde_json::json!(0),
        &|v| {
            v["tiles"].as_array_mut().unwrap().pop();
        },
        &|v| v["fingerprint"] = serde_json::json!(""),
    ];
    for edit in edits {
        let mut e = v.clone();
        edit(&mut e);
        std::fs::write(&plan, e.to_string()).unwrap();
        failing(&["merge", s(&plan), "-o", s(&m)], 3, "make the plan again");
        failing(&["run", s(&plan), "--all", "--resume", "-q"], 3, "edited");
    }
    std::fs::write(&plan, &text).unwrap();
    sweeptin(&["merge", s(&plan), "-o", s(&m)], "merge");
    // A plan whose cell or tiles were edited apart is refused.
    v["cell"] = serde_json::json!(1.0);
    std::fs::write(&plan, v.to_string()).unwrap();
    failing(&["run", s(&plan), "--task", "0"], 3, "the plan was edited");
    // Planned again into the directory of another plan's tasks.
    std::fs::remove_file(&plan).unwrap();
    let again = [
        &plan_args[..3],
        &["--cell", "1", "--tile", "32", "-o", s(&job)],
    ]
    .concat();
    failing(&again, 2, "but no plan");
    // An input rewritten in place with the same header (reclassified, heights corrected) is
    // told by its size and modification time.
    std::fs::write(&plan, &text).unwrap();
    let f = std::fs::File::options().write(true).open(&input).unwrap();
    let then = f.metadata().unwrap().modified().unwrap();
    f.set_modified(then - std::time::Duration::from_secs(60))
        .unwrap();
    failing(
        &["run", s(&plan), "--task", "0", "-q"],
        3,
        "changed since the plan was made",
    );
    f.set_modified(then).unwrap();
    // A link where the plan keeps its own files is refused, and its target left alone.
    let before = std::fs::read(&input).unwrap();
    let record = job.join("tiles/task_0.json");
    assert!(!record.exists(), "the refused task forgot its record");
    std::os::unix::fs::symlink(&input, &record).unwrap();
    failing(
        &["run", s(&plan), "--task", "0", "-q"],
        2,
        "a symbolic link",
    );
    let tile = std::fs::read_dir(job.join("tiles"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|e| e == "tif"))
        .unwrap();
    std::fs::remove_file(&record).unwrap();
    std::fs::remove_file(&tile).unwrap();
    std::os::unix::fs::symlink(&input, &tile).unwrap();
    let o = bin()
        .args(["run", s(&plan), "--all", "-q"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::remove_file(&plan).unwrap();
    std::os::unix::fs::symlink(&input, &plan).unwrap();
    failing(
        &[&plan_args[..], &["-o", s(&job)]].concat(),
        2,
        "a symbolic link",
    );
    assert!(
        std::fs::read(&input).unwrap() == before,
        "an input was replaced"
    );
}

/// Issue 41, item 15: `run --all` said "8/8 tasks finished" when 3 had failed: each line says
/// which task ended how and how many of those that ran failed.
#[test]
fn progress_of_run_all_counts_the_failed_tasks() {
    let t = tempfile::tempdir().unwrap();
    let input = t.path().join("in.laz");
    std::fs::copy(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz"),
        &input,
    )
    .unwrap();
    let job = t.path().join("job");
    sweeptin(
        &[
            "plan",
            "dem",
            s(&input),
            "--cell",
            "0.5",
            "--tile",
            "32",
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    let (_, n) = plan_extent(&plan);
    std::fs::remove_file(&input).unwrap();
    let out = bin().args(["run", s(&plan), "--all"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(!err.contains("tasks finished"), "{err}");
    assert!(
        err.contains(&format!("{n} of {n} tasks ran, {n} failed")),
        "{err}"
    );
    let lines = err
        .lines()
        .filter(|l| l.starts_with("sweeptin: task ") && l.contains(" failed: "));
    assert_eq!(lines.count(), n, "{err}");
}

/// `run --all` exits with the kind of its lowest failed task (here 3, bad input: a file of the
/// plan went missing), names the failed tasks and how to run them again; `--resume` then runs
/// them alone. `plan dem --max-cells` is checked against one task's raster.
#[test]
fn failed_tasks_set_the_exit_status_and_resume_runs_them_again() {
    let t = tempfile::tempdir().unwrap();
    let input = t.path().join("in.laz");
    std::fs::copy(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz"),
        &input,
    )
    .unwrap();
    let job = t.path().join("job");
    let plan_args = ["plan", "dem", s(&input), "--cell", "0.5", "--tile", "32"];
    let out = bin()
        .args(plan_args)
        .args(["--max-cells", "1000", "-o", s(&job)])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--max-cells"));
    assert!(!job.join("plan.json").exists());
    sweeptin(&[&plan_args[..], &["-o", s(&job)]].concat(), "plan");
    let plan = job.join("plan.json");
    let (_, n) = plan_extent(&plan);
    let away = t.path().join("away.laz");
    std::fs::rename(&input, &away).unwrap();
    let out = bin()
        .args(["run", s(&plan), "--all", "-q"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains(&format!("{n} of {n} tasks failed")) && err.contains("--resume"),
        "{err}"
    );
    std::fs::rename(&away, &input).unwrap();
    sweeptin(
        &["run", s(&plan), "--all", "--resume", "-q"],
        "run --resume",
    );
    for r in records(&job, n) {
        assert!(r["status"] == "done" || r["status"] == "empty", "{r}");
    }
    // A tile cut short after its task finished (a full disk, a copy interrupted) runs again.
    let tile = job.join(records(&job, n)[0]["outputs"][0][1].as_str().unwrap());
    let whole = std::fs::read(&tile).unwrap();
    std::fs::write(&tile, &whole[..100]).unwrap();
    sweeptin(
        &["run", s(&plan), "--all", "--resume", "-q"],
        "run --resume",
    );
    assert!(
        std::fs::read(&tile).unwrap() == whole,
        "the cut tile was not run again"
    );
}

/// Issue 41, item 15: `plan` printed the number of tasks alone on standard output among its
/// messages on a terminal; it prints it for a script (`N=$(sweeptin plan …)`) only. An empty
/// task of a contour or TIN plan said its outputs were "a nodata raster".
#[test]
fn plan_messages_say_what_each_product_writes() {
    let t = tempfile::tempdir().unwrap();
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let args = |job: &Path, product: &str| -> Vec<String> {
        let mut a = vec!["plan".to_string(), product.to_string(), s(&sample).into()];
        if product == "contours" {
            a.extend(["--interval".into(), "1".into()]);
        }
        a.extend(
            ["--class", "18", "--tile", "16", "-o", s(job)]
                .iter()
                .map(|x| x.to_string()),
        );
        a
    };
    // Captured: the count alone on stdout.
    let job = t.path().join("piped");
    let out = ok(bin().args(args(&job, "tin")).output().unwrap(), "plan");
    let n: usize = String::from_utf8_lossy(&out.stdout).trim().parse().unwrap();
    assert_eq!(n, plan_extent(&job.join("plan.json")).1);
    assert!(
        !out.stderr.is_empty(),
        "the summary and next lines are on stderr"
    );
    // `-q`: the count on stdout, nothing on stderr (the summary and "next:" lines were printed).
    let quiet = t.path().join("quiet");
    let mut a = args(&quiet, "tin");
    a.push("-q".into());
    let out = ok(bin().args(a).output().unwrap(), "plan -q");
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), n.to_string());
    // On a terminal (`script` gives the command one): the messages alone.
    let job = t.path().join("tty");
    let line = std::iter::once(bin().get_program().to_string_lossy().into_owned())
        .chain(args(&job, "tin"))
        .map(|a| format!("'{a}'"))
        .collect::<Vec<_>>()
        .join(" ");
    match Command::new("script")
        .args(["-qec", &line, "/dev/null"])
        .output()
    {
        Ok(o) => {
            let text = String::from_utf8_lossy(&o.stdout);
            assert!(text.contains(&format!("{n} tasks")), "{text}");
            assert!(
                !text.lines().any(|l| l.trim() == n.to_string()),
                "a bare count on the terminal: {text}"
            );
        }
        Err(e) => assert!(!data::in_ci(), "script (util-linux) is needed: {e}"),
    }
    // An empty task says what its product writes.
    for (product, says) in [
        ("tin", "(no triangle)"),
        ("contours", "(no contour line)"),
        ("dem", "(a nodata raster)"),
    ] {
        let job = t.path().join(product);
        let mut a = args(&job, product);
        if product == "dem" {
            a.extend(["--cell".into(), "0.5".into()]);
        }
        ok(bin().args(&a).output().unwrap(), "plan");
        let out = sweeptin(
            &["run", s(&job.join("plan.json")), "--task", "0"],
            "empty task",
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{product}: {err}");
    }
}

/// Issue 43, item 4: `plan contours … --tile 0.1` wrote 8 M tasks (a 2 GB `plan.json`, 3 GB of
/// memory). A plan has at most 2^18 tasks, and the refusal names the smallest round `--tile`
/// that fits, which then plans.
#[test]
fn a_plan_of_too_many_tasks_is_refused_naming_a_tile_that_fits() {
    let dir = tempfile::tempdir().unwrap();
    let job = dir.path().join("job");
    let input = sample();
    let args = ["plan", "tin", s(&input), "--tile", "0.01", "-o", s(&job)];
    failing(&args, 2, "tasks a plan may have: use --tile ");
    assert!(!job.join("plan.json").exists());
    let o = bin().args(args).output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    let tile = e
        .split("use --tile ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap();
    let t: f64 = tile.parse().unwrap();
    assert!(t > 0.01, "{e}");
    // Ten times the suggestion plans quickly (the suggestion itself lists ~2^18 tasks).
    let larger = (10.0 * t).to_string();
    sweeptin(
        &["plan", "tin", s(&input), "--tile", &larger, "-o", s(&job)],
        "plan",
    );
    assert!(job.join("plan.json").exists());
}

/// `plan tin --tile 1e6` over 73 k points took 185 s for one task against 0.2 s for one run:
/// the task ran every tile of the engine's grid inside its plan tile, millions of them empty. A
/// task whose products are owned by points (a TIN's pieces, contours, volumes) runs only the
/// tiles that hold points; its record counts them (`subtiles`).
#[test]
fn a_tasks_work_follows_its_points_not_its_area() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let input = sample();
    sweeptin(
        &["plan", "tin", s(&input), "--tile", "1000000", "-o", s(&job)],
        "plan",
    );
    let plan = job.join("plan.json");
    let (_, n) = plan_extent(&plan);
    sweeptin(&["run", s(&plan), "--all", "-q"], "run --all");
    let recs = records(&job, n);
    let ran: u64 = recs.iter().map(|r| r["subtiles"].as_u64().unwrap()).sum();
    // One run of the tiled engine over the same points.
    let out = sweeptin(
        &[
            "tin",
            s(&input),
            "--engine",
            "tiles",
            "--json",
            "-q",
            "-o",
            s(&t.path().join("one.ply")),
        ],
        "one run",
    );
    let one: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let tiles = one["tiles"]["tiles"].as_u64().unwrap();
    assert!(
        ran >= 1 && ran <= 4 * tiles.max(1),
        "the tasks ran {ran} tiles where one run runs {tiles}"
    );
    // And the merged mesh is one run's.
    sweeptin(
        &["merge", s(&plan), "-o", s(&t.path().join("m.ply")), "-q"],
        "merge",
    );
}

/// A DEM task runs every sub-tile of its plan tile that triangles can reach (their cells may
/// lie under other tasks' triangles), but no triangle lies outside the box of all the data: a
/// plan tile 60 times wider than the sample walked 4,096 empty sub-tiles; now those of the data's
/// box and one ring around it (9 where one run runs 2), and the mosaic is still one run's file.
#[test]
fn a_dem_tasks_work_stops_at_the_datas_box() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let input = sample();
    let (plan, n) = plan_and_run(&["dem", s(&input), "--cell", "1", "--tile", "4000"], &job);
    let ran: u64 = records(&job, n)
        .iter()
        .map(|r| r["subtiles"].as_u64().unwrap())
        .sum();
    let one = t.path().join("one.tif");
    let out = sweeptin(
        &[
            "dem",
            s(&input),
            "--cell",
            "1",
            "--engine",
            "tiles",
            "--json",
            "-q",
            "-o",
            s(&one),
        ],
        "one run",
    );
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let tiles = summary["run"]["tiles"]["tiles"].as_u64().unwrap();
    assert!(
        ran >= 1 && ran <= 16 * tiles.max(1),
        "the tasks ran {ran} sub-tiles where one run runs {tiles}"
    );
    let m = t.path().join("m.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&m), "-q"], "merge");
    assert!(
        std::fs::read(&m).unwrap() == std::fs::read(&one).unwrap(),
        "the mosaic is not one run's DEM"
    );
}
