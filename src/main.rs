//! The `sweeptin` command: a thin layer over the library (see `src/cli/`).
#![forbid(unsafe_code)]

mod cli;

fn main() -> std::process::ExitCode {
    // Built for x86-64-v2 (.cargo/config.toml): say so on an older processor rather than die of
    // an illegal instruction (status 4: the environment). `is_x86_feature_detected!` would
    // answer from the build's own target features, so ask the processor.
    #[cfg(all(target_arch = "x86_64", target_feature = "sse4.2"))]
    if !has_x86_64_v2() {
        eprintln!(
            "sweeptin: error: this build needs an x86-64-v2 processor (SSE4.2, POPCNT); \
             rebuild it with RUSTFLAGS=\"-C target-cpu=x86-64\" cargo build --release"
        );
        return std::process::ExitCode::from(4);
    }
    cli::main()
}

/// Does the processor have x86-64-v2's features (CPUID leaf 1, ECX: SSE3, SSSE3, CMPXCHG16B,
/// SSE4.1, SSE4.2, POPCNT)?
#[cfg(all(target_arch = "x86_64", target_feature = "sse4.2"))]
fn has_x86_64_v2() -> bool {
    const NEED: u32 = (1 << 0) | (1 << 9) | (1 << 13) | (1 << 19) | (1 << 20) | (1 << 23);
    std::arch::x86_64::__cpuid(1).ecx & NEED == NEED
}
