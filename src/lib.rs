//! # sweeptin
//!
//! Exact, bounded-memory Delaunay terrain models from huge lidar point clouds.
//!
//! The core is a sweep-line Delaunay triangulation (Domiter & Žalik 2008) over points sorted by
//! `y`, with exact predicates ([`geom::predicates`]) and a documented tie-breaking rule for cocircular
//! points, so the same input always gives the same triangles.
//!
//! ```
//! use sweeptin::{triangulate, Options};
//!
//! let points = [[0.0, 0.0, 1.0], [1.0, 0.0, 2.0], [0.0, 1.0, 3.0], [1.0, 1.0, 4.0]];
//! let tin = triangulate(&points, &Options::default()).unwrap();
//! assert_eq!(tin.triangles.len(), 2);
//! sweeptin::validate::validate(&tin.vertices, &tin.triangles).unwrap();
//! ```
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod breaklines;
pub(crate) mod clock;
pub mod crs;
pub mod error;
pub mod finalise;
pub mod geom;
pub(crate) mod idmap;
pub mod input;
pub mod mesh;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod products;
pub mod raster;
pub mod refine;
pub mod simplify;
pub mod sink;
pub mod sort;
pub mod sweep;
#[cfg(any(test, feature = "dev"))]
pub mod synth;
pub mod tiles;
pub mod tin;
pub mod triangulation;
pub mod validate;

pub use error::{Error, ErrorKind, Result};
pub use sort::DuplicatePolicy;
pub use triangulation::{Options, Triangulation, triangulate, triangulate_cdt};
