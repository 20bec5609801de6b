//! The block index: every point once, grouped by block, so a tile can read the blocks of its
//! buffered extent without decoding the input again.
//!
//! Reading pushes each point with its block key into the external sort ([`BlockRecord`], a stable
//! sort by key, so the points of a block stay in input order). The merged stream is written once
//! to an anonymous temporary file as bare `[x, y, z]` records (or kept in memory when it fit in
//! one chunk), with a table of the non-empty blocks and where each starts. A row of blocks is one
//! contiguous run of records, so reading a rectangle of blocks is one read per block row.
//!
//! The table also answers *occupancy* (is any point in these blocks?), which the certificates use.

use super::grid::{BlockRect, TileGrid};
use super::hull::hull;
use crate::error::{Error, Result};
use crate::sort::DuplicatePolicy;
use crate::sort::external::{Merge, SortKey};
use std::cmp::Ordering;
use std::fs::File;
use std::io::Write;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// A point with its block key, for the external sort.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct BlockRecord {
    pub key: u64,
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl SortKey for BlockRecord {
    #[inline(always)]
    fn order(a: &Self, b: &Self) -> Ordering {
        a.key.cmp(&b.key)
    }
    // Points of one block keep their input order: the duplicate policy needs it.
    const STABLE: bool = true;
    const RADIX: bool = true;
    #[inline(always)]
    fn radix_key(&self) -> u64 {
        self.key
    }
}

#[derive(Debug)]
enum Store {
    Memory(Vec<[f64; 3]>),
    File { file: File, dir: PathBuf },
}

/// Every point, grouped by block.
#[derive(Debug)]
pub(crate) struct BlockIndex {
    pub grid: TileGrid,
    /// Keys of the non-empty blocks, increasing.
    keys: Vec<u64>,
    /// Record offset of each non-empty block, and the total at the end.
    starts: Vec<u64>,
    /// Tight box of each non-empty block's points.
    extents: Vec<Extent>,
    store: Store,
    /// The blocks holding points: their bounding rectangle.
    occupied: BlockRect,
    /// Corners of the convex hull of the blocks' extreme points.
    hull: Vec<[f64; 3]>,
    /// For a task of a plan: where the points it did not read may be.
    pub scope: Option<Scope>,
}

/// What a task knows of the data (see [`BlockIndex::scope`]).
#[derive(Debug, Clone)]
pub(crate) struct Scope {
    /// Extents of the files the task did not read (closed rectangles, from their headers):
    /// points may lie there. A buffer that reaches one reads the whole file.
    pub unknown: Vec<[f64; 4]>,
    /// Parts of the extents of files the task read only around its tile (COPC): points may lie
    /// there too, and only a buffer that covers them reads them.
    pub beyond: Vec<[f64; 4]>,
    /// The task's tile.
    pub tile: [f64; 4],
    /// How far around its tile the task read.
    pub buffer: f64,
}

/// Does the closed disk of centre `c` and radius `r` meet the closed rectangle `u`? (A little
/// generously: a disk that nearly touches it counts.)
fn disk_meets(u: &[f64; 4], c: [f64; 2], r: f64) -> bool {
    let slack = 1e-9 * (r + c[0].abs().max(c[1].abs()));
    let dx = (u[0] - c[0]).max(c[0] - u[2]).max(0.0);
    let dy = (u[1] - c[1]).max(c[1] - u[3]).max(0.0);
    (dx * dx + dy * dy).sqrt() <= r + slack
}

impl Scope {
    /// The rectangle the task read whole: its tile and buffer (every file meeting it was read).
    pub fn read_rect(&self) -> [f64; 4] {
        let (t, b) = (&self.tile, self.buffer);
        [t[0] - b, t[1] - b, t[2] + b, t[3] + b]
    }

    /// Does the task know every point there is?
    pub fn complete(&self) -> bool {
        self.unknown.is_empty() && self.beyond.is_empty()
    }

    /// The buffer that would read the points not read that may lie in the closed disk of centre
    /// `c` and radius `r` (conservative), or 0 when there are none.
    pub fn disk_reach(&self, c: [f64; 2], r: f64) -> f64 {
        let files = self
            .unknown
            .iter()
            .filter(|u| disk_meets(u, c, r))
            .map(|u| self.reach(u));
        // A part of a file read around the tile: the buffer must cover the disk's box there.
        let parts = self.beyond.iter().filter(|u| disk_meets(u, c, r)).map(|u| {
            let b = [
                (c[0] - r).max(u[0]),
                (c[1] - r).max(u[1]),
                (c[0] + r).min(u[2]),
                (c[1] + r).min(u[3]),
            ];
            self.cover(&b)
        });
        files.chain(parts).fold(0.0, f64::max)
    }

    /// The buffer around the tile that reaches the rectangle `u` (a little more, so that the
    /// plan's closed overlap test selects its file).
    pub fn reach(&self, u: &[f64; 4]) -> f64 {
        let t = &self.tile;
        let d = (u[0] - t[2])
            .max(t[0] - u[2])
            .max(u[1] - t[3])
            .max(t[1] - u[3]);
        d.max(0.0) * (1.0 + 1e-9) + 1e-9
    }

    /// The buffer around the tile that covers the rectangle `u` whole (a little more).
    pub fn cover(&self, u: &[f64; 4]) -> f64 {
        let t = &self.tile;
        let d = (u[2] - t[2])
            .max(t[0] - u[0])
            .max(u[3] - t[3])
            .max(t[1] - u[1]);
        d.max(0.0) * (1.0 + 1e-9) + 1e-9
    }

    /// The buffer that reads whatever may lie in the rectangles of [`Scope::unknown`] and
    /// [`Scope::beyond`] that `meets` accepts (0: none).
    pub fn reach_where(&self, meets: impl Fn(&[f64; 4]) -> bool) -> f64 {
        let files = self.unknown.iter().filter(|u| meets(u)).map(|u| self.reach(u));
        let parts = self.beyond.iter().filter(|u| meets(u)).map(|u| self.cover(u));
        files.chain(parts).fold(0.0, f64::max)
    }
}

/// The tight bounding box of a block's points, as `f32` offsets from the block's lower-left
/// corner, rounded outward (so the box it stands for always holds every point of the block).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Extent([f32; 4]);

impl Extent {
    /// The outward-rounded offsets of `b` (`[xmin, ymin, xmax, ymax]`, world) from `corner`.
    fn new(b: [f64; 4], corner: [f64; 2], block: f64) -> Extent {
        // The f64 difference errs by an ulp of the corner, the f32 rounding by 2^-24 of a block
        // (offsets lie within one block): the margin covers both, and the reverse sum in `world`.
        let m = block * 1e-6 + (corner[0].abs() + corner[1].abs() + block) * 1e-14;
        Extent([
            (b[0] - corner[0] - m) as f32,
            (b[1] - corner[1] - m) as f32,
            (b[2] - corner[0] + m) as f32,
            (b[3] - corner[1] + m) as f32,
        ])
    }

    /// The world box `[xmin, ymin, xmax, ymax]` (a little wider than the points' box).
    #[inline]
    pub fn world(&self, corner: [f64; 2], block: f64) -> [f64; 4] {
        let m = block * 1e-6 + (corner[0].abs() + corner[1].abs() + block) * 1e-14;
        let e = &self.0;
        [
            corner[0] + f64::from(e[0]) - m,
            corner[1] + f64::from(e[1]) - m,
            corner[0] + f64::from(e[2]) + m,
            corner[1] + f64::from(e[3]) + m,
        ]
    }
}

/// The table, the occupied rectangle and the hull candidates, built as the records stream by.
#[derive(Debug)]
struct Builder {
    grid: TileGrid,
    keys: Vec<u64>,
    starts: Vec<u64>,
    extents: Vec<Extent>,
    /// The current block's box, world coordinates.
    current: [f64; 4],
    n: u64,
    occupied: BlockRect,
}

impl Builder {
    fn new(grid: TileGrid) -> Self {
        Builder {
            grid,
            keys: Vec::new(),
            starts: Vec::new(),
            extents: Vec::new(),
            current: EMPTY_BOX,
            n: 0,
            occupied: BlockRect {
                x0: i64::MAX,
                y0: i64::MAX,
                x1: i64::MIN,
                y1: i64::MIN,
            },
        }
    }
}

/// A box holding nothing.
const EMPTY_BOX: [f64; 4] = [
    f64::INFINITY,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
];

impl Builder {
    /// Closes the current block's extent.
    fn close(&mut self) {
        if let Some(&k) = self.keys.last()
            && self.extents.len() < self.keys.len()
        {
            let (bx, by) = TileGrid::unkey(k);
            let g = &self.grid;
            let corner = [bx as f64 * g.block, by as f64 * g.block];
            self.extents
                .push(Extent::new(self.current, corner, g.block));
            self.current = EMPTY_BOX;
        }
    }

    #[inline]
    fn note(&mut self, r: &BlockRecord) {
        if self.keys.last() != Some(&r.key) {
            self.close();
            let (bx, by) = TileGrid::unkey(r.key);
            self.keys.push(r.key);
            self.starts.push(self.n);
            let o = &mut self.occupied;
            o.x0 = o.x0.min(bx);
            o.y0 = o.y0.min(by);
            o.x1 = o.x1.max(bx + 1);
            o.y1 = o.y1.max(by + 1);
        }
        let c = &mut self.current;
        *c = [c[0].min(r.x), c[1].min(r.y), c[2].max(r.x), c[3].max(r.y)];
        self.n += 1;
    }
}

/// Records per batch handed from the merging thread to the writing one.
const BATCH: usize = 1 << 14;

/// Writes the merged stream to `file` as bare `[x, y, z]` records and notes its blocks: the
/// k-way merge on this thread, the block table and the writes on another (batches of
/// [`BATCH`] records through a channel, their vectors handed back), so the two halves of the
/// work overlap.
///
/// # Errors
/// [`Error::Io`] naming `tmp_dir`, the merge's own error, [`Error::Internal`] if the writing
/// thread panicked.
fn write_merged(
    grid: TileGrid,
    merge: &mut Merge<BlockRecord>,
    file: &File,
    tmp_dir: &Path,
) -> Result<Builder> {
    let io = |e| Error::io(tmp_dir, e);
    let (full_tx, full_rx) = crossbeam_channel::bounded::<Vec<BlockRecord>>(2);
    let (empty_tx, empty_rx) = crossbeam_channel::bounded::<Vec<BlockRecord>>(4);
    std::thread::scope(|scope| {
        let writer = scope.spawn(move || -> Result<Builder> {
            let mut b = Builder::new(grid);
            let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
            let mut buf: Vec<[f64; 3]> = Vec::with_capacity(BATCH);
            for batch in full_rx {
                for r in &batch {
                    b.note(r);
                    buf.push([r.x, r.y, r.z]);
                }
                w.write_all(bytemuck::cast_slice(&buf)).map_err(io)?;
                buf.clear();
                // The merging thread may have stopped taking vectors back.
                let _ = empty_tx.try_send(batch);
            }
            w.flush().map_err(io)?;
            Ok(b)
        });
        let mut batch = Vec::with_capacity(BATCH);
        for r in merge.by_ref() {
            batch.push(r);
            if batch.len() == BATCH {
                let mut next = empty_rx
                    .try_recv()
                    .unwrap_or_else(|_| Vec::with_capacity(BATCH));
                next.clear();
                // A writer that stopped says why when joined.
                if full_tx.send(std::mem::replace(&mut batch, next)).is_err() {
                    break;
                }
            }
        }
        if !batch.is_empty() {
            let _ = full_tx.send(batch);
        }
        drop(full_tx);
        let b = writer.join().unwrap_or_else(|p| {
            Err(Error::panicked("the block index's writing thread", &*p))
        })?;
        match merge.take_error() {
            Some(e) => Err(e),
            None => Ok(b),
        }
    })
}

impl BlockIndex {
    /// Builds the index from the merged sort, writing the points to an anonymous file under
    /// `tmp_dir` unless the sort kept them in memory.
    ///
    /// # Errors
    /// [`Error::Io`] naming `tmp_dir`, or the merge's own error.
    pub fn build(
        grid: TileGrid,
        mut merge: Merge<BlockRecord>,
        tmp_dir: &Path,
        policy: DuplicatePolicy,
    ) -> Result<Self> {
        let io = |e| Error::io(tmp_dir, e);
        let mut b = Builder::new(grid);
        let store = if let Some(v) = merge.take_memory() {
            let mut pts = Vec::with_capacity(v.len());
            for r in &v {
                b.note(r);
                pts.push([r.x, r.y, r.z]);
            }
            Store::Memory(pts)
        } else {
            let file = tempfile::tempfile_in(tmp_dir).map_err(io)?;
            b = write_merged(grid, &mut merge, &file, tmp_dir)?;
            Store::File {
                file,
                dir: tmp_dir.to_path_buf(),
            }
        };
        b.close();
        b.starts.push(b.n);
        if b.keys.is_empty() {
            b.occupied = BlockRect {
                x0: 0,
                y0: 0,
                x1: 0,
                y1: 0,
            };
        }
        let mut index = BlockIndex {
            grid,
            keys: b.keys,
            starts: b.starts,
            extents: b.extents,
            store,
            occupied: b.occupied,
            hull: Vec::new(),
            scope: None,
        };
        index.hull = index.convex_hull()?;
        index.resolve_hull_heights(policy)?;
        Ok(index)
    }

    /// Gives each hull corner the height the duplicate policy keeps among the points at its
    /// position (they all lie in its block), so that a run holding the corner but not its block
    /// has the same vertex as a run holding the block.
    fn resolve_hull_heights(&mut self, policy: DuplicatePolicy) -> Result<()> {
        let mut pts = Vec::new();
        let mut hull = std::mem::take(&mut self.hull);
        for c in &mut hull {
            let (bx, by) = self.grid.block_of(c[0], c[1]);
            pts.clear();
            self.read_block(TileGrid::key(bx, by), &mut pts)?;
            let mut keep: Option<(usize, f64)> = None;
            for (i, p) in pts.iter().enumerate() {
                if p[0] == c[0] && p[1] == c[1] {
                    keep = match keep {
                        Some(k) if !policy.prefers((p[2], i as u64), (k.1, k.0 as u64)) => Some(k),
                        _ => Some((i, p[2])),
                    };
                }
            }
            if let Some((_, z)) = keep {
                c[2] = z;
            }
        }
        self.hull = hull;
        Ok(())
    }

    /// The world box of the points of non-empty block `key` (slightly wider), if it has points.
    #[inline]
    pub fn extent(&self, key: u64) -> Option<[f64; 4]> {
        let i = self.keys.binary_search(&key).ok()?;
        let (bx, by) = TileGrid::unkey(key);
        let b = self.grid.block;
        Some(self.extents[i].world([bx as f64 * b, by as f64 * b], b))
    }

    /// The corners of the convex hull of all the points. Only blocks with an empty diagonal
    /// neighbour can hold one: a point of a block whose four diagonal neighbours hold points is
    /// beaten in every direction by a point of the neighbour in that quadrant (block assignment
    /// is monotone in each coordinate), so it is inside the hull.
    fn convex_hull(&self) -> Result<Vec<[f64; 3]>> {
        let has = |bx: i64, by: i64| self.keys.binary_search(&TileGrid::key(bx, by)).is_ok();
        let mut h: Vec<[f64; 3]> = Vec::new();
        let mut row: Vec<[f64; 3]> = Vec::new();
        let mut row_y = None;
        for (i, &k) in self.keys.iter().enumerate() {
            let (bx, by) = TileGrid::unkey(k);
            if row_y != Some(by) && !row.is_empty() {
                row.extend_from_slice(&h);
                h = hull(&mut row);
                row.clear();
            }
            row_y = Some(by);
            let inner = has(bx - 1, by - 1)
                && has(bx + 1, by - 1)
                && has(bx - 1, by + 1)
                && has(bx + 1, by + 1);
            if !inner {
                let before = row.len();
                self.read_span(
                    self.starts[i] as usize,
                    self.starts[i + 1] as usize,
                    &mut row,
                )?;
                // Keep the block's own hull only.
                let mut mine = row.split_off(before);
                row.extend(hull(&mut mine));
            }
        }
        row.extend_from_slice(&h);
        Ok(hull(&mut row))
    }

    /// Hull candidates of all the points (see [`super::hull`]).
    pub fn hull(&self) -> &[[f64; 3]] {
        &self.hull
    }

    /// Adds breakline vertices to the data: the blocks `blocks` holding them count as occupied
    /// (a tile with a vertex runs; a run that reads every occupied block loads every segment),
    /// and `hull`, the corners of the hull of the points and the vertices, replaces the points'.
    pub fn add_lines(&mut self, blocks: BlockRect, hull: Vec<[f64; 3]>) {
        if !blocks.is_empty() {
            self.occupied = if self.occupied.is_empty() {
                blocks
            } else {
                self.occupied.union(&blocks)
            };
        }
        self.hull = hull;
    }

    /// Number of points.
    pub fn len(&self) -> u64 {
        *self.starts.last().unwrap_or(&0)
    }

    /// The bounding rectangle of the non-empty blocks.
    pub fn occupied(&self) -> BlockRect {
        self.occupied
    }

    /// Bytes the index holds in memory: the block table, and the points when they are not in
    /// a file.
    pub fn memory_bytes(&self) -> u64 {
        let table = self.keys.len() * (8 + 8 + std::mem::size_of::<Extent>());
        let points = match &self.store {
            Store::Memory(v) => v.len() * 24,
            Store::File { .. } => 0,
        };
        (table + points) as u64
    }

    /// Number of non-empty blocks.
    pub fn blocks(&self) -> usize {
        self.keys.len()
    }

    /// Indices into `keys` of the non-empty blocks of row `by` in columns `x0 .. x1`.
    #[inline]
    fn row_range(&self, by: i64, x0: i64, x1: i64) -> std::ops::Range<usize> {
        if x1 <= x0 {
            return 0..0;
        }
        let lo = self.keys.partition_point(|&k| k < TileGrid::key(x0, by));
        let hi = self.keys.partition_point(|&k| k < TileGrid::key(x1, by));
        lo..hi.max(lo)
    }

    /// Is any point in row `by`, columns `x0 .. x1`?
    #[inline]
    #[cfg(test)]
    pub fn any_in_row(&self, by: i64, x0: i64, x1: i64) -> bool {
        !self.row_range(by, x0, x1).is_empty()
    }

    /// Keys of the non-empty blocks of row `by` in columns `x0 .. x1`.
    #[inline]
    pub fn keys_in_row(&self, by: i64, x0: i64, x1: i64) -> &[u64] {
        &self.keys[self.row_range(by, x0, x1)]
    }

    /// Appends the points of the non-empty block `key` to `out`.
    ///
    /// # Errors
    /// As [`BlockIndex::read`].
    pub fn read_block(&self, key: u64, out: &mut Vec<[f64; 3]>) -> Result<()> {
        let Ok(i) = self.keys.binary_search(&key) else {
            return Ok(());
        };
        self.read_span(self.starts[i] as usize, self.starts[i + 1] as usize, out)
    }

    fn read_span(&self, a: usize, b: usize, out: &mut Vec<[f64; 3]>) -> Result<()> {
        if a == b {
            return Ok(());
        }
        match &self.store {
            Store::Memory(v) => out.extend_from_slice(&v[a..b]),
            Store::File { file, dir } => {
                let old = out.len();
                out.resize(old + (b - a), [0.0; 3]);
                let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out[old..]);
                file.read_exact_at(bytes, (a * 24) as u64)
                    .map_err(|e| Error::io(dir, e))?;
            }
        }
        Ok(())
    }

    /// Points in the blocks of `r`.
    pub fn count(&self, r: &BlockRect) -> u64 {
        (r.y0..r.y1)
            .map(|by| {
                let k = self.row_range(by, r.x0, r.x1);
                self.starts[k.end] - self.starts[k.start]
            })
            .sum()
    }

    /// Appends the points of the blocks of `r` to `out`: block rows from south to north, blocks
    /// west to east, each block's points in input order.
    ///
    /// # Errors
    /// [`Error::Io`] if the index file cannot be read.
    pub fn read(&self, r: &BlockRect, out: &mut Vec<[f64; 3]>) -> Result<()> {
        let r = r.intersect(&self.occupied);
        out.reserve(self.count(&r) as usize);
        for by in r.y0..r.y1 {
            let k = self.row_range(by, r.x0, r.x1);
            self.read_span(
                self.starts[k.start] as usize,
                self.starts[k.end] as usize,
                out,
            )?;
        }
        Ok(())
    }
}

/// The block index of `pts` on `grid`, sorted within `mem` bytes under `dir` (for tests).
#[cfg(test)]
pub(crate) fn index(mem: u64, pts: &[[f64; 3]], grid: TileGrid, dir: &Path) -> BlockIndex {
    use crate::sort::external::ExternalSorter;
    let mut s = ExternalSorter::<BlockRecord>::new(mem, dir);
    for p in pts {
        let (bx, by) = grid.block_of(p[0], p[1]);
        s.push(BlockRecord {
            key: TileGrid::key(bx, by),
            x: p[0],
            y: p[1],
            z: p[2],
        })
        .unwrap();
    }
    BlockIndex::build(grid, s.finish().unwrap(), dir, DuplicatePolicy::First).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spilled_and_in_memory_indexes_agree_and_keep_input_order() {
        let dir = tempfile::tempdir().unwrap();
        let grid = TileGrid::new(16.0, 2).unwrap();
        let mut pts = Vec::new();
        let mut s = 99u64;
        for i in 0..50_000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let x = ((s >> 33) % 6400) as f64 / 100.0 - 10.0;
            let y = ((s >> 13) % 6400) as f64 / 100.0 - 20.0;
            pts.push([x, y, i as f64]);
        }
        let a = index(1, &pts, grid, dir.path());
        let b = index(1 << 30, &pts, grid, dir.path());
        assert_eq!(a.len(), 50_000);
        assert_eq!(a.occupied(), b.occupied());
        let r = BlockRect {
            x0: -2,
            y0: -3,
            x1: 5,
            y1: 4,
        };
        let (mut va, mut vb) = (Vec::new(), Vec::new());
        a.read(&r, &mut va).unwrap();
        b.read(&r, &mut vb).unwrap();
        assert_eq!(va, vb);
        assert_eq!(va.len() as u64, a.count(&r));
        let expect: Vec<[f64; 3]> = {
            let mut e: Vec<_> = pts
                .iter()
                .filter(|p| {
                    let (bx, by) = grid.block_of(p[0], p[1]);
                    r.contains(bx, by)
                })
                .copied()
                .collect();
            // Row-major by block, input order (z) within a block.
            e.sort_by_key(|p| {
                let (bx, by) = grid.block_of(p[0], p[1]);
                (TileGrid::key(bx, by), p[2] as u64)
            });
            e
        };
        assert_eq!(va, expect);
        // Everything, across the writer's batches: the same records, blocks and extents.
        let (mut wa, mut wb) = (Vec::new(), Vec::new());
        a.read(&a.occupied(), &mut wa).unwrap();
        b.read(&b.occupied(), &mut wb).unwrap();
        assert_eq!(wa.len(), 50_000);
        assert_eq!(wa, wb);
        assert_eq!((&a.keys, &a.starts), (&b.keys, &b.starts));
        for &k in &a.keys {
            assert_eq!(a.extent(k), b.extent(k));
        }
        assert!(a.any_in_row(0, -2, 5));
        assert!(!a.any_in_row(100, -2, 5));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
