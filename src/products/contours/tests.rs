//! Contours from triangle streams: levels, stitching in any order, spilling, and what a tiled
//! run's workers keep.

use super::*;
use crate::products::testutil::{
    Step, feed, grid_tin, in_sweep_order, random_tin, shuffled_with_watermarks,
};
use serde_json::Value;

/// `(elevation, closed, points)` of every feature, rings rotated to start at their smallest
/// point, sorted: the same for any order of the stream.
fn canonical(path: &Path) -> Vec<(f64, bool, Vec<[f64; 2]>)> {
    let v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let mut out: Vec<(f64, bool, Vec<[f64; 2]>)> = v["features"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let mut pts: Vec<[f64; 2]> = f["geometry"]["coordinates"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
                .collect();
            let closed = f["properties"]["closed"].as_bool().unwrap();
            if closed {
                assert_eq!(pts.first(), pts.last());
                pts.pop();
                let m = (0..pts.len())
                    .min_by(|&i, &j| pts[i].partial_cmp(&pts[j]).unwrap())
                    .unwrap();
                pts.rotate_left(m);
            }
            for w in pts.windows(2) {
                assert_ne!(w[0], w[1], "repeated point");
            }
            (f["properties"]["elevation"].as_f64().unwrap(), closed, pts)
        })
        .collect();
    out.sort_by(|a, b| a.partial_cmp(b).unwrap());
    out
}

fn run(steps: &[Step], dir: &Path, name: &str, options: ContourOptions) -> PathBuf {
    run_summary(steps, dir, name, options).0
}

fn run_summary(
    steps: &[Step],
    dir: &Path,
    name: &str,
    options: ContourOptions,
) -> (PathBuf, ContourSummary) {
    let path = dir.join(name);
    let mut sink = ContourSink::new(&path, options).unwrap();
    let info = StreamInfo {
        crs: None,
        bounds: [0.0, 0.0, 100.0, 100.0],
    };
    let ProductSummary::Contours(summary) = feed(&mut sink, &info, steps) else {
        panic!("not a contour summary")
    };
    (path, summary)
}

fn area(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        / 2.0
}

/// What a tiled run's workers keep for contours: the triangles the sink makes segments of
/// (a level in `(zmin, zmax]`), and those it must refuse; no others.
#[test]
fn wanted_triangles_are_those_that_cross_a_level() {
    let l = ContourLevels {
        base: 0.0,
        interval: 0.5,
    };
    let t = |z: [f64; 3]| [[0.0, 0.0, z[0]], [1.0, 0.0, z[1]], [0.0, 1.0, z[2]]];
    assert!(l.wants(&t([0.1, 0.4, 0.6])));
    assert!(!l.wants(&t([0.1, 0.4, 0.3])));
    assert!(
        l.wants(&t([0.1, 0.5, 0.3])),
        "a level at the highest vertex"
    );
    assert!(
        !l.wants(&t([0.5, 0.7, 0.9])),
        "a level at the lowest vertex only"
    );
    assert!(!l.wants(&t([0.5, 0.5, 0.5])), "flat on a level");
    let tiny = ContourLevels {
        base: 0.0,
        interval: 1e-9,
    };
    assert!(
        tiny.wants(&t([0.0, 0.0, 0.1])),
        "too many levels: the sink refuses it"
    );
    assert!(tiny.crossed(&t([0.0, 0.0, 0.1])).is_err());
}

#[test]
fn levels_are_clean_numbers() {
    assert_eq!(level_value(0.0, 0.1, 3), 0.3);
    assert_eq!(level_value(0.5, 2.0, -2), -3.5);
    assert_eq!(level_value(0.0, 1.0 / 3.0, 1), 1.0 / 3.0);
}

/// On a plane every level is one straight open line across the square whose points satisfy
/// the plane's equation, with the higher ground on the left.
#[test]
fn plane_gives_straight_lines_on_the_level() {
    let f = |x: f64, y: f64| 0.3 * x + 0.1 * y + 2.0;
    let tris = random_tin(400, 100.0, 5, f);
    let dir = tempfile::tempdir().unwrap();
    let options = ContourOptions {
        interval: 2.5,
        ..ContourOptions::default()
    };
    let path = run(&in_sweep_order(&tris), dir.path(), "p.geojson", options);
    let lines = canonical(&path);
    // z from 2 to 42: levels 2.5, 5, …, 40 (42 is not crossed: no vertex lies above it).
    assert_eq!(lines.len(), 16);
    for (l, closed, pts) in &lines {
        assert!(!closed);
        for p in pts {
            assert!((f(p[0], p[1]) - l).abs() < 1e-9, "{p:?} not at level {l}");
        }
        // Higher ground (larger x) on the left: the line runs towards -y roughly.
        assert!(pts.last().unwrap()[1] < pts[0][1]);
        let ends = [pts[0], *pts.last().unwrap()];
        for e in ends {
            let on_border = e
                .iter()
                .any(|&c| c.abs() < 1e-9 || (c - 100.0).abs() < 1e-9);
            assert!(on_border, "line ends inside at {e:?}");
        }
    }
}

/// Vertices exactly at a level: a stepped pyramid on an integer grid gives one square ring
/// per level, through the grid vertices, counter-clockwise (higher ground on the left), and
/// nothing for the single-vertex summit.
#[test]
fn vertices_at_levels_give_clean_rings() {
    let f = |x: f64, y: f64| 5.0 - (x - 5.0).abs().max((y - 5.0).abs());
    let tris = grid_tin(10, 10, 1.0, f);
    let dir = tempfile::tempdir().unwrap();
    let path = run(
        &in_sweep_order(&tris),
        dir.path(),
        "r.geojson",
        ContourOptions::default(),
    );
    let rings = canonical(&path);
    let levels: Vec<f64> = rings.iter().map(|r| r.0).collect();
    assert_eq!(levels, [1.0, 2.0, 3.0, 4.0]);
    for (l, closed, pts) in &rings {
        assert!(closed);
        let r = 5.0 - l;
        for p in pts {
            assert_eq!((p[0] - 5.0).abs().max((p[1] - 5.0).abs()), r, "{p:?}");
        }
        assert_eq!(area(pts), 4.0 * r * r);
    }
}

/// The saddle in sweep order, shuffled with late triangles, and with a tiny memory budget (so
/// that points go to the scratch file): the same lines.
#[test]
fn order_and_spilling_do_not_change_the_result() {
    let f = |x: f64, y: f64| {
        15.0 * (std::f64::consts::PI * x / 20.0).sin()
            - 15.0 * (std::f64::consts::PI * y / 20.0).sin()
    };
    let tris = random_tin(2000, 100.0, 9, f);
    let dir = tempfile::tempdir().unwrap();
    let o = ContourOptions {
        interval: 5.0,
        ..ContourOptions::default()
    };
    let a = canonical(&run(
        &in_sweep_order(&tris),
        dir.path(),
        "a.json",
        o.clone(),
    ));
    let b = canonical(&run(
        &shuffled_with_watermarks(&tris, 4),
        dir.path(),
        "b.json",
        o.clone(),
    ));
    let tiny = ContourOptions {
        memory_points: 100,
        ..o
    };
    let (c, summary) = run_summary(
        &shuffled_with_watermarks(&tris, 5),
        dir.path(),
        "c.json",
        tiny,
    );
    assert!(summary.points_spilled > 0, "{summary:?}");
    let c = canonical(&c);
    assert!(a.iter().any(|x| x.1) && a.iter().any(|x| !x.1));
    assert_eq!(a, b);
    assert_eq!(a, c);
}

/// The quick rejection never drops a triangle the sink would use: against the sink's own test,
/// on levels exactly at vertices, binary-unfriendly intervals, high and negative heights.
#[test]
fn quick_rejection_keeps_every_crossing_triangle() {
    let mut rng = crate::geom::rng::SplitMix64::new(11);
    for (base, interval) in [
        (0.0, 1.0),
        (0.0, 0.1),
        (0.05, 0.25),
        (100.0, 1.0 / 3.0),
        (-7.0, 1e-3),
    ] {
        let l = ContourLevels { base, interval };
        for centre in [0.0, 812.3, 4807.9, -31.7] {
            let (mut kept, mut crossing) = (0, 0);
            for _ in 0..20_000 {
                let mut z = || {
                    let v = centre + rng.range(-2.0, 2.0) * interval;
                    if rng.below(3) == 0 {
                        // Exactly on a level.
                        level_value(base, interval, ((v - base) / interval).round() as i64)
                    } else {
                        v
                    }
                };
                let t = [[0.0, 0.0, z()], [1.0, 0.0, z()], [0.0, 1.0, z()]];
                let exact = l.crossed(&t).map_or(true, |mut ks| ks.next().is_some());
                assert!(
                    !exact || l.wants(&t),
                    "{t:?} base {base} interval {interval}"
                );
                kept += usize::from(l.wants(&t));
                crossing += usize::from(exact);
            }
            assert!(
                kept <= crossing + crossing / 20 + 50,
                "the quick test rejects too little"
            );
        }
    }
}
