//! Putting points in sweep order: in memory ([`memory`]: validation, exact local origin, bucket
//! sort, duplicate policy) or out of core ([`external`]: chunks sorted with rayon, spilled, merged
//! by a tournament tree ([`loser`]) through sliding memory maps ([`mmap`]), duplicates merged;
//! chunks ordered by a key alone take a radix sort, [`radix`]). Every file this crate writes goes
//! out in pieces of at most `WRITE_PIECE` bytes (`write_pieces`), the spills first.
pub mod external;
pub(crate) mod loser;
pub mod memory;
pub mod mmap;
pub(crate) mod radix;

pub use memory::DuplicatePolicy;

/// The most bytes handed to one `write` call of a file: [`crate::output::AtomicFile`] writes at most this much
/// at a time, the buffered writers of large files (spills, spools, the block index) hold this
/// much, and [`write_pieces`] cuts larger slices (a writer of small files may buffer less).
/// Linux sizes the page-cache folios of a buffered write by the write's length, and on a virtual
/// machine that hands free memory back to its host (virtio-balloon free page reporting, 2 MiB
/// blocks) large folios come from blocks the host must fault in again page by page: writing
/// 1.6 GB in 1 MiB calls took 3.8–11 s of system CPU here, in 256 KiB calls 0.5 s (13 MB calls:
/// 0.1–1 s for 156 MB). Elsewhere it costs nothing (docs/BENCHMARKS.md, evening of 2026-12-04).
pub(crate) const WRITE_PIECE: usize = 256 << 10;

/// Writes `bytes` in pieces of at most [`WRITE_PIECE`] bytes.
///
/// # Errors
/// The writer's.
pub(crate) fn write_pieces(w: &mut impl std::io::Write, bytes: &[u8]) -> std::io::Result<()> {
    bytes.chunks(WRITE_PIECE).try_for_each(|p| w.write_all(p))
}
