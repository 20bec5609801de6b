//! `plan … --ground`: every task classifies the ground of the area it reads, as one run over all
//! the plan's files does, so the merged DEM is `dem --ground`'s byte for byte, whatever the tile
//! size; a task run twice writes the same tile. `plan ground`: the classification itself tiled,
//! every point written once with the class one `sweeptin ground` run gives it, merged into one
//! LAZ or a VPC of the tiles.

use crate::data;
use crate::plans;

use plans::{s, sweeptin};
use std::path::{Path, PathBuf};
use sweeptin::input::las::{Filter, LidarReader};

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
    // (CI time: two tile sizes a case took 108 s; the sizes differ between the cases.)
    let cases: [(Vec<PathBuf>, &[&str], [&str; 1]); 2] = [
        (vec![data::shared("lidar/startinpy_small.laz")], &[], ["45"]),
        (data::ign_tiles(), &["--step", "2"], ["50"]),
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

/// A `--ground` task classifies the ground blocks around its tile, from files well beyond its
/// buffer (blocks of 160 m, read with 60 m around, at the default step): it checks those files
/// against the plan too (issue 43), as it does the files of its buffer. Before, a corner task
/// of the six IGN tiles (buffer 1 m: one file) read a far file changed since the plan unchecked
/// (the classes of two versions mixed, or a chunk-index error). About 2 s in a debug build.
#[test]
fn a_ground_task_refuses_a_file_of_its_ground_blocks_changed_since_the_plan() {
    let t = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for f in data::ign_tiles() {
        let to = t.path().join(f.file_name().unwrap());
        std::fs::copy(&f, &to).unwrap();
        let mut perm = std::fs::metadata(&to).unwrap().permissions();
        #[allow(clippy::permissions_set_readonly_false)]
        perm.set_readonly(false);
        std::fs::set_permissions(&to, perm).unwrap();
        files.push(to);
    }
    let job = t.path().join("job");
    let mut args = vec!["plan", "--buffer", "1", "dem"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend([
        "--ground",
        "--cell",
        "1",
        "--tile",
        "25",
        "-o",
        s(&job),
        "-q",
    ]);
    sweeptin(&args, "plan dem --ground");
    let plan = job.join("plan.json");
    let p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&plan).unwrap()).unwrap();
    // Task 0, the south-west corner, reads the first file only; the last is 75 m away.
    assert_eq!(p["tiles"][0]["files"], serde_json::json!([0]));
    let far = files.last().unwrap();
    let f = std::fs::File::options().write(true).open(far).unwrap();
    f.set_modified(std::time::SystemTime::now() + std::time::Duration::from_secs(100))
        .unwrap();
    drop(f);
    let (code, e) = status(&["run", s(&plan), "--task", "0", "-q"]);
    assert_eq!(code, 3, "{e}");
    assert!(
        e.contains(&far.display().to_string()) && e.contains("changed since the plan"),
        "{e}"
    );
}

/// Every point of `files` by what it is and carries (x, y, z bits, return number, number of
/// returns, flags, class), sorted: equal lists mean the same points, each as often, with the
/// same classes.
fn points(files: &[PathBuf]) -> Vec<([u64; 3], [u8; 4])> {
    let mut v: Vec<_> = LidarReader::open(files, &Filter::keep_all())
        .unwrap()
        .read_all()
        .unwrap()
        .iter()
        .map(|p| {
            (
                [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()],
                [
                    p.return_number,
                    p.number_of_returns,
                    p.flags,
                    p.classification,
                ],
            )
        })
        .collect();
    v.sort_unstable();
    v
}

/// `sweeptin ground FILES PARAMS --odir DIR`: its outputs.
fn ground_run(files: &[PathBuf], params: &[&str], dir: &Path) -> Vec<PathBuf> {
    std::fs::create_dir_all(dir).unwrap();
    let mut args = vec!["ground"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend(["--odir", s(dir), "-q"]);
    args.extend(params);
    sweeptin(&args, "ground");
    files
        .iter()
        .map(|f| dir.join(f.file_name().unwrap()))
        .collect()
}

/// `plan ground FILES PARAMS --tile TILE -o JOB` and `run --all`: the plan file.
fn ground_plan(files: &[PathBuf], params: &[&str], tile: &str, job: &Path) -> PathBuf {
    let mut args = vec!["plan", "ground"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend(["--tile", tile, "-o", s(job), "-q"]);
    args.extend(params);
    sweeptin(&args, "plan ground");
    let plan = job.join("plan.json");
    sweeptin(
        &["run", s(&plan), "--all", "--jobs", "2", "-q"],
        "run --all",
    );
    plan
}

/// The files a `.vpc` lists.
fn vpc_files(vpc: &Path) -> Vec<PathBuf> {
    sweeptin::input::files::expand(
        &[vpc.to_path_buf()],
        sweeptin::input::files::Expand::VpcFiles,
    )
    .unwrap()
    .files
}

#[test]
fn plan_ground_gives_every_point_once_the_class_of_one_ground_run_for_any_tile_size() {
    let t = tempfile::tempdir().unwrap();
    // One file, and six adjacent tiles given together whose edges the plan's tiles cut across
    // (70): blocks and their buffers reach across files and tasks. One tile size a case (CI
    // time: two each took 80 s; `a_ground_plan_merges_into_the_dem_of_one_ground_run_for_any_tile_size`
    // runs the same tasks at two sizes).
    let cases: [(Vec<PathBuf>, &[&str], [&str; 1]); 2] = [
        (vec![data::shared("lidar/startinpy_small.laz")], &[], ["30"]),
        (data::ign_tiles(), &["--step", "2"], ["70"]),
    ];
    for (k, (files, params, tiles)) in cases.iter().enumerate() {
        let one = ground_run(files, params, &t.path().join(format!("one{k}")));
        let want = points(&one);
        assert!(want.iter().any(|p| p.1[3] == 2), "case {k}: no ground");
        for tile in tiles {
            let job = t.path().join(format!("job{k}_{tile}"));
            let plan = ground_plan(files, params, tile, &job);
            let laz = t.path().join(format!("m{k}_{tile}.laz"));
            sweeptin(
                &["merge", s(&plan), "-o", s(&laz), "-q"],
                "merge into a LAZ",
            );
            assert!(
                points(std::slice::from_ref(&laz)) == want,
                "case {k}, --tile {tile}: the merged LAZ is not one ground run's points"
            );
            let vpc = t.path().join(format!("m{k}_{tile}.vpc"));
            sweeptin(
                &["merge", s(&plan), "-o", s(&vpc), "-q"],
                "merge into a VPC",
            );
            let listed = vpc_files(&vpc);
            assert!(listed.iter().all(|f| f.starts_with(job.join("tiles"))));
            assert!(
                points(&listed) == want,
                "case {k}, --tile {tile}: the VPC's tiles are not one ground run's points"
            );
        }
    }
}

#[test]
fn a_ground_plan_resumes_after_a_lost_tile_and_its_merged_laz_reads_back() {
    let t = tempfile::tempdir().unwrap();
    let files = [data::shared("lidar/startinpy_small.laz")];
    let job = t.path().join("job");
    let plan = ground_plan(&files, &[], "30", &job);
    let a = t.path().join("a.laz");
    sweeptin(&["merge", s(&plan), "-o", s(&a), "-q"], "merge");
    // A tile lost: `--resume` runs its task again, and the merge is the same file.
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(job.join("tiles/task_0.json")).unwrap())
            .unwrap();
    let tile = job.join(r["outputs"][0][1].as_str().expect("task 0 wrote a tile"));
    std::fs::remove_file(&tile).unwrap();
    let refused = plans::bin()
        .args(["merge", s(&plan), "-o", s(&t.path().join("x.laz"))])
        .output()
        .unwrap();
    assert!(!refused.status.success(), "a merge without a tile");
    sweeptin(
        &["run", s(&plan), "--all", "--resume", "-q"],
        "run --all --resume",
    );
    assert!(tile.exists(), "--resume wrote the lost tile again");
    // A merge writes plain LAZ: a `.copc.laz` name is refused before any work (it passed for
    // a COPC file).
    let copc = t.path().join("x.copc.laz");
    let (code, err) = status(&["merge", s(&plan), "-o", s(&copc), "-q"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not COPC") && !copc.exists(), "{err}");
    let b = t.path().join("b.laz");
    sweeptin(&["merge", s(&plan), "-o", s(&b), "-q"], "merge again");
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap());
    sweeptin(
        &["report", s(&plan), "-o", s(&t.path().join("r.html"))],
        "report",
    );
    // An independent reader: every point, the header's count and bounds those of the points.
    if !data::python(&["laspy", "lazrs"], "ground_plan_laz_reads_back") {
        return;
    }
    let script = "import sys, laspy, numpy as np\n\
        l = laspy.read(sys.argv[1])\n\
        h = l.header\n\
        ok = np.allclose(h.mins, [l.x.min(), l.y.min(), l.z.min()]) and \
             np.allclose(h.maxs, [l.x.max(), l.y.max(), l.z.max()])\n\
        print(len(l.points), h.point_count, ok, int((np.asarray(l.classification) == 2).sum()))";
    let o = std::process::Command::new("python3")
        .args(["-c", script, s(&a)])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mine = points(std::slice::from_ref(&a));
    let ground = mine.iter().filter(|p| p.1[3] == 2).count();
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        format!("{} {} True {ground}", mine.len(), mine.len())
    );
}

/// Writes a LAS 1.2 file (point format 0, no CRS) of 20 × 20 m from `x0`: a sloping ground with
/// a 5 m box on it, coordinates stored with `scale`.
fn sloping_las(path: &Path, x0: f64, scale: f64) {
    sloping_las_as(path, x0, scale, (1, 2), false);
}

/// [`sloping_las`] in LAS `version`, with every seventh point a return 6 or 7 of 7 when
/// `high_returns` (point formats 0–5 hold them in 3 bits; the counts by return of a header
/// before LAS 1.4 have no place for them).
fn sloping_las_as(path: &Path, x0: f64, scale: f64, version: (u8, u8), high_returns: bool) {
    use las::{Builder, Point, Transform, Vector, Writer};
    let mut b = Builder::from(version);
    let t = |offset| Transform { scale, offset };
    b.transforms = Vector {
        x: t(0.0),
        y: t(0.0),
        z: t(0.0),
    };
    let mut w = Writer::from_path(path, b.into_header().unwrap()).unwrap();
    for i in 0..40 {
        for j in 0..40 {
            let (x, y) = (x0 + 0.5 * f64::from(i) + 0.25, 0.5 * f64::from(j) + 0.25);
            let roof = (6..12).contains(&(i % 20)) && (6..12).contains(&j);
            let z = 0.1 * x + if roof { 5.0 } else { 0.0 };
            let high = high_returns && (i + j) % 7 == 0;
            w.write_point(Point {
                x,
                y,
                z,
                return_number: if high { 5 } else { 1 },
                number_of_returns: if high { 5 } else { 1 },
                ..Default::default()
            })
            .unwrap();
        }
    }
    w.close().unwrap();
    if high_returns {
        // The `las` crate writes no return above 5 before LAS 1.4: set the bits (point format
        // 0, byte 14: return number in bits 0–2, number of returns in bits 3–5) as other
        // writers do (lidR_Topography.laz holds a return 6).
        let mut bytes = std::fs::read(path).unwrap();
        let start = u32::from_le_bytes(bytes[96..100].try_into().unwrap()) as usize;
        let len = usize::from(u16::from_le_bytes(bytes[105..107].try_into().unwrap()));
        for k in (start..bytes.len()).step_by(len) {
            if bytes[k + 14] & 7 == 5 {
                bytes[k + 14] = (7 << 3) | (6 + (k / len) as u8 % 2);
            }
        }
        std::fs::write(path, bytes).unwrap();
    }
}

/// `sweeptin ARGS`: its exit status and standard error.
fn status(args: &[&str]) -> (i32, String) {
    let o = plans::bin().args(args).output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn plan_ground_refuses_outputs_that_are_inputs_or_not_files_and_a_single_file_of_unlike_scales() {
    let t = tempfile::tempdir().unwrap();
    let (a, b) = (t.path().join("a.las"), t.path().join("b.las"));
    sloping_las(&a, 0.0, 0.01);
    sloping_las(&b, 20.0, 0.001);
    let before = std::fs::read(&a).unwrap();
    // The plan's directory named as an input file.
    let (code, err) = status(&["plan", "ground", s(&a), "--tile", "10", "-o", s(&a)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a directory"), "{err}");
    let job = t.path().join("job");
    let plan = ground_plan(&[a.clone(), b.clone()], &["--step", "5"], "10", &job);
    // The merge into an input, a directory, a FIFO.
    let (code, err) = status(&["merge", s(&plan), "-o", s(&a)]);
    assert_eq!(code, 2, "{err}");
    let dir = t.path().join("d.laz");
    std::fs::create_dir(&dir).unwrap();
    let fifo = t.path().join("f.laz");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    for o in [&dir, &fifo] {
        let (code, err) = status(&["merge", s(&plan), "-o", s(o)]);
        assert_eq!(code, 4, "{}: {err}", o.display());
        assert!(
            err.contains("a directory") || err.contains("regular file"),
            "{err}"
        );
    }
    assert!(std::fs::read(&a).unwrap() == before, "an input changed");
    // Unlike scales make no one file: refused (naming the VPC), and no file left.
    let one = t.path().join("one.laz");
    let (code, err) = status(&["merge", s(&plan), "-o", s(&one)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("OUT.vpc") && err.contains("scale"), "{err}");
    assert!(!one.exists());
    let vpc = t.path().join("all.vpc");
    sweeptin(
        &["merge", s(&plan), "-o", s(&vpc), "-q"],
        "merge into a VPC",
    );
    let want = points(&ground_run(
        &[a.clone(), b.clone()],
        &["--step", "5"],
        &t.path().join("one"),
    ));
    assert!(want.iter().any(|p| p.1[3] == 2) && want.iter().any(|p| p.1[3] != 2));
    assert!(points(&vpc_files(&vpc)) == want);
}

/// Points of return 6 and 7 in LAS 1.2 files: every tile and the merged file count them (the
/// legacy count was written 0 when a tile held one, and the merge left those tiles' points
/// out with exit 0); a tile whose header miscounts its task's points is refused by the merge
/// (exit 3, naming the task); files of unlike LAS versions are not joined into one file
/// (exit 2). (About 2 s in a debug build.)
#[test]
fn ground_tiles_and_merges_count_returns_six_and_seven_and_refuse_what_they_cannot_join() {
    let t = tempfile::tempdir().unwrap();
    let (a, b) = (t.path().join("a.las"), t.path().join("b.las"));
    sloping_las_as(&a, 0.0, 0.01, (1, 2), true);
    sloping_las_as(&b, 20.0, 0.01, (1, 2), true);
    let files = [a.clone(), b.clone()];
    let want = points(&ground_run(&files, &["--step", "5"], &t.path().join("one")));
    assert_eq!(want.len(), 3200);
    assert!(want.iter().any(|p| p.1[0] == 7) && want.iter().any(|p| p.1[3] == 2));
    let job = t.path().join("job");
    let plan = ground_plan(&files, &["--step", "5"], "10", &job);
    let m = t.path().join("m.laz");
    sweeptin(&["merge", s(&plan), "-o", s(&m), "-q"], "merge");
    assert!(
        points(std::slice::from_ref(&m)) == want,
        "the merge lost points"
    );
    let vpc = t.path().join("m.vpc");
    sweeptin(
        &["merge", s(&plan), "-o", s(&vpc), "-q"],
        "merge into a VPC",
    );
    assert!(
        points(&vpc_files(&vpc)) == want,
        "the tiles miscount their points"
    );
    // A tile's header saying 0 points (as the miscounting build wrote them).
    let tile = vpc_files(&vpc).into_iter().next().unwrap();
    let mut bytes = std::fs::read(&tile).unwrap();
    bytes[107..111].copy_from_slice(&0u32.to_le_bytes());
    std::fs::write(&tile, &bytes).unwrap();
    let (code, err) = status(&["merge", s(&plan), "-o", s(&t.path().join("n.laz"))]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("run it again") && err.contains("in their headers"),
        "{err}"
    );
    // LAS 1.2 and 1.4 files: one file cannot hold both unchanged.
    let c = t.path().join("c.las");
    sloping_las_as(&c, 20.0, 0.01, (1, 4), false);
    let plan2 = ground_plan(
        &[a.clone(), c],
        &["--step", "5"],
        "10",
        &t.path().join("job2"),
    );
    let (code, err) = status(&["merge", s(&plan2), "-o", s(&t.path().join("v.laz"))]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("LAS 1.4 (not 1.2)") && err.contains("OUT.vpc"),
        "{err}"
    );
}

/// A ground block too large for the plan's `--mem` is refused when the plan is made (exit 2,
/// naming the block, its points and what to change), for `plan ground` and `plan dem --ground`
/// alike, and no `plan.json` is written: it was written, and every task failed when it ran.
/// With a larger `--mem` the same plan is made. (Under a second in a debug build.)
#[test]
fn a_plan_refuses_a_ground_block_too_large_for_mem() {
    let t = tempfile::tempdir().unwrap();
    let input = data::shared("lidar/ahn3_delft_cropped_2.laz");
    let job = t.path().join("job");
    for product in [&["ground"][..], &["dem", "--ground", "--cell", "1"][..]] {
        let mut args = vec!["plan"];
        args.extend(product);
        args.extend([s(&input), "--tile", "100", "-o", s(&job), "-q", "--mem"]);
        let (code, err) = status(&[args.as_slice(), &["8M"]].concat());
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("ground block x 84960 .. 85120, y 447360 .. 447520")
                && err.contains("155005 points")
                && err.contains("--mem")
                && err.contains("--step"),
            "{err}"
        );
        assert!(!job.join("plan.json").exists(), "{product:?}");
    }
    let (code, err) = status(&[
        "plan",
        "ground",
        s(&input),
        "--tile",
        "100",
        "-o",
        s(&job),
        "-q",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(job.join("plan.json").exists());
}
