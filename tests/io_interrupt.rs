//! The interrupt clean-up: the process-wide registry (this file holds the only test touching it
//! directly, so nothing else in this process registers paths meanwhile), and the real handler in
//! the binary, interrupted by SIGINT / SIGTERM while it waits on its input.

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
        if waited.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("sweeptin did not exit after SIG{signal}");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
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
