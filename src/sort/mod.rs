//! Putting points in sweep order: in memory ([`memory`]: validation, exact local origin, bucket
//! sort, duplicate policy) or out of core ([`external`]: chunks sorted with rayon, spilled, merged
//! through sliding memory maps ([`mmap`]), duplicates merged; chunks ordered by a key alone take a
//! radix sort, [`radix`]).

pub mod external;
pub mod memory;
pub mod mmap;
pub(crate) mod radix;

pub use memory::DuplicatePolicy;
