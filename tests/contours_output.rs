//! What contour files hold (issue 41, item 21): coordinates with the data's decimals (not 16
//! digits), lines shorter than `--min-length` left out and counted, GeoPackage output, and the
//! file's size in the summary; a plan's merge writes the same.

use crate::cli;
use crate::data;
use crate::plans;

use cli::ok;
use serde_json::Value;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The most decimals of any coordinate of a GeoJSON file's lines, and the lines.
fn decimals_and_lines(path: &Path) -> (usize, Vec<Vec<[f64; 2]>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc: Value = serde_json::from_str(&text).unwrap();
    let mut most = 0;
    let mut lines = Vec::new();
    for f in doc["features"].as_array().unwrap() {
        let mut line = Vec::new();
        for p in f["geometry"]["coordinates"].as_array().unwrap() {
            for v in p.as_array().unwrap() {
                let t = v.to_string();
                most = most.max(t.split_once('.').map_or(0, |(_, d)| d.len()));
            }
            line.push([p[0].as_f64().unwrap(), p[1].as_f64().unwrap()]);
        }
        lines.push(line);
    }
    (most, lines)
}

/// Lines as a sorted list, each ring started at its least point (a plan's merge starts a ring
/// cut by a tile edge elsewhere).
fn normalised(mut lines: Vec<Vec<[f64; 2]>>) -> Vec<Vec<[f64; 2]>> {
    for l in &mut lines {
        if l.len() > 1 && l.first() == l.last() {
            l.pop();
            let i = (0..l.len())
                .min_by(|&a, &b| l[a].partial_cmp(&l[b]).unwrap())
                .unwrap();
            l.rotate_left(i);
            l.push(l[0]);
        }
    }
    lines.sort_by(|x, y| x.partial_cmp(y).unwrap());
    lines
}

fn length(line: &[[f64; 2]]) -> f64 {
    line.windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

fn contours(laz: &Path, out: &Path, more: &[&str]) -> Value {
    let mut args = vec![
        "contours",
        s(laz),
        "-o",
        s(out),
        "--interval",
        "2",
        "--json",
    ];
    args.extend(more);
    serde_json::from_slice(&ok(&args).stdout).unwrap()
}

/// `contours` wrote every coordinate with 16-odd digits (2.4 GB of GeoJSON for a large file):
/// by default it now writes the decimals of the LAS scale (IGN's 0.01 m: 2), `--precision`
/// sets them, and the summary gives the file's size.
#[test]
fn contour_coordinates_have_the_data_decimals_not_sixteen_digits() {
    let laz = data::shared("lidar/ign_test_semis_2023_0299_6802_LA93_IGN69.laz");
    let t = tempfile::tempdir().unwrap();
    let full = t.path().join("default.geojson");
    let sum = contours(&laz, &full, &["--class", "2"]);
    let (most, lines) = decimals_and_lines(&full);
    assert_eq!(most, 2, "the file's scale is 0.01");
    assert!(lines.len() > 20, "{} lines", lines.len());
    let c = &sum["contours"];
    assert_eq!(c["decimals"], 2);
    assert_eq!(
        c["bytes"].as_u64().unwrap(),
        std::fs::metadata(&full).unwrap().len(),
        "the summary gives the file's size"
    );
    let coarse = t.path().join("p0.geojson");
    contours(&laz, &coarse, &["--class", "2", "--precision", "0"]);
    assert_eq!(decimals_and_lines(&coarse).0, 0);
    assert!(std::fs::metadata(&coarse).unwrap().len() < std::fs::metadata(&full).unwrap().len());
    // Too many decimals is a usage error.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["contours", s(&laz), "-o", s(&coarse), "--precision", "16"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

/// `--min-length L` leaves out every line shorter than L (closed rings too) and says how many.
#[test]
fn contours_shorter_than_min_length_are_left_out_and_counted() {
    let laz = data::shared("lidar/lidR_Topography.laz");
    let t = tempfile::tempdir().unwrap();
    let all = t.path().join("all.geojson");
    let sum_all = contours(&laz, &all, &[]);
    let (_, every) = decimals_and_lines(&all);
    let long = t.path().join("long.geojson");
    let sum = contours(&laz, &long, &["--min-length", "25"]);
    let (_, kept) = decimals_and_lines(&long);
    let short = every.iter().filter(|l| length(l) < 25.0).count();
    assert!(short > 100, "{short} short lines in the data");
    assert!(kept.iter().all(|l| length(l) >= 25.0));
    assert_eq!(kept.len(), every.len() - short);
    assert_eq!(sum["contours"]["short_dropped"], short as u64);
    assert_eq!(
        sum["contours"]["features"].as_u64().unwrap() + short as u64,
        sum_all["contours"]["features"].as_u64().unwrap()
    );
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["contours", s(&laz), "-o", s(&long), "--min-length", "-1"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `-o c.gpkg` writes a GeoPackage with the same lines as the GeoJSON (read back through the
/// crate's own GeoPackage reader), and a contours plan merges into one.
#[test]
fn contours_written_as_geopackage_hold_the_geojson_lines() {
    let laz = data::shared("lidar/lidR_Topography.laz");
    let t = tempfile::tempdir().unwrap();
    let json = t.path().join("c.geojson");
    let gpkg = t.path().join("c.gpkg");
    contours(&laz, &json, &["--min-length", "10"]);
    let sum = contours(&laz, &gpkg, &["--min-length", "10"]);
    let a = sweeptin::input::geojson::read_lines(&json).unwrap();
    let b = sweeptin::input::geojson::read_lines(&gpkg).unwrap();
    assert_eq!(
        b.len() as u64,
        sum["contours"]["features"].as_u64().unwrap()
    );
    assert_eq!(a, b, "the same lines in the same order");
    assert_eq!(
        sum["contours"]["bytes"].as_u64().unwrap(),
        std::fs::metadata(&gpkg).unwrap().len()
    );

    // A plan's merge writes the same GeoPackage lines as one run.
    let job = t.path().join("job");
    plans::sweeptin(
        &[
            "plan",
            "contours",
            s(&laz),
            "--interval",
            "2",
            "--min-length",
            "10",
            "--tile",
            "150",
            "-q",
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    plans::sweeptin(&["run", s(&plan), "--all", "-q"], "run");
    let merged = t.path().join("m.gpkg");
    plans::sweeptin(&["merge", s(&plan), "-o", s(&merged), "-q"], "merge");
    let m = sweeptin::input::geojson::read_lines(&merged).unwrap();
    assert_eq!(
        normalised(m),
        normalised(b),
        "the merged GeoPackage differs from one run's"
    );
}
