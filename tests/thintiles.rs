//! `sweeptin thin --tile` (issue 15, item 1, bounded memory): every input point within the
//! tolerance (an independent barycentric check), the tiles one conforming triangulation (no
//! T-junction on a tile border: one boundary loop, Euler's count, the triangles' areas adding
//! up to the boundary's), the same bytes for any --mem and --threads, and not many more points
//! than the global run.

use crate::data;
use crate::mesh;
use crate::tin_errors;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::input::las::Filter;
use sweeptin::pipeline::{Input, LineOptions, RunConfig, RunOptions, ThinSummary, thin_tiled};
use sweeptin::simplify::ThinOptions;
use sweeptin::sink::MemoryMesh;
use tin_errors::tin_errors;

fn config(paths: &[PathBuf], filter: Filter) -> RunConfig {
    let input = Input {
        paths: paths.to_vec(),
        filter,
        duplicates: Default::default(),
        lines: LineOptions::default(),
    };
    RunConfig::new(input, RunOptions::default()).unwrap()
}

fn tiled(paths: &[PathBuf], filter: Filter, tol: f64, tile: f64) -> (MemoryMesh, ThinSummary) {
    let mut mesh = MemoryMesh::default();
    let s = thin_tiled(
        &config(paths, filter),
        &ThinOptions::max_error(tol),
        tile,
        &mut mesh,
    )
    .unwrap();
    (mesh, s)
}

/// The distinct positions of `pts` (the first of each, as `--duplicates first`).
fn distinct(pts: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut seen = HashMap::new();
    pts.iter()
        .filter(|p| seen.insert([p[0].to_bits(), p[1].to_bits()], ()).is_none())
        .copied()
        .collect()
}

fn read(path: &Path, filter: &Filter) -> Vec<[f64; 3]> {
    let mut r = sweeptin::input::las::LidarReader::open(&[path], filter).unwrap();
    r.read_all()
        .unwrap()
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect()
}

fn cross(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The mesh is one triangulated disk: counter-clockwise triangles, each directed edge once,
/// every vertex used, the boundary one loop, V − E + F = 1, and the triangles' areas add up to
/// the area inside the boundary (no fold, no overlap). A T-junction on a tile border leaves
/// a second boundary loop (a hole of zero area) and fails the count.
fn assert_conforming(m: &MemoryMesh) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    let mut used = vec![false; m.vertices.len()];
    let mut area = 0.0;
    for (n, t) in m.triangles.iter().enumerate() {
        let p = t.map(|v| m.vertices[v as usize]);
        let a = cross(p[0], p[1], p[2]);
        assert!(a > 0.0, "triangle {n} {p:?} is not counter-clockwise");
        area += a / 2.0;
        for k in 0..3 {
            used[t[k] as usize] = true;
            let e = (t[k], t[(k + 1) % 3]);
            assert!(directed.insert(e, n).is_none(), "edge {e:?} twice");
        }
    }
    assert!(used.iter().all(|&u| u), "a vertex no triangle uses");
    let boundary: HashMap<u32, u32> = directed
        .keys()
        .filter(|(a, b)| !directed.contains_key(&(*b, *a)))
        .map(|&(a, b)| (a, b))
        .collect();
    let edges = (directed.len() + boundary.len()) / 2;
    let euler = m.vertices.len() as i64 - edges as i64 + m.triangles.len() as i64;
    assert_eq!(euler, 1, "not one disk (a T-junction or a hole)");
    let start = *boundary.keys().min().unwrap();
    let (mut v, mut steps, mut ring) = (start, 0, 0.0);
    loop {
        let w = boundary[&v];
        let (p, q) = (m.vertices[v as usize], m.vertices[w as usize]);
        ring += (p[0] - q[0]) * (p[1] + q[1]) / 2.0;
        steps += 1;
        v = w;
        if v == start {
            break;
        }
    }
    assert_eq!(steps, boundary.len(), "more than one boundary loop");
    assert!(
        (ring - area).abs() <= 1e-9 * area,
        "areas {area} (triangles) and {ring} (boundary) differ: folds or overlaps"
    );
}

fn shared(rel: &str) -> Option<PathBuf> {
    data::optional(rel, "thintiles")
}

#[test]
fn real_ground_tiles_keep_every_point_and_conform() {
    let Some(las) = shared("lidar/ign_50m_tiles/test_data_77050_627755_LA93_IGN69_ground.las")
    else {
        return;
    };
    let pts = distinct(&read(&las, &Filter::default()));
    let (global, _) =
        sweeptin::pipeline::thin(&config(std::slice::from_ref(&las), Filter::default()), &{
            ThinOptions::max_error(0.1)
        })
        .unwrap();
    // One tile holding everything: the global run's triangles.
    let (one, _) = tiled(std::slice::from_ref(&las), Filter::default(), 0.1, 1e6);
    let set = |v: &[[f64; 3]], t: &[[u32; 3]]| {
        let mut k: Vec<[[u64; 3]; 3]> = t
            .iter()
            .map(|t| {
                let mut c = t.map(|i| v[i as usize].map(f64::to_bits));
                c.sort();
                c
            })
            .collect();
        k.sort();
        k
    };
    assert!(set(&one.vertices, &one.triangles) == set(&global.vertices, &global.triangles));
    // 20 m: the tile's west edge x = 770 500 lies on a grid line (points on it, a sliver
    // tile); 7 m: 64 small tiles.
    for tile in [20.0, 7.0] {
        let (m, s) = tiled(std::slice::from_ref(&las), Filter::default(), 0.1, tile);
        let (max, uncovered) = tin_errors(&m.vertices, &m.triangles, &pts);
        assert_eq!(uncovered, 0, "tile {tile}");
        assert!(max <= 0.1 + 1e-9, "tile {tile}: max error {max}");
        assert!(s.thin.max_error <= 0.1 && s.thin.points == pts.len() as u64);
        assert_conforming(&m);
        let t = s.tiles.unwrap();
        assert!(t.tiles > 1 && t.border_points > 0, "{t:?}");
        // The documented factor (docs/ACCURACY.md): at most 1.3 × the global run's vertices.
        assert!(
            m.vertices.len() as f64 <= 1.3 * global.vertices.len() as f64,
            "tile {tile}: {} vertices, global {}",
            m.vertices.len(),
            global.vertices.len()
        );
    }
}

/// A tilted lattice at UTM-like offsets whose rows and columns fall exactly on the tile lines
/// (grid corners at points, whole rows of points on borders), with bumps.
#[test]
fn a_lattice_on_the_tile_lines_stays_within_and_conforms() {
    let dir = tempfile::tempdir().unwrap();
    let las = dir.path().join("lattice.las");
    let mut pts = Vec::new();
    for j in 0..=120 {
        for i in 0..=100 {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
            let bump = ((i * 7 + j * 13) % 11) as f64 * 0.02;
            pts.push([x, y, 100.0 + 0.3 * x - 0.2 * y + bump]);
        }
    }
    mesh::write_las(&las, &pts);
    let world = distinct(&read(&las, &Filter::default()));
    for tile in [10.0, 2.5] {
        let (m, s) = tiled(std::slice::from_ref(&las), Filter::default(), 0.05, tile);
        let (max, uncovered) = tin_errors(&m.vertices, &m.triangles, &world);
        assert_eq!(uncovered, 0);
        assert!(max <= 0.05 + 1e-9, "tile {tile}: max error {max}");
        assert_eq!(s.thin.points, world.len() as u64);
        assert_conforming(&m);
    }
}

fn sweeptin_cmd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
}

#[test]
fn same_bytes_whatever_mem_and_threads_and_clear_refusals() {
    let Some(las) = shared("lidar/ign_50m_tiles/test_data_77050_627755_LA93_IGN69_ground.las")
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &str, extra: &[&str]| {
        let o = sweeptin_cmd()
            .arg("thin")
            .arg(&las)
            .args(["--max-error", "0.1", "--tile", "10", "--json", "-o"])
            .arg(dir.path().join(out))
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!(json["tiles"]["tiles"].as_u64().unwrap() > 1, "{json}");
        if extra.contains(&"2M") {
            assert!(
                json["tiles"]["spilled_bytes"].as_u64().unwrap() > 0,
                "{json}"
            );
        }
        std::fs::read(dir.path().join(out)).unwrap()
    };
    // 2M: the routing sort spills (a quarter of --mem holds about 8000 points).
    let a = run("a.ply", &["--threads", "1", "--mem", "2M"]);
    let b = run("b.ply", &["--threads", "2", "--mem", "1G"]);
    assert!(a == b, "thin --tile output differs with --mem / --threads");
    // The first pass's engine (its triangles arrive in another order).
    let c = run("s.ply", &["--engine", "sweep"]);
    assert!(a == c, "thin --tile output differs with --engine");
    // Refused before any work, exit 2 (usage).
    let lines = dir.path().join("line.txt");
    std::fs::write(&lines, "770510 6277560\n770540 6277580\n").unwrap();
    let xyz = dir.path().join("pts.xyz");
    std::fs::write(&xyz, "0 0 0\n1 0 0\n0 1 0\n").unwrap();
    for (input, args, says) in [
        (&las, vec!["--tile", "0"], "--tile"),
        (&las, vec!["--tile", "10", "--breaklines"], "breaklines"),
        (&xyz, vec!["--tile", "10"], "LAS/LAZ"),
    ] {
        let mut c = sweeptin_cmd();
        c.arg("thin")
            .arg(input)
            .args(["--max-error", "0.1"])
            .args(&args);
        if args.last() == Some(&"--breaklines") {
            c.arg(&lines);
        }
        let o = c.arg("-o").arg(dir.path().join("c.ply")).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(says), "{err}");
        assert!(!dir.path().join("c.ply").exists());
    }
}

/// Issue 41, item 7: `thin --tile 1` on lidR (points 1.05 m apart) wrote 321,159 vertices and
/// said "50988 points kept (69.46 %)". Tiles smaller than a point's neighbourhood (their
/// borders cut the TIN at more places than it has points) are refused, exit 2, naming the
/// smallest tile that works, which then runs; the summary counts the vertices written.
#[test]
fn a_tile_smaller_than_a_points_neighbourhood_is_refused_and_the_summary_counts_what_is_written() {
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.ply");
    let run = |tile: &str, json: bool| {
        let mut c = sweeptin_cmd();
        c.arg("thin")
            .arg(&sample)
            .args(["--max-error", "0.1", "--tile", tile, "-o"])
            .arg(&out);
        if json {
            c.arg("--json");
        }
        c.output().unwrap()
    };
    // Points about 0.18 apart: tiles of 0.5 hold about 8 points.
    let o = run("0.5", false);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("smaller than a point's neighbourhood"),
        "{err}"
    );
    assert!(!out.exists(), "a refused run left {}", out.display());
    let smallest = err
        .split("give --tile ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap_or_else(|| panic!("no smallest tile named: {err}"));
    smallest.parse::<f64>().unwrap();
    // The tile it names works, and the summary counts what is written.
    let o = run(smallest, true);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (vertices, _) = sweeptin::input::read_ply(&out).unwrap();
    let t = &json["thin"];
    assert_eq!(
        t["vertices"].as_u64(),
        Some(vertices.len() as u64),
        "{json}"
    );
    let kept = t["kept"].as_u64().unwrap();
    let border = json["tiles"]["border_points"].as_u64().unwrap();
    assert!(
        border > 0 && kept + border <= vertices.len() as u64,
        "{json}"
    );
    assert_eq!(
        t["line_vertices"].as_u64(),
        Some(vertices.len() as u64 - kept)
    );
    let ratio = t["vertex_ratio"].as_f64().unwrap();
    let points = t["points"].as_f64().unwrap();
    assert!(
        (ratio - vertices.len() as f64 / points).abs() < 1e-12,
        "{json}"
    );
    let o = run(smallest, false);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("{} vertices (", vertices.len())),
        "the summary does not count the vertices written: {err}"
    );
}

/// Issue 43, item 4: `thin --tile` on the ARSO ground at `--mem 64M` refused every side (below
/// 140 m "give a larger --tile", from 150 m "give a smaller --tile"). The borders now keep one
/// sample per position as they fill (each crossing came twice, each vertex once per triangle
/// around it), and a tile too large for `--mem` names the side that fits, which then runs.
#[test]
fn a_tile_too_large_for_mem_names_a_side_that_fits() {
    let Some(las) = shared("lidar/ign_50m_tiles/test_data_77050_627755_LA93_IGN69_ground.las")
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let run = |tile: &str| {
        sweeptin_cmd()
            .arg("thin")
            .arg(&las)
            .args(["--max-error", "0.1", "--mem", "2M", "--tile", tile, "-o"])
            .arg(dir.path().join("t.ply"))
            .output()
            .unwrap()
    };
    let o = run("100");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!dir.path().join("t.ply").exists());
    let side = err
        .split("give --tile ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap_or_else(|| panic!("no side named: {err}"));
    let o = run(side);
    assert!(
        o.status.success(),
        "--tile {side}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}
