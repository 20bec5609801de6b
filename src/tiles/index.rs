//! The block index: every point once, grouped by block, so a tile can read the blocks of its
//! buffered extent without decoding the input again.
//!
//! Reading pushes each point with its block key into the external sort (a stable sort by key, so
//! the points of a block stay in input order). The merged stream is written once to an anonymous
//! temporary file as bare points (or kept in memory when it fit in one chunk), with a table of
//! the non-empty blocks and where each starts. A row of blocks is one contiguous run of records,
//! so reading a rectangle of blocks is one read per block row.
//!
//! **Packing.** When the input files share one decimal lattice ([`Lattice`]: short decimal
//! scales and offsets, headers that bound their points) and the blocks of their boxes fit a
//! 32-bit key, a point is sorted as a [`PackedRecord`] (16 bytes: the key and three lattice
//! integers) and stored as its three integers (12 bytes), which decode to the very doubles the
//! reader gave. Otherwise it is sorted as a [`BlockRecord`] (32 bytes) and stored as `[x, y, z]`
//! (24 bytes). The spilled and stored bytes, the temporary disk and the kernel's copying are
//! halved; the points, their order and every output are the same either way.
//!
//! The table also answers *occupancy* (is any point in these blocks?), which the certificates use.

use super::grid::{BlockRect, TileGrid};
use super::hull::hull;
use crate::error::{Error, Result};
use crate::input::las::world::Lattice;
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

/// Both records of the index sort by their block key alone, stably: points of one block keep
/// their input order (the duplicate policy needs it).
macro_rules! sort_by_block_key {
    ($record:ty) => {
        impl SortKey for $record {
            #[inline(always)]
            fn order(a: &Self, b: &Self) -> Ordering {
                a.key.cmp(&b.key)
            }
            const STABLE: bool = true;
            const RADIX: bool = true;
            #[inline(always)]
            fn radix_key(&self) -> u64 {
                u64::from(self.key)
            }
        }
    };
}

sort_by_block_key!(BlockRecord);
sort_by_block_key!(PackedRecord);
sort_by_block_key!(TaggedRecord);

/// A point with its block key in 16 bytes ([`Packing`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct PackedRecord {
    key: u32,
    q: [u32; 3],
}

/// How points are packed: their lattice, and block keys counted from the lowest block of the
/// input's box, the column in the low `shift` bits (row-major, as [`TileGrid::key`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Packing {
    lattice: Lattice,
    bx0: i64,
    by0: i64,
    shift: u32,
}

impl Packing {
    /// The packing of points on `lattice` (in its box: the headers' boxes, the margin the reader
    /// allows included) with blocks of `grid`, or `None` when the box has more blocks than
    /// 32-bit keys count.
    pub fn new(lattice: Lattice, grid: &TileGrid) -> Option<Packing> {
        let b = lattice.xy_box();
        let (bx0, by0) = grid.block_of(b[0], b[1]);
        let (bx1, by1) = grid.block_of(b[2], b[3]);
        let (bx0, by0, bx1, by1) = (bx0 - 1, by0 - 1, bx1 + 1, by1 + 1);
        let shift = 64 - ((bx1 - bx0) as u64).leading_zeros();
        let rows = (by1 - by0 + 1) as u64;
        (shift <= 32 && rows <= 1u64 << (32 - shift)).then_some(Packing {
            lattice,
            bx0,
            by0,
            shift,
        })
    }

    /// The record of point `p` in block `(bx, by)`.
    ///
    /// # Errors
    /// [`Error::Internal`] for a point outside the lattice's box (the reader lets none
    /// through).
    #[inline]
    pub fn pack(&self, (bx, by): (i64, i64), p: [f64; 3]) -> Result<PackedRecord> {
        let (c, r) = (bx - self.bx0, by - self.by0);
        let fits = (0..1i64 << self.shift).contains(&c) && (0..1i64 << (32 - self.shift)).contains(&r);
        match self.lattice.encode(p) {
            Some(q) if fits => Ok(PackedRecord {
                key: (((r as u64) << self.shift) | c as u64) as u32,
                q,
            }),
            _ => Err(Error::Internal(format!(
                "point ({}, {}, {}) lies outside the files' headers' box",
                p[0], p[1], p[2]
            ))),
        }
    }
}

/// A sort record of the index: its block key and point, and what the index's file stores.
pub(crate) trait IndexRecord: SortKey + bytemuck::Pod + Send {
    /// A point as the index's file stores it.
    type Stored: bytemuck::Pod + Send;
    /// The record of point `p` in block `(bx, by)` (a packed record needs its packing).
    ///
    /// # Errors
    /// As [`Packing::pack`].
    fn pack(packing: Option<&Packing>, block: (i64, i64), p: [f64; 3]) -> Result<Self>;
    /// The block key ([`TileGrid::key`]) and the point.
    fn unpack(&self, packing: Option<&Packing>) -> (u64, [f64; 3]);
    /// The point as stored.
    fn stored(&self) -> Self::Stored;
    /// Does the record carry a tag the index keeps ([`TaggedRecord`])?
    const TAGGED: bool = false;
    /// The record's tag (0 for untagged records).
    #[inline]
    fn tag(&self) -> u64 {
        0
    }
}

impl IndexRecord for BlockRecord {
    type Stored = [f64; 3];
    #[inline]
    fn pack(_: Option<&Packing>, (bx, by): (i64, i64), [x, y, z]: [f64; 3]) -> Result<Self> {
        // The headers' boxes were checked against the grid; a point of a file whose box says
        // nothing was not, and its key must not wrap.
        const LIMIT: u64 = (1 << 31) - 2;
        if bx.unsigned_abs() > LIMIT || by.unsigned_abs() > LIMIT {
            return Err(Error::Options(format!(
                "the point ({x}, {y}) lies too far from the origin for the tiles' blocks \
                 (its file's header box says nothing): give a larger --tile, or --engine sweep"
            )));
        }
        Ok(BlockRecord {
            key: TileGrid::key(bx, by),
            x,
            y,
            z,
        })
    }
    #[inline]
    fn unpack(&self, _: Option<&Packing>) -> (u64, [f64; 3]) {
        (self.key, [self.x, self.y, self.z])
    }
    #[inline]
    fn stored(&self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

impl IndexRecord for PackedRecord {
    type Stored = [u32; 3];
    #[inline]
    fn pack(packing: Option<&Packing>, block: (i64, i64), p: [f64; 3]) -> Result<Self> {
        packing
            .expect("packed records come with their packing")
            .pack(block, p)
    }
    #[inline]
    fn unpack(&self, packing: Option<&Packing>) -> (u64, [f64; 3]) {
        let p = packing.expect("packed records come with their packing");
        let k = u64::from(self.key);
        let (c, r) = (k & ((1u64 << p.shift) - 1), k >> p.shift);
        let key = TileGrid::key(p.bx0 + c as i64, p.by0 + r as i64);
        (key, p.lattice.decode(self.q))
    }
    #[inline]
    fn stored(&self) -> [u32; 3] {
        self.q
    }
}

#[derive(Debug)]
enum Store {
    Memory(Vec<[f64; 3]>),
    /// Points as `[x, y, z]`, or as lattice integers with a packing.
    File {
        file: File,
        dir: PathBuf,
        packing: Option<Packing>,
    },
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
    /// The tags of tagged records ([`TaggedRecord`]), in the points' order.
    tags: Option<Tags>,
    /// The blocks holding points: their bounding rectangle.
    occupied: BlockRect,
    /// Corners of the convex hull of the blocks' extreme points.
    hull: Vec<[f64; 3]>,
    /// For a task of a plan: where the points it did not read may be.
    pub scope: Option<Scope>,
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
    fn note(&mut self, key: u64, p: &[f64; 3]) {
        if self.keys.last() != Some(&key) {
            self.close();
            let (bx, by) = TileGrid::unkey(key);
            self.keys.push(key);
            self.starts.push(self.n);
            let o = &mut self.occupied;
            o.x0 = o.x0.min(bx);
            o.y0 = o.y0.min(by);
            o.x1 = o.x1.max(bx + 1);
            o.y1 = o.y1.max(by + 1);
        }
        let c = &mut self.current;
        *c = [c[0].min(p[0]), c[1].min(p[1]), c[2].max(p[0]), c[3].max(p[1])];
        self.n += 1;
    }
}

/// Records per batch handed from the merging thread to the writing one.
const BATCH: usize = 1 << 14;

/// Writes the merged stream to `file` as stored points and notes its blocks: the
/// k-way merge on this thread, the block table and the writes on another (batches of
/// [`BATCH`] records through a channel, their vectors handed back), so the two halves of the
/// work overlap.
///
/// # Errors
/// [`Error::Io`] naming `tmp_dir`, the merge's own error, [`Error::Internal`] if the writing
/// thread panicked.
fn write_merged<R: IndexRecord>(
    grid: TileGrid,
    packing: Option<&Packing>,
    merge: &mut Merge<R>,
    file: &File,
    tags: Option<&File>,
    tmp_dir: &Path,
) -> Result<Builder> {
    let io = |e| Error::io(tmp_dir, e);
    let (full_tx, full_rx) = crossbeam_channel::bounded::<Vec<R>>(2);
    let (empty_tx, empty_rx) = crossbeam_channel::bounded::<Vec<R>>(4);
    std::thread::scope(|scope| {
        let writer = scope.spawn(move || -> Result<Builder> {
            let mut b = Builder::new(grid);
            let mut w = std::io::BufWriter::with_capacity(crate::sort::WRITE_PIECE, file);
            let mut buf: Vec<R::Stored> = Vec::with_capacity(BATCH);
            let mut tw = tags.map(|f| std::io::BufWriter::with_capacity(crate::sort::WRITE_PIECE, f));
            let mut tbuf: Vec<u64> = Vec::new();
            for batch in full_rx {
                for r in &batch {
                    let (key, p) = r.unpack(packing);
                    b.note(key, &p);
                    buf.push(r.stored());
                }
                crate::sort::write_pieces(&mut w, bytemuck::cast_slice(&buf)).map_err(io)?;
                buf.clear();
                if let Some(tw) = tw.as_mut() {
                    tbuf.extend(batch.iter().map(|r| r.tag()));
                    crate::sort::write_pieces(tw, bytemuck::cast_slice(&tbuf)).map_err(io)?;
                    tbuf.clear();
                }
                // The merging thread may have stopped taking vectors back.
                let _ = empty_tx.try_send(batch);
            }
            w.flush().map_err(io)?;
            if let Some(tw) = tw.as_mut() {
                tw.flush().map_err(io)?;
            }
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
    pub fn build<R: IndexRecord>(
        grid: TileGrid,
        mut merge: Merge<R>,
        packing: Option<Packing>,
        tmp_dir: &Path,
        policy: DuplicatePolicy,
    ) -> Result<Self> {
        let io = |e| Error::io(tmp_dir, e);
        let mut b = Builder::new(grid);
        let mut tags = None;
        let store = if let Some(v) = merge.take_memory() {
            let mut pts = Vec::with_capacity(v.len());
            for r in &v {
                let (key, p) = r.unpack(packing.as_ref());
                b.note(key, &p);
                pts.push(p);
            }
            if R::TAGGED {
                tags = Some(Tags::Memory(v.iter().map(|r| r.tag()).collect()));
            }
            Store::Memory(pts)
        } else {
            let file = tempfile::tempfile_in(tmp_dir).map_err(io)?;
            let tag_file = if R::TAGGED {
                Some(tempfile::tempfile_in(tmp_dir).map_err(io)?)
            } else {
                None
            };
            b = write_merged(
                grid,
                packing.as_ref(),
                &mut merge,
                &file,
                tag_file.as_ref(),
                tmp_dir,
            )?;
            tags = tag_file.map(Tags::File);
            Store::File {
                file,
                dir: tmp_dir.to_path_buf(),
                packing,
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
            tags,
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
        let keys = &self.keys;
        // Diagonal neighbours are looked up by cursors that only move forward through the rows
        // below and above (the keys are sorted row by row, then by column): one each for the
        // column before and the column after.
        let (mut below, mut above) = ([0usize; 2], [0usize; 2]);
        let has = |cursor: &mut usize, bx: i64, by: i64| {
            let k = TileGrid::key(bx, by);
            while *cursor < keys.len() && keys[*cursor] < k {
                *cursor += 1;
            }
            keys.get(*cursor) == Some(&k)
        };
        let mut h: Vec<[f64; 3]> = Vec::new();
        let mut row: Vec<[f64; 3]> = Vec::new();
        let mut row_y = None;
        for (i, &k) in keys.iter().enumerate() {
            let (bx, by) = TileGrid::unkey(k);
            if row_y != Some(by) && !row.is_empty() {
                row.extend_from_slice(&h);
                h = hull(&mut row);
                row.clear();
            }
            row_y = Some(by);
            let inner = has(&mut below[0], bx - 1, by - 1)
                && has(&mut below[1], bx + 1, by - 1)
                && has(&mut above[0], bx - 1, by + 1)
                && has(&mut above[1], bx + 1, by + 1);
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
        let tags = match &self.tags {
            Some(Tags::Memory(v)) => v.len() * 8,
            _ => 0,
        };
        (table + points + tags) as u64
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
            Store::File {
                file,
                dir,
                packing: None,
            } => {
                let old = out.len();
                out.resize(old + (b - a), [0.0; 3]);
                let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out[old..]);
                file.read_exact_at(bytes, (a * 24) as u64)
                    .map_err(|e| Error::io(dir, e))?;
            }
            Store::File {
                file,
                dir,
                packing: Some(p),
            } => {
                let (old, n) = (out.len(), b - a);
                out.resize(old + n, [0.0; 3]);
                // The packed points go to the upper half of the new points' bytes and are
                // unpacked in place, front to back: point `i` is read (at byte `12 n + 12 i`)
                // before point `i` is written (bytes `24 i .. 24 i + 24`, below `12 n + 12 (i + 1)`).
                let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out[old..]);
                file.read_exact_at(&mut bytes[12 * n..], (a * 12) as u64)
                    .map_err(|e| Error::io(dir, e))?;
                for i in 0..n {
                    let at = 12 * n + 12 * i;
                    let q: [u32; 3] = bytemuck::pod_read_unaligned(&bytes[at..at + 12]);
                    let v = p.lattice.decode(q);
                    bytes[24 * i..24 * i + 24].copy_from_slice(bytemuck::bytes_of(&v));
                }
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
    BlockIndex::build(grid, s.finish().unwrap(), None, dir, DuplicatePolicy::First).unwrap()
}

mod scope;
pub(crate) use scope::{Extent, Scope, Within, inner_polygon};
mod tagged;
pub(crate) use tagged::TaggedRecord;
use tagged::Tags;

#[cfg(test)]
mod tests;
