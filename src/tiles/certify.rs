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
//! The convex hull needs no certificate of its own: every run also holds the corners of the hull
//! of all the points ([`super::hull`]), so a run's hull *is* the whole hull, and what lies
//! outside it lies outside the whole triangulation.

use super::grid::BlockRect;
use super::index::BlockIndex;
use crate::error::Result;
use crate::geom::predicates::{CircleSide, DiskBounds, incircle};
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

/// Cached points beyond which the cache starts afresh.
const CACHE_POINTS: usize = 1 << 20;

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
}

/// Witness blocks a failed certificate reports at most.
const WITNESSES: usize = 4;

/// Squared distance from `p` to the box `e` (`[xmin, ymin, xmax, ymax]`).
#[inline]
fn box_dist2(e: &[f64; 4], p: [f64; 2]) -> f64 {
    let dx = (e[0] - p[0]).max(p[0] - e[2]).max(0.0);
    let dy = (e[1] - p[1]).max(p[1] - e[3]).max(0.0);
    dx * dx + dy * dy
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
        let w = &self.world;
        if cx - r >= w[0] && cx + r <= w[2] && cy - r >= w[1] && cy + r <= w[3] {
            return Ok(true);
        }
        if let Some(sc) = &self.index.scope
            && let reach = sc.disk_reach([cx, cy], r)
            && reach > 0.0
        {
            self.unknown.set(self.unknown.get().max(reach));
            return Ok(false);
        }
        let occ = self.index.occupied();
        let b = g.block;
        let by0 = (((cy - r) / b).floor() as i64).max(occ.y0);
        let by1 = (((cy + r) / b).floor() as i64).min(occ.y1 - 1);
        // The blocks not read whose points' box the disk reaches, nearest to the triangle first.
        let mut near: Vec<(f64, u64)> = Vec::new();
        let m = [
            (t[0][0] + t[1][0] + t[2][0]) / 3.0,
            (t[0][1] + t[1][1] + t[2][1]) / 3.0,
        ];
        for by in by0..=by1 {
            let (lo, hi) = (by as f64 * b, (by + 1) as f64 * b);
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
            let bx0 = ((cx - hw) / b).floor() as i64;
            let bx1 = ((cx + hw) / b).floor() as i64;
            self.unread_in_row(by, bx0, bx1, &mut |k| {
                if let Some(e) = self.index.extent(k)
                    && box_dist2(&e, [cx, cy]) <= r * r * (1.0 + 1e-9)
                {
                    near.push((box_dist2(&e, m), k));
                }
                Ok(())
            })?;
        }
        if near.is_empty() {
            return Ok(true);
        }
        near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        // A few witnesses are enough for the next run to make progress; a disk that a sparse
        // patch run left huge may hold points of thousands of blocks.
        let mut found = 0;
        for &(_, k) in &near {
            if self.witness(k, t)? {
                out.push(k);
                found += 1;
                if found == WITNESSES {
                    break;
                }
            }
        }
        Ok(found == 0)
    }

    /// Does block `k` (not read) hold a point inside the circumdisk of `t`? Exact.
    fn witness(&self, k: u64, t: &[[f64; 2]; 3]) -> Result<bool> {
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
        }))
    }
}

impl Certifier<'_> {
    /// For a task of a plan: might a point it did not read lie strictly on the right of the
    /// directed line `a → b` (the outer side of a counter-clockwise hull edge)? Points on the
    /// line do not move the hull's boundary beyond it (the triangles along it are judged by
    /// their disks). Without a scope, every point is known: `false`.
    pub fn beyond_unknown(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        use crate::geom::predicates::{Orientation, orient};
        let Some(sc) = &self.index.scope else {
            return false;
        };
        let reach = sc
            .unknown
            .iter()
            .filter(|u| {
                [[u[0], u[1]], [u[2], u[1]], [u[2], u[3]], [u[0], u[3]]]
                    .into_iter()
                    .any(|c| orient(a, b, c) == Orientation::Clockwise)
            })
            .map(|u| sc.reach(u))
            .fold(0.0, f64::max);
        self.unknown.set(self.unknown.get().max(reach));
        reach > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sort::external::ExternalSorter;
    use crate::tiles::grid::TileGrid;
    use crate::tiles::index::BlockRecord;

    fn index(pts: &[[f64; 2]]) -> BlockIndex {
        let dir = tempfile::tempdir().unwrap();
        let grid = TileGrid::new(8.0, 3).unwrap();
        let mut s = ExternalSorter::<BlockRecord>::new(1 << 20, dir.path());
        for p in pts {
            let (bx, by) = grid.block_of(p[0], p[1]);
            s.push(BlockRecord {
                key: TileGrid::key(bx, by),
                x: p[0],
                y: p[1],
                z: 0.0,
            })
            .unwrap();
        }
        BlockIndex::build(
            grid,
            s.finish().unwrap(),
            dir.path(),
            crate::sort::DuplicatePolicy::First,
        )
        .unwrap()
    }

    fn bounds(t: &[[f64; 2]; 3]) -> DiskBounds {
        crate::geom::predicates::circumdisk_bounds(t[0], t[1], t[2]).unwrap()
    }

    #[test]
    fn disks() {
        // Points at the integer lattice 0..20 × 0..20, except a hole at x, y in 8..12.
        let mut pts = Vec::new();
        for y in 0..20 {
            for x in 0..20 {
                if !(8..12).contains(&x) || !(8..12).contains(&y) {
                    pts.push([x as f64 + 0.5, y as f64 + 0.5]);
                }
            }
        }
        let ix = index(&pts);
        let loaded = Loaded {
            rect: BlockRect {
                x0: 4,
                y0: 4,
                x1: 16,
                y1: 16,
            },
            extra: vec![],
        };
        let unknown = std::cell::Cell::new(0.0);
        let c = Certifier::new(&ix, &loaded, &unknown);
        let mut m = Missing::new();
        // A small triangle well inside the loaded blocks.
        let t = [[9.0, 9.0], [11.0, 9.0], [10.0, 11.0]];
        assert!(c.clear(&t, &bounds(&t), &mut m).unwrap());
        // A wide one over the lower-left outside corner: lattice points there lie in its disk.
        let t = [[2.0, 2.0], [6.0, 2.0], [4.0, 6.0]];
        assert!(!c.clear(&t, &bounds(&t), &mut m).unwrap());
        assert!(!m.is_empty());
        for k in &m {
            let (bx, by) = TileGrid::unkey(*k);
            assert!(!loaded.rect.contains(bx, by));
        }
        // A disk that reaches unread blocks only where no point lies in it (the lattice points
        // around are outside the circle through these three): certified.
        let t = [[3.9, 10.0], [4.3, 9.8], [4.3, 10.2]];
        let mut m2 = Missing::new();
        assert!(c.clear(&t, &bounds(&t), &mut m2).unwrap());
        assert!(m2.is_empty());
        // A flat triangle along the lattice's bottom row: its disk is huge, but the lattice
        // points keep out of it, one by one.
        let t = [[0.5, 0.5], [1.5, 0.5], [1.0, 0.5 + 1e-7]];
        let before = c.tested.get().0;
        assert!(c.clear(&t, &bounds(&t), &mut m2).unwrap());
        assert!(c.tested.get().0 > before);
        // Outside the data everything is empty.
        let t = [[40.0, 40.0], [45.0, 40.0], [42.0, 44.0]];
        assert!(c.clear(&t, &bounds(&t), &mut m2).unwrap());
        // With the witness blocks read, the corner triangle is certified.
        m.sort_unstable();
        m.dedup();
        let more = Loaded {
            rect: loaded.rect,
            extra: m.clone(),
        };
        let t = [[2.0, 2.0], [6.0, 2.0], [4.0, 6.0]];
        let mut m3 = Missing::new();
        let c2 = Certifier::new(&ix, &more, &unknown);
        // Still not certified as a *triangle* (points of the read blocks lie in it), but no
        // unread block is a witness any more.
        let _ = c2.clear(&t, &bounds(&t), &mut m3).unwrap();
        assert!(m3.iter().all(|k| !m.contains(k)));
    }
}
