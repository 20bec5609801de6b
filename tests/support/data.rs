//! Where the real test data and the interop tools are, for every integration test.
//!
//! The real data is committed in `tests/data` (docs/DATA.md: sources, licences, checksums), so a
//! fresh clone needs nothing beside it. A test that needs something that is missing must not pass
//! silently: under `CI=true` a missing file or tool fails the test; locally the test prints why
//! it is skipped and returns.

#![allow(dead_code)]

use std::path::PathBuf;

/// Is this a CI run (`CI=true`)?
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// The folder with the real test data (`lidar/`, `dem/`, `lines/`): `tests/data` in the
/// repository. Each file, where it comes from, its licence and checksum: docs/DATA.md.
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// A file of the real data, by its path under `tests/data`.
///
/// # Panics
/// When it does not exist (the data is part of the repository: a missing file is a broken
/// checkout, under CI or not).
pub fn shared(rel: &str) -> PathBuf {
    let p = data_dir().join(rel);
    assert!(
        p.exists(),
        "test data file missing: {} (committed with the repository, see docs/DATA.md)",
        p.display()
    );
    p
}

/// Is the command-line tool `name` on the PATH? When it is not: panics under CI, prints a skip
/// message and returns `false` locally. scripts/test.sh installs the tools the tests use (GDAL's
/// from Debian packages, `rio` in its venv, whose `bin/` it puts first on the PATH).
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
        eprintln!("{test}: skipped, `{name}` is not installed (scripts/test.sh installs it)");
    }
    found
}

/// A file of the real data that a test may do without locally: `Some(path)` when it exists
/// under `tests/data`; when it does not, panics under CI and prints why the test is skipped
/// otherwise.
pub fn optional(rel: &str, test: &str) -> Option<PathBuf> {
    let p = data_dir().join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        !in_ci(),
        "{test}: test data {} is required under CI=true but missing",
        p.display()
    );
    eprintln!(
        "{test}: skipped, test data {} not found (see docs/DATA.md)",
        p.display()
    );
    None
}

/// Can `python3` import every module in `modules`? When it cannot: panics under CI, prints a skip
/// message and returns `false` locally. The tests run the `python3` on the PATH: scripts/test.sh
/// installs what they import in its venv (`target/venv-py`) and puts its `bin/` first.
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
        eprintln!(
            "{test}: skipped, python3 cannot import {modules:?} (scripts/test.sh installs them \
             in target/venv-py: put target/venv-py/bin first on the PATH)"
        );
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
