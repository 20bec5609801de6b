//! A mesh sink that keeps what it is given and checks the streaming contract, and triangle sets
//! to compare meshes whatever their order and numbering.

#![allow(dead_code)]

use std::path::Path;
use sweeptin::sink::{MeshSink, MeshSummary};

/// Collects a streamed mesh in memory, checking that a triangle only uses vertices already
/// written and not yet released, and that each vertex is released at most once.
#[derive(Default)]
pub struct Collect {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u64; 3]>,
    pub released: std::collections::HashSet<u64>,
}

impl MeshSink for Collect {
    fn vertex(&mut self, p: [f64; 3]) -> sweeptin::Result<()> {
        self.vertices.push(p);
        Ok(())
    }
    fn triangle(&mut self, t: [u64; 3]) -> sweeptin::Result<()> {
        for v in t {
            assert!(
                (v as usize) < self.vertices.len(),
                "vertex {v} not yet written"
            );
            assert!(!self.released.contains(&v), "vertex {v} used after release");
        }
        self.triangles.push(t);
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

/// A triangle by the bits of its corners, sorted.
pub type Key = [(u64, u64, u64); 3];

impl Collect {
    /// The triangles as a sorted set of coordinate triples.
    pub fn keys(&self) -> Vec<Key> {
        key_set(
            &self.vertices,
            self.triangles.iter().map(|t| t.map(|i| i as usize)),
        )
    }

    /// Validates the mesh with the crate's exact validator.
    pub fn validate(&self) {
        let tris: Vec<[u32; 3]> = self.triangles.iter().map(|t| t.map(|i| i as u32)).collect();
        sweeptin::validate::validate(&self.vertices, &tris).unwrap();
    }
}

/// The in-memory core's triangles as a sorted set of coordinate triples.
pub fn core_keys(core: &sweeptin::Triangulation) -> Vec<Key> {
    key_set(
        &core.vertices,
        core.triangles.iter().map(|t| t.map(|i| i as usize)),
    )
}

/// Triangles (vertex numbers into `vertices`) as a sorted set of coordinate triples.
pub fn key_set(vertices: &[[f64; 3]], tris: impl Iterator<Item = [usize; 3]>) -> Vec<Key> {
    let mut out: Vec<Key> = tris
        .map(|t| {
            let mut k = t.map(|i| {
                let p = vertices[i];
                (p[0].to_bits(), p[1].to_bits(), p[2].to_bits())
            });
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

/// Writes `pts` (offsets from (500 000, 4 000 000)) as a LAS 1.2 file with a 1 mm scale, so that
/// coordinates are on a lattice and ties really happen.
pub fn write_las(path: &Path, pts: &[[f64; 3]]) {
    use las::{Builder, Point, Transform, Vector, Writer};
    let mut b = Builder::from((1, 2));
    let t = |offset| Transform {
        scale: 0.001,
        offset,
    };
    b.transforms = Vector {
        x: t(500_000.0),
        y: t(4_000_000.0),
        z: t(0.0),
    };
    let mut w = Writer::from_path(path, b.into_header().unwrap()).unwrap();
    for p in pts {
        w.write_point(Point {
            x: 500_000.0 + p[0],
            y: 4_000_000.0 + p[1],
            z: p[2],
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
}

/// Contour polylines as a sorted set: each with its elevation, rings started at their least
/// point.
pub fn contour_set(bytes: &[u8]) -> Vec<String> {
    let v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    let mut out: Vec<String> = v["features"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let mut c: Vec<(u64, u64)> = f["geometry"]["coordinates"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| {
                    (
                        p[0].as_f64().unwrap().to_bits(),
                        p[1].as_f64().unwrap().to_bits(),
                    )
                })
                .collect();
            if c.len() > 1 && c.first() == c.last() {
                c.pop();
                // The smallest rotation: a ring may pass twice through a vertex at the level
                // (a pinch), so the smallest point alone does not fix where it starts.
                let best = (0..c.len())
                    .map(|i| {
                        let mut r = c.clone();
                        r.rotate_left(i);
                        r
                    })
                    .min()
                    .unwrap();
                c = best;
            }
            format!("{} {c:?}", f["properties"]["elevation"])
        })
        .collect();
    out.sort();
    out
}

/// A run of `input` into a [`Collect`]: tiled with `(tile, threads)`, or the sweep (`None`);
/// checks the summary against what was collected, that every vertex was released once and that
/// no spill file is left behind.
pub fn collect_run(
    input: &sweeptin::pipeline::Input,
    tiles: Option<(Option<f64>, usize)>,
    mem: u64,
) -> (Collect, sweeptin::pipeline::RunSummary) {
    collect_run_along(input, tiles, mem, sweeptin::pipeline::SweepAxis::Auto)
}

/// [`collect_run`] sweeping along `sweep_axis`.
pub fn collect_run_along(
    input: &sweeptin::pipeline::Input,
    tiles: Option<(Option<f64>, usize)>,
    mem: u64,
    sweep_axis: sweeptin::pipeline::SweepAxis,
) -> (Collect, sweeptin::pipeline::RunSummary) {
    use sweeptin::pipeline::{RunConfig, RunOptions, run};
    let tmp = tempfile::tempdir().unwrap();
    let options = RunOptions {
        mem,
        sweep_axis,
        tmp_dir: Some(tmp.path().to_path_buf()),
        tiles: tiles.map(|(tile, threads)| sweeptin::tiles::TileOptions {
            threads,
            tile,
            base: None,
            scope: None,
        }),
        ..RunOptions::default()
    };
    let mut c = Collect::default();
    let config = RunConfig::new(input.clone(), options).unwrap();
    let s = run(&config, Some(&mut c), &mut []).unwrap();
    assert_eq!(s.tiles.is_some(), tiles.is_some(), "engine");
    assert_eq!(s.triangles as usize, c.triangles.len());
    assert_eq!(
        c.released.len(),
        c.vertices.len(),
        "every vertex released once"
    );
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "spill files left behind"
    );
    (c, s)
}

/// The inner faces of a spade triangulation, each as its corners' `(x, y)` bits sorted, sorted.
pub fn spade_keys<T: spade::Triangulation<Vertex = spade::Point2<f64>>>(
    t: &T,
) -> Vec<[(u64, u64); 3]> {
    let mut out: Vec<[(u64, u64); 3]> = t
        .inner_faces()
        .map(|f| {
            let mut k = f
                .vertices()
                .map(|v| (v.position().x.to_bits(), v.position().y.to_bits()));
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}
