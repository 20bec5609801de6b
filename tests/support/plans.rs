//! Running the binary and reading what a plan wrote, for the plan tests: its tiles' extent, its
//! tasks' records, and a raster's cells bit for bit.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use sweeptin::input::raster::RasterReader;

/// The binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
}

/// `out`, which must be a success (else the test fails with its stderr).
pub fn ok(out: Output, what: &str) -> Output {
    assert!(
        out.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs the binary with `args`, which must succeed.
pub fn sweeptin(args: &[&str], what: &str) -> Output {
    ok(bin().args(args).output().unwrap(), what)
}

/// A path as a `&str` (the test directories are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every cell's value bits, and the raster's size and origin.
pub fn cells(path: &Path) -> (u32, u32, [f64; 6], Vec<u64>) {
    let mut r = RasterReader::open(path).unwrap();
    let spec = r.spec().clone();
    let v = r.read_window(0, 0, spec.cols, spec.rows).unwrap();
    let bits = v
        .iter()
        .map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() })
        .collect();
    (spec.cols, spec.rows, spec.transform, bits)
}

/// The union of a plan's tiles `xmin,ymin,xmax,ymax`, and its number of tasks.
pub fn plan_extent(plan: &Path) -> (String, usize) {
    let p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(plan).unwrap()).unwrap();
    let tiles = p["tiles"].as_array().unwrap();
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for t in tiles {
        let t: Vec<f64> = t["bounds"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        b = [
            b[0].min(t[0]),
            b[1].min(t[1]),
            b[2].max(t[2]),
            b[3].max(t[3]),
        ];
    }
    (format!("{},{},{},{}", b[0], b[1], b[2], b[3]), tiles.len())
}

/// The records `tiles/task_<i>.json` of the `n` tasks of the plan in `dir`.
pub fn records(dir: &Path, n: usize) -> Vec<serde_json::Value> {
    (0..n)
        .map(|i| {
            let p = dir.join("tiles").join(format!("task_{i}.json"));
            serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
        })
        .collect()
}

/// `plan ARGS… -o JOB` (`args` from the job's name, e.g. `["dem", input, "--cell", "1"]`), then
/// `run --all`: the plan file and its number of tasks.
pub fn plan_and_run(args: &[&str], job: &Path) -> (PathBuf, usize) {
    let mut all = vec!["plan"];
    all.extend_from_slice(args);
    all.extend(["-o", s(job)]);
    sweeptin(&all, "plan");
    let plan = job.join("plan.json");
    let (_, n) = plan_extent(&plan);
    sweeptin(&["run", s(&plan), "--all", "-q"], "run --all");
    (plan, n)
}
