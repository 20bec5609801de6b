//! The oracle shared by the fuzz targets: triangulate, and check everything that can be checked
//! independently of the sweep.

use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use sweeptin::geom::predicates::{Orientation, orient};
use sweeptin::sweep::Sweep;
use sweeptin::{DuplicatePolicy, Error, Options, Triangulation, triangulate};

/// Sorted set of sorted coordinate triples (as bits, `-0.0` made `+0.0`).
pub type TriSet = Vec<[(u64, u64); 3]>;

fn key(x: f64, y: f64) -> (u64, u64) {
    ((x + 0.0).to_bits(), (y + 0.0).to_bits())
}

/// What `triangulate` must do, decided independently.
#[derive(Debug, PartialEq, Eq)]
pub enum Expect {
    /// Fewer than 3 distinct positions.
    TooFew(u64),
    /// All distinct positions on one line.
    Collinear(u64),
    /// A triangulation of this many distinct positions.
    Triangles(u64),
}

/// Decides the outcome for finite points.
pub fn expect(pts: &[[f64; 3]]) -> Expect {
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

/// The triangles of `tin` as a [`TriSet`].
pub fn tri_set(tin: &Triangulation) -> TriSet {
    let mut out: TriSet = tin
        .triangles
        .iter()
        .map(|t| {
            let mut k = t.map(|i| {
                let v = tin.vertices[i as usize];
                key(v[0], v[1])
            });
            k.sort();
            k
        })
        .collect();
    out.sort();
    out
}

/// spade's Delaunay triangulation as a [`TriSet`], or `None` if spade refuses a point.
pub fn spade_set(pts: &[[f64; 3]]) -> Option<TriSet> {
    let mut d: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    for p in pts {
        d.insert(Point2::new(p[0], p[1])).ok()?;
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
    Some(out)
}

/// Triangulates finite points and checks the outcome: the right error, or a mesh that passes the
/// independent validator, has every distinct point, and does not depend on input order. With
/// `spade`, also compares with spade when the Delaunay triangulation is unique. Small inputs are
/// also stepped through the sweep with `check()` after every step.
pub fn check(pts: &[[f64; 3]], spade: bool) {
    let want = expect(pts);
    let got = triangulate(pts, &Options::default());
    let tin = match (got, &want) {
        (Ok(tin), Expect::Triangles(d)) => {
            assert_eq!(tin.vertices.len() as u64, *d);
            assert_eq!(tin.duplicates, pts.len() as u64 - d);
            tin
        }
        (Err(Error::TooFewPoints { distinct, .. }), Expect::TooFew(d)) => {
            assert_eq!(distinct, *d);
            return;
        }
        (Err(Error::AllCollinear { distinct }), Expect::Collinear(d)) => {
            assert_eq!(distinct, *d);
            return;
        }
        (Err(Error::CoordinateOutOfRange { .. }), _) => return,
        (got, want) => panic!(
            "expected {want:?}, got {:?}",
            got.map(|t| t.triangles.len())
        ),
    };
    let report = sweeptin::validate::validate(&tin.vertices, &tin.triangles)
        .unwrap_or_else(|e| panic!("{e}"));
    let set = tri_set(&tin);
    let mut rev = pts.to_vec();
    rev.reverse();
    let again = triangulate(&rev, &Options::default()).expect("reversed input");
    assert!(
        tri_set(&again) == set,
        "reversing the input changed the triangles"
    );
    if spade
        && report.cocircular_edges == 0
        && let Some(s) = spade_set(pts)
    {
        assert!(
            s == set,
            "differs from spade (unique Delaunay triangulation)"
        );
    }
    if pts.len() <= 64 {
        step_checked(pts);
    }
}

/// Runs the sweep one point at a time with every invariant checked after each step.
pub fn step_checked(pts: &[[f64; 3]]) {
    let prep = sweeptin::sort::memory::prepare(pts, DuplicatePolicy::First).expect("prepare");
    if prep.len() < 3 {
        return;
    }
    let mut s = Sweep::new(prep.xy).expect("sweep");
    s.check().unwrap_or_else(|e| panic!("initial: {e}"));
    let mut k = 0;
    while s.step().expect("step") {
        k += 1;
        s.check().unwrap_or_else(|e| panic!("step {k}: {e}"));
    }
}
