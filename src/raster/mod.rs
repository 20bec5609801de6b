//! Regular grids (DEMs): reading.
pub mod read;
