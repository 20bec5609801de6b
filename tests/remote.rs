//! Remote inputs (`http://`, `https://`, `s3://`) against real servers the tests start: nginx,
//! moto's S3 server, and a tiny server of chosen faults (tests/support/remote.rs). A DEM made
//! from a URL is byte-identical to the local file's; every fault ends in a complete output or in
//! an error naming the URL, exit 3, and no output.

use crate::data;
use crate::remote_server as remote;

use remote::{Fault, FaultServer, Moto, Nginx};
use std::path::{Path, PathBuf};
use std::process::Output;

use crate::remote_server::{stderr, sweeptin};

/// `sweeptin dem INPUT --cell 1 EXTRA… -o OUT` must succeed; the DEM's bytes.
fn dem(input: &str, out: &Path, extra: &[&str], env: &[(&str, &str)]) -> (Vec<u8>, String) {
    let mut args = vec!["dem", input, "--cell", "1", "-q", "-o"];
    let out_s = out.to_str().unwrap();
    args.push(out_s);
    args.extend_from_slice(extra);
    let o = sweeptin(&args, env);
    assert!(o.status.success(), "sweeptin {args:?}: {}", stderr(&o));
    (std::fs::read(out).unwrap(), stderr(&o))
}

fn laz() -> PathBuf {
    data::shared("lidar/lidR_Topography.laz")
}

fn copc() -> PathBuf {
    data::shared("lidR_Topography.copc.laz")
}

/// The box of `copc_box_agrees_with_laspy` (tests/inputs.rs), a corner of the file.
const BOX: &str = "273400,5274400,273450,5274450";

#[test]
fn dem_of_laz_over_nginx_equals_local() {
    let (dir, names) = remote::served(&[&laz()]);
    let Some(nginx) = Nginx::start(dir.path(), "dem_of_laz_over_nginx_equals_local") else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let (local, _) = dem(laz().to_str().unwrap(), &out.path().join("l.tif"), &[], &[]);
    let (far, _) = dem(&nginx.url(&names[0]), &out.path().join("r.tif"), &[], &[]);
    assert!(
        local == far,
        "the DEM of the URL differs from the local file's"
    );
}

#[test]
fn dem_of_copc_box_over_nginx_equals_local_and_reads_a_part() {
    let (dir, names) = remote::served(&[&copc()]);
    let test = "dem_of_copc_box_over_nginx_equals_local_and_reads_a_part";
    let Some(nginx) = Nginx::start(dir.path(), test) else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let b = ["--bbox", BOX];
    let (local, _) = dem(copc().to_str().unwrap(), &out.path().join("l.tif"), &b, &[]);
    let (far, _) = dem(&nginx.url(&names[0]), &out.path().join("r.tif"), &b, &[]);
    assert!(
        local == far,
        "the DEM of the URL differs from the local file's"
    );
    // The three octree nodes that meet the box hold 351,938 of the file's 590,087 bytes (the
    // root alone 277,031; copclib's `GetNodesIntersectBox`): with the header, the chunk table
    // and the hierarchy, at most 1.2 times that may cross the wire.
    let (sent, requests) = nginx.sent();
    assert!(
        sent <= 351_938 * 12 / 10,
        "a box read of a COPC file fetched {sent} bytes in {requests} requests"
    );
}

#[test]
fn dem_of_laz_over_s3_equals_local() {
    let Some(moto) = Moto::start("dem_of_laz_over_s3_equals_local") else {
        return;
    };
    moto.put("lidar", "tiles/topo.laz", &laz());
    let env = [
        ("AWS_ENDPOINT_URL", moto.endpoint.as_str()),
        ("AWS_ACCESS_KEY_ID", remote::KEY),
        ("AWS_SECRET_ACCESS_KEY", remote::SECRET),
        ("AWS_REGION", "us-east-1"),
    ];
    let out = tempfile::tempdir().unwrap();
    let (local, _) = dem(laz().to_str().unwrap(), &out.path().join("l.tif"), &[], &[]);
    let (far, _) = dem(
        "s3://lidar/tiles/topo.laz",
        &out.path().join("r.tif"),
        &[],
        &env,
    );
    assert!(
        local == far,
        "the DEM of the S3 object differs from the local file's"
    );
    // A missing object: its URL, exit 3, no output.
    let missing = out.path().join("m.tif");
    let o = sweeptin(
        &[
            "dem",
            "s3://lidar/none.laz",
            "--cell",
            "1",
            "-q",
            "-o",
            missing.to_str().unwrap(),
        ],
        &env,
    );
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("s3://lidar/none.laz"), "{}", stderr(&o));
    assert!(!missing.exists());
}

/// Runs `dem` on the fault server's object; the local file's DEM, the output's path and the
/// command's output.
fn through(fault: Fault, input: &Path) -> (Vec<u8>, PathBuf, Output, tempfile::TempDir) {
    through_with(fault, input, &[])
}

/// [`through`] with more options for the remote run.
fn through_with(
    fault: Fault,
    input: &Path,
    extra: &[&str],
) -> (Vec<u8>, PathBuf, Output, tempfile::TempDir) {
    let server = FaultServer::start(remote::bytes(&input.to_path_buf()), fault);
    let out = tempfile::tempdir().unwrap();
    let (local, _) = dem(input.to_str().unwrap(), &out.path().join("l.tif"), &[], &[]);
    let far = out.path().join("r.tif");
    let url = server.url("x.laz");
    let mut args = vec![
        "dem",
        &url,
        "--cell",
        "1",
        "-q",
        "-o",
        far.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = sweeptin::<&str>(&args, &[]);
    (local, far, o, out)
}

#[test]
fn connection_dropped_mid_body_is_retried() {
    let (local, far, o, _dir) = through(Fault::DropMidBody(2), &laz());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("retrying"), "{}", stderr(&o));
    assert!(std::fs::read(far).unwrap() == local);
}

#[test]
fn service_unavailable_then_success() {
    let (local, far, o, _dir) = through(Fault::Unavailable(2), &laz());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("HTTP 503; retrying"), "{}", stderr(&o));
    assert!(std::fs::read(far).unwrap() == local);
}

/// A server that stops answering (before the head, or in the middle of a body) is given up on
/// after `--io-timeout` and asked again; the output is the local file's.
#[test]
fn silent_server_times_out_and_is_asked_again() {
    for fault in [Fault::SilentHead(2), Fault::SilentBody(2)] {
        let t = std::time::Instant::now();
        let (local, far, o, _dir) = through_with(fault, &laz(), &["--io-timeout", "1"]);
        assert!(o.status.success(), "{fault:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("retrying") && e.contains("imeout"),
            "{fault:?}: {e}"
        );
        assert!(std::fs::read(far).unwrap() == local, "{fault:?}");
        // Not the minute the server stays silent, nor the default timeout.
        assert!(t.elapsed().as_secs() < 50, "{fault:?}: {:?}", t.elapsed());
    }
}

/// The run gave up after its attempts: exit 3 naming the URL, no output.
fn gave_up(o: &Output, far: &Path) {
    assert_eq!(o.status.code(), Some(3), "{}", stderr(o));
    let e = stderr(o);
    assert!(
        e.contains("gave up after 5 attempts") && e.contains("/x.laz"),
        "{e}"
    );
    assert!(!far.exists());
}

/// A server silent every time: five attempts, then exit 3 naming the URL, no output.
#[test]
fn server_silent_every_time_gives_up_naming_the_url() {
    let (_, far, o, _dir) = through_with(
        Fault::SilentHead(usize::MAX),
        &laz(),
        &["--io-timeout", "1"],
    );
    gave_up(&o, &far);
}

#[test]
fn object_replaced_between_range_reads_is_an_error() {
    for if_match in [true, false] {
        let fault = Fault::Replace { after: 2, if_match };
        let (_, far, o, _dir) = through(fault, &laz());
        assert_eq!(o.status.code(), Some(3), "{fault:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("http://127.0.0.1:") && e.contains("changed while it was being read"),
            "{fault:?}: {e}"
        );
        assert!(!far.exists(), "{fault:?}: an output was left");
    }
}

#[test]
fn server_ignoring_range_is_read_whole_with_a_warning() {
    let (local, far, o, _dir) = through(Fault::IgnoreRange, &copc());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("ignores range requests"),
        "{}",
        stderr(&o)
    );
    assert!(std::fs::read(far).unwrap() == local);
}

#[test]
fn server_failing_every_time_gives_up_naming_the_url() {
    let (_, far, o, _dir) = through(Fault::Unavailable(usize::MAX), &laz());
    gave_up(&o, &far);
}

#[test]
fn wrong_content_range_is_an_error() {
    let (_, far, o, _dir) = through(Fault::WrongRange, &laz());
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("the server answered Content-Range"), "{e}");
    assert!(!far.exists());
}

/// `-o s3://bucket/key`: the output is written to a temporary file and uploaded when complete
/// (one PUT: the object appears whole or not at all), side files too; the object's bytes are the
/// local run's. A missing bucket: exit 4 naming the URL, no object, no temporary file left. An
/// HTTP URL as output is refused before any work.
#[test]
fn outputs_to_s3_are_the_local_bytes_and_appear_only_whole() {
    let Some(moto) = Moto::start("outputs_to_s3_are_the_local_bytes_and_appear_only_whole") else {
        return;
    };
    moto.put("out", "placeholder.laz", &laz());
    let tmp = tempfile::tempdir().unwrap();
    let env_owned = moto.env();
    let mut env: Vec<(&str, &str)> = env_owned.iter().map(|(k, v)| (*k, v.as_str())).collect();
    env.push(("TMPDIR", tmp.path().to_str().unwrap()));
    let out = tempfile::tempdir().unwrap();
    let local_dem = out.path().join("l.asc");
    let local_c = out.path().join("l.geojson");
    let run = |dem: &str, contours: &str| {
        sweeptin(
            &[
                "dem",
                laz().to_str().unwrap(),
                "--cell",
                "1",
                "--contours",
                contours,
                "--interval",
                "5",
                "-q",
                "-o",
                dem,
            ],
            &env,
        )
    };
    let o = run(local_dem.to_str().unwrap(), local_c.to_str().unwrap());
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run("s3://out/dem/topo.asc", "s3://out/dem/topo.geojson");
    assert!(o.status.success(), "{}", stderr(&o));
    for (key, local) in [
        ("dem/topo.asc", local_dem.clone()),
        ("dem/topo.prj", local_dem.with_extension("prj")),
        ("dem/topo.geojson", local_c.clone()),
    ] {
        let got = out.path().join("got");
        assert!(moto.get("out", key, &got), "s3://out/{key} was not written");
        assert!(
            std::fs::read(&got).unwrap() == std::fs::read(&local).unwrap(),
            "s3://out/{key} differs from the local output"
        );
    }
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "a temporary file was left"
    );
    // No such bucket: the URL, exit 4, nothing written, nothing left.
    let o = run("s3://nobucket/topo.asc", "s3://out/c2.geojson");
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("s3://nobucket/topo.asc"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "a temporary file was left"
    );
    // An HTTP URL is not an output; nor an S3 name that is not an object's.
    let o = run("http://127.0.0.1:9/topo.asc", local_c.to_str().unwrap());
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("outputs go to local files or s3://"),
        "{}",
        stderr(&o)
    );
    for bad in ["s3://out/dem/", "s3://out"] {
        let o = run(bad, local_c.to_str().unwrap());
        assert_eq!(o.status.code(), Some(4), "{bad}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("not an S3 object name"),
            "{bad}: {}",
            stderr(&o)
        );
    }
    // An output never replaces an input object, whatever the scheme's case.
    let o = sweeptin(
        &[
            "tin",
            "s3://out/placeholder.laz",
            "-q",
            "-o",
            "S3://out/placeholder.laz",
        ],
        &env,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("that is an input"), "{}", stderr(&o));
}
