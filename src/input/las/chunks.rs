//! The chunk index of a plain LAZ or LAS file: the extent of every LAZ chunk (or LAS block of
//! [`LAS_BLOCK`] points), found in one decoding pass on every core.
//!
//! A COPC file carries its own index ([`super::copc`]); any other LAZ file is a list of chunks
//! of (usually) 50,000 points in acquisition order, and a LAS file a run of records. Once the
//! boxes of those spans are known, a reader given an area ([`super::ReadOptions::chunks`])
//! decodes only the spans whose box meets it: a plan's task over one big file decodes its tile
//! and buffer, not the whole file. The boxes come from the points themselves (their integers
//! converted as every reader converts them), so a span whose box misses an area holds no point
//! inside it, and the points kept, with their indices, are exactly those of a full read.
//!
//! LAStools' `.lax` files are not read (an index of their own, built by `lasindex`): the boxes
//! are built by decoding, by `plan` or once per file by `sweeptin index --chunks`, which stores
//! them beside the file (`plan::chunks`).

use super::decode::{Fields, FileDecoder, spans};
use super::header::{Chunk, FileInfo, format_error};
use crate::error::Result;

/// Points per span of a LAS file in a chunk index.
pub const LAS_BLOCK: u64 = 50_000;

/// Spans decoded at once while building an index (their compressed bytes are held together).
const SPANS_AT_ONCE: usize = 256;

/// One span of a file and the box of its points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SpanBox {
    pub(crate) span: Chunk,
    /// `[xmin, ymin, xmax, ymax]` of the span's points, real-world; `[inf, inf, -inf, -inf]`
    /// for a span without points.
    pub(crate) rect: [f64; 4],
}

/// The boxes of every span of one plain LAZ/LAS file, in file order (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ChunkIndex {
    pub(crate) spans: Vec<SpanBox>,
}

impl ChunkIndex {
    /// Decodes every span of the file `info` describes (LAZ chunks on every core, rayon's
    /// global pool) and keeps the box of each.
    ///
    /// # Errors
    /// The decoder's errors ([`crate::Error::Format`] for corrupt data, [`crate::Error::Io`]).
    pub fn build(info: &FileInfo) -> Result<ChunkIndex> {
        let all = spans(info, LAS_BLOCK, None);
        let mut decoder = FileDecoder::open(info)?;
        let (quant, len) = (decoder.quant, decoder.record_len);
        let mut out = Vec::with_capacity(all.len());
        for part in all.chunks(SPANS_AT_ONCE) {
            let boxes = decoder.decode(part, true, Fields::Filter, |_, raw| {
                let mut b = [i32::MAX, i32::MAX, i32::MIN, i32::MIN];
                for rec in raw.chunks_exact(len) {
                    let x = i32::from_le_bytes([rec[0], rec[1], rec[2], rec[3]]);
                    let y = i32::from_le_bytes([rec[4], rec[5], rec[6], rec[7]]);
                    b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
                }
                Ok(b)
            })?;
            for (s, b) in part.iter().zip(boxes) {
                let rect = if s.points == 0 {
                    [
                        f64::INFINITY,
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                        f64::NEG_INFINITY,
                    ]
                } else {
                    [
                        quant.axis_to_world(0, b[0]),
                        quant.axis_to_world(1, b[1]),
                        quant.axis_to_world(0, b[2]),
                        quant.axis_to_world(1, b[3]),
                    ]
                };
                out.push(SpanBox { span: *s, rect });
            }
        }
        Ok(ChunkIndex { spans: out })
    }

    /// Number of spans.
    pub fn len(&self) -> usize {
        self.spans.len()
    }

    /// Whether the index has no span (a file without points).
    pub fn is_empty(&self) -> bool {
        self.spans.is_empty()
    }

    /// The boxes `[xmin, ymin, xmax, ymax]` of the spans with points.
    pub fn rects(&self) -> impl Iterator<Item = [f64; 4]> + '_ {
        self.spans
            .iter()
            .filter(|s| s.span.points > 0)
            .map(|s| s.rect)
    }

    /// Every span in file order: the index of its first point, its points, and the box
    /// `[xmin, ymin, xmax, ymax]` of its points (none without points).
    pub fn span_boxes(&self) -> impl Iterator<Item = (u64, u64, Option<[f64; 4]>)> + '_ {
        self.spans.iter().map(|s| {
            (
                s.span.first,
                s.span.points,
                (s.span.points > 0).then_some(s.rect),
            )
        })
    }

    /// The box `[xmin, ymin, xmax, ymax]` and number of points of every span with points.
    pub fn boxes(&self) -> impl Iterator<Item = ([f64; 4], u64)> + '_ {
        self.spans
            .iter()
            .filter(|s| s.span.points > 0)
            .map(|s| (s.rect, s.span.points))
    }

    /// Checks that the index describes the spans of the file `info` (same chunks, or the same
    /// blocks of [`LAS_BLOCK`] records): an index of another file, or of this one before it was
    /// rewritten, is refused.
    ///
    /// # Errors
    /// [`crate::Error::Format`] naming the file.
    pub fn check(&self, info: &FileInfo) -> Result<()> {
        let want = spans(info, LAS_BLOCK, None);
        let same = want.len() == self.spans.len()
            && want.iter().zip(&self.spans).all(|(w, s)| *w == s.span)
            && self.spans.iter().all(|s| {
                s.span.points == 0
                    || (s.rect.iter().all(|v| v.is_finite())
                        && s.rect[0] <= s.rect[2]
                        && s.rect[1] <= s.rect[3])
            });
        if same {
            return Ok(());
        }
        Err(format_error(
            &info.path,
            format!(
                "its chunk index ({} spans) does not match the file ({} spans): the file \
                 changed since the index was made; make the plan (or the index) again",
                self.spans.len(),
                want.len()
            ),
        ))
    }

    /// A copy in which the spans `keep` does not mark (by position) have a box that no area
    /// meets: a reader given this index and an area decodes only the marked spans that meet it
    /// (a plan's band, [`crate::tiles::band`], decodes the chunks it needs this way).
    pub(crate) fn only(&self, keep: &[bool]) -> ChunkIndex {
        let far = [f64::MAX; 4];
        let spans = self
            .spans
            .iter()
            .enumerate()
            .map(|(i, s)| SpanBox {
                span: s.span,
                rect: if keep.get(i) == Some(&true) {
                    s.rect
                } else {
                    far
                },
            })
            .collect();
        ChunkIndex { spans }
    }

    /// The spans whose box `keep` keeps.
    pub(crate) fn spans_kept(&self, keep: &dyn Fn([f64; 4]) -> bool) -> Vec<Chunk> {
        self.spans
            .iter()
            .filter(|s| s.span.points > 0 && keep(s.rect))
            .map(|s| s.span)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::las::header::inspect;
    use std::path::Path;

    /// Every point of the file lies in the box of its span, and some box is smaller than the
    /// file's.
    #[test]
    fn every_point_lies_in_its_spans_box() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lidar/lidR_Topography.laz");
        let info = inspect(&path).unwrap();
        let ix = ChunkIndex::build(&info).unwrap();
        ix.check(&info).unwrap();
        assert!(ix.len() > 1, "{} spans", ix.len());
        let mut r = crate::input::las::LidarReader::open(&[&path], &Default::default()).unwrap();
        let pts = r.read_all().unwrap();
        for p in &pts {
            let s = ix
                .spans
                .iter()
                .find(|s| (s.span.first..s.span.first + s.span.points).contains(&p.index))
                .unwrap();
            let b = s.rect;
            assert!(p.x >= b[0] && p.x <= b[2] && p.y >= b[1] && p.y <= b[3]);
        }
    }
}
