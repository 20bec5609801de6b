//! In-memory triangulation: the whole point set in RAM, all triangles returned.

use crate::error::{Error, Result};
use crate::sort::memory::{self, DuplicatePolicy};
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
    /// What the breakline insertion did (zero without breaklines).
    pub constraint_stats: crate::sweep::ConstraintStats,
}

/// Delaunay triangulation of `points` (`[x, y, z]`; `z` is carried along).
///
/// The result is the unique Delaunay triangulation under the tie-breaking rule documented in
/// `geom::predicates`: it depends only on the set of distinct `(x, y)` positions (and, among
/// duplicates, on the policy), not on input order or thread count.
///
/// # Errors
/// [`Error::NonFinite`] / [`Error::CoordinateOutOfRange`] naming the first bad point,
/// [`Error::TooFewPoints`] with fewer than 3 distinct positions, [`Error::AllCollinear`] when no
/// triangle exists, [`Error::TooManyPoints`] beyond `sort::memory::MAX_POINTS`.
pub fn triangulate(points: &[[f64; 3]], options: &Options) -> Result<Triangulation> {
    sweep_in_memory(points, &[], options, false).map(|(t, _)| t)
}

/// [`triangulate`] (or [`triangulate_cdt`] with `segments`), with the triangles' adjacency:
/// `twins[3t + k]` is the half-edge across edge `k` of triangle `t` (the edge from its vertex
/// `k` to vertex `k + 1`): `3u + j` for edge `j` of the neighbour `u`, or `u32::MAX` on the
/// convex hull. The sweep has it already, so this costs 12 bytes per triangle and no search
/// (what [`crate::Tin::from_twins`] takes to walk the triangulation).
///
/// # Errors
/// As [`triangulate_cdt`].
pub fn triangulate_with_twins(
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
    options: &Options,
) -> Result<(Triangulation, Vec<u32>)> {
    check_segments(points, segments)?;
    let (t, twins) = sweep_in_memory(points, segments, options, true)?;
    Ok((t, twins.unwrap_or_default()))
}

fn check_segments(points: &[[f64; 3]], segments: &[[u32; 2]]) -> Result<()> {
    if let Some(s) = segments
        .iter()
        .find(|s| s.iter().any(|&i| i as usize >= points.len()))
    {
        return Err(Error::Invalid(format!(
            "segment {:?} refers to a point beyond the {} given",
            s,
            points.len()
        )));
    }
    Ok(())
}

/// Constrained Delaunay triangulation of `points` with the segments `segments` (pairs of indices
/// into `points`) as breaklines: every segment is a union of triangle edges (a point lying exactly
/// on a segment splits it), every other edge is locally Delaunay where visibility is not blocked by
/// a segment.
///
/// Segments must not cross each other (clean them first: `sweeptin::breaklines` splits crossings);
/// a segment that does is left out and counted in
/// [`ConstraintStats::crossing_skipped`](crate::ConstraintStats). A segment between two
/// duplicates of one position is ignored; endpoints merged as duplicates refer to the survivor.
///
/// # Errors
/// As [`triangulate`]; a segment index out of range is [`Error::Invalid`]; [`Error::Internal`] if
/// inserting a breakline breaks an invariant (a bug in sweeptin).
pub fn triangulate_cdt(
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
    options: &Options,
) -> Result<Triangulation> {
    check_segments(points, segments)?;
    sweep_in_memory(points, segments, options, false).map(|(t, _)| t)
}

/// [`triangulate_cdt`] with segment indices already checked; without segments, [`triangulate`];
/// with the adjacency when `twins`.
fn sweep_in_memory(
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
    options: &Options,
    twins: bool,
) -> Result<(Triangulation, Option<Vec<u32>>)> {
    let prepared = memory::prepare(points, options.duplicates)?;
    let distinct = prepared.len() as u64;
    if distinct < 3 {
        return Err(Error::TooFewPoints {
            distinct,
            total: prepared.total,
        });
    }
    let constraints = (!segments.is_empty()).then(|| constraint_graph(&prepared, points, segments));
    let memory::Prepared {
        xy,
        index,
        duplicates,
        ..
    } = prepared;
    let mut sweep = Sweep::new(xy)?;
    if let Some((graph, vertex_of)) = constraints {
        sweep.set_constraints(graph, &vertex_of);
    }
    sweep.run()?;
    let constraint_stats = sweep.constraint_stats();
    let (triangles, twins, xy, stats) = if twins {
        let ((t, w), xy, s) = sweep.finish_with_twins();
        (t, Some(w), xy, s)
    } else {
        let (t, xy, s) = sweep.finish();
        (t, None, xy, s)
    };
    drop(xy);
    if triangles.is_empty() {
        return Err(Error::AllCollinear { distinct });
    }
    let vertices = index.iter().map(|&i| points[i as usize]).collect();
    Ok((
        Triangulation {
            vertices,
            triangles,
            input_index: index,
            duplicates,
            stats,
            constraint_stats,
        },
        twins,
    ))
}

/// The breakline graph over the prepared vertices. Each segment endpoint is mapped to its vertex
/// through the inverse of `prepared.index` (an input point that survived de-duplication), or found
/// among the sorted, de-duplicated vertices by its local position (binary search) when it was
/// merged into another point. The endpoints are then numbered in vertex order.
fn constraint_graph(
    prepared: &memory::Prepared,
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
) -> (crate::sweep::ConstraintGraph, Vec<u32>) {
    const NONE: u32 = u32::MAX;
    let real = &prepared.xy[crate::geom::predicates::FIRST_REAL as usize..];
    let o = prepared.origin;
    let mut vertex_of_input = vec![NONE; points.len()];
    for (v, &i) in prepared.index.iter().enumerate() {
        vertex_of_input[i as usize] = v as u32;
    }
    let vertex = |i: u32| -> u32 {
        match vertex_of_input[i as usize] {
            NONE => {
                let p = points[i as usize];
                let q = [(p[0] - o[0]) + 0.0, (p[1] - o[1]) + 0.0];
                real.binary_search_by(|v| crate::geom::predicates::sweep_cmp(*v, q))
                    .expect("every input point has a vertex") as u32
            }
            v => v,
        }
    };
    let seg_vertices: Vec<[u32; 2]> = segments
        .iter()
        .map(|s| [vertex(s[0]), vertex(s[1])])
        .collect();
    drop(vertex_of_input);
    // Endpoint number of each vertex (NONE where no segment ends), in vertex order.
    let mut cid = vec![NONE; real.len()];
    for &v in seg_vertices.iter().flatten() {
        cid[v as usize] = 0;
    }
    let mut ends = Vec::new();
    for (v, c) in cid.iter_mut().enumerate() {
        if *c != NONE {
            *c = ends.len() as u32;
            ends.push(v as u32);
        }
    }
    let segs: Vec<[u32; 2]> = seg_vertices
        .iter()
        .map(|s| [cid[s[0] as usize], cid[s[1] as usize]])
        .collect();
    drop(seg_vertices);
    drop(cid);
    let xy = ends.iter().map(|&v| real[v as usize]).collect();
    (crate::sweep::ConstraintGraph::new(xy, &segs), ends)
}
