//! Synthetic point sets for tests and benchmarks.
