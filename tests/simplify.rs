//! Grid to TIN: the output is checked independently of the simplifier, by rasterising the output
//! triangles (world coordinates, barycentric interpolation) back onto the grid.

use crate::data;
use crate::grid_tin;
use grid_tin::Check;
use std::path::PathBuf;
use sweeptin::input::raster::RasterReader;
use sweeptin::input::raster::RasterSpec;
use sweeptin::simplify::{Options, Simplified, Stop, simplify};

fn dem(name: &str) -> Option<PathBuf> {
    data::optional(&format!("dem/{name}"), "simplify")
}

fn rasterise(spec: &RasterSpec, h: &[f64], tin: &Simplified) -> Check {
    let tris: Vec<[u64; 3]> = tin.triangles.iter().map(|t| t.map(u64::from)).collect();
    grid_tin::rasterise(spec, h, &tin.vertices, &tris)
}

fn check_file(name: &str, bounds: &[f64]) {
    let Some(p) = dem(name) else {
        eprintln!("skipping {name}: not found");
        return;
    };
    let mut r = RasterReader::open(&p).unwrap();
    let spec = r.spec().clone();
    let h = r.read_all().unwrap();
    for &e in bounds {
        for decimate in [false, true] {
            let opts = Options {
                stop: Stop::MaxError(e),
                decimate,
            };
            let tin = simplify(&spec, &h, &opts, None).unwrap();
            let c = rasterise(&spec, &h, &tin);
            // Floating-point tolerance of the independent interpolation.
            let tol = 1e-6 * (1.0 + h.iter().fold(0.0f64, |m, v| m.max(v.abs())));
            assert!(
                c.max_error <= e + tol,
                "{name} e={e}: {c:?} {:?}",
                tin.stats
            );
            assert_eq!(c.covered_missing, 0, "{name} e={e}");
            assert_eq!(
                c.uncovered_valid as u64, tin.stats.uncovered_cells,
                "{name} e={e}"
            );
            assert!(tin.stats.max_error <= e, "{name}: {:?}", tin.stats);
        }
    }
}

#[test]
fn srtm_ascii_grid_is_within_the_bound() {
    check_file(
        "landlab_SRTMGL3_40.09_-105.55_40.21_-105.35.asc",
        &[5.0, 40.0],
    );
}

#[test]
fn masked_gully_is_within_the_bound_and_not_triangulated_into_nodata() {
    check_file("landlab_west_bijou_gully.asc", &[0.1, 1.0]);
}

#[test]
fn ign_dtm_with_missing_cells() {
    check_file(
        "ign_DTM_test_data_77055_627760_LA93_IGN69_50CM.tif",
        &[0.02, 0.1],
    );
}

#[test]
fn planar_grid_collapses_to_two_triangles() {
    let spec = RasterSpec::north_up(300, 200, 500_000.0, 6_000_000.0, 0.5);
    let h: Vec<f64> = (0..200)
        .flat_map(|r| (0..300).map(move |c| 100.0 + 0.25 * c as f64 - 0.125 * r as f64))
        .collect();
    let tin = simplify(&spec, &h, &Options::max_error(1e-6), None).unwrap();
    assert_eq!(tin.triangles.len(), 2);
    assert_eq!(rasterise(&spec, &h, &tin).uncovered_valid, 0);
}

#[test]
fn synthetic_hills_with_a_lake_of_nodata() {
    let (cols, rows) = (160u32, 120u32);
    let spec = RasterSpec::north_up(cols, rows, 0.0, 1200.0, 10.0);
    let mut h = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let (x, y) = (c as f64 / 20.0, r as f64 / 15.0);
            let d = ((c as f64 - 80.0).powi(2) + (r as f64 - 60.0).powi(2)).sqrt();
            h.push(if d < 18.0 || (c > 150 && r < 8) {
                f64::NAN
            } else {
                50.0 * x.sin() * y.cos() + 3.0 * (3.0 * x).cos()
            });
        }
    }
    for e in [0.5, 2.0, 10.0] {
        let tin = simplify(&spec, &h, &Options::max_error(e), None).unwrap();
        let c = rasterise(&spec, &h, &tin);
        assert!(c.max_error <= e + 1e-6, "{c:?}");
        assert_eq!(c.covered_missing, 0);
        assert_eq!(c.uncovered_valid as u64, tin.stats.uncovered_cells);
    }
}

#[test]
fn cli_simplify_writes_a_mesh_and_a_json_summary() {
    let Some(p) = dem("landlab_west_bijou_gully.asc") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("gully.ply");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["simplify", p.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .args(["--max-error", "0.5", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["stats"]["points"].as_u64().unwrap() > 3);
    assert!(j["stats"]["max_error"].as_f64().unwrap() <= 0.5);
    assert!(out.exists());
    // Exactly one bound is required.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["simplify", p.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // A bound that is no distance is a usage error (it was exit 3, "mesh is not a valid
    // Delaunay triangulation").
    for bad in ["-1", "nan", "inf"] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
            .args(["simplify", p.to_str().unwrap(), "-o", out.to_str().unwrap()])
            .arg(format!("--max-error={bad}"))
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {e}");
        assert!(e.contains("must be a finite number"), "{e}");
    }
}

#[test]
fn startinpy_float64_with_non_round_cells() {
    check_file("startinpy_dem_01.tif", &[20.0]);
}

#[test]
fn non_square_cells() {
    let (cols, rows) = (90u32, 70u32);
    let mut spec = RasterSpec::north_up(cols, rows, 1000.0, 5000.0, 2.0);
    spec.transform[5] = -3.0;
    let h: Vec<f64> = (0..rows)
        .flat_map(|r| {
            (0..cols).map(move |c| 20.0 * ((c as f64 / 9.0).sin() + (r as f64 / 7.0).cos()))
        })
        .collect();
    for e in [0.2, 1.0, 5.0] {
        let tin = simplify(&spec, &h, &Options::max_error(e), None).unwrap();
        let c = rasterise(&spec, &h, &tin);
        assert!(c.max_error <= e + 1e-6, "{c:?}");
        assert_eq!(c.uncovered_valid, 0);
    }
}

/// Issue 41, item 8: an all-nodata grid gave an empty mesh with exit 0 (in one window and in
/// several); an extra row, or `NODATA_value` after the data, was read silently (-9999 became
/// a height); `xllcorner 1e300` wrote a mesh outside the exact range. Each is exit 3 naming
/// the file (and the line), and leaves no mesh.
#[test]
fn empty_and_damaged_ascii_grids_are_refused_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.ply");
    let head = "ncols 6\nnrows 5\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
    let row = |v: &str| format!("{}\n", [v; 6].join(" "));
    let nodata = format!("{head}NODATA_value -9999\n{}", row("-9999").repeat(5));
    let lonely = format!(
        "{head}NODATA_value -9999\n{}{}",
        row("-9999").repeat(4),
        "1 -9999 -9999 -9999 -9999 2\n"
    );
    let good = row("1").repeat(5);
    let cases: [(&str, String, &[&str], &str); 6] = [
        (
            "nodata.asc",
            nodata.clone(),
            &[],
            "every one of its 6×5 cells is missing",
        ),
        // Windows of 4 cells: two bands of windows.
        (
            "nodata.asc",
            nodata,
            &["--window", "4"],
            "every one of its 6×5 cells",
        ),
        (
            "lonely.asc",
            lonely,
            &[],
            "its 2 valid cells (of 6×5) make no triangle",
        ),
        (
            "extra.asc",
            format!("{head}{good}{}", row("7")),
            &[],
            ":11: \"7\" after the grid's last value",
        ),
        (
            "after.asc",
            format!("{head}{good}NODATA_value -9999\n"),
            &[],
            ":11: \"NODATA_value\" after the grid's last value: a header line",
        ),
        (
            "far.asc",
            format!("{}{good}", head.replace("xllcorner 0", "xllcorner 1e300")),
            &[],
            ":3: xllcorner 1e300",
        ),
    ];
    for (name, text, extra, says) in cases {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
            .arg("simplify")
            .arg(&p)
            .args(["--max-error", "0.1", "-q", "-o"])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{name} {extra:?}: {e}");
        assert!(e.contains(says) && e.contains(name), "{name}: {e}");
        assert!(!out.exists(), "{name}: a mesh was left");
    }
}
