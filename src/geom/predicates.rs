//! Every geometric decision of sweeptin, in one place.
//!
//! All orientation and in-circle signs come from [`robust`]'s adaptive-precision predicates
//! (Shewchuk's), so they are exact for every finite input in the supported range. Nothing else in
//! the crate compares areas or circles in floating point to make a decision; floating point is used
//! only for heuristics that cannot change the result (which triangle to try first).
//!
//! # The two artificial points
//!
//! The sweep (Domiter & Žalik 2008, section 3.3) starts from two artificial points `P-1` and `P-2`
//! below the data. Here they are *symbolic*: `P-1 = (-M, -M²)` and `P-2 = (+M, -M²)` in the local
//! frame, with `M → ∞`. Every predicate that involves them is the sign of the leading term of its
//! polynomial in `M`, which reduces to exact comparisons and real orientations:
//!
//! * `orient(P-1, a, b) = sign(a.x - b.x)`, ties broken by `sign(b.y - a.y)`;
//! * `orient(P-2, a, b) = sign(a.x - b.x)`, ties broken by `sign(a.y - b.y)`;
//! * `orient(P-1, P-2, a) = +1`;
//! * `incircle(P, b, c, d) = orient(b, c, d)`, or, when `b, c, d` are collinear, *inside* exactly
//!   when `d` lies strictly between `b` and `c`;
//! * `incircle(P-1, P-2, c, d) = sign(c.y - d.y)`, then `sign(|c.x| - |d.x|)`.
//!
//! Because the artificial points are infinitely far away, no circle through three real points
//! contains them, so the real triangles of the Delaunay triangulation of the data plus `P-1` and `P-2`
//! are exactly the Delaunay triangulation of the data: removing the artificial triangles at the end
//! leaves the convex hull closed, with no repair step (the paper's section 3.5 "adding the bordering
//! triangles" is not needed). The placement also does not depend on the data's bounding box, which
//! the streaming sweep does not know in advance.
//!
//! # Tie-breaking rule (cocircular points)
//!
//! Gridded lidar is full of four cocircular points, where the Delaunay triangulation is not unique.
//! sweeptin resolves every such tie by *symbolic perturbation of the lifting map*: each point's lifted
//! height `x² + y²` is raised by `ε^k`, where the point that comes **later in sweep order** (larger
//! `y`, then larger `x`) gets the larger raise. When four real points are exactly cocircular, the
//! in-circle sign is therefore the sign of the cofactor of the latest of the four points, which is
//! one exact [`orient`] of the other three (never zero: three distinct points on a circle are never
//! collinear). The triangulation is then the unique Delaunay triangulation of the perturbed points; it
//! depends only on the set of input positions, never on input order, memory budget, thread count or
//! hash capacity. A consequence used by streaming: a later point that lies exactly on a circumcircle is
//! always *outside* it.
//!
//! The rule is stated in the sweep's own frame. A streaming run over a strip may sweep along the
//! world's x (`--sweep-axis`, see [`crate::pipeline::SweepAxis`]): the points then enter the sweep
//! with x and y exchanged, so "later" means larger world x, then larger world y. The axis is chosen
//! from the input alone, so the output still depends only on the input.
//!
//! # Supported coordinates
//!
//! Shewchuk's predicates are exact unless an intermediate product underflows or overflows. Input
//! coordinates (after the local origin is removed) must therefore be finite, at most [`MAX_COORD`] in
//! magnitude, and either zero or at least [`MIN_NONZERO_COORD`] in magnitude; [`check_coord`] enforces
//! this once, at input.

use robust::Coord;
use std::cmp::Ordering;

/// Largest coordinate magnitude accepted (2^52 ≈ 4.5e15; in-circle terms stay far from overflow).
pub const MAX_COORD: f64 = 4_503_599_627_370_496.0;
/// Smallest non-zero coordinate magnitude accepted (keeps every product of the adaptive predicates
/// clear of underflow).
pub const MIN_NONZERO_COORD: f64 = 1e-30;

/// Id of the artificial point `P-1` (far below, to the left).
pub const P_LEFT: u32 = 0;
/// Id of the artificial point `P-2` (far below, to the right).
pub const P_RIGHT: u32 = 1;
/// Ids below this are artificial.
pub const FIRST_REAL: u32 = 2;

/// Is `v` one of the two artificial points?
#[inline(always)]
pub fn is_artificial(v: u32) -> bool {
    v < FIRST_REAL
}

/// Is a coordinate value in the range where the predicates are exact?
#[inline]
pub fn check_coord(v: f64) -> bool {
    let a = v.abs();
    a <= MAX_COORD && (a == 0.0 || a >= MIN_NONZERO_COORD)
}

/// Orientation of an ordered triple of points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orientation {
    /// The triple turns right.
    Clockwise,
    /// The three points are on one line.
    Collinear,
    /// The triple turns left.
    CounterClockwise,
}

impl Orientation {
    #[inline(always)]
    fn from_f64(d: f64) -> Self {
        if d > 0.0 {
            Orientation::CounterClockwise
        } else if d < 0.0 {
            Orientation::Clockwise
        } else {
            Orientation::Collinear
        }
    }

    #[inline(always)]
    fn from_ordering(o: Ordering) -> Self {
        match o {
            Ordering::Greater => Orientation::CounterClockwise,
            Ordering::Less => Orientation::Clockwise,
            Ordering::Equal => Orientation::Collinear,
        }
    }

    /// The orientation of the reversed triple.
    #[inline(always)]
    pub fn reversed(self) -> Self {
        match self {
            Orientation::Clockwise => Orientation::CounterClockwise,
            Orientation::Collinear => Orientation::Collinear,
            Orientation::CounterClockwise => Orientation::Clockwise,
        }
    }

    /// Is the triple a left turn?
    #[inline(always)]
    pub fn is_ccw(self) -> bool {
        self == Orientation::CounterClockwise
    }
}

/// Where a point lies relative to a circle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CircleSide {
    /// Strictly inside.
    Inside,
    /// Exactly on the circle (only from the unperturbed [`incircle_exact`]).
    On,
    /// Strictly outside.
    Outside,
}

#[inline(always)]
fn c(p: [f64; 2]) -> Coord<f64> {
    Coord { x: p[0], y: p[1] }
}

/// Exact orientation of three real points: counter-clockwise when `c` is left of `a → b`.
#[inline(always)]
pub fn orient(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> Orientation {
    Orientation::from_f64(robust::orient2d(c(a), c(b), c(p)))
}

/// Is `p` on the closed segment `a b`? Exact: collinear by [`orient`], and within the
/// segment's box.
#[inline]
pub fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    orient(a, b, p) == Orientation::Collinear
        && a[0].min(b[0]) <= p[0]
        && p[0] <= a[0].max(b[0])
        && a[1].min(b[1]) <= p[1]
        && p[1] <= a[1].max(b[1])
}

/// The orientation determinant of `a, b, p` (twice the signed area), from [`robust`]'s adaptive
/// evaluation: its sign is exact and its value never less accurate than the plain floating-point
/// formula. For constructions (such as where two segments cross), never for decisions: decide with
/// [`orient`].
#[inline]
pub fn orient_det(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    robust::orient2d(c(a), c(b), c(p))
}

/// Exact, unperturbed in-circle test: where `d` lies relative to the circle through the
/// counter-clockwise triangle `a, b, c`.
#[inline(always)]
pub fn incircle_exact(a: [f64; 2], b: [f64; 2], p: [f64; 2], d: [f64; 2]) -> CircleSide {
    let r = robust::incircle(c(a), c(b), c(p), c(d));
    if r > 0.0 {
        CircleSide::Inside
    } else if r < 0.0 {
        CircleSide::Outside
    } else {
        CircleSide::On
    }
}

/// Sweep order: by `y`, then by `x`.
#[inline(always)]
pub fn sweep_cmp(a: [f64; 2], b: [f64; 2]) -> Ordering {
    a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0]))
}

/// Perturbed in-circle test of four distinct real points, `a, b, c` counter-clockwise.
/// Never returns [`CircleSide::On`]; ties follow the module's documented rule.
#[inline(always)]
pub fn incircle(a: [f64; 2], b: [f64; 2], p: [f64; 2], d: [f64; 2]) -> CircleSide {
    let r = robust::incircle(c(a), c(b), c(p), c(d));
    if r > 0.0 {
        CircleSide::Inside
    } else if r < 0.0 {
        CircleSide::Outside
    } else {
        incircle_tie(a, b, p, d)
    }
}

#[cold]
#[inline(never)]
fn incircle_tie(a: [f64; 2], b: [f64; 2], p: [f64; 2], d: [f64; 2]) -> CircleSide {
    // The latest point in sweep order carries the dominant perturbation of its lifted height.
    // The in-circle determinant's derivative with respect to each lifted height is:
    //   a: orient(b, c, d)   b: orient(c, a, d)   c: orient(a, b, d)   d: -orient(a, b, c).
    let pts = [a, b, p, d];
    let mut latest = 0;
    for i in 1..4 {
        if sweep_cmp(pts[i], pts[latest]) == Ordering::Greater {
            latest = i;
        }
    }
    let o = match latest {
        0 => orient(b, p, d),
        1 => orient(p, a, d),
        2 => orient(a, b, d),
        _ => orient(a, b, p).reversed(),
    };
    match o {
        Orientation::CounterClockwise => CircleSide::Inside,
        Orientation::Clockwise => CircleSide::Outside,
        // Only reachable for degenerate input (a repeated point or a collinear "triangle").
        Orientation::Collinear => CircleSide::Outside,
    }
}

/// Orientation of three vertices given by id, any of which may be artificial.
#[inline(always)]
pub fn orient_ids(pts: &[[f64; 2]], a: u32, b: u32, p: u32) -> Orientation {
    if a >= FIRST_REAL && b >= FIRST_REAL && p >= FIRST_REAL {
        return orient(pts[a as usize], pts[b as usize], pts[p as usize]);
    }
    orient_symbolic(pts, a, b, p)
}

#[inline(never)]
fn orient_symbolic(pts: &[[f64; 2]], a: u32, b: u32, p: u32) -> Orientation {
    // Rotate (a cyclic shift keeps the sign) until an artificial point is first.
    let (a, b, p) = if is_artificial(a) {
        (a, b, p)
    } else if is_artificial(b) {
        (b, p, a)
    } else {
        (p, a, b)
    };
    if is_artificial(b) {
        // (P, P', x): P-1 → P-2 is the bottom edge, every real point is above it.
        return if a == b {
            Orientation::Collinear
        } else if a == P_LEFT {
            Orientation::CounterClockwise
        } else {
            Orientation::Clockwise
        };
    }
    if is_artificial(p) {
        // (P, x, P') is a rotation of (P', P, x).
        return if a == p {
            Orientation::Collinear
        } else if p == P_LEFT {
            Orientation::CounterClockwise
        } else {
            Orientation::Clockwise
        };
    }
    let (u, v) = (pts[b as usize], pts[p as usize]);
    let by_x = u[0].total_cmp(&v[0]);
    let o = if by_x != Ordering::Equal {
        by_x
    } else if a == P_LEFT {
        v[1].total_cmp(&u[1])
    } else {
        u[1].total_cmp(&v[1])
    };
    Orientation::from_ordering(o)
}

/// Perturbed in-circle test of four vertices given by id (`a, b, c` counter-clockwise), any of which
/// may be artificial. Never returns [`CircleSide::On`].
#[inline(always)]
pub fn incircle_ids(pts: &[[f64; 2]], a: u32, b: u32, p: u32, d: u32) -> CircleSide {
    if a >= FIRST_REAL && b >= FIRST_REAL && p >= FIRST_REAL && d >= FIRST_REAL {
        return incircle(
            pts[a as usize],
            pts[b as usize],
            pts[p as usize],
            pts[d as usize],
        );
    }
    incircle_symbolic(pts, [a, b, p, d])
}

#[inline(never)]
fn incircle_symbolic(pts: &[[f64; 2]], ids: [u32; 4]) -> CircleSide {
    // Move the artificial rows of the 4x4 lifted determinant to the top, keeping the others in
    // order; every transposition flips the determinant's sign.
    let mut order = [0u32; 4];
    let mut n = 0;
    let mut flips = 0;
    for (i, &v) in ids.iter().enumerate() {
        if is_artificial(v) {
            // It jumps over the (i - n) real rows before it.
            flips += i - n;
            order[n] = v;
            n += 1;
        }
    }
    let n_art = n;
    for &v in ids.iter() {
        if !is_artificial(v) {
            order[n] = v;
            n += 1;
        }
    }
    let side = match n_art {
        1 => {
            // Rows (P, b, c, d): det = M⁴·orient(b, c, d) + M²·X + M·Y + …
            let (b, p, d) = (
                pts[order[1] as usize],
                pts[order[2] as usize],
                pts[order[3] as usize],
            );
            match orient(b, p, d) {
                Orientation::CounterClockwise => 1,
                Orientation::Clockwise => -1,
                Orientation::Collinear => collinear_lift_sign(order[0], b, p, d),
            }
        }
        2 => {
            let (p, d) = (pts[order[2] as usize], pts[order[3] as usize]);
            // Rows (P-1, P-2, c, d): det = 2M⁵(c.y - d.y) + 2M³(c.x² - d.x²) + ...
            let mut s = match p[1].total_cmp(&d[1]) {
                Ordering::Greater => 1,
                Ordering::Less => -1,
                Ordering::Equal => match p[0].abs().total_cmp(&d[0].abs()) {
                    Ordering::Greater => 1,
                    Ordering::Less => -1,
                    // Genuinely cocircular for every M: the later point dominates. Its lifted
                    // height's cofactor is +1 for row c and -1 for row d.
                    Ordering::Equal => {
                        if sweep_cmp(p, d) == Ordering::Greater {
                            1
                        } else {
                            -1
                        }
                    }
                },
            };
            if order[0] == P_RIGHT {
                s = -s;
            }
            s
        }
        _ => -1,
    };
    let side = if flips % 2 == 1 { -side } else { side };
    if side > 0 {
        CircleSide::Inside
    } else {
        CircleSide::Outside
    }
}

/// Sign of the lower-order terms of the lifted determinant with rows `(P, b, c, d)` when `b, c, d`
/// are collinear. Parametrising the line, the lifted heights are a convex parabola, so the `M²`
/// coefficient is a positive multiple of `(c.x - b.x)(d.x - b.x)(d.x - c.x)` (a Vandermonde
/// determinant). On a vertical line that vanishes and the `M` coefficient decides: `∓(c.y - b.y)
/// (d.y - b.y)(d.y - c.y)`, negative sign for `P-1` (x = -M), positive for `P-2` (x = +M).
fn collinear_lift_sign(artificial: u32, b: [f64; 2], p: [f64; 2], d: [f64; 2]) -> i32 {
    let sgn = |o: Ordering| match o {
        Ordering::Greater => 1,
        Ordering::Less => -1,
        Ordering::Equal => 0,
    };
    let vandermonde = |k: usize| {
        sgn(p[k].total_cmp(&b[k])) * sgn(d[k].total_cmp(&b[k])) * sgn(d[k].total_cmp(&p[k]))
    };
    let s = vandermonde(0);
    if s != 0 {
        return s;
    }
    let s = vandermonde(1);
    if artificial == P_LEFT { -s } else { s }
}

/// A conservative bound of a triangle's circumdisk: the true disk lies inside
/// `[x_min, x_max] × (-∞, top]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskBounds {
    /// Upper bound of the disk's highest y.
    pub top: f64,
    /// Lower bound of the disk's smallest x.
    pub x_min: f64,
    /// Upper bound of the disk's largest x.
    pub x_max: f64,
    /// The centre, as computed.
    pub center: [f64; 2],
    /// An upper bound of the radius plus the centre's error: the true disk lies within this
    /// distance of `center`.
    pub radius: f64,
}

/// Bounds the circumdisk of triangle `a, b, c` in floating point, enlarged by a generous bound on
/// the rounding error, so that the true disk is always inside the bounds (used only to decide that a
/// triangle can no longer change: an error can delay that decision, never hasten it). Returns `None`
/// for triangles too flat to bound reliably (condition number above 1e8) or non-finite results.
///
/// Error analysis: with `b' = b - a`, `c' = c - a` (relative error ε each), the denominator
/// `D = 2(b'x c'y - b'y c'x)` has absolute error below `4ε·P` with `P = 2(|b'x c'y| + |b'y c'x|)`;
/// the numerators `Nx = c'y|b'|² - b'y|c'|²` (and `Ny`) below `8ε` times their absolute-value sums.
/// The centre offset `u = N / D` then errs by at most `ε(10κ|u| + 10|N|abs/|D|)` with `κ = P/|D|`, the
/// radius by the sum of both components' errors, and the final sums by a few ulps of their
/// magnitude. The bound used is 16 times all of that.
pub fn circumdisk_bounds(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> Option<DiskBounds> {
    const EPS: f64 = f64::EPSILON / 2.0;
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (p[0] - a[0], p[1] - a[1]);
    let (bb, cc) = (bx * bx + by * by, cx * cx + cy * cy);
    let d = 2.0 * (bx * cy - by * cx);
    let perm = 2.0 * ((bx * cy).abs() + (by * cx).abs());
    let kappa = perm / d.abs();
    if d == 0.0 || kappa.is_nan() || kappa > 1e8 {
        return None;
    }
    let (nx, ny) = (cy * bb - by * cc, bx * cc - cx * bb);
    let (nx_abs, ny_abs) = (cy.abs() * bb + by.abs() * cc, bx.abs() * cc + cx.abs() * bb);
    let (ux, uy) = (nx / d, ny / d);
    let r = (ux * ux + uy * uy).sqrt();
    let e_ux = EPS * (10.0 * kappa * ux.abs() + 10.0 * nx_abs / d.abs());
    let e_uy = EPS * (10.0 * kappa * uy.abs() + 10.0 * ny_abs / d.abs());
    let (cx0, cy0) = (a[0] + ux, a[1] + uy);
    let err = 16.0
        * (e_ux + e_uy + 4.0 * EPS * (r + cx0.abs() + cy0.abs() + a[0].abs() + a[1].abs()))
        + f64::MIN_POSITIVE;
    let out = DiskBounds {
        top: cy0 + r + err,
        x_min: cx0 - r - err,
        x_max: cx0 + r + err,
        center: [cx0, cy0],
        radius: r + err,
    };
    if out.top.is_finite() && out.x_min.is_finite() && out.x_max.is_finite() {
        Some(out)
    } else {
        None
    }
}

/// A triangle's plane in 3-D, for deciding whether points lie within a vertical distance of it
/// (the thinning's tolerance test, [`crate::simplify::thin()`]).
///
/// For a counter-clockwise triangle `a, b, c` and a point `p`, Shewchuk's 3-D orientation
/// `orient3d(a, b, c, p) = D2 · (plane(p) − p.z)` with `D2 = orient2d(a, b, c) > 0`, so the
/// vertical distance is `|orient3d| / D2`. [`VerticalPlane::check`] first bounds both
/// determinants in floating point with Shewchuk's error bounds for their first stage (`(7 + 56ε)ε`
/// times the permanent for `orient3d`, `(3 + 16ε)ε` for `orient2d`), which certifies most points as
/// within or beyond the tolerance; the rest are decided by [`robust`]'s exact `orient3d` on the
/// points `(p.x, p.y, lo)` and `(p.x, p.y, hi)`, where `lo ≥ z − tol` and `hi ≤ z + tol` are
/// `z ∓ tol` rounded towards `z`: the point is within when the plane passes between them. So a
/// point is reported within only when it provably is; a point within by less than one unit in the
/// last place of its `z` may be reported beyond (and then kept by the thinning), never the reverse.
#[derive(Clone, Copy, Debug)]
pub struct VerticalPlane {
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
    /// `orient2d(a, b, c)` in floating point, and a bound on its error.
    d2: f64,
    d2_err: f64,
}

/// What [`VerticalPlane::check`] found for one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertical {
    /// The vertical distance `|plane(p) − p.z|` in floating point (for ranking and statistics,
    /// not for decisions).
    pub error: f64,
    /// The point is (provably) within the tolerance.
    pub within: bool,
    /// The floating-point bound could not decide: exact `orient3d` did.
    pub exact: bool,
}

impl VerticalPlane {
    /// The plane of the counter-clockwise triangle `a, b, c` (which must not be degenerate).
    #[inline]
    pub fn new(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> VerticalPlane {
        const CCW_A: f64 = (3.0 + 16.0 * SHEWCHUK_EPS) * SHEWCHUK_EPS;
        let l = (a[0] - c[0]) * (b[1] - c[1]);
        let r = (a[1] - c[1]) * (b[0] - c[0]);
        VerticalPlane {
            a,
            b,
            c,
            d2: l - r,
            d2_err: CCW_A * (l.abs() + r.abs()),
        }
    }

    /// Is `p` (inside the triangle, or anywhere) within `tol` of the plane vertically?
    #[inline]
    pub fn check(&self, p: [f64; 3], tol: f64) -> Vertical {
        const O3D_A: f64 = (7.0 + 56.0 * SHEWCHUK_EPS) * SHEWCHUK_EPS;
        // A relative margin for the few roundings of the bounds themselves.
        const MARGIN: f64 = 1e-12;
        let (a, b, c) = (self.a, self.b, self.c);
        let (adx, bdx, cdx) = (a[0] - p[0], b[0] - p[0], c[0] - p[0]);
        let (ady, bdy, cdy) = (a[1] - p[1], b[1] - p[1], c[1] - p[1]);
        let (adz, bdz, cdz) = (a[2] - p[2], b[2] - p[2], c[2] - p[2]);
        let (bdxcdy, cdxbdy) = (bdx * cdy, cdx * bdy);
        let (cdxady, adxcdy) = (cdx * ady, adx * cdy);
        let (adxbdy, bdxady) = (adx * bdy, bdx * ady);
        let det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
        let permanent = (bdxcdy.abs() + cdxbdy.abs()) * adz.abs()
            + (cdxady.abs() + adxcdy.abs()) * bdz.abs()
            + (adxbdy.abs() + bdxady.abs()) * cdz.abs();
        let err3 = O3D_A * permanent;
        let error = (det / self.d2).abs();
        let d2 = self.d2.abs();
        if d2 > self.d2_err {
            let upper = (det.abs() + err3) / (d2 - self.d2_err) * (1.0 + MARGIN);
            if upper <= tol {
                return Vertical {
                    error,
                    within: true,
                    exact: false,
                };
            }
            let lower = (det.abs() - err3) / (d2 + self.d2_err) * (1.0 - MARGIN);
            if lower > tol {
                return Vertical {
                    error,
                    within: false,
                    exact: false,
                };
            }
        }
        Vertical {
            error,
            within: self.within_exact(p, tol),
            exact: true,
        }
    }

    /// The exact test: does the plane pass between `(p.x, p.y, lo)` and `(p.x, p.y, hi)`?
    fn within_exact(&self, p: [f64; 3], tol: f64) -> bool {
        let (lo, hi) = (sub_up(p[2], tol), add_down(p[2], tol));
        if lo > hi {
            return false;
        }
        let c3 = |q: [f64; 3]| robust::Coord3D {
            x: q[0],
            y: q[1],
            z: q[2],
        };
        let s = self.d2.signum();
        let below = robust::orient3d(c3(self.a), c3(self.b), c3(self.c), c3([p[0], p[1], lo]));
        let above = robust::orient3d(c3(self.a), c3(self.b), c3(self.c), c3([p[0], p[1], hi]));
        // Counter-clockwise: positive when the point is below the plane.
        s * below >= 0.0 && s * above <= 0.0
    }
}

/// Shewchuk's ε: half a unit in the last place of 1.
const SHEWCHUK_EPS: f64 = f64::EPSILON / 2.0;

/// `z − t` rounded up (never below the exact difference).
fn sub_up(z: f64, t: f64) -> f64 {
    let s = z - t;
    // Two-sum: `s + err` is exactly `z − t`.
    let bv = s - z;
    let av = s - bv;
    let err = (z - av) + (-t - bv);
    if err > 0.0 { s.next_up() } else { s }
}

/// `z + t` rounded down (never above the exact sum).
fn add_down(z: f64, t: f64) -> f64 {
    let s = z + t;
    let bv = s - z;
    let av = s - bv;
    let err = (z - av) + (t - bv);
    if err < 0.0 { s.next_down() } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(real: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let mut t = vec![[f64::NAN; 2]; 2];
        t.extend_from_slice(real);
        t
    }

    #[test]
    fn real_orientation() {
        assert!(orient([0., 0.], [1., 0.], [0., 1.]).is_ccw());
        assert_eq!(orient([0., 0.], [1., 1.], [2., 2.]), Orientation::Collinear);
        assert_eq!(orient([0., 0.], [0., 1.], [1., 0.]), Orientation::Clockwise);
    }

    #[test]
    fn artificial_orientation_matches_large_finite_points() {
        // Compare the symbolic rules with actual far-away points in exact arithmetic on small
        // integer data, where M = 1e6 is already "large enough".
        let m = 1.0e6;
        let far = [[-m, -m * m], [m, -m * m]];
        let real = [
            [0., 0.],
            [1., 0.],
            [0., 1.],
            [1., 1.],
            [-2., 3.],
            [0., 5.],
            [3., 3.],
        ];
        let pts = table(&real);
        let coord = |v: u32| {
            if v < 2 {
                far[v as usize]
            } else {
                real[(v - 2) as usize]
            }
        };
        let n = real.len() as u32 + 2;
        for a in 0..n {
            for b in 0..n {
                for p in 0..n {
                    if a == b || b == p || a == p {
                        continue;
                    }
                    let want = orient(coord(a), coord(b), coord(p));
                    assert_eq!(orient_ids(&pts, a, b, p), want, "{a} {b} {p}");
                }
            }
        }
    }

    #[test]
    fn artificial_incircle_matches_large_finite_points() {
        let m = 1.0e5;
        let far = [[-m, -m * m], [m, -m * m]];
        let real = [
            [0., 0.],
            [1., 0.],
            [0., 1.],
            [2., 1.],
            [-2., 3.],
            [0., 5.],
            [3., 3.],
            [2., 0.],
            [-1., 0.],
            [0., -2.],
            [1., 1.],
        ];
        let pts = table(&real);
        let coord = |v: u32| {
            if v < 2 {
                far[v as usize]
            } else {
                real[(v - 2) as usize]
            }
        };
        let n = real.len() as u32 + 2;
        let mut checked = 0;
        for a in 0..n {
            for b in 0..n {
                for p in 0..n {
                    for d in 0..n {
                        let ids = [a, b, p, d];
                        if (0..4).any(|i| (i + 1..4).any(|j| ids[i] == ids[j])) {
                            continue;
                        }
                        if !orient(coord(a), coord(b), coord(p)).is_ccw() {
                            continue;
                        }
                        let want = incircle_exact(coord(a), coord(b), coord(p), coord(d));
                        if want == CircleSide::On {
                            continue;
                        }
                        assert_eq!(incircle_ids(&pts, a, b, p, d), want, "{ids:?}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 1000);
    }

    #[test]
    fn cocircular_tie_is_decided_by_latest_point() {
        // Unit square: cocircular. Latest point in sweep order is (1, 1).
        let (a, b, p, d) = ([0., 0.], [1., 0.], [1., 1.], [0., 1.]);
        assert_eq!(incircle_exact(a, b, p, d), CircleSide::On);
        // d = (0,1) is not the latest; c = (1,1) is: sign = orient(a, b, d) > 0 → inside.
        assert_eq!(incircle(a, b, p, d), CircleSide::Inside);
        // Same quadrilateral, other diagonal: triangle (a, b, d), query c = latest → outside.
        assert_eq!(incircle(a, b, d, p), CircleSide::Outside);
        // The rule is invariant under rotating the triangle's vertices.
        assert_eq!(incircle(b, p, a, d), CircleSide::Inside);
        assert_eq!(incircle(p, a, b, d), CircleSide::Inside);
    }

    #[test]
    fn coordinate_range() {
        assert!(check_coord(0.0));
        assert!(check_coord(4.0e6));
        assert!(check_coord(-1e-9));
        assert!(!check_coord(1e-40));
        assert!(!check_coord(1e20));
        assert!(!check_coord(f64::NAN));
    }

    #[test]
    fn vertical_tolerance_is_decided_exactly_at_the_boundary() {
        // A tilted plane z = 0.25 x + 0.5 y over UTM-sized coordinates (exact in binary).
        let (x0, y0) = (511_000.0, 122_000.0);
        let z = |x: f64, y: f64| 300.0 + 0.25 * (x - x0) + 0.5 * (y - y0);
        let a = [x0, y0, z(x0, y0)];
        let b = [x0 + 8.0, y0, z(x0 + 8.0, y0)];
        let c = [x0, y0 + 8.0, z(x0, y0 + 8.0)];
        for plane in [VerticalPlane::new(a, b, c), VerticalPlane::new(a, c, b)] {
            let (px, py) = (x0 + 2.0, y0 + 3.0);
            let on = z(px, py);
            // Exactly at the tolerance (0.125 is exact): within, above and below.
            for d in [0.125, -0.125] {
                let v = plane.check([px, py, on + d], 0.125);
                assert!(v.within, "{d}");
                assert!(v.exact, "the boundary needs the exact test");
            }
            // One unit in the last place beyond: not within.
            let beyond = (on + 0.125).next_up();
            assert!(!plane.check([px, py, beyond], 0.125).within);
            assert!(!plane.check([px, py, on - 0.126], 0.125).within);
            // Far inside and far outside: decided by the floating-point bound.
            let v = plane.check([px, py, on + 0.01], 0.125);
            assert!(v.within && !v.exact && (v.error - 0.01).abs() < 1e-9);
            let v = plane.check([px, py, on + 1.0], 0.125);
            assert!(!v.within && !v.exact);
            // Tolerance 0: only points exactly on the plane.
            assert!(plane.check([px, py, on], 0.0).within);
            assert!(!plane.check([px, py, on.next_up()], 0.0).within);
        }
    }
}
