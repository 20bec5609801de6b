//! Tagged records: a point of the block index with a tag kept beside it (the ground filter's
//! global input index and class), and reading the tags back in the points' order.

use super::{BlockIndex, IndexRecord, Packing, Store};
use crate::error::{Error, Result};
use crate::tiles::grid::{BlockRect, TileGrid};
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::Path;

/// A point with its block key and a tag the index keeps beside it (read back with
/// [`BlockIndex::read_tags`]): the ground filter's global input index and class. Padded to 64
/// bytes: the sort's sliding maps (`sort::mmap`) need a record size that divides their window.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct TaggedRecord {
    pub key: u64,
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub tag: u64,
    pad: [u64; 3],
}

impl TaggedRecord {
    /// Point `p` of block `(bx, by)` with `tag`.
    pub fn new((bx, by): (i64, i64), p: [f64; 3], tag: u64) -> TaggedRecord {
        TaggedRecord {
            key: TileGrid::key(bx, by),
            x: p[0],
            y: p[1],
            z: p[2],
            tag,
            pad: [0; 3],
        }
    }
}

impl IndexRecord for TaggedRecord {
    type Stored = [f64; 3];
    const TAGGED: bool = true;
    #[inline]
    fn pack(_: Option<&Packing>, block: (i64, i64), p: [f64; 3]) -> Result<Self> {
        Ok(TaggedRecord::new(block, p, 0))
    }
    #[inline]
    fn unpack(&self, _: Option<&Packing>) -> (u64, [f64; 3]) {
        (self.key, [self.x, self.y, self.z])
    }
    #[inline]
    fn stored(&self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
    #[inline]
    fn tag(&self) -> u64 {
        self.tag
    }
}

/// The tags of a tagged index, in memory or in their own anonymous file (8 bytes a point).
#[derive(Debug)]
pub(super) enum Tags {
    Memory(Vec<u64>),
    File(File),
}

impl BlockIndex {
    /// Appends the tags of the points of the blocks of `r` to `out`, in the order
    /// [`BlockIndex::read`] gives the points.
    ///
    /// # Errors
    /// [`Error::Io`] if the tags' file cannot be read; [`Error::Internal`] for an index built
    /// from untagged records.
    pub fn read_tags(&self, r: &BlockRect, out: &mut Vec<u64>) -> Result<()> {
        let r = r.intersect(&self.occupied);
        for by in r.y0..r.y1 {
            let k = self.row_range(by, r.x0, r.x1);
            let (a, b) = (self.starts[k.start] as usize, self.starts[k.end] as usize);
            match &self.tags {
                None => return Err(Error::Internal("the block index has no tags".into())),
                Some(Tags::Memory(v)) => out.extend_from_slice(&v[a..b]),
                Some(Tags::File(f)) => {
                    let old = out.len();
                    out.resize(old + (b - a), 0);
                    let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out[old..]);
                    let dir = match &self.store {
                        Store::File { dir, .. } => dir.as_path(),
                        Store::Memory(_) => Path::new("."),
                    };
                    f.read_exact_at(bytes, (a * 8) as u64)
                        .map_err(|e| Error::io(dir, e))?;
                }
            }
        }
        Ok(())
    }
}
