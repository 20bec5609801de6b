//! Progressive TIN densification (Axelsson 2000) on the points of one run: a block of the
//! global block grid and its buffer (see [`super`] for the definition and the parameters).
//!
//! 1. **Seeds**: the lowest eligible point of each cell of the global seed grid (cell
//!    `floor(x / step), floor(y / step)`, as [`TileGrid::block_of`]), ties by the lower global
//!    input index.
//! 2. **Low noise among the seeds**: a seed lower than the median of the seeds of its (up to
//!    eight) neighbouring cells by more than `low_noise` is low noise (class 7); the cell's next
//!    lowest point becomes its seed. Passes are simultaneous (every seed judged against the
//!    seeds of the previous pass) until a pass flags nothing.
//! 3. **The initial TIN**: the seeds, and virtual points every `step` along the run's rectangle
//!    grown by one `step` (each at the height of its nearest seed), so that every point of the
//!    run lies inside the TIN. Virtual points are never classified.
//! 4. **Densification**: a candidate is accepted when its distance to the plane of the TIN
//!    triangle under it is at most `max_distance` and each angle between that plane and the
//!    lines from the candidate to the triangle's three vertices is at most `max_angle`; when
//!    only the angles fail, the candidate mirrored through the triangle's nearest (real) vertex
//!    is tested against the triangle under the mirror point (the paper's mirroring for steep
//!    edges). Per triangle the accepted candidate closest to the plane (ties: lower input index)
//!    is inserted; an iteration decides every triangle against the TIN of the previous one, and
//!    the densification stops when an iteration inserts nothing. A point on the edge of two
//!    triangles (itself, or its mirror point) belongs to the one of lower slot in the TIN
//!    (slots follow from the insertions, so from the input alone). A candidate is judged again
//!    only when a triangle its test read has changed (its answer cannot change otherwise).
//! 5. **The final TIN**: a point left over within `offset` (vertically) of the final ground TIN
//!    is ground too (densification stops in small triangles, where a few centimetres of noise
//!    make steep angles); one more than `low_noise` below it is low noise.
//!
//! Locating points and inserting them are the TIN's exact operations ([`Tin`]); the distance
//! and the angles are measurements against thresholds, in floating point relative to the
//! triangle's first vertex.

use super::densify::Densify;
use super::{GroundParams, Tag};
use crate::error::{Error, Result};
use crate::tiles::grid::TileGrid;
use crate::tin::{Tin, VertexId};
use rayon::prelude::*;
use std::collections::HashMap;

/// What the run decided for a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Label {
    /// Not ground (or not eligible).
    Other,
    /// Ground.
    Ground,
    /// Low noise: far below its neighbourhood.
    LowNoise,
}

/// Counters of a run.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct RunStats {
    pub seeds: u64,
    pub iterations: u64,
    pub evaluations: u64,
    /// Candidates judged once against the final TIN (not the lowest of their densification
    /// cell).
    pub deferred: u64,
    /// Bytes the run held at its peak (its points, tags and labels, the densification's tables
    /// and TIN), for checking [`super::RUN_BYTES_PER_POINT`].
    pub bytes: u64,
}

/// Classifies the points `pts` (their global input index and eligibility in `tags`) of the run
/// over the closed rectangle `rect`; only eligible points may become ground or low noise.
/// `grid`'s blocks are the seed cells. The points move into the ground TIN (as vertex ids, most
/// never inserted), which holds each position once.
///
/// # Errors
/// The TIN's errors (a coordinate out of range, too many vertices).
pub(crate) fn classify_run(
    pts: Vec<[f64; 3]>,
    tags: &[u64],
    rect: [f64; 4],
    grid: &TileGrid,
    params: &GroundParams,
    labels: &mut Vec<Label>,
) -> Result<RunStats> {
    let n = pts.len();
    let id = |i: u32| Tag(tags[i as usize]).index();
    labels.clear();
    labels.resize(n, Label::Other);
    let mut stats = RunStats::default();
    // Eligible points by cell, each cell's points from the lowest (ties: lower index): sorted
    // by (cell, height) packed in two integers, the input index read only on a tie.
    let mut order: Vec<(u64, i64, u32)> = (0..n)
        .filter(|&i| Tag(tags[i]).eligible())
        .map(|i| {
            let (cx, cy) = grid.block_of(pts[i][0], pts[i][1]);
            (cell_key(cx, cy), height_key(pts[i][2]), i as u32)
        })
        .collect();
    if order.is_empty() {
        return Ok(stats);
    }
    // Every key is distinct (the input index last): the same order on any number of cores.
    order.par_sort_unstable_by(|a, b| {
        (a.0, a.1)
            .cmp(&(b.0, b.1))
            .then_with(|| id(a.2).cmp(&id(b.2)))
    });
    // Cells: (first, end) into `order`, and the cursor of the current seed.
    let mut cells: Vec<(i64, i64, usize, usize)> = Vec::new();
    for (k, &(key, _, _)) in order.iter().enumerate() {
        let (cx, cy) = cell_of_key(key);
        match cells.last_mut() {
            Some(c) if c.0 == cx && c.1 == cy => c.3 = k + 1,
            _ => cells.push((cx, cy, k, k + 1)),
        }
    }
    let by_cell: HashMap<(i64, i64), usize> = cells
        .iter()
        .enumerate()
        .map(|(k, c)| ((c.0, c.1), k))
        .collect();
    let seed_z = |cells: &[(i64, i64, usize, usize)], k: usize| -> Option<f64> {
        let c = &cells[k];
        (c.2 < c.3).then(|| pts[order[c.2].2 as usize][2])
    };

    // 2. Low noise among the seeds.
    let mut flagged = Vec::new();
    let mut zs = Vec::with_capacity(8);
    loop {
        flagged.clear();
        for k in 0..cells.len() {
            let Some(z) = seed_z(&cells, k) else { continue };
            zs.clear();
            let (cx, cy) = (cells[k].0, cells[k].1);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if (dx, dy) != (0, 0)
                        && let Some(&m) = by_cell.get(&(cx + dx, cy + dy))
                        && let Some(w) = seed_z(&cells, m)
                    {
                        zs.push(w);
                    }
                }
            }
            if zs.len() >= 2 && z < median(&mut zs) - params.low_noise {
                flagged.push(k);
            }
        }
        if flagged.is_empty() {
            break;
        }
        for &k in &flagged {
            let c = &mut cells[k];
            labels[order[c.2].2 as usize] = Label::LowNoise;
            c.2 += 1;
        }
    }

    // 3. The initial TIN: the virtual ring, then the seeds.
    let seeds: Vec<u32> = cells
        .iter()
        .filter(|c| c.2 < c.3)
        .map(|c| order[c.2].2)
        .collect();
    stats.seeds = seeds.len() as u64;
    let ring = virtual_ring(rect, params.step, &pts, tags, &seeds);
    let mut tin = Tin::from_points(&ring)?;
    let virtuals = tin.vertex_slots();
    // Every point becomes a vertex id (point i is vertex virtuals + i), inserted or not.
    tin.reserve_vertices_exact(n);
    for p in &pts {
        tin.add_vertex(*p)?;
    }
    let vid = |i: u32| VertexId((virtuals + i as usize) as u32);
    for &s in &seeds {
        tin.insert_vertex(vid(s))?;
        labels[s as usize] = Label::Ground;
    }
    // The setup's peak: the points, their order and the TIN's copy of them.
    stats.bytes = (std::mem::size_of_val(&pts[..])
        + order.capacity() * std::mem::size_of::<(u64, i64, u32)>()
        + std::mem::size_of_val(tags)
        + labels.capacity()
        + tin.heap_bytes()) as u64;

    // 4. Densification, 5. the final TIN.
    let cand = order
        .iter()
        .map(|o| o.2)
        .filter(|&i| labels[i as usize] == Label::Other);
    let cand: Vec<u32> = cand.collect();
    drop(order);
    let (cand, deferred) = by_densify_cell(&pts, tags, labels, cand, &seeds, params.densify_cell);
    stats.deferred = deferred.len() as u64;
    drop(pts);
    let densify = Densify::new(tin, virtuals, tags, labels, params, &cand, deferred)?;
    drop(cand);
    densify.run(params.low_noise, params.offset, &mut stats)?;
    Ok(stats)
}

/// Splits the candidates `cand` (in their order) into those that densify — the lowest eligible
/// point (seeds included; ties: the lower input index) of their densification cell
/// (`floor(x / cell), floor(y / cell)`) — and the others, each with its cell's lowest point,
/// in point order (spatial: [`spatial_order`]). A cell of 0: every candidate densifies.
fn by_densify_cell(
    pts: &[[f64; 3]],
    tags: &[u64],
    labels: &[Label],
    cand: Vec<u32>,
    seeds: &[u32],
    cell: f64,
) -> (Vec<u32>, Vec<(u32, u32)>) {
    if cell == 0.0 || cand.is_empty() {
        return (cand, Vec::new());
    }
    let id = |i: u32| Tag(tags[i as usize]).index();
    let key = |i: u32| {
        let p = pts[i as usize];
        (
            (p[1] / cell).floor() as i64,
            (p[0] / cell).floor() as i64,
            i,
        )
    };
    let mut all: Vec<(i64, i64, u32)> = cand.iter().chain(seeds).map(|&i| key(i)).collect();
    all.par_sort_unstable_by(|a, b| {
        (a.0, a.1)
            .cmp(&(b.0, b.1))
            .then(pts[a.2 as usize][2].total_cmp(&pts[b.2 as usize][2]))
            .then(id(a.2).cmp(&id(b.2)))
    });
    let mut densifies = vec![false; pts.len()];
    let mut deferred = Vec::new();
    for group in all.chunk_by(|a, b| (a.0, a.1) == (b.0, b.1)) {
        let lowest = group[0].2;
        if labels[lowest as usize] == Label::Other {
            densifies[lowest as usize] = true;
        }
        deferred.extend(
            group[1..]
                .iter()
                .filter(|k| labels[k.2 as usize] == Label::Other)
                .map(|k| (k.2, lowest)),
        );
    }
    drop(all);
    deferred.par_sort_unstable();
    let cand = cand
        .into_iter()
        .filter(|&i| densifies[i as usize])
        .collect();
    (cand, deferred)
}

/// Puts the points of a run over `rect` (and their tags) in Z order (Morton order of a
/// 2^16 × 2^16 grid over `rect`): the candidates of a triangle then lie close together in
/// memory. The classes do not depend on this order (every tie is broken by the input index).
pub(crate) fn spatial_order(pts: &mut Vec<[f64; 3]>, tags: &mut Vec<u64>, rect: [f64; 4]) {
    let sx = 65535.0 / (rect[2] - rect[0]).max(f64::MIN_POSITIVE);
    let sy = 65535.0 / (rect[3] - rect[1]).max(f64::MIN_POSITIVE);
    let spread = |v: u32| -> u32 {
        let mut v = v & 0xFFFF;
        v = (v | (v << 8)) & 0x00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    };
    let mut keys: Vec<(u32, u32)> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let x = ((p[0] - rect[0]) * sx).clamp(0.0, 65535.0) as u32;
            let y = ((p[1] - rect[1]) * sy).clamp(0.0, 65535.0) as u32;
            (spread(x) | (spread(y) << 1), i as u32)
        })
        .collect();
    keys.par_sort_unstable();
    *pts = keys.iter().map(|&(_, i)| pts[i as usize]).collect();
    *tags = keys.iter().map(|&(_, i)| tags[i as usize]).collect();
}

/// A seed cell (coordinates within `i32`, as the block keys) as a key that sorts as `(cy, cx)`.
fn cell_key(cx: i64, cy: i64) -> u64 {
    let bits = |c: i64| u64::from((c as i32 as u32) ^ 0x8000_0000);
    (bits(cy) << 32) | bits(cx)
}

/// The cell `(cx, cy)` of a [`cell_key`].
fn cell_of_key(key: u64) -> (i64, i64) {
    let back = |b: u64| i64::from((b as u32 ^ 0x8000_0000) as i32);
    (back(key & 0xFFFF_FFFF), back(key >> 32))
}

/// A height as an integer that sorts as [`f64::total_cmp`] does.
fn height_key(z: f64) -> i64 {
    let b = z.to_bits() as i64;
    b ^ (((b >> 63) as u64) >> 1) as i64
}

/// The median of `v` (not empty): the mean of the two middle values for an even count.
fn median(v: &mut [f64]) -> f64 {
    v.sort_unstable_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Virtual points every `step` along `rect` grown by `step` (corners included), each at the
/// height of the nearest seed (ties: lower input index).
fn virtual_ring(
    rect: [f64; 4],
    step: f64,
    pts: &[[f64; 3]],
    tags: &[u64],
    seeds: &[u32],
) -> Vec<[f64; 3]> {
    let r = [
        rect[0] - step,
        rect[1] - step,
        rect[2] + step,
        rect[3] + step,
    ];
    let nx = (((r[2] - r[0]) / step).ceil() as usize).max(1);
    let ny = (((r[3] - r[1]) / step).ceil() as usize).max(1);
    let mut ring = Vec::with_capacity(2 * (nx + ny));
    let at = |k: usize, n: usize, a: f64, b: f64| {
        if k == n {
            b
        } else {
            a + (b - a) * k as f64 / n as f64
        }
    };
    for k in 0..nx {
        ring.push([at(k, nx, r[0], r[2]), r[1]]);
        ring.push([at(k + 1, nx, r[0], r[2]), r[3]]);
    }
    for k in 0..ny {
        ring.push([r[2], at(k, ny, r[1], r[3])]);
        ring.push([r[0], at(k + 1, ny, r[1], r[3])]);
    }
    ring.iter()
        .map(|q| {
            let mut bestd = (f64::INFINITY, u64::MAX, 0.0);
            for &s in seeds {
                let p = pts[s as usize];
                let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                let id = Tag(tags[s as usize]).index();
                if (d, id) < (bestd.0, bestd.1) {
                    bestd = (d, id, p[2]);
                }
            }
            [q[0], q[1], bestd.2]
        })
        .collect()
}

/// Checks the invariant the driver relies on: labels are one per point.
pub(crate) fn check_labels(labels: &[Label], n: usize) -> Result<()> {
    if labels.len() != n {
        return Err(Error::Internal(format!(
            "the ground run labelled {} points of {n}",
            labels.len()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{cell_key, cell_of_key, height_key};

    #[test]
    fn the_sort_keys_order_as_the_cells_and_heights_they_pack() {
        let cells = [
            (-5i64, -7i64),
            (-5, 3),
            (0, 0),
            (4, -7),
            (-1, 2),
            (1 << 30, -(1 << 30)),
        ];
        for &(ax, ay) in &cells {
            assert_eq!(cell_of_key(cell_key(ax, ay)), (ax, ay));
            for &(bx, by) in &cells {
                assert_eq!(
                    cell_key(ax, ay).cmp(&cell_key(bx, by)),
                    (ay, ax).cmp(&(by, bx))
                );
            }
        }
        let zs = [-1e9, -2.5, -0.0, 0.0, 1e-300, 3.25, 247.125, f64::MAX];
        for &a in &zs {
            for &b in &zs {
                assert_eq!(
                    height_key(a).cmp(&height_key(b)),
                    a.total_cmp(&b),
                    "{a} {b}"
                );
            }
        }
    }
}
