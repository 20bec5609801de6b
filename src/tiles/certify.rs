//! Certificates: which triangles of a tile's run are triangles of the triangulation of *all*
//! points.
//!
//! A tile's run triangulates the points of some blocks (the *loaded* blocks). A triangle of that
//! run is Delaunay for the loaded points: its closed circumdisk holds no other loaded point (ties
//! go by the global rule of [`crate::geom::predicates`], which depends on positions only). If the
//! disk also holds no point of any other block, it holds no point at all, so the triangle is a
//! triangle of the whole triangulation: it is **certified**.
//!
//! The test has two stages. A floating-point bound of the disk
//! ([`crate::geom::predicates::circumdisk_bounds`], never smaller than the true disk) picks the
//! blocks not read whose *extent* (the tight box of their points, rounded outward) it reaches;
//! most disks stay inside the loaded rectangle and the test ends there. The points of each block
//! it reaches are then tested one by one with the exact, perturbed in-circle predicate: the
//! certificate fails only when some point really lies in the disk (a *witness*; its block is what
//! a patch run must read). An error of the bound can only make the second stage test more
//! points, never grant a wrong certificate. This matters along the data's edges: a ragged edge
//! makes flat triangles whose huge disks reach far along the edge, but only by a sliver that the
//! points there stay out of.
//!
//! Two refinements keep the second stage small. Blocks are gathered nearest the triangle's
//! centroid first, in boxes growing fourfold, so a failing certificate stops at its first
//! witnesses (a sparse patch run has huge triangles between the hull's corners). And a *flat*
//! triangle (disk bound over 16 times its longest edge; [`Certifier::flat_clear`]) is judged by
//! the cap on its long edge and the half-plane beyond it, within the bound: along a straight
//! data edge (a survey's border, a tile's edge at a gap between tiles) the centre of a sliver's
//! disk lies far outside and is known only roughly, so the bound alone would reach every block
//! of the survey, while the half-plane beyond the edge holds none.
//!
//! The convex hull needs no certificate of its own: every run also holds the corners of the hull
//! of all the points ([`super::hull`]), so a run's hull *is* the whole hull, and what lies
//! outside it lies outside the whole triangulation.

use super::grid::BlockRect;
use super::index::{BlockIndex, Within};
use super::lines::{RegionScratch, RunLines, Sight};
use super::region::bbox;
use crate::error::Result;
use crate::geom::predicates::{CircleSide, DiskBounds, Orientation, incircle, orient};
use crate::idmap::FastMap;
use std::cell::RefCell;

/// The blocks a run read: a rectangle, and single blocks outside it (sorted keys).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Loaded {
    pub rect: BlockRect,
    pub extra: Vec<u64>,
}

impl Loaded {
    /// Is block `key` (at `(bx, by)`) read?
    #[inline]
    pub fn contains(&self, key: u64, bx: i64, by: i64) -> bool {
        self.rect.contains(bx, by) || self.extra.binary_search(&key).is_ok()
    }
}

/// Points of blocks not read, kept while a run is judged (a block is often tested by many
/// triangles along a data edge).
#[derive(Debug, Default)]
struct Cache {
    blocks: FastMap<u64, Vec<[f64; 3]>>,
    points: usize,
}

/// Cached points beyond which the cache starts afresh (6 MiB of points per run in flight: a
/// run tests the blocks around its own, and the flat route keeps a data edge's long slivers
/// from testing whole rows).
const CACHE_POINTS: usize = 1 << 18;

/// Answers certificate questions for one run over the `loaded` blocks.
#[derive(Debug)]
pub(crate) struct Certifier<'a> {
    index: &'a BlockIndex,
    loaded: &'a Loaded,
    /// World rectangle of the loaded rectangle.
    world: [f64; 4],
    /// Set when a test reached beyond what a plan's task read (see [`BlockIndex::scope`]).
    /// The widest buffer an unread file needs (0: none).
    pub unknown: &'a std::cell::Cell<f64>,
    cache: RefCell<Cache>,
    /// Points tested one by one, and the blocks they came from.
    pub tested: std::cell::Cell<(u64, u64)>,
    /// Witness blocks a failed certificate reports at most: a few are enough for the next run
    /// to make progress, and the judge doubles it with every run of a tile (a disk that a sparse
    /// patch run left huge may hold points of thousands of blocks).
    pub witnesses: usize,
    /// The breaklines the run loaded, if any (see [`super::lines`]).
    pub lines: Option<&'a RunLines<'a>>,
    /// With breaklines: the run's triangulation and adjacency, and the triangle being judged
    /// (for [`Sight::region`]).
    pub mesh: Option<(&'a crate::Triangulation, &'a [u32])>,
    pub tri: std::cell::Cell<u32>,
    /// What sight regions reuse over the run.
    scratch: RefCell<RegionScratch>,
}

/// Squared distance from `p` to the box `e` (`[xmin, ymin, xmax, ymax]`).
#[inline]
fn box_dist2(e: &[f64; 4], p: [f64; 2]) -> f64 {
    let dx = (e[0] - p[0]).max(p[0] - e[2]).max(0.0);
    let dy = (e[1] - p[1]).max(p[1] - e[3]).max(0.0);
    dx * dx + dy * dy
}

/// An upper bound of the height of the circular segment that the chord `ab` cuts off the
/// circumdisk of `a, b, c` on `c`'s side, for an obtuse angle at `c` (centre beyond the chord)
/// and `l = |ab|`. In the frame of `ab`, `c = (s, δ)`: the centre lies `K = m / 2δ` beyond the
/// chord with `m = s(l - s) - δ²`, and the height is `(l²/4) / (R + K) ≤ l²δ / 4m`; never more
/// than `l / 2`. Computed with `δ` rounded up (its cross product cancels) and `m` rounded down.
fn sagitta_bound(a: [f64; 2], b: [f64; 2], c: [f64; 2], l: f64) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let e = [c[0] - a[0], c[1] - a[1]];
    let scale = d[0].abs().max(d[1].abs()) * e[0].abs().max(e[1].abs());
    let cross = (d[0] * e[1] - d[1] * e[0]).abs() + 8.0 * f64::EPSILON * scale;
    let delta = cross / l * (1.0 + 1e-9) + f64::MIN_POSITIVE;
    let s = (d[0] * e[0] + d[1] * e[1]) / l;
    let m = s * (l - s) * (1.0 - 1e-9) - delta * delta;
    let h = if m > 0.0 {
        l * l * delta / (4.0 * m) * (1.0 + 1e-9)
    } else {
        f64::INFINITY
    };
    h.min(l / 2.0) + l * 1e-9
}

/// Squared distance from `c` to the segment `x`-`y` (floating point).
fn seg_dist2(c: [f64; 2], x: [f64; 2], y: [f64; 2]) -> f64 {
    let d = [y[0] - x[0], y[1] - x[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let s = if l2 > 0.0 {
        (((c[0] - x[0]) * d[0] + (c[1] - x[1]) * d[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let p = [x[0] + s * d[0], x[1] + s * d[1]];
    (c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)
}

/// Do two closed boxes meet?
#[inline]
fn boxes_meet(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3]
}

/// Is the angle at `c` of the triangle `a, b, c` clearly obtuse (so the circumcentre lies
/// beyond the chord `ab`)?
fn obtuse_at(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let (ca, cb) = ([a[0] - c[0], a[1] - c[1]], [b[0] - c[0], b[1] - c[1]]);
    let dot = ca[0] * cb[0] + ca[1] * cb[1];
    let lens = (ca[0].hypot(ca[1])) * (cb[0].hypot(cb[1]));
    !(dot.is_nan() || dot >= -1e-6 * lens)
}

/// The box of the cap that the chord `ab` cuts off the circumdisk of `a, b, c` on `c`'s side
/// (the chord moved up to [`sagitta_bound`] towards `c`), for an obtuse angle at `c`, widened by
/// the rounding slack and `grow`.
fn chord_box(a: [f64; 2], b: [f64; 2], c: [f64; 2], g: &super::grid::TileGrid, grow: f64) -> [f64; 4] {
    let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let mag = a[0].abs().max(a[1].abs()).max(b[0].abs()).max(b[1].abs());
    let reach = g.margin(mag + l) + l * 1e-9 + grow;
    let h = sagitta_bound(a, b, c, l);
    let n = [-(b[1] - a[1]) / l, (b[0] - a[0]) / l];
    let (ah, bh) = (
        [a[0] + n[0] * h, a[1] + n[1] * h],
        [b[0] + n[0] * h, b[1] + n[1] * h],
    );
    [
        a[0].min(b[0]).min(ah[0]).min(bh[0]) - reach,
        a[1].min(b[1]).min(ah[1]).min(bh[1]) - reach,
        a[0].max(b[0]).max(ah[0]).max(bh[0]) + reach,
        a[1].max(b[1]).max(ah[1]).max(bh[1]) + reach,
    ]
}

/// The box of the part of the circumdisk of the counter-clockwise triangle `t` that its
/// constrained edges (`hidden`) leave visible, when one of them has an obtuse angle opposite
/// (the centre lies beyond it, so the visible part is within the cap on the triangle's side:
/// the chord box of [`Certifier::flat_clear`]); the intersection of such boxes. `None`: the
/// whole disk.
fn cap_box(t: &[[f64; 2]; 3], hidden: [bool; 3], g: &super::grid::TileGrid) -> Option<[f64; 4]> {
    let mut out: Option<[f64; 4]> = None;
    for k in (0..3).filter(|&k| hidden[k]) {
        let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        if !obtuse_at(a, b, c) {
            continue;
        }
        let bx = chord_box(a, b, c, g, 0.0);
        if !bx.iter().all(|v| v.is_finite()) {
            continue;
        }
        out = Some(match out {
            None => bx,
            Some(o) => [
                o[0].max(bx[0]),
                o[1].max(bx[1]),
                o[2].min(bx[2]),
                o[3].min(bx[3]),
            ],
        });
    }
    out
}

/// Where [`Certifier`] puts the blocks that withheld a certificate.
pub(crate) type Missing = Vec<u64>;

impl<'a> Certifier<'a> {
    pub fn new(
        index: &'a BlockIndex,
        loaded: &'a Loaded,
        unknown: &'a std::cell::Cell<f64>,
    ) -> Self {
        Certifier {
            index,
            loaded,
            world: index.grid.world(&loaded.rect),
            unknown,
            cache: RefCell::new(Cache::default()),
            tested: std::cell::Cell::new((0, 0)),
            witnesses: 4,
            lines: None,
            mesh: None,
            tri: std::cell::Cell::new(0),
            scratch: RefCell::new(RegionScratch::default()),
        }
    }

    /// Calls `f` on each non-empty block not read in row `by`, columns `x0 ..= x1`.
    fn unread_in_row(
        &self,
        by: i64,
        x0: i64,
        x1: i64,
        f: &mut dyn FnMut(u64) -> Result<()>,
    ) -> Result<()> {
        let occ = self.index.occupied();
        let (x0, x1) = (x0.max(occ.x0), x1.min(occ.x1 - 1));
        if x1 < x0 {
            return Ok(());
        }
        let l = &self.loaded.rect;
        let spans = if by < l.y0 || by >= l.y1 || x1 < l.x0 || x0 >= l.x1 {
            [(x0, x1 + 1), (0, 0)]
        } else {
            [(x0, x1.min(l.x0 - 1) + 1), (x0.max(l.x1), x1 + 1)]
        };
        for (a, b) in spans {
            for &k in self.index.keys_in_row(by, a, b) {
                if self.loaded.extra.binary_search(&k).is_err() {
                    f(k)?;
                }
            }
        }
        Ok(())
    }

    /// Is the triangle `t` (counter-clockwise) certified: does its circumdisk, bounded by `d`,
    /// hold no point of a block not read? The blocks holding a point inside go to `out`.
    ///
    /// # Errors
    /// Reading a block's points.
    pub fn clear(&self, t: &[[f64; 2]; 3], d: &DiskBounds, out: &mut Missing) -> Result<bool> {
        let g = &self.index.grid;
        let [cx, cy] = d.center;
        let r = d.radius + g.margin(cx.abs().max(cy.abs()) + d.radius);
        if !r.is_finite() {
            return Ok(false);
        }
        let inside = |w: &[f64; 4]| cx - r >= w[0] && cx + r <= w[2] && cy - r >= w[1] && cy + r <= w[3];
        // A plan's task reads every file meeting its tile and buffer, but the loaded rectangle,
        // rounded out to whole blocks, can reach past that, into a file it did not read.
        let read = self.index.scope.as_ref().map(|sc| sc.read_rect());
        if inside(&self.world) && read.is_none_or(|w| inside(&w)) {
            return Ok(true);
        }
        // Points not read may lie in the disk: the triangle is not certified. With the hull's
        // band known, a witness among the points given settles it first (a patch run reads
        // it, instead of a wider buffer).
        let reach = self.index.scope.as_ref().map_or(0.0, |sc| sc.disk_reach([cx, cy], r));
        let band = self.index.scope.as_ref().is_some_and(|sc| sc.inner.is_some());
        if reach > 0.0 && (!band || inside(&self.world)) {
            self.unknown.set(self.unknown.get().max(reach));
            return Ok(false);
        }
        let settle = |ok: bool| {
            if ok && reach > 0.0 {
                self.unknown.set(self.unknown.get().max(reach));
                return false;
            }
            ok
        };
        if inside(&self.world) {
            return Ok(true);
        }
        // With breaklines: what the triangle's constrained edges hide, and the box of the part
        // of the disk they leave visible (the cap on the triangle's side of a chord whose centre
        // lies beyond it).
        let hidden = self.lines.map_or([false; 3], |l| l.hidden(t));
        let cap = cap_box(t, hidden, g);
        let disk = [cx - r, cy - r, cx + r, cy + r];
        let b0 = cap.unwrap_or(disk);
        let (c, r2) = ([cx, cy], r * r * (1.0 + 1e-9));
        let sight = self.sight(t, hidden, |x, y| {
            boxes_meet(&bbox(&[x, y, y]), &b0) && seg_dist2(c, x, y) <= r2
        });
        let b = match sight.region_box() {
            Some(rb) => [
                rb[0].max(b0[0]),
                rb[1].max(b0[1]),
                rb[2].min(b0[2]),
                rb[3].min(b0[3]),
            ],
            None => b0,
        };
        if let Some(l) = self.lines
            && !self.lines_clear(l, t, &sight, &b, out)
        {
            return Ok(false);
        }
        // The blocks not read whose points' box the disk reaches, nearest to the triangle's
        // centroid first, stage by stage: boxes around it growing fourfold, so that a failing
        // certificate with a huge disk (a sparse patch run's) stops at its first witnesses
        // instead of gathering every block under the disk. With breaklines, one stage: a
        // hidden edge's patch reads every block reaching its cap (see `witnesses_among`).
        let m = [
            (t[0][0] + t[1][0] + t[2][0]) / 3.0,
            (t[0][1] + t[1][1] + t[2][1]) / 3.0,
        ];
        let mut half = if self.lines.is_some() {
            f64::INFINITY
        } else {
            2.0 * g.block
        };
        let mut prev: Option<[f64; 4]> = None;
        let mut found = 0;
        loop {
            let stage = [m[0] - half, m[1] - half, m[0] + half, m[1] + half];
            let sb = [
                stage[0].max(b[0]),
                stage[1].max(b[1]),
                stage[2].min(b[2]),
                stage[3].min(b[3]),
            ];
            let near = self.gather([cx, cy], r, &sb, prev.as_ref(), m)?;
            found += self.witnesses_among(near, t, &sight, self.witnesses - found, out)?;
            let last = sb == b || !sb.iter().all(|v| v.is_finite());
            if found >= self.witnesses || last {
                return Ok(settle(found == 0));
            }
            prev = Some(sb);
            half *= 4.0;
        }
    }

    /// The blocks not read whose points' box meets the disk of centre `c` and radius `r` and
    /// the box `b` but not the box `inner` (gathered before), with their distance to `m`.
    fn gather(
        &self,
        c: [f64; 2],
        r: f64,
        b: &[f64; 4],
        inner: Option<&[f64; 4]>,
        m: [f64; 2],
    ) -> Result<Vec<(f64, u64)>> {
        let bs = self.index.grid.block;
        let occ = self.index.occupied();
        let [cx, cy] = c;
        let by0 = (((cy - r).max(b[1]) / bs).floor() as i64).max(occ.y0);
        let by1 = (((cy + r).min(b[3]) / bs).floor() as i64).min(occ.y1 - 1);
        let mut near: Vec<(f64, u64)> = Vec::new();
        for by in by0..=by1 {
            let (lo, hi) = (by as f64 * bs, (by + 1) as f64 * bs);
            let dy = if cy < lo {
                lo - cy
            } else if cy > hi {
                cy - hi
            } else {
                0.0
            };
            if dy > r {
                continue;
            }
            let hw = (r * r - dy * dy).max(0.0).sqrt() * (1.0 + 1e-12) + r * 1e-12;
            let bx0 = ((cx - hw).max(b[0]) / bs).floor() as i64;
            let bx1 = ((cx + hw).min(b[2]) / bs).floor() as i64;
            self.unread_in_row(by, bx0, bx1, &mut |k| {
                if let Some(e) = self.index.extent(k)
                    && box_dist2(&e, c) <= r * r * (1.0 + 1e-9)
                    && boxes_meet(&e, b)
                    && inner.is_none_or(|i| !boxes_meet(&e, i))
                {
                    near.push((box_dist2(&e, m), k));
                }
                Ok(())
            })?;
        }
        Ok(near)
    }

    /// What blocks the sight from `t` (no breaklines: nothing): the region of the run's
    /// triangles reachable across unconstrained edges that `meets` ([`Sight::region`]), or
    /// (a region too large) only its constrained edges.
    fn sight(
        &self,
        t: &[[f64; 2]; 3],
        hidden: [bool; 3],
        meets: impl Fn([f64; 2], [f64; 2]) -> bool,
    ) -> Sight {
        let Some(l) = self.lines else {
            return Sight::default();
        };
        let region = self
            .mesh
            .and_then(|(tri, twins)| {
                let scratch = &mut self.scratch.borrow_mut();
                Sight::region(l, tri, twins, self.tri.get(), meets, scratch)
            });
        match region {
            Some(r) => Sight::within(hidden, r),
            None => Sight::near(hidden, t, l.blockers(t)),
        }
    }

    /// The certificate within a sight's region: no point of a block not read, inside the
    /// region's box `b`, lies in the circumdisk of `t` and in the region.
    fn region_clear(
        &self,
        t: &[[f64; 2]; 3],
        sight: &Sight,
        b: &[f64; 4],
        out: &mut Missing,
    ) -> Result<bool> {
        let g = &self.index.grid;
        let occ = self.index.occupied();
        let bs = g.block;
        let by0 = ((b[1] / bs).floor() as i64).max(occ.y0);
        let by1 = ((b[3] / bs).floor() as i64).min(occ.y1 - 1);
        let m = [
            (t[0][0] + t[1][0] + t[2][0]) / 3.0,
            (t[0][1] + t[1][1] + t[2][1]) / 3.0,
        ];
        let mut near: Vec<(f64, u64)> = Vec::new();
        for by in by0..=by1 {
            let bx0 = (b[0] / bs).floor() as i64;
            let bx1 = (b[2] / bs).floor() as i64;
            self.unread_in_row(by, bx0, bx1, &mut |k| {
                if let Some(e) = self.index.extent(k)
                    && boxes_meet(&e, b)
                {
                    near.push((box_dist2(&e, m), k));
                }
                Ok(())
            })?;
        }
        Ok(self.witnesses_among(near, t, sight, self.witnesses, out)? == 0)
    }

    /// The breakline half of a certificate: no vertex the run did not load lies in the part of
    /// the circumdisk of `t` visible from it (within the box `b`), and no segment the run did
    /// not load crosses `t`. A block to read goes to `out` otherwise.
    fn lines_clear(
        &self,
        l: &RunLines,
        t: &[[f64; 2]; 3],
        sight: &Sight,
        b: &[f64; 4],
        out: &mut Missing,
    ) -> bool {
        let g = &self.index.grid;
        let missing = l.missing(t, sight, b, g, self.witnesses);
        let clear = missing.is_empty();
        out.extend(missing);
        clear
    }

    /// Tests the blocks `near` (keys with a distance), nearest first, until `limit` of them
    /// hold a point inside the circumdisk of `t`; returns how many did (the keys go to `out`).
    fn witnesses_among(
        &self,
        mut near: Vec<(f64, u64)>,
        t: &[[f64; 2]; 3],
        sight: &Sight,
        limit: usize,
        out: &mut Missing,
    ) -> Result<usize> {
        near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut found = 0;
        for &(_, k) in &near {
            if self.witness(k, t, sight)? {
                out.push(k);
                found += 1;
                if found >= limit {
                    break;
                }
            }
        }
        // Behind a constrained edge the visible part of the disk is the cap on the triangle's
        // side, and the triangle of the whole triangulation on that edge has its cap inside
        // this one (circles through the edge's ends are nested on one side): a patch that
        // reads every block reaching it settles the edge at once, instead of one witness at a
        // time along a long segment.
        if found > 0 && sight.hidden.iter().any(|&h| h) {
            out.extend(near.iter().map(|&(_, k)| k));
        }
        Ok(found)
    }

    /// The certificate of a triangle too flat for its disk to be bounded in floating point
    /// ([`crate::geom::predicates::circumdisk_bounds`] gives up). Let `a → b` be its longest
    /// edge, with `c` on its left. When the angle at `c` is obtuse (always, this flat), the
    /// circumcentre lies on the right of the line `L` through `a` and `b`, so the disk is within
    /// (1) the *chord box*: the points on or left of `L` that project into the segment `ab` and
    /// lie within `|ab| / 2` of `L` (the circular segment cut off by the chord `ab`), and (2) the
    /// open half-plane right of `L`. Blocks whose points' box meets either are tested point by
    /// point: those near the triangle first, then the rest of the half-plane, row by row.
    /// `None` when the angle at `c` cannot be shown obtuse.
    ///
    /// A bound of the disk (`disk`: a flat triangle's, whose centre is far and known only
    /// roughly) narrows both: only blocks that also meet it are tested. Along a straight data
    /// edge the bound alone can cover the whole survey, while the half-plane beyond the edge
    /// holds no block at all.
    ///
    /// # Errors
    /// Reading a block's points.
    pub fn flat_clear(
        &self,
        t: &[[f64; 2]; 3],
        disk: Option<&DiskBounds>,
        out: &mut Missing,
    ) -> Result<Option<bool>> {
        let len2 = |p: [f64; 2], q: [f64; 2]| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
        let i = (0..3)
            .max_by(|&i, &j| len2(t[i], t[(i + 1) % 3]).total_cmp(&len2(t[j], t[(j + 1) % 3])))
            .unwrap_or(0);
        let (a, b, c) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
        if !obtuse_at(a, b, c) {
            return Ok(None);
        }
        let g = &self.index.grid;
        let l = len2(a, b).sqrt();
        let mag = a[0].abs().max(a[1].abs()).max(b[0].abs()).max(b[1].abs());
        let slack = g.margin(mag + l) + l * 1e-9;
        // The disk's bound, as [`Certifier::clear`] widens it (none: everywhere).
        let bound = disk.map(|d| {
            let [cx, cy] = d.center;
            ([cx, cy], d.radius + g.margin(cx.abs().max(cy.abs()) + d.radius))
        });
        let in_bound = |e: &[f64; 4]| {
            bound.is_none_or(|(c, r)| r.is_finite() && box_dist2(e, c) <= r * r * (1.0 + 1e-9))
        };
        // The near box: the chord box (the segment `ab` moved up to `h` to the left), two
        // blocks wider (witnesses on the far side are most often close to the triangle).
        let near_box = chord_box(a, b, c, g, 2.0 * g.block);
        // The data's hull known with no corner right of `L`: nothing lies beyond it.
        let nothing_beyond = self.index.scope.as_ref().is_some_and(|sc| {
            sc.hull
                .as_ref()
                .is_some_and(|h| h.iter().all(|&p| orient(a, b, p) != Orientation::Clockwise))
        });
        let beyond = |e: &[f64; 4]| !nothing_beyond && corner_right_of(a, b, e);
        // A plan's task: a file it did not read that the chord box or the half-plane (within
        // the bound) reaches may hold a witness (hidden half-planes ignored: conservative).
        let mut flat_reach = 0.0;
        if let Some(sc) = &self.index.scope {
            let cap = chord_box(a, b, c, g, 0.0);
            let disk = bound.filter(|b| b.1.is_finite());
            let reach = sc.reach_where(|u| {
                in_bound(u)
                    && ((boxes_meet(u, &near_box)
                        && sc.might_hold(u, &Within { disk, boxed: Some(cap), right_of: None }))
                        || (beyond(u)
                            && sc.might_hold(u, &Within { disk, boxed: None, right_of: Some((a, b)) })))
            });
            if reach > 0.0 && sc.inner.is_none() {
                self.unknown.set(self.unknown.get().max(reach));
                return Ok(Some(false));
            }
            flat_reach = reach;
        }
        // With the hull's band known: points not read may lie in the disk only when no witness
        // among those given withholds the certificate.
        let settle = |ok: bool| {
            if ok && flat_reach > 0.0 {
                self.unknown.set(self.unknown.get().max(flat_reach));
                return false;
            }
            ok
        };
        // With breaklines: a constrained long edge hides the half-plane beyond it.
        let hidden = self.lines.map_or([false; 3], |l| l.hidden(t));
        let mut sight = Sight::default();
        if let Some(l) = self.lines {
            let all = [
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::INFINITY,
            ];
            let b0 = if hidden[i] { near_box } else { all };
            // The disk lies in the chord box and the open half-plane right of `a → b`.
            sight = self.sight(t, hidden, |x, y| {
                boxes_meet(&bbox(&[x, y, y]), &near_box)
                    || (!hidden[i]
                        && [x, y]
                            .iter()
                            .any(|&p| orient(a, b, p) == Orientation::Clockwise))
            });
            let b = sight.region_box().unwrap_or(b0);
            if !self.lines_clear(l, t, &sight, &b, out) {
                return Ok(Some(false));
            }
            if let Some(rb) = sight.region_box() {
                return self.region_clear(t, &sight, &rb, out).map(|ok| Some(settle(ok)));
            }
        }
        let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let occ = self.index.occupied();
        let bs = g.block;
        let rows = |lo: f64, hi: f64| {
            (
                ((lo / bs).floor() as i64).max(occ.y0),
                ((hi / bs).floor() as i64).min(occ.y1 - 1),
            )
        };
        // Near the triangle: the chord box and the half-plane.
        let mut near: Vec<(f64, u64)> = Vec::new();
        let (by0, by1) = rows(near_box[1], near_box[3]);
        for by in by0..=by1 {
            let bx0 = (near_box[0] / bs).floor() as i64;
            let bx1 = (near_box[2] / bs).floor() as i64;
            self.unread_in_row(by, bx0, bx1, &mut |k| {
                if let Some(e) = self.index.extent(k)
                    && boxes_meet(&e, &near_box)
                    && in_bound(&e)
                {
                    near.push((box_dist2(&e, m), k));
                }
                Ok(())
            })?;
        }
        if self.witnesses_among(near, t, &sight, self.witnesses, out)? > 0 {
            return Ok(Some(false));
        }
        if hidden[i] {
            return Ok(Some(settle(true)));
        }
        // The rest of the half-plane right of `L`, row by row: in each row the half-plane is
        // an interval of x (bounded conservatively).
        let d = [b[0] - a[0], b[1] - a[1]];
        let mut far: Vec<(f64, u64)> = Vec::new();
        let (fy0, fy1) = match bound {
            Some((c, r)) if r.is_finite() => rows(c[1] - r, c[1] + r),
            _ => (occ.y0, occ.y1 - 1),
        };
        for by in fy0..=fy1 {
            let (y0, y1) = (by as f64 * bs - slack, (by + 1) as f64 * bs + slack);
            let (lo, hi) = if d[1] == 0.0 {
                // Right of a horizontal line: below it going east, above it going west.
                let right = if d[0] > 0.0 { y0 <= a[1] } else { y1 >= a[1] };
                if !right {
                    continue;
                }
                (f64::NEG_INFINITY, f64::INFINITY)
            } else {
                // Where L crosses the row's edges; right of L is x > (d.y > 0) or x < that.
                let xs = [y0, y1].map(|y| a[0] + d[0] * (y - a[1]) / d[1]);
                let w = (xs[1] - xs[0]).abs() * 1e-9 + slack + bs * 1e-9;
                if d[1] > 0.0 {
                    (xs[0].min(xs[1]) - w, f64::INFINITY)
                } else {
                    (f64::NEG_INFINITY, xs[0].max(xs[1]) + w)
                }
            };
            let bx0 = if lo.is_finite() {
                (lo / bs).floor() as i64
            } else {
                occ.x0
            };
            let bx1 = if hi.is_finite() {
                (hi / bs).floor() as i64
            } else {
                occ.x1 - 1
            };
            self.unread_in_row(by, bx0, bx1, &mut |k| {
                if let Some(e) = self.index.extent(k)
                    && !boxes_meet(&e, &near_box)
                    && in_bound(&e)
                    && beyond(&e)
                {
                    far.push((box_dist2(&e, m), k));
                }
                Ok(())
            })?;
        }
        let ok = self.witnesses_among(far, t, &sight, self.witnesses, out)? == 0;
        Ok(Some(settle(ok)))
    }

    /// Does block `k` (not read) hold a point inside the circumdisk of `t`? Exact.
    fn witness(&self, k: u64, t: &[[f64; 2]; 3], sight: &Sight) -> Result<bool> {
        let mut cache = self.cache.borrow_mut();
        if !cache.blocks.contains_key(&k) {
            if cache.points > CACHE_POINTS {
                cache.blocks.clear();
                cache.points = 0;
            }
            let mut pts = Vec::new();
            self.index.read_block(k, &mut pts)?;
            cache.points += pts.len();
            cache.blocks.insert(k, pts);
        }
        let pts = &cache.blocks[&k];
        let (n, nb) = self.tested.get();
        self.tested.set((n + pts.len() as u64, nb + 1));
        Ok(pts.iter().any(|p| {
            let q = [p[0], p[1]];
            q != t[0]
                && q != t[1]
                && q != t[2]
                && incircle(t[0], t[1], t[2], q) == CircleSide::Inside
                && sight.visible(t, q)
        }))
    }
}

impl Certifier<'_> {
    /// For a task of a plan: might a point it did not read lie strictly on the right of the
    /// directed line `a → b` (the outer side of a counter-clockwise hull edge)? Points on the
    /// line do not move the hull's boundary beyond it (the triangles along it are judged by
    /// their disks). Without a scope, every point is known: `false`.
    pub fn beyond_unknown(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        let Some(sc) = &self.index.scope else {
            return false;
        };
        // The data's hull known: nothing lies right of the line when no corner does.
        if let Some(h) = &sc.hull
            && h.iter().all(|&c| orient(a, b, c) != Orientation::Clockwise)
        {
            return false;
        }
        let w = Within {
            right_of: Some((a, b)),
            ..Within::default()
        };
        let reach = sc.reach_where(|u| corner_right_of(a, b, u) && sc.might_hold(u, &w));
        self.unknown.set(self.unknown.get().max(reach));
        reach > 0.0
    }
}

/// Does a corner of the closed rectangle `e` lie strictly right of the directed line `a → b`
/// (exactly)? That is when the rectangle meets the open half-plane there.
fn corner_right_of(a: [f64; 2], b: [f64; 2], e: &[f64; 4]) -> bool {
    [[e[0], e[1]], [e[2], e[1]], [e[2], e[3]], [e[0], e[3]]]
        .into_iter()
        .any(|p| orient(a, b, p) == Orientation::Clockwise)
}

#[cfg(test)]
mod tests;
