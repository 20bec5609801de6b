//! `sweeptin thin` (issue 15, item 1): every input point within the tolerance, checked
//! independently of the thinning (a grid of the output triangles, barycentric interpolation),
//! the output the Delaunay triangulation of the kept points (spade) or a valid CDT with the
//! breaklines as edges (the crate's validator), the same bytes for any --mem and --threads.

use crate::data;
use crate::tin_errors;

use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::breaklines::{CleanOptions, read_file};
use sweeptin::input::las::Filter;
use sweeptin::pipeline::{Input, LineOptions, RunConfig, RunOptions};
use sweeptin::simplify::{ThinLines, ThinOptions, Thinned, thin};
use tin_errors::tin_errors;

fn shared(rel: &str) -> Option<PathBuf> {
    data::optional(rel, "thin")
}

fn config(paths: &[PathBuf], filter: Filter, lines: LineOptions) -> RunConfig {
    let input = Input {
        paths: paths.to_vec(),
        filter,
        duplicates: Default::default(),
        lines,
    };
    RunConfig::new(input, RunOptions::default()).unwrap()
}

fn ground() -> Filter {
    Filter {
        classes: Some(vec![2]),
        ..Filter::default()
    }
}

/// The distinct positions of `pts` (the first point of each, as `--duplicates first`).
fn distinct(pts: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| {
        let (p, q) = (pts[a], pts[b]);
        p[1].total_cmp(&q[1])
            .then(p[0].total_cmp(&q[0]))
            .then(a.cmp(&b))
    });
    order.dedup_by(|b, a| pts[*a][..2] == pts[*b][..2]);
    order.into_iter().map(|i| pts[i]).collect()
}

/// The triangles as sorted sets of positions.
fn keys(vertices: &[[f64; 3]], tris: impl Iterator<Item = [[f64; 2]; 3]>) -> Vec<[(u64, u64); 3]> {
    let _ = vertices;
    let mut out: Vec<[(u64, u64); 3]> = tris
        .map(|t| {
            let mut k = t.map(|p| (p[0].to_bits(), p[1].to_bits()));
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

/// The output equals spade's Delaunay triangulation of its vertices.
fn assert_spade_delaunay(t: &Thinned) {
    let mut d: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    for v in &t.vertices {
        d.insert(Point2::new(v[0], v[1])).unwrap();
    }
    let theirs = keys(
        &t.vertices,
        d.inner_faces()
            .map(|f| f.vertices().map(|v| [v.position().x, v.position().y])),
    );
    let ours = keys(
        &t.vertices,
        t.triangles
            .iter()
            .map(|tri| tri.map(|i| [t.vertices[i as usize][0], t.vertices[i as usize][1]])),
    );
    assert_eq!(ours, theirs, "not spade's Delaunay triangulation");
}

#[test]
fn real_ground_points_are_within_the_tolerance_of_a_delaunay_tin() {
    let Some(laz) = shared("lidar/startinpy_small.laz") else {
        return;
    };
    let tol = 0.05;
    let (t, summary) = sweeptin::pipeline::thin(
        &config(std::slice::from_ref(&laz), ground(), LineOptions::default()),
        &ThinOptions::max_error(tol),
    )
    .unwrap();
    let input = Input {
        paths: vec![laz],
        filter: ground(),
        duplicates: Default::default(),
        lines: LineOptions::default(),
    };
    let pts = distinct(&sweeptin::pipeline::read_points(&input).unwrap().0);
    assert_eq!(summary.thin.points, pts.len() as u64);
    assert_eq!(summary.points_read, 18_392);
    let (max, uncovered) = tin_errors(&t.vertices, &t.triangles, &pts);
    assert_eq!(uncovered, 0);
    assert!(max <= tol + 1e-9, "max error {max}");
    assert!((summary.thin.max_error - max).abs() < 1e-6);
    // Real ground, 5 cm: far fewer points than the input, and the Delaunay TIN of those.
    assert!(summary.thin.kept_ratio < 0.2, "{:?}", summary.thin);
    assert!(summary.thin.removed > 0);
    assert_spade_delaunay(&t);
}

/// Polylines of `path` with all vertices inside the box, as 2-D text lines (draped by the run).
fn lines_inside(path: &Path, b: [f64; 4], out: &Path) -> bool {
    let lines = read_file(path).unwrap();
    let mut s = String::new();
    let mut n = 0;
    for l in &lines.polylines {
        if l.iter()
            .all(|p| (b[0]..=b[2]).contains(&p[0]) && (b[1]..=b[3]).contains(&p[1]))
        {
            for p in l {
                s.push_str(&format!("{} {}\n", p[0], p[1]));
            }
            s.push('\n');
            n += 1;
        }
    }
    std::fs::write(out, s).unwrap();
    n > 10
}

#[test]
fn breaklines_stay_edges_over_real_lidar() {
    let (Some(laz), Some(bgt)) = (
        shared("lidar/ahn3_delft_cropped_2.laz"),
        shared("lines/bgt_delft_all_layers.geojson"),
    ) else {
        return;
    };
    let area = [85005.0, 447450.0, 85065.0, 447530.0];
    let dir = tempfile::tempdir().unwrap();
    let lp = dir.path().join("bgt.txt");
    assert!(lines_inside(&bgt, area, &lp));
    let filter = Filter {
        bbox: Some(sweeptin::input::las::BBox::new(area[0], area[1], area[2], area[3]).unwrap()),
        ..ground()
    };
    let lines = LineOptions {
        breaklines: vec![lp.clone()],
        ..LineOptions::default()
    };
    let tol = 0.1;
    let (t, summary) = sweeptin::pipeline::thin(
        &config(std::slice::from_ref(&laz), filter.clone(), lines),
        &ThinOptions::max_error(tol),
    )
    .unwrap();
    let segs = read_file(&lp)
        .unwrap()
        .clean(&CleanOptions::default())
        .unwrap()
        .segment_coords();
    assert!(summary.thin.segments > 50, "{:?}", summary.thin);
    let report = sweeptin::validate::validate_cdt(&t.vertices, &t.triangles, &segs).unwrap();
    assert!(report.constrained_edges >= segs.len() as u64);
    let input = Input {
        paths: vec![laz],
        filter,
        duplicates: Default::default(),
        lines: LineOptions::default(),
    };
    let mut pts = distinct(&sweeptin::pipeline::read_points(&input).unwrap().0);
    // Points merged into breakline vertices take the policy's height (the point's, `first`).
    pts.retain(|p| !t.vertices.iter().any(|v| v[..2] == p[..2] && v[2] != p[2]));
    let (max, uncovered) = tin_errors(&t.vertices, &t.triangles, &pts);
    assert_eq!(uncovered, 0);
    assert!(max <= tol + 1e-9, "max error {max}");
}

/// A pseudo-random cloud on a surface with a crease along `x = 50` (a road edge).
fn creased(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut s = seed;
    let mut r = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (x, y) = (
                (r() * 100.0 * 64.0).round() / 64.0,
                (r() * 100.0 * 64.0).round() / 64.0,
            );
            let z = if x < 50.0 {
                0.02 * x
            } else {
                1.0 + 0.3 * (x - 50.0)
            } + 0.01 * r();
            [x, y, z]
        })
        .collect()
}

#[test]
fn the_core_keeps_breaklines_and_every_point_at_zero_tolerance() {
    let pts = distinct(&creased(3000, 7));
    let line = [[50.0, -1.0, 1.0], [50.0, 101.0, 1.0]];
    let t = thin(
        pts.clone(),
        ThinLines {
            vertices: &line,
            segments: &[[0, 1]],
        },
        &ThinOptions::max_error(0.02),
    )
    .unwrap();
    let segs = [[[50.0, -1.0], [50.0, 101.0]]];
    sweeptin::validate::validate_cdt(&t.vertices, &t.triangles, &segs).unwrap();
    let (max, uncovered) = tin_errors(&t.vertices, &t.triangles, &pts);
    assert_eq!(uncovered, 0);
    assert!(max <= 0.02 + 1e-12, "{max}");
    assert!(t.stats.kept < pts.len() as u64 / 5, "{:?}", t.stats);
    // Tolerance 0 on noisy heights: every point stays, and the TIN is their Delaunay TIN.
    let all = thin(
        pts.clone(),
        ThinLines::default(),
        &ThinOptions::max_error(0.0),
    )
    .unwrap();
    assert_eq!(all.stats.kept, pts.len() as u64);
    assert_eq!(all.stats.max_error, 0.0);
    assert_spade_delaunay(&all);
    // A budget the points alone outgrow stops the run with a usage error naming --mem.
    let tight = ThinOptions {
        mem: Some(10_000),
        ..ThinOptions::max_error(0.0)
    };
    let e = thin(pts, ThinLines::default(), &tight).unwrap_err();
    assert_eq!(e.kind(), sweeptin::ErrorKind::Usage);
    assert!(e.to_string().contains("--mem"), "{e}");
}

fn sweeptin_cmd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
}

#[test]
fn same_bytes_whatever_mem_and_threads_and_clear_refusals() {
    let Some(laz) = shared("lidar/startinpy_small.laz") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &str, extra: &[&str]| {
        let o = sweeptin_cmd()
            .arg("thin")
            .arg(&laz)
            .args(["--class", "2", "--max-error", "0.1", "-o"])
            .arg(dir.path().join(out))
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(dir.path().join(out)).unwrap()
    };
    let a = run("a.ply", &["--threads", "1", "--mem", "16M"]);
    let b = run("b.ply", &["--threads", "2"]);
    assert!(a == b, "thin output differs with --mem / --threads");
    // Refused before any work, exit 2 (usage): a negative bound, a job over --mem.
    for (args, says) in [
        (vec!["--max-error", "-1"], "--max-error"),
        (vec!["--max-error", "0.1", "--mem", "1M"], "raise --mem"),
    ] {
        let o = sweeptin_cmd()
            .arg("thin")
            .arg(&laz)
            .args(&args)
            .arg("-o")
            .arg(dir.path().join("c.ply"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(says), "{err}");
        assert!(!dir.path().join("c.ply").exists());
    }
}

/// A closed square ring with a vertex every 5 units, as 2-D text (draped from the points).
fn ring(x0: f64, y0: f64, x1: f64, y1: f64) -> String {
    let corners = [[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]];
    let mut s = String::new();
    for w in corners.windows(2) {
        let n = (((w[1][0] - w[0][0]).abs() + (w[1][1] - w[0][1]).abs()) / 5.0) as usize;
        for k in 0..n {
            let t = k as f64 / n as f64;
            let p = [0, 1].map(|j| w[0][j] + t * (w[1][j] - w[0][j]));
            s.push_str(&format!("{} {}\n", p[0], p[1]));
        }
    }
    s.push_str(&format!("{x0} {y0}\n\n"));
    s
}

#[test]
fn trimming_keeps_the_survey_area_within_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let pts = distinct(&creased(4000, 3));
    let xyz = dir.path().join("pts.xyz");
    let text: String = pts
        .iter()
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    std::fs::write(&xyz, text).unwrap();
    let (b, h) = (dir.path().join("b.txt"), dir.path().join("h.txt"));
    std::fs::write(&b, ring(10.0, 10.0, 90.0, 90.0)).unwrap();
    std::fs::write(&h, ring(40.0, 40.0, 60.0, 60.0)).unwrap();
    let lines = LineOptions {
        boundary: Some(b),
        holes: Some(h),
        ..LineOptions::default()
    };
    let tol = 0.02;
    let (t, summary) = sweeptin::pipeline::thin(
        &config(&[xyz], Filter::default(), lines),
        &ThinOptions::max_error(tol),
    )
    .unwrap();
    assert!(summary.trimmed_triangles > 0);
    let check = sweeptin::validate::CdtCheck {
        convex_hull: false,
        delaunay: true,
    };
    sweeptin::validate::validate_cdt_with(&t.vertices, &t.triangles, &[], &check).unwrap();
    for tri in &t.triangles {
        let c = [0, 1].map(|k| tri.iter().map(|&i| t.vertices[i as usize][k]).sum::<f64>() / 3.0);
        let inside = |lo: f64, hi: f64| (lo..=hi).contains(&c[0]) && (lo..=hi).contains(&c[1]);
        assert!(
            inside(10.0, 90.0) && !inside(40.0, 60.0),
            "triangle at {c:?}"
        );
    }
    // Points strictly inside the survey area and outside the hole: covered and within.
    let area: Vec<[f64; 3]> = pts
        .iter()
        .filter(|p| {
            let inside = |lo: f64, hi: f64| p[0] > lo && p[0] < hi && p[1] > lo && p[1] < hi;
            inside(10.0, 90.0) && !(p[0] >= 40.0 && p[0] <= 60.0 && p[1] >= 40.0 && p[1] <= 60.0)
        })
        .copied()
        .collect();
    let (max, uncovered) = tin_errors(&t.vertices, &t.triangles, &area);
    assert_eq!(uncovered, 0);
    assert!(max <= tol + 1e-9, "max error {max}");
}
