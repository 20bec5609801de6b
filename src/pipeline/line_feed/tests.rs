//! The streamed breaklines against the in-memory graph: the same calls to the mesh sink, in the
//! same order (so the same `.stin` bytes and the same rasters).

use super::super::lines::{self, LineOptions};
use super::super::{Input, RunConfig, RunOptions, RunSummary, drive};
use crate::sink::{MeshSink, MeshSummary};
use crate::sort::memory::DuplicatePolicy;
use std::path::{Path, PathBuf};

/// Every call a mesh sink gets, in order (`.stin` keeps them all).
#[derive(Debug, Default, PartialEq)]
struct Trace(Vec<(u8, [u64; 3])>);

impl MeshSink for Trace {
    fn vertex(&mut self, p: [f64; 3]) -> crate::Result<()> {
        self.0.push((0, p.map(f64::to_bits)));
        Ok(())
    }
    fn triangle(&mut self, t: [u64; 3]) -> crate::Result<()> {
        self.0.push((1, t));
        Ok(())
    }
    fn vertex_done(&mut self, id: u64) -> crate::Result<()> {
        self.0.push((2, [id, 0, 0]));
        Ok(())
    }
    fn watermark(&mut self, y: f64) -> crate::Result<()> {
        self.0.push((3, [y.to_bits(), 0, 0]));
        Ok(())
    }
    fn keeps_watermarks(&self) -> bool {
        true
    }
    fn finish(&mut self) -> crate::Result<MeshSummary> {
        Ok(MeshSummary::default())
    }
}

fn write_xyz(path: &Path, pts: &[[f64; 3]]) {
    let s: String = pts
        .iter()
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    std::fs::write(path, s).unwrap();
}

fn write_lines(path: &Path, lines: &[Vec<[f64; 3]>]) {
    let mut s = String::new();
    for l in lines {
        for p in l {
            if p[2].is_nan() {
                s.push_str(&format!("{} {}\n", p[0], p[1]));
            } else {
                s.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
            }
        }
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

/// The run of `points` with `lines`, the graph in memory or streamed, in `mem` bytes.
fn run(
    points: &Path,
    lines: &LineOptions,
    policy: DuplicatePolicy,
    mem: u64,
    streamed: bool,
) -> (Trace, RunSummary) {
    let tmp = tempfile::tempdir().unwrap();
    let input = Input {
        paths: vec![points.to_path_buf()],
        filter: crate::input::las::Filter::keep_all(),
        duplicates: policy,
        lines: lines.clone(),
    };
    let options = RunOptions {
        mem,
        tmp_dir: Some(tmp.path().to_path_buf()),
        progress: false,
        ..Default::default()
    };
    let config = RunConfig::new(input, options).unwrap();
    let stream = streamed.then_some(config.line_budget());
    let points_only = config.points_only();
    let mut drape = |sink: &mut dyn super::super::TriangleSink| {
        drive::run(&points_only, None, None, &mut [sink]).map(|_| ())
    };
    let p = lines::prepare_with(lines, config.read_lines(), Some(&mut drape), stream).unwrap();
    assert_eq!(
        p.feed.lock().unwrap().is_some(),
        streamed,
        "the path asked for"
    );
    let mut trace = Trace::default();
    let summary = drive::run(&config, Some(&p), Some(&mut trace), &mut []).unwrap();
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
    (trace, summary)
}

/// Both paths give the same calls, and the same summary of the lines.
fn same(points: &Path, lines: &LineOptions, policy: DuplicatePolicy, mem: u64) -> RunSummary {
    let (a, sa) = run(points, lines, policy, mem, false);
    let (b, sb) = run(points, lines, policy, mem, true);
    assert!(sa.triangles > 0);
    assert_eq!(a.0.len(), b.0.len());
    if let Some(i) = (0..a.0.len()).find(|&i| a.0[i] != b.0[i]) {
        panic!("call {i} differs: {:?} against {:?}", a.0[i], b.0[i]);
    }
    let (la, mut lb) = (sa.breaklines.unwrap(), sb.breaklines.clone().unwrap());
    assert!(la.cleaner.is_none() && lb.cleaner.is_some());
    // Read whole in memory (and streamed with mixed heights, cleaned in memory); streamed, the
    // longest polyline (these are text files).
    let held = lb.read_held_vertices;
    if lb.cleaner.is_some_and(|c| c.in_memory) {
        assert_eq!(held, la.read_held_vertices);
    } else {
        assert!(held < la.read_held_vertices, "{held} {la:?}");
    }
    lb.cleaner = None;
    lb.read_held_vertices = la.read_held_vertices;
    assert_eq!(
        serde_json::to_string(&la).unwrap(),
        serde_json::to_string(&lb).unwrap()
    );
    assert_eq!(
        (sa.vertices, sa.triangles, sa.duplicates),
        (sb.vertices, sb.triangles, sb.duplicates)
    );
    sb
}

fn files(dir: &Path, points: &[[f64; 3]], lines: &[Vec<[f64; 3]>]) -> (PathBuf, PathBuf) {
    let (p, l) = (dir.join("pts.xyz"), dir.join("lines.txt"));
    write_xyz(&p, points);
    write_lines(&l, lines);
    (p, l)
}

#[test]
fn a_streamed_road_network_gives_the_in_memory_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let (p, l) = files(
        dir.path(),
        &crate::synth::road_points(4_000, 3),
        &crate::synth::roads(3_000, 3),
    );
    let o = LineOptions {
        breaklines: vec![l],
        ..LineOptions::default()
    };
    // A small budget: every sort spills.
    let s = same(&p, &o, DuplicatePolicy::First, 1 << 20);
    let b = s.breaklines.unwrap();
    assert!(b.clean.crossings > 0 && b.constraints.segments > 0, "{b:?}");
}

#[test]
fn streamed_lines_on_points_rings_and_lone_vertices_give_the_in_memory_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mut pts = crate::synth::uniform(3_000, 5);
    // Points exactly on line vertices (duplicates merged with them).
    pts.push([200.0, 300.0, 7.0]);
    pts.push([500.0, 500.0, 9.0]);
    let z = 5.0;
    let ring = |x0: f64, y0: f64, x1: f64, y1: f64| {
        vec![
            [x0, y0, z],
            [x1, y0, z],
            [x1, y1, z],
            [x0, y1, z],
            [x0, y0, z],
        ]
    };
    let lines = vec![
        // Below every point: the first point of the sweep is a line vertex.
        vec![[100.0, -50.0, 1.0], [900.0, 450.0, 2.0]],
        vec![
            [200.0, 300.0, 3.0],
            [800.0, 300.0, 4.0],
            [500.0, 500.0, 6.0],
        ],
        // Crossing the others.
        vec![
            [150.0, 800.0, 1.0],
            [600.0, 100.0, 2.0],
            [650.0, 900.0, 8.0],
        ],
        // A lone vertex, and a line laid twice.
        vec![[333.0, 666.0, 1.5]],
        vec![[10.0, 10.0, 1.0], [20.0, 990.0, 1.0]],
        vec![[20.0, 990.0, 1.0], [10.0, 10.0, 1.0]],
    ];
    let (p, l) = files(dir.path(), &pts, &lines);
    let (b, h) = (dir.path().join("b.txt"), dir.path().join("h.txt"));
    write_lines(&b, &[ring(50.0, 50.0, 950.0, 950.0)]);
    write_lines(&h, &[ring(400.0, 600.0, 700.0, 800.0)]);
    for policy in [DuplicatePolicy::First, DuplicatePolicy::Last] {
        let o = LineOptions {
            breaklines: vec![l.clone()],
            ..LineOptions::default()
        };
        same(&p, &o, policy, 1 << 30);
        let o = LineOptions {
            breaklines: vec![l.clone()],
            boundary: Some(b.clone()),
            holes: Some(h.clone()),
            max_edge: Some(60.0),
            ..LineOptions::default()
        };
        let s = same(&p, &o, policy, 1 << 20);
        assert!(s.breaklines.unwrap().trimmed_triangles > 0);
    }
}

#[test]
fn streamed_lines_without_z_are_draped_as_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let nan = f64::NAN;
    let mut roads = crate::synth::roads(1_500, 7);
    // Every line without z, then half of them.
    for l in roads.iter_mut() {
        for p in l.iter_mut() {
            p[2] = nan;
        }
    }
    let pts = crate::synth::road_points(3_000, 7);
    let (p, l) = files(dir.path(), &pts, &roads);
    let o = LineOptions {
        breaklines: vec![l],
        ..LineOptions::default()
    };
    let s = same(&p, &o, DuplicatePolicy::First, 1 << 20);
    let b = s.breaklines.unwrap();
    assert_eq!(b.draped, b.vertices, "{b:?}");
    let mut mixed = crate::synth::roads(1_500, 7);
    for l in mixed.iter_mut().step_by(2) {
        for p in l.iter_mut() {
            p[2] = nan;
        }
    }
    let (p, l) = files(dir.path(), &pts, &mixed);
    let o = LineOptions {
        breaklines: vec![l],
        ..LineOptions::default()
    };
    let b = same(&p, &o, DuplicatePolicy::First, 1 << 20)
        .breaklines
        .unwrap();
    assert!(b.draped > 0 && b.draped < b.vertices, "{b:?}");
}

/// The streamed reader keeps no `Source` per polyline: a 2-D vertex outside the points' TIN is
/// still named by its line's file and line number (found by reading the file again).
#[test]
fn a_streamed_line_outside_the_points_is_named_by_its_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let nan = f64::NAN;
    let pts: Vec<[f64; 3]> = (0..100)
        .map(|i| [(i % 10) as f64, (i / 10) as f64, 1.0])
        .collect();
    let lines = [
        vec![[1.0, 1.0, nan], [2.0, 2.0, nan]],
        vec![[3.0, 3.0, nan], [4.0, 4.0, nan], [20.0, 4.0, nan]],
    ];
    let (p, l) = files(dir.path(), &pts, &lines);
    let o = LineOptions {
        breaklines: vec![l.clone()],
        ..LineOptions::default()
    };
    let input = Input {
        paths: vec![p],
        filter: crate::input::las::Filter::keep_all(),
        duplicates: DuplicatePolicy::First,
        lines: o.clone(),
    };
    let options = RunOptions {
        mem: 1 << 20,
        tmp_dir: Some(dir.path().to_path_buf()),
        progress: false,
        ..Default::default()
    };
    let config = RunConfig::new(input, options).unwrap();
    let points_only = config.points_only();
    let mut drape = |sink: &mut dyn super::super::TriangleSink| {
        drive::run(&points_only, None, None, &mut [sink]).map(|_| ())
    };
    let e = match lines::prepare_with(
        &o,
        config.read_lines(),
        Some(&mut drape),
        Some(config.line_budget()),
    ) {
        Ok(_) => panic!("a vertex outside the points was draped"),
        Err(e) => e.to_string(),
    };
    let want = format!("{}:4", l.display());
    assert!(e.contains(&want) && e.contains("(20, 4) has no z"), "{e}");
}
