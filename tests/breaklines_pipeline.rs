//! Breaklines and trimming through the streaming pipeline: the streamed constrained triangulation
//! equals the in-memory CDT whatever the memory budget, real BGT polygons over AHN3 lidar validate
//! as a CDT, trimming keeps exactly what it should, and bad line input is a clear error.

use crate::data;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use sweeptin::breaklines::{CleanOptions, read_file};
use sweeptin::pipeline::{Input, LineOptions, RunConfig, RunOptions, RunSummary, run};
use sweeptin::sink::{MeshSink, MeshSummary};
use sweeptin::validate::{CdtCheck, validate_cdt, validate_cdt_with};
use sweeptin::{DuplicatePolicy, Options, triangulate_cdt};

#[derive(Default)]
struct Collect {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    released: HashSet<u64>,
}

impl MeshSink for Collect {
    fn vertex(&mut self, p: [f64; 3]) -> sweeptin::Result<()> {
        self.vertices.push(p);
        Ok(())
    }
    fn triangle(&mut self, t: [u64; 3]) -> sweeptin::Result<()> {
        for v in t {
            assert!((v as usize) < self.vertices.len(), "vertex {v} not written");
            assert!(!self.released.contains(&v), "vertex {v} used after release");
        }
        self.triangles.push(t.map(|v| v as u32));
        Ok(())
    }
    fn vertex_done(&mut self, id: u64) -> sweeptin::Result<()> {
        assert!(self.released.insert(id), "vertex {id} released twice");
        Ok(())
    }
    fn finish(&mut self) -> sweeptin::Result<MeshSummary> {
        Ok(MeshSummary::default())
    }
}

type Key = [(u64, u64); 3];

fn key_set(vertices: &[[f64; 3]], tris: &[[u32; 3]]) -> Vec<Key> {
    let mut out: Vec<Key> = tris
        .iter()
        .map(|t| {
            let mut k = t.map(|i| {
                let p = vertices[i as usize];
                (p[0].to_bits(), p[1].to_bits())
            });
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

fn write_xyz(path: &Path, pts: &[[f64; 3]]) {
    let mut s = String::new();
    for p in pts {
        s.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
    }
    std::fs::write(path, s).unwrap();
}

/// The breakline text format: `x y [z]` per line, a blank line between polylines.
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

fn input(paths: &[PathBuf], lines: LineOptions) -> Input {
    Input {
        paths: paths.to_vec(),
        filter: sweeptin::input::las::Filter::keep_all(),
        duplicates: DuplicatePolicy::First,
        lines,
    }
}

fn streamed(input: &Input, mem: u64) -> (Collect, RunSummary) {
    let tmp = tempfile::tempdir().unwrap();
    let options = RunOptions {
        mem,
        tmp_dir: Some(tmp.path().to_path_buf()),
        progress: false,
        ..Default::default()
    };
    let mut c = Collect::default();
    let config = RunConfig::new(input.clone(), options).unwrap();
    let summary = run(&config, Some(&mut c), &mut []).unwrap();
    assert_eq!(summary.triangles as usize, c.triangles.len());
    assert_eq!(c.released.len(), c.vertices.len(), "every vertex released");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
    (c, summary)
}

fn breaklines(files: &[PathBuf]) -> LineOptions {
    LineOptions {
        breaklines: files.to_vec(),
        ..LineOptions::default()
    }
}

#[test]
fn streamed_contours_equal_the_in_memory_cdt() {
    let dir = tempfile::tempdir().unwrap();
    let pts_path = dir.path().join("pts.xyz");
    let lines_path = dir.path().join("contours.txt");
    let pts = sweeptin::synth::contour_points(20_000, 7);
    let lines = sweeptin::synth::contours(4_000, 7);
    write_xyz(&pts_path, &pts);
    write_lines(&lines_path, &lines);
    // Exactly what the readers parse.
    let mut all = sweeptin::input::read_xyz(&pts_path).unwrap();
    let parsed = read_file(&lines_path).unwrap();
    let mut segments = Vec::new();
    for l in &parsed.polylines {
        let base = all.len() as u32;
        all.extend_from_slice(l);
        for k in 1..l.len() as u32 {
            segments.push([base + k - 1, base + k]);
        }
    }
    let core = triangulate_cdt(&all, &segments, &Options::default()).unwrap();
    assert_eq!(core.constraint_stats.crossing_skipped, 0);
    let want = key_set(&core.vertices, &core.triangles);
    let input = input(&[pts_path], breaklines(&[lines_path]));
    let segs = parsed
        .clean(&CleanOptions::default())
        .unwrap()
        .segment_coords();
    for mem in [64 << 10, 1 << 30] {
        let (c, summary) = streamed(&input, mem);
        assert_eq!(key_set(&c.vertices, &c.triangles), want, "--mem {mem}");
        let b = summary.breaklines.expect("a breakline summary");
        assert_eq!(b.constraints.crossing_skipped, 0);
        assert!(b.constraints.segments > 1000);
        validate_cdt(&c.vertices, &c.triangles, &segs).unwrap();
    }
}

fn shared(name: &str) -> Option<PathBuf> {
    data::optional(name, "breaklines_pipeline")
}

/// BGT polylines lying inside `[x0, x1] × [y0, y1]`, as 2-D lines.
fn bgt_inside(x0: f64, x1: f64, y0: f64, y1: f64) -> Option<Vec<Vec<[f64; 3]>>> {
    let bgt = read_file(&shared("lines/bgt_delft_all_layers.geojson")?).unwrap();
    Some(
        bgt.polylines
            .into_iter()
            .filter(|l| {
                l.iter()
                    .all(|p| (x0..=x1).contains(&p[0]) && (y0..=y1).contains(&p[1]))
            })
            .map(|l| l.iter().map(|p| [p[0], p[1], f64::NAN]).collect())
            .collect(),
    )
}

#[test]
fn bgt_polygons_over_ahn3_validate_as_a_cdt() {
    let (Some(laz), Some(lines)) = (
        shared("lidar/ahn3_delft_cropped_2.laz"),
        bgt_inside(85001.0, 85071.0, 447415.0, 447639.0),
    ) else {
        return;
    };
    assert!(lines.len() > 100, "{} polylines", lines.len());
    let dir = tempfile::tempdir().unwrap();
    let lp = dir.path().join("bgt.txt");
    write_lines(&lp, &lines);
    let (c, summary) = streamed(
        &input(&[laz], breaklines(std::slice::from_ref(&lp))),
        4 << 20,
    );
    let b = summary.breaklines.unwrap();
    assert_eq!(b.draped, b.vertices, "every 2-D vertex draped");
    assert_eq!(b.constraints.crossing_skipped, 0);
    // Draped heights lie within the lidar's range.
    assert!(c.vertices.iter().all(|v| (-2.0..40.0).contains(&v[2])));
    let segs = read_file(&lp)
        .unwrap()
        .clean(&CleanOptions::default())
        .unwrap()
        .segment_coords();
    let report = validate_cdt(&c.vertices, &c.triangles, &segs).unwrap();
    assert!(report.constrained_edges >= segs.len() as u64);
}

/// A closed square ring with a vertex every 10 m (so that `--max-edge` keeps the triangles along
/// it).
fn square(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 3]> {
    let corners = [[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]];
    let mut out = Vec::new();
    for w in corners.windows(2) {
        let n = (((w[1][0] - w[0][0]).abs() + (w[1][1] - w[0][1]).abs()) / 10.0) as usize;
        for k in 0..n {
            let t = k as f64 / n as f64;
            let p = [
                w[0][0] + t * (w[1][0] - w[0][0]),
                w[0][1] + t * (w[1][1] - w[0][1]),
            ];
            out.push([p[0], p[1], f64::NAN]);
        }
    }
    out.push([x0, y0, f64::NAN]);
    out
}

#[test]
fn trimming_keeps_inside_boundary_outside_holes_and_short_edges() {
    let dir = tempfile::tempdir().unwrap();
    let pts_path = dir.path().join("pts.xyz");
    write_xyz(&pts_path, &sweeptin::synth::uniform(5_000, 11));
    let (b, h) = (dir.path().join("b.txt"), dir.path().join("h.txt"));
    write_lines(&b, &[square(100.0, 100.0, 900.0, 900.0)]);
    write_lines(&h, &[square(400.0, 400.0, 600.0, 600.0)]);
    let opts = LineOptions {
        boundary: Some(b.clone()),
        holes: Some(h.clone()),
        max_edge: Some(40.0),
        ..LineOptions::default()
    };
    let (c, summary) = streamed(&input(std::slice::from_ref(&pts_path), opts), 1 << 30);
    let s = summary.breaklines.unwrap();
    assert!(s.trimmed_triangles > 0);
    // Every written vertex is used (written lazily).
    let used: HashSet<u32> = c.triangles.iter().flatten().copied().collect();
    assert_eq!(used.len(), c.vertices.len());
    let mut area = 0.0;
    for t in &c.triangles {
        let p = t.map(|i| c.vertices[i as usize]);
        let cx = (p[0][0] + p[1][0] + p[2][0]) / 3.0;
        let cy = (p[0][1] + p[1][1] + p[2][1]) / 3.0;
        assert!((100.0..=900.0).contains(&cx) && (100.0..=900.0).contains(&cy));
        assert!(!((400.0..=600.0).contains(&cx) && (400.0..=600.0).contains(&cy)));
        for k in 0..3 {
            let (a, q) = (p[k], p[(k + 1) % 3]);
            assert!(((q[0] - a[0]).powi(2) + (q[1] - a[1]).powi(2)).sqrt() <= 40.0);
        }
        area += ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
            - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]))
            / 2.0;
    }
    // Uniform points about 14 m apart: with max-edge 40 most of the 800² − 200² area is kept.
    assert!(area > 0.9 * 600_000.0 && area <= 600_000.0, "area {area}");
    // Without it, exactly that area.
    let opts = LineOptions {
        boundary: Some(b.clone()),
        holes: Some(h.clone()),
        ..LineOptions::default()
    };
    let (all, _) = streamed(&input(std::slice::from_ref(&pts_path), opts), 1 << 30);
    let total: f64 = all
        .triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| all.vertices[i as usize]);
            ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]))
                / 2.0
        })
        .sum();
    assert!((total - 600_000.0).abs() < 1e-6, "area {total}");
    let segs = [
        square(100.0, 100.0, 900.0, 900.0),
        square(400.0, 400.0, 600.0, 600.0),
    ]
    .iter()
    .flat_map(|r| {
        r.windows(2)
            .map(|w| [[w[0][0], w[0][1]], [w[1][0], w[1][1]]])
    })
    .collect::<Vec<_>>();
    let check = CdtCheck {
        convex_hull: false,
        delaunay: true,
    };
    validate_cdt_with(&c.vertices, &c.triangles, &segs, &check).unwrap();
}

#[test]
fn crossing_lines_are_split_and_z_conflicts_reported() {
    let dir = tempfile::tempdir().unwrap();
    let pts_path = dir.path().join("pts.xyz");
    write_xyz(&pts_path, &sweeptin::synth::uniform(2_000, 3));
    let lp = dir.path().join("x.txt");
    write_lines(
        &lp,
        &[
            vec![[100.0, 100.0, 10.0], [900.0, 900.0, 10.0]],
            vec![[100.0, 900.0, 20.0], [900.0, 100.0, 20.0]],
        ],
    );
    let (c, summary) = streamed(&input(&[pts_path], breaklines(&[lp])), 1 << 30);
    let b = summary.breaklines.unwrap();
    assert_eq!(b.clean.crossings, 1);
    assert_eq!(b.clean.z_conflicts, 1);
    assert_eq!(b.z_conflicts.len(), 1);
    assert!(c.vertices.iter().any(|v| v[..2] == [500.0, 500.0]));
}

#[test]
fn flat_triangles_are_flipped_away() {
    let dir = tempfile::tempdir().unwrap();
    let pts_path = dir.path().join("pts.xyz");
    let lp = dir.path().join("contours.txt");
    // Sparse points between dense contours: many triangles span two vertices of one line.
    write_xyz(&pts_path, &sweeptin::synth::contour_points(300, 5));
    write_lines(&lp, &sweeptin::synth::contours(6_000, 5));
    let mut opts = breaklines(std::slice::from_ref(&lp));
    let (_, plain) = streamed(
        &input(std::slice::from_ref(&pts_path), opts.clone()),
        1 << 30,
    );
    opts.no_flat_triangles = true;
    let (c, summary) = streamed(&input(&[pts_path], opts), 1 << 30);
    assert_eq!(plain.triangles, summary.triangles);
    let flat = summary.breaklines.unwrap().flat.unwrap();
    assert!(flat.flat > 0 && flat.flips > 0, "{flat:?}");
    assert!(flat.remaining < flat.flat, "{flat:?}");
    let segs = read_file(&lp)
        .unwrap()
        .clean(&CleanOptions::default())
        .unwrap()
        .segment_coords();
    let check = CdtCheck {
        convex_hull: true,
        delaunay: false,
    };
    validate_cdt_with(&c.vertices, &c.triangles, &segs, &check).unwrap();
}

#[test]
fn a_2d_line_outside_the_points_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let pts_path = dir.path().join("pts.xyz");
    write_xyz(&pts_path, &sweeptin::synth::uniform(500, 3));
    let lp = dir.path().join("far.txt");
    write_lines(
        &lp,
        &[vec![[500.0, 500.0, f64::NAN], [5000.0, 500.0, f64::NAN]]],
    );
    let tmp = tempfile::tempdir().unwrap();
    let options = RunOptions {
        mem: 1 << 20,
        tmp_dir: Some(tmp.path().to_path_buf()),
        progress: false,
        ..Default::default()
    };
    let config = RunConfig::new(input(&[pts_path], breaklines(&[lp])), options).unwrap();
    let err = run(&config, None, &mut []).unwrap_err().to_string();
    assert!(err.contains("far.txt") && err.contains("no z"), "{err}");
    // The same line with z extends the TIN instead.
    let lz = dir.path().join("far_z.txt");
    write_lines(&lz, &[vec![[500.0, 500.0, 1.0], [5000.0, 500.0, 2.0]]]);
    let pts_path = dir.path().join("pts.xyz");
    let (c, _) = streamed(&input(&[pts_path], breaklines(&[lz])), 1 << 30);
    assert!(c.vertices.iter().any(|v| v[0] == 5000.0));
}
