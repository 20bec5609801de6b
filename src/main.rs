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
    cli::main()
}
