//! Writes synthetic breaklines (`contours` | `coast` | `roads`) in the breakline text format, or
//! their points (`contour-points` | `coast-points` | `road-points`) as XYZ, to stdout:
//! `cargo run --release --example dump_lines -- contours 1000000 > lines.txt`.
use std::io::{BufWriter, Write};

fn main() {
    let which = std::env::args()
        .nth(1)
        .expect("contours|coast|roads|contour-points|coast-points|road-points");
    let n: usize = std::env::args()
        .nth(2)
        .expect("a count")
        .parse()
        .expect("a count");
    let mut out = BufWriter::new(std::io::stdout().lock());
    let points = match which.as_str() {
        "contour-points" => Some(sweeptin::synth::contour_points(n, 1)),
        "coast-points" => Some(sweeptin::synth::coastline_points(n, 1)),
        "road-points" => Some(sweeptin::synth::road_points(n, 1)),
        _ => None,
    };
    if let Some(pts) = points {
        for p in pts {
            writeln!(out, "{} {} {}", p[0], p[1], p[2]).unwrap();
        }
        return;
    }
    let lines = match which.as_str() {
        "coast" => sweeptin::synth::coastline(n, 1),
        "roads" => sweeptin::synth::roads(n, 1),
        _ => sweeptin::synth::contours(n, 1),
    };
    for l in lines {
        for p in l {
            writeln!(out, "{} {} {}", p[0], p[1], p[2]).unwrap();
        }
        writeln!(out).unwrap();
    }
}
