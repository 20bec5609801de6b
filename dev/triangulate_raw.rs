//! The Rust API's in-memory triangulation of raw points, for the Python package's tests
//! (python/tests: the arrays `sweeptin.triangulate` returns must equal these).
//!
//! `cargo run --example triangulate_raw -- POINTS.f64 OUT_PREFIX [first|last|lowest|highest]`
//! reads `n × [x, y, z]` little-endian doubles and writes `OUT_PREFIX.vertices` (f64),
//! `.triangles` (u32) and `.input_index` (u32), little-endian.

use sweeptin::{DuplicatePolicy, Options, triangulate};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    assert!(
        args.len() >= 3,
        "usage: triangulate_raw POINTS.f64 OUT_PREFIX [POLICY]"
    );
    let bytes = std::fs::read(&args[1]).expect("read the points");
    let points: Vec<[f64; 3]> = bytes
        .chunks_exact(24)
        .map(|c| {
            let v = |i: usize| f64::from_le_bytes(c[8 * i..8 * i + 8].try_into().unwrap());
            [v(0), v(1), v(2)]
        })
        .collect();
    let duplicates = match args.get(3).map(String::as_str) {
        None | Some("first") => DuplicatePolicy::First,
        Some("last") => DuplicatePolicy::Last,
        Some("lowest") => DuplicatePolicy::Lowest,
        Some("highest") => DuplicatePolicy::Highest,
        Some(p) => panic!("unknown policy {p}"),
    };
    let t = triangulate(&points, &Options { duplicates }).expect("triangulate");
    let write = |ext: &str, data: Vec<u8>| {
        std::fs::write(format!("{}.{ext}", args[2]), data).expect("write");
    };
    write(
        "vertices",
        t.vertices
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    );
    write(
        "triangles",
        t.triangles
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    );
    write(
        "input_index",
        t.input_index.iter().flat_map(|v| v.to_le_bytes()).collect(),
    );
}
