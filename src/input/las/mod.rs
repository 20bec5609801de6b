//! LAS/LAZ input: header facts, filters, and a chunked reader over one or more files.
//!
//! [`LidarReader`] reads one or more LAS/LAZ files as **one point set** (adjacent tiles), in
//! chunks of bounded size, keeping only the points a [`Filter`] accepts. Each [`LidarPoint`]
//! carries the **integer coordinates** the file stores, in one integer system common to all the
//! files (exact: the box filter and the combination of tiles work on them), plus its **global
//! input index**: files in the order given, points in file order, counting every point read
//! (filtered points leave gaps). The geometry is not made of these integers but of the
//! real-world doubles `offset + scale × N` ([`Quantization::to_world`]), computed once when the
//! pipeline reads the points: the values the outputs get, so that every output is Delaunay in
//! its own coordinates (docs/ARCHITECTURE.md, "Coordinates").
//!
//! ```no_run
//! use sweeptin::input::las::{Filter, LidarReader};
//!
//! let filter = Filter { classes: Some(vec![2]), ..Filter::default() };
//! let mut reader = LidarReader::open(&["a.laz", "b.laz"], &filter)?;
//! let quant = *reader.quantization(); // integers -> the real-world doubles
//! let mut chunk = Vec::new();
//! while reader.read_chunk(&mut chunk, 1 << 20)? > 0 {
//!     for p in &chunk {
//!         let [x, y, z] = quant.to_world(p);
//!         # let _ = (x, y, z);
//!     }
//!     chunk.clear();
//! }
//! println!("{:?}, CRS {:?}", reader.stats(), reader.crs().and_then(|c| c.definition()));
//! # Ok::<(), sweeptin::Error>(())
//! ```
//!
//! # Several files: one integer lattice
//!
//! Files read together are converted **exactly** into one integer system (see [`combine`] for
//! the details): per axis, the common scale is the finest scale among the files and the common
//! offset is the first file's offset; every file's scale must be a whole multiple `k` of the
//! common scale and its offset must lie a whole number `d` of common steps from the common
//! offset. A stored integer `N` becomes `k × N + d` (computed in `i64`, required to fit `i32`).
//! Real-world coordinates are `offset + scale × N` with the [`Quantization`] the reader reports.
//! Files that cannot be combined this way are refused with an [`crate::Error::Format`] naming
//! both files and their scales and offsets. Files that declare a CRS must declare the same one.
//!
//! # Damaged files
//!
//! Every file's header, VLRs and LAZ chunk table are checked against the file's length before
//! any decoder runs ([`FileInfo::read`]); empty, truncated, corrupt and non-LAS files give an
//! [`crate::Error::Format`] naming the file, never a panic.

mod chunks;
pub mod combine;

pub mod filter;
pub mod header;
mod reader;

pub use crate::crs::{Crs, HorizontalKind};
pub use combine::Quantization;
pub use filter::{BBox, Filter, FilterStats, Returns, parse_classes};
pub use header::{Bounds3, FileInfo};
pub use reader::{LidarReader, ReadOptions};

/// One lidar point as read: integer coordinates in the reader's common system, the global input
/// index, and the attributes the filters use.
///
/// 24 bytes, no padding (`bytemuck::Pod`), so chunks can be written to disk as they are.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LidarPoint {
    /// Global input index: files in the order given, then points in file order, from 0.
    pub index: u64,
    /// Integer x (real x = `offset[0] + scale[0] × x`, see [`Quantization`]).
    pub x: i32,
    /// Integer y.
    pub y: i32,
    /// Integer z.
    pub z: i32,
    /// ASPRS classification code (5 bits in point formats 0–5, 8 bits in 6–10).
    pub classification: u8,
    /// Return number (1-based; 0 in some malformed files).
    pub return_number: u8,
    /// Number of returns of the pulse.
    pub number_of_returns: u8,
    /// Classification flags: [`LidarPoint::SYNTHETIC`], [`LidarPoint::KEY_POINT`],
    /// [`LidarPoint::WITHHELD`], [`LidarPoint::OVERLAP`] (LAS 1.4 bit order for all formats).
    pub flags: u8,
}

impl LidarPoint {
    /// Flag: the point was created by a technique other than lidar collection.
    pub const SYNTHETIC: u8 = 1;
    /// Flag: model key-point.
    pub const KEY_POINT: u8 = 2;
    /// Flag: withheld (deleted); should not be used.
    pub const WITHHELD: u8 = 4;
    /// Flag: overlap point (LAS 1.4 formats 6–10 only).
    pub const OVERLAP: u8 = 8;
}
