//! The point store of a plan (`DIR/index/points`, [`PointStore`]): every point its tasks may
//! read (the job's filters applied), decoded once when the plan is saved and grouped by square
//! cells, so that a task reads the cells meeting its tile and buffer instead of decoding LAZ
//! chunks (docs/SCALING.md, "The plan's point store").
//!
//! **Order.** The points are sorted by cell with the block index's stable sort
//! ([`super::index`]): each cell's points keep their input order. A cell is a whole power of two
//! of a task's blocks (both grids from the origin), so every block lies in one cell and the
//! points of a block reach the task's own sort in input order whatever the order of the cells:
//! the task's block index is the one a read of the LAZ file by area builds. A task whose blocks
//! are larger than a cell (very sparse data) reads the LAZ file instead ([`PointStore::nests`]).
//!
//! **Layout.** The points, cell after cell, each as the block index stores it (three lattice
//! integers, 12 bytes, when the file's scale and offset are short decimals, else `[x, y, z]`,
//! 24 bytes); then a table of the cells (96 bytes each: the cell, its first point, its points,
//! the box of its points, the SHA-256 of its bytes); then a trailer of [`TRAILER`] bytes (magic,
//! the plan's id, the cell side, the lattice, the counts, and the SHA-256 of the table and the
//! trailer). The file is written under a temporary name and renamed when whole. A task checks
//! the table when it opens the store and every cell it reads against its checksum: a store that
//! is missing, truncated, edited or of another plan is refused (exit status 3).

use super::grid::TileGrid;
use super::index::{BlockRecord, IndexRecord, PackedRecord, Packing};
use crate::error::{Error, Result};
use crate::input::las::LidarReader;
use crate::input::las::world::Lattice;
use crate::sort::external::ExternalSorter;
use sha2::{Digest, Sha256};
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"STPOINT1";
/// A cell's entry: cx, cy, first point, points, box, SHA-256.
const CELL: usize = 8 * 4 + 32 + 32;
/// Magic, plan id, cell side, packed flag, lattice (10^k, bases, extents, padding), cells,
/// points, SHA-256.
const TRAILER: usize = 8 + 64 + 8 + 8 + 8 + 24 + 16 + 8 + 8 + 32;
/// Points read from the file at once.
const PIECE: usize = 1 << 16;

/// The plan's point store, its table read and checked ([`crate::TaskScope::store`]).
#[derive(Debug)]
pub struct PointStore {
    path: PathBuf,
    file: File,
    cell: f64,
    lattice: Option<Lattice>,
    cells: Vec<Cell>,
    points: u64,
}

impl PartialEq for PointStore {
    fn eq(&self, o: &PointStore) -> bool {
        self.path == o.path && self.cell == o.cell && self.points == o.points
    }
}

#[derive(Clone, Debug)]
struct Cell {
    cx: i64,
    cy: i64,
    first: u64,
    count: u64,
    rect: [f64; 4],
    sum: [u8; 32],
}

/// What a task read from the store ([`PointStore::read_area`]).
pub(crate) struct AreaRead {
    /// Where points it did not read may lie: the boxes of the cells it did not read, and the
    /// parts beyond the area of those it read.
    pub unread: Vec<[f64; 4]>,
    /// Points in the cells it read (kept or not).
    pub scanned: u64,
}

impl PointStore {
    /// Writes the store of every point `reader` gives (its filters applied), in cells of side
    /// `cell`, for the plan `id`, to `path` (under a temporary name, renamed when whole); the
    /// sort by cell within `mem`, spilling under `tmp`. Returns the store's bytes.
    ///
    /// # Errors
    /// The reader's errors; [`Error::Write`] naming `path` (a full disk: exit status 4, and no
    /// store is left); the sort's I/O errors naming `tmp`.
    pub(crate) fn write(
        reader: &mut LidarReader,
        cell: f64,
        id: &str,
        path: &Path,
        mem: u64,
        tmp: &Path,
    ) -> Result<u64> {
        let grid = TileGrid::new(cell, 0)?;
        let lattice = reader.lattice();
        match lattice.and_then(|l| Packing::new(l, &grid)) {
            Some(p) => write_as::<PackedRecord>(reader, grid, Some(p), lattice, id, path, mem, tmp),
            None => write_as::<BlockRecord>(reader, grid, None, None, id, path, mem, tmp),
        }
    }

    /// Opens the store at `path` of the plan `id` and checks its table.
    ///
    /// # Errors
    /// [`Error::Format`] naming the file when it is missing, truncated, edited or of another
    /// plan; [`Error::Io`] when it cannot be read.
    pub(crate) fn open(path: &Path, id: &str) -> Result<PointStore> {
        // Never a FIFO (a read would wait forever), a device or a link.
        match std::fs::symlink_metadata(path) {
            Ok(m) if !m.file_type().is_file() => {
                return Err(damaged(path, "not a regular file (a link, a FIFO or a directory)"));
            }
            _ => {}
        }
        let file = match File::open(path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(damaged(path, "missing")),
            Err(e) => return Err(Error::io(path, e)),
        };
        let size = file.metadata().map_err(|e| Error::io(path, e))?.len();
        let short = "truncated (or not a sweeptin point store)";
        if size < TRAILER as u64 {
            return Err(damaged(path, short));
        }
        let mut t = [0u8; TRAILER];
        file.read_exact_at(&mut t, size - TRAILER as u64)
            .map_err(|e| Error::io(path, e))?;
        if &t[..8] != MAGIC {
            return Err(damaged(path, short));
        }
        let w = |o: usize| u64::from_le_bytes(t[o..o + 8].try_into().unwrap_or_default());
        let packed = w(80) == 1;
        let (cells, points) = (w(136), w(144));
        let rec = if packed { 12 } else { 24 };
        let len = points
            .checked_mul(rec)
            .and_then(|n| cells.checked_mul(CELL as u64)?.checked_add(n))
            .and_then(|n| n.checked_add(TRAILER as u64));
        if len != Some(size) {
            return Err(damaged(path, "truncated or extended (its length is not what it says)"));
        }
        let table_at = size - TRAILER as u64 - cells * CELL as u64;
        let mut table = vec![0u8; cells as usize * CELL];
        file.read_exact_at(&mut table, table_at)
            .map_err(|e| Error::io(path, e))?;
        let mut h = Sha256::new();
        h.update(&table);
        h.update(&t[..TRAILER - 32]);
        if h.finalize()[..] != t[TRAILER - 32..] {
            return Err(damaged(path, "damaged or edited (its checksum does not match)"));
        }
        if t[8..72] != *id.as_bytes() {
            return Err(damaged(path, "of another plan (made into this directory before)"));
        }
        let lattice = if packed {
            let i = |o: usize| w(o) as i64;
            let u = |o: usize| u32::from_le_bytes(t[o..o + 4].try_into().unwrap_or_default());
            let l = Lattice::from_parts(f64::from_bits(w(88)), [i(96), i(104), i(112)], [u(120), u(124), u(128)]);
            Some(l.ok_or_else(|| damaged(path, "damaged (its lattice is not one)"))?)
        } else {
            None
        };
        let cells = table
            .chunks_exact(CELL)
            .map(|c| {
                let w = |o: usize| u64::from_le_bytes(c[o..o + 8].try_into().unwrap_or_default());
                let f = |o: usize| f64::from_bits(w(o));
                Cell {
                    cx: w(0) as i64,
                    cy: w(8) as i64,
                    first: w(16),
                    count: w(24),
                    rect: [f(32), f(40), f(48), f(56)],
                    sum: c[64..96].try_into().unwrap_or_default(),
                }
            })
            .collect::<Vec<_>>();
        let mut next = Some(0u64);
        for c in &cells {
            if next != Some(c.first) || c.count == 0 {
                next = None;
                break;
            }
            next = c.first.checked_add(c.count);
        }
        if next != Some(points) {
            return Err(damaged(path, "damaged (its table of cells does not add up)"));
        }
        Ok(PointStore {
            path: path.to_path_buf(),
            file,
            cell: f64::from_bits(w(72)),
            lattice,
            cells,
            points,
        })
    }

    /// The store's file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Its points.
    pub fn points(&self) -> u64 {
        self.points
    }

    /// Does every block of side `block` (from the origin) lie in one cell? Then a task with
    /// such blocks may read the store (see the module docs).
    pub(crate) fn nests(&self, block: f64) -> bool {
        let r = self.cell / block;
        r >= 1.0 && r.fract() == 0.0 && r < 1e18 && (r as u64).is_power_of_two() && block * r == self.cell
    }

    /// The boxes of the cells' points, in the store's order.
    pub(crate) fn rects(&self) -> impl Iterator<Item = [f64; 4]> + '_ {
        self.cells.iter().map(|c| c.rect)
    }

    /// Hands `f` every point of the cells `want` marks (by position in [`PointStore::rects`])
    /// with its position in the store (points at one position keep their input order: they lie
    /// in one cell) and its cell.
    ///
    /// # Errors
    /// As [`PointStore::read_area`].
    pub(crate) fn read_cells(
        &self,
        want: &[bool],
        mut f: impl FnMut([f64; 3], u64, usize),
    ) -> Result<()> {
        for (i, c) in self.cells.iter().enumerate().filter(|(i, _)| want[*i]) {
            let mut at = c.first;
            self.read_cell(c, |pts| {
                for &p in pts {
                    f(p, at, i);
                    at += 1;
                }
                Ok(())
            })?;
        }
        Ok(())
    }

    /// Hands `f` every point of the store in the closed rectangle `area`, cell after cell (each
    /// in input order), in batches, with the points scanned so far.
    ///
    /// # Errors
    /// [`Error::Format`] naming the store for a cell whose bytes are not those written;
    /// [`Error::Io`]; `f`'s errors.
    pub(crate) fn read_area(
        &self,
        area: [f64; 4],
        mut f: impl FnMut(&[[f64; 3]], u64) -> Result<()>,
    ) -> Result<AreaRead> {
        let mut out = AreaRead {
            unread: Vec::new(),
            scanned: 0,
        };
        let inside =
            |p: &&[f64; 3]| p[0] >= area[0] && p[0] <= area[2] && p[1] >= area[1] && p[1] <= area[3];
        let mut kept: Vec<[f64; 3]> = Vec::with_capacity(PIECE);
        for c in &self.cells {
            if !super::read::meets(&c.rect, &area) {
                out.unread.push(c.rect);
                continue;
            }
            out.unread.extend(super::read::outside_of(c.rect, area));
            self.read_cell(c, |pts| {
                kept.clear();
                kept.extend(pts.iter().filter(inside));
                out.scanned += pts.len() as u64;
                f(&kept, out.scanned)
            })?;
        }
        Ok(out)
    }

    /// Checks every cell's checksum (reading the whole store).
    ///
    /// # Errors
    /// As [`PointStore::read_area`].
    pub(crate) fn verify(self) -> Result<PointStore> {
        for c in &self.cells {
            self.pieces(c, true, |_| Ok(()))?;
        }
        Ok(self)
    }

    /// Hands `f` the bytes of cell `c` in pieces of at most [`PIECE`] records; with `check`,
    /// then checks the cell's checksum.
    fn pieces(&self, c: &Cell, check: bool, mut f: impl FnMut(&[u8]) -> Result<()>) -> Result<()> {
        let rec = if self.lattice.is_some() { 12 } else { 24 };
        let mut bytes = vec![0u8; PIECE.min(c.count as usize) * rec];
        let mut h = Sha256::new();
        let mut done = 0u64;
        while done < c.count {
            let n = (c.count - done).min(PIECE as u64) as usize;
            let b = &mut bytes[..n * rec];
            self.file
                .read_exact_at(b, (c.first + done) * rec as u64)
                .map_err(|e| Error::io(&self.path, e))?;
            if check {
                h.update(&*b);
            }
            f(b)?;
            done += n as u64;
        }
        if check && h.finalize()[..] != c.sum {
            return Err(damaged(&self.path, "damaged or edited (a cell's checksum does not match)"));
        }
        Ok(())
    }

    /// Hands `f` the points of cell `c` in batches once its checksum holds (the cell is read
    /// twice, the second time from the page cache: no point of a damaged cell reaches a task).
    /// Reading it once into memory, checked there, cost more (0.1–0.2 s of CPU over ARSO's
    /// tasks: a cell of megabytes passed over twice from memory rather than by pieces in cache).
    fn read_cell(&self, c: &Cell, mut f: impl FnMut(&[[f64; 3]]) -> Result<()>) -> Result<()> {
        self.pieces(c, true, |_| Ok(()))?;
        let mut pts: Vec<[f64; 3]> = Vec::with_capacity(PIECE.min(c.count as usize));
        let u = |r: &[u8], k: usize| u32::from_le_bytes(r[4 * k..4 * k + 4].try_into().unwrap_or_default());
        let d = |r: &[u8], k: usize| f64::from_le_bytes(r[8 * k..8 * k + 8].try_into().unwrap_or_default());
        self.pieces(c, false, |b| {
            pts.clear();
            match &self.lattice {
                Some(l) => pts.extend(b.chunks_exact(12).map(|r| l.decode([u(r, 0), u(r, 1), u(r, 2)]))),
                None => pts.extend(b.chunks_exact(24).map(|r| [d(r, 0), d(r, 1), d(r, 2)])),
            }
            f(&pts)
        })
    }
}

/// The refusal of a store that is `what`.
fn damaged(path: &Path, what: &str) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: format!(
            "the plan's point store is {what}; the plan's tasks read their points from it: make \
             the plan again"
        ),
    }
}

/// Appends record `s` (three words of 4 or 8 bytes) to `buf`, each word little-endian, as
/// [`PointStore::read_cells`] parses them (the record's own bytes on every target built here).
fn push_le<S: bytemuck::Pod>(buf: &mut Vec<u8>, s: &S) {
    let at = buf.len();
    buf.extend_from_slice(bytemuck::bytes_of(s));
    if cfg!(target_endian = "big") {
        let w = std::mem::size_of::<S>() / 3;
        for word in buf[at..].chunks_exact_mut(w) {
            word.reverse();
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn write_as<R: IndexRecord>(
    reader: &mut LidarReader,
    grid: TileGrid,
    packing: Option<Packing>,
    lattice: Option<Lattice>,
    id: &str,
    path: &Path,
    mem: u64,
    tmp: &Path,
) -> Result<u64> {
    let budget = super::read::index_sort_budget(mem, reader.point_count(), std::mem::size_of::<R>());
    let mut sorter = ExternalSorter::<R>::new(budget, tmp);
    super::read::prefetched(reader, |buf, _| {
        for p in buf {
            sorter.push(R::pack(packing.as_ref(), grid.block_of(p.x, p.y), [p.x, p.y, p.z])?)?;
        }
        Ok(())
    })?;
    let mut merge = sorter.finish()?;
    let mut out = crate::output::AtomicFile::create(path)?;
    let wr = |e| Error::write(path, e);
    let mut table: Vec<u8> = Vec::new();
    let mut buf: Vec<u8> = Vec::with_capacity(crate::sort::WRITE_PIECE);
    // The cell being written: its key, entry and running checksum.
    let mut cur: Option<(u64, Cell, Sha256)> = None;
    let mut points = 0u64;
    let close = |(_, c, h): (u64, Cell, Sha256), table: &mut Vec<u8>| {
        for v in [c.cx as u64, c.cy as u64, c.first, c.count] {
            table.extend_from_slice(&v.to_le_bytes());
        }
        for v in c.rect {
            table.extend_from_slice(&v.to_bits().to_le_bytes());
        }
        table.extend_from_slice(&h.finalize());
    };
    for r in merge.by_ref() {
        let (key, p) = r.unpack(packing.as_ref());
        if cur.as_ref().is_none_or(|(k, _, _)| *k != key) {
            if let Some((_, _, h)) = cur.as_mut() {
                h.update(&buf);
            }
            crate::sort::write_pieces(&mut out, &buf).map_err(wr)?;
            buf.clear();
            if let Some(c) = cur.take() {
                close(c, &mut table);
            }
            let (cx, cy) = TileGrid::unkey(key);
            let rect = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
            let cell = Cell { cx, cy, first: points, count: 0, rect, sum: [0; 32] };
            cur = Some((key, cell, Sha256::new()));
        }
        if let Some((_, c, h)) = cur.as_mut() {
            c.count += 1;
            c.rect = [c.rect[0].min(p[0]), c.rect[1].min(p[1]), c.rect[2].max(p[0]), c.rect[3].max(p[1])];
            push_le(&mut buf, &r.stored());
            if buf.len() >= crate::sort::WRITE_PIECE {
                h.update(&buf);
                crate::sort::write_pieces(&mut out, &buf).map_err(wr)?;
                buf.clear();
            }
        }
        points += 1;
    }
    if let Some(e) = merge.take_error() {
        return Err(e);
    }
    if let Some(mut c) = cur.take() {
        c.2.update(&buf);
        crate::sort::write_pieces(&mut out, &buf).map_err(wr)?;
        close(c, &mut table);
    }
    let cells = (table.len() / CELL) as u64;
    let mut t = Vec::with_capacity(TRAILER);
    t.extend_from_slice(MAGIC);
    let mut idb = [b'0'; 64];
    for (d, s) in idb.iter_mut().zip(id.bytes()) {
        *d = s;
    }
    t.extend_from_slice(&idb);
    t.extend_from_slice(&grid.block.to_bits().to_le_bytes());
    t.extend_from_slice(&u64::from(lattice.is_some()).to_le_bytes());
    let (pow, base, extent) = lattice.map_or((0.0, [0; 3], [0; 3]), |l| l.parts());
    t.extend_from_slice(&pow.to_bits().to_le_bytes());
    for b in base {
        t.extend_from_slice(&b.to_le_bytes());
    }
    for e in extent {
        t.extend_from_slice(&e.to_le_bytes());
    }
    t.extend_from_slice(&[0u8; 4]);
    t.extend_from_slice(&cells.to_le_bytes());
    t.extend_from_slice(&points.to_le_bytes());
    let mut h = Sha256::new();
    h.update(&table);
    h.update(&t);
    t.extend_from_slice(&h.finalize());
    debug_assert_eq!(t.len(), TRAILER);
    crate::sort::write_pieces(&mut out, &table).map_err(wr)?;
    crate::sort::write_pieces(&mut out, &t).map_err(wr)?;
    out.commit()
}
