//! Interruptions: Ctrl-C (SIGINT), SIGTERM and SIGHUP abort the multipart uploads to S3 in
//! progress ([`crate::input::source::abort_uploads`]), delete every registered temporary path
//! ([`super::atomic::register_temp`]), pass the signal on to the child processes started with
//! [`spawn_child`] (a plan's `run --all` runs each task in one) and wait for them, then exit with
//! 128 + the signal's number.

use super::atomic::cleanup_registered_temps;
use crate::error::{Error, Result};
use std::io;
use std::process::{Child, Command, ExitStatus};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use std::time::Duration;

/// How long an interrupted process waits for its children to stop (each removes its own
/// temporary files) before it kills what is left and exits.
const CHILDREN_GRACE: Duration = Duration::from_secs(30);

/// Set inside the signal handler itself, the moment a signal comes (before the handler's
/// thread runs): no child starts after it.
static SIGNALLED: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// The children an interruption passes its signal on to.
static CHILDREN: Mutex<Vec<u32>> = Mutex::new(Vec::new());

fn children() -> MutexGuard<'static, Vec<u32>> {
    CHILDREN.lock().unwrap_or_else(|e| e.into_inner())
}

/// Has this process been interrupted (a signal of [`install_interrupt_handler`] came)?
pub fn interrupted() -> bool {
    SIGNALLED.get().is_some_and(|f| f.load(Ordering::SeqCst))
}

/// Starts `command` as a child process that an interruption of this one passes its signal on
/// to and waits for (up to 30 s, then kills it); wait for it with [`wait_child`]. `None` once
/// this process is interrupted: no child starts then. (Signals are passed on under Linux.)
///
/// # Errors
/// The operating system's, when the child cannot start.
pub fn spawn_child(command: &mut Command) -> io::Result<Option<Child>> {
    let mut c = children();
    if interrupted() {
        return Ok(None);
    }
    let child = command.spawn()?;
    c.push(child.id());
    Ok(Some(child))
}

/// Waits for a child of [`spawn_child`] to end, and forgets it. Under Linux the child is
/// waited for without being reaped, then forgotten and reaped under the lock the handler holds
/// while it signals: its pid cannot be reused by another process while it is still listed.
///
/// # Errors
/// The operating system's, when it cannot be waited for.
pub fn wait_child(mut child: Child) -> io::Result<ExitStatus> {
    #[cfg(target_os = "linux")]
    {
        use rustix::io::Errno;
        use rustix::process::{Pid, WaitId, WaitIdOptions, waitid};
        let pid = Pid::from_child(&child);
        let ended = WaitIdOptions::EXITED | WaitIdOptions::NOWAIT;
        // Until it has ended (or cannot be waited for this way: then `wait` below says why),
        // without reaping it; then forgotten and reaped under the lock.
        while let Err(Errno::INTR) = waitid(WaitId::Pid(pid), ended) {}
        let mut c = children();
        c.retain(|&p| p != child.id());
        child.wait()
    }
    // Elsewhere no signal is passed on: wait without the lock (other tasks start meanwhile).
    #[cfg(not(target_os = "linux"))]
    {
        let status = child.wait();
        children().retain(|&p| p != child.id());
        status
    }
}

/// When this process has been interrupted, waits for the handler to end it (with the
/// signal's exit status, after its children): the caller's work, cut short, must not end it
/// first with an error of its own. Past the handler's grace period (it may have failed), the
/// process ends here with the interruption's status. Returns at once otherwise.
pub fn await_interruption() {
    if interrupted() {
        std::thread::sleep(CHILDREN_GRACE + Duration::from_secs(5));
        std::process::exit(super::atomic::INTERRUPTED_EXIT_CODE);
    }
}

/// Passes `signal` on to the children and waits until they have ended; after the grace period,
/// kills those left (their temporary files are removed as stale by a later run).
#[cfg(target_os = "linux")]
fn stop_children(signal: i32) {
    use rustix::process::{Pid, Signal, kill_process};
    let send = |sig: Option<Signal>| {
        for &p in children().iter() {
            if let (Some(pid), Some(sig)) = (Pid::from_raw(p as i32), sig) {
                let _ = kill_process(pid, sig);
            }
        }
    };
    send(Signal::from_named_raw(signal));
    let deadline = std::time::Instant::now() + CHILDREN_GRACE;
    while !children().is_empty() && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(10));
    }
    send(Some(Signal::KILL));
}

/// Children are not signalled here (no `kill` binding off Linux); they see a terminal's Ctrl-C
/// themselves.
#[cfg(not(target_os = "linux"))]
fn stop_children(_signal: i32) {}

static HANDLER_INSTALLED: AtomicBool = AtomicBool::new(false);

/// Installs the process-wide Ctrl-C / SIGTERM / SIGHUP handler: a thread that waits for one of
/// them, passes it on to the children of [`spawn_child`] and waits for them, deletes every
/// registered temporary path, prints one line on stderr and exits with
/// 128 + the signal's number (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP). Calling it again
/// is harmless.
///
/// # Errors
/// [`Error::Internal`] if the operating system refuses the handler.
pub fn install_interrupt_handler() -> Result<()> {
    if HANDLER_INSTALLED.swap(true, Ordering::SeqCst) {
        return Ok(());
    }
    let failed = |e: io::Error| {
        HANDLER_INSTALLED.store(false, Ordering::SeqCst);
        Error::Internal(format!("cannot install the interrupt handler: {e}"))
    };
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        use std::io::Write;
        let flag = SIGNALLED.get_or_init(|| Arc::new(AtomicBool::new(false)));
        for sig in [SIGINT, SIGTERM, SIGHUP] {
            signal_hook::flag::register(sig, flag.clone()).map_err(failed)?;
        }
        let mut signals =
            signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]).map_err(failed)?;
        std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                if let Some(signal) = signals.forever().next() {
                    stop_children(signal);
                    // Before the temporary files: an upload's parts are read from one.
                    let aborted = crate::input::source::abort_uploads();
                    let removed = cleanup_registered_temps();
                    let name = match signal {
                        SIGINT => "SIGINT",
                        SIGTERM => "SIGTERM",
                        _ => "SIGHUP",
                    };
                    // Never a panic here (a closed terminal after SIGHUP): the exit must come.
                    let uploads = match aborted {
                        0 => String::new(),
                        n => format!(", aborted {n} upload(s) to S3"),
                    };
                    let _ = writeln!(
                        io::stderr(),
                        "sweeptin: interrupted by {name}; removed {removed} temporary \
                         file(s){uploads}"
                    );
                    std::process::exit(128 + signal);
                }
            })
            .map_err(failed)?;
    }
    #[cfg(not(unix))]
    let _ = (failed, cleanup_registered_temps, stop_children);
    Ok(())
}
