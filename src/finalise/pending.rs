//! Breakline segments whose earlier end is swept and later end is not: a triangle near one of
//! them may still be cut by it, so it is not final yet.

/// Pending breakline segments, indexed by x, to keep triangles they may still cross in memory.
#[derive(Debug, Clone, Default)]
pub(super) struct PendingSegments {
    segs: Vec<Option<PendingSeg>>,
    /// Generation of each slot, bumped when its segment is removed: bucket entries of an earlier
    /// generation are stale (slots are reused) and pruned when met.
    gen_of: Vec<u32>,
    free: Vec<u32>,
    by_ends: std::collections::HashMap<(u32, u32), u32>,
    /// Slot and generation of the segments over each x range.
    buckets: Vec<Vec<(u32, u32)>>,
    x0: f64,
    inv_w: f64,
    live: usize,
    /// Most segments pending at once.
    pub(super) peak: usize,
}

#[derive(Debug, Clone, Copy)]
struct PendingSeg {
    a: [f64; 2],
    b: [f64; 2],
}

impl PendingSegments {
    pub(super) fn new(x_range: (f64, f64)) -> Self {
        let n = 1024;
        let w = x_range.1 - x_range.0;
        PendingSegments {
            buckets: vec![Vec::new(); n],
            x0: x_range.0,
            inv_w: if w > 0.0 && w.is_finite() {
                n as f64 / w
            } else {
                0.0
            },
            ..Default::default()
        }
    }

    #[inline]
    fn bucket(&self, x: f64) -> usize {
        (((x - self.x0) * self.inv_w) as usize).min(self.buckets.len() - 1)
    }

    /// Adds the pending segment between constraint vertices `lo` and `hi`.
    pub(super) fn add(&mut self, lo: u32, hi: u32, a: [f64; 2], b: [f64; 2]) {
        let id = match self.free.pop() {
            Some(id) => {
                self.segs[id as usize] = Some(PendingSeg { a, b });
                id
            }
            None => {
                self.segs.push(Some(PendingSeg { a, b }));
                self.gen_of.push(0);
                (self.segs.len() - 1) as u32
            }
        };
        self.by_ends.insert((lo, hi), id);
        let g = self.gen_of[id as usize];
        let (k0, k1) = (self.bucket(a[0].min(b[0])), self.bucket(a[0].max(b[0])));
        for k in k0..=k1 {
            self.buckets[k].push((id, g));
        }
        self.live += 1;
        self.peak = self.peak.max(self.live);
    }

    /// Removes the segment between `lo` and `hi` (inserted now).
    pub(super) fn remove(&mut self, lo: u32, hi: u32) {
        if let Some(id) = self.by_ends.remove(&(lo, hi)) {
            self.segs[id as usize] = None;
            self.gen_of[id as usize] = self.gen_of[id as usize].wrapping_add(1);
            self.free.push(id);
            self.live -= 1;
        }
    }

    /// Could a pending segment pass within `r` of `c` (conservatively: floating-point error only
    /// makes this say yes more often)? Prunes dead entries from the buckets it scans.
    pub(super) fn near(&mut self, c: [f64; 2], r: f64) -> bool {
        if self.live == 0 {
            return false;
        }
        let (k0, k1) = (self.bucket(c[0] - r), self.bucket(c[0] + r));
        for k in k0..=k1 {
            let mut i = 0;
            while i < self.buckets[k].len() {
                let (id, g) = self.buckets[k][i];
                match self.segs[id as usize] {
                    Some(s) if self.gen_of[id as usize] == g => {
                        if segment_within(s.a, s.b, c, r) {
                            return true;
                        }
                    }
                    _ => {
                        self.buckets[k].swap_remove(i);
                        continue;
                    }
                }
                i += 1;
            }
        }
        false
    }
}

/// Is segment `a`–`b` within distance `r` of `c`? Floating point with a relative margin of 1e-9
/// of the magnitudes involved, so a true "yes" is never missed.
fn segment_within(a: [f64; 2], b: [f64; 2], c: [f64; 2], r: f64) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (px, py) = (c[0] - a[0], c[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        ((px * dx + py * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (px - t * dx, py - t * dy);
    let d = (qx * qx + qy * qy).sqrt();
    let scale = dx.abs() + dy.abs() + px.abs() + py.abs() + r;
    d <= r + 1e-9 * scale
}

/// Streamed breaklines (the graph vertex by vertex with the points, see
/// [`crate::sweep::ConstraintVertex`]) instead of a whole [`crate::sweep::ConstraintGraph`].
impl super::StreamingSweep {
    /// Sets streamed breaklines; `first` is the first point's constraint vertex (given to
    /// [`super::StreamingSweep::new`]) and its record, if it is one. Call it before the second
    /// point.
    ///
    /// # Errors
    /// [`crate::error::Error::Internal`] if the first record has earlier ends.
    pub fn set_fed_constraints(
        &mut self,
        first: Option<(u32, crate::sweep::ConstraintVertex)>,
    ) -> crate::error::Result<()> {
        self.sweep.set_fed_constraints(first)
    }

    /// [`super::StreamingSweep::push`] with the record of the constraint vertex `p` is (when
    /// `p.constraint` names one; streamed breaklines).
    ///
    /// # Errors
    /// As [`super::StreamingSweep::push`]; [`crate::error::Error::Internal`] when the record
    /// does not match the point or the vertices before it (a bug).
    pub fn push_fed(
        &mut self,
        p: super::StreamPoint,
        rec: Option<crate::sweep::ConstraintVertex>,
    ) -> crate::error::Result<()> {
        if let Some(r) = rec {
            self.sweep.next_constraint_vertex(r);
        }
        self.push(p)
    }
}
