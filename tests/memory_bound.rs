//! The streaming sweep's memory is bounded by its front whatever the distribution (issue 40): a
//! far outlier or Kuzmin's heavy tail made the finaliser hold every triangle until the end
//! (1,999,837 of 1,999,834 triangles live at once for a disc of a million points plus one point
//! 10⁶ units away). The bound is asserted through the run summary's own peak figures, and the
//! triangles are checked against spade, an independent exact triangulator.

use crate::mesh;

use crate::cli;

use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use std::io::Write;
use std::path::Path;
use sweeptin::DuplicatePolicy;
use sweeptin::pipeline::{Input, SweepAxis};
use sweeptin::synth::heavy;

fn write_xyz(path: &Path, pts: &[[f64; 3]]) {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for p in pts {
        writeln!(w, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    w.flush().unwrap();
}

/// `sweeptin tin XYZ -o OUT --mem MEM --tmp-dir TMP --json`: its summary.
fn tin_json(xyz: &Path, out: &Path, mem: &str, tmp: &Path) -> serde_json::Value {
    let o = cli::ok(&[
        "tin".as_ref(),
        xyz.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--mem".as_ref(),
        mem.as_ref(),
        "--tmp-dir".as_ref(),
        tmp.as_os_str(),
        "--json".as_ref(),
    ]);
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `pts` written to `path` as XYZ, read back with every point kept.
fn xyz_input(path: &Path, pts: &[[f64; 3]]) -> Input {
    write_xyz(path, pts);
    Input {
        paths: vec![path.to_path_buf()],
        filter: sweeptin::input::las::Filter::keep_all(),
        duplicates: DuplicatePolicy::First,
        lines: Default::default(),
    }
}

/// `(x, y)` triangles of the streamed run, as sorted bit triples.
fn xy_keys(c: &mesh::Collect) -> Vec<[(u64, u64); 3]> {
    let mut out: Vec<[(u64, u64); 3]> = c
        .triangles
        .iter()
        .map(|t| {
            let mut k = t.map(|i| {
                let p = c.vertices[i as usize];
                (p[0].to_bits(), p[1].to_bits())
            });
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

#[test]
fn far_outliers_and_heavy_tails_stream_in_bounded_memory() {
    let n = 1_000_000;
    let dir = tempfile::tempdir().unwrap();
    for (name, mut pts) in [
        ("disc + far point", heavy::disc_far(n, 7)),
        ("kuzmin", heavy::kuzmin(n, 7)),
    ] {
        heavy::arrange(&mut pts, heavy::Order::Random, 7);
        let input = xyz_input(&dir.path().join("points.xyz"), &pts);
        let (c, summary) = mesh::collect_run_along(&input, None, 64 << 20, SweepAxis::Y);
        let st = summary.stream;
        eprintln!("{name}: {st:?}");
        // The front of a million points in a disc is about a thousand nodes; the live band is a
        // few dozen rows of it. Before the fix both held all 2 million triangles.
        let bound = 100 * (n as f64).sqrt() as u64;
        assert!(st.peak_live_triangles < bound, "{name}: {st:?}");
        assert!(st.peak_live_vertices < bound, "{name}: {st:?}");
        assert!(
            st.peak_queued <= 2 * st.peak_live_triangles,
            "{name}: {st:?}"
        );
        // Exact: the same triangles as spade's.
        let parsed = sweeptin::input::read_xyz(&input.paths[0]).unwrap();
        let d: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::bulk_load(
            parsed.iter().map(|p| Point2::new(p[0], p[1])).collect(),
        )
        .unwrap();
        assert_eq!(xy_keys(&c), mesh::spade_keys(&d), "{name}: spade disagrees");
    }
}

/// Issue 40, item 4: a tile plus one point 15 km away made a DEM 16,000 cells wide without a word.
/// Both engines (the tiles for LAS, the sweep for XYZ) name the point and the `--bbox` that
/// drops it, on stderr and in the `--json` summary.
#[test]
fn far_points_are_named_with_the_bbox_that_drops_them() {
    let dir = tempfile::tempdir().unwrap();
    let mut pts = sweeptin::synth::grid(60, 60, 1.0);
    pts.insert(1800, [15_000.0, 20.0, 5.0]);
    let las = dir.path().join("glitch.las");
    mesh::write_las(&las, &pts);
    let xyz = dir.path().join("glitch.xyz");
    write_xyz(&xyz, &pts);
    for (input, point, bbox) in [
        (
            &las,
            "(515000, 4000020)",
            "--bbox 500000,4000000,500059,4000059",
        ),
        (&xyz, "(15000, 20)", "--bbox 0,0,59,59"),
    ] {
        let out = dir.path().join("dem.tif");
        let o = cli::ok(&[
            "dem".as_ref(),
            input.as_os_str(),
            "--cell".as_ref(),
            "10".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
            "--json".as_ref(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let warnings = summary["run"]["warnings"].to_string();
        for text in [stderr.as_ref(), warnings.as_str()] {
            assert!(
                text.contains("1 point lies far from the others"),
                "{input:?}: {text}"
            );
            assert!(text.contains(point), "{input:?}: {text}");
        }
        assert!(warnings.contains(bbox), "{input:?}: {warnings}");
    }
}

/// Issue 40: points on one line (all but one) keep every triangle open to the end of the sweep,
/// which no sweep can avoid: the tables of those triangles now go to a temporary file past a
/// quarter of `--mem`, and the run says so (docs/RELIABILITY.md). A disc of as many points at
/// the same budget neither spills nor warns.
#[test]
fn points_on_a_line_warn_that_the_held_triangles_went_to_a_temporary_file() {
    let n = 60_000;
    let dir = tempfile::tempdir().unwrap();
    for (name, pts, warned) in [
        ("line", heavy::almost_line(n, 7), true),
        ("disc", heavy::disc(n, 7), false),
    ] {
        let input = xyz_input(&dir.path().join("points.xyz"), &pts);
        let (_, summary) = mesh::collect_run_along(&input, None, 16 << 20, SweepAxis::Y);
        let found = summary.warnings.iter().any(|w| {
            w.contains("nearly on one line or one circle")
                && w.contains("were kept in a temporary file")
        });
        assert_eq!(
            found, warned,
            "{name}: {:?} {:?}",
            summary.stream, summary.warnings
        );
        assert_eq!(summary.stream.peak_spilled_bytes > 0, warned, "{name}");
    }
}

/// Issue 40, the line row of the memory suite: a line of points plus one beside it held every
/// triangle in memory (388 MB at `--mem 64M` for a million points, a third of it the events
/// of the end, made all at once). The held triangles' tables now live in a temporary file and
/// the end hands its events over in batches: the process's own peak (the summary's) stays
/// within `--mem` + 64 MB while every triangle is held.
#[test]
fn points_on_a_line_stay_within_mem_while_every_triangle_is_held() {
    let n = 300_000;
    let dir = tempfile::tempdir().unwrap();
    let xyz = dir.path().join("line.xyz");
    write_xyz(&xyz, &heavy::almost_line(n, 7));
    let out = dir.path().join("line.stin");
    let mem: u64 = 8 << 20;
    let summary = tin_json(&xyz, &out, "8M", dir.path());
    // `tin` prints the run's summary itself (`dem` nests it under "run").
    let run = summary.get("run").unwrap_or(&summary);
    let stream = &run["stream"];
    assert!(
        stream["peak_live_triangles"].as_u64().unwrap() >= n as u64,
        "{stream}"
    );
    assert!(
        stream["peak_spilled_bytes"].as_u64().unwrap() > 0,
        "{stream}"
    );
    let peak = run["peak_rss_bytes"]
        .as_u64()
        .expect("Linux reports the peak");
    assert!(
        peak <= mem + (64 << 20),
        "peak RSS {} MB at --mem 8M: {stream}",
        peak >> 20
    );
}

/// Issue 40: the line's fan, held whole in tables spilled to temporary files (the mesh, the
/// points, the front, the queue's near buckets and far heap), is exactly spade's triangulation
/// (a line and one point beside it: no four points cocircular, so it is unique).
#[test]
fn points_on_a_line_held_in_spilled_tables_are_spades_triangles() {
    // spade's bulk load is slow on a line (the 10 M line: > 600 s): a small one, past the
    // 2 MiB spill threshold.
    let n = 20_000;
    let dir = tempfile::tempdir().unwrap();
    let mut pts = heavy::almost_line(n, 7);
    heavy::arrange(&mut pts, heavy::Order::Random, 7);
    let input = xyz_input(&dir.path().join("line.xyz"), &pts);
    let (c, summary) = mesh::collect_run_along(&input, None, 4 << 20, SweepAxis::Y);
    let st = summary.stream;
    assert!(st.peak_live_triangles >= n as u64 - 2, "{st:?}");
    assert!(
        st.peak_spilled_bytes > 0,
        "the tables did not spill: {st:?}"
    );
    let parsed = sweeptin::input::read_xyz(&input.paths[0]).unwrap();
    let d: DelaunayTriangulation<Point2<f64>> =
        DelaunayTriangulation::bulk_load(parsed.iter().map(|p| Point2::new(p[0], p[1])).collect())
            .unwrap();
    assert_eq!(xy_keys(&c), mesh::spade_keys(&d), "spade disagrees");
}

/// `(x, y)` triangles of vertices and index triples, as sorted bit triples.
fn xy_set(vertices: &[[f64; 3]], tris: impl Iterator<Item = [usize; 3]>) -> Vec<[(u64, u64); 3]> {
    let mut out: Vec<[(u64, u64); 3]> = tris
        .map(|t| {
            let mut k = t.map(|i| (vertices[i][0].to_bits(), vertices[i][1].to_bits()));
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

/// Issue 40, item 3: the cleaned breakline graph was held whole (the polylines, the cleaner's
/// arrays, the `Pslg` and the sweep's `ConstraintGraph`), so a line file larger than `--mem`
/// did not fit. Now the cleaner streams its rounds and the sweep takes the graph vertex by
/// vertex: a road network whose polylines alone are larger than `--mem` runs with what the
/// summary says was held far below it, and gives the mesh of the in-memory cleaning.
#[test]
fn a_road_network_larger_than_mem_is_triangulated_within_it() {
    use sweeptin::breaklines::{CleanOptions, read_file};
    let dir = tempfile::tempdir().unwrap();
    let (pts_path, lines_path) = (dir.path().join("pts.xyz"), dir.path().join("roads.txt"));
    write_xyz(&pts_path, &sweeptin::synth::road_points(30_000, 1));
    let roads = sweeptin::synth::roads(260_000, 1);
    let mut w = std::io::BufWriter::new(std::fs::File::create(&lines_path).unwrap());
    for l in &roads {
        for p in l {
            writeln!(w, "{} {} {}", p[0], p[1], p[2]).unwrap();
        }
        writeln!(w).unwrap();
    }
    w.flush().unwrap();
    let mem: u64 = 4 << 20;
    let lines = read_file(&lines_path).unwrap();
    let polyline_bytes: usize = lines.polylines.iter().map(|l| l.len() * 24).sum();
    assert!(
        polyline_bytes as u64 > mem,
        "the polylines alone exceed --mem"
    );
    let input = Input {
        paths: vec![pts_path.clone()],
        filter: sweeptin::input::las::Filter::keep_all(),
        duplicates: DuplicatePolicy::First,
        lines: sweeptin::pipeline::LineOptions {
            breaklines: vec![lines_path.clone()],
            ..Default::default()
        },
    };
    let (c, summary) = mesh::collect_run_along(&input, None, mem, SweepAxis::Y);
    let b = summary.breaklines.clone().expect("a breakline summary");
    assert!(b.segments >= 200_000, "{b:?}");
    let cl = b.cleaner.expect("the lines were streamed");
    assert!(!cl.in_memory);
    // The summary's own figures: the cleaner's window (128-byte records) and the sweep's pending
    // segments (with their started vertices, under 100 bytes each) are a sliver of --mem; the
    // rest of the budget goes to the sorts.
    // The reader too: the polylines are parsed as the cleaner reads them, one at a time (24
    // bytes a vertex), never the whole file.
    let held = (cl.peak_active + cl.peak_window) * 128
        + summary.stream.peak_pending_segments * 100
        + b.read_held_vertices * 24;
    assert!(
        b.read_held_vertices < 1000,
        "the reader held {} vertices",
        b.read_held_vertices
    );
    assert!(
        held < mem / 8,
        "held {held} bytes: {cl:?} {:?}",
        summary.stream
    );
    eprintln!("held {held} bytes: {cl:?} {:?}", summary.stream);
    // The mesh of the in-memory cleaning, triangulated in memory.
    let g = lines.clean(&CleanOptions::default()).unwrap();
    assert_eq!(g.segments.len() as u64, b.segments);
    let mut all = sweeptin::input::read_xyz(&pts_path).unwrap();
    let base = all.len() as u32;
    all.extend_from_slice(&g.vertices);
    let segs: Vec<[u32; 2]> = g.segments.iter().map(|s| s.map(|v| v + base)).collect();
    let core = sweeptin::triangulate_cdt(&all, &segs, &sweeptin::Options::default()).unwrap();
    assert_eq!(core.constraint_stats.crossing_skipped, 0);
    assert_eq!(
        xy_set(
            &c.vertices,
            c.triangles.iter().map(|t| t.map(|i| i as usize))
        ),
        xy_set(
            &core.vertices,
            core.triangles.iter().map(|t| t.map(|i| i as usize))
        )
    );
}

/// Points on a ring (every triangle's disk is about the circle, so the sweep holds most of them
/// to the end, like the line): 1 M points never finished (> 15 min). The sweep walked the whole
/// lower arc, a basin never deep enough to fill, at every insertion, and the finaliser scanned the
/// whole arc under each sliver's disk at every check. Now the basin walk is bounded and a check
/// that meets one of its triangle's vertices on the front stops there. The ring's mirror pairs
/// are exactly cocircular (no unique Delaunay triangulation: spade's choice is not ours), so the
/// mesh is checked by `sweeptin check` and against another memory budget byte for byte.
#[test]
fn points_on_a_ring_triangulate_without_scanning_the_arc_at_every_point() {
    let n = 20_000;
    let dir = tempfile::tempdir().unwrap();
    let mut pts = sweeptin::synth::ring(n, n as f64 * 0.01 / std::f64::consts::TAU);
    heavy::arrange(&mut pts, heavy::Order::Random, 7);
    let xyz = dir.path().join("ring.xyz");
    write_xyz(&xyz, &pts);
    let tin = |mem: &str, out: &Path| tin_json(&xyz, out, mem, dir.path())["stream"].clone();
    let (small, large) = (dir.path().join("8M.stin"), dir.path().join("512M.stin"));
    let stream = tin("8M", &small);
    // 180 front nodes and groups a point (377 when the long scans walked every node; a uniform
    // disc: about 6): most are the 64-node short scans before a finalisation, the same at any
    // size (see docs/BENCHMARKS.md).
    let scans = stream["front_scans"].as_u64().unwrap();
    assert!(scans < 250 * n as u64, "{stream}");
    tin("512M", &large);
    assert!(std::fs::read(&small).unwrap() == std::fs::read(&large).unwrap());
    let o = cli::ok(&["check".as_ref(), small.as_os_str()]);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("valid"),
        "{o:?}"
    );
}

/// A disk that fills while the held triangles spill (here: a file-size limit, `ulimit -f`, with
/// its signal ignored, so the temporary file cannot grow: EFBIG, as ENOSPC would be) stops the
/// run with exit 4 naming `--tmp-dir`, leaves no output and nothing in the temporary directory.
#[test]
fn a_full_disk_while_spilling_stops_with_exit_4_naming_the_tmp_dir_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = dir.path().join("line.xyz");
    write_xyz(&xyz, &heavy::almost_line(300_000, 7));
    let tmp = dir.path().join("spill");
    std::fs::create_dir(&tmp).unwrap();
    let out = dir.path().join("line.stin");
    // 8 MiB a file: the tables spill at 2 MiB (`--mem 8M` / 4) and then need about 50 MB.
    let o = std::process::Command::new("bash")
        .arg("-c")
        .arg("ulimit -f 8192 && trap '' XFSZ && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_sweeptin"))
        .args([
            "tin".as_ref(),
            xyz.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .args(["--mem", "8M", "--tmp-dir"])
        .arg(&tmp)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(err.contains(&*tmp.to_string_lossy()), "{err}");
    assert!(err.contains("--tmp-dir"), "{err}");
    assert!(!out.exists(), "a partial output was left");
    let left: Vec<_> = std::fs::read_dir(&tmp).unwrap().collect();
    assert!(left.is_empty(), "left in --tmp-dir: {left:?}");
    assert!(
        std::fs::read_dir(dir.path()).unwrap().all(|e| !e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .contains(".tmp")),
        "a temporary output was left"
    );
}
