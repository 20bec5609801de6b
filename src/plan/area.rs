//! The plan's geometry: tile rectangles, their buffers and overlaps, which tiles the data's hull
//! meets and which hold cell centres.

use super::task;

/// Is `tile` a whole multiple of `cell` (to a relative 1e-9)?
pub(super) fn whole_multiple(tile: f64, cell: f64) -> bool {
    let k = tile / cell;
    (k - k.round()).abs() <= 1e-9 * k.max(1.0)
}

/// The bounds of tile `(tx, ty)` of side `tile`, as every plan computes them.
pub(super) fn tile_bounds(tx: i64, ty: i64, tile: f64) -> [f64; 4] {
    [
        tx as f64 * tile,
        ty as f64 * tile,
        (tx + 1) as f64 * tile,
        (ty + 1) as f64 * tile,
    ]
}

/// The tile that owns the point or cell centre `(x, y)`: columns by floor, rows by ceil − 1,
/// so a tile owns `[x0, x1) × (y0, y1]` (a centre on a tile's lower edge belongs to the row
/// below). Every plan tiles the data with it.
pub(super) fn tile_of(x: f64, y: f64, tile: f64) -> (i64, i64) {
    ((x / tile).floor() as i64, (y / tile).ceil() as i64 - 1)
}

pub(super) fn grown(b: [f64; 4], d: f64) -> [f64; 4] {
    [b[0] - d, b[1] - d, b[2] + d, b[3] + d]
}

/// For a job whose only output is a raster, the first and last cell centres inside `lo..hi`
/// (`None` otherwise, or when no centre lies inside).
pub(super) fn centres_within(
    product: &task::Product,
    lo: [f64; 2],
    hi: [f64; 2],
) -> Option<([f64; 2], [f64; 2])> {
    let task::Product::Dem {
        cell,
        align,
        contours: None,
        ..
    } = product
    else {
        return None;
    };
    use crate::raster::{centre, exact_index, first_centre, last_centre};
    let (c, off) = (*cell, align.offset());
    if lo.iter().chain(&hi).any(|&v| exact_index(v, c).is_err()) {
        return None;
    }
    // The centres as one run's grid finds them (`GridPlan::grid`).
    let first = |v: f64| centre(first_centre(v, c, off), c, off);
    let last = |v: f64| centre(last_centre(v, c, off), c, off);
    let (a, b) = ([first(lo[0]), first(lo[1])], [last(hi[0]), last(hi[1])]);
    (a[0] <= b[0] && a[1] <= b[1]).then_some((a, b))
}

/// Does the closed convex polygon `hull` (counter-clockwise corners; one or two for a point or a
/// segment) meet the closed rectangle `r`? Exact: they are apart exactly when an axis of the
/// rectangle or an edge of the polygon separates them.
pub(super) fn meets_hull(hull: &[[f64; 2]], r: &[f64; 4]) -> bool {
    use crate::geom::predicates::{Orientation, orient};
    match hull {
        [] => false,
        [a] => crate::tiles::region::tri_meets_rect(&[*a, *a, *a], r),
        [a, b] => crate::tiles::region::tri_meets_rect(&[*a, *b, *b], r),
        _ => {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in hull {
                lo = [lo[0].min(p[0]), lo[1].min(p[1])];
                hi = [hi[0].max(p[0]), hi[1].max(p[1])];
            }
            let corners = [[r[0], r[1]], [r[2], r[1]], [r[2], r[3]], [r[0], r[3]]];
            overlaps(&[lo[0], lo[1], hi[0], hi[1]], r)
                && !(0..hull.len()).any(|i| {
                    let (p, q) = (hull[i], hull[(i + 1) % hull.len()]);
                    corners
                        .iter()
                        .all(|&c| orient(p, q, c) == Orientation::Clockwise)
                })
        }
    }
}

/// Do the closed rectangles `a` and `b` meet?
pub(super) fn overlaps(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] && a[2] >= b[0] && a[1] <= b[3] && a[3] >= b[1]
}

/// Tiles of side `tile` a plan cuts `[lo, hi]` into (the bounding grid; NaN when it overflows).
pub(super) fn tile_count(lo: [f64; 2], hi: [f64; 2], tile: f64) -> f64 {
    let cols = (hi[0] / tile).floor() - (lo[0] / tile).floor() + 1.0;
    let rows = (hi[1] / tile).ceil() - (lo[1] / tile).ceil() + 1.0;
    cols * rows
}

/// The smallest round tile side (1, 2, 2.5 or 5 times a power of ten; a whole multiple of
/// `cell` when given) that cuts `[lo, hi]` into at most `max` tiles: what a refusal suggests.
pub(super) fn fitting_tile(lo: [f64; 2], hi: [f64; 2], max: u64, cell: Option<f64>) -> f64 {
    let (w, h) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
    let need = ((w * h) / max as f64).sqrt().max((w + h) / max as f64);
    let k0 = (need.max(1e-9).log10().floor() as i32 - 1).max(-9);
    // Four tiles (2 × 2) always fit past the extent's side; the bound only ends the loop.
    for k in k0..k0 + 400 {
        for m in [1.0, 2.0, 2.5, 5.0] {
            let mut t = m * 10f64.powi(k);
            if let Some(c) = cell {
                t = (t / c).ceil().max(1.0) * c;
            }
            let n = tile_count(lo, hi, t);
            if n.is_finite() && n <= max as f64 {
                return t;
            }
        }
    }
    (w.max(h) * 2.0).max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_suggested_tile_fits_and_is_the_smallest_round_one() {
        for (lo, hi, cell) in [
            ([0.0, 0.0], [59.0, 59.0], None),
            (
                [500_000.0, 5_000_000.0],
                [501_000.0, 5_002_000.0],
                Some(0.5),
            ),
            ([0.0, 0.0], [1e6, 3.0], None),
            ([3.0, 3.0], [3.0, 3.0], Some(1.0)),
        ] {
            for max in [4u64, 7, 1000, 1 << 18] {
                let t = fitting_tile(lo, hi, max, cell);
                assert!(
                    tile_count(lo, hi, t) <= max as f64,
                    "{lo:?} {hi:?} {max}: {t}"
                );
                if let Some(c) = cell {
                    assert!(whole_multiple(t, c), "{t} {c}");
                } else if t > 1e-9 {
                    // The next smaller round side does not fit.
                    let smaller = t / 2.0;
                    assert!(
                        tile_count(lo, hi, smaller) > max as f64,
                        "{lo:?} {hi:?} {max}: {t}"
                    );
                }
            }
        }
    }
}
