//! Interruptions: Ctrl-C (SIGINT), SIGTERM and SIGHUP delete every registered temporary path
//! ([`super::atomic::register_temp`]), pass the signal on to the child processes started with
//! [`spawn_child`] (a plan's `run --all` runs each task in one) and wait for them, then exit with
//! 128 + the signal's number.

use super::atomic::cleanup_registered_temps;
use crate::error::{Error, Result};
use std::io;
use std::process::{Child, Command, ExitStatus};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How long an interrupted process waits for its children to stop (each removes its own
/// temporary files) before it exits anyway.
const CHILDREN_GRACE: Duration = Duration::from_secs(30);

/// The children an interruption passes its signal on to, and whether it has come (then no
/// child starts).
struct Children {
    interrupted: bool,
    pids: Vec<u32>,
}

static CHILDREN: Mutex<Children> = Mutex::new(Children {
    interrupted: false,
    pids: Vec::new(),
});

fn children() -> MutexGuard<'static, Children> {
    CHILDREN.lock().unwrap_or_else(|e| e.into_inner())
}

/// Starts `command` as a child process that an interruption of this one passes its signal on
/// to and waits for (up to 30 s); wait for it with [`wait_child`]. `None` once this process is
/// interrupted: no child starts then.
///
/// # Errors
/// The operating system's, when the child cannot start.
pub fn spawn_child(command: &mut Command) -> io::Result<Option<Child>> {
    let mut c = children();
    if c.interrupted {
        return Ok(None);
    }
    let child = command.spawn()?;
    c.pids.push(child.id());
    Ok(Some(child))
}

/// Waits for a child of [`spawn_child`] to end, and forgets it.
///
/// # Errors
/// The operating system's, when it cannot be waited for.
pub fn wait_child(mut child: Child) -> io::Result<ExitStatus> {
    let status = child.wait();
    children().pids.retain(|&p| p != child.id());
    status
}

/// Has this process been interrupted (a signal of [`install_interrupt_handler`] came)?
pub fn interrupted() -> bool {
    children().interrupted
}

/// When this process has been interrupted, waits for the handler to end it (with the
/// signal's exit status, after its children): the caller's work, cut short, must not end it
/// first with an error of its own. Returns at once otherwise.
pub fn await_interruption() {
    if interrupted() {
        loop {
            std::thread::park();
        }
    }
}

/// Passes `signal` on to the children, and waits until they have ended (or the grace period).
#[cfg(unix)]
fn stop_children(signal: i32) {
    {
        let mut c = children();
        c.interrupted = true;
        let sig = rustix::process::Signal::from_named_raw(signal);
        for &p in &c.pids {
            if let (Some(pid), Some(sig)) = (rustix::process::Pid::from_raw(p as i32), sig) {
                let _ = rustix::process::kill_process(pid, sig);
            }
        }
    }
    let deadline = Instant::now() + CHILDREN_GRACE;
    while !children().pids.is_empty() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(10));
    }
}

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
        let mut signals =
            signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]).map_err(failed)?;
        std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                if let Some(signal) = signals.forever().next() {
                    stop_children(signal);
                    let removed = cleanup_registered_temps();
                    let name = match signal {
                        SIGINT => "SIGINT",
                        SIGTERM => "SIGTERM",
                        _ => "SIGHUP",
                    };
                    eprintln!(
                        "sweeptin: interrupted by {name}; removed {removed} temporary file(s)"
                    );
                    std::process::exit(128 + signal);
                }
            })
            .map_err(failed)?;
    }
    #[cfg(not(unix))]
    let _ = failed;
    Ok(())
}
