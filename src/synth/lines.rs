//! Synthetic breaklines: contour lines of a smooth terrain, and a fractal coastline.
//!
//! | generator | what it looks like | guarantees |
//! |---|---|---|
//! | [`contours`] + [`contour_points`] | contour lines (closed rings and lines ending at the edge of the 1000 m square) of a terrain of Gaussian hills, one `z` per line; points sampled from the same terrain | lines of different levels never cross (marching squares with the saddle cells decided by the cell centre) |
//! | [`coastline`] + [`coastline_points`] | the coast of a fractal archipelago (islands with lakes) in the 1000 m square, `z = 0`; points on the land and sea floor around it | rings are simple and pairwise disjoint (proof at [`coastline`]) |
//!
//! Both are pure functions of their arguments, like the rest of [`crate::synth`].

use super::{SQUARE, SplitMix64};
use rayon::prelude::*;

/// Number of contour levels over the terrain's height range.
const LEVELS: f64 = 60.0;
/// Number of Gaussian hills (and hollows) of the contour terrain.
const HILLS: usize = 48;

/// Gaussian hills over a gentle plane.
struct Hills {
    /// `(cx, cy, sigma, height)`.
    list: Vec<[f64; 4]>,
    slope: [f64; 2],
}

impl Hills {
    fn new(seed: u64) -> Hills {
        let mut rng = SplitMix64::new(seed ^ 0x434F_4E54_4F55_5253);
        let list = (0..HILLS)
            .map(|_| {
                [
                    rng.range(0.0, SQUARE),
                    rng.range(0.0, SQUARE),
                    rng.range(25.0, 160.0),
                    rng.range(-30.0, 60.0),
                ]
            })
            .collect();
        Hills {
            list,
            slope: [rng.range(-0.02, 0.02), rng.range(-0.02, 0.02)],
        }
    }

    fn at(&self, x: f64, y: f64) -> f64 {
        let mut z = 100.0 + self.slope[0] * x + self.slope[1] * y;
        for h in &self.list {
            let r2 = (x - h[0]).powi(2) + (y - h[1]).powi(2);
            let s2 = h[2] * h[2];
            // Beyond 6 sigma a hill adds less than 1.5e-8 of its height: skip the exponential.
            if r2 < 36.0 * s2 {
                z += h[3] * (-r2 / (2.0 * s2)).exp();
            }
        }
        z
    }
}

/// Contour lines with about `n_segments` segments in all, of a smooth terrain of Gaussian hills
/// over the square `[0, 1000] × [0, 1000]`: 60 levels evenly spaced over the height range, each
/// line carrying its level as `z`. Closed lines repeat their first vertex; open ones end on the
/// square's edge. Lines of different levels never cross or touch; the vertices are not rounded.
/// Made by marching squares on a grid whose resolution is chosen for the segment count.
pub fn contours(n_segments: usize, seed: u64) -> Vec<Vec<[f64; 3]>> {
    let hills = Hills::new(seed);
    let levels = levels(&hills);
    // Segments grow linearly with the grid resolution: measure at a small one, then scale.
    let n0 = 64;
    let c0 = march(&hills, n0, &levels, true).len();
    let n = ((n0 as f64 * n_segments as f64 / c0.max(1) as f64).round() as usize).clamp(4, 8_000);
    march(&hills, n, &levels, false)
}

/// `n` points uniform in the square with `z` from the terrain of [`contours`] with the same seed.
pub fn contour_points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let hills = Hills::new(seed);
    let mut rng = SplitMix64::new(seed ^ 0x5054_5346_4F52_434E);
    (0..n)
        .map(|_| {
            let (x, y) = (rng.range(0.0, SQUARE), rng.range(0.0, SQUARE));
            [x, y, hills.at(x, y)]
        })
        .collect()
}

/// The contour levels: evenly spaced, offset half a step from the sampled extremes.
fn levels(hills: &Hills) -> Vec<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for j in 0..=100 {
        for i in 0..=100 {
            let z = hills.at(i as f64 * 10.0, j as f64 * 10.0);
            lo = lo.min(z);
            hi = hi.max(z);
        }
    }
    let step = (hi - lo) / LEVELS;
    (0..LEVELS as usize)
        .map(|k| lo + (k as f64 + 0.5) * step)
        .collect()
}

/// Marching squares on an `n × n` cell grid over the square (at most 8000, 512 MB of samples);
/// with `count_only`, returns one empty polyline per segment (for sizing).
fn march(hills: &Hills, n: usize, levels: &[f64], count_only: bool) -> Vec<Vec<[f64; 3]>> {
    let h = SQUARE / n as f64;
    let f: Vec<f64> = (0..(n + 1) * (n + 1))
        .into_par_iter()
        .map(|k| hills.at((k % (n + 1)) as f64 * h, (k / (n + 1)) as f64 * h))
        .collect();
    let per_level: Vec<Vec<Vec<[f64; 3]>>> = levels
        .par_iter()
        .map(|&level| {
            let segs = level_segments(&f, n, level, hills, h);
            if count_only {
                return vec![Vec::new(); segs.len()];
            }
            chain(&segs)
                .into_iter()
                .map(|ids| {
                    ids.into_iter()
                        .map(|e| {
                            let p = edge_point(&f, n, e, level, h);
                            [p[0], p[1], level]
                        })
                        .collect()
                })
                .collect()
        })
        .collect();
    per_level.into_iter().flatten().collect()
}

/// Grid edge ids: horizontal edge `(i, j)-(i+1, j)` is `j n + i`; vertical edge `(i, j)-(i, j+1)`
/// is `n (n+1) + j (n+1) + i`.
fn level_segments(f: &[f64], n: usize, level: f64, hills: &Hills, h: f64) -> Vec<[u32; 2]> {
    let node = |i: usize, j: usize| f[j * (n + 1) + i] > level;
    let hor = |i: usize, j: usize| (j * n + i) as u32;
    let ver = |i: usize, j: usize| (n * (n + 1) + j * (n + 1) + i) as u32;
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (bl, br, tr, tl) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            let case = usize::from(bl)
                | usize::from(br) << 1
                | usize::from(tr) << 2
                | usize::from(tl) << 3;
            let (b, r, t, l) = (hor(i, j), ver(i + 1, j), hor(i, j + 1), ver(i, j));
            match case {
                0 | 15 => {}
                1 | 14 => out.push([l, b]),
                2 | 13 => out.push([b, r]),
                3 | 12 => out.push([l, r]),
                4 | 11 => out.push([r, t]),
                6 | 9 => out.push([b, t]),
                7 | 8 => out.push([l, t]),
                5 | 10 => {
                    // Saddle: the centre decides which corners connect.
                    let centre = hills.at((i as f64 + 0.5) * h, (j as f64 + 0.5) * h) > level;
                    if centre == bl {
                        // bl and tr connected through the centre: cut off br and tl.
                        out.push([b, r]);
                        out.push([t, l]);
                    } else {
                        out.push([l, b]);
                        out.push([r, t]);
                    }
                }
                _ => unreachable!(),
            }
        }
    }
    out
}

/// Where the contour crosses grid edge `e`.
fn edge_point(f: &[f64], n: usize, e: u32, level: f64, h: f64) -> [f64; 2] {
    let e = e as usize;
    let hcount = n * (n + 1);
    let (i0, j0, i1, j1) = if e < hcount {
        (e % n, e / n, e % n + 1, e / n)
    } else {
        let k = e - hcount;
        (k % (n + 1), k / (n + 1), k % (n + 1), k / (n + 1) + 1)
    };
    let (f0, f1) = (f[j0 * (n + 1) + i0], f[j1 * (n + 1) + i1]);
    let t = (level - f0) / (f1 - f0);
    [
        (i0 as f64 + t * (i1 - i0) as f64) * h,
        (j0 as f64 + t * (j1 - j0) as f64) * h,
    ]
}

/// Links segments (pairs of edge ids) into polylines: open ones from their ends first, then the
/// closed ones (repeating their first id).
fn chain(segs: &[[u32; 2]]) -> Vec<Vec<u32>> {
    let mut at: Vec<(u32, u32)> = segs
        .iter()
        .enumerate()
        .flat_map(|(s, e)| [(e[0], s as u32), (e[1], s as u32)])
        .collect();
    at.sort_unstable();
    let others = |e: u32, s: u32| -> Option<u32> {
        let k = at.partition_point(|x| x.0 < e);
        at[k..]
            .iter()
            .take_while(|x| x.0 == e)
            .find(|x| x.1 != s)
            .map(|x| x.1)
    };
    let mut used = vec![false; segs.len()];
    let mut out = Vec::new();
    let walk = |start_edge: u32, s0: u32, used: &mut Vec<bool>| {
        let mut ids = vec![start_edge];
        let (mut s, mut e) = (s0, start_edge);
        loop {
            used[s as usize] = true;
            let [a, b] = segs[s as usize];
            e = if a == e { b } else { a };
            ids.push(e);
            match others(e, s) {
                Some(next) if !used[next as usize] => s = next,
                _ => break,
            }
        }
        ids
    };
    // Ends: edge ids used by a single segment.
    let ends: Vec<(u32, u32)> = at
        .iter()
        .enumerate()
        .filter(|&(k, x)| {
            (k == 0 || at[k - 1].0 != x.0) && (k + 1 == at.len() || at[k + 1].0 != x.0)
        })
        .map(|(_, x)| *x)
        .collect();
    for (e, s) in ends {
        if !used[s as usize] {
            out.push(walk(e, s, &mut used));
        }
    }
    for s in 0..segs.len() as u32 {
        if !used[s as usize] {
            out.push(walk(segs[s as usize][0], s, &mut used));
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Coastline

/// Largest amplitude of the fractal noise's octaves (sum of the gains).
const GAIN: f64 = 0.8;

/// Closed rings (about `n_vertices` vertices in all, `z = 0`) tracing the coast of a fractal
/// archipelago in the square `[0, 1000] × [0, 1000]`: islands of every size, lakes in them, and
/// islands in the lakes.
///
/// Made from a grid of land and sea cells (fractal value noise plus a falloff towards the square's
/// edge), with every diagonal-only contact between land cells filled, so each grid corner on the
/// coast has exactly one coast edge in and one out. The coast is traced with land on the left
/// (islands counter-clockwise, lakes clockwise), and each corner is then moved by a random offset
/// under a quarter of a cell in `x` and in `y`.
///
/// *Why the rings are simple and disjoint*: two coast edges of the grid that are not consecutive
/// on a ring are at least one cell apart in the maximum norm (they share no corner, since every
/// corner is on at most one ring, once). Moving the ends by less than a quarter cell moves every
/// point of an edge by less than a quarter cell, so such edges stay more than half a cell apart.
/// Consecutive edges meet at their common corner and turn by at most a right angle (a U-turn would
/// need the same grid edge in both directions), which the offsets cannot fold back.
pub fn coastline(n_vertices: usize, seed: u64) -> Vec<Vec<[f64; 3]>> {
    let noise = Noise::new(seed);
    // The coast's vertex count grows like resolution^D, with D changing slowly with the scale:
    // estimate D at coarse resolutions, fix the octaves for about that size, then estimate again
    // at half and a quarter of it.
    let count = |g: usize, oct: u32| coast_corners(&noise, g, oct) as f64;
    let predict =
        |g: usize, c: f64, d: f64| g as f64 * (n_vertices as f64 / c.max(1.0)).powf(1.0 / d);
    let (g0, g1) = (128usize, 256usize);
    let (c0, c1) = (count(g0, octaves_for(g0)), count(g1, octaves_for(g1)));
    let mut g = predict(g1, c1, (c1 / c0.max(1.0)).log2().clamp(1.0, 2.0));
    let oct = octaves_for((g.round() as usize).clamp(16, 16_000));
    let (h1, h0) = ((g / 2.0).round() as usize, (g / 4.0).round() as usize);
    if h0 > g1 {
        let (c0, c1) = (count(h0, oct), count(h1, oct));
        let d = (c1 / c0.max(1.0)).log2() / (h1 as f64 / h0 as f64).log2();
        g = predict(h1, c1, d.clamp(1.0, 2.0));
    }
    let g = (g.round() as usize).clamp(16, 16_000);
    let land = land_mask(&noise, g, oct);
    trace(&land, g, seed)
}

/// `n` points uniform in the square with `z` from the same fractal height field as
/// [`coastline`] (positive on land, negative at sea; the coast is the level 0, up to the grid).
pub fn coastline_points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let noise = Noise::new(seed);
    let mut rng = SplitMix64::new(seed ^ 0x434F_4153_5450_5453);
    (0..n)
        .map(|_| {
            let (x, y) = (rng.range(0.0, SQUARE), rng.range(0.0, SQUARE));
            [x, y, 50.0 * noise.height(x / SQUARE, y / SQUARE, 12)]
        })
        .collect()
}

/// Fractal value noise with an island falloff.
struct Noise {
    seed: u64,
}

impl Noise {
    fn new(seed: u64) -> Noise {
        Noise {
            seed: seed ^ 0x4953_4C41_4E44_5300,
        }
    }

    /// Lattice value in `[-1, 1]`.
    fn lattice(&self, octave: u32, i: i64, j: i64) -> f64 {
        let mut r = SplitMix64::new(
            self.seed
                ^ (u64::from(octave) << 58)
                ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
        );
        2.0 * r.next_f64() - 1.0
    }

    /// Smoothly interpolated value noise of one octave at `(u, v)` (unit square coordinates).
    fn octave(&self, octave: u32, u: f64, v: f64) -> f64 {
        let freq = (4u64 << octave) as f64;
        let (x, y) = (u * freq, v * freq);
        let (i, j) = (x.floor(), y.floor());
        let (fx, fy) = (x - i, y - j);
        let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
        let (i, j) = (i as i64, j as i64);
        let a = self.lattice(octave, i, j);
        let b = self.lattice(octave, i + 1, j);
        let c = self.lattice(octave, i, j + 1);
        let d = self.lattice(octave, i + 1, j + 1);
        let bottom = a + sx * (b - a);
        let top = c + sx * (d - c);
        bottom + sy * (top - bottom)
    }

    /// Height (land above 0) from `octaves` octaves.
    fn height(&self, u: f64, v: f64, octaves: u32) -> f64 {
        let mut z = self.falloff(u, v);
        let mut amp = 1.0;
        for o in 0..octaves {
            z += amp * self.octave(o, u, v);
            amp *= GAIN;
        }
        z
    }

    fn falloff(&self, u: f64, v: f64) -> f64 {
        let r2 = (u - 0.5).powi(2) + (v - 0.5).powi(2);
        0.35 - 2.2 * r2
    }

    /// Is `(u, v)` land? Stops adding octaves once the rest cannot change the sign.
    fn is_land(&self, u: f64, v: f64, octaves: u32) -> bool {
        let mut z = self.falloff(u, v);
        let mut amp = 1.0;
        // Sum of the amplitudes still to come.
        let mut rest = (1.0 - GAIN.powi(octaves as i32)) / (1.0 - GAIN);
        for o in 0..octaves {
            if z.abs() > rest {
                break;
            }
            z += amp * self.octave(o, u, v);
            rest -= amp;
            amp *= GAIN;
        }
        z > 0.0
    }
}

/// Octaves down to about two cells of a `g × g` grid.
fn octaves_for(g: usize) -> u32 {
    ((g as f64 / 8.0).log2().floor().max(0.0) as u32 + 1).min(24)
}

/// Land cells of a `g × g` grid (row by row) from `oct` octaves, the outer ring of cells forced to sea, diagonal-only
/// contacts filled.
fn land_mask(noise: &Noise, g: usize, oct: u32) -> Vec<bool> {
    let mut land: Vec<bool> = (0..g * g)
        .into_par_iter()
        .map(|k| {
            let (i, j) = (k % g, k / g);
            if i == 0 || j == 0 || i + 1 == g || j + 1 == g {
                return false;
            }
            noise.is_land(
                (i as f64 + 0.5) / g as f64,
                (j as f64 + 0.5) / g as f64,
                oct,
            )
        })
        .collect();
    // Fill one sea cell of every 2 × 2 block whose land cells touch only diagonally; repeat,
    // since a fill can create such a block next to it. (Never at the edge: see `coastline`.)
    loop {
        let mut changed = false;
        for j in 0..g - 1 {
            for i in 0..g - 1 {
                let k = j * g + i;
                let (a, b, c, d) = (land[k], land[k + 1], land[k + g], land[k + g + 1]);
                if a && d && !b && !c {
                    land[k + 1] = true;
                    changed = true;
                } else if b && c && !a && !d {
                    land[k] = true;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    land
}

/// Number of coast corners at resolution `g` (for sizing).
fn coast_corners(noise: &Noise, g: usize, oct: u32) -> usize {
    let land = land_mask(noise, g, oct);
    outgoing(&land, g).iter().filter(|&&d| d != 0).count()
}

/// For every grid corner `(i, j)` (index `j (g+1) + i`), the direction of its outgoing coast edge
/// with land on the left: 1 = +x, 2 = +y, 3 = -x, 4 = -y, 0 = none.
fn outgoing(land: &[bool], g: usize) -> Vec<u8> {
    let w = g + 1;
    let mut out = vec![0u8; w * w];
    let at = |i: usize, j: usize| land[j * g + i];
    for j in 1..g - 1 {
        for i in 1..g - 1 {
            if !at(i, j) {
                continue;
            }
            if !at(i, j - 1) {
                out[j * w + i] = 1; // bottom edge, left to right
            }
            if !at(i + 1, j) {
                out[j * w + i + 1] = 2; // right edge, upwards
            }
            if !at(i, j + 1) {
                out[(j + 1) * w + i + 1] = 3; // top edge, right to left
            }
            if !at(i - 1, j) {
                out[(j + 1) * w + i] = 4; // left edge, downwards
            }
        }
    }
    out
}

/// Traces the coast rings and moves each corner by its random offset.
fn trace(land: &[bool], g: usize, seed: u64) -> Vec<Vec<[f64; 3]>> {
    let w = g + 1;
    let mut out = outgoing(land, g);
    let h = SQUARE / g as f64;
    let jitter = |c: usize, k: u64| {
        let mut r = SplitMix64::new(seed ^ (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k);
        r.range(-0.24, 0.24)
    };
    let point = |c: usize| {
        let (i, j) = ((c % w) as f64, (c / w) as f64);
        [(i + jitter(c, 1)) * h, (j + jitter(c, 2)) * h, 0.0]
    };
    let mut rings = Vec::new();
    for start in 0..out.len() {
        if out[start] == 0 {
            continue;
        }
        let mut ring = Vec::new();
        let mut c = start;
        while out[c] != 0 {
            ring.push(point(c));
            let d = out[c];
            out[c] = 0;
            c = match d {
                1 => c + 1,
                2 => c + w,
                3 => c - 1,
                _ => c - w,
            };
        }
        debug_assert_eq!(c, start, "a coast ring does not close");
        ring.push(ring[0]);
        rings.push(ring);
    }
    rings
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::breaklines::clean::{CleanOptions, clean};

    #[test]
    fn contours_are_sized_levelled_and_planar() {
        let lines = contours(20_000, 3);
        let segs: usize = lines.iter().map(|l| l.len() - 1).sum();
        assert!((12_000..30_000).contains(&segs), "{segs} segments");
        assert_eq!(lines, contours(20_000, 3));
        assert_ne!(lines, contours(20_000, 4));
        let closed = lines.iter().filter(|l| l[0] == l[l.len() - 1]).count();
        assert!(
            closed > 0 && closed < lines.len(),
            "{closed} of {}",
            lines.len()
        );
        for l in &lines {
            assert!(l.iter().all(|p| p[2] == l[0][2]), "one z per line");
            assert!(
                l.iter()
                    .all(|p| (0.0..=SQUARE).contains(&p[0]) && (0.0..=SQUARE).contains(&p[1]))
            );
        }
        // No crossings or overlaps between different lines.
        let g = clean(&lines, &CleanOptions::default()).unwrap();
        assert_eq!(g.stats.crossings, 0, "{:?}", g.stats);
        assert_eq!(g.stats.overlaps, 0, "{:?}", g.stats);
        assert_eq!(g.stats.z_conflicts, 0, "{:?}", g.stats);
        let pts = contour_points(100, 3);
        assert_eq!(pts.len(), 100);
        assert!(pts.iter().all(|p| p[2] > 0.0 && p[2] < 400.0));
    }

    #[test]
    fn coastline_is_sized_closed_and_simple() {
        let rings = coastline(20_000, 5);
        let n: usize = rings.iter().map(|r| r.len() - 1).sum();
        assert!((12_000..32_000).contains(&n), "{n} vertices");
        assert!(rings.len() > 3, "{} rings", rings.len());
        assert_eq!(rings, coastline(20_000, 5));
        for r in &rings {
            assert!(r.len() >= 5 && r[0] == r[r.len() - 1]);
        }
        // Simple and disjoint: cleaning finds nothing to do.
        let g = clean(&rings, &CleanOptions::default()).unwrap();
        assert_eq!(g.stats.rounds, 1, "{:?}", g.stats);
        assert_eq!(g.stats.merged_vertices as usize, rings.len());
        assert_eq!(g.segments.len(), n);
        let pts = coastline_points(1000, 5);
        let land = pts.iter().filter(|p| p[2] > 0.0).count();
        assert!(land > 50 && land < 950, "{land}");
    }

    #[test]
    fn chain_links_open_and_closed() {
        // Open 10-11-12, closed 1-2-3-1.
        let segs = [[11, 12], [1, 2], [10, 11], [3, 1], [2, 3]];
        let c = chain(&segs);
        assert_eq!(c.len(), 2);
        assert!(c[0] == vec![10, 11, 12] || c[0] == vec![12, 11, 10]);
        assert_eq!(c[1].len(), 4);
        assert_eq!(c[1][0], c[1][3]);
    }
}
