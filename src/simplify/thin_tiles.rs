//! The geometry of `sweeptin thin --tile T`: greedy thinning per tile of a fixed grid, in memory
//! bounded by one tile's points, with tiles that conform along their borders.
//!
//! # The grid
//! Grid line `i` lies at `i · T` (the floating-point product, [`TileLines::line`]); a point
//! belongs to tile `(floor(x / T), floor(y / T))`, the quotient corrected against those products
//! ([`TileLines::tile_of`]) so that tile `i` holds exactly `line(i) <= x < line(i + 1)`: a point on
//! a grid line belongs to the tile above / right of it.
//!
//! # Borders: the exact TIN along the grid lines, simplified in 1-D
//! A first pass streams the exact Delaunay TIN of all the points (the `tin` pipeline) into
//! [`Sections`]: for every grid line that meets a triangle, the TIN's section along it — the
//! points where an edge crosses the line (computed from the edge alone, so both triangles of an
//! edge give the same bits) and the TIN's vertices on the line (input points, their own `z`).
//! Between two consecutive samples the TIN is linear along the line, so the section is exact up
//! to the rounding of the crossings. [`Sections::borders`] cuts each line at its ends (where it
//! leaves the points' convex hull) and at the grid corners inside (the corner's `z` interpolated
//! once, on the vertical line, and used by both lines), and simplifies each piece in 1-D
//! ([`super::border::simplify_by`], the grid simplifier's border rule): every sample within the
//! tolerance of the kept polyline, decided by the same exact `VerticalPlane` check as the
//! thinning (a plane through the segment: along the segment it is the segment's
//! interpolation). The kept samples are the **border vertices**: Steiner points on the lines
//! (not input points) unless they are TIN vertices, which are input points.
//!
//! # Tiles
//! A tile starts from the Delaunay triangulation of its border vertices (those of the four
//! lines in its closed rectangle) and of the strictly convex hull vertices of its points and
//! border vertices that lie strictly inside it. Every start vertex lies in the rectangle, so the
//! border vertices of a side are consecutive hull vertices of the start: the start's edges along
//! a side are exactly the segments between consecutive border vertices, the same for the tiles on
//! both sides. The points on a grid line are TIN vertices, hence samples, within the tolerance of
//! the border polyline (exactly): no insertion ever splits a border edge, and every point of
//! the tile lies in the start (the points on a line lie between its first and last sample). The
//! greedy insertion and decimation of [`super::thin`] then run with the start vertices fixed;
//! its final exact check covers every point of the tile. A point exactly at a border vertex is
//! that vertex (its `z` must be the vertex's: it is a TIN vertex); a tile whose start has no
//! triangle (a sliver of the hull on a line) checks its points against the border polylines.
//!
//! # Cost
//! The borders hold the sections (24 bytes per sample: about two per edge crossing of a line);
//! a tile holds its points ([`crate::pipeline::THIN_BYTES_PER_POINT`] bytes each at most). The
//! result depends only on the point set and `T`, never on `--mem` or `--threads`. It keeps more
//! points than one global run (the border vertices, and points near the borders that a global
//! run would leave to a vertex across the line); see docs/ACCURACY.md for how many.

use super::border::simplify_by;
use super::thin::{ThinOptions, Thinned, hull, thin_in_domain};
use crate::error::{Error, Result};
use crate::geom::predicates::{Orientation, VerticalPlane, orient};
use crate::sink::{ProductSummary, StreamInfo, TriangleSink};
use std::collections::{BTreeMap, HashMap};

/// Largest tile index magnitude.
const MAX_TILE: f64 = (1u64 << 31) as f64 - 2.0;

/// The grid of tiles of side `T`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TileLines {
    size: f64,
}

impl TileLines {
    /// The grid of side `size`.
    ///
    /// # Errors
    /// [`Error::Options`] unless `size` is finite and > 0.
    pub(crate) fn new(size: f64) -> Result<Self> {
        if !(size > 0.0 && size.is_finite()) {
            return Err(Error::Options(format!(
                "--tile {size}: give a tile side > 0 (in the points' horizontal units)"
            )));
        }
        Ok(TileLines { size })
    }

    /// Where grid line `i` lies.
    #[inline]
    pub(crate) fn line(&self, i: i64) -> f64 {
        i as f64 * self.size
    }

    /// The tile (column or row) of coordinate `v`: `line(i) <= v < line(i + 1)`.
    ///
    /// # Errors
    /// [`Error::Options`] when `v / T` is too large for the grid.
    #[inline]
    pub(crate) fn tile_of(&self, v: f64) -> Result<i64> {
        let q = (v / self.size).floor();
        if q.is_nan() || q.abs() >= MAX_TILE {
            return Err(Error::Options(format!(
                "coordinate {v} is {q} tiles of --tile {} from 0: give a larger --tile",
                self.size
            )));
        }
        let mut i = q as i64;
        while v < self.line(i) {
            i -= 1;
        }
        while v >= self.line(i + 1) {
            i += 1;
        }
        Ok(i)
    }
}

/// One sample of the TIN along a grid line: position along the line, height, and whether it is
/// a TIN vertex (an input point) rather than an edge crossing.
#[derive(Clone, Copy, Debug)]
struct Sample {
    pos: f64,
    z: f64,
    vertex: bool,
}

/// Bytes per sample held (with the vectors' slack).
const SAMPLE_BYTES: u64 = 48;

/// The exact TIN's sections along the grid lines: a [`TriangleSink`] for the first pass.
#[derive(Debug)]
pub(crate) struct Sections {
    grid: TileLines,
    /// Samples of the vertical lines `x = line(i)` (position: y) and horizontal lines
    /// `y = line(j)` (position: x), by line.
    lines: [BTreeMap<i64, Vec<Sample>>; 2],
    samples: u64,
    /// Memory the samples may take.
    limit: u64,
    /// The TIN's area (its triangles' areas added up).
    area: f64,
}

impl Sections {
    /// Empty sections of `grid`, holding at most `limit` bytes.
    pub(crate) fn new(grid: TileLines, limit: u64) -> Self {
        Sections {
            grid,
            lines: [BTreeMap::new(), BTreeMap::new()],
            samples: 0,
            limit,
            area: 0.0,
        }
    }

    /// The samples of triangle `t` on the lines of axis `k` (0: vertical lines, 1: horizontal).
    fn cut(&mut self, t: &[[f64; 3]; 3], k: usize) -> Result<()> {
        let o = 1 - k;
        let lo = t[0][k].min(t[1][k]).min(t[2][k]);
        let hi = t[0][k].max(t[1][k]).max(t[2][k]);
        let (first, last) = (self.grid.tile_of(lo)?, self.grid.tile_of(hi)?);
        for i in first..=last {
            let l = self.grid.line(i);
            if l < lo || l > hi {
                continue;
            }
            let line = self.lines[k].entry(i).or_default();
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                if a[k] == l {
                    line.push(Sample {
                        pos: a[o],
                        z: a[2],
                        vertex: true,
                    });
                    self.samples += 1;
                } else if (a[k] < l) != (b[k] < l) && b[k] != l {
                    // Canonical endpoint order: both triangles of the edge compute the same bits.
                    let (p, q) = if (a[0], a[1]) < (b[0], b[1]) {
                        (a, b)
                    } else {
                        (b, a)
                    };
                    let s = (l - p[k]) / (q[k] - p[k]);
                    let pos = (p[o] + s * (q[o] - p[o])).clamp(p[o].min(q[o]), p[o].max(q[o]));
                    line.push(Sample {
                        pos,
                        z: p[2] + s * (q[2] - p[2]),
                        vertex: false,
                    });
                    self.samples += 1;
                }
            }
        }
        if self.samples.saturating_mul(SAMPLE_BYTES) <= self.limit {
            return Ok(());
        }
        // Each crossing comes from both triangles of its edge and each vertex from every
        // triangle around it: one sample per position is all the borders keep. Refused when a
        // quarter of the limit is not free after it (compacting again and again for a few
        // samples each time would cost more than the pass).
        self.compact();
        if self.samples.saturating_mul(SAMPLE_BYTES) > self.limit / 4 * 3 {
            // The samples go as 1 / T (the lines' count); 10 % more for the lines' ends.
            let fits = crate::error::round_up_figure(
                1.1 * self.grid.size * (self.samples * SAMPLE_BYTES) as f64
                    / (self.limit / 4 * 3).max(1) as f64,
            );
            return Err(Error::Options(format!(
                "thin --tile {}: the TIN's sections along the tile borders need more than {} \
                 KiB ({} samples, an eighth of --mem): give --tile {fits} or larger, or a \
                 larger --mem",
                self.grid.size,
                self.limit >> 10,
                self.samples
            )));
        }
        Ok(())
    }

    /// Sorts every line's samples and keeps one per position: a total order (the triangles
    /// arrive in an order that depends on the engine and the threads), a vertex before a
    /// crossing rounded onto it, else the lowest. Keeping the least sample of each position is
    /// the same whether done once at the end or again on the way (when the samples reach the
    /// limit).
    fn compact(&mut self) {
        let mut samples = 0u64;
        for s in self.lines.iter_mut().flat_map(|l| l.values_mut()) {
            s.sort_by(|a, b| {
                a.pos
                    .total_cmp(&b.pos)
                    .then(b.vertex.cmp(&a.vertex))
                    .then(a.z.total_cmp(&b.z))
            });
            s.dedup_by(|b, a| a.pos == b.pos);
            s.shrink_to_fit();
            samples += s.len() as u64;
        }
        self.samples = samples;
    }

    /// Refuses tiles smaller than a point's neighbourhood: when the grid lines cut the TIN at
    /// more places (distinct samples, the lines sorted and deduplicated) than it has `points`.
    /// A Delaunay TIN's edges cross a line about 2.16 times per mean point spacing `s` (for
    /// uniform points, `64 / (3π²) · √density`), so a tile owning two sides of `T` is cut about
    /// `4.3 T / s` times for its `(T / s)²` points: below `T ≈ 4.3 s` its borders outnumber its
    /// points, each sample a possible vertex of the output (lidR's 73,403 points at `--tile 1`,
    /// 1.05 m apart: 321,159 vertices written, 270,171 of them on the borders). The samples go
    /// as `1 / T`, so the smallest side that works is about `T · samples / points` (10 % more
    /// is said: the ends of the lines do not shrink with `T`).
    fn check_tile_side(&self, points: u64) -> Result<()> {
        let samples: u64 = self
            .lines
            .iter()
            .flat_map(|l| l.values())
            .map(|s| s.len() as u64)
            .sum();
        if samples <= points {
            return Ok(());
        }
        let t = self.grid.size;
        let per_tile = points as f64 * t * t / self.area.max(f64::MIN_POSITIVE);
        Err(Error::Options(format!(
            "thin --tile {t}: the tiles are smaller than a point's neighbourhood (they hold \
             {per_tile:.1} points each on average): their borders cut the points' TIN at \
             {samples} places, more than its {points} points, and every cut may become a vertex \
             of the output; give --tile {} or more",
            crate::error::round_up_figure(1.1 * t * samples as f64 / points.max(1) as f64)
        )))
    }

    /// The border vertices: each line cut at its ends and at the grid corners, its pieces
    /// simplified within `options.max_error` (module docs). `points` is the number of distinct
    /// points of the TIN the sections were cut from.
    ///
    /// # Errors
    /// [`Error::Options`] when the tiles are smaller than a point's neighbourhood
    /// ([`Sections::check_tile_side`]); [`Error::Internal`] when a check cannot be set up (a
    /// degenerate line).
    pub(crate) fn borders(mut self, options: &ThinOptions, points: u64) -> Result<Borders> {
        let grid = self.grid;
        self.compact();
        self.check_tile_side(points)?;
        let [vertical, horizontal] = self.lines;
        let mut out = Borders {
            grid,
            lines: [BTreeMap::new(), BTreeMap::new()],
        };
        let mut corners: HashMap<(i64, i64), f64> = HashMap::new();
        for (k, lines) in [(0usize, vertical), (1, horizontal)] {
            for (i, mut s) in lines {
                let (lo, hi) = (s[0].pos, s[s.len() - 1].pos);
                let mut anchors = vec![false; s.len()];
                anchors[0] = true;
                anchors[s.len() - 1] = true;
                let (j0, j1) = (grid.tile_of(lo)?, grid.tile_of(hi)?);
                let mut extra = Vec::new();
                for j in j0..=j1 + 1 {
                    let c = grid.line(j);
                    if c <= lo || c >= hi {
                        continue;
                    }
                    let key = if k == 0 { (i, j) } else { (j, i) };
                    let at = s.partition_point(|q| q.pos < c);
                    if s[at].pos == c {
                        anchors[at] = true;
                        corners.entry(key).or_insert(s[at].z);
                        continue;
                    }
                    let z = *corners.entry(key).or_insert_with(|| {
                        let (a, b) = (s[at - 1], s[at]);
                        a.z + (c - a.pos) / (b.pos - a.pos) * (b.z - a.z)
                    });
                    extra.push(Sample {
                        pos: c,
                        z,
                        vertex: false,
                    });
                }
                if !extra.is_empty() {
                    s.extend(extra);
                    s.sort_by(|a, b| a.pos.total_cmp(&b.pos));
                    anchors = s
                        .iter()
                        .enumerate()
                        .map(|(n, q)| {
                            n == 0 || n + 1 == s.len() || {
                                let c = (q.pos / grid.size).round();
                                grid.line(c as i64) == q.pos
                            }
                        })
                        .collect();
                }
                let kept = simplify_section(&grid, k, i, &s, &anchors, options)?;
                let l = grid.line(i);
                let v: Vec<[f64; 3]> = kept
                    .iter()
                    .map(|&n| {
                        let q = s[n];
                        if k == 0 {
                            [l, q.pos, q.z]
                        } else {
                            [q.pos, l, q.z]
                        }
                    })
                    .collect();
                out.lines[k].insert(i, v);
            }
        }
        Ok(out)
    }
}

/// The world position of a sample of line `i` of axis `k`.
#[inline]
fn world(grid: &TileLines, k: usize, i: i64, pos: f64, z: f64) -> [f64; 3] {
    let l = grid.line(i);
    if k == 0 { [l, pos, z] } else { [pos, l, z] }
}

/// The plane through the segment `a → b` of a grid line (a third point off the line): along
/// the segment it is the segment's linear interpolation.
fn segment_plane(a: [f64; 3], b: [f64; 3]) -> Result<VerticalPlane> {
    let d = ((b[0] - a[0]).abs() + (b[1] - a[1]).abs()).max(1.0);
    // Off the line, perpendicular to it.
    let c = if a[0] == b[0] {
        [a[0] - d, a[1], a[2]]
    } else {
        [a[0], a[1] - d, a[2]]
    };
    match orient([a[0], a[1]], [b[0], b[1]], [c[0], c[1]]) {
        Orientation::CounterClockwise => Ok(VerticalPlane::new(a, b, c)),
        Orientation::Clockwise => Ok(VerticalPlane::new(b, a, c)),
        Orientation::Collinear => Err(Error::Internal(format!(
            "thin --tile: no plane through the border segment ({}, {}) - ({}, {})",
            a[0], a[1], b[0], b[1]
        ))),
    }
}

/// The kept samples of one line: the anchors, and between them the 1-D simplification.
fn simplify_section(
    grid: &TileLines,
    k: usize,
    i: i64,
    s: &[Sample],
    anchors: &[bool],
    options: &ThinOptions,
) -> Result<Vec<usize>> {
    let tol = options.max_error;
    let mut kept = Vec::new();
    let mut failure = None;
    let mut start = 0;
    for end in (1..s.len()).filter(|&n| anchors[n]) {
        let piece = simplify_by(
            end - start + 1,
            |a, b| {
                let (a, b) = (start + a, start + b);
                if b <= a + 1 {
                    return None;
                }
                let pa = world(grid, k, i, s[a].pos, s[a].z);
                let pb = world(grid, k, i, s[b].pos, s[b].z);
                let plane = match segment_plane(pa, pb) {
                    Ok(p) => p,
                    Err(e) => {
                        failure.get_or_insert(e);
                        return None;
                    }
                };
                let mut worst: Option<(f64, usize)> = None;
                for (n, q) in s.iter().enumerate().take(b).skip(a + 1) {
                    let v = plane.check(world(grid, k, i, q.pos, q.z), tol);
                    if !v.within && worst.is_none_or(|(e, _)| v.error > e) {
                        worst = Some((v.error, n));
                    }
                }
                worst.map(|(_, n)| n - start)
            },
            |_, _| false,
            options.decimate,
        );
        if kept.is_empty() {
            kept.push(start);
        }
        kept.extend(piece.into_iter().skip(1).map(|n| n + start));
        start = end;
    }
    if kept.is_empty() {
        kept.push(0);
    }
    match failure {
        Some(e) => Err(e),
        None => Ok(kept),
    }
}

impl TriangleSink for Sections {
    fn begin(&mut self, _info: &StreamInfo) -> Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        let [a, b, c] = *t;
        self.area += ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs() / 2.0;
        self.cut(t, 0)?;
        self.cut(t, 1)
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        Ok(ProductSummary::None)
    }
}

/// The border vertices of every grid line, sorted along it.
#[derive(Debug)]
pub(crate) struct Borders {
    grid: TileLines,
    lines: [BTreeMap<i64, Vec<[f64; 3]>>; 2],
}

/// One tile thinned: its mesh (vertex numbers local) and numbers.
#[derive(Debug, Default)]
pub(crate) struct TileThinned {
    /// The tile `(tx, ty)`.
    pub tile: (i64, i64),
    /// Vertices: border vertices, hull and kept points.
    pub vertices: Vec<[f64; 3]>,
    /// Is each vertex on the tile's boundary lines (shared with a neighbour)?
    pub on_border: Vec<bool>,
    /// Is each vertex an input point?
    pub is_point: Vec<bool>,
    /// Triangles, counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
    /// Points of the tile (after duplicates).
    pub points: u64,
    /// Largest vertical distance of a point from the TIN.
    pub max_error: f64,
    /// Sum of the squared distances.
    pub sum_sq: f64,
    /// Insertions, removals, flips and exact tests of the thinning.
    pub insertions: u64,
    /// Points removed again by the redundancy pass.
    pub removed: u64,
    /// Edge flips.
    pub flips: u64,
    /// Points decided by exact `orient3d`.
    pub exact_tests: u64,
}

impl Borders {
    /// Every border vertex (those at grid corners once per line).
    pub(crate) fn vertices(&self) -> impl Iterator<Item = &[f64; 3]> {
        self.lines.iter().flat_map(|l| l.values().flatten())
    }

    /// The grid.
    pub(crate) fn grid(&self) -> TileLines {
        self.grid
    }

    /// The rectangle of tile `(tx, ty)`: `[x0, y0, x1, y1]`.
    pub(crate) fn rect(&self, tx: i64, ty: i64) -> [f64; 4] {
        let g = &self.grid;
        [g.line(tx), g.line(ty), g.line(tx + 1), g.line(ty + 1)]
    }

    /// The border vertices in the closed rectangle of tile `(tx, ty)`, each position once (the
    /// vertical lines' first), in a fixed order.
    fn tile_vertices(&self, tx: i64, ty: i64) -> Vec<[f64; 3]> {
        let r = self.rect(tx, ty);
        let mut out: Vec<[f64; 3]> = Vec::new();
        for (k, i) in [(0, tx), (0, tx + 1), (1, ty), (1, ty + 1)] {
            let Some(v) = self.lines[k].get(&i) else {
                continue;
            };
            let o = 1 - k;
            let (lo, hi) = (r[o], r[o + 2]);
            let first = v.partition_point(|p| p[o] < lo);
            out.extend(v[first..].iter().take_while(|p| p[o] <= hi));
        }
        let mut seen = HashMap::new();
        out.retain(|p| seen.insert([p[0].to_bits(), p[1].to_bits()], ()).is_none());
        out
    }

    /// The vertical distance of `p`, a point on a grid line of tile `(tx, ty)`'s rectangle,
    /// from the border polyline; `Err` when it is not within `tol` (cannot happen: every point
    /// on a line is a sample of it).
    fn border_error(&self, tx: i64, ty: i64, p: [f64; 3], tol: f64) -> Result<f64> {
        let r = self.rect(tx, ty);
        let on = [(0, tx, p[0] == r[0]), (1, ty, p[1] == r[1])];
        for (k, i, hit) in on {
            if !hit {
                continue;
            }
            let o = 1 - k;
            let Some(v) = self.lines[k].get(&i) else {
                continue;
            };
            let at = v.partition_point(|q| q[o] < p[o]);
            if at < v.len() && v[at][o] == p[o] {
                return Ok((v[at][2] - p[2]).abs());
            }
            if at == 0 || at == v.len() {
                continue;
            }
            let c = segment_plane(v[at - 1], v[at])?.check(p, tol);
            if c.within {
                return Ok(c.error);
            }
        }
        Err(Error::Internal(format!(
            "thin --tile: point ({}, {}, {}) on a tile border is not within the border polyline",
            p[0], p[1], p[2]
        )))
    }

    /// Thins the points of tile `(tx, ty)` (distinct positions, all in the tile) within its
    /// borders.
    ///
    /// # Errors
    /// The thinning's errors; [`Error::Internal`] when a point is at a border vertex with
    /// another height or a border check fails.
    pub(crate) fn thin_tile(
        &self,
        tx: i64,
        ty: i64,
        points: Vec<[f64; 3]>,
        options: &ThinOptions,
    ) -> Result<TileThinned> {
        let r = self.rect(tx, ty);
        let border = self.tile_vertices(tx, ty);
        let at: HashMap<[u64; 2], usize> = border
            .iter()
            .enumerate()
            .map(|(n, p)| ([p[0].to_bits(), p[1].to_bits()], n))
            .collect();
        let mut out = TileThinned {
            tile: (tx, ty),
            points: points.len() as u64,
            ..TileThinned::default()
        };
        let mut border_point = vec![false; border.len()];
        let mut pts = Vec::with_capacity(points.len());
        for p in points {
            match at.get(&[p[0].to_bits(), p[1].to_bits()]) {
                Some(&n) if border[n][2] == p[2] => border_point[n] = true,
                Some(&n) => {
                    return Err(Error::Internal(format!(
                        "thin --tile: point ({}, {}, {}) at a border vertex of height {}",
                        p[0], p[1], p[2], border[n][2]
                    )));
                }
                None => pts.push(p),
            }
        }
        let inside = |p: &[f64; 3]| p[0] > r[0] && p[0] < r[2] && p[1] > r[1] && p[1] < r[3];
        let n = pts.len();
        pts.extend_from_slice(&border);
        let h: Vec<u32> = hull(&pts)
            .into_iter()
            .filter(|&i| (i as usize) < n && inside(&pts[i as usize]))
            .collect();
        pts.truncate(n);
        let degenerate = h.len() + border.len() < 3 || {
            let mut start: Vec<[f64; 2]> = border.iter().map(|p| [p[0], p[1]]).collect();
            start.extend(h.iter().map(|&i| [pts[i as usize][0], pts[i as usize][1]]));
            start
                .iter()
                .all(|&c| orient(start[0], start[1], c) == Orientation::Collinear)
        };
        if degenerate {
            // A sliver of the hull along a line: every point is on a line, within its border.
            for p in pts {
                let e = self.border_error(tx, ty, p, options.max_error)?;
                out.max_error = out.max_error.max(e);
                out.sum_sq += e * e;
            }
            return Ok(out);
        }
        let Thinned {
            vertices,
            triangles,
            is_point,
            stats,
        } = thin_in_domain(pts, h, &border, options)?;
        out.on_border = vertices
            .iter()
            .map(|p| p[0] == r[0] || p[0] == r[2] || p[1] == r[1] || p[1] == r[3])
            .collect();
        out.is_point = vertices
            .iter()
            .zip(is_point)
            .map(|(p, ip)| {
                ip || at
                    .get(&[p[0].to_bits(), p[1].to_bits()])
                    .is_some_and(|&n| border_point[n])
            })
            .collect();
        for (p, &b) in vertices.iter().zip(&out.on_border) {
            if b && !at.contains_key(&[p[0].to_bits(), p[1].to_bits()]) {
                return Err(Error::Internal(format!(
                    "thin --tile: a vertex ({}, {}) on the border of tile ({tx}, {ty}) is not a \
                     border vertex",
                    p[0], p[1]
                )));
            }
        }
        out.vertices = vertices;
        out.triangles = triangles;
        out.max_error = stats.max_error;
        out.sum_sq = stats.rms_error * stats.rms_error * stats.points as f64;
        out.insertions = stats.insertions;
        out.removed = stats.removed;
        out.flips = stats.flips;
        out.exact_tests = stats.exact_tests;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_are_half_open_on_the_products() {
        let g = TileLines::new(0.1).unwrap();
        for i in -50i64..50 {
            let l = g.line(i);
            assert_eq!(g.tile_of(l).unwrap(), i);
            assert_eq!(g.tile_of(l.next_down()).unwrap(), i - 1);
        }
        assert!(TileLines::new(0.0).is_err() && TileLines::new(f64::NAN).is_err());
        assert!(TileLines::new(1.0).unwrap().tile_of(1e300).is_err());
    }

    #[test]
    fn a_section_is_simplified_within_the_bound_between_its_anchors() {
        let g = TileLines::new(10.0).unwrap();
        let s: Vec<Sample> = (0..=200)
            .map(|n| {
                let pos = n as f64 * 0.1;
                Sample {
                    pos,
                    z: (pos * 1.3).sin(),
                    vertex: n % 3 == 0,
                }
            })
            .collect();
        let mut anchors = vec![false; s.len()];
        anchors[0] = true;
        anchors[100] = true;
        anchors[200] = true;
        let o = ThinOptions::max_error(0.05);
        let kept = simplify_section(&g, 0, 1, &s, &anchors, &o).unwrap();
        assert!(kept.contains(&0) && kept.contains(&100) && kept.contains(&200));
        assert!(kept.len() < 60, "{}", kept.len());
        for w in kept.windows(2) {
            let (a, b) = (s[w[0]], s[w[1]]);
            for q in &s[w[0]..=w[1]] {
                let z = a.z + (q.pos - a.pos) / (b.pos - a.pos) * (b.z - a.z);
                assert!((z - q.z).abs() <= 0.05 + 1e-12);
            }
        }
    }
}
