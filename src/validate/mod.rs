//! Independent validation of a triangulation: the check that proves the sweep right.
//!
//! [`validate`] (Delaunay) and [`validate_constrained`] (constrained Delaunay) take a mesh as plain
//! arrays (`vertices`, counter-clockwise `triangles`) and share nothing with the sweep's data
//! structures: adjacency is rebuilt here from scratch, and the convex hull is computed
//! independently. Every geometric decision is exact (`geom::predicates::orient` and
//! `geom::predicates::incircle_exact`, unperturbed: cocircular quadruples are accepted either
//! way, so any Delaunay triangulation passes, not only the one sweeptin's tie-breaking rule picks).
//!
//! # What is checked
//!
//! 1. every coordinate is finite, and `x, y` are in the predicates' exact range (after removing the
//!    local origin when that is exact, as `sort::memory` does);
//! 2. every index is in range and no triangle repeats a vertex;
//! 3. no two vertices share the same `(x, y)`;
//! 4. every triangle is strictly counter-clockwise;
//! 5. every directed edge is used by at most one triangle (so every undirected edge is used by at
//!    most two, in opposite directions: neighbours agree);
//! 6. every vertex is used by some triangle;
//! 7. no vertex has two outgoing boundary edges, and the boundary edges (directed edges without a
//!    reverse twin) form exactly one closed loop, which is the convex hull of the vertex set
//!    traversed once counter-clockwise, *collinear hull points included*; the hull is computed here
//!    by Andrew's monotone chain with exact orientation;
//! 8. Euler's count: `triangles == 2n - 2 - k`, `k` hull vertices (a consequence of the above,
//!    checked as a second line of defence);
//! 9. every interior edge that is not a constraint is locally Delaunay: the vertex opposite across
//!    it is not strictly inside the circumcircle of the triangle on this side;
//! 10. ([`validate_constrained`]) every constraint is an edge of the mesh.
//!
//! [`validate_cdt`] takes the constraints as *input segments* (coordinate pairs) instead: every
//! segment must be exactly the union of mesh edges (a chain of collinear mesh vertices from one
//! end to the other, checked exactly), and an edge is exempt from the Delaunay test exactly when
//! it lies on an input segment. [`validate_cdt_with`] can skip the convex-hull checks (7, 8, and
//! "every vertex is used") for trimmed meshes, or the Delaunay test (9) for meshes that are valid
//! triangulations but deliberately not Delaunay (flat-triangle removal); see [`CdtCheck`].
//!
//! # Why this proves a (constrained) Delaunay triangulation
//!
//! *A proper triangulation of the hull.* Let `w(p)` be the number of triangles whose interior
//! contains a point `p` that lies on no edge. Each triangle is counter-clockwise (4), so its interior
//! indicator is the winding number of its boundary cycle around `p`, and `w(p)` is the winding number
//! of the 1-chain `Σ ∂T`. In that sum every interior edge appears once in each direction (5) and
//! cancels, so `Σ ∂T` is the chain of boundary edges, which (7) is the convex hull polygon traversed
//! once counter-clockwise. Its winding number is 1 inside the hull and 0 outside: the open triangles
//! are pairwise disjoint and cover the hull up to edges. No vertex `v` lies inside a triangle or in
//! the relative interior of an edge `ab` of a triangle `T`: the triangles at `v` (there is one, by 6)
//! would overlap `T` or, when `ab` is interior, the twin triangle across `ab` (which does not have
//! `v` as a corner, since `v` is on segment `ab` and that twin is non-degenerate), contradicting
//! `w ≤ 1`; and when `ab` is a boundary edge, `v` is a collinear hull point the boundary loop skips,
//! contradicting (7). With distinct vertices (3), the triangles therefore form a simplicial complex
//! whose union is the convex hull and whose vertex set is the whole input (6): a triangulation of
//! the point set.
//!
//! *Delaunay.* In a triangulation of a point set, if every edge is locally Delaunay, every triangle's
//! circumcircle is empty of vertices (Delaunay's lemma), so (9) makes it a Delaunay triangulation.
//! With constraints, the same lemma holds for every unconstrained edge with visibility blocked by the
//! constraints (Chew's constrained Delaunay lemma), and (10) makes the constraints part of it.
//!
//! # Cost
//!
//! `O(n log n + T)` time and about 40 bytes per triangle: directed edges are bucketed by origin (a
//! counting sort into one flat array), each vertex's short list is sorted in parallel, twins are
//! found by binary search, and the predicate checks run in parallel with rayon. Errors name the
//! first offending item in index order, so messages are deterministic.

use crate::error::{Error, Result};
use crate::geom::exact::exact_diff;
use crate::geom::predicates::{self, CircleSide, Orientation, incircle_exact, orient};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering as AtomicOrdering};

mod cdt;
mod kind;
mod stream;
pub use cdt::{CdtCheck, validate_cdt, validate_cdt_with};
pub use kind::MeshKind;
pub use stream::{StreamCheck, StreamChecker, StreamReport};

/// What a valid mesh is made of.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub struct Report {
    /// Vertices (all used by some triangle).
    pub vertices: u64,
    /// Triangles.
    pub triangles: u64,
    /// Undirected edges, interior and boundary.
    pub edges: u64,
    /// Vertices on the convex hull, collinear ones included (= boundary edges).
    pub hull_vertices: u64,
    /// Distinct constraint edges (all present in the mesh).
    pub constrained_edges: u64,
    /// Interior unconstrained edges whose two opposite vertices are cocircular with the edge: the
    /// places where the Delaunay triangulation is not unique.
    pub cocircular_edges: u64,
}

/// Validates a Delaunay triangulation of `vertices` (`[x, y, z]`) given as counter-clockwise
/// `triangles`. See the [module docs](self) for the list of checks and why they suffice.
///
/// # Errors
/// [`Error::Invalid`] naming the first violation found (which vertex, triangle or edge, and what is
/// wrong with it).
pub fn validate(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Result<Report> {
    Validator::new(vertices, triangles, &[])?.run()
}

/// Validates a constrained Delaunay triangulation: like [`validate`], but the edges in
/// `constraints` (pairs of vertex indices, either direction) must be edges of the mesh and are
/// exempt from the Delaunay test.
///
/// # Errors
/// [`Error::Invalid`] naming the first violation found.
pub fn validate_constrained(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    constraints: &[[u32; 2]],
) -> Result<Report> {
    Validator::new(vertices, triangles, constraints)?.run()
}

fn invalid(msg: impl Into<String>) -> Error {
    Error::Invalid(msg.into())
}

/// No vertex (an empty slot in per-vertex tables).
const NONE: u32 = u32::MAX;
/// Vertices per parallel work item.
const BLOCK: usize = 4096;

/// Undirected edge key: smaller index in the high half.
#[inline(always)]
fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// One outgoing half-edge `a → dst` of the triangle `(a, dst, apex)`, packed so that sorting the
/// words sorts by destination.
#[inline(always)]
fn pack(dst: u32, apex: u32) -> u64 {
    (u64::from(dst) << 32) | u64::from(apex)
}

#[inline(always)]
fn dst_of(w: u64) -> u32 {
    (w >> 32) as u32
}

#[inline(always)]
fn apex_of(w: u64) -> u32 {
    w as u32
}

struct Validator<'a> {
    vertices: &'a [[f64; 3]],
    triangles: &'a [[u32; 3]],
    /// Vertices in the local frame (exact translation of the input).
    xy: Vec<[f64; 2]>,
    /// Sorted, deduplicated undirected constraint keys.
    constraints: Vec<u64>,
    /// Outgoing half-edges of vertex `v`: `out[start[v]..start[v + 1]]`, sorted.
    start: Vec<usize>,
    out: Vec<u64>,
    /// Check the boundary against the convex hull, Euler's count and that every vertex is used
    /// (off for trimmed meshes).
    hull: bool,
    /// Check that unconstrained edges are locally Delaunay.
    delaunay: bool,
    /// Input segments: an edge lying on one is exempt from the Delaunay test.
    segments: Option<cdt::SegmentIndex>,
}

/// What the per-vertex pass found for a block of vertices.
#[derive(Default)]
struct BlockInfo {
    /// Destination of each vertex's outgoing boundary edge, or [`NONE`].
    boundary_next: Vec<u32>,
    boundary_edges: u64,
    interior_edges: u64,
    constrained: u64,
    cocircular: u64,
    /// The first edge `a → b` (apex `c`, opposite `d`) that is not locally Delaunay. Reported only
    /// after the topological checks, whose failures explain more.
    not_delaunay: Option<[u32; 4]>,
}

impl<'a> Validator<'a> {
    fn new(
        vertices: &'a [[f64; 3]],
        triangles: &'a [[u32; 3]],
        constraints: &[[u32; 2]],
    ) -> Result<Self> {
        if vertices.len() > NONE as usize {
            return Err(invalid(format!(
                "{} vertices cannot be indexed by 32-bit triangle corners",
                vertices.len()
            )));
        }
        if triangles.is_empty() {
            return Err(invalid(format!(
                "no triangles (over {} vertices)",
                vertices.len()
            )));
        }
        let xy = local_frame(vertices)?;
        let constraints = constraint_keys(constraints, vertices.len())?;
        Ok(Validator {
            vertices,
            triangles,
            xy,
            constraints,
            start: Vec::new(),
            out: Vec::new(),
            hull: true,
            delaunay: true,
            segments: None,
        })
    }

    fn run(self) -> Result<Report> {
        self.run_checks().map(|(_, report)| report)
    }

    /// All checks; returns the validator (with its adjacency, for further checks) and the report.
    fn run_checks(mut self) -> Result<(Self, Report)> {
        let sorted = self.check_distinct()?;
        let hull = if self.hull {
            convex_hull(&sorted)
        } else {
            Vec::new()
        };
        drop(sorted);
        self.check_triangles()?;
        self.build_adjacency()?;
        let info = self.check_edges()?;
        if self.hull {
            self.check_boundary(&info, &hull)?;
            self.check_euler(hull.len())?;
        }
        if let Some([a, b, c, d]) = info.not_delaunay {
            return Err(self.not_delaunay(a, b, c, d));
        }
        self.check_constraints_present()?;
        let t = self.triangles.len() as u64;
        let report = Report {
            vertices: self.vertices.len() as u64,
            triangles: t,
            edges: info.interior_edges + info.boundary_edges,
            hull_vertices: if self.hull {
                hull.len() as u64
            } else {
                info.boundary_edges
            },
            constrained_edges: self.constraints.len() as u64 + info.constrained,
            cocircular_edges: info.cocircular,
        };
        Ok((self, report))
    }

    /// `vertex 3 (x, y)`, for messages.
    fn v(&self, i: u32) -> String {
        match self.vertices.get(i as usize) {
            Some(p) => format!("vertex {i} ({:?}, {:?})", p[0], p[1]),
            None => format!("vertex {i}"),
        }
    }

    /// Indices in range, no repeated corner, strictly counter-clockwise.
    fn check_triangles(&self) -> Result<()> {
        let n = self.vertices.len();
        let bad = self
            .triangles
            .par_iter()
            .enumerate()
            .find_first(|(_, t)| !self.triangle_ok(t, n));
        let Some((i, t)) = bad else { return Ok(()) };
        let [a, b, c] = *t;
        if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
            return Err(invalid(format!(
                "triangle {i} {t:?}: vertex index {v} is out of range (there are {n} vertices)"
            )));
        }
        if a == b || b == c || a == c {
            return Err(invalid(format!("triangle {i} {t:?} repeats a vertex")));
        }
        let what = match orient(
            self.xy[a as usize],
            self.xy[b as usize],
            self.xy[c as usize],
        ) {
            Orientation::Clockwise => "clockwise",
            _ => "degenerate (its corners are collinear)",
        };
        Err(invalid(format!(
            "triangle {i} ({}, {}, {}) is {what}, not counter-clockwise",
            self.v(a),
            self.v(b),
            self.v(c)
        )))
    }

    #[inline]
    fn triangle_ok(&self, t: &[u32; 3], n: usize) -> bool {
        let [a, b, c] = *t;
        if a as usize >= n || b as usize >= n || c as usize >= n || a == b || b == c || a == c {
            return false;
        }
        orient(
            self.xy[a as usize],
            self.xy[b as usize],
            self.xy[c as usize],
        )
        .is_ccw()
    }

    /// No two vertices at the same `(x, y)`; returns the vertices sorted by `(x, y)` as
    /// `(ordered(x), ordered(y), index)`.
    fn check_distinct(&self) -> Result<Vec<(u64, u64, u32)>> {
        let mut keys: Vec<(u64, u64, u32)> = self
            .xy
            .par_iter()
            .enumerate()
            .map(|(i, p)| (ordered(p[0]), ordered(p[1]), i as u32))
            .collect();
        keys.par_sort_unstable();
        let dup = keys
            .par_windows(2)
            .find_first(|w| w[0].0 == w[1].0 && w[0].1 == w[1].1);
        if let Some(w) = dup {
            return Err(invalid(format!(
                "{} and {} are at the same (x, y)",
                self.v(w[0].2),
                self.v(w[1].2)
            )));
        }
        Ok(keys)
    }

    /// Buckets every directed edge by its origin (a counting sort), sorts each bucket, and checks
    /// that no directed edge is used twice.
    fn build_adjacency(&mut self) -> Result<()> {
        let n = self.vertices.len();
        let count: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(0)).collect();
        self.triangles.par_iter().for_each(|t| {
            for &v in t {
                count[v as usize].fetch_add(1, AtomicOrdering::Relaxed);
            }
        });
        let mut start = Vec::with_capacity(n + 1);
        let mut sum = 0usize;
        start.push(0);
        for c in &count {
            sum += c.load(AtomicOrdering::Relaxed) as usize;
            start.push(sum);
        }
        drop(count);
        let mut cursor: Vec<usize> = start[..n].to_vec();
        let mut out = vec![0u64; sum];
        for &[a, b, c] in self.triangles {
            for (o, d, x) in [(a, b, c), (b, c, a), (c, a, b)] {
                let k = &mut cursor[o as usize];
                out[*k] = pack(d, x);
                *k += 1;
            }
        }
        drop(cursor);
        // Sort each vertex's bucket, a block of vertices per task.
        let mut chunks = Vec::with_capacity(n.div_ceil(BLOCK));
        let mut rest: &mut [u64] = &mut out;
        for v0 in (0..n).step_by(BLOCK) {
            let v1 = (v0 + BLOCK).min(n);
            let (chunk, tail) = rest.split_at_mut(start[v1] - start[v0]);
            chunks.push((v0, v1, chunk));
            rest = tail;
        }
        let twice: Vec<Option<(u32, u32)>> = chunks
            .into_par_iter()
            .map(|(v0, v1, chunk)| {
                let base = start[v0];
                let mut twice = None;
                for v in v0..v1 {
                    let list = &mut chunk[start[v] - base..start[v + 1] - base];
                    list.sort_unstable();
                    if twice.is_none() {
                        let dup = list.windows(2).find(|w| dst_of(w[0]) == dst_of(w[1]));
                        twice = dup.map(|w| (v as u32, dst_of(w[0])));
                    }
                }
                twice
            })
            .collect();
        self.start = start;
        self.out = out;
        match twice.into_iter().flatten().next() {
            Some((a, b)) => Err(self.edge_used_twice(a, b)),
            None => Ok(()),
        }
    }

    fn outgoing(&self, v: u32) -> &[u64] {
        &self.out[self.start[v as usize]..self.start[v as usize + 1]]
    }

    /// The apex of the triangle with directed edge `a → b`, if there is one.
    fn find(&self, a: u32, b: u32) -> Option<u32> {
        let list = self.outgoing(a);
        let i = list.partition_point(|&w| dst_of(w) < b);
        list.get(i)
            .filter(|&&w| dst_of(w) == b)
            .map(|&w| apex_of(w))
    }

    /// The per-edge checks (manifold, locally Delaunay, vertex used), in parallel over blocks of
    /// vertices; collects the boundary edges.
    fn check_edges(&self) -> Result<BlockInfo> {
        let n = self.vertices.len();
        let blocks: Vec<Result<BlockInfo>> = (0..n.div_ceil(BLOCK))
            .into_par_iter()
            .map(|b| self.check_block(b * BLOCK, ((b + 1) * BLOCK).min(n)))
            .collect();
        let mut all = BlockInfo {
            boundary_next: Vec::with_capacity(n),
            ..BlockInfo::default()
        };
        for b in blocks {
            let b = b?;
            all.boundary_next.extend_from_slice(&b.boundary_next);
            all.boundary_edges += b.boundary_edges;
            all.interior_edges += b.interior_edges;
            all.constrained += b.constrained;
            all.cocircular += b.cocircular;
            if all.not_delaunay.is_none() {
                all.not_delaunay = b.not_delaunay;
            }
        }
        Ok(all)
    }

    fn check_block(&self, v0: usize, v1: usize) -> Result<BlockInfo> {
        let mut info = BlockInfo {
            boundary_next: Vec::with_capacity(v1 - v0),
            ..BlockInfo::default()
        };
        for a in v0 as u32..v1 as u32 {
            let next = self.check_vertex(a, &mut info)?;
            info.boundary_next.push(next);
        }
        Ok(info)
    }

    /// Checks the edges leaving `a`; returns the destination of its boundary edge, or [`NONE`].
    fn check_vertex(&self, a: u32, info: &mut BlockInfo) -> Result<u32> {
        let list = self.outgoing(a);
        if list.is_empty() && self.hull {
            return Err(invalid(format!(
                "{} is not used by any triangle",
                self.v(a)
            )));
        }
        let mut boundary = NONE;
        for &w in list {
            let (b, c) = (dst_of(w), apex_of(w));
            match self.find(b, a) {
                None => {
                    if boundary != NONE && self.hull {
                        return Err(invalid(format!(
                            "{} has two outgoing boundary edges (to {} and to {}): the mesh is \
                             pinched there, not a disk",
                            self.v(a),
                            self.v(boundary),
                            self.v(b)
                        )));
                    }
                    boundary = b;
                    info.boundary_edges += 1;
                }
                Some(d) if a < b => {
                    info.interior_edges += 1;
                    self.check_interior_edge(a, b, c, d, info);
                }
                Some(_) => {}
            }
        }
        Ok(boundary)
    }

    /// Interior edge `a → b` with apex `c` on its left and `d` on its right.
    fn check_interior_edge(&self, a: u32, b: u32, c: u32, d: u32, info: &mut BlockInfo) {
        if !self.constraints.is_empty() && self.constraints.binary_search(&edge_key(a, b)).is_ok() {
            return;
        }
        if !self.delaunay {
            return;
        }
        let p = |v: u32| self.xy[v as usize];
        match incircle_exact(p(a), p(b), p(c), p(d)) {
            CircleSide::Outside => {}
            CircleSide::On => info.cocircular += 1,
            CircleSide::Inside => {
                let q = |v: u32| [self.vertices[v as usize][0], self.vertices[v as usize][1]];
                if let Some(s) = &self.segments
                    && s.contains_edge(q(a), q(b))
                {
                    info.constrained += 1;
                } else {
                    info.not_delaunay.get_or_insert([a, b, c, d]);
                }
            }
        }
    }

    fn not_delaunay(&self, a: u32, b: u32, c: u32, d: u32) -> Error {
        invalid(format!(
            "edge {a}-{b} is not locally Delaunay: {} (triangle {}) is strictly inside the \
             circumcircle of triangle {} ({}, {}, {})",
            self.v(d),
            self.triangle_index(b, a, d),
            self.triangle_index(a, b, c),
            self.v(a),
            self.v(b),
            self.v(c)
        ))
    }

    /// Index of the triangle `(a, b, c)` in any rotation, for messages (a linear scan).
    fn triangle_index(&self, a: u32, b: u32, c: u32) -> String {
        let hit = self
            .triangles
            .iter()
            .position(|t| [[a, b, c], [b, c, a], [c, a, b]].contains(t));
        hit.map_or_else(|| "?".into(), |i| i.to_string())
    }

    fn edge_used_twice(&self, a: u32, b: u32) -> Error {
        let tris: Vec<String> = self
            .triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b))
            .map(|(i, t)| format!("{i} {t:?}"))
            .collect();
        invalid(format!(
            "directed edge {} -> {} is used by more than one triangle ({}): triangles overlap or \
             the mesh is not manifold there",
            self.v(a),
            self.v(b),
            tris.join(", ")
        ))
    }

    /// The boundary edges form one loop, equal to the convex hull traversed counter-clockwise.
    fn check_boundary(&self, info: &BlockInfo, hull: &[u32]) -> Result<()> {
        let next = &info.boundary_next;
        let k = hull.len();
        for (i, &h) in hull.iter().enumerate() {
            let want = hull[(i + 1) % k];
            let got = next[h as usize];
            if got == want {
                continue;
            }
            let what = if got == NONE {
                format!(
                    "{} has no outgoing boundary edge (it is interior to the mesh)",
                    self.v(h)
                )
            } else {
                format!("the boundary runs to {} instead", self.v(got))
            };
            return Err(invalid(format!(
                "the mesh boundary is not the convex hull: the hull runs {} -> {}, but {what}",
                self.v(h),
                self.v(want)
            )));
        }
        if info.boundary_edges != k as u64 {
            let mut on_hull = hull.to_vec();
            on_hull.par_sort_unstable();
            let extra = (0..next.len() as u32)
                .find(|&a| next[a as usize] != NONE && on_hull.binary_search(&a).is_err());
            let detail = extra.map_or_else(String::new, |a| {
                format!(
                    ": boundary edge {} -> {} is not on the hull (a hole or a second boundary loop)",
                    self.v(a),
                    self.v(next[a as usize])
                )
            });
            return Err(invalid(format!(
                "the mesh has {} boundary edges, the convex hull {k}{detail}",
                info.boundary_edges
            )));
        }
        Ok(())
    }

    fn check_euler(&self, k: usize) -> Result<()> {
        let n = self.vertices.len() as u64;
        let want = 2 * n - 2 - k as u64;
        let t = self.triangles.len() as u64;
        if t != want {
            return Err(invalid(format!(
                "{t} triangles, but a triangulation of {n} points with {k} on the convex hull has \
                 2n - 2 - k = {want}"
            )));
        }
        Ok(())
    }

    fn check_constraints_present(&self) -> Result<()> {
        let missing = self.constraints.par_iter().find_first(|&&key| {
            let (a, b) = ((key >> 32) as u32, key as u32);
            self.find(a, b).is_none() && self.find(b, a).is_none()
        });
        if let Some(&key) = missing {
            let (a, b) = ((key >> 32) as u32, key as u32);
            return Err(invalid(format!(
                "constraint {}-{} is not an edge of the mesh",
                self.v(a),
                self.v(b)
            )));
        }
        Ok(())
    }
}

/// A finite `f64` as a `u64` with the same order (`-0.0` must have been made `+0.0`).
#[inline(always)]
fn ordered(v: f64) -> u64 {
    let b = v.to_bits();
    if b >> 63 == 1 { !b } else { b | (1 << 63) }
}

/// The inverse of [`ordered`].
#[inline(always)]
fn unordered(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

/// Checks the coordinates and moves `x, y` into a local frame when that is exact (the same
/// translation for every point, so every predicate keeps its sign).
fn local_frame(vertices: &[[f64; 3]]) -> Result<Vec<[f64; 2]>> {
    let bad = vertices
        .par_iter()
        .position_first(|p| !p.iter().all(|v| v.is_finite()));
    if let Some(i) = bad {
        let p = vertices[i];
        return Err(invalid(format!(
            "vertex {i}: coordinate is not finite ({:?}, {:?}, {:?})",
            p[0], p[1], p[2]
        )));
    }
    let lo = vertices.par_iter().map(|p| [p[0], p[1]]).reduce(
        || [f64::INFINITY; 2],
        |a, b| [a[0].min(b[0]), a[1].min(b[1])],
    );
    let exact = vertices
        .par_iter()
        .all(|p| exact_diff(p[0], lo[0]) && exact_diff(p[1], lo[1]));
    let origin = if exact && !vertices.is_empty() {
        lo
    } else {
        [0.0; 2]
    };
    let xy: Vec<[f64; 2]> = vertices
        .par_iter()
        .map(|p| [(p[0] - origin[0]) + 0.0, (p[1] - origin[1]) + 0.0])
        .collect();
    let out = xy
        .par_iter()
        .position_first(|p| !(predicates::check_coord(p[0]) && predicates::check_coord(p[1])));
    if let Some(i) = out {
        return Err(invalid(format!(
            "vertex {i} ({:?}, {:?}): coordinate outside the range where the predicates are exact",
            vertices[i][0], vertices[i][1]
        )));
    }
    Ok(xy)
}

/// Sorted, deduplicated undirected keys of the constraints.
fn constraint_keys(constraints: &[[u32; 2]], n: usize) -> Result<Vec<u64>> {
    for (i, &[a, b]) in constraints.iter().enumerate() {
        if a as usize >= n || b as usize >= n {
            return Err(invalid(format!(
                "constraint {i} [{a}, {b}]: vertex index out of range (there are {n} vertices)"
            )));
        }
        if a == b {
            return Err(invalid(format!(
                "constraint {i} [{a}, {b}] joins a vertex to itself"
            )));
        }
    }
    let mut keys: Vec<u64> = constraints.iter().map(|&[a, b]| edge_key(a, b)).collect();
    keys.par_sort_unstable();
    keys.dedup();
    Ok(keys)
}

/// Convex hull of the points `sorted` (`(ordered(x), ordered(y), index)` sorted by `(x, y)`,
/// distinct, not all collinear), counter-clockwise from the first, with every point on the hull
/// boundary (collinear ones included). Andrew's monotone chain; only strict right turns are removed.
/// Reads the coordinates from the sorted keys, so memory access is sequential.
fn convex_hull(sorted: &[(u64, u64, u32)]) -> Vec<u32> {
    let p = |k: &(u64, u64, u32)| [unordered(k.0), unordered(k.1)];
    let chain = |pts: &mut dyn Iterator<Item = &(u64, u64, u32)>| {
        let mut h: Vec<([f64; 2], u32)> = Vec::new();
        for k in pts {
            let q = p(k);
            while h.len() >= 2
                && orient(h[h.len() - 2].0, h[h.len() - 1].0, q) == Orientation::Clockwise
            {
                h.pop();
            }
            h.push((q, k.2));
        }
        h.pop();
        h.into_iter().map(|(_, v)| v)
    };
    let lower = chain(&mut sorted.iter());
    let upper = chain(&mut sorted.iter().rev());
    lower.chain(upper).collect()
}

#[cfg(test)]
mod tests;
