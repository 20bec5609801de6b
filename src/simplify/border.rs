//! Window borders: the cells of one side of a window, between two window corners, simplified in
//! one dimension to the error bound, so that both windows sharing the side start from the same
//! vertices on it (and their TINs conform).
//!
//! The side is a polyline through its cell centres: greedy insertion of the worst cell (the same
//! rule as the grid's, in 1-D: a segment's candidate is its cell farthest vertically from the
//! segment) until every cell is within the bound, then, with decimation, the removal (in order)
//! of every vertex whose neighbours' segment keeps its cells within the bound. In one dimension
//! segments do not interact, so the insertion order does not matter and the result is that of
//! recursive splitting. Missing cells follow the grid's rule: a segment over missing cells (or
//! with a missing end, a phantom corner) is split at the valid cell nearest to their centroid;
//! a segment over missing cells with no valid cell inside stays, and the triangles on it are
//! dropped on both sides.
//!
//! A segment is accepted when its cells are within the bound less a rounding margin: the
//! windows measure the same cells with the planes of their triangles (other roundings of the
//! same line), and must find them within the bound too.

/// The vertices (indices into `h`, increasing, the ends included) of the line of heights `h`
/// (NaN = missing) within `bound`; `decimate` removes the ones the bound does not need.
pub(super) fn simplify_line(h: &[f64], bound: f64, decimate: bool) -> Vec<usize> {
    let n = h.len();
    debug_assert!(n >= 2);
    let scale = h
        .iter()
        .filter(|v| !v.is_nan())
        .fold(1.0f64, |m, v| m.max(v.abs()));
    let limit = bound - 64e-12 * scale;
    simplify_by(
        n,
        |i, j| split(h, i, j, limit),
        |i, j| covers_missing(h, i, j),
        decimate,
    )
}

/// The one-dimensional simplification behind [`simplify_line`], for any line of `n` samples
/// (`sweeptin thin --tile` runs it on the TIN's sections along tile borders, at irregular
/// positions): `split(i, j)` names the sample where segment `i..=j` must be split (`None`: the
/// segment stays), `keep(i, j)` says that a segment must not replace its parts even so.
/// Returns the kept samples, increasing, the ends included.
pub(crate) fn simplify_by(
    n: usize,
    mut split: impl FnMut(usize, usize) -> Option<usize>,
    mut keep: impl FnMut(usize, usize) -> bool,
    decimate: bool,
) -> Vec<usize> {
    if n < 2 {
        return (0..n).collect();
    }
    let mut kept_flag = vec![false; n];
    kept_flag[0] = true;
    kept_flag[n - 1] = true;
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if let Some(k) = split(i, j) {
            kept_flag[k] = true;
            stack.push((k, j));
            stack.push((i, k));
        }
    }
    let mut out: Vec<usize> = (0..n).filter(|&i| kept_flag[i]).collect();
    if decimate && out.len() > 2 {
        let mut kept = Vec::with_capacity(out.len());
        kept.push(out[0]);
        for w in 1..out.len() - 1 {
            let (prev, next) = (*kept.last().expect("an end"), out[w + 1]);
            if split(prev, next).is_some() || keep(prev, next) {
                kept.push(out[w]);
            }
        }
        kept.push(out[out.len() - 1]);
        out = kept;
    }
    out
}

fn covers_missing(h: &[f64], i: usize, j: usize) -> bool {
    h[i..=j].iter().any(|v| v.is_nan())
}

/// Where segment `i..=j` must be split: its cell farthest from the segment when farther than
/// `limit`; over missing cells, the valid cell nearest to their centroid; `None` when the
/// segment stays.
fn split(h: &[f64], i: usize, j: usize, limit: f64) -> Option<usize> {
    if j <= i + 1 {
        return None;
    }
    if covers_missing(h, i, j) {
        let (sum, count) = (i..=j)
            .filter(|&k| h[k].is_nan())
            .fold((0.0, 0.0), |(s, c), k| (s + k as f64, c + 1.0));
        let centre = sum / count;
        let mut best: Option<(f64, usize)> = None;
        for (k, z) in h.iter().enumerate().take(j).skip(i + 1) {
            let d = (k as f64 - centre).abs();
            if !z.is_nan() && best.is_none_or(|(b, _)| d < b) {
                best = Some((d, k));
            }
        }
        return best.map(|(_, k)| k);
    }
    let (zi, zj) = (h[i], h[j]);
    let slope = (zj - zi) / (j - i) as f64;
    let (mut worst, mut at) = (limit, None);
    for (k, &z) in h.iter().enumerate().take(j).skip(i + 1) {
        let e = (z - (zi + slope * (k - i) as f64)).abs();
        if e > worst {
            worst = e;
            at = Some(k);
        }
    }
    at
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_straight_line_keeps_its_ends() {
        let h: Vec<f64> = (0..50).map(|k| 3.0 + 0.5 * k as f64).collect();
        assert_eq!(simplify_line(&h, 0.01, true), vec![0, 49]);
    }

    #[test]
    fn every_cell_is_within_the_bound() {
        let h: Vec<f64> = (0..300).map(|k| 40.0 * (k as f64 / 17.0).sin()).collect();
        for decimate in [false, true] {
            let v = simplify_line(&h, 0.5, decimate);
            assert!(v.len() > 2 && v[0] == 0 && *v.last().unwrap() == 299);
            for w in v.windows(2) {
                let (i, j) = (w[0], w[1]);
                for (k, z) in h.iter().enumerate().take(j).skip(i) {
                    let t = (k - i) as f64 / (j - i) as f64;
                    assert!((z - (h[i] + t * (h[j] - h[i]))).abs() <= 0.5);
                }
            }
        }
        assert!(simplify_line(&h, 0.5, true).len() <= simplify_line(&h, 0.5, false).len());
    }

    #[test]
    fn missing_cells_split_segments_until_no_valid_cell_is_left() {
        let mut h = vec![1.0; 20];
        h[0] = f64::NAN; // a phantom corner
        h[8] = f64::NAN;
        h[9] = f64::NAN;
        let v = simplify_line(&h, 1.0, true);
        // No kept segment has a valid cell strictly inside and a missing cell.
        for w in v.windows(2) {
            let (i, j) = (w[0], w[1]);
            if covers_missing(&h, i, j) {
                assert!((i + 1..j).all(|k| h[k].is_nan()), "{v:?}");
            }
        }
        assert!(v.contains(&1) && v.contains(&7) && v.contains(&10), "{v:?}");
    }
}
