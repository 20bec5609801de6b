//! Plans over plain LAZ/LAS files read by area (issue 43 item 1): `plan` writes the chunk index
//! of every plain file once, each task decodes only the chunks that meet its tile and buffer,
//! and the mosaic is still one run's, cell for cell; a damaged index is refused.

use crate::data;
use crate::plans;

use plans::{bin, cells, plan_extent, records, s, sweeptin};
use std::path::{Path, PathBuf};

fn topography() -> PathBuf {
    data::data_dir().join("lidar/lidR_Topography.laz")
}

/// Plans a DEM over `input` into `job` (tiles of 32, cells of 1), runs every task, merges, and
/// checks the mosaic against one run over the plan's extent. Returns the task records. (Tasks
/// away from the data's edge read by area; lidR_Topography's second chunk is its eastern 75 m.)
fn plan_equals_one_run(input: &Path, t: &Path) -> Vec<serde_json::Value> {
    let job = t.join("job");
    let (cell, tile) = ("1", "32");
    sweeptin(
        &[
            "plan",
            "dem",
            s(input),
            "--cell",
            cell,
            "--tile",
            tile,
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    assert!(
        job.join("index/0.chunks").is_file(),
        "no chunk index written"
    );
    let (_, n) = plan_extent(&plan);
    assert!(n >= 9, "{n} tasks");
    let single = t.join("single.tif");
    sweeptin(
        &["dem", s(input), "--cell", cell, "-o", s(&single), "-q"],
        "single run",
    );
    sweeptin(&["run", s(&plan), "--all", "-q"], "run --all");
    let mosaic = t.join("mosaic.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&mosaic)], "merge");
    assert!(
        cells(&mosaic) == cells(&single),
        "the mosaic differs from one run"
    );
    let recs = records(&job, n);
    for r in &recs {
        if r["status"] == "empty" {
            assert!(
                r["outputs"].as_array().unwrap().is_empty(),
                "an empty task wrote a tile: {r}"
            );
        }
    }
    recs
}

/// Every task decoded the whole file (one 10.6 M-point LAZ: each task ~4 s, the empty ones
/// too): with the chunk index, tasks far from a chunk do not decode it.
#[test]
fn tasks_of_a_plan_over_one_laz_decode_only_their_chunks() {
    let t = tempfile::tempdir().unwrap();
    let recs = plan_equals_one_run(&topography(), t.path());
    let decoded: Vec<u64> = recs
        .iter()
        .map(|r| r["decoded"].as_u64().unwrap())
        .collect();
    assert!(
        decoded.iter().any(|&d| d > 0 && d < 73_403),
        "every task decoded the whole file: {decoded:?}"
    );
}

/// The same for a LAS file, by blocks of 50,000 records.
#[test]
fn tasks_of_a_plan_over_one_las_decode_only_their_blocks() {
    let test = "tasks_of_a_plan_over_one_las_decode_only_their_blocks";
    if !data::python(&["laspy"], test) {
        return;
    }
    let t = tempfile::tempdir().unwrap();
    let las = t.path().join("topography.las");
    let code = format!(
        "import laspy; laspy.read({:?}).write({:?})",
        s(&topography()),
        s(&las)
    );
    let o = std::process::Command::new("python3")
        .args(["-c", &code])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let recs = plan_equals_one_run(&las, t.path());
    let decoded: Vec<u64> = recs
        .iter()
        .map(|r| r["decoded"].as_u64().unwrap())
        .collect();
    assert!(
        decoded.iter().any(|&d| d > 0 && d < 73_403),
        "every task decoded the whole file: {decoded:?}"
    );
}

/// Empty tasks wrote a 1 MB nodata tile each: a task whose tile holds no point of the data
/// (here the half of the file's box above its diagonal, where a copy of the file keeps no point)
/// writes no tile, its record says "empty", and the mosaic is still one run's.
#[test]
fn an_empty_task_writes_no_tile() {
    let test = "an_empty_task_writes_no_tile";
    if !data::python(&["laspy", "lazrs"], test) {
        return;
    }
    let t = tempfile::tempdir().unwrap();
    let half = t.path().join("half.laz");
    let code = format!(
        "import laspy\nl = laspy.read({:?})\nk = (l.x - l.x.min()) > (l.y - l.y.min())\n\
         o = laspy.LasData(l.header)\no.points = l.points[k]\no.write({:?})",
        s(&topography()),
        s(&half)
    );
    let o = std::process::Command::new("python3")
        .args(["-c", &code])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let recs = plan_equals_one_run(&half, t.path());
    assert!(
        recs.iter().any(|r| r["status"] == "empty"),
        "no empty task: {recs:?}"
    );
}

/// A chunk index cut short or edited would make tasks skip chunks: refused, exit 3, naming it.
#[test]
fn a_truncated_or_edited_chunk_index_is_refused() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    sweeptin(
        &[
            "plan",
            "dem",
            s(&topography()),
            "--cell",
            "1",
            "--tile",
            "128",
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    let index = job.join("index/0.chunks");
    let bytes = std::fs::read(&index).unwrap();
    let mut edited = bytes.clone();
    // The first span's xmin.
    edited[40 + 32] ^= 1;
    for (what, damaged) in [
        ("truncated", bytes[..bytes.len() - 1].to_vec()),
        ("checksum", edited),
    ] {
        std::fs::write(&index, &damaged).unwrap();
        let o = bin()
            .args(["run", s(&plan), "--task", "0", "-q"])
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{what}: {e}");
        assert!(e.contains("chunk index") && e.contains(what), "{what}: {e}");
        assert!(!job.join("tiles/task_0.json").exists());
    }
    std::fs::write(&index, &bytes).unwrap();
    sweeptin(&["run", s(&plan), "--task", "0", "-q"], "run");
}
