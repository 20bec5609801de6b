//! CPU time of this thread and of the whole process (Linux `/proc`; 0 elsewhere), for the
//! tiled engine's per-stage CPU report ([`crate::tiles::TileCpu`]). Reading them costs a few
//! microseconds: call them per tile or per phase, never per point.

/// CPU time of the calling thread, in seconds (`/proc/thread-self/schedstat`, nanoseconds).
pub(crate) fn thread_cpu() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(0.0, |ns| ns as f64 * 1e-9)
}

/// User and system CPU time of the whole process, in seconds (`/proc/self/stat`, clock ticks of
/// 1/100 s, the value on every Linux this runs on).
pub(crate) fn process_cpu() -> f64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // The command name (field 2) may hold spaces: count fields after its closing parenthesis.
    let Some(rest) = s.rfind(')').map(|i| &s[i + 1..]) else {
        return 0.0;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after the name.
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    (tick(11) + tick(12)) as f64 / 100.0
}

/// Runs `f`, adding the CPU time this thread spent in it to `total`.
pub(crate) fn timed<T>(total: &mut f64, f: impl FnOnce() -> T) -> T {
    let t = thread_cpu();
    let r = f();
    *total += thread_cpu() - t;
    r
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
