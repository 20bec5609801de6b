//! Plans at their edges: tile sides whose edges are not whole numbers, and a mosaic whose path
//! reaches the tasks' outputs.

use crate::data;
use crate::plans;

use plans::{bin, s, sweeptin};
use std::path::{Path, PathBuf};

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

/// A plan of the sample file in `t/NAME` made by `plan COMMAND… --tile TILE`, its tasks run.
fn planned_and_run(t: &std::path::Path, name: &str, command: &[&str], tile: &str) -> PathBuf {
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let job = t.join(name);
    let mut args = vec!["plan", command[0], s(&sample)];
    args.extend(&command[1..]);
    args.extend(["--tile", tile, "-q", "-o", s(&job)]);
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
        let plan = planned_and_run(t.path(), command[0], command, "100");
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

/// `merge -o m.vrt` over a truncated tile, or one whose header no longer reads (its size kept),
/// exits 3 naming the tile and the task to run again, as the `.tif` merge does, and writes no
/// VRT (it wrote one, exit 0, and GDAL failed on it later); the task run again mends it.
#[test]
fn a_vrt_merge_checks_every_tile_as_the_tif_merge_does() {
    let t = tempfile::tempdir().unwrap();
    let plan = planned_and_run(t.path(), "job", &["dem", "--cell", "0.5"], "16");
    // The first two tasks with a tile (empty ones write none).
    let records: Vec<serde_json::Value> = (0..)
        .map(|i| {
            let p = t.path().join(format!("job/tiles/task_{i}.json"));
            serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(p).unwrap()).unwrap()
        })
        .filter(|r| r["status"] == "done")
        .take(2)
        .collect();
    let task = |i: usize| records[i]["index"].to_string();
    let tile = |i: usize| {
        t.path()
            .join("job")
            .join(records[i]["outputs"][0][1].as_str().unwrap())
    };
    let vrt = t.path().join("m.vrt");
    let merge = || {
        bin()
            .args(["merge", s(&plan), "-o", s(&vrt)])
            .output()
            .unwrap()
    };
    // Task 0's tile short of its last rows (its header whole); then task 1's header pointing
    // past the end (its size kept).
    type Damage = fn(&mut Vec<u8>);
    let damage: [(&str, Damage); 2] = [
        ("was truncated", |b| b.truncate(b.len() - b.len() / 4)),
        ("cannot be read", |b| {
            b[4..8].copy_from_slice(&u32::MAX.to_le_bytes())
        }),
    ];
    for (i, (says, damage)) in damage.into_iter().enumerate() {
        let mut bytes = std::fs::read(tile(i)).unwrap();
        damage(&mut bytes);
        std::fs::write(tile(i), &bytes).unwrap();
        let o = merge();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{err}");
        assert!(err.contains(s(&tile(i))) && err.contains(says), "{err}");
        assert!(err.contains(&format!("--task {}", task(i))), "{err}");
        assert_eq!(err.contains("--resume"), i == 0, "{err}");
        assert!(!vrt.exists());
        sweeptin(&["run", s(&plan), "--task", &task(i), "-q"], "run");
    }
    sweeptin(&["merge", s(&plan), "-o", s(&vrt), "-q"], "merge");
}

/// A bit flipped anywhere in a TIN task's `.pieces` file (at 48 offsets spread over it, each
/// its own bit): the merge exits 3 naming the file and the task to run again, or 0 with the
/// same mesh, never 5 (1 in 3 flips was "an internal error", and 9 in 20 merged into a
/// different mesh with exit 0).
#[test]
fn a_damaged_pieces_file_is_an_input_error() {
    let t = tempfile::tempdir().unwrap();
    let plan = planned_and_run(t.path(), "job", &["tin"], "16");
    let good = t.path().join("good.ply");
    sweeptin(&["merge", s(&plan), "-o", s(&good), "-q"], "merge");
    let good = std::fs::read(good).unwrap();
    let pieces = std::fs::read_dir(t.path().join("job/tiles"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "pieces"))
        .max_by_key(|p| std::fs::metadata(p).unwrap().len())
        .unwrap();
    let bytes = std::fs::read(&pieces).unwrap();
    let out = t.path().join("m.ply");
    for k in 0..48 {
        let at = (k * bytes.len() / 48 + k * 7919 % 97).min(bytes.len() - 1);
        let mut b = bytes.clone();
        b[at] ^= 1 << (k % 8);
        std::fs::write(&pieces, &b).unwrap();
        let o = bin()
            .args(["merge", s(&plan), "-o", s(&out), "-q"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        match o.status.code() {
            Some(3) => assert!(err.contains(s(&pieces)) && err.contains("--task"), "{err}"),
            Some(0) => assert!(
                std::fs::read(&out).unwrap() == good,
                "byte {at}: another mesh"
            ),
            c => panic!("byte {at}, bit {}: exit {c:?}: {err}", k % 8),
        }
    }
    std::fs::write(&pieces, &bytes).unwrap();
}

/// A DEM plan over the shipped sample in `t/job` (tiles of 16, cells of 1): its `plan.json`.
#[cfg(target_os = "linux")]
fn sample_plan(t: &Path) -> PathBuf {
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let job = t.join("job");
    let args = [
        "plan",
        "dem",
        s(&sample),
        "--cell",
        "1",
        "--tile",
        "16",
        "-q",
        "-o",
        s(&job),
    ];
    sweeptin(&args, "plan");
    job.join("plan.json")
}

/// `run --all` whose task process died of SIGKILL (as the out-of-memory killer does it; the
/// test makes task 1 kill itself) exits 4, naming the task and the signal, also in `--json`
/// (it exited 5, "a bug", without naming either); `--resume` then runs it.
#[cfg(target_os = "linux")]
#[test]
fn a_task_killed_by_a_signal_is_named_with_it() {
    let t = tempfile::tempdir().unwrap();
    let plan = sample_plan(t.path());
    let o = bin()
        .args(["run", s(&plan), "--all", "-q", "--json"])
        .env("SWEEPTIN_TEST_KILL_TASK", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(
        err.contains("task 1 was killed by SIGKILL (signal 9"),
        "{err}"
    );
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["error"]["status"], 4);
    assert!(
        json["error"]["message"]
            .as_str()
            .unwrap()
            .contains("SIGKILL")
    );
    sweeptin(&["run", s(&plan), "--all", "--resume", "-q"], "resume");
    let m = t.path().join("m.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&m), "-q"], "merge");
}

/// `run --all` killed with SIGKILL (it cannot pass that on) left its tasks running, orphaned:
/// they now end with it (the kernel sends them SIGTERM, and they clean up as interrupted).
/// Task 0 waits; once it says so, `run --all` is killed, and the task must be gone within
/// seconds: the stderr pipe it shares closes.
#[cfg(target_os = "linux")]
#[test]
fn tasks_end_with_their_run_all() {
    use std::io::BufRead;
    let t = tempfile::tempdir().unwrap();
    let plan = sample_plan(t.path());
    let mut child = bin()
        .args(["run", s(&plan), "--all", "-q"])
        .env("SWEEPTIN_TEST_TASK_WAITS", "0")
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    std::thread::spawn(move || {
        for line in stderr.lines() {
            let _ = tx.send(line.unwrap_or_default());
        }
    });
    let wait = std::time::Duration::from_secs(60);
    let line = rx.recv_timeout(wait).expect("task 0 never said it waits");
    assert!(line.contains("task 0 waits"), "{line}");
    child.kill().unwrap();
    child.wait().unwrap();
    // The pipe closes when the last process holding it (the task) exits.
    let gone = std::time::Instant::now();
    loop {
        match rx.recv_timeout(std::time::Duration::from_secs(20)) {
            Ok(_) => continue,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            Err(e) => panic!(
                "task 0 still runs {:?} after its run --all was killed: {e}",
                gone.elapsed()
            ),
        }
    }
}

/// A plan whose `--max-edge` trims every triangle merged an all-nodata mosaic with exit 0,
/// where one run refuses (exit 2, "removed all … triangles"): its merge now refuses too, and
/// writes nothing (hostile trial).
#[test]
fn a_merge_with_every_triangle_trimmed_is_refused_as_one_run() {
    let t = tempfile::tempdir().unwrap();
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let job = t.path().join("job");
    let dem = ["dem", s(&sample), "--cell", "1", "--max-edge", "0.01"];
    let one = bin()
        .args(dem)
        .args(["-o", s(&t.path().join("one.tif"))])
        .output()
        .unwrap();
    assert_eq!(one.status.code(), Some(2), "{one:?}");
    sweeptin(
        &[&["plan"], &dem[..], &["--tile", "16", "-q", "-o", s(&job)]].concat(),
        "plan",
    );
    sweeptin(
        &["run", s(&job.join("plan.json")), "--all", "-q"],
        "run --all",
    );
    let m = t.path().join("m.tif");
    let o = bin()
        .args(["merge", s(&job.join("plan.json")), "-o", s(&m)])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--max-edge") && !m.exists(), "{err}");
}
