//! Plans over remote inputs (issue 44, item 3): a plan names each remote file by its URL and
//! pins its version (ETag and size); every task reads its part over HTTP; the mosaic is the
//! local plan's byte for byte; an object replaced after the plan stops the task that reads it.

use crate::data;
use crate::plans;
use crate::remote_server as remote;

use plans::{bin, plan_and_run, s, sweeptin};
use remote::{Moto, Nginx};
use std::path::{Path, PathBuf};

/// The six IGN tiles (tests/data/lidar/ign_50m_tiles).
fn ign_tiles() -> Vec<PathBuf> {
    let mut v = Vec::new();
    for x in [77050, 77055, 77060] {
        for y in [627755, 627760] {
            v.push(data::shared(&format!(
                "lidar/ign_50m_tiles/test_data_{x}_{y}_LA93_IGN69.laz"
            )));
        }
    }
    v
}

/// The job of the tests: the ground DEM of `vpc` in tiles of 25 m.
fn job(vpc: &str) -> [&str; 8] {
    ["dem", vpc, "--cell", "1", "--class", "2", "--tile", "25"]
}

/// `plan` the job into `dir`, `run --all`, `merge -o OUT`: the mosaic's bytes.
fn plan_run_merge(vpc: &str, dir: &Path, out: &Path) -> Vec<u8> {
    let (plan, _) = plan_and_run(&job(vpc), dir);
    sweeptin(&["merge", s(&plan), "-o", s(out), "-q"], vpc);
    std::fs::read(out).unwrap()
}

#[test]
fn plan_over_a_remote_vpc_equals_the_local_plan() {
    let tiles = ign_tiles();
    let refs: Vec<&Path> = tiles.iter().map(PathBuf::as_path).collect();
    let (served, names) = remote::served(&refs);
    let vpc = served.path().join("ign.vpc");
    let mut args = vec!["index"];
    args.extend(names.iter().map(|n| n.as_str()));
    args.extend(["-o", "ign.vpc"]);
    let o = bin()
        .args(&args)
        .current_dir(served.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let Some(nginx) = Nginx::start(
        served.path(),
        "plan_over_a_remote_vpc_equals_the_local_plan",
    ) else {
        return;
    };
    let t = tempfile::tempdir().unwrap();
    let local = plan_run_merge(s(&vpc), &t.path().join("local"), &t.path().join("l.tif"));
    let url = nginx.url("ign.vpc");
    let far_job = t.path().join("far");
    let far = plan_run_merge(&url, &far_job, &t.path().join("r.tif"));
    assert!(
        local == far,
        "the remote plan's mosaic differs from the local plan's"
    );
    // The plan names the URLs (not local paths) and pins each object's ETag.
    let plan = std::fs::read_to_string(far_job.join("plan.json")).unwrap();
    let p: serde_json::Value = serde_json::from_str(&plan).unwrap();
    let files = p["files"].as_array().unwrap();
    assert_eq!(files.len(), 6);
    for f in files {
        let path = f["path"].as_str().unwrap();
        assert!(path.starts_with("http://127.0.0.1:"), "{f}");
        assert!(f["version"].as_str().unwrap().starts_with("ETag "), "{f}");
    }
    // Every request was a range (the plan read headers and chunk tables; tasks their chunks).
    let (bytes, requests) = nginx.sent();
    assert!(requests > 6 && bytes > 0);

    // The mosaic merged straight to S3 is the same file; a VRT (it names the local tiles) is
    // refused there. (A plan's directory on S3: tests/remote_plan_dir.rs.)
    if let Some(moto) = Moto::start("plan_over_a_remote_vpc_equals_the_local_plan") {
        moto.put("out", "placeholder.laz", &tiles[0]);
        let merge_to = |out: &str| {
            bin()
                .args(["merge", s(&far_job.join("plan.json")), "-o", out, "-q"])
                .envs(moto.env())
                .output()
                .unwrap()
        };
        let o = merge_to("s3://out/mosaic.tif");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let got = t.path().join("got.tif");
        assert!(moto.get("out", "mosaic.tif", &got));
        assert!(
            std::fs::read(&got).unwrap() == local,
            "the mosaic on S3 differs"
        );
        let o = merge_to("s3://out/m.vrt");
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }

    // A tile replaced on the server after a new plan (same bytes, a new time: nginx's ETag
    // changes): the tasks reading it stop with exit 3 naming its URL; no mosaic is made of
    // two versions.
    let job2 = t.path().join("again");
    let mut again = vec!["plan"];
    again.extend(job(&url));
    again.extend(["-o", s(&job2)]);
    sweeptin(&again, "second plan");
    let first = served.path().join(&names[0]);
    let f = std::fs::File::options().write(true).open(&first).unwrap();
    let later = std::time::SystemTime::now() + std::time::Duration::from_secs(100);
    f.set_modified(later).unwrap();
    drop(f);
    let o = bin()
        .args(["run", s(&job2.join("plan.json")), "--all", "-q"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{e}");
    assert!(
        e.contains(&nginx.url(&names[0])) && e.contains("changed since the plan was made"),
        "{e}"
    );
    let m = bin()
        .args([
            "merge",
            s(&job2.join("plan.json")),
            "-o",
            s(&t.path().join("m.tif")),
            "-q",
        ])
        .output()
        .unwrap();
    assert!(!m.status.success());
    assert!(!t.path().join("m.tif").exists());
}

/// A VPC names remote files by their full URL, wherever it is written (issue 43): `index` of an
/// object into a local `.vpc` and into one on S3 under another prefix, and a ground plan on S3
/// merged into a local `.vpc` of its tiles (refused before: its items named local paths), each
/// read back whole. Against moto; about 6 s in a debug build.
#[test]
fn a_vpc_names_remote_files_by_their_urls() {
    let Some(moto) = Moto::start("a_vpc_names_remote_files_by_their_urls") else {
        return;
    };
    let t = tempfile::tempdir().unwrap();
    let small = data::shared("lidar/startinpy_small.laz");
    moto.put("vpcs", "t/a.laz", &small);
    let run = |args: &[&str]| {
        let o = bin()
            .args(args)
            .envs(moto.env())
            .current_dir(t.path())
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let points = |vpc: &str| -> u64 {
        let v: serde_json::Value = serde_json::from_str(&run(&["info", vpc, "--json"])).unwrap();
        v["summary"]["points"].as_u64().unwrap()
    };
    let hrefs = |text: &str| -> Vec<String> {
        let v: serde_json::Value = serde_json::from_str(text).unwrap();
        v["features"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["assets"]["data"]["href"].as_str().unwrap().to_string())
            .collect()
    };
    run(&["index", "s3://vpcs/t/a.laz", "-o", "local.vpc"]);
    let local = std::fs::read_to_string(t.path().join("local.vpc")).unwrap();
    assert_eq!(hrefs(&local), ["s3://vpcs/t/a.laz"]);
    assert_eq!(points("local.vpc"), 39_233);
    run(&["index", "s3://vpcs/t/a.laz", "-o", "s3://vpcs/u/far.vpc"]);
    let got = t.path().join("far.vpc");
    assert!(moto.get("vpcs", "u/far.vpc", &got));
    assert_eq!(
        hrefs(&std::fs::read_to_string(&got).unwrap()),
        ["s3://vpcs/t/a.laz"]
    );
    assert_eq!(points("s3://vpcs/u/far.vpc"), 39_233);
    // A ground plan on S3 (4 tasks) merged into a local VPC of its tiles.
    run(&[
        "plan",
        "ground",
        s(&small),
        "--tile",
        "50",
        "-o",
        "s3://vpcs/job/",
        "-q",
    ]);
    run(&["run", "s3://vpcs/job/plan.json", "--all", "-q"]);
    run(&["merge", "s3://vpcs/job/plan.json", "-o", "ground.vpc", "-q"]);
    let tiles = hrefs(&std::fs::read_to_string(t.path().join("ground.vpc")).unwrap());
    assert!(!tiles.is_empty());
    assert!(
        tiles.iter().all(|h| h.starts_with("s3://vpcs/job/tiles/")),
        "{tiles:?}"
    );
    assert_eq!(points("ground.vpc"), 39_233);
}
