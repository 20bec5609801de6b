//! Writing line files for the tests: one home for the GeoJSON `FeatureCollection` of
//! `LineString`s that breakline tests hand to the command line.

#![allow(dead_code)]

use std::path::Path;

/// Writes `lines` as a GeoJSON `FeatureCollection`, one `LineString` feature per line, in order:
/// `[x, y]` positions (lines without z) or `[x, y, z]`.
pub fn write_lines<const N: usize>(path: &Path, lines: &[Vec<[f64; N]>]) {
    let features: Vec<String> = lines
        .iter()
        .map(|l| {
            let coords: Vec<String> = l
                .iter()
                .map(|p| {
                    let c: Vec<String> = p.iter().map(f64::to_string).collect();
                    format!("[{}]", c.join(","))
                })
                .collect();
            format!(
                r#"{{"type":"Feature","properties":{{}},"geometry":{{"type":"LineString","coordinates":[{}]}}}}"#,
                coords.join(",")
            )
        })
        .collect();
    std::fs::write(
        path,
        format!(
            r#"{{"type":"FeatureCollection","features":[{}]}}"#,
            features.join(",\n")
        ),
    )
    .unwrap();
}
