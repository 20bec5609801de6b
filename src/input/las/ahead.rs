//! The file being read: its spans decoded ahead on rayon's pool (the reader waits for the oldest
//! and hands it out), and what turns a span's raw records into points (checked, decoded, filtered).

use super::LidarPoint;
use super::decode::{Fields, FileDecoder, Spare};
use super::filter::{CompiledFilter, FilterStats, Verdict};
use super::header::{Bounds3, Chunk, FileInfo, format_error};
use super::reader::margin;
use super::world::{HEADER_SLACK, Quantization};
use crate::error::{Error, Result};
use std::collections::{HashMap, VecDeque};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::Arc;

/// The file being read: its decoder and the spans left to decode.
pub(super) struct Current {
    pub(super) decoder: FileDecoder,
    pub(super) spans: Vec<Chunk>,
    /// The first span not yet decoded (or, parallel, not yet sent to decode).
    pub(super) next: usize,
    pub(super) first_index: u64,
    /// The attribute z comes from, placed in this file's records.
    pub(super) z_from: Option<super::extra::ExtraDim>,
    pub(super) check: Arc<PointCheck>,
    /// Spans decoding on rayon's pool, oldest first, and their points.
    pub(super) in_flight: VecDeque<InFlight>,
    pub(super) flying: u64,
}

/// The most spans decoding at once while the reader hands out the one before.
const MAX_IN_FLIGHT: usize = 64;

/// What a span decodes to: the points the filter keeps, and the tally of its verdicts.
pub(super) type SpanPoints = (Vec<LidarPoint>, FilterStats);

/// A span's result (or the error that stopped it) and its byte buffer.
pub(super) type Decoded = (Result<Vec<SpanPoints>>, Vec<Vec<u8>>);

/// A span sent to decode on rayon's pool.
pub(super) struct InFlight {
    pub(super) rx: crossbeam_channel::Receiver<Decoded>,
    pub(super) points: u64,
}

impl InFlight {
    /// Waits for the span's result. On a thread of rayon's pool the wait runs other jobs of the
    /// pool (the span's among them) rather than block the thread.
    pub(super) fn wait(&self) -> Decoded {
        let lost = || -> Decoded {
            (
                Err(Error::Internal("a decoding job was lost".into())),
                vec![],
            )
        };
        if rayon::current_thread_index().is_none() {
            return self.rx.recv().unwrap_or_else(|_| lost());
        }
        loop {
            match self.rx.try_recv() {
                Ok(d) => return d,
                Err(crossbeam_channel::TryRecvError::Disconnected) => return lost(),
                Err(crossbeam_channel::TryRecvError::Empty) => {
                    if rayon::yield_now() != Some(rayon::Yield::Executed) {
                        std::thread::yield_now();
                    }
                }
            }
        }
    }
}

/// What turns one span's raw records into points: checked, decoded, filtered.
#[derive(Clone)]
pub(super) struct SpanJob {
    pub(super) filter: Arc<CompiledFilter>,
    pub(super) check: Arc<PointCheck>,
    pub(super) spare: Arc<Spare<LidarPoint>>,
    pub(super) quant: Quantization,
    pub(super) len: usize,
    pub(super) ext: bool,
    pub(super) base: u64,
    /// The attribute z comes from (`Filter::z_from`), placed in this file's records.
    pub(super) z_from: Option<super::extra::ExtraDim>,
}

impl SpanJob {
    /// The fields to decompress: the attribute z comes from too.
    pub(super) fn fields(&self) -> Fields {
        if self.z_from.is_some() {
            Fields::All
        } else {
            Fields::Filter
        }
    }

    pub(super) fn run(&self, span: &Chunk, raw: &[u8]) -> Result<SpanPoints> {
        let mut kept = self.spare.take();
        kept.clear();
        kept.reserve(span.points as usize);
        let mut stats = FilterStats::default();
        let node = self.check.node(span);
        // `--ground`: the classes of the span's points, by global index, replace their own.
        let mut classes = Vec::new();
        if let Some(from) = &self.filter.classes_from {
            classes.resize(raw.len() / self.len, 0);
            from.0.read_classes(self.base + span.first, &mut classes)?;
        }
        for (i, rec) in raw.chunks_exact(self.len).enumerate() {
            self.check
                .test(rec, self.ext, span, node, span.first + i as u64)?;
            let mut p = decode(
                rec,
                self.ext,
                self.base + span.first + i as u64,
                &self.quant,
            );
            if let Some(&c) = classes.get(i) {
                p.classification = c;
            }
            if let Some(d) = &self.z_from {
                match d.value(rec).filter(|z| z.is_finite()) {
                    Some(z) => p.z = z,
                    None => {
                        stats.read += 1;
                        stats.no_value += 1;
                        continue;
                    }
                }
            }
            let v = self.filter.test(&p);
            stats.count(v);
            if v == Verdict::Keep {
                kept.push(p);
            }
        }
        Ok((kept, stats))
    }
}

impl Current {
    /// The end of the batch that starts at `next`, read in the call: the fewest spans that hold
    /// `batch` points (or the rest).
    pub(super) fn batch_end(&self, batch: u64) -> usize {
        let (mut end, mut points) = (self.next, 0u64);
        while end < self.spans.len() && points < batch {
            points += self.spans[end].points;
            end += 1;
        }
        end
    }

    /// Reads the bytes of spans and sends each to decode on rayon's pool, a job of its own,
    /// until at least `batch` points and two spans per thread are under way, but no more than
    /// `cap` points (the reader's memory: it does not grow with the cores), or one span. A
    /// span whose bytes cannot be read is queued as its error, to be met in span order. (A job
    /// decoding several spans with a parallel iterator would wait for a stolen span while its
    /// thread runs another job, and hold up the reader, which waits for the oldest.)
    pub(super) fn submit(&mut self, batch: u64, cap: u64, job: &SpanJob) {
        let spans_wanted = 2 * rayon::current_num_threads();
        while self.next < self.spans.len() && self.in_flight.len() < MAX_IN_FLIGHT {
            let span = self.spans[self.next];
            let wanted = self.in_flight.len() < spans_wanted || self.flying < batch;
            let room = self.in_flight.is_empty() || self.flying + span.points <= cap;
            if !(wanted && room) {
                break;
            }
            self.next += 1;
            self.flying += span.points;
            let (tx, rx) = crossbeam_channel::bounded::<Decoded>(1);
            self.in_flight.push_back(InFlight {
                rx,
                points: span.points,
            });
            let mut bytes = match self.decoder.read(&[span]) {
                Ok(b) => b,
                Err(e) => {
                    let _ = tx.send((Err(e), Vec::new()));
                    continue;
                }
            };
            let (decoder, job) = (self.decoder.spans(), job.clone());
            rayon::spawn(move || {
                let run = || {
                    decoder.decode(&[span], &mut bytes, false, job.fields(), |s, raw| {
                        job.run(s, raw)
                    })
                };
                let parts = catch_unwind(AssertUnwindSafe(run))
                    .unwrap_or_else(|p| Err(Error::panicked("decoding", &*p)));
                // The reader may have stopped waiting (an earlier error): nothing to do then.
                let _ = tx.send((parts, bytes));
            });
        }
    }
}

/// What a decoded record can be checked for: inside the header's bounds (one scale step of
/// slack, in the file's own integers), inside its COPC node's square (with the margin the index
/// is read with: a point outside it is one a box read may skip, as when a key was moved), and a
/// return number no larger than the number of returns (when that is known, > 0). A record that
/// fails is corrupt data that happened to decode.
pub(super) struct PointCheck {
    path: PathBuf,
    compressed: bool,
    /// `None` when the header has no usable bounds (all zero, or min above max).
    bounds: Option<[[i64; 2]; 3]>,
    header: Bounds3,
    scale: [f64; 3],
    offset: [f64; 3],
    /// The COPC node of each LAZ chunk (by its byte offset): its key and its square in the
    /// file's integers (x and y ranges), rounded out by the index's margin.
    nodes: HashMap<u64, NodeSquare>,
}

/// A COPC node's key and its square in its file's integers (`[[x0, x1], [y0, y1]]`).
#[derive(Clone, Copy)]
pub(super) struct NodeSquare {
    key: [i32; 4],
    square: [[i64; 2]; 2],
}

impl PointCheck {
    pub(super) fn of(info: &FileInfo) -> PointCheck {
        let b = &info.bounds;
        let usable = b.usable() && info.scale.iter().all(|s| *s > 0.0);
        let bounds = usable.then(|| {
            std::array::from_fn(|k| {
                let (s, o) = (info.scale[k], info.offset[k]);
                // Saturating: damaged headers hold any doubles.
                [
                    (((b.min[k] - o) / s).floor() as i64).saturating_sub(HEADER_SLACK),
                    (((b.max[k] - o) / s).ceil() as i64).saturating_add(HEADER_SLACK),
                ]
            })
        });
        let step = info.scale[0].max(info.scale[1]);
        let nodes = match &info.layout.nodes {
            Some(nodes) if info.scale.iter().all(|s| *s > 0.0) => nodes
                .iter()
                .map(|n| {
                    let m = margin(n.rect, step);
                    let (s, o) = (info.scale, info.offset);
                    // Saturating: a damaged info VLR holds any doubles.
                    let square = std::array::from_fn(|k| {
                        [
                            ((n.rect[k] - m - o[k]) / s[k]).floor() as i64,
                            ((n.rect[k + 2] + m - o[k]) / s[k]).ceil() as i64,
                        ]
                    });
                    let at = info.layout.chunks[n.chunk].offset;
                    (at, NodeSquare { key: n.key, square })
                })
                .collect(),
            _ => HashMap::new(),
        };
        PointCheck {
            path: info.path.clone(),
            compressed: info.compressed,
            bounds,
            header: info.bounds,
            scale: info.scale,
            offset: info.offset,
            nodes,
        }
    }

    /// The COPC node whose points `span` holds (`None` for files without an index).
    pub(super) fn node(&self, span: &Chunk) -> Option<NodeSquare> {
        self.nodes.get(&span.offset).copied()
    }

    /// Checks record `rec` (point `n` of the file, in `span`, of COPC node `node`).
    #[inline]
    fn test(
        &self,
        rec: &[u8],
        extended: bool,
        span: &Chunk,
        node: Option<NodeSquare>,
        n: u64,
    ) -> Result<()> {
        let le = |o: usize| i32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
        let xyz = [le(0), le(4), le(8)];
        let in_box = self.bounds.is_none_or(|b| {
            (0..3).all(|k| i64::from(xyz[k]) >= b[k][0] && i64::from(xyz[k]) <= b[k][1])
        });
        if let Some(node) = node.filter(|_| in_box) {
            let q = node.square;
            if !(0..2).all(|k| i64::from(xyz[k]) >= q[k][0] && i64::from(xyz[k]) <= q[k][1]) {
                return Err(self.outside_node(xyz, node, span, n));
            }
        }
        let (r, nr) = if extended {
            (rec[14] & 0x0f, rec[14] >> 4)
        } else {
            (rec[14] & 0x07, (rec[14] >> 3) & 0x07)
        };
        if in_box && (nr == 0 || r <= nr) {
            return Ok(());
        }
        Err(self.corrupt(xyz, r, nr, span, n, !in_box))
    }

    #[cold]
    fn outside_node(&self, xyz: [i32; 3], node: NodeSquare, span: &Chunk, n: u64) -> Error {
        let w = |k: usize, v: i64| self.offset[k] + self.scale[k] * v as f64;
        let (k, q) = (node.key, node.square);
        format_error(
            &self.path,
            format!(
                "invalid COPC file: point {n} (the LAZ chunk at byte {}) at ({}, {}) lies outside \
                 the square of its octree node {}-{}-{}-{} (x {} .. {}, y {} .. {}): the \
                 file is damaged (a moved key in the hierarchy, or corrupt point data), and a \
                 box read through its index would skip points; write it again from its source",
                span.offset,
                w(0, xyz[0].into()),
                w(1, xyz[1].into()),
                k[0],
                k[1],
                k[2],
                k[3],
                w(0, q[0][0]),
                w(0, q[0][1]),
                w(1, q[1][0]),
                w(1, q[1][1]),
            ),
        )
    }

    #[cold]
    fn corrupt(&self, xyz: [i32; 3], r: u8, nr: u8, span: &Chunk, n: u64, out: bool) -> Error {
        let at = if self.compressed {
            format!("the LAZ chunk at byte {}, point {n}", span.offset)
        } else {
            format!("point {n}")
        };
        let what = if out {
            let w = |k: usize| self.offset[k] + self.scale[k] * f64::from(xyz[k]);
            let h = &self.header;
            format!(
                "its position ({}, {}, {}) is outside the header's bounds x {} .. {}, y {} .. {}, \
                 z {} .. {} (the data is damaged, or the header's bounds are wrong)",
                w(0),
                w(1),
                w(2),
                h.min[0],
                h.max[0],
                h.min[1],
                h.max[1],
                h.min[2],
                h.max[2]
            )
        } else {
            format!("return number {r} of {nr} returns")
        };
        format_error(&self.path, format!("corrupt point data ({at}): {what}"))
    }
}

/// Decodes the fields a [`LidarPoint`] carries from one point record (formats 0–10; the record
/// is at least 20 bytes, 30 for formats 6–10).
#[inline]
pub(crate) fn decode(rec: &[u8], extended: bool, index: u64, q: &Quantization) -> LidarPoint {
    let le = |o: usize| i32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
    let (b14, b15) = (rec[14], rec[15]);
    let (classification, return_number, number_of_returns, flags) = if extended {
        (rec[16], b14 & 0x0f, b14 >> 4, b15 & 0x0f)
    } else {
        (b15 & 0x1f, b14 & 0x07, (b14 >> 3) & 0x07, (b15 >> 5) & 0x07)
    };
    let [x, y, z] = q.to_world([le(0), le(4), le(8)]);
    LidarPoint {
        index,
        x,
        y,
        z,
        classification,
        return_number,
        number_of_returns,
        flags,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_legacy_and_extended() {
        let q = Quantization::new([0.01; 3], [0.0; 3]);
        let mut rec = [0u8; 30];
        rec[0..4].copy_from_slice(&(-5i32).to_le_bytes());
        rec[4..8].copy_from_slice(&7i32.to_le_bytes());
        rec[8..12].copy_from_slice(&123456i32.to_le_bytes());
        rec[14] = 2 | (3 << 3); // legacy: return 2 of 3
        rec[15] = 9 | 0x80; // class 9, withheld
        let p = decode(&rec, false, 42, &q);
        assert_eq!((p.index, p.x, p.y, p.z), (42, -0.05, 0.07, 1234.56));
        assert_eq!(
            (p.classification, p.return_number, p.number_of_returns),
            (9, 2, 3)
        );
        assert_eq!(p.flags, LidarPoint::WITHHELD);
        rec[14] = 5 | (7 << 4); // extended: return 5 of 7
        rec[15] = 0x04 | 0x08 | 0x30; // withheld + overlap, scanner channel bits
        rec[16] = 66;
        let p = decode(&rec, true, 0, &q);
        assert_eq!(
            (p.classification, p.return_number, p.number_of_returns),
            (66, 5, 7)
        );
        assert_eq!(p.flags, LidarPoint::WITHHELD | LidarPoint::OVERLAP);
    }
}
