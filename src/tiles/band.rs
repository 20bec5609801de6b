//! The data's convex hull and its *band*, which a plan computes once and gives to its tasks
//! ([`HullBand`]).
//!
//! A task reading only its area cannot tell its own hull's edges from the data's: the long
//! slivers along the data's border have vertices up to the hull's corners, far outside its area,
//! and such tasks ran again with wider buffers. Given the corners of the data's exact hull and
//! every point within `width` of it (the points not strictly inside the polygon `P` of the hull's
//! edges moved `width` inwards), a task adds the band's points outside its area as points read
//! and knows that whatever it did not read lies inside `P` ([`super::index::Scope::inner`]).
//!
//! [`HullBand::compute`] decodes only what it needs, through the files' chunk indexes: first
//! the chunks whose boxes may hold the data's extreme point in one of 64 directions (the seed),
//! then rounds of the chunks whose box is not strictly inside `P` of the hull found so far, until
//! none is left (a chunk strictly inside it holds no corner, the hull so far being inside the
//! data's), keeping the points of those rounds that are not strictly inside `P` moved a little
//! further in; last, the seed's chunks not strictly inside the final `P` again, for their band
//! points. The points kept are then those not strictly inside the final `P`. The
//! points are those a task reads (the job's filters), each position once with the duplicate
//! policy's height; "strictly inside" is decided by the exact predicates on `P`'s corners as
//! stored, so the tasks' claim holds exactly.

use super::hull::HullBuilder;
use super::index::inner_polygon;
use super::read::prefetched;
use crate::error::Result;
use crate::geom::predicates::{Orientation, orient};
use crate::input::las::{BBox, ChunkIndex, Crs, Filter, LidarPoint, LidarReader, ReadOptions};
use std::path::PathBuf;
use std::sync::Arc;

/// The band's width a plan uses, in the data's units: 2 m on ARSO (0.28 m point spacing) ran
/// every task once with a band of 83 thousand points (0.6 %); 1 m left one task running twice,
/// 5 m gave the same runs with 2.6 times the points (docs/BENCHMARKS.md).
pub const BAND_WIDTH: f64 = 2.0;

/// A band holding more than this share of the job's points (1/4) is not used: every task holds
/// the whole band (data narrower than a few band widths, or coordinates in degrees).
const MAX_BAND_SHARE: u64 = 4;

/// Nor one of more points than this (about 100 MB in every task), or than a sixteenth of a
/// task's memory holds at 24 bytes a point (each task holds the band, and sorts it with its own
/// points).
const MAX_BAND_POINTS: usize = 4_000_000;

/// The data's convex hull and the points near it (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct HullBand {
    pub(crate) width: f64,
    /// The hull's corners, counter-clockwise.
    pub(crate) hull: Vec<[f64; 2]>,
    /// `P`: the hull's edges moved `width` inwards (counter-clockwise, no repeated corner).
    pub(crate) inner: Vec<[f64; 2]>,
    /// Every point not strictly inside `P`, once per position, with the duplicate policy's
    /// height, by `x` then `y`.
    pub(crate) points: Vec<[f64; 3]>,
}

/// What [`HullBand::compute`] reads: the files (as a task gives them to its reader), the job's
/// filter, the files' chunk indexes, or the plan's point store (its cells in place of the
/// chunks, read instead of decoded: the same band), the duplicate policy, the declared CRS and
/// a memory budget.
pub(crate) struct BandSource<'a> {
    pub paths: &'a [PathBuf],
    pub filter: &'a Filter,
    pub chunks: &'a [(PathBuf, Arc<ChunkIndex>)],
    pub store: Option<&'a super::store::PointStore>,
    pub policy: crate::DuplicatePolicy,
    pub crs: Option<Crs>,
    pub mem: u64,
}

impl HullBand {
    /// The band's width.
    pub fn width(&self) -> f64 {
        self.width
    }

    /// The hull's corners `[x, y]`, counter-clockwise.
    pub fn hull(&self) -> &[[f64; 2]] {
        &self.hull
    }

    /// The band's points `[x, y, z]`.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// The band's parts as stored (no check but the polygons' sizes): `None` for corners that
    /// make no polygon.
    pub(crate) fn from_parts(
        width: f64,
        hull: Vec<[f64; 2]>,
        inner: Vec<[f64; 2]>,
        points: Vec<[f64; 3]>,
    ) -> Option<HullBand> {
        (hull.len() >= 3 && inner.len() >= 3).then_some(HullBand {
            width,
            hull,
            inner,
            points,
        })
    }

    /// The band of `width` of the points `src` reads, or `None` when it would not serve the
    /// tasks: the data has no hull with an inside (fewer than three corners, or narrower than
    /// twice `width`), or the band holds more than a quarter of the points (or four million,
    /// or a sixteenth of the tasks' memory `src.mem` at 24 bytes a point).
    ///
    /// # Errors
    /// The reader's errors.
    pub(crate) fn compute(src: &BandSource, width: f64) -> Result<Option<HullBand>> {
        let spans = Spans::of(src);
        if spans.rects.is_empty() {
            return Ok(None);
        }
        let n = spans.rects.len();
        let total = spans.points;
        let most = (total / MAX_BAND_SHARE).min(src.mem / 16 / 24);
        let cap = MAX_BAND_POINTS.min(usize::try_from(most).unwrap_or(usize::MAX));
        // The seed: the chunks that may hold the extreme point in some direction; then the
        // chunks not strictly inside `P` of the hull so far, whose points not strictly inside
        // `P` moved a little further in (`guard`, inside the final `P`) are kept.
        let seeded = seed(&spans.rects);
        let mut want = seeded.clone();
        let mut done = vec![false; n];
        let mut builder = HullBuilder::new(src.policy);
        let mut band: Vec<([f64; 3], u64)> = Vec::new();
        let mut guard: Option<Vec<[f64; 2]>> = None;
        let mut overflow = false;
        let (h, inner) = loop {
            let near = guard.as_ref().map(|g| near_edges(g, &spans.rects));
            let every: Vec<usize> = (0..guard.as_ref().map_or(0, Vec::len)).collect();
            spans.decode(src, &want, |p, s| {
                builder.add([p.x, p.y, p.z], p.index);
                if let (Some(g), Some(near)) = (&guard, &near)
                    && !(g.len() >= 3
                        && edges(near, s, &every).iter().all(|&e| left_of(g, e, [p.x, p.y])))
                {
                    if band.len() < cap {
                        band.push(([p.x, p.y, p.z], p.index));
                    } else {
                        overflow = true;
                    }
                }
            })?;
            for (d, w) in done.iter_mut().zip(&want) {
                *d |= *w;
            }
            let h: Vec<[f64; 2]> = builder.clone().finish().iter().map(|c| [c[0], c[1]]).collect();
            let inner = polygon(&h, width);
            want = (0..n)
                .map(|i| !done[i] && !box_inside(&inner, &spans.rects[i]))
                .collect();
            if !want.contains(&true) {
                break (h, inner);
            }
            let mag = h.iter().fold(0.0f64, |m, c| m.max(c[0].abs()).max(c[1].abs()));
            guard = Some(polygon(&h, width * (1.0 + 1e-3) + 1e-9 * mag));
        };
        if h.len() < 3 || inner.len() < 3 {
            return Ok(None);
        }
        // The band's points in the seed's chunks (decoded for the hull alone), or in every chunk
        // not strictly inside `P` when more were kept than a band may hold.
        if overflow {
            band.clear();
        }
        band.retain(|p| !(0..inner.len()).all(|e| left_of(&inner, e, [p.0[0], p.0[1]])));
        let want: Vec<bool> = (0..n)
            .map(|i| (overflow || seeded[i]) && !box_inside(&inner, &spans.rects[i]))
            .collect();
        let near = near_edges(&inner, &spans.rects);
        let every: Vec<usize> = (0..inner.len()).collect();
        spans.decode(src, &want, |p, s| {
            let list = edges(&near, s, &every);
            if !list.iter().all(|&e| left_of(&inner, e, [p.x, p.y])) && band.len() <= cap {
                band.push(([p.x, p.y, p.z], p.index));
            }
        })?;
        if band.len() > cap {
            return Ok(None);
        }
        super::hull::keep_preferred(&mut band, src.policy);
        Ok(HullBand::from_parts(
            width,
            h,
            inner,
            band.into_iter().map(|p| p.0).collect(),
        ))
    }
}

/// `h` (counter-clockwise) with its edges moved `d` inwards, without repeated corners.
fn polygon(h: &[[f64; 2]], d: f64) -> Vec<[f64; 2]> {
    if h.len() < 3 {
        return Vec::new();
    }
    let mut p = inner_polygon(h, d);
    p.dedup();
    while p.len() > 1 && p.first() == p.last() {
        p.pop();
    }
    if p.len() < 3 { Vec::new() } else { p }
}

/// The spans that may hold the extreme point of the data in one of 64 directions, judged from
/// their boxes (each side of a box holds a point of its span: before the filters, so this is
/// only where the rounds start).
fn seed(rects: &[[f64; 4]]) -> Vec<bool> {
    let mut want = vec![false; rects.len()];
    for k in 0..64 {
        let a = f64::from(k) * std::f64::consts::TAU / 64.0;
        let dot = |x: f64, y: f64| a.cos() * x + a.sin() * y;
        // At least this far in the direction (a point on each side), at most that far.
        let low = |r: &[f64; 4]| {
            [
                dot(r[0], r[1]).min(dot(r[0], r[3])),
                dot(r[2], r[1]).min(dot(r[2], r[3])),
                dot(r[0], r[1]).min(dot(r[2], r[1])),
                dot(r[0], r[3]).min(dot(r[2], r[3])),
            ]
            .into_iter()
            .fold(f64::NEG_INFINITY, f64::max)
        };
        let high = |r: &[f64; 4]| {
            dot(r[0], r[1]).max(dot(r[2], r[1])).max(dot(r[2], r[3])).max(dot(r[0], r[3]))
        };
        let best = rects.iter().map(low).fold(f64::NEG_INFINITY, f64::max);
        for (w, r) in want.iter_mut().zip(rects) {
            *w |= high(r) >= best;
        }
    }
    want
}

/// For each box of `rects`, the edges of the polygon `p` it is not strictly left of (the only
/// ones its points need testing against).
fn near_edges(p: &[[f64; 2]], rects: &[[f64; 4]]) -> Vec<Vec<usize>> {
    rects
        .iter()
        .map(|r| (0..p.len()).filter(|&e| !box_left_of(p, e, r)).collect())
        .collect()
}

/// The edges a point of span `s` is tested against: those `near` lists for its span, or `all`
/// when its span is not known.
fn edges<'a>(near: &'a [Vec<usize>], s: Option<usize>, all: &'a [usize]) -> &'a [usize] {
    s.map_or(all, |s| &near[s])
}

/// Is `q` strictly left of the edge `e` of the polygon `p` (exactly)?
fn left_of(p: &[[f64; 2]], e: usize, q: [f64; 2]) -> bool {
    orient(p[e], p[(e + 1) % p.len()], q) == Orientation::CounterClockwise
}

/// Is the closed box `r` strictly left of the edge `e` of `p` (its four corners)?
fn box_left_of(p: &[[f64; 2]], e: usize, r: &[f64; 4]) -> bool {
    [[r[0], r[1]], [r[2], r[1]], [r[2], r[3]], [r[0], r[3]]]
        .into_iter()
        .all(|q| left_of(p, e, q))
}

/// Is the closed box `r` strictly inside the convex polygon `p` (left of every edge)? Never for
/// a polygon of fewer than three corners.
fn box_inside(p: &[[f64; 2]], r: &[f64; 4]) -> bool {
    p.len() >= 3 && (0..p.len()).all(|e| box_left_of(p, e, r))
}

/// The spans with points of the files a band reads, with their boxes.
struct Spans {
    /// `(file, position among its index's spans, global index of its first point)`.
    at: Vec<(usize, usize, u64)>,
    rects: Vec<[f64; 4]>,
    /// The files' points.
    points: u64,
}

impl Spans {
    fn of(src: &BandSource) -> Spans {
        let mut s = Spans {
            at: Vec::new(),
            rects: Vec::new(),
            points: 0,
        };
        if let Some(st) = src.store {
            s.rects = st.rects().collect();
            s.points = st.points();
            return s;
        }
        for (k, path) in src.paths.iter().enumerate() {
            let Some((_, ix)) = src.chunks.iter().find(|(p, _)| p == path) else {
                continue;
            };
            for (i, sp) in ix.spans.iter().enumerate() {
                if sp.span.points > 0 {
                    s.at.push((k, i, s.points + sp.span.first));
                    s.rects.push(sp.rect);
                }
            }
            s.points += ix.spans.iter().map(|sp| sp.span.points).sum::<u64>();
        }
        s
    }

    /// Decodes the spans `want` marks (the job's filter applied) and hands `f` each point with
    /// its span's position in [`Spans::rects`] (`None` when the point is not in that span's box:
    /// never, unless the files' point counts and chunk tables disagree).
    fn decode(
        &self,
        src: &BandSource,
        want: &[bool],
        mut f: impl FnMut(&LidarPoint, Option<usize>),
    ) -> Result<()> {
        if !want.contains(&true) {
            return Ok(());
        }
        if let Some(st) = src.store {
            // A point's position in the store stands for its index: points at one position lie
            // in one cell, in input order.
            return st.read_cells(want, |[x, y, z], index, c| {
                let r = &self.rects[c];
                let inside = x >= r[0] && x <= r[2] && y >= r[1] && y <= r[3];
                let p = LidarPoint {
                    index,
                    x,
                    y,
                    z,
                    ..LidarPoint::default()
                };
                f(&p, inside.then_some(c));
            });
        }
        let chunks: Vec<(PathBuf, Arc<ChunkIndex>)> = src
            .paths
            .iter()
            .enumerate()
            .filter_map(|(k, path)| {
                let (_, ix) = src.chunks.iter().find(|(p, _)| p == path)?;
                let mut keep = vec![false; ix.spans.len()];
                for (a, _) in self.at.iter().zip(want).filter(|(a, w)| **w && a.0 == k) {
                    keep[a.1] = true;
                }
                Some((path.clone(), Arc::new(ix.only(&keep))))
            })
            .collect();
        let r = self.rects.iter().fold(
            [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY],
            |a, r| [a[0].min(r[0]), a[1].min(r[1]), a[2].max(r[2]), a[3].max(r[3])],
        );
        let options = ReadOptions {
            area: BBox::new(r[0], r[1], r[2], r[3]),
            chunks,
            crs: src.crs.clone(),
            ..ReadOptions::for_budget(src.mem)
        };
        // The wanted spans by their first point's global index.
        let mut firsts: Vec<(u64, usize)> = (0..self.at.len())
            .filter(|&i| want[i])
            .map(|i| (self.at[i].2, i))
            .collect();
        firsts.sort_unstable();
        let mut reader = LidarReader::open_with(src.paths, src.filter, options)?;
        prefetched(&mut reader, |buf, _| {
            for p in buf {
                let k = firsts.partition_point(|a| a.0 <= p.index);
                let s = firsts[k.saturating_sub(1)].1;
                let r = &self.rects[s];
                let inside = p.x >= r[0] && p.x <= r[2] && p.y >= r[1] && p.y <= r[3];
                f(p, inside.then_some(s));
            }
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_strictly_inside_a_square() {
        let sq = polygon(&[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]], 2.0);
        assert_eq!(sq.len(), 4, "{sq:?}");
        assert!(box_inside(&sq, &[3.0, 3.0, 7.0, 7.0]));
        // On P's edge is not strictly inside.
        assert!(!box_inside(&sq, &[2.0, 3.0, 7.0, 7.0]));
        assert!(!box_inside(&sq, &[1.0, 3.0, 7.0, 7.0]));
        // Narrower than twice the width: no inside.
        assert!(polygon(&[[0.0, 0.0], [3.0, 0.0], [3.0, 10.0], [0.0, 10.0]], 2.0).is_empty());
    }

    /// The band found through the chunk index (seed, rounds, the seed's chunks again) is the
    /// hull and the points not strictly inside `P` of a full read, with and without a filter
    /// (lidR_Topography: 73,403 points in 2 chunks; ground only).
    #[test]
    fn the_band_is_that_of_every_point() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/lidar/lidR_Topography.laz");
        let info = crate::input::las::header::inspect(&path).unwrap();
        let chunks = vec![(path.clone(), Arc::new(ChunkIndex::build(&info).unwrap()))];
        for classes in [None, Some(vec![2u8])] {
            let filter = Filter {
                classes,
                ..Filter::default()
            };
            for policy in [crate::DuplicatePolicy::First, crate::DuplicatePolicy::Highest] {
                let paths = [path.clone()];
                let src = BandSource {
                    paths: &paths,
                    filter: &filter,
                    chunks: &chunks,
                    store: None,
                    policy,
                    crs: None,
                    mem: 256 << 20,
                };
                let band = HullBand::compute(&src, 2.0).unwrap().unwrap();
                // The same band from a point store's cells (of 16 units).
                let dir = tempfile::tempdir().unwrap();
                let sp = dir.path().join("points");
                let mut r = LidarReader::open_with(&paths, &filter, ReadOptions::default()).unwrap();
                let id = "0".repeat(64);
                let tmp = dir.path();
                super::super::store::PointStore::write(&mut r, 16.0, &id, &sp, 256 << 20, tmp).unwrap();
                let st = super::super::store::PointStore::open(&sp, &id).unwrap();
                let by_store = BandSource {
                    store: Some(&st),
                    chunks: &[],
                    ..src
                };
                assert_eq!(HullBand::compute(&by_store, 2.0).unwrap().unwrap(), band);
                let mut r = LidarReader::open_with(&paths, &filter, ReadOptions::default()).unwrap();
                let all = r.read_all().unwrap();
                let mut b = HullBuilder::new(policy);
                for p in &all {
                    b.add([p.x, p.y, p.z], p.index);
                }
                let h: Vec<[f64; 2]> = b.finish().iter().map(|c| [c[0], c[1]]).collect();
                assert_eq!(band.hull, h);
                assert_eq!(band.inner, polygon(&h, 2.0));
                let p = &band.inner;
                let mut want: Vec<([f64; 3], u64)> = all
                    .iter()
                    .filter(|q| !(0..p.len()).all(|e| left_of(p, e, [q.x, q.y])))
                    .map(|q| ([q.x, q.y, q.z], q.index))
                    .collect();
                want.sort_by(|a, b| {
                    a.0[0].total_cmp(&b.0[0]).then(a.0[1].total_cmp(&b.0[1])).then_with(|| {
                        match policy.prefers((a.0[2], a.1), (b.0[2], b.1)) {
                            true => std::cmp::Ordering::Less,
                            false => std::cmp::Ordering::Greater,
                        }
                    })
                });
                want.dedup_by(|b, a| a.0[0] == b.0[0] && a.0[1] == b.0[1]);
                let want: Vec<[f64; 3]> = want.into_iter().map(|q| q.0).collect();
                assert!(!want.is_empty() && want.len() < all.len() / 4);
                assert_eq!(band.points, want);
            }
        }
    }
}
