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

/// Address space the process maps beyond the data `--mem` budgets: the binary and its libraries,
/// thread stacks, the allocator's second arena (glibc reserves 64 MiB for it) and the mapped
/// windows of spilled runs. The ARSO tile peaked at 142–181 MB of address space at `--mem` 64M
/// to 1G (VmPeak, two arenas: [`crate::tune_allocator`] keeps to two under a limit).
pub(crate) const ADDRESS_OVERHEAD: u64 = 128 << 20;

/// Fails before any work when the process's address space (`ulimit -v`, a batch job's
/// `h_vmem`) is limited below `mem` plus [`ADDRESS_OVERHEAD`]: rather than aborting later when an
/// allocation fails. `what` names the work.
pub(crate) fn check_address_space(mem: u64, what: &str) -> crate::Result<()> {
    match address_space() {
        Some(limit) if limit < mem.saturating_add(ADDRESS_OVERHEAD) => {
            Err(crate::Error::OutOfMemory {
                what: what.to_string(),
                bytes: mem,
                hint: format!(
                    "the process may use {} of address space (ulimit -v or a batch job's \
                     limit), and needs --mem plus about {} (its code, threads' stacks, \
                     allocator): {}",
                    crate::human_bytes(limit),
                    crate::human_bytes(ADDRESS_OVERHEAD),
                    match limit.checked_sub(ADDRESS_OVERHEAD + (16 << 20)) {
                        Some(_) => format!(
                            "give --mem {}M or less, or raise the limit",
                            (limit - ADDRESS_OVERHEAD) >> 20
                        ),
                        None => "raise the limit".to_string(),
                    },
                ),
            })
        }
        _ => Ok(()),
    }
}
