//! Exact tiles on several threads: the tiled triangulation has the triangles of the triangulation
//! of all the points (the in-memory core's, itself proved against spade in `prop_core.rs`), on
//! random inputs, lattices (ties everywhere), real files and data with wide gaps whose tiles must
//! grow their buffers; and the tiled outputs are the same bytes for any thread count and budget,
//! with the same DEM and contours as the single sweep.

use crate::cli;
use crate::data;
use crate::mesh;

use data::shared;
use mesh::{Collect, contour_set, core_keys, write_las};
use std::path::{Path, PathBuf};
use sweeptin::pipeline::{Input, RunSummary};
use sweeptin::{DuplicatePolicy, Options, triangulate};

fn input(paths: &[PathBuf], classes: Option<Vec<u8>>) -> Input {
    Input {
        paths: paths.to_vec(),
        filter: sweeptin::input::las::Filter {
            classes,
            ..sweeptin::input::las::Filter::keep_all()
        },
        duplicates: DuplicatePolicy::First,
        lines: Default::default(),
    }
}

/// A tiled run into a collecting mesh sink.
fn tiled(input: &Input, tile: Option<f64>, threads: usize, mem: u64) -> (Collect, RunSummary) {
    mesh::collect_run(input, Some((tile, threads)), mem)
}

/// The tiled triangles equal the core's on the same points, for the given tile sizes and both
/// thread counts; the mesh is valid (exact validator).
fn assert_tiles_equal_core(input: &Input, tiles: &[Option<f64>], what: &str) {
    let (pts, _) = sweeptin::pipeline::read_points(input).unwrap();
    let core = triangulate(&pts, &Options::default()).unwrap();
    let want = core_keys(&core);
    for &tile in tiles {
        for threads in [1, 2] {
            let (c, s) = tiled(input, tile, threads, 1 << 30);
            let got = c.keys();
            assert_eq!(
                got.len(),
                want.len(),
                "{what}, tile {tile:?}, {threads} threads"
            );
            assert!(got == want, "{what}, tile {tile:?}, {threads} threads");
            let t = s.tiles.unwrap();
            assert_eq!(t.uncertified_owned, Some(0));
            if threads == 1 {
                c.validate();
            }
        }
    }
}

fn las_of(dir: &Path, name: &str, pts: &[[f64; 3]]) -> PathBuf {
    let p = dir.join(name);
    write_las(&p, pts);
    p
}

#[test]
fn random_inputs_and_lattices_equal_the_core() {
    let dir = tempfile::tempdir().unwrap();
    let sets: Vec<(&str, Vec<[f64; 3]>)> = vec![
        ("uniform", sweeptin::synth::uniform(6_000, 3)),
        ("clustered", sweeptin::synth::clustered(6_000, 5)),
        ("grid", sweeptin::synth::grid(80, 60, 1.0)),
        (
            "tilted grid",
            sweeptin::synth::tilted_grid(70, 70, 1.0, 0.3),
        ),
    ];
    for (name, pts) in sets {
        let p = las_of(dir.path(), "a.las", &pts);
        // Tiles of 16 (many tiles, thin buffers) and the automatic size.
        assert_tiles_equal_core(&input(&[p], None), &[None, Some(16.0)], name);
    }
}

#[test]
fn duplicates_follow_the_policy_across_tiles() {
    let dir = tempfile::tempdir().unwrap();
    let mut pts = sweeptin::synth::grid(60, 60, 1.0);
    // Every point twice, the second copy higher: `first` keeps the first.
    let copies: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[1], p[2] + 0.5]).collect();
    pts.extend(copies);
    let p = las_of(dir.path(), "d.las", &pts);
    let (c, s) = tiled(&input(&[p], None), Some(8.0), 2, 1 << 20);
    assert_eq!(s.points_read, 7200);
    assert_eq!(s.points_kept, 3600);
    assert!(
        c.vertices.iter().all(|v| v[2].fract() == 0.0),
        "first copies kept"
    );
}

/// Data with an empty disk much wider than a tile (a lake): the tiles on its shore must grow
/// their buffers across it, and still give the core's triangles.
#[test]
fn a_wide_lake_makes_buffers_grow() {
    let dir = tempfile::tempdir().unwrap();
    let pts: Vec<[f64; 3]> = sweeptin::synth::uniform(12_000, 11)
        .into_iter()
        .map(|p| [p[0] * 0.3, p[1] * 0.3, p[2]])
        .filter(|p| (p[0] - 150.0).hypot(p[1] - 150.0) > 90.0)
        .collect();
    let p = las_of(dir.path(), "lake.las", &pts);
    let inp = input(&[p], None);
    let (_, s) = tiled(&inp, Some(32.0), 2, 1 << 30);
    let t = s.tiles.unwrap();
    assert!(t.reruns > 0, "{t:?}");
    assert!(t.max_buffer >= 32.0, "a buffer grew past a tile: {t:?}");
    assert_tiles_equal_core(&inp, &[Some(32.0)], "lake");
}

/// A straight data edge made of decimal coordinates (a scan row at a slope of 1 cm per metre,
/// at UTM-sized offsets, which `write_las` adds): the decimal points are collinear, their binary doubles are not, so the
/// hull is lined with triangles too flat for their circumdisks to be bounded in floating point,
/// reaching far along the edge. They are certified exactly (chord box and half-plane, point by
/// point) with the buffers staying small, where doubling the buffer used to read everything.
#[test]
fn flat_triangles_along_a_straight_edge_keep_buffers_small() {
    let dir = tempfile::tempdir().unwrap();
    let mut pts = Vec::new();
    for j in 0..120 {
        for i in 0..160 {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5 + 0.01 * (i as f64 * 0.5));
            // Quantised to 1 cm, as a LAS file stores them.
            let q = |v: f64| (v * 100.0).round() / 100.0;
            pts.push([q(x), q(y), (i + j) as f64 * 0.01]);
        }
    }
    let p = las_of(dir.path(), "edge.las", &pts);
    let inp = input(&[p], None);
    let (_, s) = tiled(&inp, Some(32.0), 2, 1 << 30);
    let t = s.tiles.unwrap();
    assert!(t.max_buffer <= 64.0, "buffers stay within two tiles: {t:?}");
    assert!(
        t.loaded_points < 3 * s.points_kept,
        "no tile reads everything: {t:?}"
    );
    assert_tiles_equal_core(&inp, &[Some(32.0), Some(16.0)], "straight decimal edge");
}

#[test]
fn real_files_equal_the_core() {
    let l = |n: &str| shared(&format!("lidar/{n}"));
    let ign: Vec<PathBuf> = std::fs::read_dir(shared("lidar/ign_50m_tiles"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "laz"))
        .collect();
    let cases = [
        ("IGN 50 m tiles, ground", ign, Some(vec![2])),
        (
            "AHN3 Delft, two tiles, ground",
            vec![l("ahn3_delft_cropped_1.laz"), l("ahn3_delft_cropped_2.laz")],
            Some(vec![2]),
        ),
        (
            "lidR Topography, ground (a lake)",
            vec![l("lidR_Topography.laz")],
            Some(vec![2]),
        ),
        (
            "IGN decimated tiles (sparse, no order)",
            vec![
                l("ign_test_semis_2023_0299_6802_LA93_IGN69.laz"),
                l("ign_test_semis_2023_0300_6802_LA93_IGN69.laz"),
            ],
            None,
        ),
    ];
    for (what, paths, classes) in cases {
        assert_tiles_equal_core(&input(&paths, classes), &[Some(32.0)], what);
    }
}

use cli::ok as cli;

/// Same bytes whatever the thread count and memory budget; the DEM is the sweep's, byte for
/// byte, and the contours are the sweep's polylines.
#[test]
fn cli_outputs_do_not_depend_on_threads_or_memory() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let topo = shared("lidar/lidR_Topography.laz");
    let topo = topo.to_str().unwrap();
    let mut meshes = Vec::new();
    let mut dems = Vec::new();
    for (k, (threads, mem)) in [("1", "1G"), ("2", "1G"), ("2", "2M")].iter().enumerate() {
        let (ply, tif, geo) = (
            d(&format!("m{k}.ply")),
            d(&format!("d{k}.tif")),
            d(&format!("c{k}.geojson")),
        );
        cli(&[
            "tin",
            topo,
            "--threads",
            threads,
            "--mem",
            mem,
            "-o",
            &ply,
            "-q",
        ]);
        cli(&[
            "dem",
            topo,
            "--class",
            "2",
            "--cell",
            "0.5",
            "--threads",
            threads,
            "--mem",
            mem,
            "-o",
            &tif,
            "--contours",
            &geo,
            "-q",
        ]);
        meshes.push(std::fs::read(&ply).unwrap());
        dems.push((std::fs::read(&tif).unwrap(), std::fs::read(&geo).unwrap()));
    }
    assert!(meshes.iter().all(|m| *m == meshes[0]), "meshes differ");
    assert!(
        dems.iter().all(|m| *m == dems[0]),
        "DEMs or contours differ"
    );
    let (tif, geo) = (d("s.tif"), d("s.geojson"));
    cli(&[
        "dem",
        topo,
        "--class",
        "2",
        "--cell",
        "0.5",
        "--engine",
        "sweep",
        "-o",
        &tif,
        "--contours",
        &geo,
        "-q",
    ]);
    assert!(
        std::fs::read(&tif).unwrap() == dems[0].0,
        "the DEM is not the sweep's"
    );
    assert_eq!(
        contour_set(&std::fs::read(&geo).unwrap()),
        contour_set(&dems[0].1),
        "the contours are not the sweep's"
    );
}

/// A DEM-only tiled run leaves out, in its workers, the triangles that hold no cell centre; it
/// still counts them: its summary's triangles are the sweep's, and so is the raster.
#[test]
fn a_dem_only_run_counts_the_triangles_it_leaves_out() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let topo = shared("lidar/lidR_Topography.laz");
    let topo = topo.to_str().unwrap();
    let mut runs = Vec::new();
    for engine in ["tiles", "sweep"] {
        let tif = d(&format!("{engine}.tif"));
        let out = cli(&[
            "dem", topo, "--cell", "2", "--engine", engine, "-o", &tif, "--json", "-q",
        ]);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        runs.push((
            v["run"]["triangles"].as_u64().unwrap(),
            v["dem"]["triangles"].as_u64().unwrap(),
            std::fs::read(&tif).unwrap(),
        ));
    }
    assert!(runs[0].0 > 0);
    assert_eq!(runs[0].0, runs[1].0, "run triangles");
    assert_eq!(runs[0].1, runs[1].1, "DEM triangles");
    assert!(runs[0].2 == runs[1].2, "the DEM is not the sweep's");
}

/// A DEM alone leaves the triangles deep inside a tile that hold no cell centre unjudged
/// (covering needs): with a lake wider than the tiles and sparse clusters, whose triangles reach
/// across tiles with their centres in other tiles, and cells from finer than the points to far
/// coarser than a tile, the raster and the counts are the sweep's, on one thread or two.
#[test]
fn a_dem_alone_skips_what_it_does_not_want_and_is_still_the_sweeps() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let mut pts: Vec<[f64; 3]> = sweeptin::synth::uniform(9_000, 21)
        .into_iter()
        .map(|p| [p[0] * 0.3, p[1] * 0.3, p[2]])
        .filter(|p| (p[0] - 150.0).hypot(p[1] - 150.0) > 80.0)
        .collect();
    // Sparse clusters in the lake and beyond the data.
    for (k, c) in [[150.0, 150.0], [120.0, 170.0], [340.0, 40.0]]
        .iter()
        .enumerate()
    {
        for i in 0..12 {
            let a = i as f64 * 0.5 + k as f64;
            pts.push([
                c[0] + 3.0 * a.cos(),
                c[1] + 3.0 * a.sin(),
                (i * 7 % 5) as f64,
            ]);
        }
    }
    let lake = las_of(dir.path(), "lake.las", &pts);
    // Lattices: many points exactly on the hull's edges (the count's `B`), ties everywhere.
    let grid = las_of(dir.path(), "grid.las", &sweeptin::synth::grid(80, 60, 1.0));
    let tilted = sweeptin::synth::tilted_grid(70, 70, 1.0, 0.3);
    let tilted = las_of(dir.path(), "tilted.las", &tilted);
    let cases = [
        (lake, ["0.25", "2", "7", "40"].as_slice()),
        (grid, ["0.3", "1"].as_slice()),
        (tilted, ["0.3", "2.5"].as_slice()),
    ];
    for (las, cells) in &cases {
        let las = las.to_str().unwrap();
        for &cell in *cells {
            let mut runs = Vec::new();
            for (engine, threads) in [("tiles", "1"), ("tiles", "2"), ("sweep", "1")] {
                let tif = d(&format!("{engine}{threads}.tif"));
                let mut args = vec!["dem", las, "--cell", cell, "--engine", engine];
                args.extend_from_slice(&["--threads", threads, "-o", &tif, "--json", "-q"]);
                if engine == "tiles" && cell != "40" {
                    args.extend_from_slice(&["--tile", "16"]);
                }
                let v: serde_json::Value = serde_json::from_slice(&cli(&args).stdout).unwrap();
                runs.push((v["run"]["triangles"].as_u64(), std::fs::read(&tif).unwrap()));
            }
            for r in &runs[..2] {
                let what = format!("{las}, cell {cell}");
                assert_eq!(
                    r.0, runs[2].0,
                    "{what}: the triangle count is not the sweep's"
                );
                assert!(r.1 == runs[2].1, "{what}: the DEM is not the sweep's");
            }
        }
    }
}

/// Heights at query points (sorted by `y`, answered lazily), profiles along lines and volumes
/// are the sweep's, byte for byte, whatever the thread count: the products that need every
/// triangle get them in the tiles' order, which is not the sweep's.
#[test]
fn sample_profile_and_volume_are_the_sweeps() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let topo = shared("lidar/lidR_Topography.laz");
    let topo = topo.to_str().unwrap();
    // The file's extent: x 273357.1 .. 273642.9, y 5274357.1 .. 5274642.8.
    let (x0, y0, x1, y1) = (273357.0, 5274357.0, 273643.0, 5274643.0);
    let mut queries = String::from("x,y\n");
    for j in 0..=143 {
        for i in 0..=143 {
            queries.push_str(&format!(
                "{},{}\n",
                x0 + 2.0 * i as f64,
                y0 + 2.0 * j as f64
            ));
        }
    }
    std::fs::write(d("q.csv"), queries).unwrap();
    let mut lines = String::from(r#"{"type":"FeatureCollection","features":["#);
    for k in 0..20 {
        let kx = x0 + 13.0 * k as f64;
        lines.push_str(&format!(
            r#"{}{{"type":"Feature","properties":{{}},"geometry":{{"type":"LineString","coordinates":[[{kx},{y0}],[{},{y1}],[{x1},{}]]}}}}"#,
            if k > 0 { "," } else { "" },
            kx + 150.0,
            y0 + 11.0 * k as f64
        ));
    }
    lines.push_str("]}");
    std::fs::write(d("l.geojson"), lines).unwrap();
    let mut outs = Vec::new();
    for (k, engine) in [["tiles", "1"], ["tiles", "2"], ["sweep", "1"]]
        .iter()
        .enumerate()
    {
        let (s, p) = (d(&format!("s{k}.csv")), d(&format!("p{k}.csv")));
        let common = ["--engine", engine[0], "--threads", engine[1], "-q"];
        let q = d("q.csv");
        cli(&[&["sample", topo, "--points", &q, "-o", &s][..], &common].concat());
        let l = d("l.geojson");
        cli(&[&["profile", topo, "--line", &l, "-o", &p][..], &common].concat());
        let v = cli(&[&["volume", topo, "--plane", "800", "--json"][..], &common].concat());
        let v: serde_json::Value = serde_json::from_slice(&v.stdout).unwrap();
        outs.push((
            std::fs::read(&s).unwrap(),
            std::fs::read(&p).unwrap(),
            [
                "cut_volume",
                "fill_volume",
                "cut_area",
                "fill_area",
                "triangles",
            ]
            .map(|f| v[f].to_string()),
        ));
    }
    assert!(outs[0].0.len() > 100_000 && outs[0].1.len() > 100_000);
    assert!(outs[0].2.iter().all(|f| f != "null"), "{:?}", outs[0].2);
    for o in &outs[1..] {
        assert!(o.0 == outs[0].0, "sample differs");
        assert!(o.1 == outs[0].1, "profile differs");
        assert_eq!(o.2, outs[0].2, "volumes differ");
    }
}
