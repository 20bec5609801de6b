//! Certificates: which triangles of a tile's run are triangles of the triangulation of *all*
//! points.
//!
//! A tile's run triangulates the points of a rectangle of blocks (the *loaded* blocks). A
//! triangle of that run is Delaunay for the loaded points: its closed circumdisk holds no other
//! loaded point (ties go by the global rule of [`crate::geom::predicates`], which depends on
//! positions only). If the disk also reaches no point outside the loaded blocks, it holds no point
//! at all, so the triangle is a triangle of the whole triangulation: it is **certified**. The test
//! is conservative: the disk is the floating-point bound of [`crate::geom::predicates::circumdisk_bounds`]
//! (never smaller than the true disk), widened by the rounding of the block assignment, and it
//! asks the block index whether any *block* it touches outside the loaded ones holds a point. An
//! error can only withhold a certificate, never grant a wrong one.
//!
//! The convex hull needs no certificate of its own: every run also holds the corners of the hull
//! of all the points ([`super::hull`]), so a run's hull *is* the whole hull, and what lies
//! outside it lies outside the whole triangulation.

use super::grid::BlockRect;
use super::index::BlockIndex;

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

/// Answers certificate questions for one run over the `loaded` blocks.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Certifier<'a> {
    index: &'a BlockIndex,
    loaded: &'a Loaded,
    /// World rectangle of the loaded rectangle.
    world: [f64; 4],
    /// Set when a test reached beyond what a plan's task read (see [`BlockIndex::scope`]).
    /// The widest buffer an unread file needs (0: none).
    pub unknown: &'a std::cell::Cell<f64>,
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
        }
    }

    /// Adds to `out` the non-empty blocks of row `by`, columns `x0 ..= x1` (only those not read
    /// unless `all`); returns whether there was any.
    fn blocks_in_row(&self, by: i64, x0: i64, x1: i64, all: bool, out: &mut Missing) -> bool {
        let occ = self.index.occupied();
        let (x0, x1) = (x0.max(occ.x0), x1.min(occ.x1 - 1));
        if x1 < x0 {
            return false;
        }
        let l = &self.loaded.rect;
        let spans = if all || by < l.y0 || by >= l.y1 || x1 < l.x0 || x0 >= l.x1 {
            [(x0, x1 + 1), (0, 0)]
        } else {
            [(x0, x1.min(l.x0 - 1) + 1), (x0.max(l.x1), x1 + 1)]
        };
        let before = out.len();
        for (a, b) in spans {
            for &k in self.index.keys_in_row(by, a, b) {
                if all || self.loaded.extra.binary_search(&k).is_err() {
                    out.push(k);
                }
            }
        }
        out.len() > before
    }

    /// Is the closed disk of `center` and `radius` (an upper bound of the true radius) free of
    /// points outside the loaded blocks? The blocks that hold such points go to `out`.
    pub fn disk_clear(&self, center: [f64; 2], radius: f64, out: &mut Missing) -> bool {
        self.disk_blocks(center, radius, false, out)
    }

    /// Adds to `out` every non-empty block the closed disk touches (read or not): what a run that
    /// must get this disk right has to read.
    pub fn touched(&self, center: [f64; 2], radius: f64, out: &mut Missing) {
        self.disk_blocks(center, radius, true, out);
    }

    fn disk_blocks(&self, center: [f64; 2], radius: f64, all: bool, out: &mut Missing) -> bool {
        let g = &self.index.grid;
        let [cx, cy] = center;
        let r = radius + g.margin(cx.abs().max(cy.abs()) + radius);
        if !r.is_finite() {
            return false;
        }
        let w = &self.world;
        if !all && cx - r >= w[0] && cx + r <= w[2] && cy - r >= w[1] && cy + r <= w[3] {
            return true;
        }
        if let Some(sc) = &self.index.scope
            && let reach = sc.disk_reach([cx, cy], r)
            && reach > 0.0
        {
            self.unknown.set(self.unknown.get().max(reach));
            return false;
        }
        let occ = self.index.occupied();
        let b = g.block;
        let by0 = (((cy - r) / b).floor() as i64).max(occ.y0);
        let by1 = (((cy + r) / b).floor() as i64).min(occ.y1 - 1);
        let mut clear = true;
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
            if self.blocks_in_row(by, bx0, bx1, all, out) {
                clear = false;
            }
        }
        clear
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
        BlockIndex::build(grid, s.finish().unwrap(), dir.path()).unwrap()
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
        assert!(c.disk_clear([10.0, 10.0], 5.9, &mut m));
        assert!(!c.disk_clear([10.0, 10.0], 6.6, &mut m));
        // The hole is empty, so a disk reaching into it from a loaded side is clear.
        assert!(c.disk_clear([6.0, 10.0], 1.5, &mut m));
        // The lower-left outside corner has points.
        assert!(!c.disk_clear([4.0, 4.0], 0.8, &mut m));
        // Outside the data everything is empty.
        assert!(c.disk_clear([40.0, 40.0], 5.0, &mut m));
        let everything = Loaded {
            rect: ix.occupied(),
            extra: vec![],
        };
        let all = Certifier::new(&ix, &everything, &unknown);
        assert!(all.disk_clear([10.0, 10.0], 1e6, &mut m));
        // What withheld the certificates: blocks outside the loaded rectangle only.
        assert!(!m.is_empty());
        for k in &m {
            let (bx, by) = TileGrid::unkey(*k);
            assert!(!loaded.rect.contains(bx, by));
        }
        // With those blocks read, the corner disk is clear.
        m.sort_unstable();
        m.dedup();
        let more = Loaded {
            rect: loaded.rect,
            extra: m.clone(),
        };
        let mut m2 = Missing::new();
        assert!(Certifier::new(&ix, &more, &unknown).disk_clear([4.0, 4.0], 0.8, &mut m2));
    }
}
