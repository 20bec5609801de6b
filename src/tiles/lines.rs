//! Breaklines in exact tiles: the cleaned graph of the run (held in memory, as the sweep holds
//! it), the segments a tile's run loads, and the two checks a certificate needs for the others
//! (the rule and its proof are in [`super::worker`]).
//!
//! A run *loads* every segment that meets the world rectangle of one of its blocks (grown by the
//! grid's rounding margin, so that it holds every point assigned to those blocks), whole, with
//! both endpoints, wherever they lie; and every graph vertex inside those rectangles. A vertex
//! the run did not load lies outside them, so a circumdisk inside the loaded rectangle holds
//! none, and a triangle inside it meets no segment the run did not load: the certificate's fast
//! path stays valid. The slow path asks [`RunLines::witness`] and [`RunLines::crossing`].
//!
//! A graph vertex at exactly the position of a lidar point is one vertex whose `z` follows
//! `--duplicates` with the line read after every point (as in the sweep): [`TileLines::merge`]
//! settles that `z` once, so every run gives the vertex the same `z` whether or not it loaded the
//! point.

use super::grid::{BlockRect, TileGrid};
use super::index::BlockIndex;
use super::region::{Tri2, bbox, tri_meets_rect};
use crate::error::Result;
use crate::geom::grid::{Buckets, Grid};
use crate::geom::predicates::{CircleSide, Orientation, incircle, on_segment, orient};
use crate::idmap::FastMap;
use crate::sort::DuplicatePolicy;

/// The breakline graph of a tiled run (cleaned, every `z` known), bucketed for queries.
#[derive(Debug)]
pub(crate) struct TileLines {
    /// Vertices `[x, y, z]`.
    pub vertices: Vec<[f64; 3]>,
    /// Segments (vertex pairs).
    pub segments: Vec<[u32; 2]>,
    xy: Vec<[f64; 2]>,
    bbox: Option<[f64; 4]>,
    grid: Grid,
    segs: Buckets,
    verts: Buckets,
}

impl TileLines {
    /// The graph of `vertices` and `segments` (a planar graph: see [`crate::breaklines::clean`]).
    pub fn new(vertices: &[[f64; 3]], segments: &[[u32; 2]]) -> TileLines {
        // As the sweep sees them: -0 is 0.
        let vertices: Vec<[f64; 3]> = vertices
            .iter()
            .map(|v| [v[0] + 0.0, v[1] + 0.0, v[2]])
            .collect();
        let xy: Vec<[f64; 2]> = vertices.iter().map(|v| [v[0], v[1]]).collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &xy {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if xy.is_empty() {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        let grid = Grid::new(lo, hi, segments.len().max(xy.len()));
        let segs = Buckets::segments(&grid, &xy, segments);
        let verts = Buckets::points(&grid, &xy);
        let bbox = (!xy.is_empty()).then_some([lo[0], lo[1], hi[0], hi[1]]);
        TileLines {
            vertices,
            segments: segments.to_vec(),
            xy,
            bbox,
            grid,
            segs,
            verts,
        }
    }

    /// The bounding box of the vertices `[xmin, ymin, xmax, ymax]` (`None` without vertices).
    pub fn bounds(&self) -> Option<[f64; 4]> {
        self.bbox
    }

    /// The blocks of the vertices, as a rectangle (empty without vertices).
    pub fn blocks(&self, g: &TileGrid) -> BlockRect {
        let mut r = BlockRect {
            x0: i64::MAX,
            y0: i64::MAX,
            x1: i64::MIN,
            y1: i64::MIN,
        };
        for p in &self.xy {
            let (bx, by) = g.block_of(p[0], p[1]);
            r = BlockRect {
                x0: r.x0.min(bx),
                y0: r.y0.min(by),
                x1: r.x1.max(bx + 1),
                y1: r.y1.max(by + 1),
            };
        }
        r
    }


    /// Gives each vertex at exactly the position of a point of `index` the `z` that
    /// `--duplicates` keeps, the line counting as read after every point.
    ///
    /// # Errors
    /// Reading the index.
    pub fn merge(&mut self, index: &BlockIndex, policy: DuplicatePolicy) -> Result<()> {
        let g = index.grid;
        let mut order: Vec<(u64, u32)> = self
            .xy
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (bx, by) = g.block_of(p[0], p[1]);
                (TileGrid::key(bx, by), i as u32)
            })
            .collect();
        order.sort_unstable();
        let mut pts = Vec::new();
        let mut at: FastMap<(u64, u64), f64> = FastMap::default();
        let mut block = None;
        for (k, i) in order {
            if block != Some(k) {
                block = Some(k);
                pts.clear();
                index.read_block(k, &mut pts)?;
                at.clear();
                at.extend(
                    pts.iter()
                        .map(|p| (((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()), p[2])),
                );
            }
            let v = &mut self.vertices[i as usize];
            if let Some(&z) = at.get(&(v[0].to_bits(), v[1].to_bits()))
                && !policy.prefers((v[2], 1), (z, 0))
            {
                v[2] = z;
            }
        }
        Ok(())
    }

    /// The `z` of the vertex at exactly `(x, y)`, if there is one.
    pub fn z_at(&self, p: [f64; 2]) -> Option<f64> {
        let p = [p[0] + 0.0, p[1] + 0.0];
        self.verts
            .cell(self.grid.cell_of(p))
            .iter()
            .map(|&v| v as usize)
            .find(|&v| self.xy[v] == p)
            .map(|v| self.vertices[v][2])
    }

    /// What a run over the blocks of `rect` and `extra` loads.
    pub fn run(&self, g: &TileGrid, rect: &BlockRect, extra: &[u64]) -> RunLines<'_> {
        let mut run = RunLines {
            lines: self,
            seg: vec![false; self.segments.len()],
            vert: vec![false; self.xy.len()],
        };
        let mut rects = Vec::with_capacity(extra.len() + 1);
        if !rect.is_empty() {
            rects.push(*rect);
        }
        rects.extend(extra.iter().map(|&k| {
            let (bx, by) = TileGrid::unkey(k);
            BlockRect {
                x0: bx,
                y0: by,
                x1: bx + 1,
                y1: by + 1,
            }
        }));
        for r in &rects {
            let w = g.world(r);
            let m = g.margin(w.iter().fold(0.0f64, |m, v| m.max(v.abs())));
            let w = [w[0] - m, w[1] - m, w[2] + m, w[3] + m];
            let (lo, hi) = ([w[0], w[1]], [w[2], w[3]]);
            // Cells are clamped into the grid: skip rectangles that miss it.
            let Some(gb) = self.bbox else { break };
            if w[2] < gb[0] || w[0] > gb[2] || w[3] < gb[1] || w[1] > gb[3] {
                continue;
            }
            self.grid.box_cells(lo, hi, |c| {
                for &s in self.segs.cell(c) {
                    if !run.seg[s as usize] {
                        let [a, b] = self.segments[s as usize].map(|v| self.xy[v as usize]);
                        if tri_meets_rect(&[a, b, b], &w) {
                            run.seg[s as usize] = true;
                        }
                    }
                }
                for &v in self.verts.cell(c) {
                    let p = self.xy[v as usize];
                    if p[0] >= w[0] && p[0] <= w[2] && p[1] >= w[1] && p[1] <= w[3] {
                        run.vert[v as usize] = true;
                    }
                }
            });
        }
        for (s, _) in run.seg.iter().enumerate().filter(|(_, l)| **l) {
            for v in self.segments[s] {
                run.vert[v as usize] = true;
            }
        }
        run
    }
}

/// What one run of a tile loaded of the breaklines.
#[derive(Debug)]
pub(crate) struct RunLines<'a> {
    lines: &'a TileLines,
    seg: Vec<bool>,
    vert: Vec<bool>,
}

/// What blocks the sight from the interior of a counter-clockwise triangle `t` of a run: its
/// constrained edges (`hidden[k]` for the edge from `t[k]` to `t[k + 1]`) and the run's other
/// constrained edges, through the region of the run's triangles that sight lines inside the
/// circumdisk can reach. Only points visible from `t` can withhold its certificate; a
/// constrained edge of the run is a piece of an input segment, so what it hides in the run it
/// hides in the whole triangulation.
#[derive(Debug, Default)]
pub(crate) struct Sight {
    pub hidden: [bool; 3],
    /// Loaded segments near the triangle, tested when there is no region.
    blockers: Vec<([[f64; 2]; 2], Orientation)>,
    /// The blocker that hid the last point hidden by one (tried first: the points of a block
    /// lie together, behind the same segment).
    last: std::cell::Cell<usize>,
    /// The triangles of the run reachable from `t` across unconstrained edges within the
    /// circumdisk (see [`Sight::within`]); their bounding box.
    region: Option<Region>,
}

/// What [`Sight::region`] reuses from one triangle's region to the next over a run: a mark per
/// triangle (the region's number when it reached it) and whether each edge is constrained
/// (0: not known yet, 1: no, 2: yes; an edge and its twin alike).
#[derive(Debug, Default)]
pub(crate) struct RegionScratch {
    stamp: Vec<u32>,
    region: u32,
    constrained: Vec<u8>,
}

impl RegionScratch {
    /// The number of a new region over a run of `triangles` triangles.
    fn next(&mut self, triangles: usize) -> u32 {
        if self.stamp.len() != triangles || self.region == u32::MAX {
            self.stamp = vec![0; triangles];
            self.constrained = vec![0; 3 * triangles];
            self.region = 0;
        }
        self.region += 1;
        self.region
    }

    /// Is the edge `x-y` (half-edge `h`, twin `tw`) on a loaded segment?
    fn constrained(&mut self, lines: &RunLines, h: usize, tw: u32, x: [f64; 2], y: [f64; 2]) -> bool {
        if self.constrained[h] == 0 {
            let c = 1 + u8::from(lines.constrained(x, y));
            self.constrained[h] = c;
            self.constrained[tw as usize] = c;
        }
        self.constrained[h] == 2
    }
}

/// The triangles of a [`Sight::region`], bucketed by bounding box.
#[derive(Debug)]
struct Region {
    tris: Vec<Tri2>,
    bbox: [f64; 4],
    /// The grid over the box and its buckets, built when a point is first tested: most disks
    /// hold no point of an unread block, so no point is (Delft + BGT in tiles: 6,000 of 33,800
    /// regions were ever queried).
    buckets: std::cell::OnceCell<(Grid, Buckets)>,
}

impl Region {
    fn buckets(&self) -> &(Grid, Buckets) {
        self.buckets.get_or_init(|| {
            let a = self.bbox;
            let grid = Grid::new([a[0], a[1]], [a[2], a[3]], self.tris.len());
            let buckets = Buckets::counted(grid.len(), self.tris.len(), |i, f| {
                let b = bbox(&self.tris[i]);
                grid.box_cells([b[0], b[1]], [b[2], b[3]], f)
            });
            (grid, buckets)
        })
    }
}

/// Triangles a [`Sight::within`] region holds at most (beyond, only the constrained edges of
/// the triangle hide: the wide disks of slivers along the hull, whose part inside the data is
/// thin, are tested point by point).
pub(crate) const REGION_MAX: usize = 4096;

impl Sight {
    /// A sight hidden by the triangle's own constrained edges and the loaded segments near
    /// it (see [`RunLines::blockers`]).
    pub fn near(hidden: [bool; 3], t: &Tri2, blockers: Vec<[[f64; 2]; 2]>) -> Sight {
        let blockers = blockers
            .into_iter()
            .filter_map(|[u, v]| far_side(u, v, t).map(|s| ([u, v], s)))
            .collect();
        Sight {
            hidden,
            blockers,
            last: Default::default(),
            region: None,
        }
    }
    /// The sight from triangle `k` of the run `tri` (with `twins`, its adjacency): the run's
    /// triangles reachable from it across edges that are not constrained and that `meets` (a
    /// closed region holding the circumdisk). A point visible from `t` inside the disk lies in
    /// one of them: its sight line stays in the disk (convex), crosses no constrained edge (a
    /// segment of the input), and passes no vertex of the run (that vertex would lie in the
    /// disk, visible, against `t` being constrained Delaunay in the run), so it goes from
    /// triangle to triangle across unconstrained edges, each crossed inside the disk. `None`
    /// beyond [`REGION_MAX`] triangles.
    pub fn region(
        lines: &RunLines,
        tri: &crate::Triangulation,
        twins: &[u32],
        k: u32,
        meets: impl Fn([f64; 2], [f64; 2]) -> bool,
        scratch: &mut RegionScratch,
    ) -> Option<(Vec<Tri2>, [f64; 4])> {
        let v = &tri.vertices;
        let at = |u: u32| tri.triangles[u as usize].map(|i| [v[i as usize][0], v[i as usize][1]]);
        let seen = scratch.next(tri.triangles.len());
        scratch.stamp[k as usize] = seen;
        let mut stack = vec![k];
        let mut out = Vec::new();
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        while let Some(u) = stack.pop() {
            let tu = at(u);
            for p in &tu {
                b = [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])];
            }
            out.push(tu);
            if out.len() > REGION_MAX {
                return None;
            }
            for e in 0..3 {
                let (h, tw) = (3 * u as usize + e, twins[3 * u as usize + e]);
                let (x, y) = (tu[e], tu[(e + 1) % 3]);
                if tw == u32::MAX || !meets(x, y) || scratch.constrained(lines, h, tw, x, y) {
                    continue;
                }
                let n = tw / 3;
                if scratch.stamp[n as usize] != seen {
                    scratch.stamp[n as usize] = seen;
                    stack.push(n);
                }
            }
        }
        Some((out, b))
    }

    /// A sight bounded by a [`Sight::region`].
    pub fn within(hidden: [bool; 3], (tris, area): (Vec<Tri2>, [f64; 4])) -> Sight {
        Sight {
            hidden,
            blockers: Vec::new(),
            last: Default::default(),
            region: Some(Region {
                tris,
                bbox: area,
                buckets: Default::default(),
            }),
        }
    }

    /// The bounding box of the region, if there is one.
    pub fn region_box(&self) -> Option<[f64; 4]> {
        self.region.as_ref().map(|r| r.bbox)
    }

    /// Is `q` (a point inside the circumdisk) visible from the interior of `t`? `false` only
    /// when provably hidden: strictly beyond a constrained edge's line (in the cap the edge
    /// cuts off, where every path from the triangle crosses the edge), outside the region, or
    /// behind a blocker. Exact.
    pub fn visible(&self, t: &Tri2, q: [f64; 2]) -> bool {
        use Orientation::Clockwise;
        if (0..3).any(|k| self.hidden[k] && orient(t[k], t[(k + 1) % 3], q) == Clockwise) {
            return false;
        }
        if let Some(r) = &self.region {
            let b = r.bbox;
            // Cells are half-open and clamped: a point of a closed triangle is in a cell the
            // triangle's box registered.
            return q[0] >= b[0]
                && q[0] <= b[2]
                && q[1] >= b[1]
                && q[1] <= b[3]
                && {
                    let (grid, buckets) = r.buckets();
                    buckets.cell(grid.cell_of(q)).iter().any(|&i| {
                        let u = &r.tris[i as usize];
                        (0..3).all(|k| orient(u[k], u[(k + 1) % 3], q) != Clockwise)
                    })
                };
        }
        let hides = |&([u, v], far): &([[f64; 2]; 2], Orientation)| blocks(u, v, far, t, q);
        let last = self.last.get();
        if self.blockers.get(last).is_some_and(hides) {
            return false;
        }
        match self.blockers.iter().position(hides) {
            Some(i) => {
                self.last.set(i);
                false
            }
            None => true,
        }
    }
}

/// The side of the line `u → v` where a point can be hidden from the interior of `t` by the
/// segment `u-v`: the side opposite `t`'s, when `t` lies on one closed side of the line and
/// strictly on it somewhere; `None` when `t` straddles the line or lies on it.
fn far_side(u: [f64; 2], v: [f64; 2], t: &Tri2) -> Option<Orientation> {
    use Orientation::{Clockwise, CounterClockwise};
    let o = t.map(|c| orient(u, v, c));
    match (o.contains(&Clockwise), o.contains(&CounterClockwise)) {
        (true, false) => Some(CounterClockwise),
        (false, true) => Some(Clockwise),
        _ => None,
    }
}

/// Does the segment `u-v` hide `q` from the interior of `t`? When `t` lies on one closed side
/// of its line, `q` strictly on the other (`far`, from [`far_side`]), and it meets the segment
/// from `q` to every corner of `t`, every sight line from the interior crosses it inside. Exact.
fn blocks(u: [f64; 2], v: [f64; 2], far: Orientation, t: &Tri2, q: [f64; 2]) -> bool {
    use Orientation::Collinear;
    // The test below holds only when the closed segment `u-v` meets each segment from `q` to a
    // corner, and so its box: comparing boxes (exact) settles most segments far from the sight.
    let meets_box = |c: [f64; 2]| {
        (0..2).all(|k| {
            u[k].min(v[k]).max(q[k].min(c[k])) <= u[k].max(v[k]).min(q[k].max(c[k]))
        })
    };
    t.iter().all(|&c| meets_box(c))
        && orient(u, v, q) == far
        && t.iter().all(|&c| {
            let (a, b) = (orient(q, c, u), orient(q, c, v));
            a == Collinear || b == Collinear || a != b
        })
}

impl RunLines<'_> {
    /// The loaded segments that meet the box of `t` grown by its size on every side (the
    /// segments most likely to hide parts of a wide disk from it), at most 64.
    pub fn blockers(&self, t: &Tri2) -> Vec<[[f64; 2]; 2]> {
        let l = self.lines;
        let Some(gb) = l.bbox else {
            return Vec::new();
        };
        let b = bbox(t);
        let (lo, hi) = ([b[0], b[1]], [b[2], b[3]]);
        let d = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let (lo, hi) = ([lo[0] - d, lo[1] - d], [hi[0] + d, hi[1] + d]);
        if hi[0] < gb[0] || lo[0] > gb[2] || hi[1] < gb[1] || lo[1] > gb[3] {
            return Vec::new();
        }
        let mut ids: Vec<u32> = Vec::new();
        l.grid.box_cells(lo, hi, |c| {
            ids.extend(l.segs.cell(c).iter().filter(|&&s| self.seg[s as usize]));
        });
        ids.sort_unstable();
        ids.dedup();
        ids.truncate(64);
        ids.into_iter()
            .map(|s| l.segments[s as usize].map(|v| l.xy[v as usize]))
            .collect()
    }

    /// Appends the loaded vertices to `pts` and returns the loaded segments as indices into it.
    pub fn append(&self, pts: &mut Vec<[f64; 3]>) -> Vec<[u32; 2]> {
        let base = pts.len() as u32;
        let mut id = vec![u32::MAX; self.vert.len()];
        for (v, _) in self.vert.iter().enumerate().filter(|(_, l)| **l) {
            id[v] = base + (pts.len() as u32 - base);
            pts.push(self.lines.vertices[v]);
        }
        self.seg
            .iter()
            .enumerate()
            .filter(|(_, l)| **l)
            .map(|(s, _)| self.lines.segments[s].map(|v| id[v as usize]))
            .collect()
    }

    /// Did the run load every segment?
    pub fn all(&self) -> bool {
        self.seg.iter().all(|&l| l)
    }

    /// Is the edge `u`-`w` of a triangle of the run a piece of a loaded segment (a constrained
    /// edge of the run)? Exact.
    pub fn constrained(&self, u: [f64; 2], w: [f64; 2]) -> bool {
        let l = self.lines;
        if l.xy.is_empty() {
            return false;
        }
        l.segs.cell(l.grid.cell_of(u)).iter().any(|&s| {
            self.seg[s as usize] && {
                let [a, b] = l.segments[s as usize].map(|v| l.xy[v as usize]);
                on_segment(a, b, u) && on_segment(a, b, w)
            }
        })
    }

    /// The constrained edges of the counter-clockwise triangle `t`.
    pub fn hidden(&self, t: &Tri2) -> [bool; 3] {
        std::array::from_fn(|k| self.constrained(t[k], t[(k + 1) % 3]))
    }

    /// The vertices the run did not load inside the circumdisk of `t` (within the box `b`,
    /// which holds the part of the disk its constrained edges leave visible) and visible from
    /// it (`sight`), and
    /// the segments it did not load that cross the interior of `t`: the keys of the blocks to
    /// read (a vertex's, a segment's first end's: reading it loads the segment), at most `max`.
    pub fn missing(
        &self,
        t: &Tri2,
        sight: &Sight,
        b: &[f64; 4],
        g: &TileGrid,
        max: usize,
    ) -> Vec<u64> {
        let l = self.lines;
        let mut out = Vec::new();
        let Some(gb) = l.bbox else {
            return out;
        };
        let key = |q: [f64; 2]| {
            let (bx, by) = g.block_of(q[0], q[1]);
            TileGrid::key(bx, by)
        };
        if !(b[2] < gb[0] || b[0] > gb[2] || b[3] < gb[1] || b[1] > gb[3]) {
            l.grid.box_cells([b[0], b[1]], [b[2], b[3]], |c| {
                for &v in l.verts.cell(c) {
                    let q = l.xy[v as usize];
                    if out.len() < max
                        && !self.vert[v as usize]
                        && incircle(t[0], t[1], t[2], q) == CircleSide::Inside
                        && sight.visible(t, q)
                    {
                        out.push(key(q));
                    }
                }
            });
        }
        let b = bbox(t);
        let (lo, hi) = ([b[0], b[1]], [b[2], b[3]]);
        if hi[0] < gb[0] || lo[0] > gb[2] || hi[1] < gb[1] || lo[1] > gb[3] {
            return out;
        }
        l.grid.box_cells(lo, hi, |c| {
            for &s in l.segs.cell(c) {
                if out.len() >= max || self.seg[s as usize] {
                    continue;
                }
                let [a, b] = l.segments[s as usize].map(|v| l.xy[v as usize]);
                if crosses_interior(t, a, b) {
                    out.push(key(a));
                }
            }
        });
        out
    }
}

/// Does the closed segment `a`-`b` meet the open interior of the counter-clockwise triangle
/// `t`? Exact: they are disjoint when a line through an edge of either has the other on one
/// closed side.
pub(crate) fn crosses_interior(t: &Tri2, a: [f64; 2], b: [f64; 2]) -> bool {
    use Orientation::CounterClockwise as Ccw;
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        if orient(p, q, a) != Ccw && orient(p, q, b) != Ccw {
            return false;
        }
    }
    let o = t.map(|c| orient(a, b, c));
    let left = o.iter().all(|&s| s != Orientation::Clockwise);
    let right = o.iter().all(|&s| s != Ccw);
    !(left || right)
}

