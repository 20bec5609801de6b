//! # sweeptin
//!
//! Exact, bounded-memory Delaunay terrain models from huge lidar point clouds.
//!
//! The core is a sweep-line Delaunay triangulation (Domiter & Žalik 2008) over points sorted by
//! `y`, with exact predicates and a documented tie-breaking rule for cocircular points, so the same
//! input always gives the same triangles.
//!
//! ```
//! use sweeptin::{triangulate, Options};
//!
//! let points = [[0.0, 0.0, 1.0], [1.0, 0.0, 2.0], [0.0, 1.0, 3.0], [1.0, 1.0, 4.0]];
//! let tin = triangulate(&points, &Options::default()).unwrap();
//! assert_eq!(tin.triangles.len(), 2);
//! sweeptin::validate::validate(&tin.vertices, &tin.triangles).unwrap();
//! ```
//!
//! ## The public API
//!
//! A streaming job: [`pipeline::run`] with a [`RunConfig`] (an [`Input`], [`RunOptions`],
//! [`LineOptions`]) gives a [`RunSummary`]; the triangles go to the sinks of [`sink`] (a mesh
//! writer from [`output`], the products of [`products`] on a [`raster`] lattice), each returning
//! its typed summary. Inputs are read by [`input`]; batch jobs are [`plan`]s. In memory:
//! [`triangulate`], [`triangulate_cdt`] and the dynamic [`Tin`]; [`validate`] checks a mesh
//! independently. Errors are one enum, [`Error`], whose [`ErrorKind`] is the command's exit status.
//!
//! The engine — the sweep, its streaming finaliser, the half-edge store, the external sort and
//! its memory maps, exact tiles, the predicates — is internal: `pub(crate)` in a normal build.
//! The crate's own tests, benchmarks and `dev/` tools test those internals directly, so the `dev`
//! feature (which they turn on through `[dev-dependencies]`) makes the same modules `pub`, at the
//! same paths and hidden from the documentation. This (rather than a `dev` facade of `pub use`
//! re-exports) keeps one path per item in the tests and the library alike, and leaves nothing of
//! the engine reachable from a build without the feature. The types of the public API that the
//! engine defines (summaries, tile options, [`Tin`]) are re-exported below.
#![deny(unsafe_code)]
#![warn(missing_docs)]
#![cfg_attr(not(feature = "dev"), warn(unreachable_pub))]

/// Declares the engine's modules: `pub(crate)` in a normal build; `pub` with the `dev` feature
/// (tests, benchmarks, `dev/` tools), hidden from the documentation.
macro_rules! internal {
    ($($(#[$attr:meta])* mod $name:ident;)*) => {$(
        $(#[$attr])*
        #[cfg(feature = "dev")]
        #[doc(hidden)]
        pub mod $name;
        $(#[$attr])*
        #[cfg(not(feature = "dev"))]
        #[allow(unreachable_pub, reason = "the dev feature makes these modules public")]
        pub(crate) mod $name;
    )*};
}

pub mod breaklines;
pub mod cpu;
pub mod crs;
pub mod error;
pub mod fmt;
pub mod ground;
pub mod input;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod products;
pub mod raster;
pub mod refine;
pub mod simplify;
pub mod sink;
#[cfg(any(test, feature = "dev"))]
#[doc(hidden)]
pub mod synth;
pub mod triangulation;
pub mod validate;

pub(crate) mod clock;
pub(crate) mod idmap;
pub(crate) mod limits;
internal! {
    mod finalise;
    mod geom;
    mod mesh;
    mod sort;
    mod sweep;
    mod tiles;
    mod tin;
}

pub use error::{Error, ErrorKind, Result, human_bytes};
pub use finalise::StreamStats;
pub use pipeline::{Input, LineOptions, RunConfig, RunOptions, RunSummary, SweepAxis};
pub use sort::DuplicatePolicy;
pub use sort::external::SortStats;
pub use sort::mmap::tune_allocator;
pub use sweep::{ConstraintStats, SweepStats};
pub use tiles::{HullBand, PointStore, TaskScope, TileCpu, TileOptions, TileStats};
pub use tin::{CrossValidation, EdgeId, PointLocation, Tin, TriId, VertexId};
pub use triangulation::{
    Options, Triangulation, triangulate, triangulate_cdt, triangulate_with_twins,
};
