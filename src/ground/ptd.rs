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
//!    the densification stops when an iteration inserts nothing. A candidate is judged again
//!    only when a triangle its test read has changed (its answer cannot change otherwise).
//! 5. **The final TIN**: a point left over within `offset` (vertically) of the final ground TIN
//!    is ground too (densification stops in small triangles, where a few centimetres of noise
//!    make steep angles); one more than `low_noise` below it is low noise.
//!
//! Locating points and inserting them are the TIN's exact operations ([`Tin`]); the distance
//! and the angles are measurements against thresholds, in floating point relative to the
//! triangle's first vertex.

use super::{GroundParams, Tag};
use crate::error::{Error, Result};
use crate::tiles::grid::TileGrid;
use crate::tin::{PointLocation, Tin, TriId, VertexId};
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
}

/// A candidate's last test: the triangles it read.
#[derive(Clone, Copy)]
struct Probe {
    tri: u32,
    mirror: u32,
}

const NO_TRI: u32 = u32::MAX;

/// Classifies the points `pts` (their global input index and eligibility in `tags`) of the run
/// over the closed rectangle `rect`; only eligible points may become ground or low noise.
/// `grid`'s blocks are the seed cells.
///
/// # Errors
/// The TIN's errors (a coordinate out of range, too many vertices).
pub(crate) fn classify_run(
    pts: &[[f64; 3]],
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
    // Eligible points by cell, each cell's points from the lowest (ties: lower index).
    let mut order: Vec<(i64, i64, u32)> = (0..n)
        .filter(|&i| Tag(tags[i]).eligible())
        .map(|i| {
            let (cx, cy) = grid.block_of(pts[i][0], pts[i][1]);
            (cy, cx, i as u32)
        })
        .collect();
    if order.is_empty() {
        return Ok(stats);
    }
    order.sort_unstable_by(|a, b| {
        (a.0, a.1)
            .cmp(&(b.0, b.1))
            .then(pts[a.2 as usize][2].total_cmp(&pts[b.2 as usize][2]))
            .then(id(a.2).cmp(&id(b.2)))
    });
    // Cells: (first, end) into `order`, and the cursor of the current seed.
    let mut cells: Vec<(i64, i64, usize, usize)> = Vec::new();
    for (k, &(cy, cx, _)) in order.iter().enumerate() {
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
    let ring = virtual_ring(rect, params.step, pts, tags, &seeds);
    let mut tin = Tin::from_points(&ring)?;
    let virtuals = tin.vertex_slots();
    for &s in &seeds {
        tin.insert(pts[s as usize])?;
        labels[s as usize] = Label::Ground;
    }

    // 4. Densification.
    let sin_max = params.max_angle.to_radians().sin();
    let mut cand: Vec<u32> = order
        .iter()
        .map(|o| o.2)
        .filter(|&i| labels[i as usize] == Label::Other)
        .collect();
    let mut probes: Vec<Probe> = vec![
        Probe {
            tri: NO_TRI,
            mirror: NO_TRI,
        };
        n
    ];
    let mut touched_list: Vec<TriId> = Vec::new();
    let mut touched: Vec<bool> = Vec::new();
    // Best accepted candidate per triangle slot: (distance, index, point).
    let mut best: Vec<Option<(f64, u64, u32)>> = Vec::new();
    let mut best_slots: Vec<u32> = Vec::new();
    let mut first = true;
    tin.record_touched(true);
    while !cand.is_empty() && stats.iterations < MAX_ITERATIONS {
        stats.iterations += 1;
        best.resize(tin.triangle_slots(), None);
        for &i in &cand {
            let pr = probes[i as usize];
            let stale = first
                || touched.get(pr.tri as usize).copied().unwrap_or(true)
                || (pr.mirror != NO_TRI
                    && touched.get(pr.mirror as usize).copied().unwrap_or(true));
            if !stale {
                continue;
            }
            stats.evaluations += 1;
            let p = pts[i as usize];
            let (tri, verdict) = evaluate(&mut tin, pr.tri, p, params, sin_max, virtuals);
            let (mirror, accepted) = match verdict {
                Verdict::Accept(d) => (NO_TRI, Some(d)),
                Verdict::Reject => (NO_TRI, None),
                Verdict::Steep(v) => mirror_test(&mut tin, v, p, params, sin_max),
            };
            probes[i as usize] = Probe { tri, mirror };
            if let Some(d) = accepted {
                if tri == NO_TRI {
                    // At a vertex of the TIN already: ground without an insertion.
                    labels[i as usize] = Label::Ground;
                    continue;
                }
                let slot = &mut best[tri as usize];
                let better = match *slot {
                    None => {
                        best_slots.push(tri);
                        true
                    }
                    Some((bd, bi, _)) => (d, id(i)) < (bd, bi),
                };
                if better {
                    *slot = Some((d, id(i), i));
                }
            }
        }
        first = false;
        // Insert the chosen candidates (in input order: the TIN does not depend on it).
        let mut chosen: Vec<(u64, u32, u32)> = best_slots
            .iter()
            .filter_map(|&t| best[t as usize].take().map(|(_, id, i)| (id, i, t)))
            .collect();
        best_slots.clear();
        chosen.sort_unstable();
        for &(_, i, t) in &chosen {
            // The walk starts at the triangle the candidate was found in (or what a flip made
            // of it): next to the point.
            if tin.is_live(TriId(t)) {
                tin.set_hint(TriId(t));
            }
            tin.insert(pts[i as usize])?;
            labels[i as usize] = Label::Ground;
        }
        cand.retain(|&i| labels[i as usize] == Label::Other);
        if chosen.is_empty() {
            break;
        }
        touched.clear();
        touched.resize(tin.triangle_slots(), false);
        tin.take_touched(&mut touched_list);
        for t in touched_list.drain(..) {
            if let Some(s) = touched.get_mut(t.0 as usize) {
                *s = true;
            }
        }
    }
    tin.record_touched(false);

    // 5. Points on the final ground TIN (within `offset` vertically) are ground too; points
    //    far below it are low noise.
    for &i in &cand {
        let p = pts[i as usize];
        if let Some(z) = tin.interpolate([p[0], p[1]]) {
            if (p[2] - z).abs() <= params.offset {
                labels[i as usize] = Label::Ground;
            } else if p[2] < z - params.low_noise {
                labels[i as usize] = Label::LowNoise;
            }
        }
    }
    Ok(stats)
}

/// Densification stops after this many iterations even if points are still accepted (each
/// iteration inserts at most one point per triangle; real data needs a few dozen).
const MAX_ITERATIONS: u64 = 10_000;

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

/// The outcome of testing a candidate against its triangle.
enum Verdict {
    /// Accepted, at this distance from the plane.
    Accept(f64),
    /// Too far from the plane (or no triangle).
    Reject,
    /// Close enough to the plane but an angle is too steep: the nearest real vertex, to mirror
    /// through, with the candidate's distance.
    Steep(Option<(VertexId, f64)>),
}

/// Locates `p` (walking from triangle `from`, or the last one used) and tests it against its
/// triangle: the triangle slot (or [`NO_TRI`] at a vertex) and the verdict.
fn evaluate(
    tin: &mut Tin,
    from: u32,
    p: [f64; 3],
    params: &GroundParams,
    sin_max: f64,
    virtuals: usize,
) -> (u32, Verdict) {
    let q = [p[0], p[1]];
    let loc =
        if from != NO_TRI && (from as usize) < tin.triangle_slots() && tin.is_live(TriId(from)) {
            tin.locate_from(TriId(from), q)
        } else {
            tin.locate(q)
        };
    let t = match loc {
        PointLocation::Inside(t) => t,
        PointLocation::OnEdge(e) => e.tri(),
        PointLocation::OnVertex(v) => {
            let d = (p[2] - tin.z(v)).abs();
            return if d <= params.max_distance && (v.0 as usize) >= virtuals {
                (NO_TRI, Verdict::Accept(d))
            } else {
                let t = tin.out_edge(v).map_or(NO_TRI, |e| e.tri().0);
                (t, Verdict::Reject)
            };
        }
        PointLocation::Outside(_) => return (NO_TRI, Verdict::Reject),
    };
    let vs = tin.tri_vertices(t);
    let corners = vs.map(|v| tin.point(v));
    match test(corners, p, params.max_distance, sin_max) {
        Test::Accept(d) => (t.0, Verdict::Accept(d)),
        Test::Far => (t.0, Verdict::Reject),
        Test::Steep(d) => {
            if !params.mirror {
                return (t.0, Verdict::Reject);
            }
            // The nearest real vertex (ties: the lower vertex id).
            let near = vs
                .iter()
                .filter(|v| (v.0 as usize) >= virtuals)
                .map(|&v| {
                    let c = tin.point(v);
                    ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2), v.0, v)
                })
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                .map(|m| (m.2, d));
            (t.0, Verdict::Steep(near))
        }
    }
}

/// The mirror test: `p` mirrored through vertex `v` (in 3-D) tested against the triangle under
/// the mirror point: the triangle read, and the distance of `p` when accepted.
fn mirror_test(
    tin: &mut Tin,
    near: Option<(VertexId, f64)>,
    p: [f64; 3],
    params: &GroundParams,
    sin_max: f64,
) -> (u32, Option<f64>) {
    let Some((v, d)) = near else {
        return (NO_TRI, None);
    };
    let c = tin.point(v);
    let m = [2.0 * c[0] - p[0], 2.0 * c[1] - p[1], 2.0 * c[2] - p[2]];
    let t = match tin.locate([m[0], m[1]]) {
        PointLocation::Inside(t) => t,
        PointLocation::OnEdge(e) => e.tri(),
        _ => return (NO_TRI, None),
    };
    let corners = tin.tri_vertices(t).map(|v| tin.point(v));
    match test(corners, m, params.max_distance, sin_max) {
        Test::Accept(_) => (t.0, Some(d)),
        _ => (t.0, None),
    }
}

enum Test {
    Accept(f64),
    Far,
    Steep(f64),
}

/// Axelsson's test of `p` against the plane of triangle `t`: its distance to the plane at most
/// `max_d`, and every angle between the plane and the lines to the corners at most the angle
/// whose sine is `sin_max`.
#[inline]
fn test(t: [[f64; 3]; 3], p: [f64; 3], max_d: f64, sin_max: f64) -> Test {
    let a = t[0];
    let u = [t[1][0] - a[0], t[1][1] - a[1], t[1][2] - a[2]];
    let v = [t[2][0] - a[0], t[2][1] - a[1], t[2][2] - a[2]];
    let nrm = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
    if len == 0.0 || !len.is_finite() {
        return Test::Far;
    }
    let w = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let d = (w[0] * nrm[0] + w[1] * nrm[1] + w[2] * nrm[2]).abs() / len;
    if d > max_d || d.is_nan() {
        return Test::Far;
    }
    for c in &t {
        let r2 = (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2);
        // angle > max  <=>  d / r > sin(max)
        if d > r2.sqrt() * sin_max {
            return Test::Steep(d);
        }
    }
    Test::Accept(d)
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
