//! What a task of a plan knows of the data it did not read ([`Scope`]), and the boxes it keeps
//! of them ([`Extent`]).



/// What a task knows of the data (see [`BlockIndex::scope`]).
#[derive(Debug, Clone)]
pub(crate) struct Scope {
    /// Extents of the files the task did not read (closed rectangles, from their headers):
    /// points may lie there. A buffer that reaches one reads the whole file.
    pub unknown: Vec<[f64; 4]>,
    /// Parts of the extents of files the task read only around its tile (COPC): points may lie
    /// there too, and only a buffer that covers them reads them.
    pub beyond: Vec<[f64; 4]>,
    /// The task's tile.
    pub tile: [f64; 4],
    /// How far around its tile the task read.
    pub buffer: f64,
    /// The corners of the data's convex hull, when known.
    pub hull: Option<Vec<[f64; 2]>>,
    /// A convex polygon inside the hull that holds every point the task was not given: the
    /// points outside it (the hull's band) are read, wherever they lie.
    pub inner: Option<Vec<[f64; 2]>>,
}

/// Does the closed disk of centre `c` and radius `r` meet the closed rectangle `u`? (A little
/// generously: a disk that nearly touches it counts.)
fn disk_meets(u: &[f64; 4], c: [f64; 2], r: f64) -> bool {
    let slack = 1e-9 * (r + c[0].abs().max(c[1].abs()));
    let dx = (u[0] - c[0]).max(c[0] - u[2]).max(0.0);
    let dy = (u[1] - c[1]).max(c[1] - u[3]).max(0.0);
    (dx * dx + dy * dy).sqrt() <= r + slack
}

/// A convex polygon (counter-clockwise corners) clipped by the closed half-plane where
/// `inside` holds, `cut` giving the crossing of an edge (floating point).
fn clip(
    poly: &[[f64; 2]],
    inside: impl Fn(&[f64; 2]) -> bool,
    cut: impl Fn(&[f64; 2], &[f64; 2]) -> [f64; 2],
) -> Vec<[f64; 2]> {
    let mut out = Vec::with_capacity(poly.len() + 4);
    for i in 0..poly.len() {
        let (p, q) = (&poly[i], &poly[(i + 1) % poly.len()]);
        match (inside(p), inside(q)) {
            (true, true) => out.push(*q),
            (true, false) => out.push(cut(p, q)),
            (false, true) => {
                out.push(cut(p, q));
                out.push(*q);
            }
            (false, false) => {}
        }
    }
    out
}

/// `poly` clipped by the closed box `w`.
fn clip_box(mut poly: Vec<[f64; 2]>, w: &[f64; 4]) -> Vec<[f64; 2]> {
    for side in 0..4 {
        let (k, v) = match side {
            0 => (0, w[0]),
            1 => (1, w[1]),
            2 => (0, w[2]),
            _ => (1, w[3]),
        };
        let inside = |p: &[f64; 2]| if side < 2 { p[k] >= v } else { p[k] <= v };
        let cut = |p: &[f64; 2], q: &[f64; 2]| {
            let t = ((v - p[k]) / (q[k] - p[k])).clamp(0.0, 1.0);
            let mut o = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
            o[k] = v;
            o
        };
        poly = clip(&poly, inside, cut);
        if poly.is_empty() {
            break;
        }
    }
    poly
}

/// Does the closed disk of centre `c` and radius `r` meet the polygon `poly`? (Its centre
/// inside by the crossing rule, which holds for a polygon that rounding left a little
/// non-convex; or an edge within `r`.)
fn disk_meets_poly(poly: &[[f64; 2]], c: [f64; 2], r: f64) -> bool {
    let n = poly.len();
    let mut inside = false;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        if (p[1] > c[1]) != (q[1] > c[1])
            && c[0] < p[0] + (c[1] - p[1]) / (q[1] - p[1]) * (q[0] - p[0])
        {
            inside = !inside;
        }
        let d = [q[0] - p[0], q[1] - p[1]];
        let e = [c[0] - p[0], c[1] - p[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let t = if l2 > 0.0 {
            ((e[0] * d[0] + e[1] * d[1]) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let f = [e[0] - t * d[0], e[1] - t * d[1]];
        if f[0] * f[0] + f[1] * f[1] <= r * r {
            return true;
        }
    }
    inside
}

/// The convex polygon `h` (counter-clockwise corners) with every edge moved inwards by `d`
/// (floating point).
pub(crate) fn inner_polygon(h: &[[f64; 2]], d: f64) -> Vec<[f64; 2]> {
    let mut poly = h.to_vec();
    for i in 0..h.len() {
        let (a, b) = (h[i], h[(i + 1) % h.len()]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let l = e[0].hypot(e[1]);
        if l == 0.0 {
            continue;
        }
        let side = |q: &[f64; 2]| (e[0] * (q[1] - a[1]) - e[1] * (q[0] - a[0])) / l;
        poly = clip(
            &poly,
            |q| side(q) >= d,
            |p, q| {
                let (sp, sq) = (side(p), side(q));
                let t = ((sp - d) / (sp - sq)).clamp(0.0, 1.0);
                [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
            },
        );
        if poly.is_empty() {
            break;
        }
    }
    poly
}

/// What a test asks of the unknown points in one rectangle: that they lie in a disk, a box,
/// the open half-plane right of a directed line.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Within {
    pub disk: Option<([f64; 2], f64)>,
    pub boxed: Option<[f64; 4]>,
    pub right_of: Option<([f64; 2], [f64; 2])>,
}

impl Scope {
    /// The rectangle the task read whole: its tile and buffer (every file meeting it was read).
    pub fn read_rect(&self) -> [f64; 4] {
        let (t, b) = (&self.tile, self.buffer);
        [t[0] - b, t[1] - b, t[2] + b, t[3] + b]
    }

    /// Does the task know every point there is?
    pub fn complete(&self) -> bool {
        self.unknown.is_empty() && self.beyond.is_empty()
    }

    /// The buffer that would read the points not read that may lie in the closed disk of centre
    /// `c` and radius `r` (conservative), or 0 when there are none.
    pub fn disk_reach(&self, c: [f64; 2], r: f64) -> f64 {
        let w = Within {
            disk: Some((c, r)),
            ..Within::default()
        };
        let meets = |u: &&[f64; 4]| disk_meets(u, c, r) && self.might_hold(u, &w);
        let files = self.unknown.iter().filter(meets).map(|u| self.reach(u));
        // A part of a file read around the tile: the buffer must cover the disk's box there.
        let parts = self.beyond.iter().filter(meets).map(|u| {
            let b = [
                (c[0] - r).max(u[0]),
                (c[1] - r).max(u[1]),
                (c[0] + r).min(u[2]),
                (c[1] + r).min(u[3]),
            ];
            self.cover(&b)
        });
        files.chain(parts).fold(0.0, f64::max)
    }

    /// The buffer around the tile that reaches the rectangle `u` (a little more, so that the
    /// plan's closed overlap test selects its file).
    pub fn reach(&self, u: &[f64; 4]) -> f64 {
        let t = &self.tile;
        let d = (u[0] - t[2])
            .max(t[0] - u[2])
            .max(u[1] - t[3])
            .max(t[1] - u[3]);
        d.max(0.0) * (1.0 + 1e-9) + 1e-9
    }

    /// The buffer around the tile that covers the rectangle `u` whole (a little more).
    pub fn cover(&self, u: &[f64; 4]) -> f64 {
        let t = &self.tile;
        let d = (u[2] - t[2])
            .max(t[0] - u[0])
            .max(u[3] - t[3])
            .max(t[1] - u[1]);
        d.max(0.0) * (1.0 + 1e-9) + 1e-9
    }

    /// Might a point not read lie in the closed rectangle `u` where `w` asks? (Floating point,
    /// generously: every clip widened by a slack.) Without [`Scope::inner`], yes.
    pub fn might_hold(&self, u: &[f64; 4], w: &Within) -> bool {
        let Some(p) = &self.inner else {
            return true;
        };
        let mag = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let slack = 2e-9 * (mag + (u[2] - u[0]) + (u[3] - u[1]) + 1.0);
        let grow = |b: &[f64; 4]| [b[0] - slack, b[1] - slack, b[2] + slack, b[3] + slack];
        let mut poly = clip_box(p.clone(), &grow(u));
        if let Some(b) = &w.boxed
            && !poly.is_empty()
        {
            poly = clip_box(poly, &grow(b));
        }
        if let Some((a, b)) = w.right_of
            && !poly.is_empty()
        {
            let d = [b[0] - a[0], b[1] - a[1]];
            let l = d[0].hypot(d[1]);
            let side = |q: &[f64; 2]| (d[0] * (q[1] - a[1]) - d[1] * (q[0] - a[0])) / l;
            poly = clip(
                &poly,
                |q| side(q) <= slack,
                |p, q| {
                    let (sp, sq) = (side(p), side(q));
                    let t = ((sp - slack) / (sp - sq)).clamp(0.0, 1.0);
                    [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
                },
            );
        }
        match w.disk {
            _ if poly.is_empty() => false,
            Some((c, r)) => disk_meets_poly(&poly, c, r * (1.0 + 1e-12) + slack),
            None => true,
        }
    }

    /// The buffer that reads whatever may lie in the rectangles of [`Scope::unknown`] and
    /// [`Scope::beyond`] that `meets` accepts (0: none).
    pub fn reach_where(&self, meets: impl Fn(&[f64; 4]) -> bool) -> f64 {
        let files = self.unknown.iter().filter(|u| meets(u)).map(|u| self.reach(u));
        let parts = self.beyond.iter().filter(|u| meets(u)).map(|u| self.cover(u));
        files.chain(parts).fold(0.0, f64::max)
    }
}

/// The tight bounding box of a block's points, as `f32` offsets from the block's lower-left
/// corner, rounded outward (so the box it stands for always holds every point of the block).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Extent([f32; 4]);

impl Extent {
    /// The outward-rounded offsets of `b` (`[xmin, ymin, xmax, ymax]`, world) from `corner`.
    pub(super) fn new(b: [f64; 4], corner: [f64; 2], block: f64) -> Extent {
        // The f64 difference errs by an ulp of the corner, the f32 rounding by 2^-24 of a block
        // (offsets lie within one block): the margin covers both, and the reverse sum in `world`.
        let m = block * 1e-6 + (corner[0].abs() + corner[1].abs() + block) * 1e-14;
        Extent([
            (b[0] - corner[0] - m) as f32,
            (b[1] - corner[1] - m) as f32,
            (b[2] - corner[0] + m) as f32,
            (b[3] - corner[1] + m) as f32,
        ])
    }

    /// The world box `[xmin, ymin, xmax, ymax]` (a little wider than the points' box).
    #[inline]
    pub fn world(&self, corner: [f64; 2], block: f64) -> [f64; 4] {
        let m = block * 1e-6 + (corner[0].abs() + corner[1].abs() + block) * 1e-14;
        let e = &self.0;
        [
            corner[0] + f64::from(e[0]) - m,
            corner[1] + f64::from(e[1]) - m,
            corner[0] + f64::from(e[2]) + m,
            corner[1] + f64::from(e[3]) + m,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square hull of side 100 at UTM-sized coordinates, its band 2 wide.
    fn scope() -> Scope {
        let (x, y) = (500_000.0, 5_000_000.0);
        let hull = vec![[x, y], [x + 100.0, y], [x + 100.0, y + 100.0], [x, y + 100.0]];
        let inner = inner_polygon(&hull, 2.0);
        Scope {
            unknown: vec![],
            beyond: vec![],
            tile: [x, y, x + 10.0, y + 10.0],
            buffer: 0.0,
            hull: Some(hull),
            inner: Some(inner),
        }
    }

    #[test]
    fn the_inner_polygon_is_the_hull_moved_inwards() {
        let sc = scope();
        let mut p = sc.inner.clone().unwrap();
        p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        p.dedup();
        let (x, y) = (500_000.0, 5_000_000.0);
        let want = [[x + 2.0, y + 2.0], [x + 2.0, y + 98.0], [x + 98.0, y + 2.0], [x + 98.0, y + 98.0]];
        assert_eq!(p.len(), 4, "{p:?}");
        for (a, b) in p.iter().zip(&want) {
            assert!((a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6, "{p:?}");
        }
    }

    #[test]
    fn unknown_points_lie_only_inside_the_inner_polygon() {
        let sc = scope();
        let (x, y) = (500_000.0, 5_000_000.0);
        let all = Within::default();
        // A box within the band (the strip along the south edge) holds no unknown point.
        let band = [x + 10.0, y, x + 30.0, y + 1.5];
        assert!(!sc.might_hold(&band, &all));
        // One that crosses into the inner square may.
        let deep = [x + 10.0, y, x + 30.0, y + 2.5];
        assert!(sc.might_hold(&deep, &all));
        // A disk in the band (a sliver's cap), against the deep box: none; a larger one: some.
        let disk = |c: [f64; 2], r: f64| Within {
            disk: Some((c, r)),
            ..Within::default()
        };
        assert!(!sc.might_hold(&deep, &disk([x + 20.0, y - 100.0], 101.0)));
        assert!(sc.might_hold(&deep, &disk([x + 20.0, y - 100.0], 103.0)));
        // A disk wholly inside the inner square meets it (its centre is inside).
        let inside = [x + 40.0, y + 40.0, x + 60.0, y + 60.0];
        assert!(sc.might_hold(&inside, &disk([x + 50.0, y + 50.0], 1.0)));
        // Right of the south edge's line (below it) nothing; right of a line across, some.
        let right = |a: [f64; 2], b: [f64; 2]| Within {
            right_of: Some((a, b)),
            ..Within::default()
        };
        let whole = [x - 10.0, y - 10.0, x + 110.0, y + 110.0];
        assert!(!sc.might_hold(&whole, &right([x, y + 1.0], [x + 100.0, y + 1.0])));
        assert!(sc.might_hold(&whole, &right([x, y + 50.0], [x + 100.0, y + 50.0])));
        // Without a band, everything may hold unknown points.
        let open = Scope {
            inner: None,
            ..sc
        };
        assert!(open.might_hold(&band, &all));
    }
}
