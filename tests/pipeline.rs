//! The streaming pipeline against the in-memory core: same triangles whatever the memory budget,
//! real LAS/LAZ files, and byte-identical outputs.

use crate::data;

use crate::mesh;

use mesh::{Collect, core_keys, write_las};
use std::path::{Path, PathBuf};
use sweeptin::pipeline::{Input, RunConfig, RunOptions, SweepAxis, run};
use sweeptin::{DuplicatePolicy, Options, triangulate};

fn streamed(paths: &[PathBuf], mem: u64, dup: DuplicatePolicy) -> Collect {
    streamed_along(paths, mem, dup, SweepAxis::Auto).0
}

fn streamed_along(
    paths: &[PathBuf],
    mem: u64,
    dup: DuplicatePolicy,
    sweep_axis: SweepAxis,
) -> (Collect, sweeptin::pipeline::RunSummary) {
    let input = Input {
        paths: paths.to_vec(),
        filter: sweeptin::input::las::Filter::keep_all(),
        duplicates: dup,
        lines: Default::default(),
    };
    mesh::collect_run_along(&input, None, mem, sweep_axis)
}

fn write_xyz(path: &Path, pts: &[[f64; 3]]) {
    let mut s = String::new();
    for p in pts {
        s.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn tiny_budgets_equal_the_in_memory_core() {
    let dir = tempfile::tempdir().unwrap();
    for (name, pts) in [
        ("lidar", sweeptin::synth::lidar_like(30_000, 3)),
        ("uniform", sweeptin::synth::uniform(20_000, 4)),
        ("clustered", sweeptin::synth::clustered(20_000, 5)),
        ("grid", sweeptin::synth::grid(120, 110, 0.5)),
    ] {
        let path = dir.path().join(format!("{name}.xyz"));
        write_xyz(&path, &pts);
        // Exactly what the XYZ reader parses (round-trip of shortest decimals).
        let parsed = sweeptin::input::read_xyz(&path).unwrap();
        let core = triangulate(&parsed, &Options::default()).unwrap();
        let want = core_keys(&core);
        for mem in [32 << 10, 256 << 10, 1 << 30] {
            let c = streamed(std::slice::from_ref(&path), mem, DuplicatePolicy::First);
            let got = c.keys();
            assert_eq!(got, want, "{name} with --mem {mem}");
        }
    }
}

fn shared_lidar(name: &str) -> Option<PathBuf> {
    data::optional(&format!("lidar/{name}"), "pipeline")
}

#[test]
fn real_laz_streamed_equals_in_memory_and_is_delaunay() {
    let sample = PathBuf::from("data/sample/startinpy_small.laz");
    let mut files = vec![sample];
    if let Some(p) = shared_lidar("lidR_Topography.laz") {
        files.push(p);
    }
    for f in files {
        let input = Input {
            paths: vec![f.clone()],
            filter: sweeptin::input::las::Filter::keep_all(),
            duplicates: DuplicatePolicy::First,
            lines: Default::default(),
        };
        let (pts, _) = sweeptin::pipeline::read_points(&input).unwrap();
        let core = triangulate(&pts, &Options::default()).unwrap();
        let want = core_keys(&core);
        let c = streamed(std::slice::from_ref(&f), 64 << 10, DuplicatePolicy::First);
        let got = c.keys();
        assert_eq!(got.len(), want.len(), "{}", f.display());
        assert_eq!(got, want, "{}", f.display());
        c.validate();
    }
}

#[test]
fn byte_identical_whatever_budget_or_threads() {
    let bin = env!("CARGO_BIN_EXE_sweeptin");
    let dir = tempfile::tempdir().unwrap();
    let mut outputs = Vec::new();
    for (k, (mem, threads)) in [("1G", "2"), ("48K", "1"), ("300K", "2")]
        .iter()
        .enumerate()
    {
        for ext in ["ply", "stin"] {
            let out = dir.path().join(format!("o{k}.{ext}"));
            let st = std::process::Command::new(bin)
                .args([
                    "tin",
                    "data/sample/startinpy_small.laz",
                    "--quiet",
                    "--mem",
                    mem,
                    "-o",
                ])
                .arg(&out)
                .env("RAYON_NUM_THREADS", threads)
                .status()
                .unwrap();
            assert!(st.success());
            outputs.push((ext, std::fs::read(&out).unwrap()));
        }
    }
    for ext in ["ply", "stin"] {
        let same: Vec<_> = outputs.iter().filter(|(e, _)| *e == ext).collect();
        for o in &same[1..] {
            assert!(o.1 == same[0].1, "{ext} outputs differ");
        }
    }
}

#[test]
fn strips_are_swept_lengthwise() {
    let dir = tempfile::tempdir().unwrap();
    // General position (unique Delaunay triangulation): both axes give the core's triangles.
    let mut pts = sweeptin::synth::uniform(20_000, 7);
    for p in &mut pts {
        p[1] *= 0.025; // 1000 m x 25 m
    }
    let path = dir.path().join("strip.las");
    write_las(&path, &pts);
    let input = Input {
        paths: vec![path.clone()],
        filter: sweeptin::input::las::Filter::keep_all(),
        duplicates: DuplicatePolicy::First,
        lines: Default::default(),
    };
    let (parsed, _) = sweeptin::pipeline::read_points(&input).unwrap();
    let core = triangulate(&parsed, &Options::default()).unwrap();
    let want = core_keys(&core);
    let mut fronts = Vec::new();
    for (axis, swept) in [
        (SweepAxis::Auto, SweepAxis::X),
        (SweepAxis::X, SweepAxis::X),
        (SweepAxis::Y, SweepAxis::Y),
    ] {
        let (c, summary) = streamed_along(
            std::slice::from_ref(&path),
            64 << 10,
            DuplicatePolicy::First,
            axis,
        );
        assert_eq!(summary.sweep_axis, swept, "{axis:?}");
        let got = c.keys();
        assert_eq!(got, want, "{axis:?}");
        // Counter-clockwise in the world frame, every edge locally Delaunay, hull, Euler.
        c.validate();
        fronts.push(summary.sweep.peak_front);
    }
    assert!(
        fronts[0] * 5 < fronts[2],
        "front along x {} vs along y {}",
        fronts[0],
        fronts[2]
    );

    // A gridded strip (ties everywhere, 1 mm LAS units) swept along x is still exactly Delaunay.
    let grid: Vec<[f64; 3]> = sweeptin::synth::grid(400, 9, 0.5);
    let gpath = dir.path().join("grid.las");
    write_las(&gpath, &grid);
    let (c, summary) = streamed_along(
        std::slice::from_ref(&gpath),
        16 << 10,
        DuplicatePolicy::First,
        SweepAxis::Auto,
    );
    assert_eq!(summary.sweep_axis, SweepAxis::X);
    c.validate();
    assert_eq!(c.triangles.len(), 2 * 399 * 8);
}

#[test]
fn sweep_along_x_refuses_products() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pts.xyz");
    write_xyz(&path, &sweeptin::synth::uniform(100, 1));
    let input = Input {
        paths: vec![path],
        filter: sweeptin::input::las::Filter::keep_all(),
        duplicates: DuplicatePolicy::First,
        lines: Default::default(),
    };
    let options = RunOptions {
        sweep_axis: SweepAxis::X,
        ..Default::default()
    };
    struct Nothing;
    impl sweeptin::sink::TriangleSink for Nothing {
        fn begin(&mut self, _: &sweeptin::sink::StreamInfo) -> sweeptin::Result<()> {
            Ok(())
        }
        fn triangle(&mut self, _: &[[f64; 3]; 3]) -> sweeptin::Result<()> {
            Ok(())
        }
        fn finish(&mut self) -> sweeptin::Result<sweeptin::sink::ProductSummary> {
            Ok(sweeptin::sink::ProductSummary::None)
        }
    }
    let mut sink = Nothing;
    let config = RunConfig::new(input, options).unwrap();
    let e = run(&config, None, &mut [&mut sink]).unwrap_err();
    assert!(e.to_string().contains("--sweep-axis x"), "{e}");
}

#[test]
fn cli_sweeps_strips_along_x_except_into_a_streaming_mesh() {
    let bin = env!("CARGO_BIN_EXE_sweeptin");
    let dir = tempfile::tempdir().unwrap();
    let mut pts = sweeptin::synth::uniform(3_000, 2);
    for p in &mut pts {
        p[1] *= 0.05;
    }
    let path = dir.path().join("strip.las");
    write_las(&path, &pts);
    let axis = |out: &str, extra: &[&str]| -> String {
        let o = std::process::Command::new(bin)
            .arg("tin")
            .arg(&path)
            .args(["-o", dir.path().join(out).to_str().unwrap(), "--json"])
            .args(["--engine", "sweep"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["sweep_axis"].as_str().unwrap().to_string()
    };
    assert_eq!(axis("a.ply", &[]), "x");
    assert_eq!(axis("a.stin", &[]), "y");
    assert_eq!(axis("b.stin", &["--sweep-axis", "x"]), "x");
    assert_eq!(axis("b.ply", &["--sweep-axis", "y"]), "y");
    // The products refuse an x sweep, with exit code 2 and no output.
    let dem = dir.path().join("d.tif");
    let o = std::process::Command::new(bin)
        .arg("dem")
        .arg(&path)
        .args(["-o", dem.to_str().unwrap(), "--sweep-axis", "x"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--sweep-axis x"));
    assert!(!dem.exists());
}

#[test]
fn sweep_along_x_equals_the_core_on_random_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = sweeptin::synth::SplitMix64::new(11);
    for case in 0..12 {
        let n = 3 + rng.below(3000) as usize;
        let squash = [1.0, 0.3, 0.02, 5.0][case % 4];
        let mut pts = sweeptin::synth::uniform(n, case as u64);
        for p in &mut pts {
            p[1] *= squash;
        }
        let path = dir.path().join(format!("u{case}.xyz"));
        write_xyz(&path, &pts);
        let parsed = sweeptin::input::read_xyz(&path).unwrap();
        let core = triangulate(&parsed, &Options::default()).unwrap();
        let want = core_keys(&core);
        let mem = [16 << 10, 1 << 30][case % 2];
        let (c, s) = streamed_along(
            std::slice::from_ref(&path),
            mem,
            DuplicatePolicy::First,
            SweepAxis::X,
        );
        assert_eq!(s.sweep_axis, SweepAxis::X);
        let got = c.keys();
        assert_eq!(got, want, "case {case}: {n} points, y × {squash}");
    }
    // Ties everywhere (a tilted lattice and a cocircular ring): exactly Delaunay along x too.
    for (name, pts) in [
        ("tilted", sweeptin::synth::tilted_grid(40, 25, 0.5, 0.3)),
        ("ring", sweeptin::synth::ring(64, 10.0)),
    ] {
        let path = dir.path().join(format!("{name}.xyz"));
        write_xyz(&path, &pts);
        let (c, _) = streamed_along(
            std::slice::from_ref(&path),
            16 << 10,
            DuplicatePolicy::First,
            SweepAxis::X,
        );
        c.validate();
    }
}
