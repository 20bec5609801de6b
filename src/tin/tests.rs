use super::*;
use crate::geom::rng::SplitMix64;

/// The tests' draws: SplitMix64, integers by `%`.
struct Rng(SplitMix64);
impl Rng {
    fn new(seed: u64) -> Self {
        Rng(SplitMix64::new(seed))
    }
    fn below(&mut self, n: u64) -> u64 {
        self.0.next_u64() % n
    }
    fn unit(&mut self) -> f64 {
        self.0.next_f64()
    }
}

type Key = [(u64, u64); 3];

fn canonical(tris: impl Iterator<Item = [[f64; 2]; 3]>) -> Vec<Key> {
    let mut out: Vec<Key> = tris
        .map(|t| {
            let k = t.map(|p| (p[0].to_bits(), p[1].to_bits()));
            let m = (0..3).min_by_key(|&i| k[i]).unwrap();
            [k[m], k[(m + 1) % 3], k[(m + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}

fn tin_key(tin: &Tin) -> Vec<Key> {
    canonical(
        tin.triangles()
            .map(|t| tin.tri_vertices(t).map(|v| tin.xy(v))),
    )
}

fn scratch_key(points: &[[f64; 3]]) -> Vec<Key> {
    let t = crate::triangulate(points, &crate::Options::default()).unwrap();
    canonical(
        t.triangles
            .iter()
            .map(|tri| tri.map(|i| [t.vertices[i as usize][0], t.vertices[i as usize][1]])),
    )
}

fn live_points(tin: &Tin) -> Vec<[f64; 3]> {
    tin.vertices().map(|v| tin.point(v)).collect()
}

fn random_points(rng: &mut Rng, n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|_| [rng.unit() * 100.0, rng.unit() * 100.0, rng.unit()])
        .collect()
}

/// Points on a small integer lattice: many cocircular quadruples and collinear triples.
fn lattice_points(rng: &mut Rng, n: usize, side: u64) -> Vec<[f64; 3]> {
    (0..n)
        .map(|_| [rng.below(side) as f64, rng.below(side) as f64, rng.unit()])
        .collect()
}

#[test]
fn insertions_match_a_triangulation_from_scratch() {
    let mut rng = Rng::new(1);
    let pts = random_points(&mut rng, 2000);
    let mut tin = Tin::from_points(&pts[..3]).unwrap();
    for &p in &pts[3..] {
        tin.insert(p).unwrap();
    }
    tin.check().unwrap();
    assert_eq!(tin.vertex_count(), 2000);
    assert_eq!(tin_key(&tin), scratch_key(&pts));
}

#[test]
fn vertices_added_first_and_inserted_later_make_the_same_tin_as_insertions() {
    // The ground filter keeps every point of a run as a vertex id and inserts some of them
    // later: the TIN must be the one `insert` makes, and a position already taken gives back
    // the vertex there (the added one stays out).
    let mut rng = Rng::new(9);
    let mut pts = lattice_points(&mut rng, 1500, 40);
    pts.splice(0..0, [[-1.0, -1.0, 0.0], [41.0, -1.0, 0.0], [20.0, 41.0, 0.0]]);
    let mut tin = Tin::from_points(&pts[..3]).unwrap();
    let ids: Vec<VertexId> = pts[3..]
        .iter()
        .map(|&p| tin.add_vertex(p).unwrap())
        .collect();
    assert_eq!(tin.vertex_count(), 3);
    let mut first = std::collections::HashMap::new();
    for (&v, p) in ids.iter().zip(&pts[3..]) {
        let got = tin.insert_vertex(v).unwrap();
        let key = (p[0].to_bits(), p[1].to_bits());
        assert_eq!(got, *first.entry(key).or_insert(v), "point {p:?}");
        assert!(tin.insert_vertex(v).is_err() || got != v);
    }
    tin.check().unwrap();
    assert_eq!(tin.vertex_count(), first.len() + 3);
    let mut direct = Tin::from_points(&pts[..3]).unwrap();
    for &p in &pts[3..] {
        direct.insert(p).unwrap();
    }
    assert_eq!(tin_key(&tin), tin_key(&direct));
}

#[test]
fn lattice_insertions_follow_the_tie_rule() {
    let mut rng = Rng::new(2);
    let pts = lattice_points(&mut rng, 3000, 40);
    let mut tin = Tin::from_points(&[[0., 0., 0.], [39., 0., 0.], [0., 39., 0.]]).unwrap();
    for &p in &pts {
        tin.insert(p).unwrap();
    }
    tin.check().unwrap();
    assert_eq!(tin_key(&tin), scratch_key(&live_points(&tin)));
}

#[test]
fn random_inserts_and_removals_stay_delaunay() {
    for (seed, lattice) in [(3, false), (4, true), (5, true)] {
        let mut rng = Rng::new(seed);
        let pts = if lattice {
            lattice_points(&mut rng, 400, 30)
        } else {
            random_points(&mut rng, 400)
        };
        let mut tin = Tin::from_points(&pts).unwrap();
        let mut ops = 0;
        while ops < 3000 {
            let live: Vec<VertexId> = tin.vertices().collect();
            if rng.below(2) == 0 && live.len() > 10 {
                let v = live[rng.below(live.len() as u64) as usize];
                tin.remove(v).unwrap();
            } else {
                let p = if lattice {
                    lattice_points(&mut rng, 1, 30)[0]
                } else {
                    random_points(&mut rng, 1)[0]
                };
                tin.insert(p).unwrap();
            }
            ops += 1;
            if ops % 250 == 0 {
                tin.check().unwrap();
                let (v, t) = tin.to_mesh();
                crate::validate::validate(&v, &t).unwrap();
                assert_eq!(tin_key(&tin), scratch_key(&live_points(&tin)), "op {ops}");
            }
        }
    }
}

#[test]
fn hull_vertices_can_be_removed() {
    let pts = [
        [0., 0., 0.],
        [10., 0., 0.],
        [10., 10., 0.],
        [0., 10., 0.],
        [5., 5., 1.],
        [5., -1., 0.],
        [11., 5., 0.],
    ];
    let mut tin = Tin::from_points(&pts).unwrap();
    for v in [5, 6, 0, 1] {
        let id = tin
            .vertices()
            .find(|&w| tin.xy(w) == [pts[v][0], pts[v][1]])
            .unwrap();
        assert!(tin.is_hull_vertex(id));
        tin.remove(id).unwrap();
        tin.check().unwrap();
        assert_eq!(tin_key(&tin), scratch_key(&live_points(&tin)));
    }
    // Three points left: removing one more would leave no triangle.
    let v = tin.vertices().next().unwrap();
    assert!(tin.remove(v).is_err());
    tin.check().unwrap();
}

#[test]
fn removed_vertices_can_be_restored() {
    let mut rng = Rng::new(6);
    let pts = random_points(&mut rng, 300);
    let mut tin = Tin::from_points(&pts).unwrap();
    let before = tin_key(&tin);
    let ids: Vec<VertexId> = tin.vertices().collect();
    for &v in ids.iter().step_by(7) {
        tin.remove(v).unwrap();
        tin.restore(v).unwrap();
    }
    tin.check().unwrap();
    assert_eq!(tin_key(&tin), before);
    assert!(tin.restore(ids[0]).is_err());
}

#[test]
fn points_outside_the_hull_extend_it() {
    let mut tin = Tin::from_points(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]).unwrap();
    let far = [
        [5., 5., 0.],
        [-3., 2., 0.],
        [2., 0., 0.],
        [3., 0., 0.],
        [-1., -1., 0.],
        [10., -2., 0.],
    ];
    for p in far {
        tin.insert(p).unwrap();
        tin.check().unwrap();
    }
    let mut all = vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]];
    all.extend(far);
    assert_eq!(tin_key(&tin), scratch_key(&all));
}

#[test]
fn matches_spade_in_general_position() {
    use spade::{DelaunayTriangulation, Point2, Triangulation as _};
    let mut rng = Rng::new(7);
    let pts = random_points(&mut rng, 500);
    let mut tin = Tin::from_points(&pts).unwrap();
    for _ in 0..1500 {
        if rng.below(3) == 0 {
            let live: Vec<VertexId> = tin.vertices().collect();
            tin.remove(live[rng.below(live.len() as u64) as usize])
                .unwrap();
        } else {
            tin.insert(random_points(&mut rng, 1)[0]).unwrap();
        }
    }
    let mut sp: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    for p in live_points(&tin) {
        sp.insert(Point2::new(p[0], p[1])).unwrap();
    }
    let theirs = canonical(sp.inner_faces().map(|f| {
        f.vertices().map(|v| {
            let p = v.position();
            [p.x, p.y]
        })
    }));
    assert_eq!(tin_key(&tin), theirs);
}

#[test]
fn interpolation_is_linear_on_triangles() {
    let pts = [[0., 0., 0.], [4., 0., 4.], [0., 4., 8.], [4., 4., 12.]];
    let mut tin = Tin::from_points(&pts).unwrap();
    // z = x + 2y everywhere.
    for p in [
        [1., 1.],
        [3., 0.5],
        [2., 2.],
        [0., 0.],
        [4., 2.],
        [0.1, 3.7],
    ] {
        let z = tin.interpolate(p).unwrap();
        assert!((z - (p[0] + 2.0 * p[1])).abs() < 1e-12, "{p:?}: {z}");
    }
    assert_eq!(tin.interpolate([5., 5.]), None);
}

#[test]
fn breaklines_become_constrained_edges() {
    let mut rng = Rng::new(8);
    let pts = random_points(&mut rng, 300);
    let mut tin = Tin::from_points(&pts).unwrap();
    let line = [[10., 10., 0.], [90., 80., 0.], [20., 90., 0.]];
    let ids = tin.insert_breakline(&line).unwrap();
    for w in ids.windows(2) {
        // The segment may be split at vertices on it; here (random points) it is not.
        let e = tin.find_edge(w[0], w[1]).expect("breakline edge present");
        assert!(tin.is_constrained(e));
    }
    tin.check().unwrap();
    // A crossing breakline is refused.
    let a = tin.insert([10., 80., 0.]).unwrap();
    let b = tin.insert([80., 10., 0.]).unwrap();
    assert!(tin.insert_segment(a, b).is_err());
    // Breakline ends cannot be removed; other vertices can, and the TIN stays valid.
    assert!(tin.remove(ids[0]).is_err());
    let others: Vec<VertexId> = tin.vertices().filter(|v| !ids.contains(v)).collect();
    for &v in others.iter().step_by(3) {
        if tin.remove(v).is_err() {
            // An end of the refused breakline's partly inserted pieces.
            continue;
        }
    }
    tin.check().unwrap();
}

#[test]
fn breakline_through_lattice_vertices_is_split() {
    let mut pts = Vec::new();
    for i in 0..10 {
        for j in 0..10 {
            pts.push([i as f64, j as f64, 0.0]);
        }
    }
    let mut tin = Tin::from_points(&pts).unwrap();
    let ids = tin.insert_breakline(&[[0., 0., 0.], [9., 9., 0.]]).unwrap();
    tin.check().unwrap();
    // Every diagonal lattice step is a constrained edge.
    for k in 0..9 {
        let a = tin
            .vertices()
            .find(|&v| tin.xy(v) == [k as f64, k as f64])
            .unwrap();
        let b = tin
            .vertices()
            .find(|&v| tin.xy(v) == [k as f64 + 1.0, k as f64 + 1.0])
            .unwrap();
        let e = tin.find_edge(a, b).expect("diagonal piece");
        assert!(tin.is_constrained(e));
    }
    assert_eq!(ids.len(), 2);
    // Points inserted on a breakline split it and keep it constrained.
    let m = tin.insert([2.5, 2.5, 0.0]).unwrap();
    tin.check().unwrap();
    let e = tin.out_edges(m);
    assert_eq!(e.iter().filter(|&&e| tin.is_constrained(e)).count(), 2);
}

#[test]
fn leave_one_out_is_exact_on_a_plane_and_leaves_the_tin_unchanged() {
    let mut rng = Rng::new(9);
    let pts: Vec<[f64; 3]> = random_points(&mut rng, 500)
        .into_iter()
        .map(|p| [p[0], p[1], 2.0 * p[0] - p[1] + 7.0])
        .collect();
    let mut tin = Tin::from_points(&pts).unwrap();
    let before = tin_key(&tin);
    let cv = tin.leave_one_out(200, 1).unwrap();
    assert_eq!(cv.tested + cv.skipped, 200);
    assert!(cv.skipped > 0 || cv.tested == 200);
    assert!(cv.max_error < 1e-9, "{cv:?}");
    assert_eq!(tin_key(&tin), before);
    tin.check().unwrap();
    // On a curved surface the errors are positive.
    let curved: Vec<[f64; 3]> = pts
        .iter()
        .map(|p| [p[0], p[1], p[0] * p[0] / 10.0])
        .collect();
    let mut tin = Tin::from_points(&curved).unwrap();
    let cv = tin.leave_one_out(100, 2).unwrap();
    assert!(cv.mean_error > 0.0 && cv.bias > 0.0, "{cv:?}");
}

#[test]
fn relayout_keeps_the_triangulation() {
    let mut rng = Rng::new(10);
    let pts = random_points(&mut rng, 400);
    let mut tin = Tin::from_points(&pts).unwrap();
    let live: Vec<VertexId> = tin.vertices().collect();
    for &v in live.iter().step_by(5) {
        tin.remove(v).unwrap();
    }
    tin.insert_breakline(&[[5.0, 5.0, 0.0], [95.0, 60.0, 0.0]])
        .unwrap();
    let before = tin_key(&tin);
    let mut order: Vec<VertexId> = tin.vertices().collect();
    order.sort_by(|a, b| tin.xy(*a)[0].total_cmp(&tin.xy(*b)[0]));
    let map = tin.relayout(&order).unwrap();
    assert_eq!(map.iter().filter(|&&m| m != u32::MAX).count(), order.len());
    tin.check().unwrap();
    assert_eq!(tin_key(&tin), before);
    assert_eq!(tin.triangle_slots(), tin.triangle_count());
    // Still editable.
    tin.insert([50.5, 50.5, 1.0]).unwrap();
    let v = tin.vertices().nth(10).unwrap();
    let _ = tin.remove(v);
    tin.check().unwrap();
    assert!(tin.relayout(&order[1..]).is_err());
}

#[test]
fn untracked_insertion_then_tracking_again() {
    let mut rng = Rng::new(11);
    let pts = random_points(&mut rng, 600);
    let mut tin = Tin::from_points(&pts[..3]).unwrap();
    tin.set_vertex_tracking(false);
    for &p in &pts[3..] {
        tin.insert(p).unwrap();
    }
    let v = tin.vertices().nth(5).unwrap();
    assert!(tin.remove(v).is_err());
    tin.set_vertex_tracking(true);
    tin.check().unwrap();
    assert_eq!(tin_key(&tin), scratch_key(&pts));
    tin.remove(v).unwrap();
    tin.check().unwrap();
}

/// `from_triangles` pairs every inner edge once and refuses non-manifold input.
#[test]
fn from_triangles_pairs_twins_and_refuses_bad_meshes() {
    let v = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [2.0, 0.5, 0.0],
    ];
    let tin = Tin::from_triangles(&v, &[[0, 1, 2], [0, 2, 3], [1, 4, 2]]).unwrap();
    let inner = tin
        .triangles()
        .flat_map(|t| (0..3).map(move |k| EdgeId(3 * t.0 + k)))
        .filter(|&e| tin.twin(e).is_some())
        .count();
    assert_eq!(inner, 4, "two inner edges, each seen from both sides");
    let e = Tin::from_triangles(&v, &[[0, 1, 2], [0, 1, 4]]).unwrap_err();
    assert!(e.to_string().contains("same direction"), "{e}");
    let e = Tin::from_triangles(&v, &[[0, 1, 2], [0, 2, 3], [2, 0, 4]]).unwrap_err();
    assert!(e.to_string().contains("3 or more"), "{e}");
    assert!(Tin::from_triangles(&v, &[[0, 1, 9]]).is_err());
}

/// The sweep's own adjacency gives the same TIN as finding the twins again.
#[test]
fn from_twins_equals_from_triangles() {
    let mut r = Rng::new(12);
    let pts: Vec<[f64; 3]> = (0..3000)
        .map(|_| [(r.below(200) as f64) * 0.5, r.unit() * 100.0, r.unit()])
        .collect();
    let (t, twins) =
        crate::triangulation::triangulate_with_twins(&pts, &[], &crate::Options::default())
            .unwrap();
    let a = Tin::from_twins(&t.vertices, &t.triangles, &twins).unwrap();
    let b = Tin::from_triangles(&t.vertices, &t.triangles).unwrap();
    a.check().unwrap();
    for e in 0..3 * t.triangles.len() as u32 {
        assert_eq!(a.twin(EdgeId(e)), b.twin(EdgeId(e)), "half-edge {e}");
    }
    let mut bad = twins.clone();
    let i = bad.iter().position(|&f| f != u32::MAX).unwrap();
    bad[i] = u32::MAX;
    assert!(Tin::from_twins(&t.vertices, &t.triangles, &bad).is_err());
}

/// A hull edge named backwards can be constrained, and splitting a constrained hull edge keeps
/// both halves constrained (found by `refine`, which splits boundary segments).
#[test]
fn constrained_hull_edge_split() {
    let pts = [
        [0.0, 0.0, 0.0],
        [4.0, 0.0, 1.0],
        [4.0, 4.0, 2.0],
        [0.0, 4.0, 3.0],
    ];
    let mut tin = Tin::from_points(&pts).unwrap();
    let v = |p: [f64; 2]| tin.vertices().find(|&v| tin.xy(v) == p).unwrap();
    let (a, b) = (v([0.0, 0.0]), v([4.0, 0.0]));
    // The hull half-edge is a → b (counter-clockwise hull): name it b → a.
    assert!(tin.find_edge(b, a).is_none());
    tin.insert_segment(b, a).unwrap();
    let e = tin.find_edge(a, b).unwrap();
    assert!(tin.is_constrained(e) && tin.twin(e).is_none());
    let m = tin.split_edge_at(e, [2.0, 0.0, 0.5]).unwrap();
    for (p, q) in [(a, m), (m, b)] {
        let h = tin.find_edge(p, q).unwrap();
        assert!(
            tin.is_constrained(h),
            "half {} – {} lost its flag",
            p.0,
            q.0
        );
    }
    // A split point that would fold a triangle over is refused, and nothing changes.
    let e = tin.find_edge(m, b).unwrap();
    assert!(tin.split_edge_at(e, [10.0, 10.0, 0.0]).is_err());
    assert_eq!(tin.vertex_count(), 5);
}
