//! Memory for runs in flight, shared by workers: a run takes its bytes before it starts and
//! gives them back when it ends (the tiles' triangulation runs, the ground filter's block runs).

use std::sync::{Condvar, Mutex};

/// The memory of runs in flight. A tile's run takes [`Budget::run`] bytes when it starts,
/// gives back all but what its output holds ([`super::worker::TileOutput::heap_bytes`],
/// counted as a run's at most) when it ends, and the rest when the writer has written it.
/// Tiles are written in order, so a slow tile (or a slow writer: an overlay's) holds the
/// outputs after it, not the runs: the workers go on while there is room for a run. A ground
/// block's run takes what its points need.
pub(crate) struct Budget {
    free: Mutex<(u64, bool)>,
    freed: Condvar,
    /// Bytes a run holds at its peak (an estimate; the largest run for runs of varied size).
    pub(crate) run: u64,
    /// Runs the budget holds at once (at most the workers): the tiles' summary's `window`.
    pub(crate) runs: usize,
}

impl Budget {
    /// `free` bytes for runs of `run` bytes on `threads` workers: room for at least one run,
    /// whatever `free`.
    pub(crate) fn new(free: u64, run: u64, threads: usize) -> Budget {
        let run = run.max(1);
        let free = free.max(run);
        Budget {
            free: Mutex::new((free, false)),
            freed: Condvar::new(),
            run,
            runs: ((free / run) as usize).clamp(1, threads.max(1)),
        }
    }

    /// Waits until `bytes` are free and takes them; `false` once the budget is closed.
    pub(crate) fn take(&self, bytes: u64) -> bool {
        let Ok(mut g) = self.free.lock() else {
            return false;
        };
        loop {
            if g.1 {
                return false;
            }
            if g.0 >= bytes {
                g.0 -= bytes;
                return true;
            }
            g = match self.freed.wait(g) {
                Ok(g) => g,
                Err(_) => return false,
            };
        }
    }

    /// Gives back `bytes`.
    pub(crate) fn give(&self, bytes: u64) {
        if let Ok(mut g) = self.free.lock() {
            g.0 += bytes;
        }
        self.freed.notify_all();
    }

    /// Wakes every waiting worker with `false`.
    pub(crate) fn close(&self) {
        if let Ok(mut g) = self.free.lock() {
            g.1 = true;
        }
        self.freed.notify_all();
    }
}
