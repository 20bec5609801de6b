//! Regular grids (DEMs): georeferencing, reading.
pub mod grid;
pub mod read;
