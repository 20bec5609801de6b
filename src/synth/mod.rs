//! Deterministic synthetic point sets for tests, benchmarks and scripts.
//!
//! Every generator is a pure function of its arguments: the same call gives bit-identical points
//! on every machine (the PRNG is [`SplitMix64`], the crate's own, and only IEEE-exact operations
//! plus `sin`/`cos`/`ln`/`sqrt` are used; the transcendental functions only shape values that are
//! then rounded to a grid or used as they are, never compared across platforms in tests).
//!
//! | generator | what it looks like | degeneracies |
//! |---|---|---|
//! | [`uniform`] | uniform in a 1000 m square | none (almost surely) |
//! | [`lidar_like`] | one airborne-scanner tile at UTM-sized offsets | many: ties in `x` and `y`, cocircular rectangles, exact duplicates, holes |
//! | [`clustered`] | Gaussian clusters of very different densities over a sparse background | density contrast of 10⁶ |
//! | [`grid`], [`tilted_grid`], [`ring`] | small test shapes | everything is cocircular / collinear |
//! | [`heavy`]: `disc`, `disc_far`, `kuzmin`, `almost_line` | the memory benchmark's distributions, and input orders | bounding boxes far larger than where the points are |
//!
//! All return `Vec<[f64; 3]>` (`[x, y, z]`), the input format of [`crate::triangulate`].
//!
//! Breaklines to go with them ([`contours`], [`coastline`]) are in [`lines`]; a road network with
//! every degeneracy the breakline cleaner handles ([`roads`]) is in [`roads`](mod@roads).

use std::f64::consts::{PI, TAU};

pub mod heavy;
pub mod lines;
pub mod roads;
pub use crate::geom::rng::SplitMix64;
pub use lines::{coastline, coastline_points, contour_points, contours};
pub use roads::{road_points, roads};

/// Side of the square of [`uniform`] and of the background of [`clustered`], in metres.
pub const SQUARE: f64 = 1000.0;

/// A point count as the benchmarks and scripts write it: `1000`, `100k`, `4M`, `1.5M` (k = 10³,
/// M = 10⁶), rounded to the nearest whole count. `None` unless it is a non-negative number below
/// 10¹².
pub fn parse_count(s: &str) -> Option<usize> {
    let s = s.trim();
    let (num, mult) = match s.chars().last()? {
        'k' | 'K' => (&s[..s.len() - 1], 1e3),
        'm' | 'M' => (&s[..s.len() - 1], 1e6),
        _ => (s, 1.0),
    };
    let v: f64 = num.parse().ok()?;
    let n = v * mult;
    (0.0..1e12).contains(&n).then_some(n.round() as usize)
}

/// `n` points uniform in the square `[0, 1000) × [0, 1000)`, `z` uniform in `[0, 100)`.
pub fn uniform(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let x = rng.range(0.0, SQUARE);
            let y = rng.range(0.0, SQUARE);
            [x, y, rng.range(0.0, 100.0)]
        })
        .collect()
}

/// `x` offset of [`lidar_like`] tiles (a UTM easting).
pub const LIDAR_X0: f64 = 500_000.0;
/// `y` offset of [`lidar_like`] tiles (a UTM northing).
pub const LIDAR_Y0: f64 = 5_000_000.0;
/// Coordinate quantum of [`lidar_like`] (a LAS scale factor of 0.01).
pub const LIDAR_SCALE: f64 = 0.01;

/// Nominal distance between neighbouring points of a scan row and between rows, metres.
const SPACING: f64 = 0.5;
/// Share of the points that are exact `(x, y)` duplicates of another point.
const DUP_SHARE: f64 = 0.01;
/// Share of the points that come from the second, crossing flight line.
const SECOND_SHARE: f64 = 0.2;
/// Slope of the first flight line's scan rows (`dy/dx`).
const ROW_TILT: f64 = 0.01;
/// Angle between the two flight directions, radians (30°).
const SECOND_ANGLE: f64 = PI / 6.0;
/// Width of the second flight line's swath, as a share of the tile side.
const SECOND_SWATH: f64 = 0.4;

/// `n` points the way an airborne laser scanner delivers a tile (LAS-like).
///
/// What is modelled, and why it matters to a triangulator:
/// - **Scan rows.** The first flight line flies north; its mirror sweeps scan rows roughly along
///   `x`, points 0.5 m apart, rows 0.5 m apart (4 points/m²). Rows are tilted by a slope of 0.01
///   and shifted by a random whole number of cm (σ = 2 cm) each; points get a 2 mm jitter. Rows
///   come in blocks of 8 that share their `x` phase (a whole number of cm), so neighbouring rows
///   put points at the same `x`.
/// - **1 cm quantisation** (LAS scale 0.01, offset ([`LIDAR_X0`], [`LIDAR_Y0`])): coordinates are
///   `offset + 0.01 * integer`, computed the way LAS readers do. Hence many exact ties in `y`
///   (a row climbs 1 cm every metre) and in `x` (rows of a block), and many exact rectangles, i.e.
///   cocircular quadruples, where two rows of a block do not step between two columns.
/// - **About 1 % exact `(x, y)` duplicates** (`⌊n/100⌋` of them), each placed right after the
///   point it repeats, with a lower `z` (like a second return).
/// - **A second flight line** (20 % of the points) flying at 30° to the first, over a swath 40 %
///   as wide as the tile, crossing the tile through its centre: there the density doubles and the
///   two row patterns interleave.
/// - **Holes**: five elliptical areas without any point (water), about 5 % of the tile in all.
/// - **Realistic `z`**: smooth terrain around 250 m (a gentle random plane, slope under 1 %, plus
///   long waves of 21 m total amplitude) plus 5 cm noise, also quantised to 1 cm.
///
/// The tile is square, its side chosen so that the first flight line yields the wanted count
/// (about `0.46 √n` m: 455 m for 1 M points); it starts at ([`LIDAR_X0`], [`LIDAR_Y0`]). Points
/// come in acquisition order: the first flight line row by row, then the second.
pub fn lidar_like(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed ^ 0x4C49_4441_5200_0000);
    let n_dup = (n as f64 * DUP_SHARE) as usize;
    let n_second = ((n - n_dup) as f64 * SECOND_SHARE) as usize;
    let n_first = n - n_dup - n_second;
    let holes = Holes::random(&mut rng);
    // Side such that the first flight line fills the square with `n_first` points.
    let area = n_first as f64 * SPACING * SPACING / (1.0 - holes.area_share());
    let side = area.sqrt().max(4.0);
    let terrain = Terrain::random(&mut rng, side);
    let tile = Tile {
        side,
        holes,
        terrain,
    };
    let mut out = Vec::with_capacity(n);
    first_flight_line(&mut rng, &tile, n_first, &mut out);
    second_flight_line(&mut rng, &tile, n_first + n_second, &mut out);
    add_duplicates(&mut rng, out, n_dup)
}

/// What the two flight lines share: extent, holes, terrain.
struct Tile {
    side: f64,
    holes: Holes,
    terrain: Terrain,
}

impl Tile {
    /// Quantises a local point (metres from the tile corner) and appends it, unless it falls
    /// into a hole or (for the second flight line) outside the tile.
    fn emit(&self, rng: &mut SplitMix64, x: f64, y: f64, out: &mut Vec<[f64; 3]>) -> bool {
        let u = x / self.side;
        let v = y / self.side;
        if x < 0.0 || x > self.side || y < 0.0 || self.holes.contains(u, v) {
            return false;
        }
        let z = self.terrain.at(x, y) + 0.05 * rng.normal();
        out.push([
            LIDAR_X0 + LIDAR_SCALE * (x / LIDAR_SCALE).round(),
            LIDAR_Y0 + LIDAR_SCALE * (y / LIDAR_SCALE).round(),
            LIDAR_SCALE * (z / LIDAR_SCALE).round(),
        ]);
        true
    }
}

/// Rows along `x`, going north until `count` points are out. Rows beyond the estimated side only
/// happen when the holes' share was over-estimated (they are outside every hole, so this ends).
fn first_flight_line(rng: &mut SplitMix64, tile: &Tile, count: usize, out: &mut Vec<[f64; 3]>) {
    let mut row = 0u64;
    let mut phase = 0.0;
    while out.len() < count {
        if row.is_multiple_of(8) {
            phase = LIDAR_SCALE * rng.below(50) as f64;
        }
        let y0 = row as f64 * SPACING + LIDAR_SCALE * (2.0 * rng.normal()).round();
        let mut x = phase;
        while x <= tile.side && out.len() < count {
            let jx = 0.002 * rng.normal();
            let jy = 0.002 * rng.normal();
            tile.emit(rng, x + jx, y0 + ROW_TILT * x + jy, out);
            x += SPACING;
        }
        row += 1;
    }
}

/// Scan rows across a swath flying at [`SECOND_ANGLE`] through the tile centre, until `total`
/// points are out. Passes repeat with a shifted phase if one pass is not enough (tiny tiles).
fn second_flight_line(rng: &mut SplitMix64, tile: &Tile, total: usize, out: &mut Vec<[f64; 3]>) {
    let (s, c) = SECOND_ANGLE.sin_cos();
    let flight = [s, c];
    let across = [c, -s];
    let centre = tile.side / 2.0;
    let half_swath = SECOND_SWATH * tile.side / 2.0;
    let half_len = tile.side; // longer than half the diagonal
    let mut pass = 0u32;
    while out.len() < total {
        let shift = 0.137 * pass as f64;
        let mut b = -half_len + shift;
        while b <= half_len && out.len() < total {
            let row_off = 0.02 * rng.normal();
            let mut a = -half_swath + shift;
            while a <= half_swath && out.len() < total {
                let bb = b + row_off + 0.003 * rng.normal();
                let aa = a + 0.003 * rng.normal();
                let x = centre + aa * across[0] + bb * flight[0];
                let y = centre + aa * across[1] + bb * flight[1];
                if y <= tile.side {
                    tile.emit(rng, x, y, out);
                }
                a += SPACING;
            }
            b += SPACING;
        }
        pass += 1;
        if pass > 1000 {
            // Unreachable for any tile the first flight line can produce; a guard, not a path.
            break;
        }
    }
}

/// Inserts `n_dup` exact `(x, y)` duplicates, each right after a random earlier point.
fn add_duplicates(rng: &mut SplitMix64, base: Vec<[f64; 3]>, n_dup: usize) -> Vec<[f64; 3]> {
    if base.is_empty() || n_dup == 0 {
        return base;
    }
    let mut after: Vec<usize> = (0..n_dup)
        .map(|_| rng.below(base.len() as u64) as usize)
        .collect();
    after.sort_unstable();
    let mut out = Vec::with_capacity(base.len() + n_dup);
    let mut k = 0;
    for (i, p) in base.iter().enumerate() {
        out.push(*p);
        while k < after.len() && after[k] == i {
            let dz = LIDAR_SCALE * (rng.range(0.1, 2.0) / LIDAR_SCALE).round();
            out.push([p[0], p[1], p[2] - dz]);
            k += 1;
        }
    }
    out
}

/// Elliptical holes in unit tile coordinates.
struct Holes {
    /// `(cu, cv, ru, rv)`: centre and radii.
    list: Vec<[f64; 4]>,
}

impl Holes {
    fn random(rng: &mut SplitMix64) -> Self {
        let list = (0..5)
            .map(|_| {
                [
                    rng.range(0.15, 0.85),
                    rng.range(0.15, 0.85),
                    rng.range(0.03, 0.08),
                    rng.range(0.03, 0.08),
                ]
            })
            .collect();
        Holes { list }
    }

    /// Upper estimate of the share of the tile they cover (overlaps counted twice).
    fn area_share(&self) -> f64 {
        self.list
            .iter()
            .map(|h| PI * h[2] * h[3])
            .sum::<f64>()
            .min(0.5)
    }

    fn contains(&self, u: f64, v: f64) -> bool {
        self.list.iter().any(|h| {
            let du = (u - h[0]) / h[2];
            let dv = (v - h[1]) / h[3];
            du * du + dv * dv < 1.0
        })
    }
}

/// Smooth terrain: a base level, a gentle plane and a few long waves.
struct Terrain {
    base: f64,
    slope: [f64; 2],
    /// `(amplitude, kx, ky, phase)`.
    waves: Vec<[f64; 4]>,
}

impl Terrain {
    fn random(rng: &mut SplitMix64, side: f64) -> Self {
        let waves = (0..4)
            .map(|i| {
                let wavelength = side / (1.0 + i as f64 * 1.7);
                let dir = rng.range(0.0, TAU);
                let k = TAU / wavelength;
                [
                    10.0 / (1.0 + i as f64),
                    k * dir.cos(),
                    k * dir.sin(),
                    rng.range(0.0, TAU),
                ]
            })
            .collect();
        Terrain {
            base: 250.0,
            slope: [rng.range(-0.01, 0.01), rng.range(-0.01, 0.01)],
            waves,
        }
    }

    fn at(&self, x: f64, y: f64) -> f64 {
        let plane = self.base + self.slope[0] * x + self.slope[1] * y;
        plane
            + self
                .waves
                .iter()
                .map(|w| w[0] * (w[1] * x + w[2] * y + w[3]).sin())
                .sum::<f64>()
    }
}

/// Number of clusters in [`clustered`].
const CLUSTERS: usize = 24;
/// Share of [`clustered`]'s points in the uniform background.
const BACKGROUND_SHARE: f64 = 0.05;

/// `n` points in Gaussian clusters of very different densities plus a sparse background.
///
/// 95 % of the points fall into 24 clusters whose centres are uniform in the 1000 m square, with
/// standard deviations log-uniform between 0.5 m and 100 m and weights log-uniform over a factor
/// 100, so densities differ by about six orders of magnitude; the other 5 % are uniform over the
/// square. Cluster tails may leave the square. `z` is the distance to the cluster centre plus
/// noise. Coordinates are not rounded. Points come cluster by cluster, then the background.
pub fn clustered(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed ^ 0x434C_5553_5445_5200);
    let clusters: Vec<[f64; 4]> = (0..CLUSTERS)
        .map(|_| {
            let sigma = 0.5 * 200f64.powf(rng.next_f64());
            let weight = 100f64.powf(rng.next_f64());
            [
                rng.range(0.0, SQUARE),
                rng.range(0.0, SQUARE),
                sigma,
                weight,
            ]
        })
        .collect();
    let n_background = (n as f64 * BACKGROUND_SHARE) as usize;
    let total_weight: f64 = clusters.iter().map(|c| c[3]).sum();
    let mut out = Vec::with_capacity(n);
    let in_clusters = n - n_background;
    let mut done_weight = 0.0;
    for c in &clusters {
        done_weight += c[3];
        // Cumulative rounding, so the counts add up to exactly `in_clusters`.
        let upto = ((done_weight / total_weight) * in_clusters as f64).round() as usize;
        while out.len() < upto.min(in_clusters) {
            let x = c[0] + c[2] * rng.normal();
            let y = c[1] + c[2] * rng.normal();
            let r = (x - c[0]).hypot(y - c[1]);
            out.push([x, y, r + 0.1 * rng.normal()]);
        }
    }
    while out.len() < in_clusters {
        // Only reachable through rounding of the last cumulative share; keeps the count exact.
        let c = clusters[CLUSTERS - 1];
        out.push([c[0] + c[2] * rng.normal(), c[1] + c[2] * rng.normal(), 0.0]);
    }
    while out.len() < n {
        out.push([
            rng.range(0.0, SQUARE),
            rng.range(0.0, SQUARE),
            rng.range(0.0, 10.0),
        ]);
    }
    out
}

/// The `nx × ny` grid `(i * spacing, j * spacing)`, row by row (`i` fastest), with
/// `z = i + 1000 j` so every vertex can be recognised by its `z`.
///
/// Every unit square is cocircular: the Delaunay triangulation is not unique, only the
/// tie-breaking rule makes it so.
pub fn grid(nx: usize, ny: usize, spacing: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            out.push([
                i as f64 * spacing,
                j as f64 * spacing,
                i as f64 + 1000.0 * j as f64,
            ]);
        }
    }
    out
}

/// Rounds to the 1 mm grid (round half away from zero, so the rounding is symmetric under
/// negation).
#[inline]
fn mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// [`grid`] rotated by `angle` (radians, counter-clockwise about the origin), each coordinate
/// rounded to 1 mm; `z` as in [`grid`].
///
/// The rounding makes the cells slightly irregular: some stay exactly cocircular, most become
/// nearly cocircular, which is where inexact in-circle tests go wrong.
pub fn tilted_grid(nx: usize, ny: usize, spacing: f64, angle: f64) -> Vec<[f64; 3]> {
    let (s, c) = angle.sin_cos();
    grid(nx, ny, spacing)
        .into_iter()
        .map(|[x, y, z]| [mm(c * x - s * y), mm(s * x + c * y), z])
        .collect()
}

/// `n` points at angles `2πk/n` on the circle of `radius` about the origin, rounded to 1 mm,
/// `z = k`.
///
/// Each point is computed from its mirror image in the first octant, so when `n` is a multiple
/// of 8 the points form orbits under the 8 symmetries of the square, and the points of one orbit
/// are exactly cocircular (they share `x² + y²` exactly); all points are within 0.71 mm of the
/// circle. With `2π radius / n` under a few mm, rounding can make neighbours coincide.
pub fn ring(n: usize, radius: f64) -> Vec<[f64; 3]> {
    (0..n)
        .map(|k| {
            let [x, y] = ring_unit(k as u64, n as u64);
            [mm(radius * x), mm(radius * y), k as f64]
        })
        .collect()
}

/// `(cos, sin)` of the angle `2πk/n`, derived by symmetry from an angle in `[0, π/4]`.
fn ring_unit(k: u64, n: u64) -> [f64; 2] {
    let base = |num: u64| {
        let phi = PI / 4.0 * (num as f64 / n as f64);
        let (s, c) = phi.sin_cos();
        [c, s]
    };
    let eighth = 8 * (k % n);
    let octant = eighth / n;
    let rem = eighth - octant * n;
    let mut v = if octant.is_multiple_of(2) {
        base(rem)
    } else {
        let [c, s] = base(n - rem);
        [s, c]
    };
    for _ in 0..octant / 2 {
        v = [-v[1], v[0]];
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::predicates::{CircleSide, incircle_exact};
    use std::collections::HashSet;

    #[test]
    fn counts() {
        assert_eq!(parse_count("1000"), Some(1000));
        assert_eq!(parse_count("100k"), Some(100_000));
        assert_eq!(parse_count("2.9M"), Some(2_900_000));
        assert_eq!(parse_count("16M"), Some(16_000_000));
        assert_eq!(parse_count("-1"), None);
        assert_eq!(parse_count("M"), None);
        assert_eq!(parse_count(""), None);
    }

    fn key(p: &[f64; 3]) -> (u64, u64) {
        (p[0].to_bits(), p[1].to_bits())
    }

    fn duplicates(pts: &[[f64; 3]]) -> usize {
        let distinct: HashSet<_> = pts.iter().map(key).collect();
        pts.len() - distinct.len()
    }

    #[test]
    fn generators_are_deterministic_and_exact_in_count() {
        for n in [0, 1, 2, 3, 7, 100, 5000] {
            for (name, f) in [
                ("uniform", uniform as fn(usize, u64) -> Vec<[f64; 3]>),
                ("lidar_like", lidar_like),
                ("clustered", clustered),
            ] {
                let a = f(n, 42);
                assert_eq!(a.len(), n, "{name} n={n}");
                assert_eq!(a, f(n, 42), "{name} n={n}");
                assert!(a.iter().flatten().all(|v| v.is_finite()), "{name}");
                if n >= 100 {
                    assert_ne!(a, f(n, 43), "{name}: the seed matters");
                }
            }
        }
    }

    #[test]
    fn uniform_stays_in_the_square() {
        let pts = uniform(10_000, 1);
        assert!(
            pts.iter()
                .all(|p| (0.0..SQUARE).contains(&p[0]) && (0.0..SQUARE).contains(&p[1]))
        );
    }

    #[test]
    fn lidar_like_looks_like_a_las_tile() {
        let n = 200_000;
        let pts = lidar_like(n, 5);
        // On the 1 cm grid at UTM offsets, as LAS readers compute it.
        for p in &pts {
            let ix = ((p[0] - LIDAR_X0) / LIDAR_SCALE).round();
            let iy = ((p[1] - LIDAR_Y0) / LIDAR_SCALE).round();
            assert_eq!(p[0], LIDAR_X0 + LIDAR_SCALE * ix);
            assert_eq!(p[1], LIDAR_Y0 + LIDAR_SCALE * iy);
            assert!(ix >= 0.0 && iy >= 0.0);
            assert!((150.0..350.0).contains(&p[2]), "z {}", p[2]);
        }
        // About 1 % exact duplicates (a few more from quantisation where the flight lines meet).
        let dups = duplicates(&pts);
        assert!((n / 100..n / 50).contains(&dups), "{dups} duplicates");
        // Many exact ties in y and in x.
        let ys: HashSet<u64> = pts.iter().map(|p| p[1].to_bits()).collect();
        let xs: HashSet<u64> = pts.iter().map(|p| p[0].to_bits()).collect();
        assert!(ys.len() < n / 5, "{} distinct y", ys.len());
        assert!(xs.len() < n / 5, "{} distinct x", xs.len());
        // Square tile of about sqrt(n / 4 / 0.8) m, with empty 5 m cells (holes) inside.
        let side = pts.iter().map(|p| p[0] - LIDAR_X0).fold(0.0, f64::max);
        let height = pts.iter().map(|p| p[1] - LIDAR_Y0).fold(0.0, f64::max);
        assert!((180.0..230.0).contains(&side), "side {side}");
        assert!((height - side).abs() < 0.1 * side, "height {height}");
        let cells = (side / 5.0) as usize;
        let mut hit = vec![false; cells * cells];
        for p in &pts {
            let i = ((p[0] - LIDAR_X0) / 5.0) as usize;
            let j = ((p[1] - LIDAR_Y0) / 5.0) as usize;
            if i < cells && j < cells {
                hit[j * cells + i] = true;
            }
        }
        let empty = hit.iter().filter(|h| !**h).count();
        assert!(empty > cells * cells / 100, "{empty} empty cells");
    }

    #[test]
    fn lidar_like_has_exact_cocircular_rectangles() {
        use std::collections::HashMap;
        let pts = lidar_like(20_000, 9);
        let set: HashSet<_> = pts.iter().map(key).collect();
        // Points by exact y (rows) and by exact x (columns), each sorted.
        let mut by_y: HashMap<u64, Vec<f64>> = HashMap::new();
        let mut by_x: HashMap<u64, Vec<f64>> = HashMap::new();
        for p in &pts {
            by_y.entry(p[1].to_bits()).or_default().push(p[0]);
            by_x.entry(p[0].to_bits()).or_default().push(p[1]);
        }
        by_y.values_mut().for_each(|v| v.sort_by(f64::total_cmp));
        by_x.values_mut().for_each(|v| v.sort_by(f64::total_cmp));
        let next = |v: &[f64], after: f64| v.iter().copied().find(|&w| w > after);
        // p, its right neighbour in its row, the point above it in its column, and the fourth
        // corner: an exact axis-aligned rectangle, hence exactly cocircular.
        let mut rects = 0;
        for p in &pts {
            let Some(x1) = next(&by_y[&p[1].to_bits()], p[0]) else {
                continue;
            };
            let Some(y1) = next(&by_x[&p[0].to_bits()], p[1]) else {
                continue;
            };
            if x1 - p[0] < 0.7 && y1 - p[1] < 0.7 && set.contains(&(x1.to_bits(), y1.to_bits())) {
                let c = |x: f64, y: f64| [x - LIDAR_X0, y - LIDAR_Y0];
                let side = incircle_exact(c(p[0], p[1]), c(x1, p[1]), c(x1, y1), c(p[0], y1));
                assert_eq!(side, CircleSide::On);
                rects += 1;
            }
        }
        assert!(rects > 2000, "{rects} small exact rectangles");
    }

    #[test]
    fn clustered_has_dense_and_sparse_parts() {
        let n = 100_000;
        let pts = clustered(n, 3);
        let mut counts = vec![0usize; 100 * 100];
        for p in &pts {
            if (0.0..SQUARE).contains(&p[0]) && (0.0..SQUARE).contains(&p[1]) {
                counts[(p[1] / 10.0) as usize * 100 + (p[0] / 10.0) as usize] += 1;
            }
        }
        let max = *counts.iter().max().unwrap();
        let sparse = counts.iter().filter(|&&c| c <= 1).count();
        assert!(max > 2000, "densest 10 m cell has {max}");
        assert!(sparse > 1000, "{sparse} cells with at most one point");
        assert_eq!(duplicates(&pts), 0);
    }

    #[test]
    fn grids_and_rings() {
        let g = grid(3, 2, 0.5);
        assert_eq!(g.len(), 6);
        assert_eq!(g[4], [0.5, 0.5, 1001.0]);
        let t = tilted_grid(10, 10, 1.0, 0.3);
        assert_eq!(t.len(), 100);
        assert!(t.iter().all(|p| p[0] == mm(p[0]) && p[1] == mm(p[1])));
        assert_eq!(duplicates(&t), 0);
        let r = ring(64, 10.0);
        assert_eq!(duplicates(&r), 0);
        assert_eq!(r[0], [10.0, 0.0, 0.0]);
        assert_eq!(r[16][..2], [0.0, 10.0]);
        assert_eq!(r[32][..2], [-10.0, 0.0]);
        for p in &r {
            let d = p[0].hypot(p[1]);
            assert!((d - 10.0).abs() < 0.000_71, "{d}");
        }
    }

    #[test]
    fn ring_orbits_are_exactly_cocircular() {
        let n = 40;
        let r = ring(n, 123.456);
        let xy = |k: usize| [r[k % n][0], r[k % n][1]];
        // Orbit of k = 3: its mirror images in the 8 octants.
        let orbit: Vec<[f64; 2]> = (0..8)
            .map(|o| {
                let base = o * n / 8;
                if o % 2 == 0 {
                    xy(base + 3)
                } else {
                    xy(base + n / 8 - 3)
                }
            })
            .collect();
        let sq = |p: [f64; 2]| p[0] * p[0] + p[1] * p[1];
        for p in &orbit[1..] {
            assert_eq!(sq(*p), sq(orbit[0]));
            assert_eq!(
                incircle_exact(orbit[0], orbit[2], orbit[4], *p),
                CircleSide::On
            );
        }
    }
}
