//! Criterion benchmarks of the in-memory core against in-memory peers, side by side.
//!
//! For each distribution (`uniform`, `lidar-like`, `clustered`; see `sweeptin::synth`) and size,
//! one group `core/<dist>/<n>` times sweeptin (`sweeptin::triangulate`, its sort included),
//! delaunator, spade (`bulk_load`) and cdt on the same points, each given the layout it wants
//! (`benches/support/peers.rs`), with `Throughput::Elements(n)` so criterion reports points/s.
//! Point generation and layout conversion happen outside the timed closure.
//!
//! ```text
//! cargo bench --bench core                      # 1M and 4M: ~11 min on 2 quiet cores (docs/BENCHMARKS.md)
//! SWEEPTIN_BENCH_SIZES=100k,1M cargo bench --bench core
//! cargo bench --bench core -- lidar-like        # criterion's filter on the benchmark id
//! ```
//!
//! To keep the whole run short, every benchmark takes 10 samples of one iteration each (flat
//! sampling) after a 1 s warm-up; criterion warns that the target time cannot be met, which is
//! expected. Peak memory is measured per process by `examples/bench_core.rs` instead, see
//! `scripts/bench-core.sh`.

#[path = "support/peers.rs"]
mod peers;

use criterion::{
    BatchSize, BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use peers::{Algo, Dist};
use std::hint::black_box;
use std::time::Duration;

/// Sizes from `SWEEPTIN_BENCH_SIZES` (comma-separated, `k`/`M` suffixes), or 1M and 4M.
fn sizes() -> Vec<usize> {
    let Ok(spec) = std::env::var("SWEEPTIN_BENCH_SIZES") else {
        return vec![1_000_000, 4_000_000];
    };
    spec.split(',')
        .map(|s| {
            sweeptin::synth::parse_count(s)
                .unwrap_or_else(|| panic!("SWEEPTIN_BENCH_SIZES: bad size {s:?}"))
        })
        .collect()
}

fn core(c: &mut Criterion) {
    for n in sizes() {
        for dist in Dist::ALL {
            let pts = dist.generate(n, 1);
            let mut group = c.benchmark_group(format!("core/{}/{n}", dist.name()));
            group
                .sampling_mode(SamplingMode::Flat)
                .sample_size(10)
                .warm_up_time(Duration::from_secs(1))
                .measurement_time(Duration::from_secs(5))
                .throughput(Throughput::Elements(n as u64));
            for algo in Algo::ALL {
                let input = algo.input(pts.clone());
                group.bench_function(BenchmarkId::from_parameter(algo.name()), |b| {
                    b.iter_batched(
                        || input.clone(),
                        |mut input| {
                            let done = peers::run(&mut input)
                                .unwrap_or_else(|e| panic!("{} failed: {e}", algo.name()));
                            black_box(done.triangles);
                            // Dropped outside the timed region by criterion.
                            (done, input)
                        },
                        BatchSize::LargeInput,
                    )
                });
            }
            group.finish();
        }
    }
}

criterion_group!(benches, core);
criterion_main!(benches);
