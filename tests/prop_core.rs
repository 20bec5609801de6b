//! Property tests of the in-memory core.
//!
//! * General position: sweeptin's triangles are exactly spade's (the Delaunay triangulation is
//!   unique there).
//! * Degenerate inputs (grids, tilted grids, cocircular rings, collinear runs, duplicates, clusters,
//!   extreme scales, UTM offsets): the Delaunay triangulation is not unique, so the independent
//!   validator decides, and the result must not depend on input order or on exact translations and
//!   power-of-two scalings.
//! * Bad input gives the right error, never a panic.
//! * The steppable sweep passes `check()` after every step.
//!
//! Case counts are kept modest so CI stays fast; raise them with `PROPTEST_CASES`. Every run of the
//! sweep has a time limit (a worker thread), so a sweep that loops fails the case instead of hanging
//! CI while its flip stack eats the machine's memory.

use proptest::prelude::*;
use proptest::test_runner::Config;
use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use sweeptin::geom::predicates::{Orientation, orient};
use sweeptin::sort::memory::prepare;
use sweeptin::sweep::Sweep;
use sweeptin::validate::validate;
use sweeptin::{DuplicatePolicy, Error, Options, Triangulation};

/// Runs `f` on a worker thread; panics if it takes longer than a generous limit.
fn bounded<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(std::time::Duration::from_secs(60))
        .expect("the sweep did not finish within a minute: it loops")
}

/// [`sweeptin::triangulate`] with a time limit.
fn triangulate(pts: &[[f64; 3]], options: &Options) -> sweeptin::Result<Triangulation> {
    let (pts, options) = (pts.to_vec(), *options);
    bounded(move || sweeptin::triangulate(&pts, &options))
}

type TriSet = Vec<[(u64, u64); 3]>;

/// A position as bits, with `-0.0` made `+0.0`.
fn key(x: f64, y: f64) -> (u64, u64) {
    ((x + 0.0).to_bits(), (y + 0.0).to_bits())
}

/// The triangles as a sorted set of sorted coordinate triples.
fn tri_set(tin: &Triangulation, back: impl Fn(f64, f64) -> (f64, f64)) -> TriSet {
    let mut out: TriSet = tin
        .triangles
        .iter()
        .map(|t| {
            let mut k = t.map(|i| {
                let v = tin.vertices[i as usize];
                let (x, y) = back(v[0], v[1]);
                key(x, y)
            });
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

fn same(x: f64, y: f64) -> (f64, f64) {
    (x, y)
}

fn spade_set(pts: &[[f64; 3]]) -> TriSet {
    let mut d: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    for p in pts {
        d.insert(Point2::new(p[0], p[1])).unwrap();
    }
    let mut out: TriSet = d
        .inner_faces()
        .map(|f| {
            let mut k = f.vertices().map(|v| key(v.position().x, v.position().y));
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

/// What `triangulate` must do with `pts`, decided independently of it.
#[derive(Debug, PartialEq)]
enum Expect {
    TooFew(u64),
    Collinear(u64),
    Triangles(u64),
}

fn expect(pts: &[[f64; 3]]) -> Expect {
    let mut keys: Vec<(u64, u64)> = pts.iter().map(|p| key(p[0], p[1])).collect();
    keys.sort_unstable();
    keys.dedup();
    let d = keys.len() as u64;
    if d < 3 {
        return Expect::TooFew(d);
    }
    let p = |k: (u64, u64)| [f64::from_bits(k.0), f64::from_bits(k.1)];
    let (a, b) = (p(keys[0]), p(keys[1]));
    if keys
        .iter()
        .all(|&k| orient(a, b, p(k)) == Orientation::Collinear)
    {
        Expect::Collinear(d)
    } else {
        Expect::Triangles(d)
    }
}

/// A deterministic permutation of `pts` from `seed`.
fn shuffled(pts: &[[f64; 3]], seed: u64) -> Vec<[f64; 3]> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut out = pts.to_vec();
    for i in (1..out.len()).rev() {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        out.swap(i, (s % (i as u64 + 1)) as usize);
    }
    out
}

/// Is `x + off` exact, and does subtracting `off` give `x` back?
fn exact_shift(x: f64, off: f64) -> bool {
    let s = x + off;
    s.is_finite() && s - off == x && {
        let bv = s - x;
        (x - (s - bv)) + (off - bv) == 0.0
    }
}

/// Triangulates `pts`, checks the outcome against [`expect`] and validates the mesh; then checks
/// that shuffling, exact translations and power-of-two scalings give the identical triangle set.
/// Returns the triangulation when there is one.
fn check_all(pts: &[[f64; 3]], seed: u64) -> Result<Option<Triangulation>, TestCaseError> {
    let want = expect(pts);
    let tin = match (triangulate(pts, &Options::default()), &want) {
        (Ok(tin), Expect::Triangles(d)) => {
            prop_assert_eq!(tin.vertices.len() as u64, *d);
            prop_assert_eq!(tin.duplicates, pts.len() as u64 - d);
            tin
        }
        (Err(Error::TooFewPoints { distinct, total }), Expect::TooFew(d)) => {
            prop_assert_eq!((distinct, total), (*d, pts.len() as u64));
            return Ok(None);
        }
        (Err(Error::AllCollinear { distinct }), Expect::Collinear(d)) => {
            prop_assert_eq!(distinct, *d);
            return Ok(None);
        }
        (got, want) => {
            return Err(TestCaseError::fail(format!(
                "expected {want:?}, got {:?}",
                got.map(|t| t.triangles.len())
            )));
        }
    };
    if let Err(e) = validate(&tin.vertices, &tin.triangles) {
        return Err(TestCaseError::fail(format!("{e}")));
    }
    let base = tri_set(&tin, same);

    let again = triangulate(&shuffled(pts, seed), &Options::default()).unwrap();
    prop_assert!(
        tri_set(&again, same) == base,
        "shuffling changed the triangles"
    );

    for off in [
        [1024.0, -2048.0],
        [-65536.0, 3.0 * 65536.0],
        [1048576.0, 1048576.0],
    ] {
        if !pts
            .iter()
            .all(|p| exact_shift(p[0], off[0]) && exact_shift(p[1], off[1]))
        {
            continue;
        }
        let moved: Vec<[f64; 3]> = pts
            .iter()
            .map(|p| [p[0] + off[0], p[1] + off[1], p[2]])
            .collect();
        let t = triangulate(&moved, &Options::default()).unwrap();
        let back = tri_set(&t, |x, y| (x - off[0], y - off[1]));
        prop_assert!(
            back == base,
            "translating by {:?} changed the triangles",
            off
        );
    }
    for s in [0.25, 1024.0] {
        let scaled: Vec<[f64; 3]> = pts.iter().map(|p| [p[0] * s, p[1] * s, p[2]]).collect();
        if scaled.iter().any(|p| {
            !sweeptin::geom::predicates::check_coord(p[0])
                || !sweeptin::geom::predicates::check_coord(p[1])
        }) || scaled
            .iter()
            .zip(pts)
            .any(|(q, p)| q[0] / s != p[0] || q[1] / s != p[1])
        {
            continue;
        }
        let t = triangulate(&scaled, &Options::default()).unwrap();
        let back = tri_set(&t, |x, y| (x / s, y / s));
        prop_assert!(back == base, "scaling by {} changed the triangles", s);
    }
    Ok(Some(tin))
}

/// Runs the steppable sweep over `pts`, checking every invariant after every step.
fn check_steps(pts: &[[f64; 3]]) -> Result<(), TestCaseError> {
    let pts = pts.to_vec();
    bounded(move || steps(&pts)).map_err(TestCaseError::fail)
}

fn steps(pts: &[[f64; 3]]) -> Result<(), String> {
    let prep = prepare(pts, DuplicatePolicy::First).unwrap();
    if prep.len() < 3 {
        return Ok(());
    }
    let mut s = Sweep::new(prep.xy).unwrap();
    s.check().map_err(|e| format!("initial state: {e}"))?;
    let mut k = 0;
    while s.step().unwrap() {
        k += 1;
        s.check().map_err(|e| format!("after step {k}: {e}"))?;
    }
    let (tris, _, _) = s.finish();
    if tris.is_empty() != matches!(expect(pts), Expect::Collinear(_)) {
        return Err(format!("{} triangles from {:?}", tris.len(), expect(pts)));
    }
    Ok(())
}

fn with_z(xy: impl IntoIterator<Item = (f64, f64)>) -> Vec<[f64; 3]> {
    xy.into_iter()
        .enumerate()
        .map(|(i, (x, y))| [x, y, i as f64])
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Generators.

/// Subsets of a small integer grid, duplicates and collinear runs included.
fn grid_subset(side: i32, max: usize) -> impl Strategy<Value = Vec<[f64; 3]>> {
    prop::collection::vec((0..side, 0..side), 0..max)
        .prop_map(|v| with_z(v.into_iter().map(|(x, y)| (x as f64, y as f64))))
}

/// Full `w × h` grids with spacing `s`.
fn full_grid() -> impl Strategy<Value = Vec<[f64; 3]>> {
    (
        1usize..24,
        1usize..24,
        prop::sample::select(vec![1.0, 0.5, 3.0, 0.1, 1e-9, 1e9]),
    )
        .prop_map(|(w, h, s)| with_z((0..w * h).map(|i| ((i % w) as f64 * s, (i / w) as f64 * s))))
}

/// Grids rotated by an angle, rounded to `f32` or to 1 mm.
fn tilted_grid() -> impl Strategy<Value = Vec<[f64; 3]>> {
    (
        2usize..20,
        2usize..20,
        0.0f64..std::f64::consts::FRAC_PI_2,
        0.01f64..10.0,
        any::<bool>(),
    )
        .prop_map(|(w, h, a, s, to_f32)| {
            let (c, si) = (a.cos() * s, a.sin() * s);
            let round = |v: f64| {
                if to_f32 {
                    v as f32 as f64
                } else {
                    (v * 1000.0).round() / 1000.0
                }
            };
            with_z((0..w * h).map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (round(x * c - y * si), round(x * si + y * c))
            }))
        })
}

/// Every lattice point on a circle of radius `r` (radii with many Pythagorean representations),
/// optionally the centre, plus a few other grid points.
fn cocircular_ring() -> impl Strategy<Value = Vec<[f64; 3]>> {
    (
        prop::sample::select(vec![5i64, 25, 65, 85, 325, 1105]),
        any::<bool>(),
        prop::collection::vec((-1200i64..1200, -1200i64..1200), 0..6),
        prop::sample::select(vec![1.0, 0.001, 1e-9, 1e6]),
    )
        .prop_map(|(r, centre, extra, s)| {
            let mut pts = Vec::new();
            for x in -r..=r {
                let y2 = r * r - x * x;
                let y = (y2 as f64).sqrt() as i64;
                if y * y == y2 {
                    pts.push((x, y));
                    pts.push((x, -y));
                }
            }
            if centre {
                pts.push((0, 0));
            }
            pts.extend(extra);
            with_z(pts.into_iter().map(|(x, y)| (x as f64 * s, y as f64 * s)))
        })
}

/// Long exactly collinear runs (horizontal, vertical, diagonal) mixed with other points.
fn collinear_runs() -> impl Strategy<Value = Vec<[f64; 3]>> {
    let run = ((-3i64..=3, -3i64..=3), (-50i64..50, -50i64..50), 2usize..80);
    (
        prop::collection::vec(run, 1..4),
        prop::collection::vec((-100i64..100, -100i64..100), 0..8),
    )
        .prop_map(|(runs, extra)| {
            let mut pts = Vec::new();
            for ((dx, dy), (x0, y0), len) in runs {
                let (dx, dy) = if (dx, dy) == (0, 0) { (1, 0) } else { (dx, dy) };
                pts.extend((0..len as i64).map(|t| (x0 + t * dx, y0 + t * dy)));
            }
            pts.extend(extra);
            with_z(pts.into_iter().map(|(x, y)| (x as f64, y as f64)))
        })
}

/// A few tight clusters (spread down to 1e-6 of their distance) plus scattered points.
fn clusters() -> impl Strategy<Value = Vec<[f64; 3]>> {
    let cluster = (
        (-1000.0f64..1000.0, -1000.0f64..1000.0),
        prop::sample::select(vec![1e-6, 1e-3, 1.0]),
        prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 1..40),
        any::<bool>(),
    );
    prop::collection::vec(cluster, 1..4).prop_map(|cs| {
        let mut pts = Vec::new();
        for ((cx, cy), spread, offs, snap) in cs {
            for (dx, dy) in offs {
                let (mut x, mut y) = (cx + dx * spread, cy + dy * spread);
                if snap {
                    // Snap to a grid of the cluster's own size so that ties happen.
                    let q = spread / 8.0;
                    x = (x / q).round() * q;
                    y = (y / q).round() * q;
                }
                pts.push((x, y));
            }
        }
        with_z(pts)
    })
}

/// Grid subsets scaled by powers of ten from 1e-9 to 1e9.
fn scaled() -> impl Strategy<Value = Vec<[f64; 3]>> {
    (grid_subset(12, 100), -9i32..=9).prop_map(|(pts, k)| {
        let s = 10f64.powi(k);
        pts.into_iter()
            .map(|p| [p[0] * s, p[1] * s, p[2]])
            .collect()
    })
}

/// UTM-sized coordinates at 1 mm resolution, as LAS stores them (integer × 0.001 + offset).
fn utm() -> impl Strategy<Value = Vec<[f64; 3]>> {
    (
        prop::collection::vec((0i32..20, 0i32..20), 0..120),
        prop::sample::select(vec![1i32, 7, 1000, 100_000]),
    )
        .prop_map(|(v, step)| {
            with_z(v.into_iter().map(|(i, j)| {
                (
                    (i * step) as f64 * 0.001 + 500_000.0,
                    (j * step) as f64 * 0.001 + 4_000_000.0,
                )
            }))
        })
}

// ---------------------------------------------------------------------------------------------
// Properties.

proptest! {
    #![proptest_config(Config::with_cases(128))]

    #[test]
    fn general_position_matches_spade(
        xy in prop::collection::vec((-1e3f64..1e3, -1e3f64..1e3), 3..300),
    ) {
        let pts = with_z(xy);
        let tin = triangulate(&pts, &Options::default()).unwrap();
        validate(&tin.vertices, &tin.triangles).unwrap();
        prop_assert!(tri_set(&tin, same) == spade_set(&pts));
    }

    #[test]
    fn grid_subsets(pts in grid_subset(16, 150), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn full_grids(pts in full_grid(), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn tilted_grids(pts in tilted_grid(), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn cocircular_rings(pts in cocircular_ring(), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn collinear_runs_with_others(pts in collinear_runs(), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn clustered_points(pts in clusters(), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn scales_1e_minus_9_to_1e9(pts in scaled(), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn utm_offsets(pts in utm(), seed in any::<u64>()) {
        check_all(&pts, seed)?;
    }

    #[test]
    fn stepwise_check_on_degenerate_inputs(
        pts in prop_oneof![
            grid_subset(8, 60),
            tilted_grid(),
            cocircular_ring(),
            collinear_runs(),
            utm(),
        ],
    ) {
        check_steps(&pts)?;
    }

    #[test]
    fn duplicates_follow_the_policy(
        base in prop::collection::vec((-4i32..4, -4i32..4), 1..40),
        copies in prop::collection::vec((any::<prop::sample::Index>(), -3i32..3, any::<bool>()), 0..40),
        seed in any::<u64>(),
    ) {
        // Each copy repeats a base position (sometimes spelled with negative zeros) with its own z.
        let mut pts: Vec<[f64; 3]> =
            base.iter().map(|&(x, y)| [x as f64, y as f64, 0.0]).collect();
        for (i, z, neg_zero) in copies {
            let mut p = pts[i.index(base.len())];
            p[2] = z as f64;
            if neg_zero {
                p = p.map(|v| if v == 0.0 { -0.0 } else { v });
            }
            pts.push(p);
        }
        let pts = shuffled(&pts, seed);
        for policy in [
            DuplicatePolicy::First,
            DuplicatePolicy::Last,
            DuplicatePolicy::Lowest,
            DuplicatePolicy::Highest,
        ] {
            check_policy(&pts, policy)?;
        }
    }

    #[test]
    fn all_collinear_is_an_error(
        (dx, dy) in (-5i64..=5, -5i64..=5).prop_filter("a direction", |d| *d != (0, 0)),
        ts in prop::collection::vec(-100i64..100, 0..50),
    ) {
        let pts = with_z(ts.iter().map(|&t| ((t * dx) as f64 + 0.5, (t * dy) as f64 - 3.0)));
        let got = triangulate(&pts, &Options::default());
        match (expect(&pts), got) {
            (Expect::Collinear(d), Err(Error::AllCollinear { distinct })) => prop_assert_eq!(d, distinct),
            (Expect::TooFew(d), Err(Error::TooFewPoints { distinct, .. })) => prop_assert_eq!(d, distinct),
            (want, got) => prop_assert!(false, "expected {:?}, got {:?}", want, got.map(|t| t.triangles.len())),
        }
    }

    #[test]
    fn fewer_than_three_distinct_is_an_error(
        a in (-3i32..3, -3i32..3),
        b in (-3i32..3, -3i32..3),
        picks in prop::collection::vec(any::<bool>(), 0..20),
    ) {
        let pts: Vec<[f64; 3]> = picks
            .iter()
            .enumerate()
            .map(|(i, &first)| {
                let (x, y) = if first { a } else { b };
                [x as f64, y as f64, i as f64]
            })
            .collect();
        let Expect::TooFew(d) = expect(&pts) else { unreachable!() };
        match triangulate(&pts, &Options::default()) {
            Err(Error::TooFewPoints { distinct, total }) => {
                prop_assert_eq!((distinct, total), (d, pts.len() as u64));
            }
            other => prop_assert!(false, "{:?}", other.map(|t| t.triangles.len())),
        }
    }

    #[test]
    fn non_finite_names_the_first_bad_point(
        pts in grid_subset(10, 40),
        bad in prop::collection::vec((any::<prop::sample::Index>(), 0usize..3, 0usize..3), 1..4),
    ) {
        prop_assume!(!pts.is_empty());
        let mut pts = pts;
        let n = pts.len();
        for &(i, axis, kind) in &bad {
            pts[i.index(n)][axis] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][kind];
        }
        let first = pts.iter().position(|p| p.iter().any(|v| !v.is_finite())).unwrap();
        match triangulate(&pts, &Options::default()) {
            Err(Error::NonFinite { index, .. }) => prop_assert_eq!(index, first as u64),
            other => prop_assert!(false, "{:?}", other.map(|t| t.triangles.len())),
        }
    }

    #[test]
    fn out_of_range_is_an_error(
        pts in grid_subset(10, 40),
        i in any::<prop::sample::Index>(),
        v in prop::sample::select(vec![1e20, -1e17, 1e-40, -1e-35]),
    ) {
        prop_assume!(pts.len() >= 2);
        let mut pts = pts;
        let i = i.index(pts.len());
        // A tiny value next to zero-valued neighbours cannot be fixed by the local origin.
        pts[i][0] = v;
        match triangulate(&pts, &Options::default()) {
            Err(Error::CoordinateOutOfRange { .. }) => {}
            other => prop_assert!(false, "{:?}", other.map(|t| t.triangles.len())),
        }
    }
}

/// Duplicates are merged by `policy`: the survivor of each position is the right input point, and
/// the count of merged points is right.
fn check_policy(pts: &[[f64; 3]], policy: DuplicatePolicy) -> Result<(), TestCaseError> {
    let opts = Options { duplicates: policy };
    let tin = match (triangulate(pts, &opts), expect(pts)) {
        (Ok(tin), Expect::Triangles(_)) => tin,
        (Err(Error::TooFewPoints { .. }), Expect::TooFew(_))
        | (Err(Error::AllCollinear { .. }), Expect::Collinear(_)) => return Ok(()),
        (got, want) => {
            return Err(TestCaseError::fail(format!(
                "expected {want:?}, got {:?}",
                got.map(|t| t.triangles.len())
            )));
        }
    };
    // The survivor of each position, decided here from the definition of each policy.
    let mut best: std::collections::BTreeMap<(u64, u64), usize> = Default::default();
    for (i, p) in pts.iter().enumerate() {
        let k = key(p[0], p[1]);
        let keep = best.entry(k).or_insert(i);
        let (kz, z) = (pts[*keep][2], p[2]);
        let better = match policy {
            DuplicatePolicy::First => false,
            DuplicatePolicy::Last => true,
            DuplicatePolicy::Lowest => z < kz,
            DuplicatePolicy::Highest => z > kz,
        };
        if better {
            *keep = i;
        }
    }
    prop_assert_eq!(tin.duplicates, (pts.len() - best.len()) as u64);
    prop_assert_eq!(tin.vertices.len(), best.len());
    for (v, &i) in tin.vertices.iter().zip(&tin.input_index) {
        prop_assert_eq!(v.map(f64::to_bits), pts[i as usize].map(f64::to_bits));
        prop_assert_eq!(best[&key(v[0], v[1])], i as usize, "policy {:?}", policy);
    }
    if let Err(e) = validate(&tin.vertices, &tin.triangles) {
        return Err(TestCaseError::fail(format!("{e}")));
    }
    Ok(())
}
