//! What a run of a tile must get right, and the verdict on a run.
//!
//! The first run of a tile must certify every triangle that meets the tile's closed rectangle.
//! When some fail, the next run (a *patch*) is smaller: it reads the blocks around the failed
//! triangles and those their circumdisks touch, and must certify every triangle that meets the
//! union of the failed ones. The certified triangles of all runs together cover the rectangle
//! (see [`super::worker`]).

use super::certify::{Certifier, Loaded, Missing};
use super::index::BlockIndex;
use crate::geom::predicates::{DiskBounds, Orientation, circumdisk_bounds, orient};

/// A triangle in the plane.
pub(crate) type Tri2 = [[f64; 2]; 3];

/// The bounding box `[xmin, ymin, xmax, ymax]` of a triangle.
pub(crate) fn bbox(t: &Tri2) -> [f64; 4] {
    crate::geom::tri_bbox(t)
}

fn overlap(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3]
}

/// Does an edge line of the counter-clockwise triangle `t` have every corner of the rectangle
/// `r` strictly outside? (Then they do not meet: the exact half of the separating-axis test, the
/// bounding boxes being the other half.)
fn separated(t: &Tri2, r: &[f64; 4]) -> bool {
    let corners = [[r[0], r[1]], [r[2], r[1]], [r[2], r[3]], [r[0], r[3]]];
    (0..3).any(|i| {
        let (p, q) = (t[i], t[(i + 1) % 3]);
        corners
            .iter()
            .all(|&c| orient(p, q, c) == Orientation::Clockwise)
    })
}

/// Does the closed counter-clockwise triangle `t` meet the closed rectangle `r`? Exact.
pub(crate) fn tri_meets_rect(t: &Tri2, r: &[f64; 4]) -> bool {
    overlap(&bbox(t), r) && !separated(t, r)
}

/// Do two closed counter-clockwise triangles meet? Exact: they are disjoint exactly when an edge
/// line of one has the other strictly outside (separating axes of two triangles are their edges).
pub(crate) fn tris_meet(a: &Tri2, b: &Tri2) -> bool {
    let outside = |t: &Tri2, u: &Tri2| {
        (0..3).any(|i| {
            let (p, q) = (t[i], t[(i + 1) % 3]);
            u.iter().all(|&c| orient(p, q, c) == Orientation::Clockwise)
        })
    };
    !outside(a, b) && !outside(b, a)
}

/// Side of the bucket grid over the failed triangles.
const CELLS: usize = 64;

/// Failed triangles of an earlier run, bucketed by bounding box.
#[derive(Debug, Clone)]
pub(crate) struct Tris {
    bbox: [f64; 4],
    tris: Vec<Tri2>,
    cells: Vec<Vec<u32>>,
}

/// The part of the plane whose triangles a run must certify: the tile's closed rectangle
/// (widened by the rounding margin), and for a patch run also the union of the closed triangles
/// the earlier runs failed. A triangle must be certified when it meets both; the certified
/// triangles of all runs then cover the rectangle (see [`super::worker`]). With covering needs,
/// the triangles in an open rectangle inside the tile that the needs do not want are left out
/// (`skip`; see [`super::worker`], "Covering needs").
#[derive(Debug, Clone)]
pub(crate) struct Region<'a> {
    pub rect: [f64; 4],
    pub failed: Option<Tris>,
    pub skip: Option<(&'a crate::sink::Needs, [f64; 4])>,
}

impl Tris {
    /// The union of the closed triangles `tris` (not empty).
    pub fn new(tris: Vec<Tri2>) -> Tris {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for t in &tris {
            let tb = bbox(t);
            b = [
                b[0].min(tb[0]),
                b[1].min(tb[1]),
                b[2].max(tb[2]),
                b[3].max(tb[3]),
            ];
        }
        let mut cells = vec![Vec::new(); CELLS * CELLS];
        for (i, t) in tris.iter().enumerate() {
            let (cx0, cy0, cx1, cy1) = cell_range_of(&b, &bbox(t));
            for cy in cy0..=cy1 {
                for cx in cx0..=cx1 {
                    cells[cy * CELLS + cx].push(i as u32);
                }
            }
        }
        Tris {
            bbox: b,
            tris,
            cells,
        }
    }

    /// Does triangle `t` (with bounding box `tb`) meet one of them? Exact.
    fn meets(&self, t: &Tri2, tb: &[f64; 4]) -> bool {
        if !overlap(tb, &self.bbox) {
            return false;
        }
        let (cx0, cy0, cx1, cy1) = cell_range_of(&self.bbox, tb);
        for cy in cy0..=cy1 {
            for cx in cx0..=cx1 {
                for &i in &self.cells[cy * CELLS + cx] {
                    let f = &self.tris[i as usize];
                    if overlap(tb, &bbox(f)) && tris_meet(t, f) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// The cells of the grid over `all` that the box `b` covers (clamped), inclusive.
fn cell_range_of(all: &[f64; 4], b: &[f64; 4]) -> (usize, usize, usize, usize) {
    let w = (all[2] - all[0]).max(f64::MIN_POSITIVE);
    let h = (all[3] - all[1]).max(f64::MIN_POSITIVE);
    let c = |v: f64, lo: f64, span: f64| -> usize {
        (((v - lo) / span * CELLS as f64).floor().max(0.0) as usize).min(CELLS - 1)
    };
    (
        c(b[0], all[0], w),
        c(b[1], all[1], h),
        c(b[2], all[0], w),
        c(b[3], all[1], h),
    )
}

impl Region<'_> {
    /// Does triangle `t` meet the region? (Exact, the rectangle being widened by its margin.)
    pub fn meets(&self, t: &Tri2) -> bool {
        let tb = bbox(t);
        let r = &self.rect;
        if !overlap(&tb, r) {
            return false;
        }
        let within = tb[0] >= r[0] && tb[2] <= r[2] && tb[1] >= r[1] && tb[3] <= r[3];
        if !within && separated(t, r) {
            return false;
        }
        self.failed.as_ref().is_none_or(|f| f.meets(t, &tb))
    }

    /// The bounding box of what must be certified.
    pub fn bbox(&self) -> [f64; 4] {
        let r = self.rect;
        match &self.failed {
            None => r,
            Some(f) => {
                let b = f.bbox;
                [
                    r[0].max(b[0]),
                    r[1].max(b[1]),
                    r[2].min(b[2]),
                    r[3].min(b[3]),
                ]
            }
        }
    }
}

/// What a run got right and what it did not.
#[derive(Debug, Default)]
pub(crate) struct Verdict {
    /// Triangles (indices into the run's triangles) that meet the region and are certified.
    pub certified: Vec<u32>,
    /// Triangles that meet the region and are not.
    pub failed: Vec<u32>,
    /// Blocks not read holding a point inside a failed triangle's circumdisk: the next run
    /// must read them.
    pub blocks: Missing,
    /// A failed triangle too thin for its disk to be bounded: the next run doubles its buffer.
    pub degenerate: bool,
    /// A certificate reached beyond what a plan's task read: the task needs a wider buffer.
    /// (0: it did not.) The buffer that reads the files it reached.
    pub unknown: f64,
    /// Points (and blocks) tested one by one against disks that left the loaded blocks.
    pub tested: (u64, u64),
}

/// Judges the run `t` over `loaded` on `region` (the tile's `run`-th), with the breaklines it
/// loaded and the run's adjacency (`lines`). A run over every non-empty block and every segment
/// (`full`) is the whole triangulation: everything in it is certified. The region's `skip`
/// leaves some triangles unjudged ([`Region`]).
///
/// # Errors
/// Reading the points of blocks not loaded.
pub(crate) fn judge(
    index: &BlockIndex,
    t: &crate::Triangulation,
    region: &Region,
    loaded: &Loaded,
    full: bool,
    run: u32,
    lines: Option<(&super::lines::RunLines, &[u32])>,
) -> crate::error::Result<Verdict> {
    let unknown = std::cell::Cell::new(0.0);
    let mut cert = Certifier::new(index, loaded, &unknown);
    cert.witnesses = 4usize << run.saturating_sub(1).min(8);
    cert.lines = lines.map(|l| l.0);
    cert.mesh = lines.map(|l| (t, l.1));
    let v = &t.vertices;
    let mut out = Verdict::default();
    // A DEM's test from each vertex's place among the centres, computed once per vertex.
    let centres = region.skip.and_then(|(needs, _)| needs.centres());
    let keys: Vec<[i32; 4]> = centres.map_or_else(Vec::new, |g| {
        v.iter().map(|p| g.lattice_keys(p)).collect()
    });
    for (k, tri) in t.triangles.iter().enumerate() {
        let t2: Tri2 = tri.map(|i| [v[i as usize][0], v[i as usize][1]]);
        if !region.meets(&t2) {
            continue;
        }
        if let Some((needs, r)) = region.skip
            && strictly_inside(&t2, &r)
            && !match centres {
                Some(g) => g.keys_hold_centre(tri.map(|i| keys[i as usize])),
                None => needs.wants(&tri.map(|i| v[i as usize])),
            }
        {
            continue;
        }
        if full {
            out.certified.push(k as u32);
            continue;
        }
        cert.tri.set(k as u32);
        let ok = match circumdisk_bounds(t2[0], t2[1], t2[2]) {
            Some(d) if lines.is_some() || !flat(&t2, &d) => cert.clear(&t2, &d, &mut out.blocks)?,
            d => match (cert.flat_clear(&t2, d.as_ref(), &mut out.blocks)?, d) {
                (Some(ok), _) => ok,
                (None, Some(d)) => cert.clear(&t2, &d, &mut out.blocks)?,
                (None, None) => {
                    out.degenerate = true;
                    false
                }
            },
        };
        if ok {
            out.certified.push(k as u32);
        } else {
            out.failed.push(k as u32);
        }
    }
    out.blocks.sort_unstable();
    out.blocks.dedup();
    // A task does not hold the corners of the whole hull: the parts of the region outside the
    // run's hull are outside the whole hull only if nothing unread lies beyond its edges.
    if index.scope.is_some() && !full {
        hull_unknown(&cert, v, region);
    }
    out.unknown = unknown.get();
    out.tested = cert.tested.get();
    Ok(out)
}

/// Does the triangle `t` lie in the open rectangle `r`?
fn strictly_inside(t: &Tri2, r: &[f64; 4]) -> bool {
    let b = bbox(t);
    b[0] > r[0] && b[1] > r[1] && b[2] < r[2] && b[3] < r[3]
}

/// Is `t` flat for its disk: a radius (bound) over 16 times its longest edge? Its disk is then
/// judged as a flat triangle's ([`Certifier::flat_clear`]: the cap on its long edge and the
/// half-plane beyond it), within the bound; not with breaklines, whose sight over a half-plane
/// costs more than the disk's.
fn flat(t: &Tri2, d: &DiskBounds) -> bool {
    let len2 = |p: [f64; 2], q: [f64; 2]| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
    let l2 = len2(t[0], t[1]).max(len2(t[1], t[2])).max(len2(t[2], t[0]));
    d.radius * d.radius > 256.0 * l2
}

/// Might an unread point lie beyond an edge of the convex hull of `v` whose outer half-plane
/// meets the region's box? (Sets the certifier's `unknown`.)
fn hull_unknown(cert: &Certifier, v: &[[f64; 3]], region: &Region) -> bool {
    let r = region.bbox();
    let hull = super::hull::hull_of(v);
    let corners = [[r[0], r[1]], [r[2], r[1]], [r[2], r[3]], [r[0], r[3]]];
    for i in 0..hull.len() {
        let a = [hull[i][0], hull[i][1]];
        let j = &hull[(i + 1) % hull.len()];
        let b = [j[0], j[1]];
        let meets = corners
            .iter()
            .any(|&c| orient(a, b, c) != Orientation::CounterClockwise);
        if meets && cert.beyond_unknown(a, b) {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions() {
        let r = Region {
            rect: [0.0, 0.0, 10.0, 10.0],
            failed: None,
            skip: None,
        };
        assert!(r.meets(&[[1.0, 1.0], [2.0, 1.0], [1.0, 2.0]]));
        // Bounding boxes overlap, the triangle does not reach the square.
        assert!(!r.meets(&[[11.0, 5.0], [5.0, 11.0], [11.0, 11.0]]));
        assert!(r.meets(&[[10.0, 5.0], [20.0, 5.0], [20.0, 6.0]]));
        let f = Region {
            rect: [-1e3, -1e3, 1e3, 1e3],
            skip: None,
            failed: Some(Tris::new(vec![
                [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                [[100.0, 100.0], [101.0, 100.0], [100.0, 101.0]],
            ])),
        };
        assert!(f.meets(&[[0.5, 0.5], [3.0, 0.5], [0.5, 3.0]]));
        assert!(!f.meets(&[[50.0, 50.0], [51.0, 50.0], [50.0, 51.0]]));
        assert!(f.meets(&[[99.0, 99.0], [101.0, 99.0], [99.0, 101.0]]));
        // Boxes overlap, triangles do not.
        assert!(!f.meets(&[[0.6, 0.6], [2.0, 0.6], [0.6, 2.0]]));
        assert!(f.meets(&[[0.5, 0.5], [2.0, 0.5], [0.5, 2.0]]));
    }
}
