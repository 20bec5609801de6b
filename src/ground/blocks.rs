//! The classification in blocks, bounded by `--mem`: every point into the tiles' block index
//! (blocks = seed cells, with each point's global index and class as its tag), then every
//! ground block with points run on its buffered rectangle ([`super::ptd`]), blocks taken by
//! every core as the memory budget has room, the classes of the points each block owns written at their global index into
//! a [`ClassStore`] (one byte a point, a temporary file for large inputs).

use super::ptd::{RunStats, check_labels, classify_run};
use super::{GroundParams, GroundSummary, Tag};
use crate::error::{Error, Result};
use crate::sort::DuplicatePolicy;
use crate::sort::external::ExternalSorter;
use crate::tiles::budget::Budget;
use crate::tiles::grid::{BlockRect, TileGrid};
use crate::tiles::index::{BlockIndex, TaggedRecord};
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Bytes a run takes per point of its buffered rectangle (the tags and labels, the candidates'
/// bucket and mirror links, the ground TIN, which holds every point's position once, and its
/// per-triangle tables, grown a sixteenth at a time), for fitting runs into `--mem`. It grows
/// with the share of ground (about 53 + 66 × that share): measured 96–106 on ARSO (106.3 on its
/// densest 160 m block, 1.11 M points, most of them ground), 103 on a synthetic block, and
/// checked against every run of real files by
/// `ground::a_run_takes_no_more_than_run_bytes_per_point_of_the_refusal`. A block of ground
/// alone would take about 120.
pub const RUN_BYTES_PER_POINT: u64 = 108;

/// Largest seed cell coordinate (block keys pack two `i32`).
const KEY_LIMIT: f64 = ((1u64 << 31) - 4) as f64;

/// Refuses seed cells of `params` too small for the points of `path`, by its header's box
/// (a plan's check, before any task runs: they would all fail on the first point).
///
/// # Errors
/// [`Error::Options`] naming the file and `--step`.
pub(crate) fn check_reach(
    params: &GroundParams,
    path: &std::path::Path,
    rect: [f64; 4],
) -> Result<()> {
    let grid = params.grid()?;
    let far = rect.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if far / grid.block > KEY_LIMIT {
        return Err(Error::Options(format!(
            "{}: its points reach coordinates as large as {far}, too far from the origin for \
             seed cells of {} (--step): give a larger --step",
            path.display(),
            grid.block
        )));
    }
    Ok(())
}

/// The classes of every point by global input index: in memory, or one byte a point in an
/// anonymous temporary file (written at each point's offset).
#[derive(Debug)]
pub struct ClassStore {
    inner: Inner,
    len: u64,
}

#[derive(Debug)]
enum Inner {
    Memory(Vec<u8>),
    File {
        file: File,
        dir: PathBuf,
        buf: Vec<u8>,
        /// Index of `buf[0]` (reading in order).
        at: u64,
    },
}

/// Bytes read at a time from a store's file.
pub(crate) const READ_PIECE: usize = 1 << 20;

impl ClassStore {
    /// A store of `len` classes: in memory when they take at most `in_memory` bytes, else a
    /// temporary file under `dir`.
    ///
    /// # Errors
    /// [`Error::Write`] when the temporary file cannot be made.
    pub fn new(len: u64, in_memory: u64, dir: &Path) -> Result<ClassStore> {
        let inner = if len <= in_memory {
            Inner::Memory(vec![0; len as usize])
        } else {
            let w = |e| Error::Write {
                path: dir.to_path_buf(),
                source: e,
            };
            let file = tempfile::tempfile_in(dir).map_err(w)?;
            file.set_len(len).map_err(w)?;
            Inner::File {
                file,
                dir: dir.to_path_buf(),
                buf: Vec::new(),
                at: 0,
            }
        };
        Ok(ClassStore { inner, len })
    }

    /// Bytes the store holds in memory (its read piece when its classes are in a temporary
    /// file).
    pub fn memory_bytes(&self) -> u64 {
        match &self.inner {
            Inner::Memory(v) => v.len() as u64,
            Inner::File { .. } => READ_PIECE as u64,
        }
    }

    /// Number of classes.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// No classes at all?
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Records `(index, class)` pairs (sorted here; runs of consecutive indices are one write).
    fn put(&mut self, pairs: &mut [(u64, u8)]) -> Result<()> {
        pairs.sort_unstable_by_key(|p| p.0);
        match &mut self.inner {
            Inner::Memory(v) => {
                for &(i, c) in pairs.iter() {
                    v[i as usize] = c;
                }
            }
            Inner::File { file, dir, buf, .. } => {
                let mut k = 0;
                while k < pairs.len() {
                    let start = pairs[k].0;
                    buf.clear();
                    while k < pairs.len() && pairs[k].0 == start + buf.len() as u64 {
                        buf.push(pairs[k].1);
                        k += 1;
                    }
                    file.write_all_at(buf, start).map_err(|e| Error::Write {
                        path: dir.clone(),
                        source: e,
                    })?;
                }
                buf.clear();
            }
        }
        Ok(())
    }

    /// The class of point `index`; fast when asked in increasing order.
    ///
    /// # Errors
    /// [`Error::Io`] if the temporary file cannot be read; [`Error::Internal`] past the end.
    pub fn get(&mut self, index: u64) -> Result<u8> {
        if index >= self.len {
            return Err(Error::Internal(format!(
                "point {index} has no class: the ground filter classified {} points",
                self.len
            )));
        }
        match &mut self.inner {
            Inner::Memory(v) => Ok(v[index as usize]),
            Inner::File { file, dir, buf, at } => {
                if index < *at || index >= *at + buf.len() as u64 {
                    let n = (self.len - index).min(READ_PIECE as u64) as usize;
                    buf.resize(n, 0);
                    file.read_exact_at(buf, index)
                        .map_err(|e| Error::io(dir.clone(), e))?;
                    *at = index;
                }
                Ok(buf[(index - *at) as usize])
            }
        }
    }
}

/// A reader with `--ground` takes each point's class from the store (any thread, any order:
/// a file's classes are read with `pread`, a span at a time).
impl crate::input::las::PointClasses for ClassStore {
    fn read_classes(&self, first: u64, out: &mut [u8]) -> Result<()> {
        let end = first
            .checked_add(out.len() as u64)
            .filter(|&e| e <= self.len);
        if end.is_none() {
            return Err(Error::Internal(format!(
                "points {first} .. {} have no class: the ground filter classified {} points \
                 (the files changed since?)",
                first.saturating_add(out.len() as u64),
                self.len
            )));
        }
        match &self.inner {
            Inner::Memory(v) => out.copy_from_slice(&v[first as usize..first as usize + out.len()]),
            Inner::File { file, dir, .. } => file
                .read_exact_at(out, first)
                .map_err(|e| Error::io(dir.clone(), e))?,
        }
        Ok(())
    }
}

/// Hands every point to the function it is given (see [`classify_stream`]).
pub type Feed<'a> = dyn FnMut(&mut dyn FnMut(GroundInput) -> Result<()>) -> Result<()> + 'a;

/// What a block's run gives back: the `(index, class)` of the points it owns, its counters
/// and the points it read.
struct BlockResult {
    classes: Vec<(u64, u8)>,
    stats: RunStats,
    points: u64,
}

/// One point handed to the classification.
#[derive(Clone, Copy, Debug)]
pub struct GroundInput {
    /// Global input index (0, 1, 2, ... over all the inputs).
    pub index: u64,
    /// Position.
    pub xyz: [f64; 3],
    /// Its class before.
    pub class: u8,
    /// Withheld (never ground, keeps its class).
    pub withheld: bool,
}

/// Classifies the points that `feed` pushes (each exactly once, every index below `total`),
/// within `mem` bytes, temporary files under `tmp`.
///
/// # Errors
/// [`Error::Options`] for bad parameters or a run that does not fit what the block index and
/// the class store leave of `mem` (checked before any run); the sort's,
/// the index's and the TIN's errors; whatever `feed` returns.
pub fn classify_stream(
    params: &GroundParams,
    total: u64,
    mem: u64,
    tmp: &Path,
    feed: &mut Feed<'_>,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<(ClassStore, GroundSummary)> {
    params.check()?;
    let start = Instant::now();
    let grid = params.grid()?;
    let mut summary = GroundSummary {
        points: total,
        block: grid.tile,
        buffer: params.buffer(),
        ..GroundSummary::default()
    };
    // 1. The block index of every point, tagged with its index and class.
    let budget = (mem / 2).max(8 << 20);
    let mut sorter = ExternalSorter::<TaggedRecord>::new(budget, tmp);
    let mut seen = 0u64;
    let mut bounds = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    feed(&mut |p: GroundInput| {
        let [x, y, _] = p.xyz;
        crate::tin::check_point(p.xyz, p.index)?;
        if p.index >= total {
            return Err(Error::Internal(format!(
                "point {} given to the ground filter of {total} points",
                p.index
            )));
        }
        bounds = [
            bounds[0].min(x),
            bounds[1].min(y),
            bounds[2].max(x),
            bounds[3].max(y),
        ];
        // Seed cells whose keys fit (checked again exactly over all the points below).
        if x.abs().max(y.abs()) / grid.block > KEY_LIMIT {
            return Err(Error::Options(format!(
                "point {}: ({x}, {y}) lies too far from the origin for seed cells of {}: give \
                 a larger --step",
                p.index, grid.block
            )));
        }
        seen += 1;
        if seen.is_multiple_of(1 << 20) {
            progress("reading", seen, total);
        }
        sorter.push(TaggedRecord::new(grid.block_of(x, y), p.xyz, Tag::of(&p).0))
    })?;
    if seen != total {
        return Err(Error::Internal(format!(
            "the ground filter was given {seen} points of {total}"
        )));
    }
    if seen > 0 {
        grid.check_bounds(bounds)?;
    }
    let merge = sorter.finish()?;
    let index = BlockIndex::build(grid, merge, None, tmp, DuplicatePolicy::First)?;
    summary.read_seconds = start.elapsed().as_secs_f64();

    // 2. The blocks with points, in order.
    let start = Instant::now();
    let mut blocks: Vec<(i64, i64)> = Vec::new();
    let occ = index.occupied();
    for by in occ.y0..occ.y1 {
        for &k in index.keys_in_row(by, occ.x0, occ.x1) {
            let (bx, by) = TileGrid::unkey(k);
            blocks.push(grid.tile_of_block(bx, by));
        }
    }
    blocks.sort_unstable_by_key(|&(tx, ty)| (ty, tx));
    blocks.dedup();
    summary.blocks = blocks.len() as u64;

    let mut store = ClassStore::new(total, mem / 8, tmp)?;
    let threads = rayon::current_num_threads().max(1);
    // The runs have what the index and the store leave of --mem.
    let run_budget = mem.saturating_sub(index.memory_bytes() + store.memory_bytes());
    let buffer_cells = super::BUFFER_CELLS;
    let runs: Vec<(i64, i64, BlockRect, u64)> = blocks
        .iter()
        .map(|&(tx, ty)| {
            let rect = grid.tile_blocks(tx, ty).expand(buffer_cells);
            (tx, ty, rect, index.count(&rect) * RUN_BYTES_PER_POINT)
        })
        .collect();
    // The largest run is refused before any work.
    if let Some(&(tx, ty, rect, need)) = runs
        .iter()
        .max_by_key(|r| (r.3, std::cmp::Reverse((r.1, r.0))))
        && need > run_budget
    {
        let w = grid.world(&grid.tile_blocks(tx, ty));
        return Err(Error::Options(format!(
            "ground: the block x {} .. {}, y {} .. {} with its buffer of {} holds {} points, \
             about {} MiB to classify, more than the {} MiB that --mem ({} MiB) leaves for it: \
             give a larger --mem, or a smaller --step (blocks are {} steps a side)",
            w[0],
            w[2],
            w[1],
            w[3],
            params.buffer(),
            index.count(&rect),
            need >> 20,
            run_budget >> 20,
            mem >> 20,
            1u32 << grid.shift
        )));
    }
    // Every core takes the next block while the budget has room for its run; the classes
    // are put in the store as the runs end (a point's class does not depend on the order).
    let budget = Budget::new(
        run_budget,
        runs.iter().map(|r| r.3).max().unwrap_or(1),
        threads,
    );
    let next = AtomicUsize::new(0);
    let (tx, rx) = crossbeam_channel::unbounded::<Result<BlockResult>>();
    let mut done_points = 0u64;
    std::thread::scope(|scope| -> Result<()> {
        let rx = rx;
        for _ in 0..threads.min(runs.len()) {
            let (tx, budget, next, runs, index, grid) =
                (tx.clone(), &budget, &next, &runs, &index, &grid);
            scope.spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(tx_, ty_, rect, need)) = runs.get(k) else {
                        break;
                    };
                    if !budget.take(need) {
                        break;
                    }
                    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        run_block(index, grid, params, (tx_, ty_), rect)
                    }))
                    .unwrap_or_else(|p| Err(Error::panicked("ground block", &*p)));
                    budget.give(need);
                    if tx.send(r).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let outcome = (|| -> Result<()> {
            for _ in 0..runs.len() {
                let r = rx.recv().map_err(|_| {
                    Error::Internal("a ground worker stopped without a result".into())
                })?;
                let BlockResult {
                    classes: mut pairs,
                    stats,
                    points: run_points,
                } = r?;
                done_points += pairs.len() as u64;
                for &(_, c) in &pairs {
                    match c {
                        2 => summary.ground += 1,
                        7 => summary.low_noise += 1,
                        _ => {}
                    }
                }
                summary.seeds += stats.seeds;
                summary.iterations = summary.iterations.max(stats.iterations);
                summary.largest_run_points = summary.largest_run_points.max(run_points);
                summary.largest_run_bytes = summary.largest_run_bytes.max(stats.bytes);
                store.put(&mut pairs)?;
                progress("classifying", done_points, total);
            }
            Ok(())
        })();
        // Workers waiting for memory, or to send a result, see the budget or channel closed.
        if outcome.is_err() {
            next.store(runs.len(), Ordering::Relaxed);
        }
        budget.close();
        drop(rx);
        outcome
    })?;
    if done_points != total {
        return Err(Error::Internal(format!(
            "the ground blocks owned {done_points} points of {total}"
        )));
    }
    summary.classify_seconds = start.elapsed().as_secs_f64();
    Ok((store, summary))
}

/// Runs the block `(tx, ty)` over the blocks `rect` (its buffered rectangle): the classes of
/// the points it owns, as `(index, tag)` pairs with the new class in the low byte, its
/// counters and the points it read.
fn run_block(
    index: &BlockIndex,
    grid: &TileGrid,
    params: &GroundParams,
    (tx, ty): (i64, i64),
    rect: BlockRect,
) -> Result<BlockResult> {
    let mut pts = Vec::new();
    let mut tags = Vec::new();
    index.read(&rect, &mut pts)?;
    index.read_tags(&rect, &mut tags)?;
    if tags.len() != pts.len() {
        return Err(Error::Internal(format!(
            "the block index gave {} points and {} tags",
            pts.len(),
            tags.len()
        )));
    }
    let world = grid.world(&rect);
    super::ptd::spatial_order(&mut pts, &mut tags, world);
    // The points the block owns, marked in their tags (the run keeps no coordinates of its
    // own: they move into its TIN).
    for (p, tag) in pts.iter().zip(tags.iter_mut()) {
        let (bx, by) = grid.block_of(p[0], p[1]);
        if grid.tile_of_block(bx, by) == (tx, ty) {
            *tag = Tag(*tag).owned().0;
        }
    }
    let n = pts.len();
    let mut labels = Vec::new();
    let stats = classify_run(pts, &tags, world, grid, params, &mut labels)?;
    check_labels(&labels, n)?;
    let mut out = Vec::new();
    for (&tag, &label) in tags.iter().zip(&labels) {
        let tag = Tag(tag);
        if tag.is_owned() {
            out.push((tag.index(), tag.new_class(label, params.reset)));
        }
    }
    Ok(BlockResult {
        classes: out,
        stats,
        points: n as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::ClassStore;

    #[test]
    fn class_store_in_a_file_gives_back_what_was_put_at_each_index() {
        let dir = std::env::temp_dir();
        let n = 3 * super::READ_PIECE as u64 + 17;
        let mut file = ClassStore::new(n, 0, &dir).unwrap();
        let mut memory = ClassStore::new(n, n, &dir).unwrap();
        // Scattered and consecutive indices, given out of order.
        let mut pairs: Vec<(u64, u8)> = (0..n)
            .rev()
            .step_by(3)
            .map(|i| (i, (i % 251) as u8))
            .collect();
        pairs.extend((0..1000).map(|i| (i * 3 + 1, 9)));
        file.put(&mut pairs.clone()).unwrap();
        memory.put(&mut pairs).unwrap();
        for i in (0..n).chain([n - 1, 5, 0]) {
            assert_eq!(file.get(i).unwrap(), memory.get(i).unwrap(), "index {i}");
        }
        assert!(file.get(n).is_err());
    }
}
