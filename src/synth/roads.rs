//! A synthetic road network: breaklines with every degeneracy the cleaner handles, at any size.
//!
//! | piece | what it gives the cleaner |
//! |---|---|
//! | streets along the rows and columns of a jittered grid, cut into polylines that share their end nodes | shared vertices, exactly horizontal and vertical segments, crossings at common vertices |
//! | nodes a street skips (about one in ten) | T-junctions: a vertex of the crossing street on a segment's interior |
//! | street pieces laid twice, some from a point half-way between nodes | duplicate segments, collinear overlaps |
//! | highways: wobbly polylines across the square | proper crossings (new vertices), with `z` that disagrees (bridges) |
//! | roundabouts: straight lines through one point, half of them with the point as a vertex | many segments through one point (snapping) |
//!
//! Coordinates are multiples of `2^-10` (exact, and their mid-points too), in the square
//! `[0, 1000] × [0, 1000]`; `z` is a smooth function of the position ([`road_height`]). A pure
//! function of its arguments, like the rest of [`crate::synth`].

use super::{SQUARE, SplitMix64};

/// Coordinates are rounded to multiples of this.
const LATTICE: f64 = 1.0 / 1024.0;

fn snap(v: f64) -> f64 {
    (v / LATTICE).round() * LATTICE
}

/// The height of the road network's terrain at `(x, y)` (also that of [`road_points`]).
pub fn road_height(x: f64, y: f64) -> f64 {
    100.0 + 20.0 * (x / 97.0).sin() * (y / 131.0).cos() + 0.01 * x
}

/// A road network of about `n_segments` input segments in the square (see the module docs).
pub fn roads(n_segments: usize, seed: u64) -> Vec<Vec<[f64; 3]>> {
    let mut rng = SplitMix64::new(seed ^ 0x524F_4144_5321_0001);
    // Streets give about 2.3 m² segments for an m × m grid.
    let m = ((n_segments as f64 / 2.3).sqrt().ceil() as usize).max(3);
    let g = SQUARE / m as f64;
    let axis = |rng: &mut SplitMix64| -> Vec<f64> {
        (0..m)
            .map(|i| snap((i as f64 + 0.5 + rng.range(-0.3, 0.3)) * g))
            .collect()
    };
    let xs = axis(&mut rng);
    let ys = axis(&mut rng);
    let at = |x: f64, y: f64| [x, y, road_height(x, y)];
    let mut out: Vec<Vec<[f64; 3]>> = Vec::new();
    // Streets: rows (horizontal) then columns (vertical).
    for horizontal in [true, false] {
        for k in 0..m {
            let node = |i: usize| {
                if horizontal {
                    at(xs[i], ys[k])
                } else {
                    at(xs[k], ys[i])
                }
            };
            let mut i = 0;
            while i + 1 < m {
                let len = 2 + rng.below(18) as usize;
                let end = (i + len).min(m - 1);
                let mut line = vec![node(i)];
                for j in i + 1..end {
                    // Skipped nodes make T-junctions with the crossing street.
                    if rng.below(10) != 0 {
                        line.push(node(j));
                    }
                }
                line.push(node(end));
                out.push(line);
                // A piece laid twice: a duplicate, or an overlap from a half-way point.
                if rng.below(30) == 0 && end > i + 1 {
                    let (a, b) = (node(i), node(i + 1));
                    let mid = at(snap(0.5 * (a[0] + b[0])), snap(0.5 * (a[1] + b[1])));
                    let from = if rng.below(2) == 0 { a } else { mid };
                    out.push(vec![from, node(i + 1), node((i + 2).min(end))]);
                }
                i = end;
            }
        }
    }
    // Highways: wobbly lines across the square, crossing streets between their nodes.
    let highways = (m / 16).max(1);
    for h in 0..highways {
        let steps = (m / 3).max(2);
        let (y0, y1) = (rng.range(0.0, SQUARE), rng.range(0.0, SQUARE));
        let line = (0..=steps)
            .map(|s| {
                let t = s as f64 / steps as f64;
                let wobble = if s == 0 || s == steps {
                    0.0
                } else {
                    rng.range(-g, g)
                };
                let along = snap(t * SQUARE);
                let across = snap((y0 + t * (y1 - y0) + wobble).clamp(0.0, SQUARE));
                let (x, y) = if h % 2 == 0 {
                    (along, across)
                } else {
                    (across, along)
                };
                // Bridges: a highway is a few metres above the ground it crosses.
                [x, y, road_height(x, y) + 5.0]
            })
            .collect();
        out.push(line);
    }
    // Roundabouts: lines through one point, half of them with it as a vertex.
    let roundabouts = (m / 8).max(1);
    for _ in 0..roundabouts {
        let c = [
            snap(rng.range(0.1 * SQUARE, 0.9 * SQUARE)),
            snap(rng.range(0.1 * SQUARE, 0.9 * SQUARE)),
        ];
        let spokes = 3 + rng.below(6);
        for s in 0..spokes {
            let d = [snap(rng.range(-g, g)), snap(rng.range(-g, g))];
            if d == [0.0, 0.0] {
                continue;
            }
            let a = at(c[0] - d[0], c[1] - d[1]);
            let b = at(c[0] + d[0], c[1] + d[1]);
            if s % 2 == 0 {
                out.push(vec![a, b]);
            } else {
                out.push(vec![a, at(c[0], c[1]), b]);
            }
        }
    }
    out
}

/// `n` points uniform in the square, plus its four corners (so every road lies inside their
/// hull), with `z` from [`road_height`].
pub fn road_points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed ^ 0x524F_4144_5054_5301);
    let corners = [[0.0, 0.0], [SQUARE, 0.0], [0.0, SQUARE], [SQUARE, SQUARE]];
    corners
        .into_iter()
        .chain((0..n).map(|_| [rng.range(0.0, SQUARE), rng.range(0.0, SQUARE)]))
        .map(|[x, y]| [x, y, road_height(x, y)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::breaklines::clean::{CleanOptions, clean};

    #[test]
    fn roads_are_sized_and_have_every_degeneracy() {
        let lines = roads(20_000, 7);
        let segs: usize = lines.iter().map(|l| l.len() - 1).sum();
        assert!((14_000..28_000).contains(&segs), "{segs} segments");
        assert_eq!(lines, roads(20_000, 7));
        let g = clean(&lines, &CleanOptions::default()).unwrap();
        let s = g.stats;
        assert!(s.crossings > 100, "{s:?}");
        assert!(s.snapped > 0, "{s:?}");
        assert!(s.vertex_splits > 100, "{s:?}");
        assert!(s.overlaps > 0 && s.duplicate_segments > 0, "{s:?}");
        assert!(s.merged_vertices > 1000, "{s:?}");
        g.check_planar().unwrap();
        let pts = road_points(10, 7);
        assert_eq!(pts.len(), 14);
    }
}
