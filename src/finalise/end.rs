//! The end of the sweep: the hull closed, every triangle still held emitted in slot order, the
//! vertices released, in batches so that a sweep that held everything (points on a line or a
//! circle) never has all its events in memory at once.

use super::{Event, NOT_OUT, StreamingSweep, tables};
use crate::geom::predicates::{FIRST_REAL, is_artificial};
use crate::mesh::TriId;

impl StreamingSweep {
    /// Ends the sweep: closes the hull and emits everything still in memory, in a fixed order
    /// (triangle slot order, then vertex slot order for the releases). The events wait in
    /// [`StreamingSweep::take_events`]; the statistics stay readable.
    #[cfg(any(test, feature = "dev"))]
    pub fn finish(&mut self) {
        self.finish_in_batches(usize::MAX, |_| true);
    }

    /// As [`StreamingSweep::finish`], handing the events to `drain` whenever `batch` of them
    /// wait (and not at the end: take those with [`StreamingSweep::take_events`]), so that the
    /// triangles held to the end (points on a line: all of them) are not all events in memory
    /// at once. Stops early, returning `false`, when `drain` does (its consumer is gone).
    pub fn finish_in_batches(
        &mut self,
        batch: usize,
        mut drain: impl FnMut(&mut Vec<Event>) -> bool,
    ) -> bool {
        let _ = self.look_at_tables();
        self.fin().ending = true;
        self.sweep.close_hull();
        let slots = self.sweep.mesh().triangle_count() as u32;
        for t in 0..slots {
            let mesh = self.sweep.mesh();
            if mesh.is_live(TriId(t))
                && !mesh
                    .tri_vertices(TriId(t))
                    .iter()
                    .any(|v| is_artificial(v.0))
            {
                self.finalize(t);
                if self.pending_events() >= batch && !drain(&mut self.fin().events) {
                    return false;
                }
            }
            // This pass touches every held triangle: keep dropping the spilled pages.
            if self.fin().spill.touched(tables::PAGES_AN_EMISSION) {
                self.sweep.release_spilled();
            }
        }
        let count = self.fin().vertices.out.len();
        for v in FIRST_REAL as usize..count {
            let fin = self.fin();
            let vt = &fin.vertices;
            if vt.out[v] != NOT_OUT && vt.refs[v] > 0 {
                fin.events.push(Event::VertexDone(vt.out[v]));
                if fin.events.len() >= batch && !drain(&mut fin.events) {
                    return false;
                }
            }
            // Millions of vertices held (a line): their rows would all come back into memory.
            if v % tables::CHECK_EVERY as usize == 0 {
                let _ = self.look_at_tables();
            }
        }
        true
    }
}
