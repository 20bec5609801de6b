//! In-memory triangulation: the whole point set in RAM, all triangles returned.

use crate::error::{Error, Result};
use crate::points::{self, DuplicatePolicy};
use crate::sweep::{Sweep, SweepStats};

/// Options of [`triangulate`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Options {
    /// Which point survives among exact `(x, y)` duplicates.
    pub duplicates: DuplicatePolicy,
}

/// A Delaunay triangulation of a 2.5D point set.
#[derive(Clone, Debug, Default)]
pub struct Triangulation {
    /// Distinct points `[x, y, z]`, exactly as given, in sweep order (by `y`, then `x`).
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as counter-clockwise (in x, y) triples of indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
    /// For every vertex, the index of the input point it is.
    pub input_index: Vec<u32>,
    /// Input points merged away as exact `(x, y)` duplicates.
    pub duplicates: u64,
    /// What the sweep did.
    pub stats: SweepStats,
}

/// Delaunay triangulation of `points` (`[x, y, z]`; `z` is carried along).
///
/// The result is the unique Delaunay triangulation under the tie-breaking rule documented in
/// [`crate::predicates`]: it depends only on the set of distinct `(x, y)` positions (and, among
/// duplicates, on the policy), not on input order or thread count.
///
/// # Errors
/// [`Error::NonFinite`] / [`Error::CoordinateOutOfRange`] naming the first bad point,
/// [`Error::TooFewPoints`] with fewer than 3 distinct positions, [`Error::AllCollinear`] when no
/// triangle exists, [`Error::TooManyPoints`] beyond [`points::MAX_POINTS`].
pub fn triangulate(points: &[[f64; 3]], options: &Options) -> Result<Triangulation> {
    let prepared = points::prepare(points, options.duplicates)?;
    let distinct = prepared.len() as u64;
    if distinct < 3 {
        return Err(Error::TooFewPoints {
            distinct,
            total: prepared.total,
        });
    }
    let points::Prepared {
        xy,
        index,
        duplicates,
        ..
    } = prepared;
    let mut sweep = Sweep::new(xy)?;
    sweep.run();
    let (triangles, xy, stats) = sweep.finish();
    drop(xy);
    if triangles.is_empty() {
        return Err(Error::AllCollinear { distinct });
    }
    let vertices = index.iter().map(|&i| points[i as usize]).collect();
    Ok(Triangulation {
        vertices,
        triangles,
        input_index: index,
        duplicates,
        stats,
    })
}
