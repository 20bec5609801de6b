//! The process's limits, as the operating system states them (Linux `getrlimit`; elsewhere the
//! usual values): the external sort sizes its open runs by the open-file limit, and a run
//! refuses an address space smaller than `--mem` and what the program maps itself before any
//! work ([`check_address_space`]). Also what the process holds (`/proc/self/status`).

fn proc_status_kb(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Peak resident set size of this process, from `/proc/self/status` (Linux).
pub fn peak_rss() -> Option<u64> {
    proc_status_kb("VmHWM:")
}

/// Current shared resident memory of this process: mapped file pages and shared memory
/// (`/proc/self/statm`'s third field, RssFile + RssShmem; Linux). Read every few thousand
/// steps while a sweep's tables are spilled, so from the short `statm` rather than `status`.
pub(crate) fn file_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = s.split_whitespace().nth(2)?.parse().ok()?;
    Some(pages * rustix::param::page_size() as u64)
}

/// Current anonymous resident memory of this process (Linux).
pub fn anon_rss() -> Option<u64> {
    proc_status_kb("RssAnon:")
}

/// Most worker threads a job starts (`--threads`, and `--jobs` for a plan's tasks): more is a
/// typo, not a machine (`--threads 100000` spawned that many threads and kept a 2-core machine
/// busy for minutes).
pub const MAX_THREADS: usize = 1024;

/// Refuses a thread count above [`MAX_THREADS`] (0 means every core).
///
/// # Errors
/// [`crate::Error::Options`] naming the count and the machine's cores.
pub fn check_threads(threads: usize) -> crate::Result<()> {
    if threads > MAX_THREADS {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        return Err(crate::Error::Options(format!(
            "{threads} threads: at most {MAX_THREADS} (this machine has {cores} cores; 0 \
             means every core)"
        )));
    }
    Ok(())
}

/// Most threads the process-wide pool that decodes and sorts is given, beyond the cores: idle
/// workers of the pool look for work among all the others, which costs CPU that grows with the
/// square of their number (`--threads 1024` on 2 cores spent 1.8 s of CPU on a 10,000-point
/// file, against 0.03 s), and more decoding threads than cores gain nothing. Tile workers are
/// not capped (each waits for `--mem`).
const MAX_POOL_THREADS: usize = 64;

/// Sizes the process-wide pool that decodes and sorts for `--threads threads` (0: every core,
/// the pool's default): `threads`, but at most the larger of the cores and 64. Only the first
/// call in a process sizes it; later ones keep it.
pub fn size_thread_pool(threads: usize) {
    if threads > 0 {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.min(cores.max(MAX_POOL_THREADS)))
            .build_global();
    }
}

/// The soft limit on open files.
#[cfg(target_os = "linux")]
pub(crate) fn open_files() -> u64 {
    rustix::process::getrlimit(rustix::process::Resource::Nofile)
        .current
        .unwrap_or(u64::MAX)
}

/// The soft limit on open files (the usual 1,024 where it is not asked).
#[cfg(not(target_os = "linux"))]
pub(crate) fn open_files() -> u64 {
    1024
}

/// The soft limit on the address space (`ulimit -v`), if there is one.
#[cfg(target_os = "linux")]
pub(crate) fn address_space() -> Option<u64> {
    rustix::process::getrlimit(rustix::process::Resource::As).current
}

/// The soft limit on the address space (not asked here).
#[cfg(not(target_os = "linux"))]
pub(crate) fn address_space() -> Option<u64> {
    None
}

/// Address space the process maps beyond the data `--mem` budgets, with `threads` workers (0:
/// one per core): 96 MiB for the binary and its libraries, the allocator's second arena (glibc
/// reserves 64 MiB for it) and the mapped windows of spilled runs, and 4 MiB for each thread's
/// stack (about two per worker, the tile workers and rayon's, and four more). The ARSO tile
/// mapped 142–181 MB (VmPeak) at `--mem` 64M to 1G on two cores, with two arenas
/// ([`crate::tune_allocator`] keeps to two under a limit); this says 128 MiB there.
pub(crate) fn address_overhead(threads: usize) -> u64 {
    let n = match threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    } as u64;
    (96 << 20) + (4 << 20) * (2 * n + 4)
}

/// The budget an address-space limit leaves beside [`address_overhead`], in whole MiB and at
/// least 16 MiB, or `mem` when it is smaller or there is no limit.
pub(crate) fn fit_address_space(mem: u64, threads: usize) -> u64 {
    match address_space() {
        Some(limit) => {
            let left = limit.saturating_sub(address_overhead(threads)) >> 20 << 20;
            mem.min(left.max(16 << 20))
        }
        None => mem,
    }
}

/// Fails before any work when the process's address space (`ulimit -v`, a batch job's
/// `h_vmem`) is limited below `mem` plus [`address_overhead`] of `threads`: rather than
/// aborting later when an allocation fails. `what` names the work.
pub(crate) fn check_address_space(mem: u64, threads: usize, what: &str) -> crate::Result<()> {
    let overhead = address_overhead(threads);
    match address_space() {
        Some(limit) if limit < mem.saturating_add(overhead) => Err(crate::Error::OutOfMemory {
            what: what.to_string(),
            bytes: mem,
            hint: format!(
                "the process may use {} of address space (ulimit -v or a batch job's limit), \
                 and needs --mem plus about {} (its code, threads' stacks, allocator): {}",
                crate::human_bytes(limit),
                crate::human_bytes(overhead),
                match limit.checked_sub(overhead + (16 << 20)) {
                    Some(_) => format!(
                        "give --mem {}M or less, or raise the limit",
                        (limit - overhead) >> 20
                    ),
                    None => "raise the limit".to_string(),
                },
            ),
        }),
        _ => Ok(()),
    }
}

/// Fails when an address-space limit (`ulimit -v`, a batch job's `h_vmem`) leaves less than
/// `bytes` beside what the process maps now (`VmSize`): for in-memory steps whose size shows only
/// as they go (`refine`), before the allocation that would abort the process. `what` names the
/// memory, `hint` what to do. Without a limit (or `/proc`), `Ok`.
pub(crate) fn check_room(bytes: u64, what: &str, hint: &str) -> crate::Result<()> {
    let Some(limit) = address_space() else {
        return Ok(());
    };
    let mapped = proc_status_kb("VmSize:").unwrap_or(0);
    if mapped.saturating_add(bytes) <= limit {
        return Ok(());
    }
    Err(crate::Error::OutOfMemory {
        what: what.to_string(),
        bytes,
        hint: format!(
            "the process maps {} of the {} of address space it may use (ulimit -v or a batch \
             job's limit): {hint}",
            crate::human_bytes(mapped),
            crate::human_bytes(limit),
        ),
    })
}
