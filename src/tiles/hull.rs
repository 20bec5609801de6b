//! The convex hull of all the points, whose corners every tile's run holds (so that a run's hull
//! is the whole hull). They are real input points, so adding them to a run never changes a
//! certified triangle.

use crate::geom::predicates::{Orientation, orient};

fn xy(p: &[f64; 3]) -> [f64; 2] {
    [p[0], p[1]]
}

/// Andrew's monotone chain over `p` sorted lexicographically in some frame; `turn` is the
/// orientation a kept triple must have (counter-clockwise for an `(x, y)` order, clockwise for a
/// `(y, x)` order, which is a mirror image). Collinear points are left out.
fn chain(p: &[[f64; 3]], turn: Orientation) -> Vec<[f64; 3]> {
    let mut h: Vec<[f64; 3]> = Vec::new();
    for pass in 0..2 {
        let base = h.len();
        let it: Box<dyn Iterator<Item = &[f64; 3]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for q in it {
            while h.len() >= base + 2
                && orient(xy(&h[h.len() - 2]), xy(&h[h.len() - 1]), xy(q)) != turn
            {
                h.pop();
            }
            h.push(*q);
        }
        h.pop();
    }
    h
}

/// The corners of the convex hull of `v` (any order, duplicates allowed), counter-clockwise.
pub(crate) fn hull(v: &mut [[f64; 3]]) -> Vec<[f64; 3]> {
    v.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let mut d: Vec<[f64; 3]> = Vec::with_capacity(v.len());
    for p in v.iter() {
        if d.last().is_none_or(|q| q[0] != p[0] || q[1] != p[1]) {
            d.push(*p);
        }
    }
    if d.len() < 3 {
        return d;
    }
    chain(&d, Orientation::CounterClockwise)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_grid() {
        let mut v = vec![];
        for y in 0..4 {
            for x in 0..4 {
                v.push([x as f64, y as f64, 0.0]);
            }
        }
        v.push([1.5, 1.7, 0.0]);
        v.sort_by(|a, b| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0])));
        let square = vec![[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]];
        let from_origin = |mut h: Vec<[f64; 2]>| {
            let i = h.iter().position(|p| *p == [0.0, 0.0]).unwrap();
            h.rotate_left(i);
            h
        };
        let h = hull(&mut v.clone());
        assert_eq!(from_origin(h.iter().map(xy).collect()), square);
    }
}
