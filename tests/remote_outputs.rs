//! Outputs to `s3://` against moto's S3 server (tests/support/remote.rs): an output larger
//! than four parts goes up in a multipart upload and the object is the local bytes; a refused
//! upload is aborted, leaving neither an object nor stored parts; a missing bucket is refused
//! before any input is read. (The single-`PUT` outputs and their refusals: tests/remote.rs.)

use crate::data;
use crate::remote_server as remote;

use remote::{Fault, FaultServer, Moto};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use crate::remote_server::{stderr, sweeptin};

fn laz() -> PathBuf {
    data::shared("lidar/lidR_Topography.laz")
}

/// The part size the tests upload in (`SWEEPTIN_S3_PART_SIZE`): a DEM of lidR_Topography at
/// 1 m (a GeoTIFF of 330 kB) goes up in ten parts.
const PART: &str = "32768";

/// `moto`'s environment for a run, with the tests' part size and `TMPDIR`.
fn env(moto: &Moto, tmp: &Path) -> Vec<(&'static str, String)> {
    let mut env: Vec<(&str, String)> = moto.env().into_iter().collect();
    env.push(("SWEEPTIN_S3_PART_SIZE", PART.to_string()));
    env.push(("TMPDIR", tmp.to_str().unwrap().to_string()));
    env
}

fn dem(input: &str, out: &str, env: &[(&str, String)]) -> Output {
    sweeptin(&["dem", input, "--cell", "1", "-q", "-o", out], env)
}

fn no_temporary_file(tmp: &Path) {
    let left: Vec<_> = std::fs::read_dir(tmp).unwrap().flatten().collect();
    assert!(left.is_empty(), "temporary files were left: {left:?}");
}

#[test]
fn large_output_to_s3_is_uploaded_in_parts_and_equals_the_local_bytes() {
    // moto refuses parts under 5 MiB (but the last), as S3 does; the test's parts are smaller.
    let Some(moto) = Moto::start_with(
        "large_output_to_s3_is_uploaded_in_parts_and_equals_the_local_bytes",
        &[("S3_UPLOAD_PART_MIN_SIZE", "1024")],
    ) else {
        return;
    };
    moto.make_bucket("out");
    let tmp = tempfile::tempdir().unwrap();
    let env = env(&moto, tmp.path());
    let local = tmp.path().join("l.tif");
    let o = dem(laz().to_str().unwrap(), local.to_str().unwrap(), &env);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&local).unwrap();
    std::fs::remove_file(&local).unwrap();
    let parts = bytes.len().div_ceil(PART.parse().unwrap());
    assert!(
        parts > 4,
        "{} bytes: too few for a multipart upload",
        bytes.len()
    );

    let o = dem(laz().to_str().unwrap(), "s3://out/dem/topo.tif", &env);
    assert!(o.status.success(), "{}", stderr(&o));
    let etag = moto.etag("out", "dem/topo.tif").expect("no object written");
    assert!(
        etag.trim_matches('"').ends_with(&format!("-{parts}")),
        "ETag {etag}: not an upload of {parts} parts"
    );
    let got = tmp.path().join("got.tif");
    assert!(moto.get("out", "dem/topo.tif", &got));
    assert!(
        std::fs::read(&got).unwrap() == bytes,
        "the object differs from the local output"
    );
    std::fs::remove_file(&got).unwrap();
    assert_eq!(moto.pending_uploads("out"), 0);
    no_temporary_file(tmp.path());
}

/// A part the server refuses (moto, as S3, refuses to complete an upload of parts under its
/// minimum): exit 4 naming the URL, the upload aborted (no part stays stored), no object, no
/// temporary file.
#[test]
fn refused_multipart_upload_is_aborted_and_leaves_nothing() {
    let Some(moto) = Moto::start("refused_multipart_upload_is_aborted_and_leaves_nothing") else {
        return;
    };
    moto.make_bucket("out");
    let tmp = tempfile::tempdir().unwrap();
    let env = env(&moto, tmp.path());
    let o = dem(laz().to_str().unwrap(), "s3://out/topo.tif", &env);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("s3://out/topo.tif"), "{e}");
    assert!(e.contains("EntityTooSmall"), "{e}");
    assert_eq!(moto.etag("out", "topo.tif"), None, "an object was written");
    assert_eq!(moto.pending_uploads("out"), 0, "the upload was not aborted");
    no_temporary_file(tmp.path());
}

/// `-o s3://nobucket/…`: refused at once, exit 4 naming the URL, before the input is opened
/// (the input's server gets no request) and before any temporary file.
#[test]
fn missing_output_bucket_is_refused_before_any_input_is_read() {
    let Some(moto) = Moto::start("missing_output_bucket_is_refused_before_any_input_is_read")
    else {
        return;
    };
    moto.make_bucket("out");
    let input = FaultServer::start(remote::bytes(&laz()), Fault::None);
    let tmp = tempfile::tempdir().unwrap();
    let env = env(&moto, tmp.path());
    let start = Instant::now();
    let o = sweeptin(
        &[
            "dem",
            &input.url("topo.laz"),
            "--cell",
            "1",
            "--contours",
            "s3://nobucket/c.geojson",
            "-q",
            "-o",
            "s3://out/topo.tif",
        ],
        &env,
    );
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("s3://nobucket/c.geojson"), "{e}");
    assert!(e.contains("no such bucket"), "{e}");
    assert_eq!(
        input.requests.load(std::sync::atomic::Ordering::SeqCst),
        0,
        "the input was read before the output's bucket was checked"
    );
    assert!(start.elapsed() < Duration::from_secs(20));
    assert_eq!(moto.etag("out", "topo.tif"), None);
    no_temporary_file(tmp.path());
}

/// Ctrl-C while a multipart upload is under way (its second part unanswered): the process
/// aborts the upload (a `DELETE …?uploadId=…`, so that no part stays stored) and deletes its
/// temporary file, exit 130. (The parts stayed stored, billed, until a lifecycle rule.)
#[test]
fn interrupted_multipart_upload_is_aborted() {
    let s3 = remote::FakeS3::start(2);
    let tmp = tempfile::tempdir().unwrap();
    let env = [
        ("AWS_ENDPOINT_URL", s3.endpoint()),
        ("AWS_ACCESS_KEY_ID", remote::KEY.to_string()),
        ("AWS_SECRET_ACCESS_KEY", remote::SECRET.to_string()),
        ("AWS_REGION", "us-east-1".to_string()),
        ("SWEEPTIN_S3_PART_SIZE", PART.to_string()),
        ("TMPDIR", tmp.path().to_str().unwrap().to_string()),
    ];
    let mut child = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["dem", laz().to_str().unwrap(), "--cell", "1", "-q"])
        .args(["-o", "s3://out/topo.tif"])
        .envs(env.iter().map(|(k, v)| (*k, v.as_str())))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !s3.requests().iter().any(|r| r.contains("partNumber=2")) {
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!(
                "the upload did not reach its second part: {:?}",
                s3.requests()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .arg("-INT")
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let aborts: Vec<String> = s3
        .requests()
        .into_iter()
        .filter(|r| r.starts_with("DELETE") && r.contains("uploadId=up1"))
        .collect();
    assert_eq!(aborts.len(), 1, "{:?}", s3.requests());
    assert!(
        stderr(&o).contains("aborted 1 upload(s) to S3"),
        "{}",
        stderr(&o)
    );
    no_temporary_file(tmp.path());
}
