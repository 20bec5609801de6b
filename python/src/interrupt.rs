//! Ctrl-C during a long run: the library works on another thread while the calling thread
//! checks Python's signals every 100 ms; on a signal the run is told to stop (a sink that
//! fails with `Error::Interrupted` at its next triangle), its outputs are dropped unfinished
//! (atomic: nothing is left under their names), and the signal's exception (KeyboardInterrupt)
//! is raised once the run has stopped.

use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use sweeptin::sink::{MeshSink, MeshSummary, ProductSummary, StreamInfo, TriangleSink};

/// Has the caller been interrupted?
#[derive(Default)]
pub(crate) struct Cancel(AtomicBool);

impl Cancel {
    fn check(&self) -> sweeptin::Result<()> {
        if self.0.load(Ordering::Relaxed) {
            Err(sweeptin::Error::Interrupted)
        } else {
            Ok(())
        }
    }
}

/// Runs `work` on a scoped thread, checking Python's signals meanwhile (see the module docs).
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    work: impl FnOnce() -> sweeptin::Result<T> + Send,
) -> PyResult<T> {
    std::thread::scope(|s| {
        let handle = s.spawn(work);
        loop {
            let done = py.detach(|| {
                for _ in 0..10 {
                    if handle.is_finished() {
                        return true;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                handle.is_finished()
            });
            if done {
                break;
            }
            if let Err(signal) = py.check_signals() {
                cancel.0.store(true, Ordering::Relaxed);
                let _ = py.detach(|| handle.join());
                return Err(signal);
            }
        }
        match handle.join() {
            Ok(r) => r.map_err(crate::to_py),
            Err(_) => Err(crate::to_py(sweeptin::Error::Internal(
                "the run's thread panicked".into(),
            ))),
        }
    })
}

/// A triangle sink that stops the run once cancelled (added to a run's products).
pub(crate) struct CancelSink<'a>(pub(crate) &'a Cancel);

impl TriangleSink for CancelSink<'_> {
    fn begin(&mut self, _info: &StreamInfo) -> sweeptin::Result<()> {
        self.0.check()
    }

    fn triangle(&mut self, _t: &[[f64; 3]; 3]) -> sweeptin::Result<()> {
        self.0.check()
    }

    fn finish(&mut self) -> sweeptin::Result<ProductSummary> {
        Ok(ProductSummary::None)
    }
}

/// A mesh writer that stops the run once cancelled (a mesh-only run has no triangle sink, and
/// adding one would change its sweep axis).
pub(crate) struct CancelMesh<'a> {
    pub(crate) inner: &'a mut (dyn MeshSink + Send),
    pub(crate) cancel: &'a Cancel,
}

impl MeshSink for CancelMesh<'_> {
    fn declare(&mut self, kind: sweeptin::validate::MeshKind) -> sweeptin::Result<()> {
        self.inner.declare(kind)
    }

    fn vertex(&mut self, p: [f64; 3]) -> sweeptin::Result<()> {
        self.inner.vertex(p)
    }

    fn triangle(&mut self, t: [u64; 3]) -> sweeptin::Result<()> {
        self.cancel.check()?;
        self.inner.triangle(t)
    }

    fn vertex_done(&mut self, id: u64) -> sweeptin::Result<()> {
        self.inner.vertex_done(id)
    }

    fn watermark(&mut self, y: f64) -> sweeptin::Result<()> {
        self.inner.watermark(y)
    }

    fn keeps_watermarks(&self) -> bool {
        self.inner.keeps_watermarks()
    }

    fn finish(&mut self) -> sweeptin::Result<MeshSummary> {
        self.inner.finish()
    }
}
