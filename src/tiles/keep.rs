//! What a finished tile keeps: its owned triangles, their vertices, and the degree of every owned
//! vertex, from the certified triangles of its runs.

use super::grid::{BlockRect, TileGrid};
use super::worker::{NOT_OWNED, TileOutput};
use crate::idmap::FastMap;
use crate::sink::Needs;
use std::cmp::Ordering;

/// What the writer will do with a tile's owned triangles.
#[derive(Clone, Debug)]
pub(crate) struct Want {
    /// A mesh numbers the vertices: it needs every owned vertex's degree and every triangle.
    pub mesh: bool,
    /// The products' needs: triangles they do not want are counted, not kept ([`Needs`]).
    pub needs: Needs,
    /// The needs are covering and nothing else looks at every triangle: tiles leave the unwanted
    /// triangles deep inside them uncertified and uncounted ([`super::worker`]).
    pub skip_inside: bool,
}

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
/// triangles meeting the tile are), and `patched`: certified triangles of later runs (world
/// coordinates, counter-clockwise; a triangle may come from two runs, and a patch's triangle
/// may be one of the first run's).
pub(crate) fn from_runs(
    owner: &Owner,
    task: Option<&Owner>,
    want: &Want,
    t: &crate::Triangulation,
    certified: &[u32],
    patched: &[[[f64; 3]; 3]],
    out: &mut TileOutput,
) {
    if patched.is_empty() {
        collect(
            owner,
            task,
            want,
            &t.vertices,
            certified.iter().map(|&k| t.triangles[k as usize]),
            out,
        );
        return;
    }
    // The patches' vertices: the first run's (its vertices are in sweep order, so found by
    // binary search), or new ones appended.
    let mut vertices = t.vertices.clone();
    let first = t.vertices.len();
    let mut shared = vec![false; first];
    let mut new_ids: FastMap<(u64, u64), u32> = FastMap::default();
    let mut id_of = |p: &[f64; 3], vertices: &mut Vec<[f64; 3]>| -> u32 {
        match t.vertices.binary_search_by(|v| sweep_cmp(v, p)) {
            Ok(i) => {
                shared[i] = true;
                i as u32
            }
            Err(_) => *new_ids
                .entry((p[0].to_bits(), p[1].to_bits()))
                .or_insert_with(|| {
                    vertices.push(*p);
                    (vertices.len() - 1) as u32
                }),
        }
    };
    // A patch's triangle that is also one of the first run's is kept where the first run has it.
    let mut patch_tris: Vec<[u32; 3]> = Vec::with_capacity(patched.len());
    let mut keys: FastMap<[u32; 3], bool> = FastMap::default();
    for p in patched {
        let v = p.map(|q| id_of(&q, &mut vertices));
        let mut k = v;
        k.sort_unstable();
        if keys.insert(k, false).is_none() {
            patch_tris.push(v);
        }
    }
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(certified.len() + patch_tris.len());
    for &k in certified {
        let v = t.triangles[k as usize];
        if v.iter().all(|&i| shared[i as usize]) {
            let mut s = v;
            s.sort_unstable();
            if let Some(dup) = keys.get_mut(&s) {
                *dup = true;
            }
        }
        tris.push(v);
    }
    for v in patch_tris {
        let mut s = v;
        s.sort_unstable();
        if !keys[&s] {
            tris.push(v);
        }
    }
    // Number the vertices in sweep order again (the new ones are few), so that a triangle's
    // lowest vertex is its least number.
    let mut order: Vec<u32> = (first as u32..vertices.len() as u32).collect();
    order.sort_unstable_by(|&i, &j| sweep_cmp(&vertices[i as usize], &vertices[j as usize]));
    let mut remap = vec![0u32; vertices.len()];
    let mut sorted = Vec::with_capacity(vertices.len());
    let mut news = order.iter().peekable();
    for i in 0..first {
        while let Some(&&j) = news.peek()
            && sweep_cmp(&vertices[j as usize], &vertices[i]) == Ordering::Less
        {
            remap[j as usize] = sorted.len() as u32;
            sorted.push(vertices[j as usize]);
            news.next();
        }
        remap[i] = sorted.len() as u32;
        sorted.push(vertices[i]);
    }
    for &j in news {
        remap[j as usize] = sorted.len() as u32;
        sorted.push(vertices[j as usize]);
    }
    for t in &mut tris {
        *t = t.map(|i| remap[i as usize]);
    }
    collect(owner, task, want, &sorted, tris.iter().copied(), out);
}

/// Fills `out` from triangles (indices into `vertices`, which are in sweep order; each triangle
/// once) certified for the tile: the owned ones the writer wants (the others counted in
/// `out.skipped`), and for a mesh every owned vertex's degree.
fn collect(
    owner: &Owner,
    task: Option<&Owner>,
    want: &Want,
    vertices: &[[f64; 3]],
    tris: impl Iterator<Item = [u32; 3]> + Clone,
    out: &mut TileOutput,
) {
    let n = vertices.len();
    let is_owned: Vec<bool> = vertices.iter().map(|p| owner.owns(p)).collect();
    let low = |t: &[u32; 3]| t[0].min(t[1]).min(t[2]) as usize;
    let (degree, foreign) = if want.mesh {
        degrees(&is_owned, tris.clone())
    } else {
        (Vec::new(), Vec::new())
    };
    // Sized once: growing them copies into fresh pages, tile after tile.
    if matches!(want.needs, Needs::All) {
        out.triangles
            .reserve(tris.clone().filter(|t| is_owned[low(t)]).count());
        out.vertices.reserve(n);
    }
    if want.mesh {
        out.degree.reserve(n);
    }
    let mut map = vec![u32::MAX; n];
    let mut add = |i: usize, out: &mut TileOutput| -> u32 {
        if map[i] == u32::MAX {
            map[i] = out.vertices.len() as u32;
            out.vertices.push(vertices[i]);
            if want.mesh {
                out.degree
                    .push(if is_owned[i] { degree[i] } else { NOT_OWNED });
            }
        }
        map[i]
    };
    for tri in tris {
        let l = low(&tri);
        if is_owned[l] {
            // (Without a filter, no coordinates are gathered.)
            if matches!(want.needs, Needs::All)
                || want.needs.wants(&tri.map(|i| vertices[i as usize]))
            {
                let o = tri.map(|i| add(i as usize, out));
                out.triangles.push(o);
            } else {
                out.skipped += 1;
            }
        } else if task.is_some_and(|tk| !tk.owns(&vertices[l])) {
            let o = tri.map(|i| add(i as usize, out));
            out.boundary.push(o);
        }
    }
    if want.mesh {
        for i in 0..n {
            if is_owned[i] && foreign[i] {
                add(i, out);
            }
        }
    }
    out.points_kept = is_owned.iter().filter(|&&o| o).count() as u64;
}

/// Each vertex's number of triangles, and whether a triangle owned by another tile uses it.
fn degrees(is_owned: &[bool], tris: impl Iterator<Item = [u32; 3]>) -> (Vec<u32>, Vec<bool>) {
    let n = is_owned.len();
    let mut degree = vec![0u32; n];
    let mut foreign = vec![false; n];
    for tri in tris {
        let o = is_owned[tri[0].min(tri[1]).min(tri[2]) as usize];
        for &i in &tri {
            degree[i as usize] += 1;
            if !o {
                foreign[i as usize] = true;
            }
        }
    }
    (degree, foreign)
}
