//! A plan's directory on S3 (issue 44, item 3: workers that share no disk): `plan -o
//! s3://BUCKET/JOB/` writes the plan and its chunk index there, each task its tiles and then its
//! record, `merge` reads them back, and the mosaic is the local plan's byte for byte. Against
//! moto's S3 server (tests/support/remote.rs); a few seconds each.

use crate::data;
use crate::plans;
use crate::remote_server as remote;

use plans::{bin, s, sweeptin};
use remote::Moto;
use std::path::{Path, PathBuf};

/// The small test file (39,233 points, 41 × 48 m): 6 tasks in tiles of 25.
fn input() -> PathBuf {
    data::shared("lidar/startinpy_small.laz")
}

/// `plan dem INPUT --cell 1 --tile 25 -o DIR` (a path or an `s3://` prefix).
fn plan_args(dir: &str) -> Vec<String> {
    [
        "plan",
        "dem",
        s(&input()),
        "--cell",
        "1",
        "--tile",
        "25",
        "-o",
        dir,
    ]
    .map(String::from)
    .to_vec()
}

/// `sweeptin ARGS` against `moto`, from `cwd`.
fn on_s3(moto: &Moto, args: &[&str], env: &[(&str, &str)], cwd: &Path) -> std::process::Output {
    bin()
        .args(args)
        .envs(moto.env())
        .envs(env.iter().copied())
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn ok(o: std::process::Output, what: &str) -> std::process::Output {
    assert!(
        o.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

#[test]
fn a_plan_on_s3_merges_to_the_local_plans_mosaic_byte_for_byte() {
    let Some(moto) = Moto::start("a_plan_on_s3_merges_to_the_local_plans_mosaic_byte_for_byte")
    else {
        return;
    };
    moto.bucket("jobs");
    let t = tempfile::tempdir().unwrap();
    // The local plan's mosaic.
    let local = t.path().join("local");
    let args = plan_args(s(&local));
    sweeptin(&args.iter().map(String::as_str).collect::<Vec<_>>(), "plan");
    let plan = local.join("plan.json");
    sweeptin(
        &["run", s(&plan), "--all", "--jobs", "3", "-q"],
        "run --all",
    );
    let want = t.path().join("want.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&want), "-q"], "merge");

    // The same plan on S3, run by a worker with no plan directory (another working directory).
    let worker = tempfile::tempdir().unwrap();
    let args = plan_args("s3://jobs/job/");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    ok(on_s3(&moto, &args, &[], worker.path()), "plan -o s3://");
    let keys = moto.keys("jobs", "job/");
    assert!(
        keys.contains(&"job/plan.json".to_string())
            && keys.contains(&"job/index/0.chunks".to_string()),
        "{keys:?}"
    );
    let remote_plan = "s3://jobs/job/plan.json";
    ok(
        on_s3(
            &moto,
            &["run", remote_plan, "--all", "--jobs", "3", "-q"],
            &[],
            worker.path(),
        ),
        "run --all",
    );
    assert_eq!(
        std::fs::read_dir(worker.path()).unwrap().count(),
        0,
        "the worker wrote local files"
    );
    let keys = moto.keys("jobs", "job/tiles/");
    let records = keys.iter().filter(|k| k.ends_with(".json")).count();
    assert_eq!(records, 6, "{keys:?}");
    assert!(keys.iter().any(|k| k.ends_with(".tif")), "{keys:?}");
    // Merged to a local file and to S3: the local plan's bytes.
    let got = t.path().join("got.tif");
    ok(
        on_s3(
            &moto,
            &["merge", remote_plan, "-o", s(&got), "-q"],
            &[],
            t.path(),
        ),
        "merge",
    );
    assert!(
        std::fs::read(&got).unwrap() == std::fs::read(&want).unwrap(),
        "the mosaic of the plan on S3 differs from the local plan's"
    );
    ok(
        on_s3(
            &moto,
            &["merge", remote_plan, "-o", "s3://jobs/mosaic.tif", "-q"],
            &[],
            t.path(),
        ),
        "merge -o s3://",
    );
    let fetched = t.path().join("fetched.tif");
    assert!(moto.get("jobs", "mosaic.tif", &fetched));
    assert!(std::fs::read(&fetched).unwrap() == std::fs::read(&want).unwrap());
    // A .vrt would name tiles on S3; a mosaic among the plan's tiles; another plan there.
    let o = on_s3(&moto, &["merge", remote_plan, "-o", "m.vrt"], &[], t.path());
    assert_eq!(o.status.code(), Some(2), "{}", remote::stderr(&o));
    assert!(!t.path().join("m.vrt").exists());
    let o = on_s3(
        &moto,
        &["merge", remote_plan, "-o", "s3://jobs/job/tiles/m.tif"],
        &[],
        t.path(),
    );
    assert_eq!(o.status.code(), Some(2), "{}", remote::stderr(&o));
    let mut other = plan_args("s3://jobs/job/");
    other[4] = "0.5".into();
    let other: Vec<&str> = other.iter().map(String::as_str).collect();
    let o = on_s3(&moto, &other, &[], t.path());
    let e = remote::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("already holds another plan"), "{e}");
}

#[test]
fn a_task_on_s3_failing_before_its_record_leaves_none_and_resume_runs_it_again() {
    let Some(moto) =
        Moto::start("a_task_on_s3_failing_before_its_record_leaves_none_and_resume_runs_it_again")
    else {
        return;
    };
    moto.bucket("jobs");
    let t = tempfile::tempdir().unwrap();
    let args = plan_args("s3://jobs/job");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    ok(on_s3(&moto, &args, &[], t.path()), "plan -o s3://");
    let plan = "s3://jobs/job/plan.json";
    // Task 1 has points (a tile, then a record).
    let run = |env: &[(&str, &str)], extra: &[&str]| {
        let mut a = vec!["run", plan, "--task", "1", "-q"];
        a.extend_from_slice(extra);
        on_s3(&moto, &a, env, t.path())
    };
    ok(run(&[], &[]), "run --task 1");
    let record = "job/tiles/task_1.json".to_string();
    assert!(moto.keys("jobs", "job/tiles/").contains(&record));
    // Run again, it fails after uploading its tile: the old record was removed first, and no
    // new one is written, so neither merge nor --resume take the task as finished.
    let o = run(&[("SWEEPTIN_TEST_FAIL_BEFORE_RECORD", "1")], &[]);
    assert!(!o.status.success(), "{}", remote::stderr(&o));
    let keys = moto.keys("jobs", "job/tiles/");
    assert!(!keys.contains(&record), "{keys:?}");
    assert!(keys.iter().any(|k| k.ends_with(".tif")), "{keys:?}");
    let o = on_s3(&moto, &["merge", plan, "-o", "m.tif"], &[], t.path());
    let e = remote::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("have not finished"), "{e}");
    let o = ok(run(&[], &["--resume"]), "run --resume");
    assert!(
        !remote::stderr(&o).contains("already finished"),
        "{}",
        remote::stderr(&o)
    );
    assert!(moto.keys("jobs", "job/tiles/").contains(&record));
    let o = ok(run(&[], &["--resume"]), "run --resume, finished");
    assert!(
        remote::stderr(&o).contains("already finished"),
        "{}",
        remote::stderr(&o)
    );
    // A tile gone from under its record (HEAD finds none): --resume runs the task again.
    let tile = moto
        .keys("jobs", "job/tiles/")
        .into_iter()
        .find(|k| k.ends_with(".tif"))
        .unwrap();
    moto.delete("jobs", &tile);
    let o = ok(run(&[], &["--resume"]), "run --resume, a tile missing");
    assert!(
        !remote::stderr(&o).contains("already finished"),
        "{}",
        remote::stderr(&o)
    );
    assert!(moto.keys("jobs", "job/tiles/").contains(&tile));
}

#[test]
fn a_plan_into_a_missing_bucket_is_refused_before_any_work() {
    let Some(moto) = Moto::start("a_plan_into_a_missing_bucket_is_refused_before_any_work") else {
        return;
    };
    let t = tempfile::tempdir().unwrap();
    // The input does not exist either: the bucket is checked before any input is read.
    let o = on_s3(
        &moto,
        &[
            "plan",
            "dem",
            "missing.laz",
            "--cell",
            "1",
            "--tile",
            "25",
            "-o",
            "s3://nobucket/job/",
        ],
        &[],
        t.path(),
    );
    let e = remote::stderr(&o);
    assert_eq!(o.status.code(), Some(4), "{e}");
    assert!(
        e.contains("s3://nobucket/job/plan.json") && e.contains("no such bucket"),
        "{e}"
    );
    assert_eq!(std::fs::read_dir(t.path()).unwrap().count(), 0);
    // An HTTP server cannot hold a plan.
    let args = plan_args("http://x/job/");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = on_s3(&moto, &args, &[], t.path());
    assert_eq!(o.status.code(), Some(2), "{}", remote::stderr(&o));
}
