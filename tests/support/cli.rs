//! Running the `sweeptin` binary from a test: one home for the runner that fails the test with
//! the command line and the tool's stderr when the command does not succeed.

use std::ffi::OsStr;
use std::process::{Command, Output};

/// Runs `sweeptin ARGS…` and returns its output; panics with the arguments and stderr when it
/// fails.
pub fn ok<S: AsRef<OsStr> + std::fmt::Debug>(args: &[S]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "sweeptin {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}
