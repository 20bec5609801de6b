//! The process's limits, as the operating system states them (Linux `getrlimit`; elsewhere the
//! usual values): the external sort sizes its open runs by the open-file limit, and the tiled
//! engine refuses an address space smaller than `--mem` before any work.

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
