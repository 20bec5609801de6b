//! The cleaner's rounds streamed by the sweep axis (issue 40, item 3, step 2).
//!
//! [`clean`](super::clean) holds the graph while its rounds run. Here each round is one plane
//! sweep over the items (segments with their ends' heights, isolated vertices) sorted by their
//! lower end with the crate's external sort; what the round does to an item is settled within a
//! window of the sweep line, and the item's pieces go straight into the next round's sorter:
//!
//! - contacts (rules 4–6) are found as in `sweep.rs`: an item against the *active* items;
//! - a segment's splits are complete once the sweep is past its upper end and the crossings on
//!   it are settled; its pieces are then written out;
//! - a crossing is settled (rule 7) once the sweep is past its point by twice the snap distance
//!   and no unsettled crossing lies within that distance of it (the crossings of one snap
//!   cluster are taken together, in `(x, y)` order, as `clean()` takes them): every vertex it
//!   could snap to is then known, through an index of the vertices near the sweep line;
//! - identical pieces (rule 3 after splitting) are adjacent in the next round's order and merge
//!   as they are read.
//!
//! Only the active items, the segments waiting for their crossings, the unsettled crossings and
//! the vertices near the sweep line are held ([`StreamStats`]), plus the sorter's budget.
//!
//! Equal to `clean()` (vertices bit for bit, segments, lines, counters, warnings) when the
//! heights are *uniform*: every vertex has a `z`, or none has. Then no vertex's `z` changes in a
//! round (rules 4 and 7 only report disagreements), so nothing depends on the order in which
//! `clean()` applies a round's findings across the whole graph. With mixed heights a vertex
//! without `z` takes one from the first line it lies on in `clean()`'s global pair order, and a
//! later interpolation along a segment ending there reads it: that order is not the sweep's, so
//! mixed heights are cleaned by `clean()` in memory and its graph is streamed out
//! ([`StreamStats::in_memory`]). Rules 1–3 are streamed too (`input.rs`); the polylines come
//! from a [`PolylineSource`], read once in order (a slice, or the breakline files read polyline
//! by polyline: [`crate::input::lines::LineStream`]), so they are never held whole unless the
//! heights are mixed.

use super::intersect::{contact, point_on};
use super::split::{along, closer, z_between};
use super::sweep::{ActiveSet, Span};
use super::{CleanOptions, CleanStats, MAX_ROUNDS, Work, ZConflict, ZConflictKind, lex};
use crate::error::{Error, Result};
use crate::sort::external::ExternalSorter;
use rec::{DIRTY, Dedup, POINT, Rec, V, WKey, Warnings};
use std::cmp::Ordering;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::path::{Path, PathBuf};

/// An active item and its number in the round's stream.
#[derive(Clone, Copy, Debug)]
struct Act {
    rec: Rec,
    seq: u64,
}

impl Span for Act {
    fn lo(&self) -> [f64; 2] {
        self.rec.lo
    }
    fn hi(&self) -> [f64; 2] {
        self.rec.hi
    }
}

/// What the streamed cleaning held at most at once (over all rounds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct StreamStats {
    /// Most items in one round.
    pub items: u64,
    /// Most items crossing the sweep line at once.
    pub peak_active: u64,
    /// Most items held otherwise at once: segments waiting for their crossings, unsettled
    /// crossings, isolated vertices waiting for the snap window, vertices near the sweep line.
    pub peak_window: u64,
    /// The heights were mixed: cleaned in memory by `clean()` (module docs).
    pub in_memory: bool,
}

/// A cleaned item, in sweep order of its lower end: a segment (`lo` before `hi` in sweep order)
/// or, when `lo == hi`, an isolated vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Lower end `[x, y, z]`.
    pub lo: [f64; 3],
    /// Upper end `[x, y, z]`.
    pub hi: [f64; 3],
    /// The input polyline it lies on (the first one, when several do).
    pub line: u32,
}

/// The cleaned graph as a stream: counters and warnings as [`super::clean`] gives them, and
/// the segments and isolated vertices in sweep order, read back from the last round's spill.
pub struct Cleaned {
    /// Counters (equal to `clean()`'s).
    pub stats: CleanStats,
    /// The first [`MAX_WARNINGS`](super::MAX_WARNINGS) `z` disagreements, in `clean()`'s order.
    pub warnings: Vec<ZConflict>,
    /// What was held.
    pub held: StreamStats,
    pieces: Dedup,
}

impl Cleaned {
    /// The error that cut the stream short, if any (check after the last piece).
    pub fn take_error(&mut self) -> Option<Error> {
        self.pieces.inner.take_error()
    }
}

impl Cleaned {
    /// The next piece, with `clean()`'s order of its ends' vertices (of `lo`, then `hi`):
    /// vertices compare by this key, then by `(x, y)` (as `clean()` numbers them: input
    /// vertices by first appearance, then those made at crossings, by round and position).
    pub fn next_keyed(&mut self) -> Option<(Piece, [(u32, u64); 2])> {
        let r = self.pieces.next()?;
        let piece = Piece {
            lo: [r.lo[0], r.lo[1], r.z[0]],
            hi: [r.hi[0], r.hi[1], r.z[1]],
            line: r.line,
        };
        Some((piece, [(r.round[0], r.id[0]), (r.round[1], r.id[1])]))
    }
}

impl Iterator for Cleaned {
    type Item = Piece;
    fn next(&mut self) -> Option<Piece> {
        self.next_keyed().map(|(p, _)| p)
    }
}

/// Polylines given in order, one at a time, as often as asked: what [`clean_streamed`] reads
/// (once; a second time into memory when the heights are mixed).
pub trait PolylineSource {
    /// Calls `f` with every polyline, in order (the `i`-th call is polyline `i`).
    ///
    /// # Errors
    /// The source's (a file that cannot be read or parsed) and the first of `f`'s.
    fn for_each_polyline(&self, f: &mut dyn FnMut(&[[f64; 3]]) -> Result<()>) -> Result<()>;
}

impl PolylineSource for [Vec<[f64; 3]>] {
    fn for_each_polyline(&self, f: &mut dyn FnMut(&[[f64; 3]]) -> Result<()>) -> Result<()> {
        self.iter().try_for_each(|l| f(l))
    }
}

impl PolylineSource for Vec<Vec<[f64; 3]>> {
    fn for_each_polyline(&self, f: &mut dyn FnMut(&[[f64; 3]]) -> Result<()>) -> Result<()> {
        self.as_slice().for_each_polyline(f)
    }
}

/// [`super::clean`] with the rounds streamed (module docs): the same graph as pieces in sweep
/// order, with `clean()`'s counters and warnings, and what was held. The sorts take `mem` bytes
/// and spill under `tmp_dir`. The polylines are read once, in order, and not held (but for
/// mixed heights, cleaned in memory).
///
/// # Errors
/// As [`super::clean`], and the external sort's and the source's.
pub fn clean_streamed(
    polylines: &(impl PolylineSource + ?Sized),
    options: &CleanOptions,
    mem: u64,
    tmp_dir: &Path,
) -> Result<Cleaned> {
    let Some(pre) = input::prepare(polylines, options, mem, tmp_dir)? else {
        return in_memory(polylines, options, mem, tmp_dir);
    };
    let mut s = Streamer {
        snap: pre.snap,
        ztol: options.z_tolerance,
        x: pre.x,
        mem,
        tmp: tmp_dir.to_path_buf(),
        stats: pre.stats,
        warnings: Warnings::new(pre.warnings),
        held: StreamStats {
            items: pre.count,
            ..StreamStats::default()
        },
    };
    let mut input = Dedup::new(pre.items);
    for round in 1..=MAX_ROUNDS {
        s.stats.rounds = round;
        let mut next = s.sorter();
        let (found, count) = s.round(round, &mut input, &mut next)?;
        if let Some(e) = input.inner.take_error() {
            return Err(e);
        }
        if round == 1 {
            s.stats.duplicate_segments += input.merged;
        } else {
            s.stats.merged_pieces += input.merged;
        }
        input = Dedup::new(next.finish()?);
        if !found {
            s.stats.segments = count.segments;
            return s.output(input, count.items);
        }
    }
    Err(Error::Internal(format!(
        "breaklines still not planar after {MAX_ROUNDS} rounds of splitting; the snap distance \
         {:e} may be too small for these coordinates",
        s.snap
    )))
}

/// Mixed heights: `clean()` in memory (the polylines read whole), its graph sorted and streamed
/// out.
fn in_memory(
    source: &(impl PolylineSource + ?Sized),
    options: &CleanOptions,
    mem: u64,
    tmp_dir: &Path,
) -> Result<Cleaned> {
    let mut polylines = Vec::new();
    source.for_each_polyline(&mut |l| {
        polylines.push(l.to_vec());
        Ok(())
    })?;
    let mut w = Work::new(&polylines, options)?;
    drop(polylines);
    w.run(&mut |w: &Work, first| Ok(w.find(first)))?;
    let s = Streamer {
        snap: w.snap,
        ztol: w.ztol,
        x: [w.lo[0], w.hi[0]],
        mem,
        tmp: tmp_dir.to_path_buf(),
        stats: CleanStats {
            segments: w.segs.len() as u64,
            ..w.stats
        },
        warnings: Warnings::new(w.warnings.clone()),
        held: StreamStats {
            in_memory: true,
            ..StreamStats::default()
        },
    };
    let v = |i: u32| V {
        p: w.xy[i as usize],
        z: w.z[i as usize],
        round: 0,
        id: u64::from(i),
        vline: w.vline[i as usize],
    };
    let mut sorter = s.sorter();
    for (k, &[a, b]) in w.segs.iter().enumerate() {
        sorter.push(Rec::new(v(a), v(b), w.line[k], 0))?;
    }
    for &i in &w.isolated {
        sorter.push(Rec::new(v(i), v(i), 0, POINT))?;
    }
    let items = (w.segs.len() + w.isolated.len()) as u64;
    drop(w);
    let input = Dedup::new(sorter.finish()?);
    s.output(input, items)
}

/// What a round read.
#[derive(Clone, Copy, Debug, Default)]
struct Count {
    items: u64,
    segments: u64,
}

/// A crossing found and not yet settled.
#[derive(Clone, Copy, Debug)]
struct Cross {
    p: [f64; 2],
    s: Act,
    t: Act,
}

/// A segment with splits or crossings, until its pieces are written.
#[derive(Debug, Default)]
struct Touched {
    splits: Vec<V>,
    /// Unsettled crossings on it.
    open: u32,
    /// The sweep is past its upper end.
    expired: bool,
}

/// The rounds' state that outlives one round.
struct Streamer {
    snap: f64,
    ztol: f64,
    x: [f64; 2],
    mem: u64,
    tmp: PathBuf,
    stats: CleanStats,
    warnings: Warnings,
    held: StreamStats,
}

/// One round's sweep state.
struct Round {
    round: u32,
    act: ActiveSet<Act>,
    touched: HashMap<u64, Touched>,
    crossings: Vec<Cross>,
    /// The round's vertices near the sweep line (ends of the items read), by `(y, x)`; isolated
    /// vertices flag whether a split took them.
    index: BTreeMap<(u64, u64), (V, bool)>,
    /// Isolated vertices waiting until no crossing can snap to them.
    points: VecDeque<Rec>,
    found: bool,
}

/// `v` as bits whose unsigned order is `total_cmp`'s.
fn key(v: f64) -> u64 {
    let b = v.to_bits();
    if b >> 63 == 1 { !b } else { b | (1 << 63) }
}

impl Streamer {
    fn sorter(&self) -> ExternalSorter<Rec> {
        ExternalSorter::new(self.mem / 2, &self.tmp)
    }

    /// How far from a point a vertex can be and still be snapped to (with room for rounding).
    fn reach(&self) -> f64 {
        2.0 * self.snap
    }

    fn output(mut self, input: Dedup, items: u64) -> Result<Cleaned> {
        self.stats.vertices =
            self.stats.input_vertices - self.stats.merged_vertices + self.stats.new_vertices;
        self.held.items = self.held.items.max(items);
        Ok(Cleaned {
            stats: self.stats,
            warnings: self.warnings.finish(),
            held: self.held,
            pieces: input,
        })
    }

    fn warn(&mut self, key: WKey, c: ZConflict) {
        self.stats.z_conflicts += 1;
        self.warnings.push(key, c);
    }

    /// One round: every item of `input` swept, its pieces (or itself) written to `out`.
    fn round(
        &mut self,
        round: u32,
        input: &mut Dedup,
        out: &mut ExternalSorter<Rec>,
    ) -> Result<(bool, Count)> {
        let mut count = Count::default();
        // Buckets: about the square root of the last round's items.
        let cols = ((self.held.items.max(1) as f64).sqrt() as u32).clamp(1, 1 << 16);
        let mut r = Round {
            round,
            act: ActiveSet::new(self.x[0], self.x[1], cols),
            touched: HashMap::new(),
            crossings: Vec::new(),
            index: BTreeMap::new(),
            points: VecDeque::new(),
            found: false,
        };
        let mut gone = Vec::new();
        for (seq, mut rec) in input.enumerate() {
            count.items += 1;
            if !rec.point() {
                count.segments += 1;
            }
            if round > 1 && rec.point() {
                rec.flags &= !DIRTY;
            }
            let y = rec.lo[1];
            r.act.expire_with(y, |a| gone.push(a));
            for a in gone.drain(..) {
                self.expired(&mut r, a, out)?;
            }
            self.settle(&mut r, y, out)?;
            for k in 0..2 {
                let v = rec.end(k);
                r.index
                    .entry((key(v.p[1]), key(v.p[0])))
                    .or_insert((v, false));
            }
            let it = Act {
                rec,
                seq: seq as u64,
            };
            self.contacts(&mut r, &it);
            let cols = r.act.cols_of(&it);
            r.act.insert(it, cols);
            if rec.point() {
                r.points.push_back(rec);
            }
            self.held.peak_active = self.held.peak_active.max(r.act.live);
            let window = r.touched.len() + r.crossings.len() + r.index.len() + r.points.len();
            self.held.peak_window = self.held.peak_window.max(window as u64);
        }
        r.act.expire_with(f64::INFINITY, |a| gone.push(a));
        for a in gone.drain(..) {
            self.expired(&mut r, a, out)?;
        }
        self.settle(&mut r, f64::INFINITY, out)?;
        debug_assert!(r.touched.is_empty() && r.points.is_empty());
        self.held.items = self.held.items.max(count.items);
        Ok((r.found, count))
    }

    /// Tests `it` against the active items it meets (the pair rule of `Work::find`).
    fn contacts(&mut self, r: &mut Round, it: &Act) {
        let cols = r.act.cols_of(it);
        let mut hits: Vec<(Act, Act)> = Vec::new();
        r.act.for_each_meeting(it, cols, |&other| {
            let (f, g) = (it.rec.flags, other.rec.flags);
            if f & g & POINT != 0 || (f | g) & DIRTY == 0 {
                return;
            }
            if it.rec.key_cmp(&other.rec) == Ordering::Less {
                hits.push((*it, other));
            } else {
                hits.push((other, *it));
            }
        });
        for (s, t) in hits {
            self.pair(r, s, t);
        }
    }

    /// The exact tests of `s` and `t` (`s` first in `clean()`'s item order) and what follows
    /// from them at once: on-line splits recorded (their height disagreements reported),
    /// crossings queued.
    fn pair(&mut self, r: &mut Round, s: Act, t: Act) {
        let [a, b] = s.rec.ends();
        let mut splits: [(Act, V); 2] = [(s, a); 2];
        let mut n = 0;
        let mut cross = None;
        if t.rec.point() {
            let v = t.rec.end(0);
            if point_on(a.p, b.p, v.p) {
                splits[0] = (s, v);
                n = 1;
                if let Some((_, used)) = r.index.get_mut(&(key(v.p[1]), key(v.p[0]))) {
                    *used = true;
                }
            }
        } else {
            let [c, d] = t.rec.ends();
            let ends = [a, b, c, d];
            let k = contact([a.p, b.p, c.p, d.p]);
            if k.is_empty() {
                return;
            }
            self.stats.overlaps += u64::from(k.overlap);
            for &(seg, end) in &k.splits[..k.n_splits as usize] {
                splits[n] = (if seg == 0 { s } else { t }, ends[end as usize]);
                n += 1;
            }
            cross = k.cross;
        }
        if n == 0 && cross.is_none() {
            return;
        }
        r.found = true;
        self.stats.vertex_splits += n as u64;
        for (sub, &(seg, v)) in splits[..n].iter().enumerate() {
            let [a, b] = seg.rec.ends();
            let zi = z_between([a.p, b.p], [a.z, b.z], v.p);
            if !v.z.is_nan() && (zi - v.z).abs() > self.ztol {
                let key = WKey {
                    round: r.round,
                    phase: 0,
                    p: [0.0; 2],
                    s: s.rec,
                    t: t.rec,
                    sub: sub as u8,
                };
                let c = ZConflict {
                    at: v.p,
                    z: [v.z, zi],
                    kind: ZConflictKind::OnLine,
                    lines: [seg.rec.line, v.vline],
                };
                self.warn(key, c);
            }
            r.touched.entry(seg.seq).or_default().splits.push(v);
        }
        if let Some(p) = cross {
            for seg in [s, t] {
                r.touched.entry(seg.seq).or_default().open += 1;
            }
            r.crossings.push(Cross { p, s, t });
        }
    }

    /// An item the sweep is past: a segment without pending crossings is written out.
    fn expired(&mut self, r: &mut Round, a: Act, out: &mut ExternalSorter<Rec>) -> Result<()> {
        if a.rec.point() {
            return Ok(());
        }
        match r.touched.get_mut(&a.seq) {
            None => {
                let mut rec = a.rec;
                rec.flags &= !DIRTY;
                out.push(rec)
            }
            Some(t) => {
                t.expired = true;
                if t.open == 0 {
                    self.finish(r, a, out)?;
                }
                Ok(())
            }
        }
    }

    /// Writes the pieces of the touched segment `a` (all its splits known).
    fn finish(&mut self, r: &mut Round, a: Act, out: &mut ExternalSorter<Rec>) -> Result<()> {
        let t = r.touched.remove(&a.seq).unwrap_or_default();
        let (lo, hi) = (a.rec.end(0), a.rec.end(1));
        let mut splits = t.splits;
        splits.sort_by(|u, v| along(lo.p, hi.p, u.p, v.p));
        splits.dedup_by(|u, v| u.p == v.p);
        if splits.is_empty() {
            let mut rec = a.rec;
            rec.flags &= !DIRTY;
            return out.push(rec);
        }
        let mut prev = lo;
        for v in splits.into_iter().chain(std::iter::once(hi)) {
            out.push(Rec::new(prev, v, a.rec.line, DIRTY))?;
            prev = v;
        }
        Ok(())
    }

    /// Settles the crossings no later item can change (the sweep is at `y`), then writes out
    /// what waited for them and forgets the vertices left behind.
    fn settle(&mut self, r: &mut Round, y: f64, out: &mut ExternalSorter<Rec>) -> Result<()> {
        let reach = self.reach();
        if !r.crossings.is_empty() {
            let low = r
                .crossings
                .iter()
                .map(|c| c.p[1])
                .fold(f64::INFINITY, f64::min);
            if low + reach < y {
                r.crossings.sort_by(|a, b| a.p[1].total_cmp(&b.p[1]));
                // The longest prefix behind the sweep and apart from the rest by more than the
                // reach: no crossing outside it can snap to what it makes.
                let n = r.crossings.len();
                let mut cut = 0;
                for k in (1..=n).rev() {
                    let last = r.crossings[k - 1].p[1];
                    let apart = k == n || r.crossings[k].p[1] - last > reach;
                    if last + reach < y && apart {
                        cut = k;
                        break;
                    }
                }
                let mut ready: Vec<Cross> = r.crossings.drain(..cut).collect();
                ready.sort_by(|a, b| {
                    lex(a.p, b.p)
                        .then_with(|| a.s.rec.key_cmp(&b.s.rec))
                        .then_with(|| a.t.rec.key_cmp(&b.t.rec))
                });
                let mut fresh: Vec<V> = Vec::new();
                for c in ready {
                    self.crossing(r, c, &mut fresh, out)?;
                }
            }
        }
        let front = r.crossings.iter().map(|c| c.p[1]).fold(y, f64::min);
        while let Some(p) = r.points.front() {
            if p.lo[1] + reach >= front {
                break;
            }
            let p = r.points.pop_front().unwrap_or_default();
            let used = r
                .index
                .get(&(key(p.lo[1]), key(p.lo[0])))
                .is_some_and(|e| e.1);
            if !used {
                out.push(p)?;
            }
        }
        let keep = (key(front - reach), 0);
        while let Some(e) = r.index.first_entry() {
            if *e.key() >= keep {
                break;
            }
            e.remove();
        }
        Ok(())
    }

    /// Rule 7 for one crossing: the vertex it snaps to (the nearest old one, or one made in
    /// this round before it) or a new one; the split of both segments there.
    fn crossing(
        &mut self,
        r: &mut Round,
        c: Cross,
        fresh: &mut Vec<V>,
        out: &mut ExternalSorter<Rec>,
    ) -> Result<()> {
        let (p, reach, snap) = (c.p, self.reach(), self.snap);
        let [sa, sb] = c.s.rec.ends();
        let [ta, tb] = c.t.rec.ends();
        let zs = z_between([sa.p, sb.p], [sa.z, sb.z], p);
        let zt = z_between([ta.p, tb.p], [ta.z, tb.z], p);
        let lines = [c.s.rec.line, c.t.rec.line];
        let mut cand: Vec<V> = Vec::new();
        let mut best = None;
        for (v, _) in r
            .index
            .range((key(p[1] - reach), 0)..=(key(p[1] + reach), u64::MAX))
            .map(|e| e.1)
        {
            if (v.p[0] - p[0]).abs() <= reach {
                best = closer(best, p, v.p, cand.len() as u32, snap);
                cand.push(*v);
            }
        }
        for v in fresh.iter() {
            best = closer(best, p, v.p, cand.len() as u32, snap);
            cand.push(*v);
        }
        self.stats.crossings += 1;
        let key_of = |sub: u8| WKey {
            round: r.round,
            phase: 1,
            p,
            s: c.s.rec,
            t: c.t.rec,
            sub,
        };
        let v = if let Some(near) = best {
            self.stats.snapped += 1;
            let v = cand[near.v as usize];
            for (sub, zin) in [zs, zt].into_iter().enumerate() {
                if !v.z.is_nan() && (zin - v.z).abs() > self.ztol {
                    let w = ZConflict {
                        at: v.p,
                        z: [v.z, zin],
                        kind: ZConflictKind::OnLine,
                        lines,
                    };
                    self.warn(key_of(sub as u8), w);
                }
            }
            if let Some((_, used)) = r.index.get_mut(&(key(v.p[1]), key(v.p[0]))) {
                *used = true;
            }
            v
        } else {
            let z = match (zs.is_nan(), zt.is_nan()) {
                (false, false) => {
                    if (zs - zt).abs() > self.ztol {
                        let w = ZConflict {
                            at: p,
                            z: [zs, zt],
                            kind: ZConflictKind::Crossing,
                            lines,
                        };
                        self.warn(key_of(0), w);
                    }
                    0.5 * (zs + zt)
                }
                (false, true) => zs,
                _ => zt,
            };
            self.stats.new_vertices += 1;
            let v = V {
                p,
                z,
                round: r.round,
                id: 0,
                vline: lines[0],
            };
            fresh.push(v);
            v
        };
        for seg in [c.s, c.t] {
            let t = r.touched.entry(seg.seq).or_default();
            if v.p != seg.rec.lo && v.p != seg.rec.hi {
                t.splits.push(v);
            }
            t.open -= 1;
            let done = t.open == 0 && t.expired;
            if done {
                self.finish(r, seg, out)?;
            }
        }
        Ok(())
    }
}

mod input;
mod rec;
#[cfg(test)]
mod tests;
