//! The streaming sweep's tables that grow with the triangles it holds, and their spill.
//!
//! An ordinary front holds a few rows of triangles, but points on (or near) one line or one
//! circle keep every triangle open to the end of the sweep (each circumdisk reaches past every
//! later point), so the triangles held grow with the points: about 300 bytes each with their
//! share of vertices and queue entries. Past a threshold derived from `--mem`
//! ([`SpillPolicy`]), the per-triangle and per-vertex tables ([`SpillVec`]s: the mesh's two
//! half-edge arrays, the point table, the finaliser's due buckets, blocked counts and vertex
//! rows) move into shared maps of anonymous temporary files under `--tmp-dir`, and whenever
//! the process's file-backed resident memory has grown by the budget since the last time, their
//! pages are dropped from it ([`SpillVec::release`]): the data stays in the files' page cache,
//! which the kernel may write out and reclaim, and a later touch faults it back in. What is
//! decided never depends on where the tables are, so the output is the same.

use crate::error::{Error, Result};
use crate::sort::mmap::SpillVec;
use std::path::PathBuf;

/// Where and past what size the tables of held triangles spill (see the module docs).
#[derive(Clone, Debug)]
pub struct SpillPolicy {
    /// Directory of the temporary files (`--tmp-dir`).
    pub dir: PathBuf,
    /// The run's memory budget (`--mem`): the tables spill once their heap passes a quarter of
    /// it, and their resident pages are dropped whenever they grow by that much again.
    pub mem: u64,
}

/// Pages of the spilled tables that may come into memory between two readings of the
/// file-backed resident memory ([`Spill::touched`]): each step that touches the tables counts
/// what it may bring in (random pages when the held triangles and the front's nodes are not in
/// sweep order, as on a ring of points, where 1,024 checks brought 60–100 MB of the files in
/// between two looks, and a point inserted near the ring's top filled and legalised hundreds of
/// thousands of triangles: 130 MB in 0.2 s). A thread that read the resident memory every
/// 2 ms and raised a flag for every step to read dropped them sooner, by 5 MB on the 10 M ring
/// at `--mem 64M` (71 against 76 MB, bound 128): not worth a thread.
pub(super) const LOOK_EVERY_PAGES: u64 = 2048;
/// A finality check, and a front node scanned under its disk: about a page each.
pub(super) const PAGES_A_CHECK: u64 = 1;
/// A step of the sweep (a new triangle, a flip): the rows of its triangles and vertices.
pub(super) const PAGES_A_STEP: u64 = 8;
/// A far-queue entry pulled into the ring: about a page a level of the heap past its first
/// pages (some 15 levels for millions of entries).
pub(super) const PAGES_A_PULL: u64 = 16;
/// A triangle emitted at the end of the sweep: the rows of its triangle, neighbours and
/// vertices (on a ring, 4,096 emitted brought 160 MB in).
pub(super) const PAGES_AN_EMISSION: u64 = 8;

/// Points between two looks at the tables' size (and, once spilled, at the resident memory).
pub(super) const CHECK_EVERY: u64 = 4096;
/// Smallest threshold, whatever `--mem`.
const MIN_SPILL: u64 = 2 << 20;

/// Per-vertex data needed only when streaming (the same rows as the core's vertex table).
#[derive(Debug, Clone, Default)]
pub(super) struct VertexTable {
    pub(super) z: SpillVec<f64>,
    pub(super) index: SpillVec<u64>,
    /// Output number, or `NOT_OUT`.
    pub(super) out: SpillVec<u64>,
    /// Live triangles and pending breakline segments using the vertex.
    pub(super) refs: SpillVec<u32>,
    /// Rows of released vertices, to reuse.
    pub(super) free: Vec<u32>,
}

impl VertexTable {
    /// Appends a row.
    pub(super) fn push(&mut self, z: f64, index: u64) {
        self.z.push(z);
        self.index.push(index);
        self.out.push(super::NOT_OUT);
        self.refs.push(0);
    }

    /// Stores point `p` in a freed row, or a new one; returns the row (the vertex id).
    pub(super) fn add(&mut self, p: &super::StreamPoint) -> u32 {
        match self.free.pop() {
            Some(v) => {
                let i = v as usize;
                self.z[i] = p.z;
                self.index[i] = p.index;
                self.out[i] = super::NOT_OUT;
                self.refs[i] = 0;
                v
            }
            None => {
                self.push(p.z, p.index);
                (self.z.len() - 1) as u32
            }
        }
    }
}

/// One spillable table, whatever its element type.
pub(super) trait Table {
    fn heap_bytes(&self) -> usize;
    fn mapped_bytes(&self) -> usize;
    fn spill(&mut self, dir: &std::path::Path) -> std::io::Result<()>;
    fn release(&mut self);
    /// Room for a quarter more (at least 64 Ki elements), reserved when it cannot fail later.
    fn headroom(&mut self) -> std::io::Result<()>;
}

impl<T: bytemuck::Pod> Table for SpillVec<T> {
    fn heap_bytes(&self) -> usize {
        SpillVec::heap_bytes(self)
    }
    fn mapped_bytes(&self) -> usize {
        if self.is_mapped() {
            self.capacity() * std::mem::size_of::<T>()
        } else {
            0
        }
    }
    fn spill(&mut self, dir: &std::path::Path) -> std::io::Result<()> {
        SpillVec::spill(self, dir)
    }
    fn release(&mut self) {
        SpillVec::release(self)
    }
    fn headroom(&mut self) -> std::io::Result<()> {
        if self.is_mapped() {
            self.try_reserve((self.len() / 4).max(1 << 16))
        } else {
            Ok(())
        }
    }
}

/// The spill's state: whether the tables are in files, and the resident memory since the last
/// release.
#[derive(Debug, Clone, Default)]
pub(super) struct Spill {
    policy: Option<SpillPolicy>,
    spilled: bool,
    /// File-backed resident bytes of the process just after the last release.
    base: u64,
    /// Pages counted by [`Spill::touched`] since the last reading of the resident memory.
    touched: u64,
    /// Most bytes of the tables in their files at once.
    pub(super) peak_spilled: u64,
    /// Times the tables' pages were dropped from the resident set.
    pub(super) releases: u64,
}

impl Spill {
    pub(super) fn new(policy: Option<SpillPolicy>) -> Self {
        Spill {
            policy,
            ..Spill::default()
        }
    }

    /// Looks at `tables` (every few thousand points): spills them once their heap passes the
    /// threshold, keeps room in their files, and drops their resident pages when the
    /// file-backed resident memory has grown by the budget since the last release.
    ///
    /// # Errors
    /// [`Error::Write`] naming the temporary directory when a spilled table's file cannot
    /// grow (the disk is full).
    pub(super) fn look(&mut self, tables: &mut [&mut dyn Table]) -> Result<()> {
        let Some(p) = &self.policy else {
            return Ok(());
        };
        let budget = (p.mem / 4).max(MIN_SPILL);
        if !self.spilled {
            let heap: usize = tables.iter().map(|t| t.heap_bytes()).sum();
            if (heap as u64) < budget {
                return Ok(());
            }
            // A table that cannot spill (no room, an address-space limit) stays on the heap:
            // the run goes on as it would have without the spill.
            for t in tables.iter_mut() {
                let _ = t.spill(&p.dir);
                // The copy brought every page in: they would count in the base below.
                t.release();
            }
            self.spilled = true;
            self.base = crate::limits::file_rss().unwrap_or(0);
        }
        for t in tables.iter_mut() {
            t.headroom().map_err(|e| {
                let what = format!(
                    "the temporary file of the triangles the sweep holds cannot grow ({e}): \
                     give --tmp-dir a directory with more free space"
                );
                Error::write(&p.dir, std::io::Error::new(e.kind(), what))
            })?;
        }
        let mapped: usize = tables.iter().map(|t| t.mapped_bytes()).sum();
        self.peak_spilled = self.peak_spilled.max(mapped as u64);
        if self.grown() {
            for t in tables.iter_mut() {
                t.release();
            }
            self.released();
        }
        Ok(())
    }

    /// Has the file-backed resident memory grown by the budget since the last release (the
    /// tables spilled)? Reads `/proc/self/statm` now.
    pub(super) fn grown(&self) -> bool {
        let Some(p) = self.policy.as_ref().filter(|_| self.spilled) else {
            return false;
        };
        let resident = crate::limits::file_rss().unwrap_or(0);
        resident > self.base + (p.mem / 4).max(MIN_SPILL)
    }

    /// Counts `pages` of the tables that a step may have brought into memory; `true` when
    /// their pages should be dropped now: [`LOOK_EVERY_PAGES`] have been counted since the
    /// last reading and `/proc/self/statm` says the file-backed resident memory grew by the
    /// budget since the last release. The one count of every step that touches the tables
    /// (checks, the sweep's new triangles and flips, far pulls, the end's emission).
    #[inline(always)]
    pub(super) fn touched(&mut self, pages: u64) -> bool {
        if !self.spilled {
            return false;
        }
        self.touched += pages;
        if self.touched < LOOK_EVERY_PAGES {
            return false;
        }
        self.touched = 0;
        self.grown()
    }

    /// The tables' pages were just dropped: the growth counts from here.
    pub(super) fn released(&mut self) {
        if self.spilled {
            self.releases += 1;
            self.touched = 0;
            self.base = crate::limits::file_rss().unwrap_or(0);
        }
    }
}
