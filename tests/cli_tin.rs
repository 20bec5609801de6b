//! `sweeptin tin` on bad input: a clear message naming the file, exit code 3 (bad input data; 2
//! for a bad option), no output file and no temporary file left behind.

use crate::cli;
use std::path::Path;
use std::process::Command;

fn run_tin(input: &Path, out_dir: &Path) -> (i32, String) {
    let out = out_dir.join("out.ply");
    let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["tin", "--quiet"])
        .arg(input)
        .arg("-o")
        .arg(&out)
        .arg("--tmp-dir")
        .arg(out_dir)
        .output()
        .unwrap();
    let left: Vec<_> = std::fs::read_dir(out_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn bad_inputs_fail_cleanly() {
    let inputs = tempfile::tempdir().unwrap();
    let sample = std::fs::read("data/sample/startinpy_small.laz").unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty.laz", vec![], "empty.laz"),
        ("text.laz", b"x y z\n1 2 3\n".to_vec(), "text.laz"),
        (
            "truncated.laz",
            sample[..sample.len() / 2].to_vec(),
            "truncated.laz",
        ),
        ("header_only.las", sample[..200].to_vec(), "header_only.las"),
        (
            "bad.xyz",
            b"1 2 3\n4 5 6\n7 eight 9\n".to_vec(),
            "bad.xyz:3",
        ),
        (
            "collinear.xyz",
            b"0 0 0\n1 1 0\n2 2 0\n3 3 0\n".to_vec(),
            "collinear",
        ),
        ("two.xyz", b"0 0 0\n1 1 0\n1 1 5\n".to_vec(), "fewer than 3"),
        ("empty.xyz", b"".to_vec(), "hold no point"),
        ("nan.xyz", b"0 0 0\n1 nan 0\n2 1 0\n".to_vec(), "nan.xyz:2"),
    ];
    for (name, bytes, expect) in cases {
        let path = inputs.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = tempfile::tempdir().unwrap();
        let (code, err) = run_tin(&path, out.path());
        assert_eq!(code, 3, "{name}: {err}");
        assert!(
            err.contains(expect),
            "{name}: message should mention {expect:?}: {err}"
        );
    }
    let out = tempfile::tempdir().unwrap();
    let (code, err) = run_tin(&inputs.path().join("missing.laz"), out.path());
    assert_eq!(code, 3);
    assert!(err.contains("missing.laz"), "{err}");
}

#[test]
fn bad_breaklines_fail_cleanly() {
    let inputs = tempfile::tempdir().unwrap();
    let sample = Path::new("data/sample/startinpy_small.laz");
    let cases: Vec<(&str, &[u8], &str)> = vec![
        (
            "broken.geojson",
            b"{\"type\": \"FeatureCollection\", \"features\": [",
            "broken.geojson",
        ),
        (
            "point.geojson",
            b"{\"type\": \"Point\", \"coordinates\": [1, 2]}",
            "point.geojson",
        ),
        ("bad.txt", b"1 2 3\n4 five 6\n", "bad.txt:2"),
    ];
    for (name, bytes, expect) in cases {
        let path = inputs.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = tempfile::tempdir().unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
            .args(["tin", "--quiet"])
            .arg(sample)
            .arg("--breaklines")
            .arg(&path)
            .arg("-o")
            .arg(out.path().join("out.ply"))
            .arg("--tmp-dir")
            .arg(out.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{name}: {err}");
        assert!(err.contains(expect), "{name}: {err}");
        assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0, "{name}");
    }
}

/// Every command's options parse (clap checks for clashing names only when a command is built).
#[test]
fn every_command_has_consistent_options() {
    for c in [
        "tin",
        "info",
        "check",
        "dem",
        "contours",
        "volume",
        "sample",
        "profile",
        "hillshade",
        "products",
        "simplify",
        "crossval",
    ] {
        cli::ok(&[c, "--help"]);
    }
}

/// `--max-edge 0` is an option error naming the flag, not "breakline 18446744073709551615"
/// (`Trim::new` used to report it as a bad line with index `u64::MAX`).
#[test]
fn bad_max_edge_names_the_option() {
    let sample = Path::new("data/sample/startinpy_small.laz");
    for value in ["0", "inf"] {
        let out = tempfile::tempdir().unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
            .args(["tin", "--quiet"])
            .arg(sample)
            .args(["--max-edge", value, "-o"])
            .arg(out.path().join("x.ply"))
            .arg("--tmp-dir")
            .arg(out.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "--max-edge {value}: {err}");
        assert!(err.contains("--max-edge"), "--max-edge {value}: {err}");
        assert!(!err.contains("18446744073709551615"), "{err}");
        assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0);
    }
}
