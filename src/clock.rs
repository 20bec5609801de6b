//! CPU time of this thread and of the whole process (Linux `clock_gettime`; 0 elsewhere), for
//! the tiled engine's per-stage CPU report ([`crate::tiles::TileCpu`]). One system call each
//! (reading `/proc/thread-self/schedstat` took four, 4,000 times a run): call them per tile or
//! per phase, never per point.

/// CPU time of the calling thread, in seconds.
pub(crate) fn thread_cpu() -> f64 {
    #[cfg(target_os = "linux")]
    {
        seconds(rustix::time::clock_gettime(
            rustix::time::ClockId::ThreadCPUTime,
        ))
    }
    #[cfg(not(target_os = "linux"))]
    {
        0.0
    }
}

/// User and system CPU time of the whole process (all its threads), in seconds.
pub(crate) fn process_cpu() -> f64 {
    #[cfg(target_os = "linux")]
    {
        seconds(rustix::time::clock_gettime(
            rustix::time::ClockId::ProcessCPUTime,
        ))
    }
    #[cfg(not(target_os = "linux"))]
    {
        0.0
    }
}

#[cfg(target_os = "linux")]
fn seconds(t: rustix::time::Timespec) -> f64 {
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// Runs `f`, adding the CPU time this thread spent in it to `total`.
pub(crate) fn timed<T>(total: &mut f64, f: impl FnOnce() -> T) -> T {
    let t = thread_cpu();
    let r = f();
    *total += thread_cpu() - t;
    r
}

/// CPU time several threads spend on one stage, added up (the reader's decoding jobs on
/// rayon's threads): shared by clones.
#[derive(Clone, Debug, Default)]
pub(crate) struct Tally(std::sync::Arc<std::sync::atomic::AtomicU64>);

impl Tally {
    /// Runs `f`, adding the CPU time this thread spent in it.
    pub(crate) fn timed<T>(&self, f: impl FnOnce() -> T) -> T {
        let mut spent = 0.0;
        let r = timed(&mut spent, f);
        let ns = (spent * 1e9) as u64;
        self.0.fetch_add(ns, std::sync::atomic::Ordering::Relaxed);
        r
    }

    /// The CPU seconds added so far.
    pub(crate) fn seconds(&self) -> f64 {
        self.0.load(std::sync::atomic::Ordering::Relaxed) as f64 * 1e-9
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn clocks_move_with_work() {
        let (t, p) = (super::thread_cpu(), super::process_cpu());
        let mut x = 0u64;
        let mut spent = 0.0;
        super::timed(&mut spent, || {
            for i in 0..50_000_000u64 {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
            }
        });
        std::hint::black_box(x);
        if cfg!(target_os = "linux") {
            assert!(super::thread_cpu() > t && spent > 0.0);
            assert!(super::process_cpu() >= p);
        }
    }
}
