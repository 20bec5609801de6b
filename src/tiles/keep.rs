//! What a finished tile keeps: its owned triangles, their vertices, and the degree of every owned
//! vertex, from the certified triangles of its runs.

use super::grid::{BlockRect, TileGrid};
use super::worker::{NOT_OWNED, TileOutput};
use crate::idmap::{FastMap, FastSet};
use std::cmp::Ordering;

/// Decides which points the tile owns: clearly inside or outside its rectangle by a margin, or
/// else by the block function itself (the one rule of ownership).
pub(crate) struct Owner {
    grid: TileGrid,
    owned: BlockRect,
    w: [f64; 4],
    m: f64,
}

impl Owner {
    pub fn new(grid: TileGrid, owned: BlockRect) -> Owner {
        let w = grid.world(&owned);
        let m = grid.margin(w.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        Owner { grid, owned, w, m }
    }

    #[inline]
    pub fn owns(&self, p: &[f64; 3]) -> bool {
        let (x, y, w, m) = (p[0], p[1], &self.w, self.m);
        if x > w[0] + m && x < w[2] - m && y > w[1] + m && y < w[3] - m {
            true
        } else if x < w[0] - m || x > w[2] + m || y < w[1] - m || y > w[3] + m {
            false
        } else {
            let (bx, by) = self.grid.block_of(x, y);
            self.owned.contains(bx, by)
        }
    }
}

/// Sweep order of two points (`y`, then `x`).
fn sweep_cmp(a: &[f64; 3], b: &[f64; 3]) -> Ordering {
    a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0]))
}

/// Fills `out` from one run, `certified` naming the run's triangles that are certified (all the
/// triangles meeting the tile are). Vertices are in sweep order, so a triangle's lowest vertex is
/// its least index.
pub(crate) fn from_run(
    owner: &Owner,
    task: Option<&Owner>,
    t: &crate::Triangulation,
    certified: &[u32],
    out: &mut TileOutput,
) {
    let n = t.vertices.len();
    let is_owned: Vec<bool> = t.vertices.iter().map(|p| owner.owns(p)).collect();
    let mut degree = vec![0u32; n];
    let mut foreign = vec![false; n];
    for &k in certified {
        let tri = t.triangles[k as usize];
        let low = tri[0].min(tri[1]).min(tri[2]) as usize;
        for &i in &tri {
            degree[i as usize] += 1;
            if !is_owned[low] {
                foreign[i as usize] = true;
            }
        }
    }
    let mut map = vec![u32::MAX; n];
    let mut add = |i: usize, out: &mut TileOutput| -> u32 {
        if map[i] == u32::MAX {
            map[i] = out.vertices.len() as u32;
            out.vertices.push(t.vertices[i]);
            out.degree
                .push(if is_owned[i] { degree[i] } else { NOT_OWNED });
        }
        map[i]
    };
    for &k in certified {
        let tri = t.triangles[k as usize];
        let low = tri[0].min(tri[1]).min(tri[2]) as usize;
        if is_owned[low] {
            let o = tri.map(|i| add(i as usize, out));
            out.triangles.push(o);
        } else if task.is_some_and(|tk| !tk.owns(&t.vertices[low])) {
            let o = tri.map(|i| add(i as usize, out));
            out.boundary.push(o);
        }
    }
    for i in 0..n {
        if is_owned[i] && foreign[i] {
            add(i, out);
        }
    }
    out.points_kept = is_owned.iter().filter(|&&o| o).count() as u64;
}

/// Fills `out` from certified triangles of several runs (world coordinates, counter-clockwise;
/// the same triangle may come from two runs).
pub(crate) fn from_list(
    owner: &Owner,
    task: Option<&Owner>,
    tris: &[[[f64; 3]; 3]],
    out: &mut TileOutput,
) {
    let key = |p: &[f64; 3]| (p[0].to_bits(), p[1].to_bits());
    let mut ids: FastMap<(u64, u64), u32> = FastMap::default();
    ids.reserve(tris.len() / 2 + 16);
    let mut pts: Vec<[f64; 3]> = Vec::with_capacity(tris.len() / 2 + 16);
    let mut seen = FastSet::default();
    seen.reserve(tris.len());
    let mut unique: Vec<[u32; 3]> = Vec::with_capacity(tris.len());
    for t in tris {
        let v = t.map(|p| {
            *ids.entry(key(&p)).or_insert_with(|| {
                pts.push(p);
                (pts.len() - 1) as u32
            })
        });
        let mut s = v;
        s.sort_unstable();
        if seen.insert(s) {
            unique.push(v);
        }
    }
    let is_owned: Vec<bool> = pts.iter().map(|p| owner.owns(p)).collect();
    let low = |t: &[u32; 3]| -> usize {
        let mut l = t[0];
        for &i in &t[1..] {
            if sweep_cmp(&pts[i as usize], &pts[l as usize]) == Ordering::Less {
                l = i;
            }
        }
        l as usize
    };
    let mut degree = vec![0u32; pts.len()];
    let mut foreign = vec![false; pts.len()];
    for t in &unique {
        let o = is_owned[low(t)];
        for &i in t {
            degree[i as usize] += 1;
            if !o {
                foreign[i as usize] = true;
            }
        }
    }
    let mut map = vec![u32::MAX; pts.len()];
    let mut add = |i: usize, out: &mut TileOutput| -> u32 {
        if map[i] == u32::MAX {
            map[i] = out.vertices.len() as u32;
            out.vertices.push(pts[i]);
            out.degree
                .push(if is_owned[i] { degree[i] } else { NOT_OWNED });
        }
        map[i]
    };
    for t in &unique {
        let l = low(t);
        if is_owned[l] {
            let o = t.map(|i| add(i as usize, out));
            out.triangles.push(o);
        } else if task.is_some_and(|tk| !tk.owns(&pts[l])) {
            let o = t.map(|i| add(i as usize, out));
            out.boundary.push(o);
        }
    }
    for i in 0..pts.len() {
        if is_owned[i] && foreign[i] {
            add(i, out);
        }
    }
}
