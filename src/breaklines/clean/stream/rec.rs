//! The streamed cleaner's records: items as the external sort stores them, their order as
//! `clean()` numbers them, the merging of identical pieces, and the warnings kept in `clean()`'s
//! order.

use super::super::{MAX_WARNINGS, ZConflict, lex};
use crate::geom::predicates::sweep_cmp;
use crate::sort::external::{Merge, SortKey};
use std::cmp::Ordering;

/// Record flag: new in the last round (tested against everything it meets).
pub(super) const DIRTY: u32 = 1;
/// Record flag: an isolated vertex (`lo == hi`), not a segment.
pub(super) const POINT: u32 = 2;

/// A segment (ends in sweep order) or an isolated vertex, as the external sort stores it, with
/// what `clean()` knows of its ends: height, the line each first appeared on, and their order as
/// `clean()` numbers vertices (input vertices by first appearance, `round = 0`; then those made
/// at crossings, by round and position).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Rec {
    pub(super) lo: [f64; 2],
    pub(super) hi: [f64; 2],
    pub(super) z: [f64; 2],
    pub(super) id: [u64; 2],
    pub(super) round: [u32; 2],
    pub(super) vline: [u32; 2],
    pub(super) line: u32,
    pub(super) flags: u32,
    /// Records are 128 bytes: the sort's sliding maps take sizes that divide their window.
    pub(super) pad: [u64; 5],
}

impl SortKey for Rec {
    #[inline]
    fn order(a: &Self, b: &Self) -> Ordering {
        sweep_cmp(a.lo, b.lo)
            .then(sweep_cmp(a.hi, b.hi))
            .then((a.flags & POINT).cmp(&(b.flags & POINT)))
            .then(a.line.cmp(&b.line))
    }
    // Equal records are the same piece twice, merged as they are read.
    const STABLE: bool = false;
}

/// A vertex: position, height, `clean()`'s order of it, the line it first appeared on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct V {
    pub(super) p: [f64; 2],
    pub(super) z: f64,
    pub(super) round: u32,
    pub(super) id: u64,
    pub(super) vline: u32,
}

/// `clean()`'s vertex order: input vertices by first appearance, then by round and position.
pub(super) fn vcmp(a: &V, b: &V) -> Ordering {
    a.round
        .cmp(&b.round)
        .then(a.id.cmp(&b.id))
        .then_with(|| lex(a.p, b.p))
}

impl Rec {
    pub(super) fn end(&self, k: usize) -> V {
        V {
            p: if k == 0 { self.lo } else { self.hi },
            z: self.z[k],
            round: self.round[k],
            id: self.id[k],
            vline: self.vline[k],
        }
    }

    pub(super) fn new(a: V, b: V, line: u32, flags: u32) -> Rec {
        let (a, b) = match sweep_cmp(a.p, b.p) {
            Ordering::Greater => (b, a),
            _ => (a, b),
        };
        Rec {
            lo: a.p,
            hi: b.p,
            z: [a.z, b.z],
            id: [a.id, b.id],
            round: [a.round, b.round],
            vline: [a.vline, b.vline],
            line,
            flags,
            pad: [0; 5],
        }
    }

    pub(super) fn point(&self) -> bool {
        self.flags & POINT != 0
    }

    /// The ends in `clean()`'s vertex order (its segment's `[a, b]`).
    pub(super) fn ends(&self) -> [V; 2] {
        let (a, b) = (self.end(0), self.end(1));
        if vcmp(&a, &b) == Ordering::Greater {
            [b, a]
        } else {
            [a, b]
        }
    }

    /// `clean()`'s order of items: segments by their ends' order, then isolated vertices.
    pub(super) fn key_cmp(&self, o: &Rec) -> Ordering {
        let ([a, b], [c, d]) = (self.ends(), o.ends());
        self.point()
            .cmp(&o.point())
            .then(vcmp(&a, &c))
            .then(vcmp(&b, &d))
    }
}

/// A round's sorted items with identical pieces merged (the first line kept; new only if every
/// copy is).
pub(super) struct Dedup {
    pub(super) inner: Merge<Rec>,
    pub(super) next: Option<Rec>,
    pub(super) merged: u64,
}

impl Dedup {
    pub(super) fn new(mut inner: Merge<Rec>) -> Dedup {
        let next = inner.next();
        Dedup {
            inner,
            next,
            merged: 0,
        }
    }
}

impl Iterator for Dedup {
    type Item = Rec;
    fn next(&mut self) -> Option<Rec> {
        let mut r = self.next.take()?;
        loop {
            match self.inner.next() {
                Some(n) if n.lo == r.lo && n.hi == r.hi && n.point() == r.point() => {
                    r.flags &= n.flags | !DIRTY;
                    self.merged += 1;
                }
                n => {
                    self.next = n;
                    return Some(r);
                }
            }
        }
    }
}

/// The first [`MAX_WARNINGS`] warnings of the rounds by `clean()`'s order, after those of
/// rules 1–3.
pub(super) struct Warnings {
    pub(super) first: Vec<ZConflict>,
    pub(super) keyed: Vec<(WKey, ZConflict)>,
}

/// Where a round's warning comes in `clean()`'s order: vertices on lines in pair order, then
/// crossings in `(x, y)` order of their points.
#[derive(Clone, Copy, Debug)]
pub(super) struct WKey {
    pub(super) round: u32,
    pub(super) phase: u8,
    pub(super) p: [f64; 2],
    pub(super) s: Rec,
    pub(super) t: Rec,
    pub(super) sub: u8,
}

pub(super) fn wcmp(a: &WKey, b: &WKey) -> Ordering {
    a.round
        .cmp(&b.round)
        .then(a.phase.cmp(&b.phase))
        .then_with(|| lex(a.p, b.p))
        .then_with(|| a.s.key_cmp(&b.s))
        .then_with(|| a.t.key_cmp(&b.t))
        .then(a.sub.cmp(&b.sub))
}

impl Warnings {
    pub(super) fn new(first: Vec<ZConflict>) -> Warnings {
        Warnings {
            first,
            keyed: Vec::new(),
        }
    }

    pub(super) fn room(&self) -> usize {
        MAX_WARNINGS.saturating_sub(self.first.len())
    }

    pub(super) fn push(&mut self, key: WKey, w: ZConflict) {
        if self.room() == 0 {
            return;
        }
        self.keyed.push((key, w));
        if self.keyed.len() >= 2 * self.room() + 64 {
            self.trim();
        }
    }

    pub(super) fn trim(&mut self) {
        self.keyed.sort_by(|a, b| wcmp(&a.0, &b.0));
        self.keyed.truncate(self.room());
    }

    pub(super) fn finish(mut self) -> Vec<ZConflict> {
        self.trim();
        self.first.extend(self.keyed.into_iter().map(|k| k.1));
        self.first
    }
}
