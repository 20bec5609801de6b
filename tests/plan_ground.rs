//! `plan … --ground`: every task classifies the ground of the area it reads, as one run over all
//! the plan's files does, so the merged DEM is `dem --ground`'s byte for byte, whatever the tile
//! size; a task run twice writes the same tile.

use crate::data;
use crate::plans;

use plans::{s, sweeptin};
use std::path::{Path, PathBuf};

/// `dem FILES --ground PARAMS --cell 1 -o OUT`, its bytes.
fn one_run(files: &[PathBuf], params: &[&str], out: &Path) -> Vec<u8> {
    let mut args = vec!["dem"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend(["--ground", "--cell", "1", "-o", s(out), "-q"]);
    args.extend(params);
    sweeptin(&args, "dem --ground");
    std::fs::read(out).unwrap()
}

/// `plan dem FILES --ground PARAMS --cell 1 --tile TILE -o JOB`, then the plan file.
fn plan(files: &[PathBuf], params: &[&str], tile: &str, job: &Path) -> PathBuf {
    let mut args = vec!["plan", "dem"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend(["--ground", "--cell", "1", "--tile", tile, "-o", s(job)]);
    args.extend(params);
    sweeptin(&args, "plan dem --ground");
    job.join("plan.json")
}

#[test]
fn a_ground_plan_merges_into_the_dem_of_one_ground_run_for_any_tile_size() {
    let t = tempfile::tempdir().unwrap();
    // One file with its own classes (ignored), and six adjacent tiles given together (blocks
    // and their buffers reach across files and tasks).
    let cases: [(Vec<PathBuf>, &[&str], [&str; 2]); 2] = [
        (
            vec![data::shared("lidar/startinpy_small.laz")],
            &[],
            ["30", "45"],
        ),
        (data::ign_tiles(), &["--step", "2"], ["50", "100"]),
    ];
    for (k, (files, params, tiles)) in cases.iter().enumerate() {
        let want = one_run(files, params, &t.path().join(format!("one{k}.tif")));
        for tile in tiles {
            let job = t.path().join(format!("job{k}_{tile}"));
            let plan = plan(files, params, tile, &job);
            let v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&plan).unwrap()).unwrap();
            assert_eq!(v["version"], 4, "a plan with --ground is version 4");
            assert!(
                v["job"]["ground"]["step"].is_number(),
                "the plan keeps the filter"
            );
            sweeptin(
                &["run", s(&plan), "--all", "--jobs", "2", "-q"],
                "run --all",
            );
            let merged = t.path().join(format!("m{k}_{tile}.tif"));
            sweeptin(&["merge", s(&plan), "-o", s(&merged), "-q"], "merge");
            assert!(
                std::fs::read(&merged).unwrap() == want,
                "case {k}, --tile {tile}: the merged DEM is not one run's"
            );
        }
    }
}

#[test]
fn a_ground_task_run_twice_writes_the_same_tile() {
    let t = tempfile::tempdir().unwrap();
    let files = [data::shared("lidar/startinpy_small.laz")];
    let job = t.path().join("job");
    let plan = plan(&files, &[], "30", &job);
    let tile = |i: usize| -> Vec<u8> {
        sweeptin(
            &["run", s(&plan), "--task", &i.to_string(), "-q"],
            "run a task",
        );
        let r: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(job.join("tiles").join(format!("task_{i}.json"))).unwrap(),
        )
        .unwrap();
        let out = r["outputs"][0][1].as_str().expect("the task wrote a tile");
        std::fs::read(job.join(out)).unwrap()
    };
    for i in 0..2 {
        assert!(tile(i) == tile(i), "task {i}: the tile changed");
    }
}
