//! `sweeptin refine` and `sweeptin::refine`: quality refinement proved against its promises on
//! synthetic planar straight-line graphs and on real breaklines (the BGT partition of Delft):
//!
//! * smallest angle ≥ the bound: computed at each corner from `f64` edge vectors as
//!   `cos = u·v / (|u| |v|)` and compared with `cos(bound)` with a margin of 1e-12 (the rounding
//!   of these few operations is below 1e-15 relative, so this proves the angle to ~1e-10°);
//!   only the triangles the algorithm documents as unfixable (at input angles below 60°) may
//!   fall short, and they are counted in `stats.skinny`;
//! * every input segment is the union of output edges, each flagged constrained, whose
//!   intermediate vertices lie on the segment (within a few units in the last place of their
//!   coordinates plus 1e-12 of its length: a split point is rounded once) and advance along it;
//! * every Steiner point's z is the original surface's at its xy (free points: the input
//!   triangle holding it, found here by brute force) or the segment's line (segment points);
//! * the output is the constrained Delaunay triangulation of its own vertices and constrained
//!   edges: spade's CDT of them holds every output triangle, or a cocircular twin of it (an exact
//!   in-circle tie), and sweeptin's validator agrees.

use crate::data;
use crate::geojson;

use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation as _};
use std::collections::HashSet;
use sweeptin::geom::predicates::{CircleSide, incircle_exact};
use sweeptin::refine::{RefineOptions, Refined, VertexKind, refine, refine_pslg};

/// A domain mesh: the CDT of `points` and `segments` without the triangles whose centroid lies
/// in one of the `holes` (axis-aligned boxes).
fn domain(
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
    holes: &[[f64; 4]],
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let t = sweeptin::triangulate_cdt(points, segments, &sweeptin::Options::default()).unwrap();
    let tris = t
        .triangles
        .iter()
        .copied()
        .filter(|tri| {
            let c = tri.iter().fold([0.0, 0.0], |c, &v| {
                let p = t.vertices[v as usize];
                [c[0] + p[0] / 3.0, c[1] + p[1] / 3.0]
            });
            !holes
                .iter()
                .any(|h| c[0] > h[0] && c[0] < h[2] && c[1] > h[1] && c[1] < h[3])
        })
        .collect();
    (t.vertices, tris)
}

/// A closed polygon's segments over vertex indices `first..first + n`.
fn ring(first: u32, n: u32) -> Vec<[u32; 2]> {
    (0..n).map(|i| [first + i, first + (i + 1) % n]).collect()
}

fn plane(x: f64, y: f64) -> f64 {
    10.0 + 0.02 * x - 0.03 * y + 0.0001 * x * y
}

/// Smallest angle of a triangle above `bound` degrees (see the module docs)?
fn meets(t: [[f64; 3]; 3], bound: f64) -> bool {
    let c = bound.to_radians().cos();
    (0..3).all(|k| {
        let (o, p, q) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        let (u, v) = ([p[0] - o[0], p[1] - o[1]], [q[0] - o[0], q[1] - o[1]]);
        let cos = (u[0] * v[0] + u[1] * v[1]) / (u[0].hypot(u[1]) * v[0].hypot(v[1]));
        cos <= c + 1e-12
    })
}

/// Height of the input mesh at `p`, by brute force.
fn height(vertices: &[[f64; 3]], tris: &[[u32; 3]], p: [f64; 2]) -> Option<f64> {
    for t in tris {
        let [a, b, c] = t.map(|v| vertices[v as usize]);
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        let wb = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
        let wc = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
        let eps = 1e-12;
        if wb >= -eps && wc >= -eps && wb + wc <= 1.0 + eps {
            return Some(a[2] + wb * (b[2] - a[2]) + wc * (c[2] - a[2]));
        }
    }
    None
}

/// Checks every promise (module docs) of `r`, refined from the mesh `vertices`/`tris` with the
/// input segments `segments` (coordinates) at `bound` degrees.
fn check(
    r: &Refined,
    vertices: &[[f64; 3]],
    tris: &[[u32; 3]],
    segments: &[[[f64; 2]; 2]],
    bound: f64,
) {
    assert!(!r.triangles.is_empty());
    // Angles.
    let bad = r
        .triangles
        .iter()
        .filter(|t| !meets(t.map(|v| r.vertices[v as usize]), bound))
        .count();
    assert_eq!(bad as u64, r.stats.skinny, "triangles below the bound");
    // Constraints: chains of constrained output edges.
    let constrained: HashSet<[u32; 2]> = r.constrained.iter().copied().collect();
    let mut adj = vec![Vec::new(); r.vertices.len()];
    for &[a, b] in &r.constrained {
        adj[a as usize].push(b);
        adj[b as usize].push(a);
    }
    let index: std::collections::HashMap<(u64, u64), u32> = r
        .vertices
        .iter()
        .enumerate()
        .map(|(i, p)| ((p[0].to_bits(), p[1].to_bits()), i as u32))
        .collect();
    for s in segments {
        let at = |p: [f64; 2]| index.get(&(p[0].to_bits(), p[1].to_bits())).copied();
        let (a, b) = (
            at(s[0]).expect("segment end"),
            at(s[1]).expect("segment end"),
        );
        let (d, len2) = {
            let d = [s[1][0] - s[0][0], s[1][1] - s[0][1]];
            (d, d[0] * d[0] + d[1] * d[1])
        };
        let along = |v: u32| {
            let p = r.vertices[v as usize];
            let w = [p[0] - s[0][0], p[1] - s[0][1]];
            // Distance to the line, against a few units in the last place of the coordinates
            // (a split point is rounded once) plus 1e-12 of the length.
            let dist = (w[0] * d[1] - w[1] * d[0]).abs() / len2.sqrt();
            let tol = 1e-14 * (p[0].abs() + p[1].abs()) + 1e-12 * len2.sqrt();
            ((w[0] * d[0] + w[1] * d[1]) / len2, dist / tol)
        };
        let (mut v, mut t) = (a, 0.0);
        while v != b {
            let next = adj[v as usize]
                .iter()
                .copied()
                .filter(|&w| {
                    let (tw, off) = along(w);
                    off <= 1.0 && tw > t && tw <= 1.0 + 1e-12
                })
                .min_by(|&x, &y| along(x).0.total_cmp(&along(y).0))
                .unwrap_or_else(|| panic!("segment {s:?} is not made of output edges"));
            assert!(constrained.contains(&[v.min(next), v.max(next)]));
            t = along(next).0;
            v = next;
        }
    }
    // Heights of the Steiner points.
    for (i, p) in r.vertices.iter().enumerate() {
        match r.kinds[i] {
            VertexKind::Input => {}
            VertexKind::Free => {
                let h = height(vertices, tris, [p[0], p[1]]).expect("Steiner point in the mesh");
                assert!((h - p[2]).abs() <= 1e-9 * (1.0 + h.abs()), "{p:?} vs {h}");
            }
            VertexKind::Segment => {
                // On a constrained edge between two vertices whose line gives its height.
                let n = &adj[i];
                assert!(n.len() >= 2, "segment point {p:?} on no segment");
                let (q, w) = (r.vertices[n[0] as usize], r.vertices[n[1] as usize]);
                let t = ((p[0] - q[0]) * (w[0] - q[0]) + (p[1] - q[1]) * (w[1] - q[1]))
                    / ((w[0] - q[0]).powi(2) + (w[1] - q[1]).powi(2));
                let z = q[2] + t * (w[2] - q[2]);
                assert!((z - p[2]).abs() <= 1e-9 * (1.0 + z.abs()), "{p:?} vs {z}");
            }
        }
    }
    // Constrained Delaunay: spade's CDT of the output vertices and constrained edges.
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(
        r.vertices.iter().map(|p| Point2::new(p[0], p[1])).collect(),
        r.constrained
            .iter()
            .map(|e| [e[0] as usize, e[1] as usize])
            .collect(),
    )
    .unwrap();
    let _ = &mut cdt;
    let key = |mut t: [usize; 3]| {
        t.sort_unstable();
        t
    };
    let theirs: HashSet<[usize; 3]> = cdt
        .inner_faces()
        .map(|f| key(f.vertices().map(|v| v.fix().index())))
        .collect();
    let ours: HashSet<[usize; 3]> = r
        .triangles
        .iter()
        .map(|t| key(t.map(|v| v as usize)))
        .collect();
    let xy = |v: usize| [r.vertices[v][0], r.vertices[v][1]];
    let mut ties = 0;
    for t in &r.triangles {
        if theirs.contains(&key(t.map(|v| v as usize))) {
            continue;
        }
        // Not in spade's CDT: only allowed when a neighbour's apex is exactly on its circle.
        let [a, b, c] = t.map(|v| v as usize);
        let cocircular = r.vertices.iter().enumerate().any(|(d, _)| {
            d != a
                && d != b
                && d != c
                && incircle_exact(xy(a), xy(b), xy(c), xy(d)) == CircleSide::On
        });
        assert!(cocircular, "triangle {t:?} is not in spade's CDT");
        ties += 1;
    }
    assert!(ties * 20 <= r.triangles.len(), "{ties} ties");
    assert!(ours.len() == r.triangles.len());
    let report = sweeptin::validate::validate_cdt_with(
        &r.vertices,
        &r.triangles,
        &r.constrained
            .iter()
            .map(|e| e.map(|v| xy(v as usize)))
            .collect::<Vec<_>>(),
        &sweeptin::validate::CdtCheck {
            convex_hull: false,
            delaunay: true,
        },
    );
    report.expect("sweeptin's validator");
}

/// A square with a zig-zag breakline and a square hole.
/// Points, segments and hole boxes of a PSLG.
type Pslg = (Vec<[f64; 3]>, Vec<[u32; 2]>, Vec<[f64; 4]>);

fn square_pslg() -> Pslg {
    let mut pts: Vec<[f64; 3]> = vec![];
    for &(x, y) in &[(0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0)] {
        pts.push([x, y, plane(x, y)]);
    }
    let mut segs = ring(0, 4);
    // Hole 60..80 × 60..80.
    for &(x, y) in &[(60.0, 60.0), (80.0, 60.0), (80.0, 80.0), (60.0, 80.0)] {
        pts.push([x, y, plane(x, y)]);
    }
    segs.extend(ring(4, 4));
    // Zig-zag breakline (angles of about 70° between its pieces).
    let first = pts.len() as u32;
    for i in 0..6 {
        let (x, y) = (10.0 + 8.0 * i as f64, if i % 2 == 0 { 20.0 } else { 34.0 });
        pts.push([x, y, plane(x, y) + 1.0]);
    }
    segs.extend((0..5).map(|i| [first + i, first + i + 1]));
    (pts, segs, vec![[60.0, 60.0, 80.0, 80.0]])
}

fn as_lines(pts: &[[f64; 3]], segs: &[[u32; 2]]) -> Vec<[[f64; 3]; 2]> {
    segs.iter().map(|s| s.map(|v| pts[v as usize])).collect()
}

fn coords(pts: &[[f64; 3]], segs: &[[u32; 2]]) -> Vec<[[f64; 2]; 2]> {
    segs.iter()
        .map(|s| s.map(|v| [pts[v as usize][0], pts[v as usize][1]]))
        .collect()
}

#[test]
fn square_with_breakline_and_hole() {
    let (pts, segs, holes) = square_pslg();
    let (v, t) = domain(&pts, &segs, &holes);
    let o = RefineOptions::default();
    let lines = as_lines(&pts, &segs[8..]);
    let r = refine(&v, &t, &lines, &o).unwrap();
    assert_eq!(r.stats.breakline_segments, 5);
    assert_eq!(r.stats.skinny, 0);
    assert!(r.stats.min_angle >= 30.0, "{:?}", r.stats);
    check(&r, &v, &t, &coords(&pts, &segs), 30.0);
    // No triangle inside the hole.
    for tri in &r.triangles {
        let c = tri.iter().fold([0.0, 0.0], |c, &i| {
            let p = r.vertices[i as usize];
            [c[0] + p[0] / 3.0, c[1] + p[1] / 3.0]
        });
        assert!(!(c[0] > 60.0 && c[0] < 80.0 && c[1] > 60.0 && c[1] < 80.0));
    }
    // Deterministic.
    let again = refine(&v, &t, &lines, &o).unwrap();
    assert_eq!(again.vertices, r.vertices);
    assert_eq!(again.triangles, r.triangles);
}

#[test]
fn small_input_angles_terminate() {
    // A square with two segments from its corner at about 8° and 4° from its bottom edge: input
    // angles that no refinement can fix. It must end, leave only triangles at those wedges under
    // the bound, and meet it everywhere else.
    let mut pts: Vec<[f64; 3]> = [(0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0)]
        .iter()
        .map(|&(x, y)| [x, y, plane(x, y)])
        .collect();
    let mut segs = ring(0, 4);
    for &(x, y) in &[(100.0, 14.0), (90.0, 6.3)] {
        pts.push([x, y, plane(x, y)]);
        segs.push([0, pts.len() as u32 - 1]);
    }
    let (v, t) = domain(&pts, &segs, &[]);
    let lines = as_lines(&pts, &segs[4..]);
    let r = refine(&v, &t, &lines, &RefineOptions::default()).unwrap();
    check(&r, &v, &t, &coords(&pts, &segs), 30.0);
    assert!(r.stats.skinny > 0 && r.stats.skinny < 20, "{:?}", r.stats);
    // Every skinny triangle sits in a wedge: each of its vertices is on a segment from the
    // corner (or is the corner).
    let on_ray = |p: [f64; 3]| {
        [[100.0, 0.0], [100.0, 14.0], [90.0, 6.3]]
            .iter()
            .any(|d: &[f64; 2]| (p[0] * d[1] - p[1] * d[0]).abs() <= 1e-9 * 100.0 * 100.0)
    };
    for tri in &r.triangles {
        let p = tri.map(|i| r.vertices[i as usize]);
        if !meets(p, 30.0) {
            assert!(
                p.iter().all(|&q| on_ray(q)),
                "skinny triangle {p:?} off the wedges"
            );
        }
    }
}

#[test]
fn max_area_bounds_every_triangle() {
    let (pts, segs, holes) = square_pslg();
    let (v, t) = domain(&pts, &segs, &holes);
    let o = RefineOptions {
        min_angle: 25.0,
        max_area: Some(20.0),
        ..RefineOptions::default()
    };
    let r = refine(&v, &t, &as_lines(&pts, &segs[8..]), &o).unwrap();
    check(&r, &v, &t, &coords(&pts, &segs), 25.0);
    assert_eq!(r.stats.skinny, 0);
    assert!(r.stats.max_area <= 20.0, "{:?}", r.stats);
    assert!(r.triangles.len() >= 9600 / 20);
}

#[test]
fn bad_input_is_refused() {
    let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let bad = |t: &[[u32; 3]], o: &RefineOptions| refine(&v, t, &[], o).unwrap_err().to_string();
    let o = RefineOptions::default();
    assert!(bad(&[[0, 2, 1]], &o).contains("clockwise"));
    assert!(bad(&[[0, 1, 3]], &o).contains("beyond"));
    let steep = RefineOptions {
        min_angle: 40.0,
        ..o
    };
    assert!(bad(&[[0, 1, 2]], &steep).contains("34"));
    // A breakline that leaves the mesh is left out and counted.
    let out = [[[0.2, 0.2, f64::NAN], [3.0, 3.0, f64::NAN]]];
    let r = refine(&v, &[[0, 1, 2]], &out, &o).unwrap();
    assert_eq!(r.stats.breakline_segments_outside, 1);
}

/// The BGT partition of Delft (real breaklines: a planar partition with segments down to 1 mm
/// and many small angles), in an 60 m window, refined at 30° and checked like the synthetic
/// graphs.
#[test]
fn real_bgt_breaklines() {
    let path = data::shared("lines/bgt_delft_all_layers.geojson");
    let g = sweeptin::breaklines::read_files(&[path])
        .unwrap()
        .clean(&Default::default())
        .unwrap();
    let (lo, hi) = ([84920.0, 447500.0], [84980.0, 447560.0]);
    let inside = |p: [f64; 3]| {
        p[0] > lo[0] + 0.5 && p[0] < hi[0] - 0.5 && p[1] > lo[1] + 0.5 && p[1] < hi[1] - 0.5
    };
    let mut pts: Vec<[f64; 3]> = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]]
        .iter()
        .map(|p| [p[0], p[1], plane(p[0] - lo[0], p[1] - lo[1])])
        .collect();
    let mut segs = ring(0, 4);
    let mut id = std::collections::HashMap::new();
    for s in &g.segments {
        let [a, b] = s.map(|v| g.vertices[v as usize]);
        if !(inside(a) && inside(b)) {
            continue;
        }
        let ends = s.map(|v| {
            *id.entry(v).or_insert_with(|| {
                let p = g.vertices[v as usize];
                pts.push([p[0], p[1], plane(p[0] - lo[0], p[1] - lo[1])]);
                pts.len() as u32 - 1
            })
        });
        segs.push(ends);
    }
    assert!(segs.len() > 100, "{} segments in the window", segs.len());
    let (v, t) = domain(&pts, &segs, &[]);
    // 2-D breaklines: their heights come from the mesh.
    let lines: Vec<[[f64; 3]; 2]> = segs[4..]
        .iter()
        .map(|s| s.map(|i| [pts[i as usize][0], pts[i as usize][1], f64::NAN]))
        .collect();
    let r = refine(&v, &t, &lines, &RefineOptions::default()).unwrap();
    check(&r, &v, &t, &coords(&pts, &segs), 30.0);
    eprintln!("real_bgt_breaklines: {:?}", r.stats);
    assert!(r.stats.skinny * 100 < r.stats.triangles, "{:?}", r.stats);
}

fn sweeptin(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap()
}

/// `sweeptin refine MESH.ply --breaklines F -o OUT.2dm --json`, and its refusals.
#[test]
fn cli_mesh_to_2dm() {
    use sweeptin::sink::MeshSink;
    let dir = tempfile::tempdir().unwrap();
    let (pts, segs, holes) = square_pslg();
    let (v, t) = domain(&pts, &segs, &holes);
    let ply = dir.path().join("in.ply");
    let mut w = sweeptin::output::PlyWriter::create(&ply, &Default::default()).unwrap();
    v.iter().for_each(|&p| w.vertex(p).unwrap());
    t.iter()
        .for_each(|&tri| w.triangle(tri.map(u64::from)).unwrap());
    w.finish().unwrap();
    // The zig-zag as a 2-D GeoJSON line: its heights come from the mesh.
    let zig: Vec<[f64; 2]> = (8..14).map(|i| [pts[i][0], pts[i][1]]).collect();
    let lines = dir.path().join("zig.geojson");
    geojson::write_lines(&lines, &[zig]);
    let out = dir.path().join("out.2dm");
    let (p, l, o) = (
        ply.to_str().unwrap(),
        lines.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let r = sweeptin(&["refine", p, "--breaklines", l, "-o", o, "--json"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let stats = &json["stats"];
    assert!(stats["min_angle"].as_f64().unwrap() >= 30.0, "{json}");
    assert_eq!(stats["skinny"], 0);
    assert_eq!(stats["breakline_segments"], 5);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.starts_with("MESH2D\n"));
    let count = |card: &str| text.lines().filter(|l| l.starts_with(card)).count() as u64;
    assert_eq!(count("ND "), stats["vertices"].as_u64().unwrap());
    assert_eq!(count("E3T "), stats["triangles"].as_u64().unwrap());
    // The same mesh as the library makes, byte for byte in PLY.
    let lib = refine(
        &v,
        &t,
        &as_lines(&pts, &segs[8..]),
        &RefineOptions::default(),
    )
    .unwrap();
    assert_eq!(lib.stats.vertices, stats["vertices"].as_u64().unwrap());
    // Refusals: a bound past 34° and --boundary on a mesh (usage, 2); a clockwise mesh (input, 3).
    let r = sweeptin(&["refine", p, "--min-angle", "40", "-o", o]);
    assert_eq!(r.status.code(), Some(2));
    let r = sweeptin(&["refine", p, "--boundary", l, "-o", o]);
    assert_eq!(
        r.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let bad = dir.path().join("cw.ply");
    let mut w = sweeptin::output::PlyWriter::create(&bad, &Default::default()).unwrap();
    for q in [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]] {
        w.vertex(q).unwrap();
    }
    w.triangle([0, 1, 2]).unwrap();
    w.finish().unwrap();
    let o2 = dir.path().join("cw.2dm");
    let r = sweeptin(&["refine", bad.to_str().unwrap(), "-o", o2.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(3));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("clockwise"), "{err}");
    assert!(!o2.exists());
}

/// Issue 41, item 12: `refine --max-area 1e-6` ran to --max-steiner, then said "the angle bound
/// cannot be met (… a bound above 34°?)". The output `--max-area` implies (the domain's area /
/// max-area triangles) is checked against `--mem` and `--max-steiner` before refining: exit 2,
/// naming the size and the smallest bound that fits.
#[test]
fn a_max_area_beyond_memory_is_refused_before_refining() {
    use sweeptin::sink::MeshSink;
    let (pts, segs, holes) = square_pslg();
    let (v, t) = domain(&pts, &segs, &holes);
    let lines = as_lines(&pts, &segs[8..]);
    let o = RefineOptions {
        max_area: Some(1e-6),
        mem: Some(1 << 30),
        ..RefineOptions::default()
    };
    let e = refine(&v, &t, &lines, &o).unwrap_err();
    let msg = e.to_string();
    assert_eq!(e.kind(), sweeptin::ErrorKind::Usage, "{msg}");
    assert!(
        msg.contains("--max-area 0.000001: the domain's area of 9600")
            && msg.contains("makes at least 9.60e9 triangles")
            && msg.contains("more than --mem 1.0 GiB; give --max-area 0.0013 or more"),
        "{msg}"
    );
    // The smallest bound it names fits.
    let fits = RefineOptions {
        max_area: Some(0.0013),
        max_steiner: Some(0),
        ..o
    };
    let msg = refine(&v, &t, &lines, &fits).unwrap_err().to_string();
    assert!(!msg.contains("--mem"), "{msg}");
    // Within memory, past --max-steiner: named up front too.
    assert!(
        msg.contains("more than --max-steiner 0; give --max-area"),
        "{msg}"
    );
    // The command line: exit 2 before refining, nothing written.
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("in.ply");
    let mut w = sweeptin::output::PlyWriter::create(&ply, &Default::default()).unwrap();
    v.iter().for_each(|&p| w.vertex(p).unwrap());
    t.iter()
        .for_each(|&tri| w.triangle(tri.map(u64::from)).unwrap());
    w.finish().unwrap();
    let out = dir.path().join("out.ply");
    let r = sweeptin(&[
        "refine",
        ply.to_str().unwrap(),
        "--max-area",
        "1e-6",
        "--mem",
        "256M",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(err.contains("more than --mem 256.0 MiB"), "{err}");
    assert!(!err.contains("angle bound"), "{err}");
    assert!(!out.exists());
}

/// Issue 41, item 13: `refine` wrote "min angle 30°" in its PLY header, which `plyfile`
/// decodes as ASCII (UnicodeDecodeError). The header is ASCII.
#[test]
fn refine_writes_an_ascii_ply_header() {
    use sweeptin::sink::MeshSink;
    let (pts, segs, holes) = square_pslg();
    let (v, t) = domain(&pts, &segs, &holes);
    let dir = tempfile::tempdir().unwrap();
    // A file name that is not ASCII goes into the comment too.
    let ply = dir.path().join("in – é.ply");
    let mut w = sweeptin::output::PlyWriter::create(&ply, &Default::default()).unwrap();
    v.iter().for_each(|&p| w.vertex(p).unwrap());
    t.iter()
        .for_each(|&tri| w.triangle(tri.map(u64::from)).unwrap());
    w.finish().unwrap();
    let out = dir.path().join("out.ply");
    let r = sweeptin(&["refine", ply.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let bytes = std::fs::read(&out).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap();
    let head = &bytes[..end];
    assert!(head.is_ascii(), "{}", String::from_utf8_lossy(head));
    let head = String::from_utf8_lossy(head);
    assert!(head.contains("min angle 30 degrees"), "{head}");
    assert!(head.contains("in - <U+00E9>.ply"), "{head}");
}

/// Real lidar ground points (IGN, 22,332 points) as FILES: triangulated as `tin` does, refined.
#[test]
fn cli_real_points() {
    let las = data::shared("lidar/ign_50m_tiles/test_data_77055_627760_LA93_IGN69_ground.las");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mesh.ply");
    let r = sweeptin(&[
        "refine",
        las.to_str().unwrap(),
        "--min-angle",
        "28",
        "--max-area",
        "4",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let s = &json["stats"];
    assert_eq!(s["input_vertices"], 22332, "{json}");
    assert!(s["min_angle"].as_f64().unwrap() >= 28.0, "{json}");
    assert!(s["max_area"].as_f64().unwrap() <= 4.0, "{json}");
    assert_eq!(s["skinny"], 0);
    let (v, t) = sweeptin::input::read_ply(&out).unwrap();
    assert_eq!(v.len() as u64, s["vertices"].as_u64().unwrap());
    assert!(t.iter().all(|tri| meets(tri.map(|i| v[i as usize]), 28.0)));
    // The output pass runs in two halves side by side: one thread gives the same bytes.
    let one = dir.path().join("one.ply");
    let r = sweeptin(&[
        "refine",
        las.to_str().unwrap(),
        "--min-angle",
        "28",
        "--max-area",
        "4",
        "--threads",
        "1",
        "-o",
        one.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        std::fs::read(&one).unwrap() == std::fs::read(&out).unwrap(),
        "--threads 1 differs"
    );
}

/// `refine_pslg` (Triangle's `-pq`: the graph's CDT, outside regions eaten from the hull) makes
/// the same mesh as `refine` on that CDT with the segments as breaklines.
#[test]
fn pslg_in_quality_mesh_out() {
    let (pts, segs, _) = square_pslg();
    // The hole's ring stays a breakline: no hole without hole points.
    let r = refine_pslg(&pts, &segs, &RefineOptions::default()).unwrap();
    let (v, t) = domain(&pts, &segs, &[]);
    check(&r, &v, &t, &coords(&pts, &segs), 30.0);
    let m = refine(
        &v,
        &t,
        &as_lines(&pts, &segs[4..]),
        &RefineOptions::default(),
    )
    .unwrap();
    assert_eq!(m.triangles.len(), r.triangles.len());
    // A graph open to the hull: a polygon inside a point cloud's hull is refined inside only.
    let mut p2 = pts[..8].to_vec();
    p2.push([-50.0, -50.0, 0.0]);
    let inner = ring(4, 4);
    let r = refine_pslg(&p2, &inner, &RefineOptions::default()).unwrap();
    assert!(
        r.vertices.iter().all(|p| p[0] >= 60.0 && p[0] <= 80.0),
        "{:?}",
        r.stats
    );
}
