//! The `sweeptin` command: a thin layer over the library (see `src/cli/`).
#![forbid(unsafe_code)]

mod cli;

fn main() -> std::process::ExitCode {
    // Built for x86-64-v2 (.cargo/config.toml): say so on an older processor rather than die of
    // an illegal instruction (status 4: the environment).
    if let Some(missing) = sweeptin::cpu::missing_features() {
        eprintln!("sweeptin: error: {}", sweeptin::cpu::message(&missing));
        return std::process::ExitCode::from(4);
    }
    raise_open_file_limit();
    cli::main()
}

/// Lifts the soft limit on open files to the hard one, as `ulimit -n $(ulimit -Hn)` would: the
/// external sort keeps a file per run and sizes its merges by this limit (often 1,024 soft on a
/// cluster node, with a higher hard limit).
#[cfg(target_os = "linux")]
fn raise_open_file_limit() {
    use rustix::process::{Resource, getrlimit, setrlimit};
    let mut limit = getrlimit(Resource::Nofile);
    // `None` is no limit.
    let below = match (limit.current, limit.maximum) {
        (Some(c), Some(m)) => c < m,
        (Some(_), None) => true,
        (None, _) => false,
    };
    if below {
        limit.current = limit.maximum;
        // Refused (a sandbox): the sort adapts to the soft limit instead.
        let _ = setrlimit(Resource::Nofile, limit);
    }
}

/// Elsewhere the sort adapts to the usual limit.
#[cfg(not(target_os = "linux"))]
fn raise_open_file_limit() {}
