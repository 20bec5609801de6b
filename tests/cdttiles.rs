//! Breaklines and trimming in exact tiles (issue 11, item 4): the tiled constrained triangulation
//! has exactly the triangles of the single streaming sweep's, itself checked against spade's
//! constrained Delaunay triangulation here, on random points with random segments cut into small
//! tiles (long segments across many tiles, ends at lidar points under both duplicate policies,
//! boundary and hole rings), and on real lidar with real breaklines (IGN LiDAR HD with IGN's
//! constraint lines, AHN3 with the BGT polygons), plus a long line across several tiles and one
//! along a tile edge; the CLI's DEM is the sweep's, byte for byte, for any `--threads` and
//! `--mem`.

use crate::cli;
use crate::data;
use crate::mesh;

use mesh::{Key, write_las};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation as _};
use std::path::{Path, PathBuf};
use sweeptin::DuplicatePolicy;
use sweeptin::geom::predicates::{Orientation, orient};
use sweeptin::pipeline::{Input, LineOptions};
use sweeptin::synth::SplitMix64;

/// The world double of `n` millimetres east (or north) of `origin` metres, as the LAS reader
/// makes it (the nearest double of the decimal value).
fn mm(origin: i64, n: i64) -> f64 {
    (origin * 1000 + n) as f64 / 1000.0
}

const X0: i64 = 500_000;
const Y0: i64 = 4_000_000;

/// Do the closed segments `a-b` and `c-d` meet?
fn meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    let col = Orientation::Collinear;
    let within = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    if o1 != o2 && o3 != o4 && o1 != col && o2 != col && o3 != col && o4 != col {
        return true;
    }
    (o1 == col && within(a, b, c))
        || (o2 == col && within(a, b, d))
        || (o3 == col && within(c, d, a))
        || (o4 == col && within(c, d, b))
}

/// Random points on a 1 mm lattice in a 100 m square (relative to the LAS origin) and random
/// breakline segments with z, in world coordinates: disjoint, no point on one except at its
/// ends; a third of the ends are lidar points; one in five is up to 100 m long (across many
/// tiles).
fn random_case(seed: u64, n: usize, m: usize) -> (Vec<[f64; 3]>, Vec<[[f64; 3]; 2]>) {
    let mut r = SplitMix64::uniform(seed);
    let lattice: Vec<[i64; 2]> = (0..n)
        .map(|_| [(r() * 100_000.0) as i64, (r() * 100_000.0) as i64])
        .collect();
    let pts: Vec<[f64; 3]> = lattice
        .iter()
        .map(|p| {
            [
                p[0] as f64 / 1000.0,
                p[1] as f64 / 1000.0,
                (r() * 10_000.0).round() / 1000.0,
            ]
        })
        .collect();
    let world: Vec<[f64; 2]> = lattice
        .iter()
        .map(|p| [mm(X0, p[0]), mm(Y0, p[1])])
        .collect();
    let mut segs: Vec<[[f64; 3]; 2]> = Vec::new();
    let mut tries = 0;
    while segs.len() < m && tries < 200 * m {
        tries += 1;
        let long = segs.len().is_multiple_of(5);
        let (u, v) = (r() < 0.33, r() < 0.33 && !long);
        let mut end = |at_point: bool, near: Option<[i64; 2]>| -> [i64; 2] {
            if at_point {
                lattice[(r() * n as f64) as usize]
            } else {
                let span = if long { 100_000.0 } else { 12_000.0 };
                match near {
                    Some(p) => [
                        (p[0] + ((r() - 0.5) * span) as i64).clamp(0, 99_999),
                        (p[1] + ((r() - 0.5) * span) as i64).clamp(0, 99_999),
                    ],
                    _ => [(r() * 100_000.0) as i64, (r() * 100_000.0) as i64],
                }
            }
        };
        let a = end(u, None);
        let b = end(v, Some(a));
        if a == b {
            continue;
        }
        let (pa, pb) = ([mm(X0, a[0]), mm(Y0, a[1])], [mm(X0, b[0]), mm(Y0, b[1])]);
        let on = |q: [f64; 2]| {
            q != pa && q != pb && orient(pa, pb, q) == Orientation::Collinear && {
                q[0] >= pa[0].min(pb[0])
                    && q[0] <= pa[0].max(pb[0])
                    && q[1] >= pa[1].min(pb[1])
                    && q[1] <= pa[1].max(pb[1])
            }
        };
        let xy = |s: &[[f64; 3]; 2]| ([s[0][0], s[0][1]], [s[1][0], s[1][1]]);
        if world.iter().any(|&q| on(q)) || segs.iter().any(|s| meet(xy(s).0, xy(s).1, pa, pb)) {
            continue;
        }
        let mut z = || (r() * 10_000.0).round() / 1000.0;
        let (za, zb) = (z(), z());
        segs.push([[pa[0], pa[1], za], [pb[0], pb[1], zb]]);
    }
    (pts, segs)
}

/// Writes segments (or rings: polylines) as a text breakline file.
fn write_lines(path: &Path, lines: &[Vec<[f64; 3]>]) {
    let mut s = String::new();
    for l in lines {
        for v in l {
            s += &format!("{} {} {}\n", v[0], v[1], v[2]);
        }
        s += "\n";
    }
    std::fs::write(path, s).unwrap();
}

fn input(paths: &[PathBuf], lines: LineOptions, duplicates: DuplicatePolicy) -> Input {
    Input {
        paths: paths.to_vec(),
        filter: sweeptin::input::las::Filter::keep_all(),
        duplicates,
        lines,
    }
}

use mesh::collect_run as collect;

/// The tiled triangles (with z) equal the sweep's for each tile size and both thread counts.
fn assert_tiles_equal_sweep(input: &Input, tiles: &[Option<f64>], what: &str) -> Vec<Key> {
    let (sweep, _) = collect(input, None, 1 << 30);
    let want = sweep.keys();
    assert!(!want.is_empty());
    for &tile in tiles {
        for threads in [1, 2] {
            let (c, s) = collect(input, Some((tile, threads)), 1 << 30);
            let got = c.keys();
            assert_eq!(
                got.len(),
                want.len(),
                "{what}, tile {tile:?}, {threads} threads"
            );
            assert!(got == want, "{what}, tile {tile:?}, {threads} threads");
            // Counted (0) without lines; with lines it cannot be counted.
            assert!(s.tiles.unwrap().uncertified_owned.is_none_or(|n| n == 0));
        }
    }
    want
}

type Key2 = [(u64, u64); 3];

fn xy_keys(keys: &[Key]) -> Vec<Key2> {
    let mut v: Vec<Key2> = keys.iter().map(|k| k.map(|p| (p.0, p.1))).collect();
    v.iter_mut().for_each(|k| k.sort());
    v.sort();
    v
}

/// spade's constrained Delaunay triangulation of `pts` with `segs` (world coordinates).
fn spade_cdt(pts: &[[f64; 3]], segs: &[[[f64; 3]; 2]]) -> Vec<Key2> {
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    for p in pts {
        cdt.insert(Point2::new(p[0], p[1])).unwrap();
    }
    for s in segs {
        let a = cdt.insert(Point2::new(s[0][0], s[0][1])).unwrap();
        let b = cdt.insert(Point2::new(s[1][0], s[1][1])).unwrap();
        assert!(cdt.add_constraint(a, b));
    }
    mesh::spade_keys(&cdt)
}

/// Random segments (long ones across many tiles, ends at lidar points) in tiles of 8 m: the
/// tiled CDT is the sweep's, which is spade's; `first` and `last` give line ends at points the
/// point's and the line's z.
#[test]
fn random_segments_in_small_tiles_equal_the_sweep_and_spade() {
    let dir = tempfile::tempdir().unwrap();
    for seed in 0..3u64 {
        let (pts, segs) = random_case(seed, 2500, 40);
        let las = dir.path().join(format!("p{seed}.las"));
        write_las(&las, &pts);
        let lines = dir.path().join(format!("l{seed}.txt"));
        let polylines: Vec<Vec<[f64; 3]>> = segs.iter().map(|s| s.to_vec()).collect();
        write_lines(&lines, &polylines);
        let opts = LineOptions {
            breaklines: vec![lines],
            ..LineOptions::default()
        };
        for policy in [DuplicatePolicy::First, DuplicatePolicy::Last] {
            let inp = input(std::slice::from_ref(&las), opts.clone(), policy);
            let want = assert_tiles_equal_sweep(&inp, &[Some(8.0)], &format!("seed {seed}"));
            if policy == DuplicatePolicy::First {
                let (read, _) = sweeptin::pipeline::read_points(&input(
                    std::slice::from_ref(&las),
                    LineOptions::default(),
                    policy,
                ))
                .unwrap();
                assert_eq!(
                    xy_keys(&want),
                    spade_cdt(&read, &segs),
                    "seed {seed}: spade"
                );
            }
        }
    }
}

/// A boundary polygon with a hole, and a hole file: the kept triangles are the sweep's.
#[test]
fn trimming_rings_in_small_tiles_equal_the_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let (pts, segs) = random_case(7, 3000, 10);
    let las = dir.path().join("p.las");
    write_las(&las, &pts);
    let ring = |c: [f64; 2], r: f64, k: usize| -> Vec<[f64; 3]> {
        let mut v: Vec<[f64; 3]> = (0..k)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / k as f64;
                let q = |v: f64| (v * 1000.0).round() / 1000.0;
                [q(c[0] + r * t.cos()), q(c[1] + r * t.sin()), 5.0]
            })
            .collect();
        v.push(v[0]);
        v
    };
    let (cx, cy) = (X0 as f64 + 50.0, Y0 as f64 + 50.0);
    let boundary = dir.path().join("b.txt");
    write_lines(
        &boundary,
        &[ring([cx, cy], 45.0, 37), ring([cx + 20.0, cy], 8.0, 11)],
    );
    let holes = dir.path().join("h.txt");
    write_lines(&holes, &[ring([cx - 20.0, cy - 10.0], 12.0, 23)]);
    // Breaklines clear of the rings' vertices are fine; here only the rings.
    let _ = segs;
    let opts = LineOptions {
        boundary: Some(boundary),
        holes: Some(holes),
        max_edge: Some(6.0),
        ..LineOptions::default()
    };
    let inp = input(&[las], opts, DuplicatePolicy::First);
    let want = assert_tiles_equal_sweep(&inp, &[Some(8.0), None], "rings");
    assert!(want.len() > 1000);
}

/// The crop of the two IGN LiDAR HD tiles (sharing x = 300 000) the tests use: 800 m × 600 m
/// around their common edge (the CI runs debug builds).
const IGN_BOX: [f64; 4] = [299_600.0, 6_801_200.0, 300_400.0, 6_801_800.0];

/// The IGN pair cropped to [`IGN_BOX`], IGN's constraint lines (2-D, spread over 50 km: cut to
/// the data and draped), a long line with z across the crop (one segment crossing eight tiles of
/// 100 m), and a line with z along the tile edge x = 300 000 (cut to the data too).
fn ign_case(dir: &Path) -> (Input, Vec<String>) {
    let l = |n: &str| data::shared(&format!("lidar/{n}"));
    let paths = vec![
        l("ign_test_semis_2023_0299_6802_LA93_IGN69.laz"),
        l("ign_test_semis_2023_0300_6802_LA93_IGN69.laz"),
    ];
    let ign_lines = data::shared("lines/ign_NUALHD_1-0_DF_lignes_contrainte.geojson");
    let extra = dir.join("extra.txt");
    write_lines(
        &extra,
        &[
            vec![
                [299_020.5, 6_801_030.25, 150.0],
                [300_975.75, 6_801_960.5, 160.0],
            ],
            (0..9)
                .map(|k| [300_000.0, 6_801_050.0 + 100.0 * k as f64, 140.0 + k as f64])
                .collect(),
        ],
    );
    let lines = LineOptions {
        breaklines: vec![ign_lines.clone(), extra.clone()],
        clip: true,
        ..LineOptions::default()
    };
    let b = IGN_BOX;
    let mut inp = input(&paths, lines, DuplicatePolicy::First);
    inp.filter.bbox = sweeptin::input::las::BBox::new(b[0], b[1], b[2], b[3]);
    let args = vec![
        "--bbox".to_string(),
        format!("{},{},{},{}", b[0], b[1], b[2], b[3]),
        "--breaklines".to_string(),
        ign_lines.to_string_lossy().into_owned(),
        "--breaklines".to_string(),
        extra.to_string_lossy().into_owned(),
        "--clip-breaklines".to_string(),
    ];
    (inp, args)
}

/// Real lidar with real breaklines: the tiled CDT (tiles of 100 m, a line across eight of them
/// and one along a tile edge) is the sweep's, on IGN LiDAR HD with IGN's constraint lines.
/// (AHN3 Delft with the 13 131-vertex BGT partition is compared in release by
/// scripts/bench-cdttiles.sh: too slow for a debug test.)
#[test]
fn real_lidar_with_real_breaklines_equals_the_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let (ign, _) = ign_case(dir.path());
    let (sweep, s) = collect(&ign, None, 1 << 30);
    let want = sweep.keys();
    let b = s.breaklines.as_ref().unwrap();
    assert!(b.segments >= 10, "{b:?}");
    for threads in [1, 2] {
        let (c, s) = collect(&ign, Some((Some(100.0), threads)), 1 << 30);
        assert!(c.keys() == want, "IGN, {threads} threads");
        let t = s.tiles.unwrap();
        assert!(t.tiles >= 40, "{t:?}");
        assert_eq!(t.uncertified_owned, None, "breaklines: not countable");
    }
}

use cli::ok as cli;

/// The CLI on the IGN crop with breaklines and a trimming polygon (2-D, draped): the DEM of
/// `--engine tiles` (`auto` keeps the sweep for lines) is the sweep's byte for byte, and the DEM and the PLY mesh are the same bytes
/// for `--threads 1` and `2` and two `--mem` budgets.
#[test]
fn cli_dem_and_mesh_with_breaklines_do_not_depend_on_engine_threads_or_memory() {
    let dir = tempfile::tempdir().unwrap();
    let (ign, lines) = ign_case(dir.path());
    let d = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    // An ellipse over the crop (48 vertices), without z.
    let boundary = dir.path().join("boundary.txt");
    let ring: Vec<String> = (0..=48)
        .map(|k| {
            let t = std::f64::consts::TAU * (k % 48) as f64 / 48.0 + 0.3;
            format!(
                "{:.2} {:.2}",
                300_000.0 + 380.0 * t.cos(),
                6_801_500.0 + 280.0 * t.sin()
            )
        })
        .collect();
    std::fs::write(&boundary, ring.join("\n") + "\n").unwrap();
    let mut base: Vec<String> = ign
        .paths
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    base.extend(lines);
    base.extend([
        "--trim-boundary".into(),
        boundary.to_string_lossy().into_owned(),
    ]);
    base.push("-q".into());
    let run = |cmd: &str, out: &str, extra: &[&str]| -> Vec<u8> {
        let mut a = vec![cmd.to_string()];
        a.extend(base.iter().cloned());
        a.extend(extra.iter().map(|s| s.to_string()));
        a.extend(["-o".to_string(), d(out)]);
        let o = cli(&a);
        assert!(
            !String::from_utf8_lossy(&o.stderr).contains("one exact streaming sweep"),
            "{a:?} fell back to the sweep"
        );
        std::fs::read(d(out)).unwrap()
    };
    let sweep = run("dem", "s.tif", &["--cell", "1", "--engine", "sweep"]);
    let tiled = [
        run(
            "dem",
            "t1.tif",
            &["--cell", "1", "--engine", "tiles", "--threads", "1"],
        ),
        run(
            "dem",
            "t2.tif",
            &[
                "--cell",
                "1",
                "--engine",
                "tiles",
                "--threads",
                "2",
                "--mem",
                "64M",
                "--tile",
                "100",
            ],
        ),
    ];
    for t in &tiled {
        assert!(*t == sweep, "the tiled DEM differs from the sweep's");
    }
    let meshes = [
        run(
            "tin",
            "m1.ply",
            &["--engine", "tiles", "--threads", "1", "--tile", "100"],
        ),
        run(
            "tin",
            "m2.ply",
            &[
                "--engine",
                "tiles",
                "--threads",
                "2",
                "--mem",
                "64M",
                "--tile",
                "100",
            ],
        ),
    ];
    assert!(meshes[0] == meshes[1], "meshes differ");
}
