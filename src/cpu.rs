//! The processor check: builds for x86-64 Linux target x86-64-v2 (`.cargo/config.toml`), so the
//! binary and the Python module say so on an older processor instead of dying of an illegal
//! instruction. `is_x86_feature_detected!` would answer from the build's own target features,
//! so the kernel's list (`/proc/cpuinfo`) is asked instead.

/// The x86-64-v2 features this build was compiled for and the processor lacks (their
/// `/proc/cpuinfo` names), or `None` when it has them all, when the build does not target
/// x86-64-v2, or when the list cannot be read (then nothing is claimed).
pub fn missing_features() -> Option<Vec<&'static str>> {
    #[cfg(all(target_arch = "x86_64", target_os = "linux", target_feature = "sse4.2"))]
    {
        // SSE3 is "pni"; LAHF/SAHF in 64-bit mode is "lahf_lm".
        const V2: [&str; 7] = [
            "pni", "ssse3", "cx16", "sse4_1", "sse4_2", "popcnt", "lahf_lm",
        ];
        use std::io::BufRead;
        // The first processor's flags (the whole file is large on many cores).
        let info = std::io::BufReader::new(std::fs::File::open("/proc/cpuinfo").ok()?);
        let flags = info
            .lines()
            .map_while(|l| l.ok())
            .find(|l| l.starts_with("flags"))?;
        let have: Vec<&str> = flags.split_whitespace().collect();
        let missing: Vec<&'static str> = V2.into_iter().filter(|f| !have.contains(f)).collect();
        (!missing.is_empty()).then_some(missing)
    }
    #[cfg(not(all(target_arch = "x86_64", target_os = "linux", target_feature = "sse4.2")))]
    None
}

/// The message for [`missing_features`].
pub fn message(missing: &[&str]) -> String {
    format!(
        "this build of sweeptin needs an x86-64-v2 processor, and this one lacks {}; rebuild it \
         from source with RUSTFLAGS=\"-C target-cpu=x86-64\" (see the README)",
        missing.join(", ")
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn this_machine_runs_the_build() {
        // The tests run on the processor they were built for.
        assert_eq!(super::missing_features(), None);
        assert!(super::message(&["popcnt"]).contains("lacks popcnt"));
    }
}
