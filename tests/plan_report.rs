//! `sweeptin report` (issue 43 item 6): the report of a night's plan — a static HTML page with
//! one SVG rect per tile coloured by its task's state, the failed tasks with their messages and
//! the command that runs each again, and `--json` with the same counts — checked in the page's
//! text and in a headless Chromium's screenshot.

use crate::data;
use crate::plans;

use plans::{bin, s, sweeptin};
use std::path::{Path, PathBuf};

fn sample() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz")
}

/// `plan dem` of the sample at `cell` in tiles of `tile` into `job`: the plan file.
fn plan_dem(job: &Path, cell: &str, tile: &str) -> PathBuf {
    sweeptin(
        &[
            "plan",
            "dem",
            s(&sample()),
            "--cell",
            cell,
            "--tile",
            tile,
            "-q",
            "-o",
            s(job),
        ],
        "plan",
    );
    job.join("plan.json")
}

/// A night: a DEM plan over the sample whose task 0 fails (a directory where its tile goes),
/// whose last task is not run and whose other tasks finish. Returns the plan and its tasks.
fn night(job: &Path) -> (PathBuf, usize) {
    let plan = plan_dem(job, "0.5", "16");
    let p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&plan).unwrap()).unwrap();
    let tiles = p["tiles"].as_array().unwrap();
    let n = tiles.len();
    assert!(n >= 3, "{n} tasks");
    let (tx, ty) = (
        tiles[0]["tx"].as_i64().unwrap(),
        tiles[0]["ty"].as_i64().unwrap(),
    );
    std::fs::create_dir_all(job.join(format!("tiles/dem_{tx}_{ty}.tif"))).unwrap();
    let o = bin()
        .args(["run", s(&plan), "--task", "0", "-q"])
        .output()
        .unwrap();
    assert!(!o.status.success(), "task 0 ran over a directory");
    for i in 1..n - 1 {
        sweeptin(&["run", s(&plan), "--task", &i.to_string(), "-q"], "run");
    }
    (plan, n)
}

fn rect_of(html: &str, i: usize) -> &str {
    let at = html
        .find(&format!("data-task=\"{i}\""))
        .unwrap_or_else(|| panic!("no rect for task {i}"));
    let start = html[..at].rfind("<rect").unwrap();
    &html[start..at]
}

/// A night of tasks left no view of what happened: which tiles failed, why, and how to run them
/// again, short of reading every `task_<i>.json` (and a failed task left no record at all).
#[test]
fn report_maps_done_failed_and_not_run_tasks_and_says_how_to_rerun_the_failed() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let (plan, n) = night(&job);
    let page = t.path().join("report.html");
    let o = sweeptin(&["report", s(&plan), "-o", s(&page), "--json"], "report");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["tasks"], n);
    assert_eq!(j["failed"], 1, "{j}");
    assert_eq!(j["not_run"], 1, "{j}");
    assert_eq!(
        j["done"].as_u64().unwrap() + j["empty"].as_u64().unwrap(),
        n as u64 - 2
    );
    assert_eq!(j["task_list"][0]["state"], "failed");
    assert_eq!(j["task_list"][n - 1]["state"], "not_run");
    assert!(j["points"].as_u64().unwrap() > 0);
    let html = std::fs::read_to_string(&page).unwrap();
    assert_eq!(html.matches("<rect ").count(), n, "one rect per tile");
    assert!(rect_of(&html, 0).contains("class=\"failed\""));
    assert!(rect_of(&html, n - 1).contains("class=\"not_run\""));
    for i in 1..n - 1 {
        let r = rect_of(&html, i);
        assert!(
            r.contains("class=\"done\"") || r.contains("class=\"empty\""),
            "{r}"
        );
    }
    assert!(html.contains("not a regular file"), "the failure's message");
    assert!(html.contains(&format!("sweeptin run {} --task 0", s(&plan))));
    assert!(!html.contains("<script"), "no script");

    // Every string from a record is escaped.
    let f = job.join("tiles/task_0.failed.json");
    let mut rec: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
    rec["message"] = "<script>alert(1)</script> & \"quoted\"".into();
    std::fs::write(&f, rec.to_string()).unwrap();
    sweeptin(&["report", s(&plan), "-o", s(&page)], "report again");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(!html.contains("<script"), "{html}");
    assert!(html.contains("&lt;script&gt;alert(1)&lt;/script&gt; &amp; &quot;quoted&quot;"));

    // A task that runs again and finishes leaves no failure behind.
    std::fs::remove_dir(
        job.join(
            std::fs::read_dir(job.join("tiles"))
                .unwrap()
                .flatten()
                .find(|e| e.path().is_dir())
                .unwrap()
                .path(),
        ),
    )
    .unwrap();
    sweeptin(&["run", s(&plan), "--task", "0", "-q"], "run 0 again");
    assert!(
        !f.exists(),
        "the failure record outlived the task's success"
    );
    let o = sweeptin(&["report", s(&plan), "--json"], "report json");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (j["failed"].as_u64(), j["not_run"].as_u64()),
        (Some(0), Some(1))
    );
}

/// The report refuses to replace the plan or a tile, and a name that is not a regular file.
#[test]
fn report_refuses_the_plans_own_files_and_names_that_are_not_files() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let plan = plan_dem(&job, "0.5", "32");
    let before = std::fs::read(&plan).unwrap();
    for (out, says) in [
        (plan.clone(), "plan"),
        (job.join("tiles/report.html"), "tiles"),
        (t.path().to_path_buf(), "not a regular file"),
    ] {
        let o = bin()
            .args(["report", s(&plan), "-o", s(&out)])
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{out:?}: {e}");
        assert!(e.contains(says), "{out:?}: {e}");
    }
    assert_eq!(
        std::fs::read(&plan).unwrap(),
        before,
        "the plan was overwritten"
    );
    assert!(!job.join("tiles/report.html").exists());
}

/// The page is drawn as meant in a real browser: headless Chromium's screenshot holds the
/// colours of the done, failed and not-run tiles.
#[test]
fn report_renders_the_tile_states_in_headless_chromium() {
    let test = "report_renders_the_tile_states_in_headless_chromium";
    if !data::tool("chromium", test) {
        return;
    }
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let (plan, _) = night(&job);
    let page = t.path().join("report.html");
    sweeptin(&["report", s(&plan), "-o", s(&page)], "report");
    let shot = t.path().join("shot.png");
    let profile = t.path().join("profile");
    let o = std::process::Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            &format!("--user-data-dir={}", s(&profile)),
            &format!("--screenshot={}", s(&shot)),
            "--window-size=1000,1400",
        ])
        .arg(format!("file://{}", s(&page)))
        .output()
        .unwrap();
    assert!(
        shot.exists(),
        "no screenshot: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = match info.color_type {
        png::ColorType::Rgba => 4,
        png::ColorType::Rgb => 3,
        c => panic!("screenshot in {c:?}"),
    };
    let count = |rgb: [u8; 3]| {
        buf[..info.buffer_size()]
            .chunks(px)
            .filter(|p| (0..3).all(|k| p[k].abs_diff(rgb[k]) <= 8))
            .count()
    };
    for (state, rgb) in [
        ("failed", [0xd6, 0x27, 0x28]),
        ("not run", [0x1f, 0x5f, 0xd6]),
        ("done", [0x2c, 0xa0, 0x2c]),
    ] {
        assert!(count(rgb) > 400, "no {state} tile in the screenshot");
    }
}

/// A task killed by a signal (the out-of-memory killer's SIGKILL) wrote nothing: the report took
/// it for one not run. `run --all` records the signal, and the report shows it as failed.
#[test]
fn report_names_a_task_killed_by_a_signal_as_failed() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let plan = plan_dem(&job, "1", "32");
    let o = bin()
        .args(["run", s(&plan), "--all", "-q"])
        .env("SWEEPTIN_TEST_KILL_TASK", "1")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(4));
    let o = sweeptin(&["report", s(&plan), "--json"], "report");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (j["failed"].as_u64(), j["not_run"].as_u64()),
        (Some(1), Some(0))
    );
    let task = &j["task_list"][1];
    assert_eq!(task["state"], "failed");
    let m = task["message"].as_str().unwrap();
    assert!(m.contains("killed by SIGKILL (signal 9"), "{m}");
    assert_eq!(task["rerun"], format!("sweeptin run {} --task 1", s(&plan)));
}
