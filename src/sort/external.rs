//! External sort of points into sweep order (by `y`, then `x`, then input index), with bounded
//! memory.
//!
//! Points are collected in chunks sized from the memory budget: two halves of it. When both are
//! full, each full half is sorted in RAM (rayon) and spilled as fixed-size little-endian records
//! ([`SortRecord`], `#[repr(C)]`, 32 bytes) to an anonymous temporary file under the chosen
//! directory (already unlinked: nothing is left behind even if the process is killed) by a
//! spilling thread, while the caller fills the other half: reading (LAZ decoding) goes on while a
//! run is sorted and written. At the end the runs are k-way merged,
//! each read through a small sliding memory map ([`crate::sort::mmap`]), so the merge's resident file
//! pages stay at a few hundred KiB per run. When everything fits
//! in one chunk, nothing is spilled. The merged order is a total order, so the result never
//! depends on the memory budget or the thread count.
//!
//! [`Dedup`] then merges exact `(x, y)` duplicates by a [`DuplicatePolicy`].

use crate::error::{Error, Result};
use crate::sort::memory::DuplicatePolicy;
use crate::sort::loser::LoserTree;
use crate::sort::mmap::MappedRecords;
use rayon::slice::ParallelSliceMut;
use std::cmp::Ordering;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// One point in a chunk or spill file: local-frame coordinates and the input index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SortRecord {
    /// x in the local frame.
    pub x: f64,
    /// y in the local frame.
    pub y: f64,
    /// Height.
    pub z: f64,
    /// Index of the point in the input.
    pub index: u64,
}

/// Sweep order: `y`, then `x`, then input index.
#[inline(always)]
pub fn sweep_order(a: &SortRecord, b: &SortRecord) -> Ordering {
    a.y.total_cmp(&b.y)
        .then(a.x.total_cmp(&b.x))
        .then(a.index.cmp(&b.index))
}

/// A fixed-size record the external sort can order.
pub trait SortKey: bytemuck::Pod + Send + Sync + std::fmt::Debug {
    /// The order of the sort.
    fn order(a: &Self, b: &Self) -> Ordering;
    /// Must records that compare equal keep their input order? (Then chunks are sorted with a
    /// stable sort and the merge breaks ties by run, so equal records come out in input order.)
    const STABLE: bool;
    /// Is the order (stable) that of [`SortKey::radix_key`] alone? Then spilled chunks take a
    /// radix sort, with scratch space as large as the half it sorts.
    const RADIX: bool = false;
    /// The key of a [`SortKey::RADIX`] order.
    fn radix_key(&self) -> u64 {
        0
    }
}

impl SortKey for SortRecord {
    #[inline(always)]
    fn order(a: &Self, b: &Self) -> Ordering {
        sweep_order(a, b)
    }
    // The order is total (the input index decides last).
    const STABLE: bool = false;
}

/// Records per spill when the budget allows no more.
const MIN_CHUNK: usize = 1 << 10;

/// Collects points, spilling sorted runs when the chunk is full.
#[derive(Debug)]
pub struct ExternalSorter<R: SortKey = SortRecord> {
    /// The half being filled.
    chunk: Vec<R>,
    /// The other half, full, while nothing is spilled yet.
    held: Vec<R>,
    /// Records per half.
    capacity: usize,
    /// The spilling thread, once the first run is spilled.
    spiller: Option<Spiller<R>>,
    tmp_dir: PathBuf,
    stats: SortStats,
    /// Most runs open at once (`max_open_runs`).
    max_runs: usize,
}

/// The thread that sorts full halves and writes them as runs, in the order it gets them, and
/// hands each emptied half back.
#[derive(Debug)]
struct Spiller<R: SortKey> {
    full: Option<crossbeam_channel::Sender<Vec<R>>>,
    empty: crossbeam_channel::Receiver<Vec<R>>,
    thread: Option<std::thread::JoinHandle<Result<Vec<File>>>>,
}

impl<R: SortKey> Spiller<R> {
    fn start(tmp_dir: &Path, max_runs: usize) -> Self {
        // A rendezvous: the caller's next half waits until the thread is free, so at most two
        // halves exist (the one being spilled, the one being filled).
        let (full, rx) = crossbeam_channel::bounded::<Vec<R>>(0);
        let (tx, empty) = crossbeam_channel::bounded::<Vec<R>>(1);
        let dir = tmp_dir.to_path_buf();
        let thread = std::thread::spawn(move || -> Result<Vec<File>> {
            let mut runs = Runs::new(max_runs);
            let mut scratch = Vec::new();
            for mut chunk in rx {
                let run = write_run(&mut chunk, &mut scratch, &dir)?;
                chunk.clear();
                // Never waits: the sorter takes each half back before handing over the next
                // (a half it does not want any more is freed here).
                let _ = tx.try_send(chunk);
                runs.push(run, &mut scratch, &dir)?;
            }
            Ok(runs.into_files())
        });
        Spiller {
            full: Some(full),
            empty,
            thread: Some(thread),
        }
    }

    /// Hands a full half over; `Err` when the thread has stopped (see [`Spiller::finish`]).
    fn send(&self, chunk: Vec<R>) -> std::result::Result<(), ()> {
        self.full.as_ref().ok_or(())?.send(chunk).map_err(|_| ())
    }

    /// The runs in order, or the error that stopped the thread.
    fn finish(&mut self) -> Result<Vec<File>> {
        self.full = None;
        let thread = self.thread.take().expect("finished once");
        thread
            .join()
            .unwrap_or_else(|p| Err(Error::panicked("the sort's spilling thread", &*p)))
    }
}

/// The spilled runs, in input order, with at most about `max_runs` files open: each run is an
/// open file (its descriptor), and a batch job's limit is often 1,024 descriptors. When the
/// newest `max_runs / 2` runs are all of one *level* (0: a spilled half; `l + 1`: a merge of
/// runs of level `l`), they are merged into one run of the next level, and so are the newest
/// `max_runs / 2` whatever their levels when `max_runs` are open. The runs merged are
/// consecutive in input order and the merge breaks ties by run, so the result is the same
/// stable order; each record is rewritten once per level, and a second level needs
/// `(max_runs / 2)²` halves.
struct Runs {
    files: Vec<(File, u32)>,
    group: usize,
}

impl Runs {
    fn new(max_runs: usize) -> Runs {
        Runs {
            files: Vec::new(),
            group: (max_runs / 2).max(2),
        }
    }

    /// Adds the newest run; `scratch` (the radix sort's) is given back before a merge.
    fn push<R: SortKey>(&mut self, run: File, scratch: &mut Vec<R>, dir: &Path) -> Result<()> {
        self.files.push((run, 0));
        loop {
            let Some(&(_, level)) = self.files.last() else {
                return Ok(());
            };
            let n = self.files.iter().rev().take_while(|f| f.1 == level).count();
            // The levels keep the rewriting to one per level; the cap holds whatever the levels.
            let full = self.files.len() >= 2 * self.group;
            if n < self.group && !full {
                return Ok(());
            }
            *scratch = Vec::new();
            let from = self.files.len() - self.group;
            let top = self.files[from..].iter().map(|f| f.1).max().unwrap_or(0);
            let group = self.files.drain(from..).map(|f| f.0).collect();
            let merged = merge_files::<R>(group, dir)?;
            self.files.push((merged, top + 1));
        }
    }

    fn into_files(self) -> Vec<File> {
        self.files.into_iter().map(|f| f.0).collect()
    }
}

/// Merges the runs `files` (in input order) into one new run under `dir`.
fn merge_files<R: SortKey>(files: Vec<File>, dir: &Path) -> Result<File> {
    let mut merge = Merge::<R>::of_runs(files, SortStats::default(), dir)?;
    let mut batch: Vec<R> = Vec::with_capacity(1 << 14);
    let file = new_run(dir, |w| {
        loop {
            batch.clear();
            batch.extend(merge.by_ref().take(1 << 14));
            if batch.is_empty() {
                return Ok(());
            }
            super::write_pieces(w, bytemuck::cast_slice(&batch))?;
        }
    })?;
    match merge.take_error() {
        Some(e) => Err(e),
        None => Ok(file),
    }
}

/// A new anonymous run file under `dir`, its records written by `write` through a buffer.
fn new_run(
    dir: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<&File>) -> std::io::Result<()>,
) -> Result<File> {
    let io = |e| Error::write(dir, e);
    let file = tempfile::tempfile_in(dir).map_err(io)?;
    let mut w = std::io::BufWriter::with_capacity(super::WRITE_PIECE, &file);
    write(&mut w).map_err(io)?;
    w.flush().map_err(io)?;
    drop(w);
    Ok(file)
}

/// How many runs a sort of `budget` bytes keeps open at most: a quarter of the process's limit on
/// open files beyond its own 16 (other sorts, inputs and outputs need theirs), and as many as the merge's windows
/// of the runs ([`crate::sort::mmap::WINDOW`] each) fit in half the budget; between 4 and 1,024.
fn max_open_runs(budget: u64) -> usize {
    let windows = budget / 2 / crate::sort::mmap::WINDOW as u64;
    // About 16 descriptors are the process's own (standard streams, the interrupt handler's
    // pipe, inputs, outputs and their spools).
    (crate::limits::open_files().saturating_sub(16) / 4)
        .min(windows)
        .clamp(4, 1024) as usize
}

/// Sorts `chunk` (a radix sort's scratch space in `scratch`) and writes it to a new anonymous
/// file under `dir`.
fn write_run<R: SortKey>(chunk: &mut [R], scratch: &mut Vec<R>, dir: &Path) -> Result<File> {
    if R::RADIX {
        crate::sort::radix::sort_by_key(chunk, scratch, R::radix_key);
    } else {
        sort_records(chunk);
    }
    let bytes: &[u8] = bytemuck::cast_slice(chunk);
    new_run(dir, |w| super::write_pieces(w, bytes))
}

fn sort_records<R: SortKey>(chunk: &mut [R]) {
    if R::STABLE {
        chunk.par_sort_by(R::order);
    } else {
        chunk.par_sort_unstable_by(R::order);
    }
}

/// What the sort did.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct SortStats {
    /// Points pushed.
    pub points: u64,
    /// Runs spilled to disk (0 when everything fit in memory).
    pub runs: u64,
    /// Bytes spilled.
    pub spilled_bytes: u64,
    /// Records per chunk.
    pub chunk_records: u64,
}

impl<R: SortKey> ExternalSorter<R> {
    /// A sorter whose two halves use at most `chunk_bytes` of memory, spilling under `tmp_dir`.
    /// A stable sort needs scratch space of half what it sorts (one half at a time, or both
    /// halves sorted as one when nothing is spilled): the halves then take four fifths. A radix
    /// sort needs scratch as large as the half it spills: the halves take two thirds.
    pub fn new(chunk_bytes: u64, tmp_dir: &Path) -> Self {
        let bytes = if R::RADIX {
            chunk_bytes / 3 * 2
        } else if R::STABLE {
            chunk_bytes / 5 * 4
        } else {
            chunk_bytes
        };
        let capacity = ((bytes as usize) / 2 / std::mem::size_of::<R>()).max(MIN_CHUNK);
        ExternalSorter {
            chunk: Vec::new(),
            held: Vec::new(),
            capacity,
            spiller: None,
            tmp_dir: tmp_dir.to_path_buf(),
            stats: SortStats {
                chunk_records: capacity as u64,
                ..SortStats::default()
            },
            max_runs: max_open_runs(chunk_bytes),
        }
    }

    /// Keeps at most about `n` runs open (at least 4).
    #[cfg(test)]
    fn with_max_runs(mut self, n: usize) -> Self {
        self.max_runs = n.max(4);
        self
    }

    /// Room left in the current half before it is full.
    #[cfg(any(test, feature = "dev"))]
    pub fn room(&self) -> usize {
        self.capacity - self.chunk.len()
    }

    /// Adds a point.
    ///
    /// # Errors
    /// [`Error::Write`] if a spill fails; [`Error::OutOfMemory`] if the chunk cannot grow (a
    /// memory limit below the budget): a message and clean-up instead of an abort.
    #[inline]
    pub fn push(&mut self, r: R) -> Result<()> {
        if self.chunk.len() == self.chunk.capacity() {
            self.grow()?;
        }
        self.chunk.push(r);
        self.stats.points += 1;
        if self.chunk.len() >= self.capacity {
            self.full()?;
        }
        Ok(())
    }

    /// The current half is full: hold it while nothing is spilled (the input may still fit in
    /// memory), else hand it to the spilling thread and take an emptied half back.
    #[cold]
    fn full(&mut self) -> Result<()> {
        if self.spiller.is_none() && self.held.is_empty() {
            self.held = std::mem::take(&mut self.chunk);
            return Ok(());
        }
        if self.spiller.is_none() {
            self.spiller = Some(Spiller::start(&self.tmp_dir, self.max_runs));
            let held = std::mem::take(&mut self.held);
            self.hand_over(held)?;
        }
        let chunk = std::mem::take(&mut self.chunk);
        self.hand_over(chunk)?;
        let spiller = self.spiller.as_mut().expect("started");
        match spiller.empty.recv() {
            Ok(v) => self.chunk = v,
            Err(_) => return Err(self.stopped()),
        }
        Ok(())
    }

    /// Gives a full half to the spilling thread.
    fn hand_over(&mut self, chunk: Vec<R>) -> Result<()> {
        self.stats.runs += 1;
        self.stats.spilled_bytes += std::mem::size_of_val(&chunk[..]) as u64;
        let spiller = self.spiller.as_ref().expect("started");
        spiller.send(chunk).map_err(|()| self.stopped())
    }

    /// The error that stopped the spilling thread.
    fn stopped(&mut self) -> Error {
        match self.spiller.as_mut().map(Spiller::finish) {
            Some(Err(e)) => e,
            _ => Error::Internal("the sort's spilling thread stopped".into()),
        }
    }

    /// Allocates the chunk for `points` points (as many as the input has, when its headers say;
    /// at most the chunk's capacity) before reading, so that a memory limit below the budget
    /// fails at once, with a message, rather than after minutes of reading.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`] naming the size.
    pub fn reserve(&mut self, points: u64) -> Result<()> {
        let want = usize::try_from(points)
            .unwrap_or(usize::MAX)
            .min(self.capacity);
        self.reserve_more(want.saturating_sub(self.chunk.len()))
    }

    /// Doubles the chunk's allocation (up to its capacity), failing cleanly.
    #[cold]
    fn grow(&mut self) -> Result<()> {
        let have = self.chunk.capacity();
        let more = have
            .max(1 << 20)
            .min(self.capacity - self.chunk.len())
            .max(1);
        self.reserve_more(more)
    }

    fn reserve_more(&mut self, more: usize) -> Result<()> {
        let have = self.chunk.capacity();
        self.chunk.try_reserve_exact(more).map_err(|_| {
            let bytes = ((have + more) * std::mem::size_of::<R>()) as u64;
            Error::OutOfMemory {
                what: format!("the sort's chunk of {} points", have + more),
                bytes,
                hint: "the process has less memory than --mem asks (ulimit -v, a cgroup or \
                       a batch job's limit): give a smaller --mem"
                    .into(),
            }
        })
    }

    /// Ends the input: returns the points in sweep order.
    ///
    /// # Errors
    /// [`Error::Write`] if the last spill or a mapping fails.
    pub fn finish(mut self) -> Result<Merge<R>> {
        let Some(mut spiller) = self.spiller.take() else {
            // Nothing spilled: both halves in memory, as one sorted vector (no copy when the
            // allocator can grow the first in place).
            let mut v = std::mem::take(&mut self.held);
            if v.is_empty() {
                v = std::mem::take(&mut self.chunk);
            } else if !self.chunk.is_empty() {
                let more = self.chunk.len();
                v.try_reserve_exact(more).map_err(|_| Error::OutOfMemory {
                    what: format!("the sort's chunk of {} points", v.len() + more),
                    bytes: ((v.len() + more) * std::mem::size_of::<R>()) as u64,
                    hint: "give a smaller --mem".into(),
                })?;
                v.append(&mut self.chunk);
            }
            sort_records(&mut v);
            return Ok(Merge {
                source: Source::Memory(v, 0),
                stats: self.stats,
                error: None,
            });
        };
        if !self.chunk.is_empty() {
            let chunk = std::mem::take(&mut self.chunk);
            self.stats.runs += 1;
            self.stats.spilled_bytes += std::mem::size_of_val(&chunk[..]) as u64;
            // A stopped thread reports its error from `finish` below.
            let _ = spiller.send(chunk);
        }
        let files = spiller.finish()?;
        Merge::of_runs(files, self.stats, &self.tmp_dir)
    }
}

#[derive(Debug)]
struct Run<R: SortKey> {
    map: MappedRecords<R>,
    pos: usize,
}

#[derive(Debug)]
enum Source<R: SortKey> {
    Memory(Vec<R>, usize),
    Runs {
        runs: Vec<Run<R>>,
        /// Each run's current record (`None`: the run is done).
        heads: Vec<Option<R>>,
        tree: LoserTree,
        /// The spill directory, to name it in an error.
        dir: PathBuf,
    },
}

/// The sorted points, as an iterator (k-way merge of the spilled runs, or the in-memory chunk).
#[derive(Debug)]
pub struct Merge<R: SortKey = SortRecord> {
    source: Source<R>,
    stats: SortStats,
    /// A spill file that could not be read ends the stream early; see [`Merge::take_error`].
    error: Option<Error>,
}

impl<R: SortKey> Merge<R> {
    /// The k-way merge of the sorted runs `files` (in input order), spilled under `dir`.
    fn of_runs(files: Vec<File>, stats: SortStats, dir: &Path) -> Result<Merge<R>> {
        let io = |e| Error::write(dir, e);
        let mut runs = Vec::with_capacity(files.len());
        for f in files {
            let m = MappedRecords::<R>::map(f).map_err(io)?;
            runs.push(Run { map: m, pos: 0 });
        }
        let heads = runs
            .iter_mut()
            .map(|r| r.map.get(0))
            .collect::<std::io::Result<Vec<_>>>()
            .map_err(io)?;
        let tree = LoserTree::new(runs.len(), |a, b| beats(&heads, a, b));
        Ok(Merge {
            source: Source::Runs {
                runs,
                heads,
                tree,
                dir: dir.to_path_buf(),
            },
            stats,
            error: None,
        })
    }

    /// What the sort did.
    pub fn stats(&self) -> SortStats {
        self.stats
    }

    /// The whole sorted input as one vector, when it fit in memory and nothing was read yet
    /// (no spill: the chunk itself).
    pub fn take_memory(&mut self) -> Option<Vec<R>> {
        match &mut self.source {
            Source::Memory(v, 0) => Some(std::mem::take(v)),
            _ => None,
        }
    }

    /// The error that ended the stream early, if any. A consumer must check it after the last
    /// record: a merge cut short by an I/O error is not the whole input.
    pub fn take_error(&mut self) -> Option<Error> {
        self.error.take()
    }
}

impl<R: SortKey> Iterator for Merge<R> {
    type Item = R;

    #[inline]
    fn next(&mut self) -> Option<R> {
        match &mut self.source {
            Source::Memory(v, i) => {
                let r = v.get(*i).copied();
                *i += 1;
                r
            }
            Source::Runs {
                runs,
                heads,
                tree,
                dir,
            } => {
                let w = tree.winner();
                let out = (*heads.get(w)?)?;
                let run = &mut runs[w];
                run.pos += 1;
                match run.map.get(run.pos) {
                    Ok(next) => heads[w] = next,
                    Err(e) => {
                        heads.iter_mut().for_each(|h| *h = None);
                        self.error = Some(Error::write(dir.as_path(), e));
                        return None;
                    }
                }
                tree.replay(|a, b| beats(heads, a, b));
                Some(out)
            }
        }
    }
}

/// Does run `a`'s head come before run `b`'s? The smaller record first, equal records from the
/// earlier run first (runs are in input order), a finished run last.
#[inline(always)]
fn beats<R: SortKey>(heads: &[Option<R>], a: usize, b: usize) -> bool {
    match (&heads[a], &heads[b]) {
        (Some(x), Some(y)) => R::order(x, y).then(a.cmp(&b)) == Ordering::Less,
        (Some(_), None) => true,
        (None, Some(_)) => false,
        (None, None) => a < b,
    }
}

/// Merges exact `(x, y)` duplicates of a sorted stream, keeping one point per position by policy.
#[derive(Debug)]
pub struct Dedup<I: Iterator<Item = SortRecord>> {
    inner: std::iter::Peekable<I>,
    policy: DuplicatePolicy,
    /// Index bits that mark a record whose identity must survive a merge (breakline vertices).
    mark: u64,
    /// Points merged away so far.
    pub duplicates: u64,
}

impl<I: Iterator<Item = SortRecord>> Dedup<I> {
    /// Wraps a stream sorted by [`sweep_order`].
    pub fn new(inner: I, policy: DuplicatePolicy) -> Self {
        Dedup {
            inner: inner.peekable(),
            policy,
            mark: 0,
            duplicates: 0,
        }
    }

    /// Records with any of the `mark` bits in their index keep their index when merged with
    /// duplicates: the survivor's `z` follows the policy, its index is the marked record's.
    pub fn with_mark(mut self, mark: u64) -> Self {
        self.mark = mark;
        self
    }
}

impl<I: Iterator<Item = SortRecord>> Iterator for Dedup<I> {
    type Item = SortRecord;

    #[inline]
    fn next(&mut self) -> Option<SortRecord> {
        let mut keep = self.inner.next()?;
        let mut marked = (keep.index & self.mark != 0).then_some(keep.index);
        while let Some(n) = self.inner.peek() {
            if n.x != keep.x || n.y != keep.y {
                break;
            }
            let n = *n;
            self.inner.next();
            self.duplicates += 1;
            if n.index & self.mark != 0 {
                marked = Some(n.index);
            }
            if self.policy.prefers((n.z, n.index), (keep.z, keep.index)) {
                keep = n;
            }
        }
        if let Some(m) = marked {
            keep.index = m;
        }
        Some(keep)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(x: f64, y: f64, z: f64, index: u64) -> SortRecord {
        SortRecord { x, y, z, index }
    }

    #[test]
    fn spilled_merge_equals_in_memory_sort() {
        let dir = tempfile::tempdir().unwrap();
        let mut s: u64 = 12345;
        let mut pts = Vec::new();
        for i in 0..300_000u64 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let x = ((s >> 33) % 1000) as f64;
            let y = ((s >> 13) % 1000) as f64;
            pts.push(rec(x, y, i as f64, i));
        }
        let mut small = ExternalSorter::new(1, dir.path());
        let mut big = ExternalSorter::new(1 << 30, dir.path());
        for p in &pts {
            small.push(*p).unwrap();
            big.push(*p).unwrap();
        }
        let a = small.finish().unwrap();
        assert!(a.stats().runs >= 4);
        let b = big.finish().unwrap();
        assert_eq!(b.stats().runs, 0);
        let a: Vec<_> = a.collect();
        let b: Vec<_> = b.collect();
        assert_eq!(a, b);
        pts.sort_by(sweep_order);
        assert_eq!(a, pts);
        // The spill files were anonymous: nothing is left in the directory.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    /// A record with a key and its input position, ordered by the key alone (stably).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
    struct Keyed {
        key: u64,
        seq: u64,
    }

    impl SortKey for Keyed {
        fn order(a: &Self, b: &Self) -> Ordering {
            a.key.cmp(&b.key)
        }
        const STABLE: bool = true;
        const RADIX: bool = true;
        fn radix_key(&self) -> u64 {
            self.key
        }
    }

    #[test]
    fn many_runs_are_merged_as_they_come_in_the_same_stable_order() {
        let dir = tempfile::tempdir().unwrap();
        let mut s: u64 = 99;
        let recs: Vec<Keyed> = (0..300_000u64)
            .map(|seq| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                Keyed {
                    key: (s >> 40) % 50,
                    seq,
                }
            })
            .collect();
        // Halves of 1,024 records: about 290 runs, never more than about 3 per level open.
        let mut sorter = ExternalSorter::<Keyed>::new(1, dir.path()).with_max_runs(8);
        for r in &recs {
            sorter.push(*r).unwrap();
        }
        let merge = sorter.finish().unwrap();
        assert!(merge.stats().runs > 250, "{:?}", merge.stats());
        let Source::Runs { runs, .. } = &merge.source else {
            panic!("spilled")
        };
        assert!(runs.len() < 8, "{} runs open", runs.len());
        let got: Vec<Keyed> = merge.collect();
        let mut want = recs;
        want.sort_by_key(|r| r.key);
        assert_eq!(got, want);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_merge_of_no_runs_is_empty() {
        let dir = tempfile::tempdir().unwrap();
        let mut m = Merge::<SortRecord>::of_runs(Vec::new(), SortStats::default(), dir.path())
            .unwrap();
        assert!(m.next().is_none());
    }

    #[test]
    fn dedup_by_policy() {
        let v = vec![
            rec(0., 0., 5., 0),
            rec(0., 0., 1., 3),
            rec(0., 0., 9., 7),
            rec(1., 0., 0., 1),
        ];
        let first: Vec<_> = Dedup::new(v.clone().into_iter(), DuplicatePolicy::First).collect();
        assert_eq!(first[0].index, 0);
        let low: Vec<_> = Dedup::new(v.clone().into_iter(), DuplicatePolicy::Lowest).collect();
        assert_eq!(low[0].index, 3);
        let mut d = Dedup::new(v.into_iter(), DuplicatePolicy::Last);
        assert_eq!(d.next().unwrap().index, 7);
        assert_eq!(d.next().unwrap().index, 1);
        assert_eq!(d.duplicates, 2);
    }
}
