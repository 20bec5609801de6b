//! Flat half-edge storage for the sweep's triangles.
//!
//! Triangle `t` owns half-edges `3t, 3t+1, 3t+2`, counter-clockwise. Half-edge `e` starts at vertex
//! `origin[e]` and ends at `origin[e.next()]`. Each half-edge has one 32-bit *link word*:
//!
//! * bit 31 clear: the low 30 bits are the twin half-edge (the same edge seen from the neighbour);
//! * bit 31 set: the edge is on the boundary of the triangulated region; the low 30 bits name the
//!   advancing-front node whose segment this edge lies under, or [`NO_NODE`] for the bottom edge
//!   `P-1 → P-2` (and for hull edges after the sweep);
//! * bit 30: the edge is constrained (a breakline) and is never flipped.
//!
//! Keeping the front node in the unused twin slot of a boundary edge lets a flip that moves a
//! boundary edge to another slot fix the front's reference in O(1), with no per-vertex table.

/// A vertex of the sweep (an index into its vertex table; 0 and 1 are the artificial points).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(transparent)]
pub struct VertexId(pub u32);

/// A half-edge: `3 * triangle + corner`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
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
    pub fn tri(self) -> u32 {
        self.0 / 3
    }

    #[inline(always)]
    pub(crate) fn idx(self) -> usize {
        self.0 as usize
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
/// Largest number of half-edges (ids must fit in 30 bits).
pub const MAX_HALF_EDGES: u64 = ID_MASK as u64;

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

/// The triangles, as two flat arrays indexed by half-edge.
#[derive(Debug, Default, Clone)]
pub struct Mesh {
    /// Origin vertex of each half-edge.
    pub origin: Vec<VertexId>,
    /// Link word of each half-edge (see the module docs).
    pub link: Vec<u32>,
}

impl Mesh {
    /// An empty mesh with room for `triangles` triangles.
    pub fn with_capacity(triangles: usize) -> Self {
        Mesh {
            origin: Vec::with_capacity(3 * triangles),
            link: Vec::with_capacity(3 * triangles),
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
        self.link.extend_from_slice(&[BOUNDARY | NO_NODE; 3]);
        EdgeId(e)
    }

    /// Overwrites the freed triangle slot `t` with triangle `a, b, c`, all edges on the hull.
    #[inline]
    pub fn reuse_triangle(&mut self, t: u32, a: VertexId, b: VertexId, c: VertexId) -> EdgeId {
        let e = 3 * t as usize;
        self.origin[e..e + 3].copy_from_slice(&[a, b, c]);
        self.link[e..e + 3].copy_from_slice(&[BOUNDARY | NO_NODE; 3]);
        EdgeId(e as u32)
    }

    /// Marks triangle slot `t` free.
    #[inline]
    pub fn free_triangle(&mut self, t: u32) {
        let e = 3 * t as usize;
        self.origin[e..e + 3].copy_from_slice(&[DEAD; 3]);
    }

    /// Is triangle slot `t` in use?
    #[inline(always)]
    pub fn is_live(&self, t: u32) -> bool {
        self.origin[3 * t as usize] != DEAD
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

    /// Is `e` constrained?
    #[inline(always)]
    pub fn is_constrained(&self, e: EdgeId) -> bool {
        self.link[e.idx()] & CONSTRAINED != 0
    }

    /// Makes `a` and `b` twins, both constrained when `constrained`.
    #[inline(always)]
    pub fn pair(&mut self, a: EdgeId, b: EdgeId, constrained: bool) {
        let f = if constrained { CONSTRAINED } else { 0 };
        self.link[a.idx()] = b.0 | f;
        self.link[b.idx()] = a.0 | f;
    }

    /// The three vertices of triangle `t`.
    #[inline]
    pub fn tri_vertices(&self, t: u32) -> [VertexId; 3] {
        let e = 3 * t as usize;
        [self.origin[e], self.origin[e + 1], self.origin[e + 2]]
    }
}
