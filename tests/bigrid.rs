//! Grids simplified window by window (`simplify --window`, issue 15 item 3): every valid cell
//! within the bound of the output TIN (checked by rasterising it back, independently of the
//! simplifier), border vertices shared (a conforming mesh), the same bytes whatever `--threads`
//! and `--mem`, and a grid of one window simplified exactly as a whole grid.

use crate::data;
use crate::grid_tin;

use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::input::raster::{RasterReader, RasterSpec};
use sweeptin::simplify::{GridOptions, Options, SimplifyStats, simplify, simplify_raster};
use sweeptin::sink::{MeshSink, MeshSummary};

/// A mesh kept in memory.
#[derive(Default)]
struct Collect {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u64; 3]>,
}

impl MeshSink for Collect {
    fn vertex(&mut self, p: [f64; 3]) -> sweeptin::Result<()> {
        self.vertices.push(p);
        Ok(())
    }

    fn triangle(&mut self, t: [u64; 3]) -> sweeptin::Result<()> {
        assert!(t.iter().all(|&v| v < self.vertices.len() as u64), "{t:?}");
        self.triangles.push(t);
        Ok(())
    }

    fn finish(&mut self) -> sweeptin::Result<MeshSummary> {
        Ok(MeshSummary::default())
    }
}

fn windowed(path: &Path, bound: f64, window: u32, threads: usize) -> (Collect, SimplifyStats) {
    let mut r = RasterReader::open(path).unwrap();
    let grid = GridOptions {
        window,
        threads,
        ..GridOptions::new(Options::max_error(bound), 1 << 30)
    };
    let mut mesh = Collect::default();
    let stats = simplify_raster(&mut r, &grid, &mut mesh, None).unwrap();
    (mesh, stats)
}

/// Simplifies `path` in windows and checks the result against the grid itself.
fn check(path: &Path, bound: f64, window: u32) -> SimplifyStats {
    let mut r = RasterReader::open(path).unwrap();
    let spec = r.spec().clone();
    let h = r.read_all().unwrap();
    let (mesh, stats) = windowed(path, bound, window, 2);
    let name = path.display();
    assert!(stats.windows > 1, "{name}: {stats:?}");
    let c = grid_tin::rasterise(&spec, &h, &mesh.vertices, &mesh.triangles);
    let tol = 1e-6 * (1.0 + h.iter().fold(0.0f64, |m, v| m.max(v.abs())));
    assert!(c.max_error <= bound + tol, "{name}: {c:?} {stats:?}");
    assert!(stats.max_error <= bound, "{name}: {stats:?}");
    assert_eq!(c.covered_missing, 0, "{name}");
    assert_eq!(c.uncovered_valid as u64, stats.uncovered_cells, "{name}");
    assert_eq!(stats.points, mesh.vertices.len() as u64);
    assert_eq!(stats.triangles, mesh.triangles.len() as u64);
    // Every vertex written once.
    let mut xy: Vec<[u64; 2]> = mesh
        .vertices
        .iter()
        .map(|v| [v[0].to_bits(), v[1].to_bits()])
        .collect();
    xy.sort_unstable();
    xy.dedup();
    assert_eq!(
        xy.len(),
        mesh.vertices.len(),
        "{name}: a vertex written twice"
    );
    // Conforming: no edge with more than one triangle on a side; without missing cells the
    // edges with one triangle are the grid's outer sides, and the mesh is a disc.
    let boundary = grid_tin::boundary_edges(&mesh.triangles);
    if h.iter().all(|v| !v.is_nan()) {
        assert_outer(&spec, &mesh, &boundary);
    }
    stats
}

/// Every boundary edge lies on one of the grid's four outer sides, and V - E + F = 1.
fn assert_outer(spec: &RasterSpec, mesh: &Collect, boundary: &[[u64; 2]]) {
    let [x0, y0] = spec.cell_center(0, 0);
    let [x1, y1] = spec.cell_center(spec.cols - 1, spec.rows - 1);
    for e in boundary {
        let [a, b] = e.map(|i| mesh.vertices[i as usize]);
        let same = |k: usize, v: f64| a[k] == v && b[k] == v;
        assert!(
            same(0, x0) || same(0, x1) || same(1, y0) || same(1, y1),
            "edge {a:?}–{b:?} is inside the grid with one triangle: a crack between windows"
        );
    }
    let edges = (3 * mesh.triangles.len() + boundary.len()) / 2;
    let euler = mesh.vertices.len() as i64 - edges as i64 + mesh.triangles.len() as i64;
    assert_eq!(euler, 1);
}

/// An ESRI ASCII grid of smooth hills, with an optional lake of missing cells (-9999) across
/// window borders and a missing corner.
fn hills(dir: &Path, cols: usize, rows: usize, lake: bool) -> PathBuf {
    let mut s = format!(
        "ncols {cols}\nnrows {rows}\nxllcorner 500000\nyllcorner 6000000\ncellsize 2\n\
         NODATA_value -9999\n"
    );
    for r in 0..rows {
        for c in 0..cols {
            let (x, y) = (c as f64 / 11.0, r as f64 / 7.0);
            let d = ((c as f64 - 70.0).powi(2) + (r as f64 - 48.0).powi(2)).sqrt();
            let missing = lake && (d < 14.0 || (c + r < 3) || (r == 33 && c > 100));
            if missing {
                s.push_str("-9999 ");
            } else {
                let z = 100.0 + 30.0 * x.sin() * y.cos() + 2.0 * (3.1 * x + y).cos();
                s.push_str(&format!("{:.3} ", z));
            }
        }
        s.push('\n');
    }
    let p = dir.join(if lake { "lake.asc" } else { "hills.asc" });
    std::fs::write(&p, s).unwrap();
    p
}

#[test]
fn synthetic_windows_are_within_the_bound_and_conforming() {
    let dir = tempfile::tempdir().unwrap();
    let p = hills(dir.path(), 150, 110, false);
    for (bound, window) in [(0.2, 32), (1.0, 17)] {
        let s = check(&p, bound, window);
        assert!(s.border_points > 0 && s.windows >= 20, "{s:?}");
    }
}

#[test]
fn missing_cells_across_window_borders_are_never_covered() {
    let dir = tempfile::tempdir().unwrap();
    let p = hills(dir.path(), 150, 110, true);
    check(&p, 0.5, 32);
    check(&p, 0.05, 16);
}

#[test]
fn real_dems_in_windows() {
    for (name, bound, window) in [
        // int16, tiled 128 × 128: 10 × 6 windows
        ("topotoolbox_srtm_bigtujunga30m_utm11.tif", 10.0, 128),
        // float32 with 5 missing cells
        (
            "ign_DTM_test_data_77055_627760_LA93_IGN69_50CM.tif",
            0.05,
            16,
        ),
        // ASCII, 2,739 of 3,827 cells missing
        ("landlab_west_bijou_gully.asc", 0.2, 16),
    ] {
        if let Some(p) = data::optional(&format!("dem/{name}"), "real_dems_in_windows") {
            check(&p, bound, window);
        }
    }
}

#[test]
fn one_window_is_the_whole_grid_simplification() {
    let Some(p) = data::optional(
        "dem/ign_DTM_test_data_77055_627760_LA93_IGN69_50CM.tif",
        "one_window",
    ) else {
        return;
    };
    let mut r = RasterReader::open(&p).unwrap();
    let spec = r.spec().clone();
    let h = r.read_all().unwrap();
    let whole = simplify(&spec, &h, &Options::max_error(0.02), None).unwrap();
    let (mesh, stats) = windowed(&p, 0.02, 256, 2);
    assert_eq!(stats.windows, 1);
    assert_eq!(mesh.vertices, whole.vertices);
    let tris: Vec<[u64; 3]> = whole.triangles.iter().map(|t| t.map(u64::from)).collect();
    assert_eq!(mesh.triangles, tris);
    assert_eq!(stats.points, whole.stats.points);
}

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .arg("simplify")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn same_bytes_whatever_threads_and_mem_and_refused_when_a_band_cannot_fit() {
    let Some(p) = data::optional("dem/startinpy_dem_01.tif", "same_bytes") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let p = p.to_str().unwrap();
    let mut outputs = Vec::new();
    for (threads, mem) in [("1", "1G"), ("2", "1G"), ("2", "18M")] {
        let out = dir.path().join(format!("t{threads}_{mem}.ply"));
        let o = cli(&[
            p,
            "-o",
            out.to_str().unwrap(),
            "--max-error",
            "20",
            "--window",
            "64",
            "--threads",
            threads,
            "--mem",
            mem,
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert!(outputs.len() == 3 && outputs[0].len() > 1000);
    assert!(outputs[0] == outputs[1], "--threads 1 and 2 differ");
    assert!(outputs[0] == outputs[2], "--mem 1G and 18M differ");
    // A band that cannot fit is refused before anything is written (exit 2).
    let out = dir.path().join("small.ply");
    let o = cli(&[
        p,
        "-o",
        out.to_str().unwrap(),
        "--max-error",
        "20",
        "--mem",
        "4M",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--mem") && err.contains("--window"), "{err}");
    assert!(!out.exists());
    // Budgets need one window.
    let o = cli(&[
        p,
        "-o",
        out.to_str().unwrap(),
        "--max-points",
        "100",
        "--window",
        "64",
    ]);
    assert_eq!(o.status.code(), Some(2));
}
