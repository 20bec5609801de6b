//! What a sweep mode does when the core changes the triangulation.
//!
//! The core ([`Sweep`](super::Sweep)) is generic over its mode and monomorphised for each: in
//! batch mode ([`Batch`]) every hook is empty and compiles away, so batch mode pays nothing for
//! streaming; the streaming finaliser ([`crate::finalise::StreamingSweep`]) counts vertex
//! references, recycles triangle slots and schedules finalisation checks. The hooks are told what
//! the core has changed (for a breakline's cavity, what it is about to replace), and never change
//! the mesh themselves.

use crate::mesh::{Mesh, TriId, VertexId};

/// A mode of the sweep: [`Batch`], or the streaming finaliser inside
/// [`crate::finalise::StreamingSweep`]. Sealed: only this crate implements it.
pub trait Mode: sealed::Hooks {}

impl<T: sealed::Hooks> Mode for T {}

pub(crate) mod sealed {
    use super::{Mesh, TriId, VertexId};

    /// The hooks behind [`super::Mode`] (not nameable outside the crate).
    pub trait Hooks: std::fmt::Debug + Clone {
        /// Do triangles leave the mesh before the end? Then edges facing them are boundary
        /// edges too (see [`crate::sweep::Sweep::check`]).
        #[cfg(any(test, feature = "dev"))]
        const FINALISES: bool;

        /// A freed triangle slot to reuse for the next new triangle, if any.
        fn free_slot(&mut self) -> Option<TriId>;

        /// Triangle slot `t` of `mesh` was (re)filled.
        fn created(&mut self, mesh: &Mesh, t: TriId);

        /// Triangle slots `ta` and `tb` were flipped in place: their shared edge `gone` was
        /// replaced by the edge `new`.
        fn flipped(&mut self, ta: TriId, tb: TriId, gone: [VertexId; 2], new: [VertexId; 2]);

        /// The triangles `dead` of a breakline's cavity are about to be replaced (their slots
        /// are reused for the new triangles, see [`Self::cavity_filled`]).
        fn cavity_removed(&mut self, mesh: &Mesh, dead: &[u32]);

        /// A triangle with these vertices was put into a slot of a breakline's cavity.
        fn cavity_filled(&mut self, tri: [VertexId; 3]);

        /// The breakline segment from constraint vertex `lo` (swept as `v`, at `a`) to the later
        /// constraint vertex `hi` (at `b`) is pending until `hi` is swept.
        fn segment_pending(&mut self, v: VertexId, lo: u32, hi: u32, a: [f64; 2], b: [f64; 2]);

        /// The segment from constraint vertex `lo` (swept as `v`) to `hi` is in.
        fn segment_done(&mut self, v: VertexId, lo: u32, hi: u32);

        /// Drops the resident pages of the mode's own tables that live in temporary files
        /// (called with [`crate::sweep::Sweep::release_spilled`]).
        fn release_spilled(&mut self) {}

        /// Called at every new triangle: should the spilled tables' pages be dropped now
        /// (the mode measures its resident memory every few hundred)?
        #[inline(always)]
        fn spill_due(&mut self) -> bool {
            false
        }
    }
}

/// Batch mode: every triangle stays in memory until [`Sweep::finish`](super::Sweep::finish).
/// All hooks are empty.
#[derive(Clone, Copy, Debug, Default)]
pub struct Batch;

impl sealed::Hooks for Batch {
    #[cfg(any(test, feature = "dev"))]
    const FINALISES: bool = false;

    #[inline(always)]
    fn free_slot(&mut self) -> Option<TriId> {
        None
    }

    #[inline(always)]
    fn created(&mut self, _: &Mesh, _: TriId) {}

    #[inline(always)]
    fn flipped(&mut self, _: TriId, _: TriId, _: [VertexId; 2], _: [VertexId; 2]) {}

    #[inline(always)]
    fn cavity_removed(&mut self, _: &Mesh, _: &[u32]) {}

    #[inline(always)]
    fn cavity_filled(&mut self, _: [VertexId; 3]) {}

    #[inline(always)]
    fn segment_pending(&mut self, _: VertexId, _: u32, _: u32, _: [f64; 2], _: [f64; 2]) {}

    #[inline(always)]
    fn segment_done(&mut self, _: VertexId, _: u32, _: u32) {}
}
