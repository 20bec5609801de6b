use super::*;
use scan::CellTriangle;

fn grid(cols: u32, rows: u32, f: impl Fn(f64, f64) -> f64) -> (RasterSpec, Vec<f64>) {
    let spec = RasterSpec::north_up(cols, rows, 1000.0, 2000.0, 2.0);
    let mut h = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            h.push(f(c as f64, r as f64));
        }
    }
    (spec, h)
}

#[test]
fn planar_grid_gives_two_triangles() {
    let (spec, h) = grid(50, 30, |c, r| 3.0 + 0.5 * c - 0.25 * r);
    let s = simplify(&spec, &h, &Options::max_error(1e-9), None).unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.vertices.len(), 4);
    assert!(s.stats.max_error < 1e-9);
    // Counter-clockwise in world coordinates.
    for t in &s.triangles {
        let [a, b, c] = t.map(|i| s.vertices[i as usize]);
        let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(cross > 0.0);
    }
}

#[test]
fn bump_is_within_the_bound_and_budgets_hold() {
    let (spec, h) = grid(60, 40, |c, r| {
        10.0 * (-((c - 30.0).powi(2) + (r - 20.0).powi(2)) / 80.0).exp()
    });
    let s = simplify(&spec, &h, &Options::max_error(0.05), None).unwrap();
    assert!(s.stats.max_error <= 0.05, "{:?}", s.stats);
    assert!(s.stats.points > 4);
    assert_eq!(s.stats.uncovered_cells, 0);
    let p = simplify(
        &spec,
        &h,
        &Options {
            stop: Stop::MaxPoints(20),
            decimate: false,
        },
        None,
    )
    .unwrap();
    assert_eq!(p.stats.points, 20);
    let t = simplify(
        &spec,
        &h,
        &Options {
            stop: Stop::MaxTriangles(25),
            decimate: false,
        },
        None,
    )
    .unwrap();
    assert!(
        t.stats.triangles <= 25 && t.stats.triangles >= 23,
        "{}",
        t.stats.triangles
    );
}

#[test]
fn missing_cells_are_not_covered() {
    // A hole in the middle and a missing corner.
    let (spec, mut h) = grid(30, 30, |c, r| c * 0.1 + r * 0.2);
    for r in 10..15 {
        for c in 12..20 {
            h[r * 30 + c] = f64::NAN;
        }
    }
    h[0] = f64::NAN;
    let s = simplify(&spec, &h, &Options::max_error(0.01), None).unwrap();
    for t in &s.triangles {
        let ct = CellTriangle {
            v: t.map(|i| {
                let [c, r] = s.cells[i as usize];
                [i64::from(c), i64::from(r)]
            }),
            z: [0.0; 3],
        }
        .ccw();
        ct.rows(scan::Clip::all(30, 30), |r, lo, hi| {
            for c in lo..=hi {
                assert!(
                    !h[(r * 30 + c) as usize].is_nan(),
                    "cell ({c}, {r}) covered"
                );
            }
        });
    }
    assert!(s.stats.max_error <= 0.01);
    assert_eq!(s.stats.uncovered_cells, 0);
}

#[test]
fn bad_grids_are_refused() {
    let (spec, h) = grid(1, 5, |_, _| 0.0);
    assert!(simplify(&spec, &h, &Options::max_error(1.0), None).is_err());
    let (spec, h) = grid(4, 4, |_, _| 0.0);
    assert!(simplify(&spec, &h[1..], &Options::max_error(1.0), None).is_err());
    assert!(simplify(&spec, &h, &Options::max_error(f64::NAN), None).is_err());
}
