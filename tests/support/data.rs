//! Where the real test data and the interop tools are, for every integration test.
//!
//! A test that needs something that is missing must not pass silently: under `CI=true` a missing
//! data folder or tool fails the test; locally the test prints why it is skipped and returns.

#![allow(dead_code)]

use std::path::PathBuf;

/// Is this a CI run (`CI=true`)?
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// The folder with the real data (`lidar/`, `dem/`, `lines/`): `$SWEEPTIN_DATA`, or
/// `../shared/data` beside the repository.
///
/// # Panics
/// When it cannot be found (the data is part of every test run).
pub fn data_dir() -> PathBuf {
    [
        std::env::var_os("SWEEPTIN_DATA").map(PathBuf::from),
        Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data")),
        Some(PathBuf::from("/work/shared/data")),
    ]
    .into_iter()
    .flatten()
    .find(|d| d.join("lidar").is_dir())
    .expect("real test data not found: set SWEEPTIN_DATA to the folder holding lidar/")
}

/// A file of the real data, by its path under the data folder.
///
/// # Panics
/// When it does not exist.
pub fn shared(rel: &str) -> PathBuf {
    let p = data_dir().join(rel);
    assert!(p.exists(), "test data file missing: {}", p.display());
    p
}

/// Is the command-line tool `name` on the PATH? When it is not: panics under CI, prints a skip
/// message and returns `false` locally.
pub fn tool(name: &str, test: &str) -> bool {
    let found = std::process::Command::new("sh")
        .args(["-c", &format!("command -v {name}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            !in_ci(),
            "{test}: `{name}` is required under CI=true but not installed"
        );
        eprintln!("{test}: skipped, `{name}` is not installed");
    }
    found
}

/// A file of the real data that a test may do without locally: `Some(path)` when it exists;
/// when it does not, panics under CI and prints why the test is skipped otherwise.
pub fn optional(rel: &str, test: &str) -> Option<PathBuf> {
    let base = [
        std::env::var_os("SWEEPTIN_DATA").map(PathBuf::from),
        Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data")),
        Some(PathBuf::from("/work/shared/data")),
    ]
    .into_iter()
    .flatten()
    .find(|d| d.join(rel).exists());
    match base {
        Some(d) => Some(d.join(rel)),
        None => {
            assert!(
                !in_ci(),
                "{test}: test data {rel} is required under CI=true but missing"
            );
            eprintln!("{test}: skipped, test data {rel} not found (set SWEEPTIN_DATA)");
            None
        }
    }
}

/// Can `python3` import every module in `modules`? When it cannot: panics under CI, prints a skip
/// message and returns `false` locally (scripts/test.sh installs what the tests import).
pub fn python(modules: &[&str], test: &str) -> bool {
    let code = format!("import {}", modules.join(", "));
    let found = std::process::Command::new("python3")
        .args(["-c", &code])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            !in_ci(),
            "{test}: python3 with {modules:?} is required under CI=true but missing"
        );
        eprintln!("{test}: skipped, python3 cannot import {modules:?}");
    }
    found
}

/// The six IGN 50 m LAZ tiles (`lidar/ign_50m_tiles`), sorted by name.
pub fn ign_tiles() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(shared("lidar/ign_50m_tiles"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "laz"))
        .collect();
    v.sort();
    assert_eq!(v.len(), 6);
    v
}
