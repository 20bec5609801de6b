//! Leave-one-out accuracy of a TIN (Herva 2009, section 7.3.4): remove a point, interpolate its
//! height from the TIN without it, put it back; the differences estimate how well the TIN
//! predicts the terrain between its points.

use super::{Tin, VertexId};
use crate::error::Result;
use crate::geom::rng::SplitMix64;

/// What [`Tin::leave_one_out`] measured.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CrossValidation {
    /// Points tested (removed, interpolated, restored).
    pub tested: u64,
    /// Sampled points that could not be tested: hull points (no TIN around them once removed)
    /// and breakline ends.
    pub skipped: u64,
    /// Mean absolute difference between a point's height and the interpolated one.
    pub mean_error: f64,
    /// Root-mean-square difference.
    pub rms_error: f64,
    /// Largest absolute difference.
    pub max_error: f64,
    /// Mean signed difference (interpolated − true): a bias of the surface.
    pub bias: f64,
}

impl Tin {
    /// Leave-one-out test of `samples` distinct points drawn at random (a deterministic draw from
    /// `seed`): each is removed, its height interpolated from the rest, and put back, so the TIN
    /// is the same afterwards.
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] / [`crate::Error::Internal`] only if a removed point cannot be
    /// restored (a bug).
    pub fn leave_one_out(&mut self, samples: usize, seed: u64) -> Result<CrossValidation> {
        let mut ids: Vec<VertexId> = self.vertices().collect();
        let mut rng = SplitMix64::new(seed);
        let n = samples.min(ids.len());
        for i in 0..n {
            let j = i + (rng.next_u64() % (ids.len() - i) as u64) as usize;
            ids.swap(i, j);
        }
        let mut out = CrossValidation::default();
        let (mut sum, mut sum2, mut signed) = (0.0, 0.0, 0.0);
        for &v in &ids[..n] {
            let Some(neighbour) = self.out_edge(v).map(|e| self.dst(e)) else {
                continue;
            };
            if self.remove(v).is_err() {
                out.skipped += 1;
                continue;
            }
            if let Some(e) = self.out_edge(neighbour) {
                self.set_hint(e.tri());
            }
            let estimate = self.interpolate(self.xy(v));
            self.restore(v)?;
            let Some(z) = estimate else {
                out.skipped += 1;
                continue;
            };
            let d = z - self.z(v);
            out.tested += 1;
            sum += d.abs();
            sum2 += d * d;
            signed += d;
            out.max_error = out.max_error.max(d.abs());
        }
        if out.tested > 0 {
            let t = out.tested as f64;
            out.mean_error = sum / t;
            out.rms_error = (sum2 / t).sqrt();
            out.bias = signed / t;
        }
        Ok(out)
    }
}
