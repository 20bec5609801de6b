//! What the points of a file say (`sweeptin info --classes`): counts by classification, return
//! number and number of returns, flags, coordinate, intensity and GPS-time ranges, and the area
//! the points cover, computed on every core at the decoder's speed.

use super::ahead::decode;
use super::decode::{Fields, FileDecoder, spans};
use super::filter::{CompiledFilter, Filter, FilterStats, Verdict};
use super::header::FileInfo;
use crate::error::Result;
use serde::Serialize;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// Statistics of the points of one file that pass a filter.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PointStats {
    /// Points counted (those that pass the filter).
    pub points: u64,
    /// Points per classification code (index = code).
    #[serde(serialize_with = "nonzero")]
    pub classes: Vec<u64>,
    /// Points per return number (index = return number, 0–15).
    #[serde(serialize_with = "nonzero")]
    pub by_return: Vec<u64>,
    /// Points per number of returns of their pulse (index = number of returns, 0–15).
    #[serde(serialize_with = "nonzero")]
    pub by_returns: Vec<u64>,
    /// First returns (return number 1).
    pub first: u64,
    /// Last returns (return number = number of returns, single returns included).
    pub last: u64,
    /// Single returns (one return in the pulse).
    pub single: u64,
    /// Points flagged synthetic, key-point, withheld, overlap.
    pub flags: [u64; 4],
    /// Smallest x, y, z.
    pub min: [f64; 3],
    /// Largest x, y, z.
    pub max: [f64; 3],
    /// Intensity range.
    pub intensity: [u16; 2],
    /// GPS time range (point formats with a time).
    pub gps_time: Option<[f64; 2]>,
    /// Side of the square cells of the coverage grid (2 units, coarser for huge extents).
    pub cell: f64,
    /// Area of the cells that hold at least one point.
    pub covered_area: f64,
    /// What the filters kept and dropped.
    pub filter: FilterStats,
}

fn nonzero<S: serde::Serializer>(v: &[u64], s: S) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut m = s.serialize_map(None)?;
    for (k, n) in v.iter().enumerate().filter(|(_, n)| **n > 0) {
        m.serialize_entry(&k.to_string(), n)?;
    }
    m.end()
}

/// Cells of the coverage grid at most (a 2 MiB bit set).
const MAX_CELLS: f64 = (1u64 << 24) as f64;

impl PointStats {
    fn empty() -> PointStats {
        PointStats {
            classes: vec![0; 256],
            by_return: vec![0; 16],
            by_returns: vec![0; 16],
            min: [f64::INFINITY; 3],
            max: [f64::NEG_INFINITY; 3],
            intensity: [u16::MAX, 0],
            ..PointStats::default()
        }
    }

    /// Adds the counts of `o` (another part of the file, or another file: the covered areas
    /// add up) and widens the ranges.
    pub fn merge(&mut self, o: &PointStats) {
        let (mine, theirs) = (self.points > 0, o.points > 0);
        self.points += o.points;
        for (a, b) in [
            (&mut self.classes, &o.classes),
            (&mut self.by_return, &o.by_return),
            (&mut self.by_returns, &o.by_returns),
        ] {
            a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        }
        self.first += o.first;
        self.last += o.last;
        self.single += o.single;
        for k in 0..4 {
            self.flags[k] += o.flags[k];
        }
        if !mine {
            (self.min, self.max, self.intensity) = (o.min, o.max, o.intensity);
        } else if theirs {
            for a in 0..3 {
                self.min[a] = self.min[a].min(o.min[a]);
                self.max[a] = self.max[a].max(o.max[a]);
            }
            self.intensity = [
                self.intensity[0].min(o.intensity[0]),
                self.intensity[1].max(o.intensity[1]),
            ];
        }
        self.gps_time = match (self.gps_time, o.gps_time) {
            (Some(a), Some(b)) => Some([a[0].min(b[0]), a[1].max(b[1])]),
            (a, b) => a.or(b),
        };
        self.covered_area += o.covered_area;
        self.cell = self.cell.max(o.cell);
        self.filter += o.filter;
    }
}

/// Reads every point of `path` that passes `filter` (in parallel when `parallel`) and counts.
///
/// # Errors
/// The reader's errors (see [`FileInfo::read`] and [`super::LidarReader::read_chunk`]).
pub fn scan(path: &Path, filter: &Filter, parallel: bool) -> Result<PointStats> {
    let info = FileInfo::read(path)?;
    let compiled = CompiledFilter::new(filter, None);
    let mut total = PointStats::empty();
    // The coverage grid over the header extent.
    let r = info.rect();
    let (w, h) = ((r[2] - r[0]).max(0.0), (r[3] - r[1]).max(0.0));
    let mut cell = 2.0f64;
    while (w / cell + 1.0) * (h / cell + 1.0) > MAX_CELLS {
        cell *= 2.0;
    }
    let (nx, ny) = ((w / cell) as usize + 1, (h / cell) as usize + 1);
    let bits: Vec<AtomicU64> = (0..(nx * ny).div_ceil(64))
        .map(|_| AtomicU64::new(0))
        .collect();
    if info.point_count > 0 {
        let mut d = FileDecoder::open(&info)?;
        let step = info.scale[0].max(info.scale[1]);
        let keep = |n: [f64; 4]| !compiled.misses(n, step);
        let all = if info.known_rect().is_some_and(|r| compiled.misses(r, step)) {
            Vec::new()
        } else {
            spans(&info, 1 << 16, Some(&keep))
        };
        let skipped = info.point_count - all.iter().map(|s| s.points).sum::<u64>();
        total.filter.skipped = skipped;
        let (q, len, ext) = (d.quant, d.record_len, d.extended);
        let gps_at = match info.point_format {
            0 | 2 => None,
            1 | 3 | 4 | 5 => Some(20),
            _ => Some(22),
        };
        // Bounded batches keep the decoded records of one batch in memory at most.
        for batch in all.chunks(64) {
            let parts = d.decode(batch, parallel, Fields::Stats, |span, raw| {
                let mut s = PointStats::empty();
                for (i, rec) in raw.chunks_exact(len).enumerate() {
                    let p = decode(rec, ext, span.first + i as u64, &q);
                    let v = compiled.test(&p);
                    s.filter.count(v);
                    if v != Verdict::Keep {
                        continue;
                    }
                    s.points += 1;
                    s.classes[usize::from(p.classification)] += 1;
                    s.by_return[usize::from(p.return_number & 15)] += 1;
                    s.by_returns[usize::from(p.number_of_returns & 15)] += 1;
                    s.first += u64::from(p.return_number == 1);
                    s.last += u64::from(p.return_number == p.number_of_returns);
                    s.single += u64::from(p.number_of_returns == 1);
                    for k in 0..4 {
                        s.flags[k] += u64::from(p.flags >> k & 1);
                    }
                    for (a, v) in [p.x, p.y, p.z].into_iter().enumerate() {
                        s.min[a] = s.min[a].min(v);
                        s.max[a] = s.max[a].max(v);
                    }
                    let it = u16::from_le_bytes([rec[12], rec[13]]);
                    s.intensity = [s.intensity[0].min(it), s.intensity[1].max(it)];
                    if let Some(o) = gps_at {
                        let t = f64::from_le_bytes(rec[o..o + 8].try_into().unwrap_or_default());
                        s.gps_time = Some(match s.gps_time {
                            Some([a, b]) => [a.min(t), b.max(t)],
                            None => [t, t],
                        });
                    }
                    let cx = ((p.x - r[0]) / cell).clamp(0.0, (nx - 1) as f64) as usize;
                    let cy = ((p.y - r[1]) / cell).clamp(0.0, (ny - 1) as f64) as usize;
                    let k = cy * nx + cx;
                    bits[k / 64].fetch_or(1 << (k % 64), Ordering::Relaxed);
                }
                Ok(s)
            })?;
            for p in &parts {
                total.merge(p);
            }
        }
    }
    let cells: u64 = bits
        .iter()
        .map(|b| u64::from(b.load(Ordering::Relaxed).count_ones()))
        .sum();
    total.cell = cell;
    total.covered_area = cells as f64 * cell * cell;
    debug_assert!(total.points > 0 || total.min[0].is_infinite());
    if total.points == 0 {
        total.min = [0.0; 3];
        total.max = [0.0; 3];
        total.intensity = [0, 0];
    }
    Ok(total)
}
