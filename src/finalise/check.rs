//! The finality check of one triangle: its circumdisk against the advancing front (the rule is
//! in the module above, "When is a triangle final?"), and the triangle re-scheduled when the
//! front does not cover it yet.

use super::{FIRST_CHECK, PATIENT_CHECKS, PARKED, SHORT_SCAN, StreamingSweep};
use crate::geom::predicates::{self, is_artificial};
use crate::mesh::{TriId, VertexId};

impl StreamingSweep {
    /// Finalises triangle slot `t` if its circumdisk is under the front; otherwise re-schedules it.
    pub(super) fn check_final(&mut self, t: u32, y: f64, ks: u64) {
        let [a, b, c] = self.sweep.mesh().tri_vertices(TriId(t));
        if is_artificial(a.0) || is_artificial(b.0) || is_artificial(c.0) {
            self.fin().schedule(t, ks + PARKED);
            return;
        }
        let p = self.sweep.points();
        let Some(d) =
            predicates::circumdisk_bounds(p[a.0 as usize], p[b.0 as usize], p[c.0 as usize])
        else {
            let fin = self.fin();
            fin.stats.rechecks += 1;
            fin.schedule(t, ks + PARKED);
            return;
        };
        if d.top >= y {
            let fin = self.fin();
            fin.stats.rechecks += 1;
            let k = fin.bucket(d.top);
            fin.schedule(t, k.max(ks));
            return;
        }
        let low = self.front_low(&d, [a, b, c]);
        let fin = self.fin();
        if d.top < low && fin.pending.near(d.center, d.radius) {
            // A breakline still to come may cross it.
            fin.stats.rechecks += 1;
            fin.schedule(t, ks + FIRST_CHECK);
        } else if d.top < low {
            self.finalize(t);
        } else {
            fin.stats.rechecks += 1;
            // The front under the disk must rise by (top - low) at least (`low` is the first
            // front height found at or below the top, not always the lowest): wait about that long, or longer
            // once it has not risen several times (a part of the front that never rises: the
            // upper side of a diagonal strip, whose hull triangles would otherwise be checked
            // every few buckets until the end).
            let b = &mut fin.blocked[t as usize];
            *b = b.saturating_add(1);
            let patience = match *b {
                n if n > PATIENT_CHECKS => 1u64 << (n - PATIENT_CHECKS).min(48),
                _ => 1,
            };
            let k = fin.bucket(y + (d.top - low));
            fin.schedule(t, k.max(ks.saturating_add(patience)));
        }
    }

    /// The front's lowest height under the disk `d` of the triangle `abc`, or the first height
    /// found at or below the disk's top ([`crate::sweep::front::Front::min_y_within`]). When that
    /// takes more than [`SHORT_SCAN`] front nodes, a vertex of the triangle on the front settles
    /// it at once (it lies on the circle, so at or below the top, and inside the span): points on
    /// a ring or a wide flat arc made every check of their slivers scan the whole arc. Else the
    /// whole span is scanned through the front's bucket minima (`Front::min_y_indexed`).
    fn front_low(&mut self, d: &predicates::DiskBounds, tri: [VertexId; 3]) -> f64 {
        let front = self.sweep.front();
        let mut steps = SHORT_SCAN;
        let low = front
            .min_y_within(d.x_min, d.x_max, d.top, &mut steps)
            .or_else(|| {
                let p = self.sweep.points();
                tri.iter()
                    .map(|v| p[v.0 as usize])
                    .zip(tri)
                    .filter(|&(xy, v)| xy[1] <= d.top && front.holds(v, xy[0]))
                    .map(|(xy, _)| xy[1])
                    .reduce(f64::min)
            });
        let mut scanned = (SHORT_SCAN - steps) as u64;
        let low = low.unwrap_or_else(|| {
            let f = self.sweep.front_mut();
            f.min_y_indexed(d.x_min, d.x_max, d.top, &mut scanned)
        });
        self.fin().stats.front_scans += scanned;
        low
    }
}
