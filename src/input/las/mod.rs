//! LAS/LAZ/COPC input: header facts, filters, and a chunked reader over one or more files.
//!
//! [`LidarReader`] reads one or more LAS/LAZ files (COPC included, and the files of a `.vpc`
//! virtual point cloud, see [`vpc`]) as **one point set** (adjacent tiles), in chunks of bounded
//! size, keeping only the points a [`Filter`] accepts. Each [`LidarPoint`] carries its
//! **real-world coordinates** (the doubles the outputs get, see [`world`]: each file's integers
//! are converted with the file's own scale and offset, so files with any scales and offsets
//! combine) and its **global input index**: files in the order given, points in file order,
//! counting every point of every file (filtered and skipped points leave gaps).
//!
//! ```no_run
//! use sweeptin::input::las::{Filter, LidarReader};
//!
//! let filter = Filter { classes: Some(vec![2]), ..Filter::default() };
//! let mut reader = LidarReader::open(&["a.laz", "b.copc.laz"], &filter)?;
//! let mut chunk = Vec::new();
//! while reader.read_chunk(&mut chunk, 1 << 20)? > 0 {
//!     for p in &chunk {
//!         let (x, y, z) = (p.x, p.y, p.z);
//!         # let _ = (x, y, z);
//!     }
//!     chunk.clear();
//! }
//! println!("{:?}, CRS {:?}", reader.stats(), reader.crs().and_then(|c| c.definition()));
//! # Ok::<(), sweeptin::Error>(())
//! ```
//!
//! # Reading only an area
//!
//! With a box (`Filter::bbox`, or the area of [`LidarReader::open_area`], which the exact-tiles
//! engine can use for a tile's buffered extent), files whose header extent misses the box are
//! never decoded, a COPC file decodes only the octree nodes that meet it ([`copc`]), and a plain
//! LAZ/LAS file given with its [`ChunkIndex`] ([`ReadOptions::chunks`]) only the chunks whose
//! box meets it: the points kept, and their indices, are exactly those of a full read, only
//! faster.
//!
//! # Damaged files
//!
//! Every file's header, VLRs, LAZ chunk table and COPC hierarchy are checked against the file's
//! length before any decoder runs ([`FileInfo::read`]); empty, truncated, corrupt and non-LAS
//! files give an [`crate::Error::Format`] naming the file, never a panic. Files that declare a
//! CRS must declare the same one.

mod ahead;
pub mod chunks;
pub mod copc;
pub(crate) mod decode;
pub mod extra;
pub mod filter;
pub mod header;
mod laz_check;
mod reader;
pub mod stats;
pub mod vlrs;
pub mod vpc;
pub mod world;

pub use crate::crs::{Crs, HorizontalKind};
pub use chunks::ChunkIndex;
pub use copc::CopcInfo;
pub use filter::{BBox, ClassesFrom, Filter, FilterStats, PointClasses, Returns, parse_classes};
pub use header::{Bounds3, FileInfo};
pub use reader::{LidarReader, ReadOptions};
pub use stats::{PointStats, scan};
pub use vlrs::VlrInfo;
pub use world::Quantization;

/// One lidar point as read: real-world coordinates, the global input index, and the attributes
/// the filters use.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LidarPoint {
    /// Global input index: files in the order given, then points in file order, from 0.
    pub index: u64,
    /// Real-world x (the file's `offset + scale × X`, rounded once: see [`world`]).
    pub x: f64,
    /// Real-world y.
    pub y: f64,
    /// Real-world z.
    pub z: f64,
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
