//! Cut and fill between two surfaces, with bounded memory.
//!
//! Both TINs stream in increasing `y`, but a late triangle of either can arrive below the other's
//! progress, so the two streams are not merged live. Instead:
//!
//! 1. The **reference** surface is streamed first into a [`BandStore`]: its triangles are filed
//!    by *piece* — a horizontal band cut into blocks of 64 columns (a triangle goes to every
//!    piece its box meets) — into an anonymous scratch file, in chunks; a piece's buffer is
//!    written out when the watermark passes its band, when it fills, or when all buffers
//!    together pass 262,144 triangles (a tiled run fills a row of tiles' pieces at once).
//! 2. The **surface** is then streamed into an [`OverlaySink`]. For each of its triangles the
//!    pieces it meets are loaded, every reference triangle whose box meets it is paired with it,
//!    pieces below the surface's watermark are dropped, and past the byte budget the least
//!    recently used pieces are dropped too (a tiled run gives a row of tiles one tile at a time).
//!
//! A surface triangle that meets more than 16 bands (a long thin triangle along the hull, which
//! a tiled run delivers with its first tiles, or a triangle across a lake) would load most of
//! the reference at once, and so would the late triangles a sweep gives at its end, all along
//! the hull: a tall or late triangle (one meeting a band dropped at a watermark) waits instead,
//! and the waiting triangles meet the reference at the end, one band in memory at a time (or
//! sooner, when 65,536 wait). On every path a pair is counted only in the first band and column
//! both triangles meet, so which pieces are in memory never changes the result.
//!
//! For a pair, the surface triangle is clipped to the reference triangle (both convex), then to
//! the boundary, and the difference `d = z_surface − z_reference`, linear on each piece, is split
//! at `d = 0` and integrated exactly as for a plane ([`CutFill`]). Each pair is met exactly once,
//! so the overlap of the two TINs is covered once; where only one surface exists nothing is
//! counted.

use super::boundary::Boundary;
use super::geom::{PV, Tri, clip_left};
use super::volume::CutFill;
use crate::error::{Error, Result};
use crate::sink::{
    CutFillTotals, OverlayStats, ProductSummary, StreamInfo, SurfaceStoreSummary, TriangleSink,
    VolumeReference, VolumeSummary,
};
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Bytes of one stored triangle: 9 coordinates.
const RECORD: usize = 72;
/// Triangles buffered per piece before a chunk is written.
const CHUNK: usize = 4096;
/// Triangles buffered in all pieces together before every buffer is written (about 23 MB).
const MAX_BUFFERED: usize = 1 << 18;
/// Columns of a block: a piece is one band's columns of one block.
const BLOCK_COLUMNS: usize = 64;
/// A surface triangle meeting more bands than this waits for one pass over the bands.
const TALL_BANDS: usize = 16;
/// Most surface triangles waiting (about 5 MB).
const MAX_TALL: usize = 1 << 16;

/// The layout of the pieces: `count` bands of height `h` from `y0`, each cut into columns of
/// width `w` from `x[0]`, `BLOCK_COLUMNS` columns to a block.
#[derive(Clone, Copy, Debug)]
struct Bands {
    y0: f64,
    h: f64,
    count: usize,
    /// `[xmin, xmax]` of the reference surface.
    x: [f64; 2],
    w: f64,
    columns: usize,
}

impl Bands {
    fn new(bounds: [f64; 4], wanted: usize) -> Bands {
        let [xmin, ymin, xmax, ymax] = bounds;
        let height = ymax - ymin;
        let (count, h) = if height > 0.0 && height.is_finite() {
            (wanted, height / wanted as f64)
        } else {
            (1, 1.0)
        };
        let width = (xmax - xmin).max(h);
        let columns = ((width / h).ceil() as usize).clamp(1, 1 << 16);
        Bands {
            y0: ymin,
            h,
            count,
            x: [xmin, xmax],
            w: width / columns as f64,
            columns,
        }
    }

    fn of(&self, y: f64) -> usize {
        let b = ((y - self.y0) / self.h).floor();
        if b < 0.0 {
            0
        } else {
            (b as usize).min(self.count - 1)
        }
    }

    fn top(&self, b: usize) -> f64 {
        self.y0 + (b + 1) as f64 * self.h
    }

    fn column(&self, x: f64) -> usize {
        let c = ((x - self.x[0]) / self.w).floor();
        if c < 0.0 {
            0
        } else {
            (c as usize).min(self.columns - 1)
        }
    }

    fn blocks(&self) -> usize {
        self.columns.div_ceil(BLOCK_COLUMNS)
    }

    /// The pieces (band, block) a box `[xmin, ymin, xmax, ymax]` meets, band by band.
    fn pieces(&self, bb: &[f64; 4]) -> impl Iterator<Item = Piece> + use<> {
        let (k0, k1) = (
            self.column(bb[0]) / BLOCK_COLUMNS,
            self.column(bb[2]) / BLOCK_COLUMNS,
        );
        (self.of(bb[1])..=self.of(bb[3])).flat_map(move |b| (k0..=k1).map(move |k| (b, k)))
    }

    /// Index of piece `p` in the store's index.
    fn slot(&self, p: Piece) -> usize {
        p.0 * self.blocks() + p.1
    }

    /// Is `(b, c)` the first band and column that boxes `a` and `t` (which overlap) both meet?
    /// Each pair is counted there only.
    fn first_common(&self, a: &[f64; 4], t: &[f64; 4], b: usize, c: usize) -> bool {
        b == self.of(a[1].max(t[1])) && c == self.column(a[0].max(t[0]))
    }
}

/// Phase 1 whole: the reference surface of a volume, the TIN of `paths` read as `config` reads
/// its own input (duplicates, breaklines, `--mem`, the box) but with the point filter `filter`
/// (a DSM of first returns against a DTM of ground points from the same file: one filter per
/// surface), filed into about `bands` bands in a scratch file under `dir`.
///
/// # Errors
/// As [`crate::pipeline::run`] for the reference's files; [`Error::Write`] for the scratch file.
pub fn reference_surface(
    config: &crate::pipeline::RunConfig,
    paths: &[PathBuf],
    filter: crate::input::las::Filter,
    dir: &Path,
    bands: usize,
) -> Result<BandReader> {
    let reference = crate::pipeline::RunConfig::new(
        crate::pipeline::Input {
            paths: paths.to_vec(),
            filter,
            ..config.input().clone()
        },
        config.options().clone(),
    )?;
    let mut store = BandStore::new(dir, bands);
    crate::pipeline::run(&reference, None, &mut [&mut store])?;
    store.into_reader()
}

/// A piece of the reference: (band, block).
type Piece = (usize, usize);

/// Phase 1: a [`TriangleSink`] that files the reference surface's triangles by band.
#[derive(Debug)]
pub struct BandStore {
    dir: PathBuf,
    bands_wanted: usize,
    bands: Option<Bands>,
    file: Option<BufWriter<File>>,
    written: u64,
    buffers: HashMap<Piece, Vec<Tri>>,
    /// Triangles in `buffers`.
    buffered: usize,
    /// Flushed below this band.
    flushed_below: usize,
    /// The chunks (offset, count) of each piece, by [`Bands::slot`].
    index: Vec<Vec<(u64, u32)>>,
    /// Triangles filed.
    triangles: u64,
}

impl BandStore {
    /// A store whose scratch file lives in `dir`, with about `bands` bands.
    pub fn new(dir: &Path, bands: usize) -> BandStore {
        BandStore {
            dir: dir.to_path_buf(),
            bands_wanted: bands.max(1),
            bands: None,
            file: None,
            written: 0,
            buffers: HashMap::new(),
            buffered: 0,
            flushed_below: 0,
            index: Vec::new(),
            triangles: 0,
        }
    }

    fn flush_piece(&mut self, p: Piece) -> Result<()> {
        let Some(buf) = self.buffers.remove(&p) else {
            return Ok(());
        };
        self.buffered -= buf.len();
        if buf.is_empty() {
            return Ok(());
        }
        let slot = self.bands.expect("set in begin").slot(p);
        let dir = &self.dir;
        let f = self.file.as_mut().expect("opened in begin");
        let mut bytes = Vec::with_capacity(buf.len() * RECORD);
        for t in &buf {
            for c in t.v.iter().flatten() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        crate::sort::write_pieces(f, &bytes).map_err(|e| Error::write(dir, e))?;
        self.index[slot].push((self.written, buf.len() as u32));
        self.written += bytes.len() as u64;
        Ok(())
    }

    /// Ends phase 1: the store, ready to be read by an [`OverlaySink`].
    ///
    /// # Errors
    /// [`Error::Write`] if the scratch file cannot be written; [`Error::Internal`] before `finish`.
    pub fn into_reader(mut self) -> Result<BandReader> {
        let bands = self
            .bands
            .ok_or_else(|| Error::Internal("band store read before it was filled".into()))?;
        self.flush_all()?;
        let dir = self.dir.clone();
        let file = self
            .file
            .take()
            .expect("opened in begin")
            .into_inner()
            .map_err(|e| Error::write(&dir, e.into_error()))?;
        Ok(BandReader {
            file,
            dir,
            bands,
            index: self.index,
            triangles: self.triangles,
        })
    }
}

impl BandStore {
    /// Writes every buffer, in piece order (so the scratch file depends only on the input).
    fn flush_all(&mut self) -> Result<()> {
        let mut keys: Vec<Piece> = self.buffers.keys().copied().collect();
        keys.sort_unstable();
        for p in keys {
            self.flush_piece(p)?;
        }
        Ok(())
    }
}

impl TriangleSink for BandStore {
    fn begin(&mut self, info: &StreamInfo) -> Result<()> {
        let bands = Bands::new(info.bounds, self.bands_wanted);
        self.bands = Some(bands);
        self.index = vec![Vec::new(); bands.count * bands.blocks()];
        let f = tempfile::tempfile_in(&self.dir).map_err(|e| Error::write(&self.dir, e))?;
        self.file = Some(BufWriter::with_capacity(crate::sort::WRITE_PIECE, f));
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        let bands = self.bands.expect("set in begin");
        let bb = t.bbox();
        self.triangles += 1;
        for p in bands.pieces(&bb) {
            let buf = self.buffers.entry(p).or_default();
            buf.push(t);
            self.buffered += 1;
            if buf.len() >= CHUNK {
                self.flush_piece(p)?;
            }
        }
        if self.buffered > MAX_BUFFERED {
            // A tiled run delivers a row of tiles before its watermark: many pieces fill at once.
            self.flush_all()?;
        }
        Ok(())
    }

    /// The buffers of all pieces together stay under about 262,144 triangles.
    fn memory_share(&self) -> u64 {
        ((MAX_BUFFERED + CHUNK) * std::mem::size_of::<Tri>()) as u64
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        let bands = self.bands.expect("set in begin");
        let below = self.flushed_below;
        while self.flushed_below < bands.count && bands.top(self.flushed_below) < y {
            self.flushed_below += 1;
        }
        if self.flushed_below > below {
            let mut done: Vec<Piece> = (self.buffers.keys())
                .filter(|p| p.0 < self.flushed_below)
                .copied()
                .collect();
            done.sort_unstable();
            for p in done {
                self.flush_piece(p)?;
            }
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        Ok(ProductSummary::SurfaceStore(SurfaceStoreSummary {
            reference_triangles: self.triangles,
            bands: self.bands.map_or(0, |b| b.count as u64),
        }))
    }
}

/// The reference surface filed by band (phase 1's result).
#[derive(Debug)]
pub struct BandReader {
    file: File,
    dir: PathBuf,
    bands: Bands,
    index: Vec<Vec<(u64, u32)>>,
    triangles: u64,
}

/// A piece in memory, its triangles listed by column.
struct Loaded {
    tris: Vec<Tri>,
    /// The triangles meeting each column of the block, from column `first`.
    /// Column `first + c` lists `cells[starts[c]..starts[c + 1]]` (one allocation, not one per
    /// column: pieces come and go by the thousand, and many small vectors fragment the heap).
    starts: Vec<u32>,
    cells: Vec<u32>,
    first: usize,
    /// When it was last used (a count of surface triangles).
    used: u64,
}

impl Loaded {
    /// The reference triangles filed in this piece's part of columns `c0..=c1`, as (column,
    /// triangle).
    fn in_columns(&self, c0: usize, c1: usize) -> impl Iterator<Item = (usize, &Tri)> {
        let last = self.first + self.starts.len() - 2;
        (c0.max(self.first)..=c1.min(last)).flat_map(move |c| {
            let k = c - self.first;
            self.cells[self.starts[k] as usize..self.starts[k + 1] as usize]
                .iter()
                .map(move |&i| (c, &self.tris[i as usize]))
        })
    }

    /// What the piece holds on the heap: its vectors' capacities, not their lengths.
    fn bytes(&self) -> usize {
        self.tris.capacity() * std::mem::size_of::<Tri>()
            + (self.starts.capacity() + self.cells.capacity()) * std::mem::size_of::<u32>()
    }
}

impl BandReader {
    fn load(&mut self, p: Piece) -> Result<Loaded> {
        let slot = self.bands.slot(p);
        let count: u64 = self.index[slot].iter().map(|&(_, n)| u64::from(n)).sum();
        let mut tris = Vec::with_capacity(count as usize);
        let mut bytes = Vec::new();
        for &(offset, count) in &self.index[slot] {
            bytes.resize(count as usize * RECORD, 0);
            self.file
                .seek(SeekFrom::Start(offset))
                .and_then(|_| self.file.read_exact(&mut bytes))
                .map_err(|e| Error::write(&self.dir, e))?;
            for r in bytes.chunks_exact(RECORD) {
                let f = |i: usize| f64::from_le_bytes(r[8 * i..8 * i + 8].try_into().expect("8"));
                let v = [[f(0), f(1), f(2)], [f(3), f(4), f(5)], [f(6), f(7), f(8)]];
                tris.push(Tri { v });
            }
        }
        let bands = &self.bands;
        let first = p.1 * BLOCK_COLUMNS;
        let last = (first + BLOCK_COLUMNS).min(bands.columns) - 1;
        // Each column's list counted first, then filled in place.
        let columns = |t: &Tri| {
            let bb = t.bbox();
            bands.column(bb[0]).max(first)..=bands.column(bb[2]).min(last)
        };
        let mut starts = vec![0u32; last + 2 - first];
        for t in &tris {
            for c in columns(t) {
                starts[c - first + 1] += 1;
            }
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        let mut next = starts.clone();
        let mut cells = vec![0u32; starts[starts.len() - 1] as usize];
        for (i, t) in tris.iter().enumerate() {
            for c in columns(t) {
                let at = &mut next[c - first];
                cells[*at as usize] = i as u32;
                *at += 1;
            }
        }
        Ok(Loaded {
            tris,
            starts,
            cells,
            first,
            used: 0,
        })
    }
}

/// Phase 2: a [`TriangleSink`] for the surface, computing cut and fill against the reference.
pub struct OverlaySink {
    reference: BandReader,
    boundary: Option<Boundary>,
    loaded: HashMap<Piece, Loaded>,
    /// Bytes of the loaded pieces, and the most they may take before the least recently used
    /// are dropped.
    loaded_bytes: usize,
    budget: usize,
    max_loaded_bytes: usize,
    acc: CutFill,
    triangles: u64,
    pairs: u64,
    loads: u64,
    others: Vec<Tri>,
    scratch: (Vec<PV>, Vec<PV>),
    /// Surface triangles meeting more than `tall_bands` bands, waiting for a pass over the bands.
    tall: Vec<Tri>,
    tall_bands: usize,
    /// The highest watermark seen: bands below it were dropped.
    watermark: f64,
}

impl OverlaySink {
    /// Cut and fill of the streamed surface against `reference`, inside `boundary` when given,
    /// holding about `budget` bytes of the reference in memory (the pieces the current triangle
    /// meets are always held).
    pub fn new(reference: BandReader, boundary: Option<Boundary>, budget: usize) -> OverlaySink {
        OverlaySink {
            reference,
            boundary,
            loaded: HashMap::new(),
            loaded_bytes: 0,
            budget,
            max_loaded_bytes: 0,
            acc: CutFill::default(),
            triangles: 0,
            pairs: 0,
            loads: 0,
            others: Vec::new(),
            scratch: (Vec::new(), Vec::new()),
            tall: Vec::new(),
            tall_bands: TALL_BANDS,
            watermark: f64::NEG_INFINITY,
        }
    }

    /// Loads piece `p` unless it is in memory, and marks it used now.
    fn touch(&mut self, p: Piece) -> Result<()> {
        let now = self.triangles;
        if let Some(l) = self.loaded.get_mut(&p) {
            l.used = now;
            return Ok(());
        }
        let mut l = self.reference.load(p)?;
        l.used = now;
        self.loads += 1;
        self.loaded_bytes += l.bytes();
        self.max_loaded_bytes = self.max_loaded_bytes.max(self.loaded_bytes);
        self.loaded.insert(p, l);
        Ok(())
    }

    /// Drops the least recently used pieces (never those of the current triangle) until the
    /// loaded pieces fit in three quarters of the budget.
    fn shed(&mut self) {
        if self.loaded_bytes <= self.budget {
            return;
        }
        let now = self.triangles;
        let mut old: Vec<(u64, Piece)> = (self.loaded.iter())
            .filter(|(_, l)| l.used < now)
            .map(|(&p, l)| (l.used, p))
            .collect();
        old.sort_unstable();
        for (_, p) in old {
            if self.loaded_bytes <= self.budget / 4 * 3 {
                break;
            }
            if let Some(l) = self.loaded.remove(&p) {
                self.loaded_bytes -= l.bytes();
            }
        }
    }

    /// Pairs the waiting tall triangles with the reference, band by band: a piece already in
    /// memory is used, any other is loaded for the pass and dropped.
    fn pass_over_bands(&mut self) -> Result<()> {
        let mut tall = std::mem::take(&mut self.tall);
        let bands = self.reference.bands;
        // By first band: the triangles meeting band b are a window of this order.
        tall.sort_by_key(|a| bands.of(a.bbox()[1]));
        let boxes: Vec<[f64; 4]> = tall.iter().map(Tri::bbox).collect();
        let mut from = 0;
        let mut pairs: Vec<(usize, Tri)> = Vec::new();
        let mut temp: HashMap<Piece, Loaded> = HashMap::new();
        let Some(hi) = boxes.iter().map(|bb| bands.of(bb[3])).max() else {
            return Ok(());
        };
        for b in bands.of(boxes[0][1])..=hi {
            while from < tall.len() && bands.of(boxes[from][3]) < b {
                from += 1;
            }
            pairs.clear();
            temp.clear();
            for (k, bb) in boxes.iter().enumerate().skip(from) {
                if bands.of(bb[1]) > b {
                    break;
                }
                if bands.of(bb[3]) < b {
                    continue;
                }
                let (c0, c1) = (bands.column(bb[0]), bands.column(bb[2]));
                for blk in c0 / BLOCK_COLUMNS..=c1 / BLOCK_COLUMNS {
                    let p = (b, blk);
                    if !self.loaded.contains_key(&p) && !temp.contains_key(&p) {
                        temp.insert(p, self.reference.load(p)?);
                        self.loads += 1;
                    }
                    let l = self.loaded.get(&p).or(temp.get(&p)).expect("loaded");
                    for (c, t) in l.in_columns(c0, c1) {
                        let tb = t.bbox();
                        if overlaps(bb, &tb) && bands.first_common(bb, &tb, b, c) {
                            pairs.push((k, *t));
                        }
                    }
                }
            }
            for &(k, t) in &pairs {
                self.pair(&tall[k], &t);
            }
        }
        Ok(())
    }

    /// The totals so far.
    pub fn totals(&self) -> CutFillTotals {
        self.acc.totals()
    }

    /// Adds the pair (surface triangle `a`, reference triangle `b`).
    fn pair(&mut self, a: &Tri, b: &Tri) {
        let (mut p, mut q) = std::mem::take(&mut self.scratch);
        p.clear();
        p.extend(a.v.iter().copied());
        for i in 0..3 {
            let (s, e) = (b.v[i], b.v[(i + 1) % 3]);
            clip_left(&p, [s[0], s[1]], [e[0], e[1]], &mut q);
            std::mem::swap(&mut p, &mut q);
            if p.len() < 3 {
                self.scratch = (p, q);
                return;
            }
        }
        self.pairs += 1;
        let acc = &mut self.acc;
        // The same triangle in both surfaces (canonical vertices): no difference at all, where
        // the planes' arithmetic left ±1e-16 that counted as cut and fill areas.
        let same = a.v == b.v;
        let mut add = |piece: &[PV]| {
            let d: Vec<PV> = piece
                .iter()
                .map(|v| {
                    let d = if same {
                        0.0
                    } else {
                        v[2] - b.plane_value([v[0], v[1]])
                    };
                    [v[0], v[1], d]
                })
                .collect();
            acc.add(&d);
        };
        match &self.boundary {
            None => add(&p),
            Some(bd) => bd.clip(&p, add),
        }
        self.scratch = (p, q);
    }
}

fn overlaps(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3]
}

impl TriangleSink for OverlaySink {
    fn begin(&mut self, _info: &StreamInfo) -> Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        self.triangles += 1;
        let Some(a) = Tri::new(t) else {
            return Ok(());
        };
        let bb = a.bbox();
        let bands = self.reference.bands;
        let (b0, b1) = (bands.of(bb[1]), bands.of(bb[3]));
        // A late triangle (some of its bands were dropped at a watermark) waits too: the sweep
        // gives the hull's triangles late, all along the data, and they reloaded every band.
        if b1 - b0 >= self.tall_bands || bands.top(b0) < self.watermark {
            if self.tall.len() == MAX_TALL {
                self.pass_over_bands()?;
            }
            self.tall.push(a);
            return Ok(());
        }
        let (c0, c1) = (bands.column(bb[0]), bands.column(bb[2]));
        let mut others = std::mem::take(&mut self.others);
        others.clear();
        for p in bands.pieces(&bb) {
            self.touch(p)?;
            for (c, t) in self.loaded[&p].in_columns(c0, c1) {
                let tb = t.bbox();
                if overlaps(&bb, &tb) && bands.first_common(&bb, &tb, p.0, c) {
                    others.push(*t);
                }
            }
        }
        for t in &others {
            self.pair(&a, t);
        }
        self.others = others;
        self.shed();
        Ok(())
    }

    /// The pieces held (their budget, about) and the waiting tall triangles.
    fn memory_share(&self) -> u64 {
        (self.budget + MAX_TALL * std::mem::size_of::<Tri>()) as u64
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        let bands = self.reference.bands;
        self.watermark = self.watermark.max(y);
        let mut freed = 0;
        self.loaded.retain(|&(b, _), l| {
            let keep = bands.top(b) >= y;
            if !keep {
                freed += l.bytes();
            }
            keep
        });
        self.loaded_bytes -= freed;
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        self.pass_over_bands()?;
        Ok(ProductSummary::Volume(VolumeSummary {
            partials: None,
            totals: self.acc.totals(),
            reference: VolumeReference::Surface(self.reference.triangles),
            boundary_area: self.boundary.as_ref().map(Boundary::area),
            triangles: self.triangles,
            overlay: Some(OverlayStats {
                pairs: self.pairs,
                loads: self.loads,
                max_loaded_bytes: self.max_loaded_bytes as u64,
            }),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::products::testutil::{
        Step, feed, in_sweep_order, random_tin, shuffled_with_watermarks,
    };
    use crate::products::volume::VolumeSink;

    fn info() -> StreamInfo {
        StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 100.0, 100.0],
        }
    }

    fn overlay(reference: &[Step], surface: &[Step], bands: usize) -> OverlaySink {
        let dir = tempfile::tempdir().unwrap();
        let mut store = BandStore::new(dir.path(), bands);
        feed(&mut store, &info(), reference);
        let mut sink = OverlaySink::new(store.into_reader().unwrap(), None, usize::MAX);
        feed(&mut sink, &info(), surface);
        sink
    }

    /// Triangles that wait for a pass over the bands (all but the smallest, with a threshold of
    /// one band) give exactly the totals of pairing each one as it comes (the sums are exact),
    /// and so does a budget that drops every piece as soon as it can: each pair counted once, in
    /// sweep order and shuffled.
    #[test]
    fn waiting_tall_triangles_give_the_same_totals() {
        let a = random_tin(900, 100.0, 3, |x, y| 15.0 * (x / 7.0).sin() - y / 9.0);
        let b = random_tin(800, 100.0, 4, |x, y| 10.0 * (x / 11.0).cos() + 0.1 * y);
        let run = |tall_bands: usize, shuffled: bool, budget: usize| {
            let dir = tempfile::tempdir().unwrap();
            let mut store = BandStore::new(dir.path(), 64);
            feed(&mut store, &info(), &in_sweep_order(&b));
            let mut sink = OverlaySink::new(store.into_reader().unwrap(), None, budget);
            sink.tall_bands = tall_bands;
            let steps = if shuffled {
                shuffled_with_watermarks(&a, 9)
            } else {
                in_sweep_order(&a)
            };
            feed(&mut sink, &info(), &steps);
            (
                format!("{:?}", sink.totals()),
                sink.pairs,
                sink.max_loaded_bytes,
            )
        };
        let want = run(usize::MAX, false, usize::MAX);
        for shuffled in [false, true] {
            let got = run(1, shuffled, usize::MAX);
            assert_eq!((&got.0, got.1), (&want.0, want.1));
            assert!(got.2 <= want.2);
            // A budget of nothing: every piece but the current triangle's is dropped at once.
            let got = run(usize::MAX, shuffled, 0);
            assert_eq!((&got.0, got.1), (&want.0, want.1));
            assert!(got.2 <= want.2);
        }
    }

    /// Two different TINs of planes: the difference is the exact difference of the planes, and
    /// agrees with each surface's volume against z = 0.
    #[test]
    fn two_planes_on_different_tins() {
        let a = random_tin(600, 100.0, 1, |x, y| 0.1 * x + 0.05 * y);
        let b = random_tin(700, 100.0, 2, |x, _| 0.1 * x - 2.5);
        let s = overlay(&in_sweep_order(&b), &in_sweep_order(&a), 16);
        let t = s.totals();
        // d = 0.05 y + 2.5 > 0 everywhere: ∫ = 100 × (0.05 × 5000 + 250) = 50_000.
        assert!((t.cut_volume - 50_000.0).abs() < 1e-6, "{t:?}");
        assert_eq!(t.fill_volume, 0.0);
        assert!((t.area - 10_000.0).abs() < 1e-7, "{t:?}");
    }

    /// Curved surfaces: the net difference equals the difference of the volumes against a plane,
    /// in sweep order and shuffled (late triangles, band reloads), with few or many bands.
    #[test]
    fn net_equals_difference_of_plane_volumes_in_any_order() {
        let f = |x: f64, y: f64| 15.0 * (x / 7.0).sin() - 15.0 * (y / 9.0).sin();
        let g = |x: f64, y: f64| 10.0 * (x / 11.0).cos() + 0.1 * y;
        let a = random_tin(900, 100.0, 3, f);
        let b = random_tin(800, 100.0, 4, g);
        let plane = |tris: &[[[f64; 3]; 3]]| {
            let mut s = VolumeSink::new(0.0, None).unwrap();
            feed(&mut s, &info(), &in_sweep_order(tris));
            s.totals().net_volume
        };
        let want = plane(&a) - plane(&b);
        let t1 = overlay(&in_sweep_order(&b), &in_sweep_order(&a), 8).totals();
        let s2 = overlay(
            &shuffled_with_watermarks(&b, 5),
            &shuffled_with_watermarks(&a, 6),
            64,
        );
        let t2 = s2.totals();
        assert!(
            (t1.net_volume - want).abs() < 1e-6 * want.abs().max(1.0),
            "{t1:?} {want}"
        );
        assert!(
            (t2.net_volume - want).abs() < 1e-6 * want.abs().max(1.0),
            "{t2:?} {want}"
        );
        assert!((t1.cut_volume - t2.cut_volume).abs() < 1e-6 * t1.cut_volume);
        assert!(t1.cut_volume > 0.0 && t1.fill_volume > 0.0);
        assert!((t1.area - 10_000.0).abs() < 1e-6);
        assert!(s2.loads > 64, "late triangles reload bands");
    }
}
