//! `sweeptin info` end to end, on the real data in `tests/data/lidar` (docs/DATA.md).

use crate::data;
use data::data_dir;

use std::path::PathBuf;
use std::process::{Command, Output};

fn lidar(name: &str) -> PathBuf {
    data_dir().join("lidar").join(name)
}

fn sweeptin(args: &[&str], files: &[PathBuf]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .arg("info")
        .args(args)
        .args(files)
        .output()
        .unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn text_report() {
    let o = sweeptin(
        &[],
        &[lidar("startinpy_small.laz"), lidar("lidR_Topography.laz")],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    for want in [
        "LAZ, LAS 1.4, point format 8",
        "39233 (legacy field 39233, LAS 1.4 field 39233)",
        "x 85699.665 .. 85740.506",
        "offset: 84980 446230 0",
        "EPSG:7415",
        "LAS 1.2, point format 1",
        "x 273357.14475 .. 273642.85650",
        "EPSG:2949 (GeoTIFF keys)",
    ] {
        assert!(out.contains(want), "missing {want:?} in:\n{out}");
    }
    assert!(!out.contains("classes:"));
}

#[test]
fn json_with_classes_and_filters() {
    let o = sweeptin(&["--json", "--classes"], &[lidar("lidR_Topography.laz")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let f = &v["files"][0];
    assert_eq!(f["point_count"], 73_403);
    assert_eq!(f["version"], serde_json::json!([1, 2]));
    // The CRS once, no float noise in the bounds (at the file's 0.00025 precision).
    assert_eq!(f["crs"]["epsg"], 2949);
    assert!(f.get("crs_definition").is_none());
    assert_eq!(f["bounds"]["min"][0], 273357.14475);
    assert_eq!(
        f["stats"]["classes"],
        serde_json::json!({"1": 61_347, "2": 8_159, "9": 3_897})
    );
    assert_eq!(v["summary"]["points"], 73_403);
    let o = sweeptin(
        &["--json", "--classes", "--class", "2", "--keep-withheld"],
        &[lidar("startinpy_small.laz")],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let f = &v["files"][0];
    assert_eq!(f["stats"]["classes"], serde_json::json!({"2": 18_392}));
    assert_eq!(f["stats"]["filter"]["kept"], 18_392);
    assert_eq!(f["stats"]["filter"]["class"], 39_233 - 18_392);
    assert_eq!(f["crs"]["epsg"], 7415);
}

#[test]
fn a_bad_file_is_reported_and_the_others_still_shown() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("notes.laz");
    std::fs::write(&bad, "just text\n").unwrap();
    let o = sweeptin(&[], &[bad.clone(), lidar("startinpy_small.laz")]);
    assert_eq!(o.status.code(), Some(3), "bad input data");
    assert!(stdout(&o).contains("point format 8"));
    let err = stderr(&o);
    assert!(
        err.contains("notes.laz") && err.contains("not a LAS/LAZ file"),
        "{err}"
    );
    assert!(err.contains("1 of 2 files"), "{err}");
    let o = sweeptin(&["--json"], &[bad]);
    assert_eq!(o.status.code(), Some(3));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["summary"]["failed"], 1);
    assert!(
        v["files"][0]["error"]
            .as_str()
            .unwrap()
            .contains("not a LAS/LAZ file")
    );
}

#[test]
fn bad_flags_are_usage_errors() {
    let file = [lidar("startinpy_small.laz")];
    for args in [
        &["--bbox", "1,2,3"][..],
        &["--class", "2,300"],
        &["--returns", "second"],
        &["--drop-withheld", "false", "--keep-withheld"],
    ] {
        let o = sweeptin(args, &file);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(!stderr(&o).is_empty());
    }
    let o = sweeptin(&["--classes", "--bbox", "-1e9,-1e9,1e9,1e9"], &file);
    assert!(o.status.success(), "{}", stderr(&o));
}
