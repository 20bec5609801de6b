//! Step 5, against the final TIN: the candidates left over, and those that do not densify
//! (`--densify-cell`), each located in the final TIN and judged once, as an iteration would
//! judge it.

use super::{Densify, Effect, NONE, Plane, Verdicts};
use crate::error::Result;
use crate::ground::ptd::Label;
use crate::tin::{TriId, VertexId, planar};
use rayon::prelude::*;

/// Points a task of step 5 labels (pieces on every core).
const FINISH_PIECE: usize = 8192;

impl Densify<'_> {
    /// Step 5: a candidate left within `offset` (vertically) of the final ground TIN is ground,
    /// one more than `low_noise` below it is low noise; each point alone, on every core.
    pub(super) fn finish(&mut self, low_noise: f64, offset: f64) {
        let (tin, tri, virtuals) = (&self.tin, &self.tri, self.virtuals);
        let labels = &mut *self.labels;
        labels
            .par_chunks_mut(FINISH_PIECE)
            .enumerate()
            .for_each(|(k, piece)| {
                for (j, label) in piece.iter_mut().enumerate() {
                    let i = k * FINISH_PIECE + j;
                    let t = tri[i];
                    if t == NONE || *label != Label::Other {
                        continue;
                    }
                    let p = tin.point(VertexId((virtuals + i) as u32));
                    let [a, b, c] = tin.tri_vertices(TriId(t)).map(|v| tin.point(v));
                    let z = planar(a, b, c, [p[0], p[1]]);
                    if (p[2] - z).abs() <= offset {
                        *label = Label::Ground;
                    } else if p[2] < z - low_noise {
                        *label = Label::LowNoise;
                    }
                }
            });
    }

    /// The triangles of the final TIN that hold the deferred candidates (a walk from the
    /// triangle of each one's cell's lowest point, or of the point before it), on every core.
    fn locate_deferred(&self, deferred: &[(u32, u32)]) -> Result<Vec<u32>> {
        let mut found = Vec::new();
        let at = |&(i, lowest): &(u32, u32), prev: u32| {
            let near = self.tri[lowest as usize];
            let live = near != NONE && self.tin.is_live(TriId(near));
            (i, if live { near } else { prev })
        };
        self.locate_all(deferred, at, &mut found);
        match deferred.iter().zip(&found).find(|(_, t)| **t == NONE) {
            Some((&(i, _), _)) => Err(self.outside(i)),
            None => Ok(found),
        }
    }

    /// Step 5 for the candidates that did not densify: each judged once against the final TIN
    /// as the densification would ([`Self::judge_once`]), on every core.
    pub(super) fn finish_deferred(&mut self, low_noise: f64, offset: f64) -> Result<()> {
        let deferred = std::mem::take(&mut self.deferred);
        let found = self.locate_deferred(&deferred)?;
        let this = &*self;
        let judged: Vec<(u32, Label)> = deferred
            .par_iter()
            .zip(&found)
            .map_init(Verdicts::default, |v, (&(i, _), &t)| {
                (i, this.judge_once(i, t, low_noise, offset, v))
            })
            .collect();
        for (i, l) in judged {
            if l != Label::Other {
                self.labels[i as usize] = l;
            }
        }
        Ok(())
    }

    /// The label of candidate `i`, in triangle `t` of the final TIN, judged once: ground when
    /// the densification would accept it (its distance and angles, or its mirror point's, or
    /// at a real vertex close enough to it) or when within `offset` (vertically) of the TIN;
    /// low noise more than `low_noise` below it.
    fn judge_once(&self, i: u32, t: u32, low_noise: f64, offset: f64, v: &mut Verdicts) -> Label {
        let vs = self.tin.tri_vertices(TriId(t));
        let corners = self.corners(vs);
        let plane = Plane::new(corners);
        v.effects.clear();
        let accepted = match self.distance(i, vs, &corners, &plane, v) {
            Some(d) => self.accepts(i, t, vs, &corners, d, v),
            None => v.effects.iter().any(|e| matches!(e, Effect::Ground(_))),
        };
        if accepted {
            return Label::Ground;
        }
        let p = self.tin.point(self.vid(i));
        let z = planar(corners[0], corners[1], corners[2], [p[0], p[1]]);
        if (p[2] - z).abs() <= offset {
            Label::Ground
        } else if p[2] < z - low_noise {
            Label::LowNoise
        } else {
            Label::Other
        }
    }
}
