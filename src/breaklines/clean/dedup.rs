//! Rules 1–3 of the [cleaner](super): the input checked, exact duplicate vertices merged (first
//! known `z` wins), zero-length segments dropped and duplicate segments merged.

use super::{
    CELLS_PER_ITEM, CleanOptions, CleanStats, SNAP_REL, Work, ZConflict, ZConflictKind, bounds,
};
use crate::error::{Error, Result};
use crate::geom::grid::Grid;
use crate::geom::predicates::check_coord;
use rayon::prelude::*;

impl Work {
    pub(super) fn new(polylines: &[Vec<[f64; 3]>], options: &CleanOptions) -> Result<Work> {
        check_input(polylines)?;
        let total: usize = polylines.iter().map(Vec::len).sum();
        if total >= u32::MAX as usize {
            return Err(Error::TooManyPoints {
                count: total as u64,
                max: u32::MAX as u64 - 1,
            });
        }
        let id_of = merge_ids(polylines, total);
        let mut w = Work {
            xy: Vec::new(),
            z: Vec::new(),
            vline: Vec::new(),
            segs: Vec::new(),
            line: Vec::new(),
            dirty: Vec::new(),
            isolated: Vec::new(),
            lo: [0.0; 2],
            hi: [0.0; 2],
            grid: Grid::new([0.0; 2], [0.0; 2], 1),
            snap: 0.0,
            ztol: options.z_tolerance,
            stats: CleanStats {
                input_vertices: total as u64,
                ..CleanStats::default()
            },
            warnings: Vec::new(),
        };
        w.add_vertices(polylines, &id_of);
        w.add_segments(polylines, &id_of);
        let (lo, hi, mag) = bounds(&w.xy);
        (w.lo, w.hi) = (lo, hi);
        let items = w.segs.len() + w.isolated.len();
        w.grid = Grid::new(lo, hi, (items as f64 * CELLS_PER_ITEM) as usize);
        w.snap = options.snap.unwrap_or(SNAP_REL * mag).max(0.0);
        Ok(w)
    }

    /// Creates the distinct vertices in order of first appearance; first known `z` wins.
    fn add_vertices(&mut self, polylines: &[Vec<[f64; 3]>], id_of: &[u32]) {
        let mut g = 0usize;
        for (i, p) in polylines.iter().enumerate() {
            for v in p {
                let id = id_of[g] as usize;
                g += 1;
                if id == self.xy.len() {
                    self.xy.push([v[0] + 0.0, v[1] + 0.0]);
                    self.z.push(v[2]);
                    self.vline.push(i as u32);
                    continue;
                }
                self.stats.merged_vertices += 1;
                let kept = self.z[id];
                if kept.is_nan() {
                    self.z[id] = v[2];
                } else if (v[2] - kept).abs() > self.ztol {
                    self.warn(ZConflict {
                        at: self.xy[id],
                        z: [kept, v[2]],
                        kind: ZConflictKind::Duplicate,
                        lines: [self.vline[id], i as u32],
                    });
                }
            }
        }
    }

    /// Segments between consecutive distinct vertices, normalised, sorted and deduplicated.
    fn add_segments(&mut self, polylines: &[Vec<[f64; 3]>], id_of: &[u32]) {
        let mut segs: Vec<([u32; 2], u32)> = Vec::new();
        let mut g = 0usize;
        for (i, p) in polylines.iter().enumerate() {
            let ids = &id_of[g..g + p.len()];
            g += p.len();
            self.stats.input_segments += ids.len().saturating_sub(1) as u64;
            for w in ids.windows(2) {
                if w[0] == w[1] {
                    self.stats.zero_length += 1;
                } else {
                    segs.push(([w[0].min(w[1]), w[0].max(w[1])], i as u32));
                }
            }
        }
        segs.par_sort_unstable();
        let before = segs.len();
        segs.dedup_by_key(|s| s.0);
        self.stats.duplicate_segments = (before - segs.len()) as u64;
        let mut used = vec![false; self.xy.len()];
        for (s, _) in &segs {
            used[s[0] as usize] = true;
            used[s[1] as usize] = true;
        }
        self.isolated = (0..self.xy.len() as u32)
            .filter(|&v| !used[v as usize])
            .collect();
        self.line = segs.iter().map(|s| s.1).collect();
        self.segs = segs.into_iter().map(|s| s.0).collect();
        self.dirty = vec![true; self.segs.len()];
    }
}

/// Every `x, y` finite and in the predicates' range, every `z` finite or `NaN`.
pub(super) fn check_input(polylines: &[Vec<[f64; 3]>]) -> Result<()> {
    let bad = polylines.par_iter().enumerate().find_map_first(|(i, p)| {
        p.iter()
            .enumerate()
            .find_map(|(k, v)| check_vertex(i as u64, k as u64, v).err())
    });
    match bad {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// [`check_input`] for vertex `vertex` of polyline `polyline`.
pub(super) fn check_vertex(polyline: u64, vertex: u64, v: &[f64; 3]) -> Result<()> {
    let message = if !(v[0].is_finite() && v[1].is_finite()) {
        format!("coordinate is not finite ({}, {})", v[0], v[1])
    } else if !(check_coord(v[0]) && check_coord(v[1])) {
        format!(
            "coordinate ({}, {}) is outside the range where the predicates are exact",
            v[0], v[1]
        )
    } else if v[2].is_infinite() {
        format!("z is infinite ({})", v[2])
    } else {
        return Ok(());
    };
    Err(Error::BadLine {
        polyline,
        vertex,
        message,
    })
}

/// For every input vertex (in input order), its distinct-vertex id; ids are given in order of
/// first appearance.
fn merge_ids(polylines: &[Vec<[f64; 3]>], total: usize) -> Vec<u32> {
    let flat: Vec<[f64; 2]> = polylines
        .iter()
        .flatten()
        .map(|v| [v[0] + 0.0, v[1] + 0.0])
        .collect();
    let mut keys: Vec<(u64, u64, u32)> = flat
        .par_iter()
        .enumerate()
        .map(|(g, p)| (p[0].to_bits(), p[1].to_bits(), g as u32))
        .collect();
    keys.par_sort_unstable();
    // First appearance of each position.
    let mut rep = vec![0u32; total];
    let mut k = 0;
    while k < keys.len() {
        let first = keys[k].2;
        let mut e = k;
        while e < keys.len() && keys[e].0 == keys[k].0 && keys[e].1 == keys[k].1 {
            rep[keys[e].2 as usize] = first;
            e += 1;
        }
        k = e;
    }
    let mut id_of = vec![0u32; total];
    let mut next = 0u32;
    for g in 0..total {
        let r = rep[g] as usize;
        if r == g {
            id_of[g] = next;
            next += 1;
        } else {
            id_of[g] = id_of[r];
        }
    }
    id_of
}
