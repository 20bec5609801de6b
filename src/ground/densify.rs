//! The densification of one run (steps 4 and 5 of [`super::ptd`]) with conflict lists: every
//! candidate lives in the bucket of the ground triangle that contains it (closed, decided
//! exactly with `orient`: a linked list through the candidates, as `simplify::thin` keeps its
//! points), and is registered with the triangle under its mirror point when it has one.
//!
//! An iteration judges only the candidates of the triangles created or changed since the last
//! one, and those whose mirror triangle changed: a candidate's answer depends on nothing else.
//! Its accepted candidates (the closest to its plane per triangle, ties by the lower input
//! index) are inserted by a walk from the triangle that held them; then the candidates of the
//! triangles the insertions changed are moved, once per iteration, to the triangles that now
//! hold them (a walk from their old triangle slot, which insertion never frees: a few steps).
//! So no candidate is located from afar, nor judged again when nothing it read changed.
//!
//! The judging and the walks run on every core: an iteration's dirty triangles (and its
//! candidates whose mirror moved) are judged in pieces against the TIN as it stands, each
//! verdict's changes (mirror registrations, ground at a vertex) applied after in list order,
//! and the moved candidates are walked in pieces. The result is the same for any thread count:
//! a walk's path never decides, since a point on the edge of two triangles belongs to the one
//! with the lower slot ([`holder`]).

use super::ptd::{Label, RunStats};
use super::{GroundParams, Tag};
use crate::error::{Error, Result};
use crate::tin::{PointLocation, Tin, TriId, VertexId};
use rayon::prelude::*;

mod deferred;

/// No triangle, no candidate.
const NONE: u32 = u32::MAX;

/// `mnext` of a candidate registered with no mirror triangle.
const UNLINKED: u32 = u32::MAX - 1;

/// Densification stops after this many iterations even if points are still accepted (each
/// iteration inserts at most one point per triangle; real data needs a few dozen).
const MAX_ITERATIONS: u64 = 10_000;

/// Candidates walked to their new triangles by one task (pieces run on every core when an
/// iteration moves at least two).
const WALK_PIECE: usize = 4096;

/// An accepted candidate: `(triangle, distance, input index, point)`.
type Accepted = (u32, f64, u64, u32);

/// Triangles (or candidates) judged by one task, pieces on every core when an iteration has at
/// least two.
const JUDGE_PIECE: usize = 512;

/// What judging a candidate changes, applied once the iteration's judging is done (each
/// concerns its own candidate, judged once an iteration).
#[derive(Clone, Copy, Debug)]
enum Effect {
    /// Out of its mirror triangle's registrants.
    Unlink(u32),
    /// At a real vertex, close enough to it: ground (and out of the registrants).
    Ground(u32),
    /// Registered with mirror triangle `.1` (out of the one it was in).
    Register(u32, u32),
}

/// The verdicts of a piece of an iteration's judging.
struct Verdicts {
    effects: Vec<Effect>,
    accepted: Vec<Accepted>,
    evaluations: u64,
    /// Draws the mirror walks' edge order (the triangle found does not depend on it).
    rng: u64,
}

impl Default for Verdicts {
    fn default() -> Self {
        Verdicts {
            effects: Vec::new(),
            accepted: Vec::new(),
            evaluations: 0,
            rng: 0x9E37_79B9_7F4A_7C15,
        }
    }
}

/// The state of one run's densification.
pub(super) struct Densify<'a> {
    /// The ground TIN. Every point of the run is one of its vertex ids (inserted or not:
    /// point `i` is vertex `virtuals + i`), so each position is held once.
    tin: Tin,
    tags: &'a [u64],
    labels: &'a mut [Label],
    max_distance: f64,
    /// How far (vertically) a candidate at the x, y of a real ground vertex may lie from it to
    /// be ground: `--offset` (at most `--max-distance`). Its angles to that corner are
    /// undefined and it cannot be inserted; Axelsson's angles (90°) would refuse it, and the
    /// final TIN's `--offset` take it.
    stacked: f64,
    sin_max: f64,
    mirror: bool,
    /// Vertex ids below this are the virtual ring's.
    virtuals: usize,
    /// Per point: the triangle whose bucket holds it, the next point of that bucket, the
    /// triangle its mirror point was last found in (kept as the start of its next mirror walk)
    /// and the next registrant there ([`UNLINKED`]: not registered).
    tri: Vec<u32>,
    next: Vec<u32>,
    mtri: Vec<u32>,
    mnext: Vec<u32>,
    /// Per triangle slot: the first point of its bucket and of its mirror registrants; is it
    /// to be judged again (one bit a slot)?
    head: Vec<u32>,
    mhead: Vec<u32>,
    dirty: Vec<u64>,
    /// The dirty triangles (possibly freed since), and the candidates whose mirror triangle
    /// changed.
    dirty_list: Vec<u32>,
    reeval: Vec<u32>,
    touched: Vec<TriId>,
    gathered: Vec<u32>,
    /// One bit a point: puts a long gathered list in point order without sorting it.
    marks: Vec<u64>,
    /// The triangle each gathered candidate was found in.
    found: Vec<u32>,
    accepted: Vec<Accepted>,
    chosen: Vec<(u64, u32)>,
    /// The candidates that do not densify (not the lowest of their densification cell), each
    /// with its cell's lowest point, in point order: judged once against the final TIN.
    deferred: Vec<(u32, u32)>,
}

impl<'a> Densify<'a> {
    /// The densification of the candidates `cand` (eligible points not yet labelled) on the
    /// initial ground TIN `tin`, whose first `virtuals` vertices are virtual and whose next
    /// `tags.len()` vertex ids are the run's points.
    pub(super) fn new(
        mut tin: Tin,
        virtuals: usize,
        tags: &'a [u64],
        labels: &'a mut [Label],
        params: &GroundParams,
        cand: &[u32],
        deferred: Vec<(u32, u32)>,
    ) -> Result<Densify<'a>> {
        let n = tags.len();
        let mut d = Densify {
            tags,
            labels,
            max_distance: params.max_distance,
            stacked: params.offset.min(params.max_distance),
            sin_max: params.max_angle.to_radians().sin(),
            mirror: params.mirror,
            virtuals,
            tri: vec![NONE; n],
            next: vec![NONE; n],
            mtri: vec![NONE; n],
            mnext: vec![UNLINKED; n],
            head: Vec::new(),
            mhead: Vec::new(),
            dirty: Vec::new(),
            dirty_list: Vec::new(),
            reeval: Vec::new(),
            touched: Vec::new(),
            gathered: Vec::new(),
            marks: vec![0; n.div_ceil(64)],
            found: Vec::new(),
            accepted: Vec::new(),
            chosen: Vec::new(),
            deferred,
            tin: Tin::default(),
        };
        d.grow_for(&tin);
        // Every candidate into the bucket of its triangle (a walk from the last one: the
        // candidates come cell by cell).
        for &i in cand {
            let p = tin.xy(VertexId((virtuals + i as usize) as u32));
            let loc = tin.locate(p);
            if let Some(t) = holder(&tin, loc) {
                d.link(i, t.0);
            }
        }
        for t in tin.triangles() {
            d.set_dirty(t.0);
            d.dirty_list.push(t.0);
        }
        tin.record_touched(true);
        d.tin = tin;
        Ok(d)
    }

    /// Bytes this densification holds on the heap (the TIN's, with every point's position,
    /// included).
    fn heap_bytes(&self) -> usize {
        let u = std::mem::size_of::<u32>();
        let per_point = self.tri.capacity()
            + self.next.capacity()
            + self.mtri.capacity()
            + self.mnext.capacity()
            + self.dirty_list.capacity()
            + self.reeval.capacity()
            + self.gathered.capacity()
            + self.found.capacity();
        self.tin.heap_bytes()
            + u * (per_point + self.head.capacity() + self.mhead.capacity())
            + 8 * (self.dirty.capacity() + self.marks.capacity())
            + self.touched.capacity() * u
            + self.accepted.capacity() * std::mem::size_of::<Accepted>()
            + self.chosen.capacity() * std::mem::size_of::<(u64, u32)>()
            + self.deferred.capacity() * std::mem::size_of::<(u32, u32)>()
    }

    /// Bytes the run holds: this densification's, `extra` more, the tags and the labels.
    fn held(&self, extra: usize) -> u64 {
        (self.heap_bytes() + extra + std::mem::size_of_val(self.tags) + self.labels.len()) as u64
    }

    fn grow_for(&mut self, tin: &Tin) {
        let m = tin.triangle_slots();
        if self.head.len() < m {
            if self.head.capacity() < m {
                let more = (m - self.head.len()).max(m / 16);
                self.head.reserve_exact(more);
                self.mhead.reserve_exact(more);
            }
            self.head.resize(m, NONE);
            self.mhead.resize(m, NONE);
            let words = m.div_ceil(64);
            if self.dirty.capacity() < words {
                let more = (words - self.dirty.len()).max(words / 16);
                self.dirty.reserve_exact(more);
            }
            self.dirty.resize(words, 0);
        }
    }

    #[inline]
    fn is_dirty(&self, t: u32) -> bool {
        self.dirty[t as usize / 64] & (1 << (t % 64)) != 0
    }

    #[inline]
    fn set_dirty(&mut self, t: u32) {
        self.dirty[t as usize / 64] |= 1 << (t % 64);
    }

    #[inline]
    fn clear_dirty(&mut self, t: u32) {
        self.dirty[t as usize / 64] &= !(1 << (t % 64));
    }

    #[inline]
    fn id(&self, i: u32) -> u64 {
        Tag(self.tags[i as usize]).index()
    }

    /// The positions of a triangle's corners (written out: `array::map` was not inlined).
    #[inline]
    fn corners(&self, vs: [VertexId; 3]) -> [[f64; 3]; 3] {
        [
            self.tin.point(vs[0]),
            self.tin.point(vs[1]),
            self.tin.point(vs[2]),
        ]
    }

    /// The vertex id of point `i`.
    #[inline]
    fn vid(&self, i: u32) -> VertexId {
        VertexId((self.virtuals + i as usize) as u32)
    }

    #[inline]
    fn link(&mut self, i: u32, t: u32) {
        self.next[i as usize] = self.head[t as usize];
        self.head[t as usize] = i;
        self.tri[i as usize] = t;
    }

    /// Registers `i` (not registered) with mirror triangle `t`.
    fn mlink(&mut self, i: u32, t: u32) {
        self.mnext[i as usize] = self.mhead[t as usize];
        self.mhead[t as usize] = i;
        self.mtri[i as usize] = t;
    }

    /// Takes `i` out of its mirror triangle's registrants (a short list: found by a scan).
    fn munlink(&mut self, i: u32) {
        let n = self.mnext[i as usize];
        if n == UNLINKED {
            return;
        }
        let t = self.mtri[i as usize] as usize;
        if self.mhead[t] == i {
            self.mhead[t] = n;
        } else {
            let mut j = self.mhead[t];
            while j != NONE && self.mnext[j as usize] != i {
                j = self.mnext[j as usize];
            }
            if j != NONE {
                self.mnext[j as usize] = n;
            }
        }
        self.mnext[i as usize] = UNLINKED;
    }

    /// Densifies until an iteration inserts nothing; then the final pass (step 5).
    pub(super) fn run(mut self, low_noise: f64, offset: f64, stats: &mut RunStats) -> Result<()> {
        let mut accepted = std::mem::take(&mut self.accepted);
        let mut chosen = std::mem::take(&mut self.chosen);
        while stats.iterations < MAX_ITERATIONS {
            stats.iterations += 1;
            // Judge the candidates of the dirty triangles, and those whose mirror moved (their
            // own triangles not dirty), all against the TIN as it is, on every core; then apply
            // what the verdicts change (each concerns its own candidate).
            accepted.clear();
            let dirty = std::mem::take(&mut self.dirty_list);
            let reeval = std::mem::take(&mut self.reeval);
            let mut verdicts = self.judge_all(&dirty, None);
            verdicts.extend(self.judge_all(&reeval, Some(())));
            for v in verdicts {
                stats.evaluations += v.evaluations;
                accepted.extend_from_slice(&v.accepted);
                self.apply(&v.effects);
            }
            for &t in &dirty {
                self.clear_dirty(t);
            }
            self.dirty_list = dirty;
            self.dirty_list.clear();
            self.reeval = reeval;
            self.reeval.clear();
            // The best of each triangle, inserted in input order (the TIN does not depend on
            // it).
            accepted.sort_unstable_by(|a, b| {
                a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2))
            });
            chosen.clear();
            let mut last = NONE;
            for &(t, _, id, i) in &accepted {
                if t != last {
                    chosen.push((id, i));
                    last = t;
                }
            }
            chosen.sort_unstable();
            if chosen.is_empty() {
                break;
            }
            // Grow the TIN's triangles by a sixteenth at a time, not by doubling: its memory
            // is most of a run's.
            if self.tin.triangle_room() < chosen.len() {
                let more = chosen.len().max(self.tin.vertex_count() / 16);
                self.tin.reserve_triangles_exact(more);
            }
            for &(_, i) in &chosen {
                self.insert(i)?;
            }
            self.redistribute()?;
            // The peak, at the end of the iteration (the TIN at its largest so far, the
            // iteration's lists at theirs); then lists far larger than their last use give
            // their room back (the first iterations move most candidates at once).
            let lists = accepted.capacity() * std::mem::size_of::<Accepted>()
                + chosen.capacity() * std::mem::size_of::<(u64, u32)>();
            stats.bytes = stats.bytes.max(self.held(lists));
            trim(&mut accepted);
            trim(&mut chosen);
            trim(&mut self.gathered);
            trim(&mut self.found);
            trim(&mut self.touched);
            trim(&mut self.dirty_list);
            trim(&mut self.reeval);
        }
        self.tin.record_touched(false);
        self.accepted = accepted;
        self.chosen = chosen;
        stats.bytes = stats.bytes.max(self.held(0));
        self.finish(low_noise, offset);
        self.finish_deferred(low_noise, offset)
    }

    /// Judges the jobs of a list on every core (in pieces, when it is long): `jobs` are dirty
    /// triangles (`single` none: each live one's whole bucket) or candidates whose mirror
    /// triangle changed (`single`: each alone, unless it is no longer a candidate or its own
    /// triangle is dirty, then judged with it). The verdicts come back in the list's order.
    fn judge_all(&self, jobs: &[u32], single: Option<()>) -> Vec<Verdicts> {
        let piece = |jobs: &[u32]| {
            let mut v = Verdicts::default();
            let mut close = Vec::new();
            for &j in jobs {
                match single {
                    None if self.tin.is_live(TriId(j)) => self.judge(j, None, &mut v, &mut close),
                    None => {}
                    Some(()) => {
                        let t = self.tri[j as usize];
                        if self.labels[j as usize] == Label::Other && !self.is_dirty(t) {
                            self.judge(t, Some(j), &mut v, &mut close);
                        }
                    }
                }
            }
            v
        };
        if jobs.len() < 2 * JUDGE_PIECE {
            vec![piece(jobs)]
        } else {
            jobs.par_chunks(JUDGE_PIECE).map(piece).collect()
        }
    }

    /// Applies the verdicts' changes to the candidates' mirror registrations and labels.
    fn apply(&mut self, effects: &[Effect]) {
        for &e in effects {
            match e {
                Effect::Unlink(i) => self.munlink(i),
                Effect::Ground(i) => {
                    self.munlink(i);
                    self.labels[i as usize] = Label::Ground;
                }
                Effect::Register(i, mt) => {
                    self.munlink(i);
                    self.mlink(i, mt);
                }
            }
        }
    }

    /// Judges the candidates of triangle `t`'s bucket (`only`: just that one, whose mirror
    /// triangle changed); a candidate at a vertex of the TIN is ground at once when close
    /// enough to it. Of a whole bucket only the best accepted candidate goes to the verdicts
    /// (closest to the plane, ties by the lower input index: the one the iteration inserts),
    /// so the candidates within `max_distance` are tried from the closest and the angles (and
    /// the mirror) are measured only until one is accepted: the others need no answer now, as
    /// the insertion changes `t` and they are all judged again in the next iteration.
    fn judge(&self, t: u32, only: Option<u32>, out: &mut Verdicts, close: &mut Vec<(f64, u32)>) {
        let vs = self.tin.tri_vertices(TriId(t));
        let corners = self.corners(vs);
        let plane = Plane::new(corners);
        if let Some(i) = only {
            out.evaluations += 1;
            if let Some(d) = self.distance(i, vs, &corners, &plane, out)
                && self.accepts(i, t, vs, &corners, d, out)
            {
                out.accepted.push((t, d, self.id(i), i));
            }
            return;
        }
        close.clear();
        let mut i = self.head[t as usize];
        while i != NONE {
            if self.labels[i as usize] == Label::Other {
                out.evaluations += 1;
                if let Some(d) = self.distance(i, vs, &corners, &plane, out) {
                    close.push((d, i));
                }
            }
            i = self.next[i as usize];
        }
        let tags = self.tags;
        let id = |i: u32| Tag(tags[i as usize]).index();
        let order =
            |a: &(f64, u32), b: &(f64, u32)| a.0.total_cmp(&b.0).then(id(a.1).cmp(&id(b.1)));
        // The closest is usually accepted: picked by a scan; after a few refusals, the rest sorted.
        let mut tries = 0;
        while !close.is_empty() {
            let k = if tries < 4 {
                (0..close.len())
                    .min_by(|&a, &b| order(&close[a], &close[b]))
                    .unwrap_or(0)
            } else {
                if tries == 4 {
                    close.sort_unstable_by(|a, b| order(b, a));
                }
                close.len() - 1
            };
            let (d, i) = close.swap_remove(k);
            if self.accepts(i, t, vs, &corners, d, out) {
                out.accepted.push((t, d, id(i), i));
                break;
            }
            tries += 1;
        }
    }

    /// Takes `i` out of its mirror triangle's registrants (after the judging), if it is one.
    #[inline]
    fn unlink(&self, i: u32, out: &mut Verdicts) {
        if self.mnext[i as usize] != UNLINKED {
            out.effects.push(Effect::Unlink(i));
        }
    }

    /// The distance of candidate `i` to the plane of its triangle when at most
    /// `max_distance`; `None` (and no mirror registration) otherwise, or when `i` lies at a
    /// corner (then it is ground when within `stacked` of a real one).
    fn distance(
        &self,
        i: u32,
        vs: [VertexId; 3],
        corners: &[[f64; 3]; 3],
        plane: &Plane,
        out: &mut Verdicts,
    ) -> Option<f64> {
        let p = self.tin.point(self.vid(i));
        if let Some(k) = (0..3).find(|&k| corners[k][0] == p[0] && corners[k][1] == p[1]) {
            let d = (p[2] - corners[k][2]).abs();
            if d <= self.stacked && (vs[k].0 as usize) >= self.virtuals {
                out.effects.push(Effect::Ground(i));
            } else {
                self.unlink(i, out);
            }
            return None;
        }
        let d = plane.distance(p, self.max_distance);
        if d.is_none() {
            self.unlink(i, out);
        }
        d
    }

    /// Is candidate `i` of triangle `t`, at distance `d` from its plane, accepted: its angles,
    /// or else its mirror point's test?
    fn accepts(
        &self,
        i: u32,
        t: u32,
        vs: [VertexId; 3],
        corners: &[[f64; 3]; 3],
        d: f64,
        out: &mut Verdicts,
    ) -> bool {
        let p = self.tin.point(self.vid(i));
        if !Plane::steep(corners, p, d, self.sin_max) {
            self.unlink(i, out);
            return true;
        }
        if !self.mirror {
            self.unlink(i, out);
            return false;
        }
        // Steep: mirror through the nearest real vertex (ties: the lower vertex id), and test
        // the mirror point against the triangle under it.
        let near = (0..3)
            .filter(|&k| (vs[k].0 as usize) >= self.virtuals)
            .map(|k| {
                let c = corners[k];
                ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2), vs[k].0, k)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        match near {
            Some((_, _, k)) => self.mirror_accepts(i, t, corners[k], p, out),
            None => {
                self.unlink(i, out);
                false
            }
        }
    }

    /// The mirror test of candidate `i` (in triangle `t`) through corner `c`; registers `i`
    /// with the triangle under the mirror point. The walk starts from the triangle slot the
    /// mirror point was last found in (insertions never free a slot, and change a triangle only
    /// into triangles near it: the same mirror point is there or a few steps away), else from
    /// `t`; the triangle found does not depend on the start.
    fn mirror_accepts(&self, i: u32, t: u32, c: [f64; 3], p: [f64; 3], out: &mut Verdicts) -> bool {
        let m = [2.0 * c[0] - p[0], 2.0 * c[1] - p[1], 2.0 * c[2] - p[2]];
        let last = self.mtri[i as usize];
        let from = if last != NONE && self.tin.is_live(TriId(last)) {
            last
        } else {
            t
        };
        let loc = self.tin.walk_from(TriId(from), [m[0], m[1]], &mut out.rng);
        let mt = match loc {
            PointLocation::Inside(_) | PointLocation::OnEdge(_) => holder(&self.tin, loc),
            _ => None,
        };
        let Some(mt) = mt else {
            self.unlink(i, out);
            return false;
        };
        if self.mnext[i as usize] == UNLINKED || last != mt.0 {
            out.effects.push(Effect::Register(i, mt.0));
        }
        let corners = self.corners(self.tin.tri_vertices(mt));
        Plane::new(corners).accepts(&corners, m, self.max_distance, self.sin_max)
    }

    /// Inserts candidate `i` (accepted), walking from the triangle slot whose bucket holds it
    /// (insertions never free a slot: it is live, and near the point).
    fn insert(&mut self, i: u32) -> Result<()> {
        self.labels[i as usize] = Label::Ground;
        self.munlink(i);
        // A candidate of this iteration at the same place may have gone in first: then this
        // one is that vertex.
        self.tin.set_hint(TriId(self.tri[i as usize]));
        self.tin.insert_vertex(self.vid(i))?;
        Ok(())
    }

    /// After an iteration's insertions: moves the candidates of the triangles they touched
    /// into the triangles that now hold them (a walk from the slot each was in: near), marks
    /// the touched triangles dirty, and queues their mirror registrants.
    fn redistribute(&mut self) -> Result<()> {
        let tin = std::mem::take(&mut self.tin);
        self.grow_for(&tin);
        self.tin = tin;
        let mut touched = std::mem::take(&mut self.touched);
        touched.clear();
        self.tin.take_touched(&mut touched);
        touched.sort_unstable();
        touched.dedup();
        let mut gathered = std::mem::take(&mut self.gathered);
        gathered.clear();
        for &t in &touched {
            let t = t.0;
            let mut i = std::mem::replace(&mut self.head[t as usize], NONE);
            while i != NONE {
                if self.labels[i as usize] == Label::Other {
                    gathered.push(i);
                }
                i = self.next[i as usize];
            }
            let mut j = std::mem::replace(&mut self.mhead[t as usize], NONE);
            while j != NONE {
                let n = self.mnext[j as usize];
                self.mnext[j as usize] = UNLINKED;
                self.reeval.push(j);
                j = n;
            }
            if self.tin.is_live(TriId(t)) && !self.is_dirty(t) {
                self.set_dirty(t);
                self.dirty_list.push(t);
            }
        }
        // In memory order (spatial, see `ptd::spatial_order`), walks from the slot each was in
        // (near), pieces on every core: the triangle found does not depend on the walk's path.
        in_point_order(&mut gathered, &mut self.marks);
        let mut found = std::mem::take(&mut self.found);
        let tri = &self.tri;
        self.locate_all(&gathered, |&i, _| (i, tri[i as usize]), &mut found);
        for (&i, &t) in gathered.iter().zip(&found) {
            if t == NONE {
                return Err(self.outside(i));
            }
            self.link(i, t);
        }
        self.found = found;
        self.gathered = gathered;
        self.touched = touched;
        Ok(())
    }

    /// The triangles that hold points ([`holder`]; [`NONE`] outside the TIN), one for each of
    /// `items`: `at(item, the triangle found for the item before it)` gives its point and the
    /// triangle its walk starts from ([`NONE`]: any). Pieces on every core: the triangle found
    /// does not depend on the walk's path.
    fn locate_all<T, F>(&self, items: &[T], at: F, found: &mut Vec<u32>)
    where
        T: Sync,
        F: Fn(&T, u32) -> (u32, u32) + Sync,
    {
        found.clear();
        found.resize(items.len(), NONE);
        let any = self.tin.triangles().next().map_or(0, |t| t.0);
        let walk = |piece: &[T], out: &mut [u32]| {
            let mut rng = 0x9E37_79B9_7F4A_7C15_u64;
            let mut prev = NONE;
            for (item, t) in piece.iter().zip(out) {
                let (i, start) = at(item, prev);
                let start = if start == NONE { any } else { start };
                let loc = self
                    .tin
                    .walk_from(TriId(start), self.tin.xy(self.vid(i)), &mut rng);
                *t = holder(&self.tin, loc).map_or(NONE, |t| t.0);
                prev = *t;
            }
        };
        if items.len() < 2 * WALK_PIECE {
            walk(items, found);
        } else {
            items
                .par_chunks(WALK_PIECE)
                .zip(found.par_chunks_mut(WALK_PIECE))
                .for_each(|(piece, out)| walk(piece, out));
        }
    }

    /// The error of point `i` found outside the ground TIN (every point lies inside its
    /// virtual ring).
    fn outside(&self, i: u32) -> Error {
        let p = self.tin.xy(self.vid(i));
        Error::Internal(format!(
            "ground: point {} ({}, {}) lies outside the ground TIN",
            self.id(i),
            p[0],
            p[1]
        ))
    }
}

/// The triangle whose bucket holds a point found at `loc`: the one containing it; on an edge,
/// the one of its two triangles with the lower slot (whichever the walk reached); at a vertex,
/// the triangle of the vertex's out-edge; none outside.
fn holder(tin: &Tin, loc: PointLocation) -> Option<TriId> {
    match loc {
        PointLocation::Inside(t) => Some(t),
        PointLocation::OnEdge(e) => Some(match tin.twin(e) {
            Some(f) => e.tri().min(f.tri()),
            None => e.tri(),
        }),
        PointLocation::OnVertex(v) => tin.out_edge(v).map(|e| e.tri()),
        PointLocation::Outside(_) => None,
    }
}

/// Puts `list` (distinct points) in increasing order: a long list by marking its points in
/// `marks` (one bit a point, all clear before and after) and reading the marks back, a short one
/// by sorting it.
fn in_point_order(list: &mut Vec<u32>, marks: &mut [u64]) {
    if list.len() < marks.len() {
        list.sort_unstable();
        return;
    }
    for &i in list.iter() {
        marks[i as usize / 64] |= 1 << (i % 64);
    }
    list.clear();
    for (w, word) in marks.iter_mut().enumerate() {
        let mut bits = std::mem::take(word);
        while bits != 0 {
            list.push(64 * w as u32 + bits.trailing_zeros());
            bits &= bits - 1;
        }
    }
}

/// Gives back most of the room of a list far larger than its last use.
fn trim<T>(v: &mut Vec<T>) {
    if v.capacity() > 4096 && v.len() < v.capacity() / 4 {
        v.shrink_to(2 * v.len());
    }
}

/// The plane of a triangle: its first corner and its (unnormalised) normal with its length.
struct Plane {
    a: [f64; 3],
    nrm: [f64; 3],
    len: f64,
}

impl Plane {
    #[inline]
    fn new(t: [[f64; 3]; 3]) -> Plane {
        let a = t[0];
        let u = [t[1][0] - a[0], t[1][1] - a[1], t[1][2] - a[2]];
        let v = [t[2][0] - a[0], t[2][1] - a[1], t[2][2] - a[2]];
        let nrm = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let len = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
        Plane { a, nrm, len }
    }

    /// The distance of `p` to the plane when at most `max_d` (and a plane at all).
    #[inline]
    fn distance(&self, p: [f64; 3], max_d: f64) -> Option<f64> {
        let (a, nrm, len) = (self.a, self.nrm, self.len);
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let w = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
        let d = (w[0] * nrm[0] + w[1] * nrm[1] + w[2] * nrm[2]).abs() / len;
        (d <= max_d).then_some(d)
    }

    /// Is an angle between the plane and the lines from `p` (at distance `d` from it) to the
    /// corners of `t` larger than the angle whose sine is `sin_max`?
    #[inline]
    fn steep(t: &[[f64; 3]; 3], p: [f64; 3], d: f64, sin_max: f64) -> bool {
        t.iter().any(|c| {
            let r2 = (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2);
            // angle > max  <=>  d / r > sin(max)
            d > r2.sqrt() * sin_max
        })
    }

    /// Axelsson's test of `p` against the plane of triangle `t`: its distance to the plane at
    /// most `max_d`, and every angle between the plane and the lines to the corners at most
    /// the angle whose sine is `sin_max`.
    #[inline]
    fn accepts(&self, t: &[[f64; 3]; 3], p: [f64; 3], max_d: f64, sin_max: f64) -> bool {
        self.distance(p, max_d)
            .is_some_and(|d| !Plane::steep(t, p, d, sin_max))
    }
}
