//! The interrupt clean-up: the process-wide registry (this file holds the only test touching it
//! directly, so nothing else in this process registers paths meanwhile), and the real handler in
//! the binary, interrupted by SIGINT / SIGTERM while it waits on its input.

use crate::data;

use std::io::Write;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};
use sweeptin::output::AtomicFile;
use sweeptin::output::atomic::{
    RegisteredTempDir, TempKind, cleanup_registered_temps, register_temp, registered_temps,
};

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn cleanup_removes_every_registered_path() {
    let dir = tempfile::tempdir().unwrap();
    let mut out = AtomicFile::create(dir.path().join("out.ply")).unwrap();
    out.write_all(b"partial").unwrap();
    out.flush().unwrap();
    let spill = RegisteredTempDir::new_in(dir.path()).unwrap();
    std::fs::write(spill.path().join("run-0"), b"sorted run").unwrap();
    let own = dir.path().join("own.bin");
    std::fs::write(&own, b"x").unwrap();
    let _reg = register_temp(&own, TempKind::File);
    assert_eq!(registered_temps().len(), 3);
    assert_eq!(names(dir.path()).len(), 3);

    assert_eq!(cleanup_registered_temps(), 3);
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
    assert!(registered_temps().is_empty());
    // The owners find their files gone: committing fails cleanly, dropping is harmless.
    assert!(out.commit().is_err());
    drop(spill);
    assert!(names(dir.path()).is_empty());
}

/// Starts `sweeptin tin FIFO -o DIR/out.ply`: it creates its temporary output, then blocks
/// opening the FIFO; the signal must delete the temporary file and exit with 128 + the signal
/// (130 for SIGINT, 143 for SIGTERM).
#[cfg(unix)]
/// Sends `child` the signal `SIG<signal>` and waits for it to exit (at most `seconds`): its
/// status and what it wrote on stderr (piped).
fn signalled(
    child: &mut std::process::Child,
    signal: &str,
    seconds: u64,
) -> (std::process::ExitStatus, String) {
    let killed = Command::new("kill")
        .arg(format!("-{signal}"))
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(killed.success());
    let waited = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if waited.elapsed() > Duration::from_secs(seconds) {
            let _ = child.kill();
            panic!("sweeptin did not exit after SIG{signal}");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    (status, stderr)
}

fn interrupted_run(signal: &str, code: i32) {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("points.xyz");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("SKIP interrupted_run: mkfifo is not available");
        return;
    }
    let out = dir.path().join("out.ply");
    let mut child = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .arg("tin")
        .arg(&fifo)
        .arg("-o")
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while names(dir.path()).len() < 2 {
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "no temporary file appeared"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let temp = names(dir.path());
    assert!(
        temp.iter().any(|n| n.starts_with(".out.ply.sweeptin-")),
        "{temp:?}"
    );
    let (status, stderr) = signalled(&mut child, signal, 30);
    assert_eq!(status.code(), Some(code), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    assert_eq!(
        names(dir.path()),
        ["points.xyz"],
        "temporary output left behind"
    );
}

#[cfg(unix)]
#[test]
fn sigint_deletes_temporary_output() {
    interrupted_run("INT", 130);
}

#[cfg(unix)]
#[test]
fn sigterm_deletes_temporary_output() {
    interrupted_run("TERM", 143);
}

/// Every command line running now whose arguments include `needle`.
#[cfg(target_os = "linux")]
fn processes_with(needle: &str) -> Vec<String> {
    let mut found = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        if let Ok(cmd) = std::fs::read(e.path().join("cmdline")) {
            let cmd = String::from_utf8_lossy(&cmd).replace('\0', " ");
            if cmd.contains(needle) {
                found.push(cmd);
            }
        }
    }
    found
}

/// `run --all` passes SIGTERM on to the tasks it runs (each its own process) and waits for them:
/// none is left running, nothing is written after it exits (143), and no task starts after the
/// signal. The tasks kept running, orphaned, and wrote their tiles after the job was reported
/// interrupted.
#[cfg(target_os = "linux")]
#[test]
fn sigterm_stops_the_tasks_of_run_all() {
    let dir = tempfile::tempdir().unwrap();
    let job = dir.path().join("job");
    let arso = data::shared("lidar/arso_TM_511_122_sw_250m.laz");
    let bin = env!("CARGO_BIN_EXE_sweeptin");
    let plan = Command::new(bin)
        .arg("plan")
        .arg("dem")
        .arg(&arso)
        .args(["--cell", "1", "--tile", "50", "-q", "-o"])
        .arg(&job)
        .status()
        .unwrap();
    assert!(plan.success());
    let plan = job.join("plan.json");
    let mut all = Command::new(bin)
        .arg("run")
        .arg(&plan)
        .args(["--all", "--jobs", "2", "-q"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The first records are written: tasks are running now.
    let started = Instant::now();
    while names(&job.join("tiles")).len() < 2 {
        assert!(started.elapsed() < Duration::from_secs(60), "no task ended");
        std::thread::sleep(Duration::from_millis(10));
    }
    let needle = plan.to_string_lossy().into_owned();
    assert!(processes_with(&needle).len() >= 2, "no task is running");
    let (status, stderr) = signalled(&mut all, "TERM", 60);
    assert_eq!(status.code(), Some(143), "{stderr}");
    assert_eq!(
        processes_with(&needle),
        Vec::<String>::new(),
        "tasks left running"
    );
    let after = names(&job.join("tiles"));
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(names(&job.join("tiles")), after, "written after the exit");
    assert!(after.iter().all(|n| !n.contains("sweeptin-")), "{after:?}");
    assert!(after.len() < 2 * 25, "every task ran: {after:?}");
}
