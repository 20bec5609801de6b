//! Plans at their edges: tile sides whose edges are not whole numbers, and a mosaic whose path
//! reaches the tasks' outputs.

#[path = "support/data.rs"]
mod data;
#[path = "support/plans.rs"]
mod plans;

use plans::{bin, s, sweeptin};
use std::path::PathBuf;

/// Tiles whose edges are not whole numbers (27.9 × 225,002 rounds below the edge): each task
/// runs its own tile, found by its centre (half the tasks ran a neighbour's or nothing, reported
/// "empty", and the mosaic lost whole rows: a volume 11 % low). The volume sums exactly to one
/// run's, which needs every tile's triangles once.
#[test]
fn tiles_with_edges_that_round_each_run_their_own_tile() {
    let files = data::ign_tiles();
    let t = tempfile::tempdir().unwrap();
    let mut one: Vec<&str> = vec!["volume"];
    one.extend(files.iter().map(|p| s(p)));
    one.extend(["--plane", "30", "--json", "-q"]);
    let one: serde_json::Value = serde_json::from_slice(&sweeptin(&one, "volume").stdout).unwrap();
    for tile in ["27.9", "24.9"] {
        let job = t.path().join(tile);
        let mut args: Vec<&str> = vec!["plan", "volume"];
        args.extend(files.iter().map(|p| s(p)));
        args.extend(["--plane", "30", "--tile", tile, "-o", s(&job)]);
        sweeptin(&args, "plan");
        let plan = job.join("plan.json");
        sweeptin(&["run", s(&plan), "--all", "--jobs", "2", "-q"], "run");
        let out = sweeptin(&["merge", s(&plan), "--json"], "merge");
        let merged: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        for k in ["cut_volume", "fill_volume", "area"] {
            assert_eq!(merged["volume"][k], one[k], "--tile {tile}: {k}");
        }
    }
}

/// Files whose edges lie on tile edges (the IGN tiles end on multiples of 50 m): a DEM plan
/// has a task per tile holding cell centres, and the mosaic is one run's raster, byte for byte
/// (a row and a column of empty tasks made the mosaic 200 × 150 against 150 × 100).
#[test]
fn a_dem_plan_tiles_only_where_cell_centres_are() {
    let files = data::ign_tiles();
    let t = tempfile::tempdir().unwrap();
    let one = t.path().join("one.tif");
    let mut args: Vec<&str> = vec!["dem"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend(["--cell", "1", "-q", "-o", s(&one)]);
    sweeptin(&args, "dem");
    let job = t.path().join("job");
    let mut args: Vec<&str> = vec!["plan", "dem"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend(["--cell", "1", "--tile", "50", "-q", "-o", s(&job)]);
    sweeptin(&args, "plan");
    let plan = job.join("plan.json");
    let p: serde_json::Value = serde_json::from_slice(&std::fs::read(&plan).unwrap()).unwrap();
    assert_eq!(p["tiles"].as_array().unwrap().len(), files.len());
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    let mosaic = t.path().join("m.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&mosaic), "-q"], "merge");
    assert!(std::fs::read(&mosaic).unwrap() == std::fs::read(&one).unwrap());
}

/// The mosaic never goes over a task's output, however its path reaches the tiles: through
/// `..` or a symbolic link (both replaced a tile with the mosaic, and later merges took it).
#[test]
fn the_mosaic_never_replaces_a_task_output() {
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let args = [
        "plan",
        "dem",
        s(&sample),
        "--cell",
        "0.5",
        "--tile",
        "16",
        "-o",
        s(&job),
    ];
    sweeptin(&args, "plan");
    let plan = job.join("plan.json");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    let tile = std::fs::read_dir(job.join("tiles"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "tif"))
        .unwrap();
    let before = std::fs::read(&tile).unwrap();
    let name = tile.file_name().unwrap().to_str().unwrap();
    let dotted = job.join("..").join("job/tiles").join(name);
    #[cfg(unix)]
    let links = {
        let link = t.path().join("link.tif");
        std::os::unix::fs::symlink(&tile, &link).unwrap();
        let dangling = t.path().join("dangling.vrt");
        std::os::unix::fs::symlink(job.join("tiles/new.vrt"), &dangling).unwrap();
        vec![link, dangling]
    };
    #[cfg(not(unix))]
    let links: Vec<PathBuf> = Vec::new();
    for out in std::iter::once(dotted).chain(links) {
        let o = bin()
            .args(["merge", s(&plan), "-o", s(&out)])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{}", out.display());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("where the tasks' outputs are"), "{err}");
    }
    assert!(
        std::fs::read(&tile).unwrap() == before,
        "a tile was replaced"
    );
    assert!(!job.join("tiles/new.vrt").exists());
}

/// A plan of the sample file in `t/NAME` made by `plan COMMAND… --tile 100`, its tasks run.
fn planned_and_run(t: &std::path::Path, name: &str, command: &[&str]) -> PathBuf {
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let job = t.join(name);
    let mut args = vec!["plan", command[0], s(&sample)];
    args.extend(&command[1..]);
    args.extend(["--tile", "100", "-q", "-o", s(&job)]);
    sweeptin(&args, "plan");
    let plan = job.join("plan.json");
    sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    plan
}

/// `merge --contours` on a plan whose tasks drew no contour lines (a DEM planned without
/// --contours, a contours, volume or TIN plan) is refused, saying what the plan makes (it
/// exited 0 and wrote no lines).
#[test]
fn merge_refuses_outputs_its_plan_cannot_give() {
    let t = tempfile::tempdir().unwrap();
    let lines = t.path().join("c.geojson");
    let cases: &[(&[&str], &str, &str)] = &[
        (
            &["dem", "--cell", "1"],
            "m.tif",
            "a DEM without contour lines",
        ),
        (
            &["contours", "--interval", "1"],
            "m.geojson",
            "makes contour lines",
        ),
        (&["volume", "--plane", "0"], "", "makes volumes"),
        (&["tin"], "m.ply", "makes a TIN"),
    ];
    for (command, out, says) in cases {
        let plan = planned_and_run(t.path(), command[0], command);
        let mut args = vec!["merge", s(&plan), "--contours", s(&lines)];
        let out = t.path().join(out);
        if out != t.path() {
            args.extend(["-o", s(&out)]);
        }
        let o = bin().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{command:?}: {err}");
        assert!(err.contains(says), "{command:?}: {err}");
        assert!(!lines.exists(), "{command:?}");
        assert!(
            out == t.path() || !out.exists(),
            "{command:?}: {}",
            out.display()
        );
    }
}
