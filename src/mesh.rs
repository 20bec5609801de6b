//! The one half-edge store: flat triangle arrays with typed ids, shared by the sweep
//! ([`crate::sweep`], [`crate::finalise`]) and the dynamic TIN ([`crate::tin`]).
//!
//! Triangle `t` owns half-edges `3t, 3t+1, 3t+2`, counter-clockwise. Half-edge `e` starts at vertex
//! `origin[e]` and ends at `origin[e.next()]`. Each half-edge has one 32-bit *link word*:
//!
//! * bit 31 clear: the low 30 bits are the twin half-edge (the same edge seen from the neighbour);
//! * bit 31 set: the edge is on the boundary of the triangulated region; the low 30 bits name the
//!   advancing-front node whose segment this edge lies under, or [`NO_NODE`] for the bottom edge
//!   `P-1 → P-2`, for hull edges after the sweep, and for every hull edge of a TIN (the word
//!   [`HULL`]);
//! * bit 30: the edge is constrained (a breakline) and is never flipped.
//!
//! Keeping the front node in the unused twin slot of a boundary edge lets a flip that moves a
//! boundary edge to another slot fix the front's reference in O(1), with no per-vertex table.
//! Ids are 30 bits, so a mesh has at most [`MAX_HALF_EDGES`] half-edges, which bounds the points
//! of a triangulation to [`MAX_VERTICES`].

use crate::sort::mmap::SpillVec;

/// A vertex: an index into the vertex table of its mesh (in the sweep, 0 and 1 are the artificial
/// points).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(transparent)]
pub struct VertexId(pub u32);

/// A half-edge: `3 * triangle + corner`.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(transparent)]
pub struct EdgeId(pub u32);

impl EdgeId {
    /// The next half-edge counter-clockwise in the same triangle.
    #[inline(always)]
    pub fn next(self) -> EdgeId {
        EdgeId(if self.0 % 3 == 2 {
            self.0 - 2
        } else {
            self.0 + 1
        })
    }

    /// The previous half-edge in the same triangle.
    #[inline(always)]
    pub fn prev(self) -> EdgeId {
        EdgeId(if self.0.is_multiple_of(3) {
            self.0 + 2
        } else {
            self.0 - 1
        })
    }

    /// The triangle this half-edge belongs to.
    #[inline(always)]
    pub fn tri(self) -> TriId {
        TriId(self.0 / 3)
    }

    #[inline(always)]
    pub(crate) fn idx(self) -> usize {
        self.0 as usize
    }
}

/// A triangle slot: triangle `t` owns half-edges `3t, 3t+1, 3t+2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TriId(pub u32);

impl TriId {
    /// The first half-edge of the triangle (the others are its `next()` and `prev()`).
    #[inline(always)]
    pub fn edge(self) -> EdgeId {
        EdgeId(3 * self.0)
    }

    #[inline(always)]
    pub(crate) fn idx(self) -> usize {
        3 * self.0 as usize
    }
}

/// Link-word flag: boundary edge (no twin).
pub const BOUNDARY: u32 = 1 << 31;
/// Link-word flag: constrained edge, never flipped.
pub const CONSTRAINED: u32 = 1 << 30;
/// Mask of the id part of a link word.
pub const ID_MASK: u32 = CONSTRAINED - 1;
/// Boundary edge that belongs to no front node.
pub const NO_NODE: u32 = ID_MASK;
/// Link word of a hull edge that belongs to no front node (every hull edge of a TIN).
pub const HULL: u32 = BOUNDARY | NO_NODE;
/// Largest number of half-edges (ids must fit in 30 bits).
pub const MAX_HALF_EDGES: u64 = ID_MASK as u64;
/// Largest number of points of a triangulation: `n` points make at most `2n - 5` triangles, whose
/// `6n - 15` half-edges fit under [`MAX_HALF_EDGES`] (with room for the sweep's two artificial
/// points).
pub const MAX_VERTICES: u64 = (MAX_HALF_EDGES + 1) / 6 - 4;

/// Origin of the half-edges of a freed triangle slot.
pub const DEAD: VertexId = VertexId(u32::MAX);

/// What lies across a half-edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Across {
    /// Another triangle, through this twin half-edge.
    Twin(EdgeId),
    /// Nothing: the edge lies under the segment of this front node.
    Front(u32),
    /// Nothing, and no front node (the bottom edge, or the hull after the sweep).
    Hull,
}

/// Decodes a link word.
#[inline(always)]
pub fn across(word: u32) -> Across {
    if word & BOUNDARY == 0 {
        Across::Twin(EdgeId(word & ID_MASK))
    } else if word & ID_MASK == NO_NODE {
        Across::Hull
    } else {
        Across::Front(word & ID_MASK)
    }
}

/// The triangles, as two flat arrays indexed by half-edge (on the heap, or in a temporary file's
/// map once the streaming sweep spills them: [`SpillVec`]). Freed slots keep their place (their
/// origins are [`DEAD`]); which slot to reuse is the owner's business (the sweep's finaliser, the
/// TIN's free list).
#[derive(Debug, Default, Clone)]
pub struct Mesh {
    /// Origin vertex of each half-edge.
    pub origin: SpillVec<VertexId>,
    /// Link word of each half-edge (see the module docs).
    pub link: SpillVec<u32>,
}

impl Mesh {
    /// An empty mesh with room for `triangles` triangles.
    pub fn with_capacity(triangles: usize) -> Self {
        Mesh {
            origin: SpillVec::with_capacity(3 * triangles),
            link: SpillVec::with_capacity(3 * triangles),
        }
    }

    /// Number of triangle slots.
    #[inline]
    pub fn triangle_count(&self) -> usize {
        self.origin.len() / 3
    }

    /// Appends triangle `a, b, c` (counter-clockwise) with all edges on the hull; returns the
    /// half-edge `a → b` (then `b → c`, `c → a`).
    #[inline]
    pub fn add_triangle(&mut self, a: VertexId, b: VertexId, c: VertexId) -> EdgeId {
        let e = self.origin.len() as u32;
        self.origin.extend_from_slice(&[a, b, c]);
        self.link.extend_from_slice(&[HULL; 3]);
        EdgeId(e)
    }

    /// Overwrites triangle slot `t` (freed, or live and being replaced) with triangle `a, b, c`,
    /// all edges on the hull.
    #[inline]
    pub fn reuse_triangle(&mut self, t: TriId, a: VertexId, b: VertexId, c: VertexId) -> EdgeId {
        let e = t.idx();
        self.origin[e..e + 3].copy_from_slice(&[a, b, c]);
        self.link[e..e + 3].copy_from_slice(&[HULL; 3]);
        t.edge()
    }

    /// Marks triangle slot `t` free.
    #[inline]
    pub fn free_triangle(&mut self, t: TriId) {
        let e = t.idx();
        self.origin[e..e + 3].copy_from_slice(&[DEAD; 3]);
    }

    /// Is triangle slot `t` in use?
    #[inline(always)]
    pub fn is_live(&self, t: TriId) -> bool {
        self.origin[t.idx()] != DEAD
    }

    /// Origin of `e`.
    #[inline(always)]
    pub fn org(&self, e: EdgeId) -> VertexId {
        self.origin[e.idx()]
    }

    /// Destination of `e`.
    #[inline(always)]
    pub fn dst(&self, e: EdgeId) -> VertexId {
        self.origin[e.next().idx()]
    }

    /// What lies across `e`.
    #[inline(always)]
    pub fn across(&self, e: EdgeId) -> Across {
        across(self.link[e.idx()])
    }

    /// The twin of `e`, or `None` on the boundary.
    #[inline(always)]
    pub fn twin(&self, e: EdgeId) -> Option<EdgeId> {
        let w = self.link[e.idx()];
        (w & BOUNDARY == 0).then_some(EdgeId(w & ID_MASK))
    }

    /// Is `e` constrained?
    #[inline(always)]
    pub fn is_constrained(&self, e: EdgeId) -> bool {
        self.link[e.idx()] & CONSTRAINED != 0
    }

    /// Marks both half-edges of the edge at `e` constrained.
    #[inline]
    pub fn constrain(&mut self, e: EdgeId) {
        self.link[e.idx()] |= CONSTRAINED;
        if let Some(t) = self.twin(e) {
            self.link[t.idx()] |= CONSTRAINED;
        }
    }

    /// Makes `e` a hull edge (no twin, no front node), keeping its constrained flag.
    #[inline(always)]
    pub fn detach(&mut self, e: EdgeId) {
        let w = &mut self.link[e.idx()];
        *w = HULL | (*w & CONSTRAINED);
    }

    /// Stores link word `word` at `e`, which has just taken over the edge that word describes;
    /// when the word names a twin, points that twin back at `e` (with the word's constrained
    /// flag). A front node named by the word is not updated (the sweep does that itself).
    #[inline(always)]
    pub fn link_to(&mut self, e: EdgeId, word: u32) {
        self.link[e.idx()] = word;
        if word & BOUNDARY == 0 {
            self.link[(word & ID_MASK) as usize] = e.0 | (word & CONSTRAINED);
        }
    }

    /// Makes `a` and `b` twins, both constrained when `constrained`.
    #[inline(always)]
    pub fn pair(&mut self, a: EdgeId, b: EdgeId, constrained: bool) {
        let f = if constrained { CONSTRAINED } else { 0 };
        self.link[a.idx()] = b.0 | f;
        self.link[b.idx()] = a.0 | f;
    }

    /// The three vertices of triangle `t`, counter-clockwise.
    #[inline(always)]
    pub fn tri_vertices(&self, t: TriId) -> [VertexId; 3] {
        let e = t.idx();
        [self.origin[e], self.origin[e + 1], self.origin[e + 2]]
    }
}
