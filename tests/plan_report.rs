//! `sweeptin report` (issue 43 item 6): the report of a night's plan — a static HTML page with
//! one SVG rect per tile coloured by its task's state, the failed tasks with their messages and
//! the command that runs each again, the overview of a DEM's mosaic (a small hillshade PNG inline
//! as a `data:` URI), and `--json` with the same counts — checked in the page's text and in a
//! headless Chromium's screenshot.

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

/// Decodes standard base64 (RFC 4648, padded).
fn unbase64(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let mut out = Vec::new();
    for q in text.as_bytes().chunks(4) {
        let n = q
            .iter()
            .take_while(|&&c| c != b'=')
            .fold((0u32, 0), |(n, k), &c| {
                (n | u32::from(value(c)) << (18 - 6 * k), k + 1)
            });
        out.extend_from_slice(&n.0.to_be_bytes()[1..n.1.max(1)]);
    }
    out
}

/// The overview the page embeds: its size and its (grey, alpha) pixels.
fn overview_png(html: &str) -> (u32, u32, Vec<(u8, u8)>) {
    let at = html
        .find("<img class=\"overview\"")
        .unwrap_or_else(|| panic!("no overview in the page"));
    let uri = "src=\"data:image/png;base64,";
    let start = at + html[at..].find(uri).unwrap() + uri.len();
    let end = start + html[start..].find('"').unwrap();
    let bytes = unbase64(&html[start..end]);
    let mut r = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::GrayscaleAlpha);
    let px = buf[..info.buffer_size()]
        .chunks(2)
        .map(|p| (p[0], p[1]))
        .collect();
    (info.width, info.height, px)
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
    assert_eq!(j["overview"]["drawn"], true, "{}", j["overview"]);
    assert_eq!(j["overview"]["tiles"], j["done"], "{}", j["overview"]);
    let html = std::fs::read_to_string(&page).unwrap();
    let (w, h, shades) = overview_png(&html);
    assert!(w > 0 && h > 0 && w.max(h) <= 720, "{w} × {h}");
    assert_eq!(
        (u64::from(w), u64::from(h)),
        (
            j["overview"]["cols"].as_u64().unwrap(),
            j["overview"]["rows"].as_u64().unwrap()
        )
    );
    let shaded = shades.iter().filter(|&&(_, a)| a == 255).count();
    assert_eq!(shaded as u64, j["overview"]["shaded"].as_u64().unwrap());
    assert!(shaded > 1000, "{shaded} pixels shaded");
    let greys: std::collections::BTreeSet<u8> = shades.iter().map(|&(g, _)| g).collect();
    assert!(greys.len() > 20, "a flat overview: {greys:?}");
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
    let shot = screenshot(&page, &t.path().join("shot.png"));
    let count = |rgb: [u8; 3]| {
        shot.iter()
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
    // The overview is decoded and drawn: shades of grey over a large area, which the same page
    // with the image's data broken does not have.
    let html = std::fs::read_to_string(&page).unwrap();
    let broken = t.path().join("broken.html");
    std::fs::write(
        &broken,
        html.replace("data:image/png;base64,", "data:image/png;base64,AAAA"),
    )
    .unwrap();
    let without = screenshot(&broken, &t.path().join("broken.png"));
    let greys = |px: &[[u8; 3]]| {
        px.iter()
            .filter(|p| p[0] == p[1] && p[1] == p[2] && (16..=240).contains(&p[0]))
            .count()
    };
    let (with, without) = (greys(&shot), greys(&without));
    assert!(
        with > without + 20_000,
        "the overview is not drawn: {with} grey pixels with it, {without} with it broken"
    );
}

/// Headless Chromium's screenshot of `page` (1000 × 2400 pixels), as RGB pixels.
fn screenshot(page: &Path, shot: &Path) -> Vec<[u8; 3]> {
    let profile = shot.with_extension("profile");
    let o = std::process::Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            &format!("--user-data-dir={}", s(&profile)),
            &format!("--screenshot={}", s(shot)),
            "--window-size=1000,2400",
        ])
        .arg(format!("file://{}", s(page)))
        .output()
        .unwrap();
    assert!(
        shot.exists(),
        "no screenshot: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = match info.color_type {
        png::ColorType::Rgba => 4,
        png::ColorType::Rgb => 3,
        c => panic!("screenshot in {c:?}"),
    };
    buf[..info.buffer_size()]
        .chunks(px)
        .map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// A plan whose product has no raster (contours) gets no overview, and the report says so.
#[test]
fn report_of_a_plan_without_a_raster_says_it_has_no_overview() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    sweeptin(
        &[
            "plan",
            "contours",
            s(&sample()),
            "--interval",
            "1",
            "--tile",
            "32",
            "-q",
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    let page = t.path().join("report.html");
    let o = sweeptin(&["report", s(&plan), "-o", s(&page), "--json"], "report");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["overview"]["drawn"], false, "{}", j["overview"]);
    let note = j["overview"]["note"].as_str().unwrap();
    assert!(note.contains("no raster"), "{note}");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        !html.contains("<img"),
        "an image for a plan without a raster"
    );
    assert!(html.contains("No overview: the plan&#39;s product (contours) has no raster"));
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

/// `report job/plan.json` (a relative name) called every finished task failed: the record's
/// outputs, already under `job/`, were looked for under `job/job/`.
#[test]
fn report_of_a_plan_named_by_a_relative_path_finds_its_tiles() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let plan = plan_dem(&job, "1", "32");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    let o = bin()
        .current_dir(t.path())
        .args(["report", "job/plan.json", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["failed"], 0, "{}", j["task_list"]);
    assert_eq!(
        j["done"].as_u64().unwrap() + j["empty"].as_u64().unwrap(),
        j["tasks"].as_u64().unwrap()
    );
    assert_eq!(j["overview"]["drawn"], true, "{}", j["overview"]);
}
