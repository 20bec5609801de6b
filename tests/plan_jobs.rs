//! A plan's job directory as nightly operations treat it (issue 43): moved or copied, it merges
//! its own tiles from its new place; its `tiles/` deleted, `run` makes it again; a task record
//! that names an output outside its directory is refused.

#[path = "support/plans.rs"]
mod plans;

use plans::{bin, cells, s, sweeptin};
use std::path::{Path, PathBuf};

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
