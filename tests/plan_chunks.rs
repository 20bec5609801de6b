//! Plans over plain LAZ/LAS files read by area (issue 43 item 1): `plan` writes the chunk index
//! of every plain file once, each task decodes only the chunks that meet its tile and buffer
//! (`--no-store`), or reads its points from the plan's point store and decodes nothing, and the
//! mosaic is still one run's, cell for cell; a damaged index, band or store is refused.

use crate::data;
use crate::plans;

use plans::{bin, cells, plan_extent, records, s, sweeptin};
use std::path::{Path, PathBuf};

fn topography() -> PathBuf {
    data::data_dir().join("lidar/lidR_Topography.laz")
}

/// Plans a DEM over `input` into `job` (tiles of 32, cells of 1; `--no-store` unless `store`),
/// runs every task, merges, and checks the mosaic against one run over the plan's extent.
/// Returns the task records. (Tasks away from the data's edge read by area; lidR_Topography's
/// second chunk is its eastern 75 m.)
fn plan_equals_one_run(input: &Path, t: &Path, store: bool) -> Vec<serde_json::Value> {
    let job = t.join("job");
    let (cell, tile) = ("1", "32");
    let mut args = vec!["plan", "--no-store"];
    if store {
        args.pop();
    }
    args.extend([
        "dem",
        s(input),
        "--cell",
        cell,
        "--tile",
        tile,
        "-o",
        s(&job),
    ]);
    sweeptin(&args, "plan");
    let plan = job.join("plan.json");
    // A plan with the point store has no chunk index (its tasks and band read the store).
    assert_eq!(job.join("index/0.chunks").is_file(), !store);
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
    assert_eq!(job.join("index/points").is_file(), store);
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
/// too): with the chunk index (`--no-store`), tasks far from a chunk do not decode it. With the
/// plan's point store (the default over one plain file) they decode nothing: they read the
/// cells meeting their tile and buffer, and the mosaic is byte for byte the one of the plan
/// without the store (and one run's, cell for cell).
#[test]
fn tasks_of_a_plan_over_one_laz_decode_only_their_chunks_or_nothing_with_the_store() {
    let t = tempfile::tempdir().unwrap();
    let recs = plan_equals_one_run(&topography(), t.path(), false);
    let decoded: Vec<u64> = recs
        .iter()
        .map(|r| r["decoded"].as_u64().unwrap())
        .collect();
    assert!(
        decoded.iter().any(|&d| d > 0 && d < 73_403),
        "every task decoded the whole file: {decoded:?}"
    );
    let with = t.path().join("store");
    std::fs::create_dir(&with).unwrap();
    let recs = plan_equals_one_run(&topography(), &with, true);
    for r in &recs {
        assert_eq!(r["decoded"].as_u64(), Some(0), "{r}");
    }
    assert!(
        recs.iter()
            .any(|r| (1..73_403).contains(&r["stored"].as_u64().unwrap())),
        "no task read part of the store: {recs:?}"
    );
    // The report of the night sums what the tasks read from the store.
    let plan = with.join("job/plan.json");
    let o = sweeptin(&["report", s(&plan), "--json"], "report");
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let stored: u64 = recs.iter().map(|r| r["stored"].as_u64().unwrap()).sum();
    assert_eq!(report["stored"].as_u64(), Some(stored), "{report}");
    assert_eq!(report["decoded"].as_u64(), Some(0), "{report}");
    // A DEM's tasks count only the triangles they certify, as one run leaves the unwanted
    // ones deep inside its tiles uncounted (and counts them by Euler over all the points, which
    // no task holds): the report gives no total.
    assert!(
        recs.iter().all(|r| r["inside_uncounted"] == true),
        "{recs:?}"
    );
    assert!(report["triangles"].is_null(), "{report}");
    let (a, b) = (t.path().join("mosaic.tif"), with.join("mosaic.tif"));
    assert!(
        std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
        "the mosaics with and without the store differ"
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
    let recs = plan_equals_one_run(&las, t.path(), false);
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
    let recs = plan_equals_one_run(&half, t.path(), false);
    assert!(
        recs.iter().any(|r| r["status"] == "empty"),
        "no empty task: {recs:?}"
    );
}

/// A chunk index cut short or edited would make tasks skip chunks, a hull band or a point store
/// cut short, edited, missing or of another plan would let them certify against points that
/// are not the data's, or read others: refused, exit 3, naming it.
#[test]
fn a_truncated_or_edited_chunk_index_is_refused() {
    let t = tempfile::tempdir().unwrap();
    let input = topography();
    // Plans of tiles of `tile` into `t/name`, with the point store or not (then with a chunk
    // index).
    let plan = |name: &str, tile: &str, store: bool| {
        let job = t.path().join(name);
        let mut args = vec!["plan", "--no-store"];
        if store {
            args.pop();
        }
        args.extend([
            "dem",
            s(&input),
            "--cell",
            "1",
            "--tile",
            tile,
            "-o",
            s(&job),
        ]);
        sweeptin(&args, "plan");
        job
    };
    let (chunked, stored) = (plan("job", "128", false), plan("stored", "128", true));
    let (other, other_stored) = (plan("other", "64", false), plan("other_stored", "64", true));
    // Task 0 refused (exit 3) naming the damaged file and what is wrong, no record written.
    let refused = |job: &Path, file: &str, what: &str| {
        let o = bin()
            .args(["run", s(&job.join("plan.json")), "--task", "0", "-q"])
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{what}: {e}");
        assert!(e.contains(file) && e.contains(what), "{what}: {e}");
        assert!(!job.join("tiles/task_0.json").exists());
    };
    // The chunk index: cut short, or the first span's xmin edited; the plan's hull band and
    // point store: cut short, edited (the band's points, the store's first point, the end of
    // the store's table), missing, or another plan's.
    for (job, other, file, name, at, table) in [
        (&chunked, &other, "0.chunks", "chunk index", 40 + 32, None),
        (&chunked, &other, "band", "hull band", 120, None),
        (&stored, &other_stored, "band", "hull band", 120, None),
        (
            &stored,
            &other_stored,
            "points",
            "point store",
            0,
            Some(200),
        ),
    ] {
        let path = job.join("index").join(file);
        let bytes = std::fs::read(&path).unwrap();
        let edit = |at: usize| {
            let mut e = bytes.clone();
            e[at] ^= 1;
            Some(e)
        };
        let mut cases = vec![
            ("truncated", Some(bytes[..bytes.len() - 1].to_vec())),
            ("checksum", edit(at)),
        ];
        if let Some(back) = table {
            cases.push(("checksum", edit(bytes.len() - back)));
            // The high bit of the first point's z: no point of a damaged cell reaches the task
            // (it did, and the task failed as an internal error, exit 5).
            let mut e = bytes.clone();
            e[11] ^= 0x80;
            cases.push(("checksum", Some(e)));
        }
        if file != "0.chunks" {
            cases.push(("missing", None));
            let theirs = std::fs::read(other.join("index").join(file)).unwrap();
            cases.push(("another plan", Some(theirs)));
        }
        for (what, damaged) in cases {
            match damaged {
                Some(d) => std::fs::write(&path, d).unwrap(),
                None => std::fs::remove_file(&path).unwrap(),
            }
            refused(job, name, what);
        }
        std::fs::write(&path, &bytes).unwrap();
    }
    // A FIFO in the store's place is refused, not waited on; a damaged store is written anew
    // when the plan is made again (it was kept, and the remedy looped).
    let store = stored.join("index/points");
    std::fs::remove_file(&store).unwrap();
    let made = std::process::Command::new("mkfifo")
        .arg(&store)
        .status()
        .unwrap();
    assert!(made.success());
    refused(&stored, "point store", "not a regular file");
    std::fs::remove_file(&store).unwrap();
    let whole = std::fs::read(other_stored.join("index/points")).unwrap();
    let mut bad = whole.clone();
    bad[11] ^= 0x80;
    std::fs::write(other_stored.join("index/points"), bad).unwrap();
    plan("other_stored", "64", true);
    assert!(std::fs::read(other_stored.join("index/points")).unwrap() == whole);
    plan("stored", "128", true);
    for job in [&chunked, &stored] {
        sweeptin(
            &["run", s(&job.join("plan.json")), "--task", "0", "-q"],
            "run",
        );
    }
}

/// `sweeptin index --chunks FILE`: the plan's chunk index, built once per file (as LAStools'
/// `lasindex` writes a `.lax`) and stored beside it.
fn index_chunks(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["index", "--chunks", "--json"];
    all.extend_from_slice(args);
    let o = sweeptin(&all, "index --chunks");
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `plan` into `job` over `input`, without the hull band (which decodes the chunks along the
/// data's edge) or the point store (which decodes the file: here only the chunk index is read
/// or decoded): its stderr.
fn plan_into(input: &Path, job: &Path) -> std::process::Output {
    bin()
        .args([
            "plan",
            "--no-hull-band",
            "--no-store",
            "dem",
            s(input),
            "--cell",
            "1",
            "--tile",
            "32",
            "-o",
        ])
        .arg(job)
        .output()
        .unwrap()
}

/// Every plan over a big plain LAZ decoded it whole to index its chunks, with no way to build
/// the index once per file: `index --chunks` writes `FILE.chunks` (each chunk's box and
/// points), keeps it while it is up to date, and `plan` reads it instead of decoding the file.
#[test]
fn index_chunks_stores_the_chunk_boxes_beside_the_file_and_plan_reads_them() {
    let t = tempfile::tempdir().unwrap();
    let laz = t.path().join("topo.laz");
    std::fs::copy(topography(), &laz).unwrap();
    let copc = t.path().join("topo.copc.laz");
    std::fs::copy(data::data_dir().join("lidR_Topography.copc.laz"), &copc).unwrap();
    let j = index_chunks(&[s(&laz), s(&copc)]);
    let f = &j["files"][0];
    assert_eq!(f["state"], "built", "{f}");
    let side = t.path().join("topo.laz.chunks");
    assert_eq!(f["index"], s(&side));
    let chunks = f["chunks"].as_array().unwrap();
    assert!(chunks.len() >= 2, "{f}");
    let points: u64 = chunks.iter().map(|c| c["points"].as_u64().unwrap()).sum();
    assert_eq!(points, 73_403);
    for c in chunks {
        let b: Vec<f64> = serde_json::from_value(c["bounds"].clone()).unwrap();
        assert!(b[0] <= b[2] && b[1] <= b[3], "{c}");
    }
    assert_eq!(j["files"][1]["state"], "copc");
    assert!(!t.path().join("topo.copc.laz.chunks").exists());
    let built = std::fs::read(&side).unwrap();
    assert_eq!(index_chunks(&[s(&laz)])["files"][0]["state"], "up_to_date");

    // The plan reads it: the same bytes in the job, and a file whose points no longer decode
    // (same size and time) still plans with its index, not without it.
    let o = plan_into(&laz, &t.path().join("job"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains(&format!("read the chunk index {}", s(&side))),
        "{e}"
    );
    assert_eq!(
        std::fs::read(t.path().join("job/index/0.chunks")).unwrap(),
        built
    );
    let when = std::fs::metadata(&laz).unwrap().modified().unwrap();
    let mut bytes = std::fs::read(&laz).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid..mid + 4000].fill(0xa5);
    std::fs::write(&laz, &bytes).unwrap();
    let file = std::fs::File::options().write(true).open(&laz).unwrap();
    file.set_modified(when).unwrap();
    drop(file);
    let o = plan_into(&laz, &t.path().join("job2"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read(t.path().join("job2/index/0.chunks")).unwrap(),
        built
    );
    std::fs::rename(&side, t.path().join("aside")).unwrap();
    let o = plan_into(&laz, &t.path().join("job3"));
    assert!(
        !o.status.success()
            || std::fs::read(t.path().join("job3/index/0.chunks")).unwrap() != built,
        "the plan did not decode the file without its index"
    );

    // A file rewritten since (another time): its index is left, with a warning, and built again.
    std::fs::rename(t.path().join("aside"), &side).unwrap();
    std::fs::copy(topography(), &laz).unwrap();
    let o = plan_into(&laz, &t.path().join("job4"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("is of another version"), "{e}");
    assert_eq!(
        std::fs::read(&side).unwrap(),
        built,
        "the stored index was changed"
    );
    assert_eq!(index_chunks(&[s(&laz)])["files"][0]["state"], "built");
}

/// The LAS blocks of 50,000 records, `-o DIR`, and what `index --chunks` refuses: two files
/// whose indexes would have one name, and a URL.
#[test]
fn index_chunks_of_las_blocks_into_a_directory_and_its_refusals() {
    let t = tempfile::tempdir().unwrap();
    let las =
        data::data_dir().join("lidar/ign_50m_tiles/test_data_77050_627755_LA93_IGN69_ground.las");
    let out = t.path().join("ix");
    let j = index_chunks(&[s(&las), "-o", s(&out)]);
    let f = &j["files"][0];
    let want = out.join("test_data_77050_627755_LA93_IGN69_ground.las.chunks");
    assert_eq!(f["index"], s(&want), "{f}");
    assert!(want.is_file());
    let chunks = f["chunks"].as_array().unwrap();
    let total = f["points"].as_u64().unwrap();
    assert_eq!(chunks.len() as u64, total.div_ceil(50_000), "{f}");
    for (k, c) in chunks.iter().enumerate() {
        assert_eq!(c["first"].as_u64().unwrap(), k as u64 * 50_000);
    }
    assert!(!PathBuf::from(format!("{}.chunks", s(&las))).exists());

    let other = t.path().join("b");
    std::fs::create_dir(&other).unwrap();
    let copy = other.join(las.file_name().unwrap());
    std::fs::copy(&las, &copy).unwrap();
    let o = bin()
        .args(["index", "--chunks", s(&las), s(&copy), "-o", s(&out)])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = bin()
        .args(["index", "--chunks", "https://example.invalid/a.laz"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("local file"), "{e}");
}

/// An edge task over one LAZ read by chunk ran twice (lidR_Topography, tiles of 32: task 9 on
/// the data's south-east hull, buffer 3.2 then 276, the whole file decoded), because it could
/// not tell its own hull edges from the data's: given the data's hull and the points within 2
/// of it (the plan's hull band, `DIR/index/band`), it runs once and writes the same tile, byte
/// for byte; a plan made with `--no-hull-band` runs it twice.
#[test]
fn an_edge_task_given_the_hull_band_runs_once() {
    let t = tempfile::tempdir().unwrap();
    let input = topography();
    let task = |name: &str, band: bool| {
        let job = t.path().join(name);
        let mut args = vec!["plan"];
        if !band {
            args.push("--no-hull-band");
        }
        args.extend([
            "dem",
            s(&input),
            "--cell",
            "1",
            "--tile",
            "32",
            "-o",
            s(&job),
        ]);
        sweeptin(&args, "plan");
        assert_eq!(job.join("index/band").exists(), band);
        let plan = job.join("plan.json");
        let mut c = bin();
        c.args(["run", s(&plan), "--task", "9", "-q"]);
        plans::ok(c.output().unwrap(), "run --task 9");
        let rec: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(job.join("tiles/task_9.json")).unwrap())
                .unwrap();
        let tile = rec["outputs"][0][1].as_str().unwrap().to_string();
        let bytes = std::fs::read(job.join(&tile)).unwrap();
        (rec["runs"].as_u64().unwrap(), bytes)
    };
    let (before, tile_before) = task("off", false);
    assert_eq!(
        before, 2,
        "without the hull the edge task ran {before} times"
    );
    let (runs, tile) = task("on", true);
    assert_eq!(
        runs, 1,
        "given the hull's band the edge task ran {runs} times"
    );
    assert!(tile == tile_before, "the task's tile differs");
}
