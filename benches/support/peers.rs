//! The triangulators compared in the core benchmarks, each fed the input layout it wants.
//!
//! Shared by `benches/core.rs` (criterion) and `examples/bench_core.rs` (one run per process, for
//! peak memory), included in both with `#[path]`.
//!
//! | algorithm | what is timed | input it is given |
//! |---|---|---|
//! | `sweeptin` | `sweeptin::triangulate` (validation, sort, de-duplication, sweep, output) | `&[[f64; 3]]` |
//! | `delaunator` | `delaunator::triangulate` | `&[delaunator::Point]` (`{x, y}`, 16 B) |
//! | `spade` | `DelaunayTriangulation::<Point2<f64>>::bulk_load` | `Vec<Point2<f64>>` (moved in, 16 B) |
//! | `cdt` | `cdt::triangulate_points` | `&[(f64, f64)]` (16 B) |
//!
//! Every peer gets only `x, y`; sweeptin also carries `z` (its API takes `[x, y, z]`).

#![allow(dead_code)] // each includer uses a different part

use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use std::any::Any;
use sweeptin::synth;

/// A synthetic input distribution (see `sweeptin::synth`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dist {
    /// `synth::uniform`.
    Uniform,
    /// `synth::lidar_like`.
    LidarLike,
    /// `synth::clustered`.
    Clustered,
}

impl Dist {
    /// All distributions, in report order.
    pub const ALL: [Dist; 3] = [Dist::Uniform, Dist::LidarLike, Dist::Clustered];

    /// Name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Dist::Uniform => "uniform",
            Dist::LidarLike => "lidar-like",
            Dist::Clustered => "clustered",
        }
    }

    /// Parses [`Dist::name`] (also `lidar`).
    pub fn parse(s: &str) -> Option<Dist> {
        match s {
            "uniform" => Some(Dist::Uniform),
            "lidar-like" | "lidar" => Some(Dist::LidarLike),
            "clustered" => Some(Dist::Clustered),
            _ => None,
        }
    }

    /// `n` points of this distribution.
    pub fn generate(self, n: usize, seed: u64) -> Vec<[f64; 3]> {
        match self {
            Dist::Uniform => synth::uniform(n, seed),
            Dist::LidarLike => synth::lidar_like(n, seed),
            Dist::Clustered => synth::clustered(n, seed),
        }
    }
}

/// A triangulator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algo {
    /// `sweeptin::triangulate`.
    Sweeptin,
    /// `delaunator::triangulate`.
    Delaunator,
    /// `spade::DelaunayTriangulation::bulk_load`.
    Spade,
    /// `cdt::triangulate_points`.
    Cdt,
}

impl Algo {
    /// All algorithms, sweeptin first.
    pub const ALL: [Algo; 4] = [Algo::Sweeptin, Algo::Delaunator, Algo::Spade, Algo::Cdt];

    /// Name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Algo::Sweeptin => "sweeptin",
            Algo::Delaunator => "delaunator",
            Algo::Spade => "spade",
            Algo::Cdt => "cdt",
        }
    }

    /// Parses [`Algo::name`].
    pub fn parse(s: &str) -> Option<Algo> {
        Algo::ALL.into_iter().find(|a| a.name() == s)
    }

    /// Converts generated points into this algorithm's input layout (the points are consumed so
    /// that only the layout the algorithm needs stays in memory).
    pub fn input(self, pts: Vec<[f64; 3]>) -> Input {
        match self {
            Algo::Sweeptin => Input::Sweeptin(pts),
            Algo::Delaunator => Input::Delaunator(
                pts.iter()
                    .map(|p| delaunator::Point { x: p[0], y: p[1] })
                    .collect(),
            ),
            Algo::Spade => Input::Spade(pts.iter().map(|p| Point2::new(p[0], p[1])).collect()),
            Algo::Cdt => Input::Cdt(pts.iter().map(|p| (p[0], p[1])).collect()),
        }
    }
}

/// One algorithm's input, in its own layout.
#[derive(Clone)]
pub enum Input {
    /// `[x, y, z]`.
    Sweeptin(Vec<[f64; 3]>),
    /// `{x, y}`.
    Delaunator(Vec<delaunator::Point>),
    /// `Point2 {x, y}`; moved into `bulk_load`, so an input serves one run only.
    Spade(Vec<Point2<f64>>),
    /// `(x, y)`.
    Cdt(Vec<(f64, f64)>),
}

impl Input {
    /// Bytes of the input's buffer.
    pub fn bytes(&self) -> usize {
        match self {
            Input::Sweeptin(v) => std::mem::size_of_val(v.as_slice()),
            Input::Delaunator(v) => std::mem::size_of_val(v.as_slice()),
            Input::Spade(v) => std::mem::size_of_val(v.as_slice()),
            Input::Cdt(v) => std::mem::size_of_val(v.as_slice()),
        }
    }
}

/// A finished triangulation: its triangle count, and the result itself, to be dropped outside
/// the timed region.
pub struct Done {
    /// Number of triangles.
    pub triangles: usize,
    /// The algorithm's result.
    pub result: Box<dyn Any>,
}

/// Runs the triangulation (the part that is timed). Spade's input is moved out (left empty).
///
/// # Errors
/// The algorithm's own error, as text.
pub fn run(input: &mut Input) -> Result<Done, String> {
    match input {
        Input::Sweeptin(pts) => {
            let t = sweeptin::triangulate(pts, &sweeptin::Options::default())
                .map_err(|e| e.to_string())?;
            Ok(Done {
                triangles: t.triangles.len(),
                result: Box::new(t),
            })
        }
        Input::Delaunator(pts) => {
            let t = delaunator::triangulate(pts);
            Ok(Done {
                triangles: t.len(),
                result: Box::new(t),
            })
        }
        Input::Spade(pts) => {
            let t = DelaunayTriangulation::<Point2<f64>>::bulk_load(std::mem::take(pts))
                .map_err(|e| format!("{e:?}"))?;
            Ok(Done {
                triangles: t.num_inner_faces(),
                result: Box::new(t),
            })
        }
        Input::Cdt(pts) => {
            let t = cdt::triangulate_points(pts).map_err(|e| e.to_string())?;
            Ok(Done {
                triangles: t.len(),
                result: Box::new(t),
            })
        }
    }
}
