//! Rules 7–8 of the [cleaner](super), applying what a round found: crossing points snapped to a
//! near vertex or made new ones, `z` merged, segments split into their pieces and identical pieces
//! merged.

use super::intersect::Found;
use super::{Work, ZConflict, ZConflictKind, lex};
use crate::geom::grid::Buckets;
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::HashMap;

impl Work {
    /// Turns the pair results into splits (creating or snapping crossing vertices) and applies
    /// them.
    pub(super) fn apply(&mut self, found: Found) {
        let mut splits: Vec<(u32, u32)> = Vec::new();
        let mut on_line: Vec<(u32, u32)> = Vec::new();
        let mut crossings: Vec<(u32, u32, [f64; 2])> = Vec::new();
        for ([i, j], r) in found {
            self.stats.overlaps += u64::from(r.overlap);
            for &(seg, v) in &r.splits[..r.n_splits as usize] {
                on_line.push((seg, v));
            }
            if let Some(p) = r.cross {
                crossings.push((i, j, p));
            }
        }
        for &(seg, v) in &on_line {
            let zi = self.z_along(seg, self.p(v));
            self.merge_z(v, zi, [self.line[seg as usize], self.vline[v as usize]]);
        }
        self.stats.vertex_splits += on_line.len() as u64;
        splits.extend(on_line);
        if !crossings.is_empty() {
            self.stats.crossings += crossings.len() as u64;
            // In the order of the points, so that which crossing point of a cluster becomes the
            // vertex depends on the geometry only.
            crossings.par_sort_by(|x, y| lex(x.2, y.2).then((x.0, x.1).cmp(&(y.0, y.1))));
            // The nearest existing vertex of each crossing, in parallel; the vertices made in this
            // round are looked at in order below.
            let vertices = Buckets::points(&self.grid, &self.xy);
            let old: Vec<Option<Near>> = crossings
                .par_iter()
                .map(|c| {
                    let mut best = None;
                    self.snap_cells(c.2, |cell| {
                        for &v in vertices.cell(cell) {
                            best = closer(best, c.2, self.xy[v as usize], v, self.snap);
                        }
                    });
                    best
                })
                .collect();
            let mut fresh: HashMap<u32, Vec<u32>> = HashMap::new();
            for ((s, t, p), near) in crossings.into_iter().zip(old) {
                let v = self.crossing_vertex(s, t, p, near, &mut fresh);
                for seg in [s, t] {
                    let [a, b] = self.segs[seg as usize];
                    if v != a && v != b {
                        splits.push((seg, v));
                    }
                }
            }
        }
        self.split(splits);
    }

    /// The cells within the snap distance of `p`.
    fn snap_cells(&self, p: [f64; 2], f: impl FnMut(u32)) {
        let (lo, hi) = (
            [p[0] - self.snap, p[1] - self.snap],
            [p[0] + self.snap, p[1] + self.snap],
        );
        self.grid.box_cells(lo, hi, f);
    }

    /// The vertex for the crossing of `s` and `t` at `p`: the nearest of `near` (the nearest
    /// older vertex within the snap distance) and the vertices made in this round (`fresh`, by
    /// cell), or a new one.
    fn crossing_vertex(
        &mut self,
        s: u32,
        t: u32,
        p: [f64; 2],
        near: Option<Near>,
        fresh: &mut HashMap<u32, Vec<u32>>,
    ) -> u32 {
        let (zs, zt) = (self.z_along(s, p), self.z_along(t, p));
        let lines = [self.line[s as usize], self.line[t as usize]];
        let mut best = near;
        if !fresh.is_empty() {
            self.snap_cells(p, |c| {
                for &v in fresh.get(&c).map_or(&[][..], |l| &l[..]) {
                    best = closer(best, p, self.xy[v as usize], v, self.snap);
                }
            });
        }
        if let Some(Near { v, .. }) = best {
            self.stats.snapped += 1;
            self.merge_z(v, zs, lines);
            self.merge_z(v, zt, lines);
            return v;
        }
        let z = match (zs.is_nan(), zt.is_nan()) {
            (false, false) => {
                if (zs - zt).abs() > self.ztol {
                    self.warn(ZConflict {
                        at: p,
                        z: [zs, zt],
                        kind: ZConflictKind::Crossing,
                        lines,
                    });
                }
                0.5 * (zs + zt)
            }
            (false, true) => zs,
            _ => zt,
        };
        let v = self.xy.len() as u32;
        self.xy.push(p);
        self.z.push(z);
        self.vline.push(lines[0]);
        self.stats.new_vertices += 1;
        fresh.entry(self.grid.cell_of(p)).or_default().push(v);
        v
    }

    /// Gives `v` the value `zin` if it has none; reports a disagreement otherwise.
    fn merge_z(&mut self, v: u32, zin: f64, lines: [u32; 2]) {
        let kept = self.z[v as usize];
        if kept.is_nan() {
            self.z[v as usize] = zin;
        } else if (zin - kept).abs() > self.ztol {
            self.warn(ZConflict {
                at: self.p(v),
                z: [kept, zin],
                kind: ZConflictKind::OnLine,
                lines,
            });
        }
    }

    /// `z` interpolated linearly along segment `seg` at (the projection of) `p`.
    fn z_along(&self, seg: u32, p: [f64; 2]) -> f64 {
        let [a, b] = self.segs[seg as usize];
        z_between(
            [self.p(a), self.p(b)],
            [self.z[a as usize], self.z[b as usize]],
            p,
        )
    }

    /// Replaces every segment that has splits by its pieces; merges identical segments.
    fn split(&mut self, mut splits: Vec<(u32, u32)>) {
        splits.par_sort_unstable();
        splits.dedup();
        let mut out: Vec<([u32; 2], u32, bool)> =
            Vec::with_capacity(self.segs.len() + splits.len());
        let mut k = 0;
        let mut chain: Vec<u32> = Vec::new();
        for (i, &[a, b]) in self.segs.iter().enumerate() {
            let line = self.line[i];
            if k >= splits.len() || splits[k].0 != i as u32 {
                out.push(([a, b], line, false));
                continue;
            }
            chain.clear();
            while k < splits.len() && splits[k].0 == i as u32 {
                chain.push(splits[k].1);
                k += 1;
            }
            let (pa, pb) = (self.p(a), self.p(b));
            chain.sort_by(|&u, &v| along(pa, pb, self.p(u), self.p(v)));
            let mut prev = a;
            for &v in chain.iter().chain(std::iter::once(&b)) {
                out.push(([prev.min(v), prev.max(v)], line, true));
                prev = v;
            }
        }
        out.par_sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.cmp(&y.1)));
        let before = out.len();
        // Identical segments: keep the first line; it needs testing only if every copy is new.
        let mut merged: Vec<([u32; 2], u32, bool)> = Vec::with_capacity(out.len());
        for s in out {
            match merged.last_mut() {
                Some(last) if last.0 == s.0 => last.2 &= s.2,
                _ => merged.push(s),
            }
        }
        self.stats.merged_pieces += (before - merged.len()) as u64;
        self.segs = merged.iter().map(|s| s.0).collect();
        self.line = merged.iter().map(|s| s.1).collect();
        self.dirty = merged.iter().map(|s| s.2).collect();
        self.refresh_isolated();
    }

    /// Drops isolated vertices that became segment ends.
    fn refresh_isolated(&mut self) {
        if self.isolated.is_empty() {
            return;
        }
        let mut used = vec![false; self.xy.len()];
        for s in &self.segs {
            used[s[0] as usize] = true;
            used[s[1] as usize] = true;
        }
        self.isolated.retain(|&v| !used[v as usize]);
    }
}

/// `z` interpolated linearly along the segment from `e[0]` (height `z[0]`) to `e[1]` at (the
/// projection of) `p`.
pub(super) fn z_between(e: [[f64; 2]; 2], z: [f64; 2], p: [f64; 2]) -> f64 {
    let [pa, pb] = e;
    let [za, zb] = z;
    let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
    let u = ((p[0] - pa[0]) * dx + (p[1] - pa[1]) * dy) / (dx * dx + dy * dy);
    let u = u.clamp(0.0, 1.0);
    za + u * (zb - za)
}

/// Order of `u` and `v` along the segment from `a` to `b`: along its dominant axis, then the
/// other one (exact for points on the segment; a consistent order for points snapped near it).
pub(super) fn along(a: [f64; 2], b: [f64; 2], u: [f64; 2], v: [f64; 2]) -> Ordering {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (major, minor) = if dx.abs() >= dy.abs() { (0, 1) } else { (1, 0) };
    let dir = |d: f64, x: f64, y: f64| {
        if d < 0.0 {
            y.total_cmp(&x)
        } else {
            x.total_cmp(&y)
        }
    };
    let d = [dx, dy];
    dir(d[major], u[major], v[major]).then(dir(d[minor], u[minor], v[minor]))
}

/// A vertex near a crossing point.
#[derive(Clone, Copy, Debug)]
pub(super) struct Near {
    pub(super) d2: f64,
    pub(super) at: [f64; 2],
    pub(super) v: u32,
}

/// `best`, or vertex `v` at `q` if it is within `snap` of `p` (or exactly at `p`) and nearer
/// (ties: lower in `(x, y)` order).
#[inline]
pub(super) fn closer(
    best: Option<Near>,
    p: [f64; 2],
    q: [f64; 2],
    v: u32,
    snap: f64,
) -> Option<Near> {
    let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
    if !(d2 <= snap * snap || q == p) {
        return best;
    }
    match best {
        Some(b) if d2.total_cmp(&b.d2).then(lex(q, b.at)) != Ordering::Less => best,
        _ => Some(Near { d2, at: q, v }),
    }
}
