//! Validation of a constrained Delaunay triangulation against its input segments.
//!
//! An input segment `s0 → s1` is *covered* when both ends are mesh vertices and a chain of mesh
//! edges leads from `s0` to `s1` through vertices exactly on the segment (exact `orient` = 0),
//! each strictly further along than the one before (exact coordinate comparisons). An edge is
//! exempt from the Delaunay test exactly when it lies on an input segment (both ends on the
//! segment's line and within its extent). Segment tests use the coordinates as given (not the local
//! frame), so they are exact for any segment whose coordinates are in the predicates' range.

use super::MeshKind;
use super::{Report, Validator, apex_of, dst_of, invalid};
use crate::error::Result;
use crate::geom::grid::{Buckets, Grid};
use crate::geom::predicates::{Orientation, check_coord, on_segment, orient};
use rayon::prelude::*;

/// Which checks [`validate_cdt_with`] runs besides the structural ones (indices, distinct
/// vertices, counter-clockwise triangles, each directed edge used once) and segment coverage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CdtCheck {
    /// The mesh covers the convex hull of its vertices: boundary = hull, Euler's count, every
    /// vertex used, no pinched vertex, every input segment covered. Turn off for trimmed meshes
    /// (`--boundary`, `--holes`, `--max-edge`): then input segments only exempt the edges lying on
    /// them from the Delaunay test, since trimmed parts of a segment have no edges. Without the
    /// hull, the checks no longer prove that triangles do not overlap (validate the untrimmed mesh
    /// for that).
    pub convex_hull: bool,
    /// Every edge not on an input segment is locally Delaunay. Turn off for a triangulation that is
    /// deliberately not Delaunay (after [`crate::breaklines::flat`] flips).
    pub delaunay: bool,
}

impl Default for CdtCheck {
    fn default() -> Self {
        CdtCheck {
            convex_hull: true,
            delaunay: true,
        }
    }
}

impl CdtCheck {
    /// The checks a mesh of `kind` must pass ([`MeshKind`], as its file says): the convex hull
    /// unless it is trimmed; the Delaunay test unless it is not Delaunay by design, or
    /// constrained while its constraints are not given (`segments`: the file does not list its
    /// constrained edges, so any edge may be one).
    pub fn for_kind(kind: MeshKind, segments: bool) -> Self {
        CdtCheck {
            convex_hull: !kind.trimmed,
            delaunay: !kind.not_delaunay && (!kind.constrained || segments),
        }
    }
}

/// Validates a constrained Delaunay triangulation of `vertices` (counter-clockwise `triangles`)
/// with the input `segments` (coordinate pairs): every segment is exactly the union of mesh edges,
/// every edge not lying on a segment is locally Delaunay, and everything [`super::validate`] checks.
///
/// `Report::constrained_edges` counts the mesh edges along the segments.
///
/// # Errors
/// [`crate::Error::Invalid`] naming the first violation.
pub fn validate_cdt(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    segments: &[[[f64; 2]; 2]],
) -> Result<Report> {
    validate_cdt_with(vertices, triangles, segments, &CdtCheck::default())
}

/// [`validate_cdt`] with a choice of checks (see [`CdtCheck`]).
///
/// # Errors
/// [`crate::Error::Invalid`] naming the first violation.
pub fn validate_cdt_with(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    segments: &[[[f64; 2]; 2]],
    check: &CdtCheck,
) -> Result<Report> {
    let index = SegmentIndex::new(segments)?;
    let mut v = Validator::new(vertices, triangles, &[])?;
    v.hull = check.convex_hull;
    v.delaunay = check.delaunay;
    v.segments = Some(index);
    let (v, mut report) = v.run_checks()?;
    if check.convex_hull {
        report.constrained_edges = v.check_coverage(segments)?;
    }
    Ok(report)
}

/// The input segments in a grid, to tell whether an edge lies on one.
pub(super) struct SegmentIndex {
    pts: Vec<[f64; 2]>,
    grid: Grid,
    buckets: Buckets,
}

impl SegmentIndex {
    fn new(segments: &[[[f64; 2]; 2]]) -> Result<SegmentIndex> {
        for (i, s) in segments.iter().enumerate() {
            if !s.iter().flatten().all(|&v| check_coord(v)) {
                return Err(invalid(format!(
                    "input segment {i} {s:?}: coordinate not finite or outside the range where \
                     the predicates are exact"
                )));
            }
            if s[0] == s[1] {
                return Err(invalid(format!("input segment {i} {s:?} has zero length")));
            }
        }
        let pts: Vec<[f64; 2]> = segments.iter().flatten().copied().collect();
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &pts {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if pts.is_empty() {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        let grid = Grid::new(lo, hi, segments.len());
        let ids: Vec<[u32; 2]> = (0..segments.len() as u32)
            .map(|i| [2 * i, 2 * i + 1])
            .collect();
        let buckets = Buckets::segments(&grid, &pts, &ids);
        Ok(SegmentIndex { pts, grid, buckets })
    }

    /// Does the edge `p-q` lie on an input segment?
    pub(super) fn contains_edge(&self, p: [f64; 2], q: [f64; 2]) -> bool {
        if self.pts.is_empty() {
            return false;
        }
        self.buckets.cell(self.grid.cell_of(p)).iter().any(|&s| {
            let (a, b) = (self.pts[2 * s as usize], self.pts[2 * s as usize + 1]);
            on_segment(a, b, p) && on_segment(a, b, q)
        })
    }
}

/// For `p` on the line `ab`: between `a` and `b`, ends included.
fn within(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    let k = if a[0] != b[0] { 0 } else { 1 };
    a[k].min(b[k]) <= p[k] && p[k] <= a[k].max(b[k])
}

/// Is `w` strictly further than `v` from `a` towards `b` (all on the line `ab`)?
fn further(a: [f64; 2], b: [f64; 2], v: [f64; 2], w: [f64; 2]) -> bool {
    let k = if a[0] != b[0] { 0 } else { 1 };
    if a[k] < b[k] {
        w[k] > v[k]
    } else {
        w[k] < v[k]
    }
}

/// `ordered` key of a point's coordinates as given.
fn key(p: [f64; 2]) -> (u64, u64) {
    (super::ordered(p[0] + 0.0), super::ordered(p[1] + 0.0))
}

impl Validator<'_> {
    /// Walks every input segment along mesh edges; returns the number of distinct mesh edges on
    /// segments.
    fn check_coverage(&self, segments: &[[[f64; 2]; 2]]) -> Result<u64> {
        let mut by_pos: Vec<((u64, u64), u32)> = self
            .vertices
            .par_iter()
            .enumerate()
            .map(|(i, p)| (key([p[0], p[1]]), i as u32))
            .collect();
        by_pos.par_sort_unstable();
        let find = |p: [f64; 2]| {
            by_pos
                .binary_search_by_key(&key(p), |e| e.0)
                .ok()
                .map(|i| by_pos[i].1)
        };
        let walks: Vec<Result<Vec<u64>>> = segments
            .par_iter()
            .enumerate()
            .map(|(i, s)| self.walk(i, *s, &find))
            .collect();
        let mut edges = Vec::new();
        for w in walks {
            edges.extend(w?);
        }
        edges.par_sort_unstable();
        edges.dedup();
        Ok(edges.len() as u64)
    }

    /// The mesh edges along segment `i`, or an error naming where the chain breaks.
    fn walk(
        &self,
        i: usize,
        [a, b]: [[f64; 2]; 2],
        find: &impl Fn([f64; 2]) -> Option<u32>,
    ) -> Result<Vec<u64>> {
        let end = |p: [f64; 2]| {
            find(p).ok_or_else(|| {
                invalid(format!(
                    "input segment {i} ({a:?} - {b:?}): its end {p:?} is not a mesh vertex"
                ))
            })
        };
        let (start, stop) = (end(a)?, end(b)?);
        let q = |v: u32| [self.vertices[v as usize][0], self.vertices[v as usize][1]];
        let mut edges = Vec::new();
        let mut v = start;
        while v != stop {
            let here = q(v);
            let next = self
                .outgoing(v)
                .iter()
                .flat_map(|&w| [dst_of(w), apex_of(w)])
                .find(|&w| {
                    let p = q(w);
                    orient(a, b, p) == Orientation::Collinear
                        && further(a, b, here, p)
                        && within(a, b, p)
                });
            let Some(w) = next else {
                return Err(invalid(format!(
                    "input segment {i} ({a:?} - {b:?}) is not a union of mesh edges: no edge \
                     continues along it from {}",
                    self.v(v)
                )));
            };
            edges.push(super::edge_key(v, w));
            v = w;
        }
        Ok(edges)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;
    use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation as _};

    fn fails(r: Result<Report>, needle: &str) {
        match r {
            Err(Error::Invalid(msg)) => assert!(msg.contains(needle), "{msg:?} lacks {needle:?}"),
            other => panic!("expected Invalid containing {needle:?}, got {other:?}"),
        }
    }

    fn v2(pts: &[[f64; 2]]) -> Vec<[f64; 3]> {
        pts.iter().map(|p| [p[0], p[1], 0.0]).collect()
    }

    // A thin rhombus: the Delaunay diagonal is 1-3 (short); 0-2 (long) only with a constraint.
    const RHOMBUS: [[f64; 2]; 4] = [[0., 0.], [2., -0.5], [4., 0.], [2., 0.5]];

    #[test]
    fn constrained_diagonal() {
        let v = v2(&RHOMBUS);
        let delaunay = [[0, 1, 3], [1, 2, 3]];
        let constrained = [[0, 1, 2], [0, 2, 3]];
        validate_cdt(&v, &delaunay, &[]).unwrap();
        fails(validate_cdt(&v, &constrained, &[]), "not locally Delaunay");
        let r = validate_cdt(&v, &constrained, &[[[0., 0.], [4., 0.]]]).unwrap();
        assert_eq!(r.constrained_edges, 1);
        // The segment is reversed or given as two collinear pieces: the same.
        validate_cdt(&v, &constrained, &[[[4., 0.], [0., 0.]]]).unwrap();
        // The Delaunay mesh does not contain the segment.
        fails(
            validate_cdt(&v, &delaunay, &[[[0., 0.], [4., 0.]]]),
            "not a union of mesh edges",
        );
        fails(
            validate_cdt(&v, &delaunay, &[[[0., 0.], [5., 0.]]]),
            "is not a mesh vertex",
        );
        fails(
            validate_cdt(&v, &delaunay, &[[[0., 0.], [0., 0.]]]),
            "zero length",
        );
    }

    #[test]
    fn segment_through_collinear_vertices() {
        // Square with its centre; the segment runs corner to corner through the centre.
        let v = v2(&[[0., 0.], [2., 0.], [2., 2.], [0., 2.], [1., 1.]]);
        let t = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        let r = validate_cdt(&v, &t, &[[[0., 0.], [2., 2.]]]).unwrap();
        assert_eq!(r.constrained_edges, 2);
        // Along the hull too.
        let r = validate_cdt(&v, &t, &[[[0., 0.], [2., 0.]], [[2., 0.], [2., 2.]]]).unwrap();
        assert_eq!(r.constrained_edges, 2);
    }

    #[test]
    fn trimmed_and_non_delaunay_variants() {
        let v = v2(&RHOMBUS);
        // One triangle of the constrained pair: not the hull, still manifold.
        let trimmed = [[0, 1, 2]];
        fails(validate_cdt(&v, &trimmed, &[]), "not used by any triangle");
        let check = CdtCheck {
            convex_hull: false,
            delaunay: true,
        };
        validate_cdt_with(&v, &trimmed, &[], &check).unwrap();
        // Non-Delaunay without a segment: only accepted with the Delaunay test off.
        let constrained = [[0, 1, 2], [0, 2, 3]];
        fails(
            validate_cdt_with(&v, &constrained, &[], &check),
            "not locally Delaunay",
        );
        let no_delaunay = CdtCheck {
            convex_hull: true,
            delaunay: false,
        };
        validate_cdt_with(&v, &constrained, &[], &no_delaunay).unwrap();
        // Overlaps are still caught.
        fails(
            validate_cdt_with(&v, &[[0, 1, 2], [0, 1, 2]], &[], &check),
            "more than one triangle",
        );
    }

    /// spade's CDT of random points and non-crossing segments passes; removing a constraint from
    /// the segment list makes it fail (when that edge is not Delaunay).
    #[test]
    fn spade_cdt_passes() {
        let mut failures = 0;
        for seed in 0..10 {
            let mut r = crate::synth::SplitMix64::uniform(seed);
            let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
                ConstrainedDelaunayTriangulation::new();
            for _ in 0..300 {
                cdt.insert(Point2::new(r() * 100.0, r() * 100.0)).unwrap();
            }
            let mut segs = Vec::new();
            for _ in 0..40 {
                let a = Point2::new(r() * 100.0, r() * 100.0);
                let b = Point2::new(a.x + r() * 30.0 - 15.0, a.y + r() * 30.0 - 15.0);
                let (ha, hb) = (cdt.insert(a).unwrap(), cdt.insert(b).unwrap());
                if ha != hb && cdt.can_add_constraint(ha, hb) {
                    cdt.add_constraint(ha, hb);
                    segs.push([[a.x, a.y], [b.x, b.y]]);
                }
            }
            let verts: Vec<[f64; 3]> = cdt
                .vertices()
                .map(|v| [v.position().x, v.position().y, 0.0])
                .collect();
            let tris: Vec<[u32; 3]> = cdt
                .inner_faces()
                .map(|f| f.vertices().map(|v| v.fix().index() as u32))
                .collect();
            let rep = validate_cdt(&verts, &tris, &segs).unwrap();
            assert!(rep.constrained_edges >= segs.len() as u64);
            // Without the segments, some constraint edge is (almost surely) not Delaunay.
            if let Err(e) = validate_cdt(&verts, &tris, &[]) {
                assert!(e.to_string().contains("not locally Delaunay"), "{e}");
                failures += 1;
            }
        }
        assert!(failures >= 5, "{failures}");
    }
}
