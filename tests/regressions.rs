//! One regression test per bug found by property tests and fuzzing, named after what broke.
//!
//! Inputs that once made the sweep loop forever run on a worker thread with a time limit, so a
//! regression fails the test instead of hanging CI (and eating memory: the runaway flip loop grows
//! its stack without bound).

use std::sync::mpsc;
use std::time::Duration;
use sweeptin::geom::predicates::{CircleSide, incircle_exact, incircle_ids, orient, orient_ids};
use sweeptin::validate::validate;
use sweeptin::{Error, Options, Triangulation, triangulate};

/// Triangulates on a worker thread; fails if it takes more than a few seconds.
fn triangulate_bounded(xy: &[(f64, f64)]) -> sweeptin::Result<Triangulation> {
    let pts: Vec<[f64; 3]> = xy.iter().map(|&(x, y)| [x, y, 0.0]).collect();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(triangulate(&pts, &Options::default()));
    });
    rx.recv_timeout(Duration::from_secs(20))
        .expect("the sweep did not finish: it loops")
}

fn valid(xy: &[(f64, f64)]) {
    let tin = triangulate_bounded(xy).unwrap();
    validate(&tin.vertices, &tin.triangles).unwrap();
}

/// Bug: `incircle_symbolic` with one artificial point, when the three real points are collinear,
/// returned "inside iff strictly between" without the orientation of the reordered triangle
/// `(P, b, c)`. When the artificial point was the *second* of the triangle, moving it to the top
/// made that triangle clockwise and the answer came out reversed. The sweep then flipped a legal
/// edge, and on exactly collinear vertical runs flipped back and forth forever, growing the flip
/// stack without bound.
///
/// Checked here against the finite determinant with `P-1`, `P-2` at a large but finite `M`, for
/// every position of the artificial point, on points that include collinear runs.
#[test]
fn symbolic_incircle_collinear_with_artificial_point_second() {
    let m = 1.0e5;
    let far = [[-m, -m * m], [m, -m * m]];
    let real = [
        [0., 0.],
        [0., 1.],
        [0., 2.],
        [1., 0.],
        [2., 0.],
        [1., 1.],
        [3., 3.],
        [-1., 2.],
    ];
    let mut pts = vec![[f64::NAN; 2]; 2];
    pts.extend_from_slice(&real);
    let coord = |v: u32| {
        if v < 2 {
            far[v as usize]
        } else {
            real[(v - 2) as usize]
        }
    };
    let n = pts.len() as u32;
    let mut collinear_cases = 0;
    for a in 0..n {
        for b in 0..n {
            for c in 0..n {
                for d in 2..n {
                    let ids = [a, b, c, d];
                    if (0..4).any(|i| (i + 1..4).any(|j| ids[i] == ids[j])) {
                        continue;
                    }
                    if [a, b, c].iter().filter(|&&v| v < 2).count() != 1 {
                        continue;
                    }
                    if !orient_ids(&pts, a, b, c).is_ccw() {
                        continue;
                    }
                    let reals: Vec<[f64; 2]> = [a, b, c, d]
                        .into_iter()
                        .filter(|&v| v >= 2)
                        .map(coord)
                        .collect();
                    if orient(reals[0], reals[1], reals[2])
                        != sweeptin::geom::predicates::Orientation::Collinear
                    {
                        continue;
                    }
                    collinear_cases += 1;
                    let want = incircle_exact(coord(a), coord(b), coord(c), coord(d));
                    assert_ne!(want, CircleSide::On);
                    assert_eq!(incircle_ids(&pts, a, b, c, d), want, "{ids:?}");
                }
            }
        }
    }
    assert!(collinear_cases > 50, "{collinear_cases}");
}

/// The same bug, end to end: three points on a vertical line made the sweep loop forever (it
/// must report `AllCollinear`), and so did every input with a vertical run of three.
#[test]
fn vertical_collinear_run_looped_forever() {
    match triangulate_bounded(&[(0., 0.), (0., 1.), (0., 2.)]) {
        Err(Error::AllCollinear { distinct: 3 }) => {}
        other => panic!("{:?}", other.map(|t| t.triangles)),
    }
    valid(&[(0., 0.), (0., 1.), (0., 2.), (1., 0.)]);
    valid(&[(0., 0.), (0., 1.), (0., 2.), (-1., 0.)]);
    valid(&[(0., 0.), (0., 1.), (0., 2.), (1., 3.)]);
    let grid: Vec<(f64, f64)> = (0..9).map(|i| ((i % 3) as f64, (i / 3) as f64)).collect();
    valid(&grid);
}
