//! The only `unsafe` code in sweeptin: read-only memory maps of the external sort's own spill
//! files, [`SpillVec`] (a growable table of plain data that can move into a shared map of its own
//! temporary file and drop its pages from the resident set), one allocator setting that gives large allocations maps of their own
//! ([`tune_allocator`]), and one system call that has no safe wrapper ([`start_writeback`]).
//!
//! A spill file is an anonymous temporary file (already unlinked, so no other process can open
//! it) that this process wrote completely and never writes again while it is mapped; that is what
//! makes mapping it sound. Records are plain old data (`bytemuck::Pod`), so any bytes are a valid
//! record, and every mapping starts at a page-aligned file offset that is a multiple of the record
//! size, so the cast to records is aligned.
//!
//! # Why a sliding window, not the whole file
//!
//! The merge reads each run front to back. Mapping a whole run and releasing consumed pages with
//! `MADV_DONTNEED` is not enough on current kernels: the spill file's page cache is made of large
//! folios (up to 2 MiB), and one page fault maps the whole folio around the faulting address, so a
//! k-way merge kept about k × 2 MiB of file pages resident (measured: 45 MiB of file-backed RSS
//! merging 20 runs, 100 MiB merging 48). The map only ever covers a [`WINDOW`]-byte window of the
//! file, pre-faulted with `MAP_POPULATE`; moving on unmaps the old window. A fault can map no page
//! outside the mapping, so at most k × [`WINDOW`] bytes of the runs are resident.
//!
//! # Disk space given back as the merge goes
//!
//! The records are read once, front to back. On Linux the bytes behind the window are released
//! with `fallocate(PUNCH_HOLE)` every [`PUNCH`] bytes, so the runs shrink on disk while the merge
//! writes its output: a billion points need the runs' size of temporary disk, not the runs' plus
//! the merged output's. (Reading a released part again is refused: the records are gone.)
#![allow(unsafe_code)]

use bytemuck::Pod;
use memmap2::{Mmap, MmapOptions};
use std::fs::File;
use std::marker::PhantomData;

/// Bytes of a run mapped at a time (a multiple of the page size and of every record size used).
pub const WINDOW: usize = 256 * 1024;

/// Bytes of consumed records released from the disk at a time (a multiple of [`WINDOW`]).
pub const PUNCH: usize = 64 * WINDOW;

/// A file of fixed-size records, read front to back through a sliding read-only memory map.
#[derive(Debug)]
pub struct MappedRecords<T: Pod> {
    file: File,
    /// The current window, covering records `start .. start + records().len()`.
    map: Option<Mmap>,
    start: usize,
    len: usize,
    /// Bytes from the start of the file given back to the file system (read no more).
    released: usize,
    _t: PhantomData<T>,
}

impl<T: Pod> MappedRecords<T> {
    /// Takes `file`, which must hold a whole number of `T` records and must not be written while
    /// mapped (the caller created it and finished writing it), and maps its first window.
    ///
    /// # Errors
    /// The operating system's error if mapping fails, `InvalidData` if the length is not a
    /// multiple of the record size.
    pub fn map(file: File) -> std::io::Result<Self> {
        let bytes = file.metadata()?.len() as usize;
        let size = std::mem::size_of::<T>();
        debug_assert!(WINDOW.is_multiple_of(size));
        if !bytes.is_multiple_of(size) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "spill file is not a whole number of records",
            ));
        }
        let mut m = MappedRecords {
            file,
            map: None,
            start: 0,
            len: bytes / size,
            released: 0,
            _t: PhantomData,
        };
        m.slide(0)?;
        Ok(m)
    }

    /// Maps the window holding record `i` (or nothing past the end).
    fn slide(&mut self, i: usize) -> std::io::Result<()> {
        let size = std::mem::size_of::<T>();
        let per = WINDOW / size;
        let start = i / per * per;
        if start * size < self.released {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "spill records read again after their disk space was released",
            ));
        }
        self.map = None; // unmap the old window first: never two windows resident
        self.start = start;
        if start * size >= self.released + PUNCH {
            let upto = start * size / PUNCH * PUNCH;
            release(&self.file, self.released, upto - self.released);
            self.released = upto;
        }
        if start >= self.len {
            return Ok(());
        }
        let count = per.min(self.len - start);
        // SAFETY: the file is a private, unlinked temporary file that this process has finished
        // writing; nothing modifies or truncates it while the map lives (see the module docs).
        // The offset is a multiple of WINDOW, hence page-aligned.
        let map = unsafe {
            MmapOptions::new()
                .offset((start * size) as u64)
                .len(count * size)
                .populate()
                .map(&self.file)?
        };
        self.map = Some(map);
        Ok(())
    }

    /// Bytes given back to the file system so far (Linux; 0 elsewhere).
    #[cfg(test)]
    fn released(&self) -> usize {
        self.released
    }

    /// The records of the current window (from record [`MappedRecords::window_start`] on).
    fn records(&self) -> &[T] {
        match &self.map {
            Some(m) => bytemuck::cast_slice(&m[..]),
            None => &[],
        }
    }

    /// Index of the first record of the current window.
    fn window_start(&self) -> usize {
        self.start
    }

    /// Record `i`, moving the window forward (or back) when `i` lies outside it; `None` past the
    /// end.
    ///
    /// # Errors
    /// The operating system's error if mapping the next window fails.
    #[inline]
    pub fn get(&mut self, i: usize) -> std::io::Result<Option<T>> {
        let off = i.wrapping_sub(self.window_start());
        if let Some(r) = self.records().get(off) {
            return Ok(Some(*r));
        }
        if i >= self.len {
            return Ok(None);
        }
        self.slide(i)?;
        Ok(self.records().get(i - self.start).copied())
    }

    /// Number of records.
    #[cfg(any(test, feature = "dev"))]
    pub fn len(&self) -> usize {
        self.len
    }

    /// No records?
    #[cfg(any(test, feature = "dev"))]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Gives the bytes `offset .. offset + len` of `file` back to the file system (a hole: the size
/// stays). Best effort: a file system without holes keeps the bytes, which only costs space.
#[cfg(target_os = "linux")]
fn release(file: &File, offset: usize, len: usize) {
    use rustix::fs::{FallocateFlags, fallocate};
    let flags = FallocateFlags::PUNCH_HOLE | FallocateFlags::KEEP_SIZE;
    // Best effort (a file system without holes keeps the bytes), but an interrupted call is
    // tried again.
    while fallocate(file, flags, offset as u64, len as u64) == Err(rustix::io::Errno::INTR) {}
}

#[cfg(not(target_os = "linux"))]
fn release(_file: &File, _offset: usize, _len: usize) {}

/// Starts writing every dirty page of `file` to its disk without waiting for it and without
/// dropping any page from the cache (`sync_file_range(SYNC_FILE_RANGE_WRITE)` over the whole
/// file): a later `fsync` then has little left to do. A hint: errors are ignored.
pub fn start_writeback(file: &File) {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        // SAFETY: sync_file_range only reads the descriptor, which `file` keeps open for the
        // call; offset 0 and length 0 mean the whole file; it touches no memory of ours.
        unsafe {
            libc::sync_file_range(file.as_raw_fd(), 0, 0, libc::SYNC_FILE_RANGE_WRITE);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = file;
}

/// Fewest elements a [`SpillVec`] maps (a map is never empty).
const MIN_MAPPED: usize = 1 << 16;

/// A growable array of plain-old-data values that lives on the heap like a `Vec` until
/// [`SpillVec::spill`] moves it into a shared memory map of a temporary file of its own
/// (anonymous: already unlinked). From then on its pages belong to the file's page cache:
/// [`SpillVec::release`] drops them from the process's resident set (`MADV_DONTNEED`; the data
/// stays in the file, and a later touch is a minor fault, or a read if the kernel wrote the page
/// out and reclaimed it). The streaming sweep's per-triangle and per-vertex tables are
/// `SpillVec`s, so the triangles it must hold (points on a line or a circle) live in a file
/// rather than in `--mem` (`crate::finalise`).
///
/// Indexing goes through a raw pointer and a length, as a `Vec`'s does, in both states.
pub struct SpillVec<T: Pod> {
    /// Start of the elements: the vector's buffer or the map's.
    ptr: *mut T,
    len: usize,
    store: Store<T>,
}

enum Store<T> {
    Heap(Vec<T>),
    /// `map` covers `cap` elements of `file`, which nothing else opens.
    Map {
        map: memmap2::MmapMut,
        file: File,
        cap: usize,
    },
}

// SAFETY: a `SpillVec` owns its elements as a `Vec` does (the pointer is into its own vector or
// its own private map, never shared), so it is sent and shared exactly when `T` is.
unsafe impl<T: Pod + Send> Send for SpillVec<T> {}
// SAFETY: as above: `&SpillVec` only gives `&[T]`.
unsafe impl<T: Pod + Sync> Sync for SpillVec<T> {}

impl<T: Pod> Default for SpillVec<T> {
    fn default() -> Self {
        Self::from_vec(Vec::new())
    }
}

impl<T: Pod> From<Vec<T>> for SpillVec<T> {
    fn from(v: Vec<T>) -> Self {
        Self::from_vec(v)
    }
}

impl<T: Pod> Clone for SpillVec<T> {
    /// A copy on the heap.
    fn clone(&self) -> Self {
        Self::from_vec(self.to_vec())
    }
}

impl<T: Pod + std::fmt::Debug> std::fmt::Debug for SpillVec<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpillVec")
            .field("len", &self.len)
            .field("mapped", &self.is_mapped())
            .finish()
    }
}

impl<T: Pod> std::ops::Deref for SpillVec<T> {
    type Target = [T];
    #[inline(always)]
    fn deref(&self) -> &[T] {
        // SAFETY: `ptr` points at `len` initialised elements owned by `self` (the vector's first
        // `len`, or the first `len` of the map, which covers at least that many and whose bytes
        // are valid values of a `Pod` type); `ptr` is aligned (a vector's buffer, or a map that
        // starts on a page) and non-null; nothing else writes them while `&self` lives.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

impl<T: Pod> std::ops::DerefMut for SpillVec<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T] {
        // SAFETY: as for `deref`, and `&mut self` makes the access exclusive.
        unsafe { std::slice::from_raw_parts_mut(self.ptr, self.len) }
    }
}

impl<T: Pod> SpillVec<T> {
    /// An empty vector with room for `n` elements on the heap.
    pub fn with_capacity(n: usize) -> Self {
        Self::from_vec(Vec::with_capacity(n))
    }

    /// Takes `v` as it is (on the heap).
    pub fn from_vec(mut v: Vec<T>) -> Self {
        SpillVec {
            ptr: v.as_mut_ptr(),
            len: v.len(),
            store: Store::Heap(v),
        }
    }

    /// The elements as a `Vec` (the heap buffer itself, or a copy of the map).
    pub fn into_vec(self) -> Vec<T> {
        if self.is_mapped() {
            return self.to_vec();
        }
        match self.store {
            Store::Heap(v) => v,
            Store::Map { .. } => unreachable!("checked above"),
        }
    }

    /// Is it in a file's map?
    pub fn is_mapped(&self) -> bool {
        matches!(self.store, Store::Map { .. })
    }

    /// Elements it has room for without growing.
    pub fn capacity(&self) -> usize {
        match &self.store {
            Store::Heap(v) => v.capacity(),
            Store::Map { cap, .. } => *cap,
        }
    }

    /// Bytes of heap it holds (its capacity; 0 once mapped).
    pub fn heap_bytes(&self) -> usize {
        match &self.store {
            Store::Heap(v) => v.capacity() * std::mem::size_of::<T>(),
            Store::Map { .. } => 0,
        }
    }

    /// Makes room for `extra` more elements; in a map, the file grows first (its blocks
    /// allocated, so that a later write through the map cannot find the disk full).
    ///
    /// # Errors
    /// The operating system's error if the file cannot grow or be mapped again; the elements
    /// are then as they were.
    pub fn try_reserve(&mut self, extra: usize) -> std::io::Result<()> {
        let need = self.len + extra;
        match &mut self.store {
            Store::Heap(v) => {
                v.reserve(extra);
                self.ptr = v.as_mut_ptr();
            }
            Store::Map { cap, .. } if need <= *cap => {}
            Store::Map { map, file, cap } => {
                let new_cap = need.max(2 * *cap);
                let bytes = new_cap * std::mem::size_of::<T>();
                allocate(file, bytes)?;
                let mut grown = map_table(file, bytes)?;
                self.ptr = grown.as_mut_ptr().cast();
                *map = grown;
                *cap = new_cap;
            }
        }
        Ok(())
    }

    #[inline(always)]
    fn grow_for(&mut self, extra: usize) {
        if self.len + extra > self.capacity()
            && let Err(e) = self.try_reserve(extra)
        {
            // The owner reserves room before each step that adds elements (the sweep: every
            // point), so this needs one step to add more than that room.
            panic!("a spilled table could not grow its temporary file: {e}");
        }
    }

    /// Makes room for exactly `extra` more elements on the heap (in a map as [`SpillVec::try_reserve`]).
    pub fn reserve_exact(&mut self, extra: usize) {
        if let Store::Heap(v) = &mut self.store {
            v.reserve_exact(extra);
            self.ptr = v.as_mut_ptr();
        } else {
            self.grow_for(extra);
        }
    }

    /// Appends `x`.
    #[inline(always)]
    pub fn push(&mut self, x: T) {
        self.extend_from_slice(std::slice::from_ref(&x));
    }

    /// Appends the elements of `xs`.
    #[inline(always)]
    pub fn extend_from_slice(&mut self, xs: &[T]) {
        if let Store::Heap(v) = &mut self.store {
            v.extend_from_slice(xs);
            self.ptr = v.as_mut_ptr();
            self.len = v.len();
            return;
        }
        self.grow_for(xs.len());
        // SAFETY: the map has room for `len + xs.len()` elements (`grow_for`), `xs` cannot
        // overlap the map's unused part (no slice of it is handed out).
        unsafe { std::ptr::copy_nonoverlapping(xs.as_ptr(), self.ptr.add(self.len), xs.len()) };
        self.len += xs.len();
    }

    /// Sets the length to `n`, filling new places with `x`.
    pub fn resize(&mut self, n: usize, x: T) {
        if let Store::Heap(v) = &mut self.store {
            v.resize(n, x);
            self.ptr = v.as_mut_ptr();
            self.len = v.len();
            return;
        }
        if n > self.len {
            self.grow_for(n - self.len);
            let old = self.len;
            self.len = n;
            self[old..].fill(x);
        } else {
            self.len = n;
        }
    }

    /// Moves the elements into a shared map of a new anonymous temporary file under `dir`,
    /// with room for twice as many; the heap buffer is freed. Does nothing if already mapped.
    ///
    /// # Errors
    /// The operating system's error (no room for the file, the map refused under an
    /// address-space limit); the elements then stay where they were.
    pub fn spill(&mut self, dir: &std::path::Path) -> std::io::Result<()> {
        let Store::Heap(v) = &self.store else {
            return Ok(());
        };
        let cap = (2 * v.len()).max(MIN_MAPPED);
        let bytes = cap * std::mem::size_of::<T>();
        let file = tempfile::tempfile_in(dir)?;
        allocate(&file, bytes)?;
        let mut map = map_table(&file, bytes)?;
        map[..v.len() * std::mem::size_of::<T>()].copy_from_slice(bytemuck::cast_slice(v));
        self.ptr = map.as_mut_ptr().cast();
        self.store = Store::Map { map, file, cap };
        Ok(())
    }

    /// Drops the map's pages from the process's resident set; the data stays in the file (a
    /// later touch faults the page in again). Does nothing on the heap.
    pub fn release(&mut self) {
        if let Store::Map { map, .. } = &self.store {
            // SAFETY: on a shared file mapping, MADV_DONTNEED only unmaps the pages: their
            // contents, dirty ones included, stay in the file's page cache and are what a later
            // access reads, so no element changes (a reference into the map would see the same
            // bytes).
            let _ = unsafe { map.unchecked_advise(memmap2::UncheckedAdvice::DontNeed) };
        }
    }
}

/// Maps the first `bytes` of a [`SpillVec`]'s file (at least that long), for random access.
///
/// `MADV_RANDOM`: the tables are touched all over (a heap, rows of held triangles), so no
/// read-ahead around a fault. A hint whose effect was not measured apart: on Linux 6.18 with
/// ext4's large folios the resident memory between two releases stayed bounded only once the
/// releases came often enough (`finalise::tables`), with or without it.
fn map_table(file: &File, bytes: usize) -> std::io::Result<memmap2::MmapMut> {
    // SAFETY: the file was created by `SpillVec::spill`, already unlinked, and is owned by one
    // `SpillVec` alone: no other process or mapping can change it while it is mapped, so its
    // bytes behave as memory of ours. It is at least `bytes` long, which the map covers.
    let map = unsafe { memmap2::MmapOptions::new().len(bytes).map_mut(file)? };
    // A hint: a kernel that ignores it maps larger folios, nothing else changes.
    let _ = map.advise(memmap2::Advice::Random);
    Ok(map)
}

/// Makes `file` `bytes` long with its blocks allocated (`fallocate`): a write through a map of
/// it then cannot meet a full disk (which a map reports as SIGBUS, not as an error).
fn allocate(file: &File, bytes: usize) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{FallocateFlags, fallocate};
        loop {
            match fallocate(file, FallocateFlags::empty(), 0, bytes as u64) {
                Err(rustix::io::Errno::INTR) => continue,
                // A file system without fallocate: the size alone.
                Err(rustix::io::Errno::OPNOTSUPP) => break,
                r => return r.map_err(std::io::Error::from),
            }
        }
    }
    file.set_len(bytes as u64)
}

/// Bytes from which an allocation gets an anonymous memory map of its own (glibc), see
/// [`tune_allocator`].
pub const OWN_MAP_BYTES: usize = 4 << 20;

/// Bytes of freed memory a glibc heap keeps at its top before giving them back, see
/// [`tune_allocator`].
pub const KEEP_FREE_BYTES: usize = 8 << 20;

/// glibc's heaps (arenas) at most, whatever the number of threads ([`tune_allocator`]).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MAX_ARENAS: libc::c_int = 4;

/// Set by [`tune_allocator`]: the program owns the allocator's settings.
static TUNED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Gives the pages of freed memory inside glibc's heaps back to the system (`malloc_trim`) when
/// the process holds more than three quarters of `budget` in anonymous memory, once
/// [`tune_allocator`] has run (a host such as Python keeps its allocator to itself). The heaps
/// keep what freed vectors leave between live ones: holes that the top-of-heap trim never
/// reaches, most with many threads (ARSO's ground DEM at `--threads 32`, `--mem 128M`: 152 →
/// 119 MB peak RSS; trimming only above the whole budget, 146 MB). Called between rows of tiles;
/// below that it does nothing, since trimmed pages fault in again (trimming every row of the
/// 100M DEM cost up to 0.75 s of system time for the same peak).
pub(crate) fn release_free_memory_above(budget: u64) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if TUNED.load(std::sync::atomic::Ordering::Relaxed)
        && crate::limits::anon_rss().is_some_and(|a| a > budget / 4 * 3)
    {
        // SAFETY: malloc_trim only returns free pages of the heaps to the system; glibc takes
        // each heap's lock while it does.
        unsafe {
            libc::malloc_trim(0);
        }
    }
}

/// Makes glibc serve every allocation of 4 MiB (`OWN_MAP_BYTES`) or more from a memory map of its own,
/// unmapped when freed, so memory freed by one tile or run goes back to the system at once; and
/// lets each heap keep up to 8 MiB (`KEEP_FREE_BYTES`) of freed memory at its top.
///
/// By default glibc raises that threshold to the size of the largest block freed so far, so after
/// the first large buffer is freed, later ones come from its heaps (one per thread), which keep
/// freed memory for reuse: the tiled `thin` of the ARSO ground peaked at 416 MB at `--mem 256M`
/// (216 MB with this setting) and the billion-point tiled DEM at 543 MB (379 MB with a 1 MiB
/// threshold). A smaller threshold holds less but faults in more fresh pages (1 MiB: 2.5× the
/// system time); 4 MiB is the compromise measured in `docs/BENCHMARKS.md`.
///
/// Fixing the threshold leaves glibc's trim threshold at 128 KiB: each tile's run freed its
/// vectors, the heap gave the pages back (`madvise`) and the next run faulted fresh ones in. An
/// 8 MiB trim threshold keeps them: the ARSO ground DEM's system time 0.5–0.6 s → 0.2–0.3 s
/// at the same peak RSS (a heap keeps at most that much it does not use).
///
/// glibc keeps to four arenas (two under an address-space limit, `ulimit -v` or SGE's `h_vmem`,
/// which counts each arena's 64 MiB reservation). By default it makes up to eight per core as
/// threads contend, and each keeps what its threads freed: ARSO's ground DEM at `--mem 128M`
/// and `--threads 32` peaked at 292–306 MB of RSS (four arenas: 204–218 MB, the same time; at
/// `--threads 2` no change, 68–71 MB).
///
/// Call it once, first thing (the `sweeptin` command does; the Python module leaves its host's
/// allocator alone); the environment's `MALLOC_MMAP_THRESHOLD_`, `MALLOC_TRIM_THRESHOLD_` and
/// `MALLOC_ARENA_MAX`, when set, win. Does nothing on other C libraries.
pub fn tune_allocator() {
    TUNED.store(true, std::sync::atomic::Ordering::Relaxed);
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    for (name, param, bytes) in [
        ("MALLOC_MMAP_THRESHOLD_", libc::M_MMAP_THRESHOLD, OWN_MAP_BYTES),
        ("MALLOC_TRIM_THRESHOLD_", libc::M_TRIM_THRESHOLD, KEEP_FREE_BYTES),
    ] {
        if std::env::var_os(name).is_none() {
            // SAFETY: mallopt only changes the allocator's parameters; it is safe to call at
            // any time (glibc takes its own lock), and a rejected value leaves them as they
            // were.
            unsafe {
                libc::mallopt(param, bytes as libc::c_int);
            }
        }
    }
    // Under an address-space limit (`ulimit -v`, SGE's `h_vmem`), each arena's 64 MiB
    // reservation counts: ARSO's tiled DEM mapped 370–390 MB with one arena per thread, whatever
    // `--mem`, and aborted under 322 MiB at `--mem 64M`; with two arenas it maps 142–181 MB.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_ARENA_MAX").is_none() {
        let arenas = if crate::limits::address_space().is_some() {
            2
        } else {
            MAX_ARENAS
        };
        // SAFETY: as above.
        unsafe {
            libc::mallopt(libc::M_ARENA_MAX, arenas);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// A spilled table reads back what it held, grows in its file, and keeps every element
    /// when its pages are dropped from the resident set.
    #[test]
    fn a_spilled_vector_keeps_its_elements_through_growth_and_release() {
        let dir = tempfile::tempdir().unwrap();
        let mut v: SpillVec<u64> = SpillVec::default();
        for i in 0..1000u64 {
            v.push(i * 3);
        }
        v.spill(dir.path()).unwrap();
        assert!(v.is_mapped() && v.heap_bytes() == 0);
        let n = 3 * MIN_MAPPED as u64;
        for i in 1000..n {
            v.push(i * 3);
        }
        v[7] = 1;
        v.release();
        v.extend_from_slice(&[5, 6]);
        v.resize(v.len() + 3, 9);
        v.release();
        assert_eq!(v.len() as u64, n + 5);
        assert_eq!(v[7], 1);
        assert!((8..n as usize).all(|i| v[i] == 3 * i as u64));
        assert_eq!(&v[n as usize..], &[5, 6, 9, 9, 9]);
        let c = v.clone();
        assert!(!c.is_mapped());
        assert_eq!(c.into_vec(), v.into_vec());
    }

    #[test]
    fn reads_every_record_across_windows() {
        let per = WINDOW / 8;
        let n = 2 * per + 17;
        let mut f = tempfile::tempfile().unwrap();
        let data: Vec<u64> = (0..n as u64).collect();
        f.write_all(bytemuck::cast_slice(&data)).unwrap();
        let mut m = MappedRecords::<u64>::map(f).unwrap();
        assert_eq!(m.len(), n);
        for (i, want) in data.iter().enumerate() {
            assert_eq!(m.get(i).unwrap(), Some(*want));
        }
        assert_eq!(m.get(n).unwrap(), None);
        // Going back within what is still on disk maps the earlier window again.
        assert_eq!(m.get(3).unwrap(), Some(3));
    }

    #[test]
    fn consumed_records_leave_the_disk() {
        use std::os::unix::fs::MetadataExt;
        let per = WINDOW / 8;
        let n = PUNCH / 8 * 3 + per / 2;
        let mut f = tempfile::tempfile().unwrap();
        let data: Vec<u64> = (0..n as u64).collect();
        f.write_all(bytemuck::cast_slice(&data)).unwrap();
        f.sync_all().unwrap();
        let probe = f.try_clone().unwrap();
        let blocks = |f: &File| f.metadata().unwrap().blocks() * 512;
        let before = blocks(&probe);
        let mut m = MappedRecords::<u64>::map(f).unwrap();
        for (i, want) in data.iter().enumerate() {
            assert_eq!(m.get(i).unwrap(), Some(*want));
        }
        if cfg!(target_os = "linux") {
            assert_eq!(m.released(), 3 * PUNCH);
            // tmpfs and ext4 both punch holes; the allocated size shrinks by what was released,
            // give or take the file system's own blocks (ext4 may add an extent-tree block when
            // a file written beside others is fragmented: seen as 4 KiB more).
            let after = blocks(&probe);
            let slack = 64 * 1024;
            assert!(
                after <= before - 3 * PUNCH as u64 + slack,
                "no hole punched: {before} -> {after} bytes allocated"
            );
            let e = m.get(0).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        }
    }

    #[test]
    fn empty_and_ragged_files() {
        let f = tempfile::tempfile().unwrap();
        let mut m = MappedRecords::<u64>::map(f).unwrap();
        assert!(m.is_empty());
        assert_eq!(m.get(0).unwrap(), None);
        let mut f = tempfile::tempfile().unwrap();
        f.write_all(&[1, 2, 3]).unwrap();
        let e = MappedRecords::<u64>::map(f).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
    }
}
