//! `--no-flat-triangles`: no triangle lying flat on one contour line (Herva 2009, section 4.2.2).
//!
//! Contour lines given as breaklines have one `z` along their whole length. A triangle with two
//! edges on the same contour line, or more generally with its three corners on one such line, is
//! flat at exactly the contour's height, so the contour at that height is no longer a line but a
//! whole triangle: contours derived from the TIN become ambiguous. Herva rules such triangles out
//! "during the apex searching and edge-swap phase", i.e. he picks another triangulation of the
//! same vertices rather than adding points. This post-pass does the same on a finished
//! triangulation: for every flat triangle it flips one of its unconstrained edges, when
//!
//! * the quadrilateral of the two triangles across that edge is strictly convex (both new
//!   triangles strictly counter-clockwise, decided by exact `orient`), so the result is still a
//!   triangulation, and
//! * neither new triangle is flat,
//!
//! choosing, among the possible flips, the one whose worse new triangle is the best shaped (a
//! floating-point heuristic; it only picks between valid results). Each flip removes at least one
//! flat triangle and creates none, so the pass ends; passes repeat while they flip something,
//! because a flip can open a flip for a neighbour. No vertex is added (a Steiner point would need a
//! `z` that nothing measured), so a flat triangle with no such flip stays (a closed contour around
//! nothing but its own vertices, or one whose other edges are all constrained or on the hull); the
//! count is reported.
//!
//! The result is a valid constrained triangulation with every constraint kept, but deliberately
//! not Delaunay where it flipped: validate it with
//! [`crate::validate::validate_cdt_with`] and `delaunay: false`.
//!
//! *Flat* here: the three corners have exactly the same (known) `z` and are all vertices of one
//! breakline (one line id among the constraint edges at each corner). Giving every constraint the
//! same line id widens the rule to "three breakline vertices at the same height", which also
//! removes triangles that bridge two different contour lines of one level.

use crate::geom::predicates::{Orientation, orient};

/// No twin (hull edge).
const NONE: u32 = u32::MAX;

/// What [`remove_flat_triangles`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FlatStats {
    /// Flat triangles before.
    pub flat: u64,
    /// Edges flipped.
    pub flips: u64,
    /// Flat triangles left (no valid flip).
    pub remaining: u64,
}

/// Removes flat triangles (module docs) from the triangulation `triangles` (counter-clockwise
/// index triples into `vertices`) by flipping unconstrained edges in place.
///
/// `constraints` are the constrained edges (vertex index pairs, either direction) and `lines`
/// the breakline each one lies on (same length as `constraints`).
///
/// # Panics
/// If `lines` and `constraints` differ in length or an index is out of range.
pub fn remove_flat_triangles(
    vertices: &[[f64; 3]],
    triangles: &mut [[u32; 3]],
    constraints: &[[u32; 2]],
    lines: &[u32],
) -> FlatStats {
    assert_eq!(constraints.len(), lines.len(), "one line id per constraint");
    let mut m = Flat::new(vertices, triangles, constraints, lines);
    let mut stats = FlatStats {
        flat: m.count_flat(),
        ..FlatStats::default()
    };
    loop {
        let mut flipped = 0;
        for t in 0..m.tris.len() as u32 {
            if m.is_flat(m.tris[t as usize]) && m.fix(t) {
                flipped += 1;
            }
        }
        stats.flips += flipped;
        if flipped == 0 {
            break;
        }
    }
    stats.remaining = m.count_flat();
    triangles.copy_from_slice(&m.tris);
    stats
}

/// Number of flat triangles (module docs) in a triangulation.
pub fn count_flat_triangles(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    constraints: &[[u32; 2]],
    lines: &[u32],
) -> u64 {
    Flat::new(vertices, triangles, constraints, lines).count_flat()
}

struct Flat<'a> {
    vertices: &'a [[f64; 3]],
    tris: Vec<[u32; 3]>,
    /// Twin of half-edge `3t + k` (edge `tris[t][k] → tris[t][k + 1]`), or [`NONE`].
    twin: Vec<u32>,
    /// Sorted undirected keys of the constrained edges.
    fixed: Vec<u64>,
    /// Lines at each vertex: `vline[vstart[v]..vstart[v + 1]]`, sorted.
    vstart: Vec<u32>,
    vline: Vec<u32>,
}

fn key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

impl<'a> Flat<'a> {
    fn new(
        vertices: &'a [[f64; 3]],
        triangles: &[[u32; 3]],
        constraints: &[[u32; 2]],
        lines: &[u32],
    ) -> Self {
        let mut fixed: Vec<u64> = constraints.iter().map(|c| key(c[0], c[1])).collect();
        fixed.sort_unstable();
        fixed.dedup();
        let mut at: Vec<(u32, u32)> = constraints
            .iter()
            .zip(lines)
            .flat_map(|(c, &l)| [(c[0], l), (c[1], l)])
            .collect();
        at.sort_unstable();
        at.dedup();
        let mut vstart = vec![0u32; vertices.len() + 1];
        for &(v, _) in &at {
            vstart[v as usize + 1] += 1;
        }
        for v in 0..vertices.len() {
            vstart[v + 1] += vstart[v];
        }
        let vline = at.into_iter().map(|(_, l)| l).collect();
        let tris = triangles.to_vec();
        let twin = twins(&tris);
        Flat {
            vertices,
            tris,
            twin,
            fixed,
            vstart,
            vline,
        }
    }

    fn lines_at(&self, v: u32) -> &[u32] {
        &self.vline[self.vstart[v as usize] as usize..self.vstart[v as usize + 1] as usize]
    }

    fn is_flat(&self, [a, b, c]: [u32; 3]) -> bool {
        let z = |v: u32| self.vertices[v as usize][2];
        if z(a).is_nan() || z(a) != z(b) || z(a) != z(c) {
            return false;
        }
        let (lb, lc) = (self.lines_at(b), self.lines_at(c));
        self.lines_at(a)
            .iter()
            .any(|l| lb.binary_search(l).is_ok() && lc.binary_search(l).is_ok())
    }

    fn count_flat(&self) -> u64 {
        self.tris.iter().filter(|&&t| self.is_flat(t)).count() as u64
    }

    fn xy(&self, v: u32) -> [f64; 2] {
        [self.vertices[v as usize][0], self.vertices[v as usize][1]]
    }

    /// Flips the best valid edge of flat triangle `t`; returns whether it did.
    fn fix(&mut self, t: u32) -> bool {
        let mut best: Option<(f64, u32)> = None;
        for k in 0..3 {
            let e = 3 * t + k;
            if let Some(score) = self.flip_score(e)
                && best.is_none_or(|(s, _)| score > s)
            {
                best = Some((score, e));
            }
        }
        match best {
            Some((_, e)) => {
                self.flip(e);
                true
            }
            None => false,
        }
    }

    /// The quadrilateral across half-edge `e`: `(a, b, c, d)` with `e = a → b`, `c` its apex and
    /// `d` the apex across; `None` on the hull.
    fn quad(&self, e: u32) -> Option<(u32, u32, u32, u32, u32)> {
        let f = self.twin[e as usize];
        if f == NONE {
            return None;
        }
        let t = self.tris[(e / 3) as usize];
        let k = (e % 3) as usize;
        let u = self.tris[(f / 3) as usize];
        let m = (f % 3) as usize;
        Some((t[k], t[(k + 1) % 3], t[(k + 2) % 3], u[(m + 2) % 3], f))
    }

    /// If flipping `e` is allowed (unconstrained, convex, no new flat triangle), a shape score of
    /// the result (higher is better).
    fn flip_score(&self, e: u32) -> Option<f64> {
        let (a, b, c, d, _) = self.quad(e)?;
        if self.fixed.binary_search(&key(a, b)).is_ok() {
            return None;
        }
        let (pa, pb, pc, pd) = (self.xy(a), self.xy(b), self.xy(c), self.xy(d));
        if orient(pc, pa, pd) != Orientation::CounterClockwise
            || orient(pd, pb, pc) != Orientation::CounterClockwise
        {
            return None;
        }
        if self.is_flat([c, a, d]) || self.is_flat([d, b, c]) {
            return None;
        }
        Some(shape(pc, pa, pd).min(shape(pd, pb, pc)))
    }

    /// Flips half-edge `e` (`a → b` in `(a, b, c)`, twin in `(b, a, d)`) to `c - d`:
    /// triangles `(c, a, d)` and `(d, b, c)`.
    fn flip(&mut self, e: u32) {
        let (a, b, c, d, f) = self.quad(e).expect("flip of a hull edge");
        let (t, u) = (e / 3, f / 3);
        let (k, m) = (e % 3, f % 3);
        // Outer half-edges: b→c, c→a in t; a→d, d→b in u.
        let tb = self.twin[(3 * t + (k + 1) % 3) as usize];
        let tc = self.twin[(3 * t + (k + 2) % 3) as usize];
        let ua = self.twin[(3 * u + (m + 1) % 3) as usize];
        let ub = self.twin[(3 * u + (m + 2) % 3) as usize];
        self.tris[t as usize] = [c, a, d];
        self.tris[u as usize] = [d, b, c];
        let set = |tw: &mut Vec<u32>, h: u32, o: u32| {
            tw[h as usize] = o;
            if o != NONE {
                tw[o as usize] = h;
            }
        };
        set(&mut self.twin, 3 * t, tc); // c→a
        set(&mut self.twin, 3 * t + 1, ua); // a→d
        set(&mut self.twin, 3 * t + 2, 3 * u + 2); // d→c with c→d
        set(&mut self.twin, 3 * u, ub); // d→b
        set(&mut self.twin, 3 * u + 1, tb); // b→c
    }
}

/// Twin half-edges by sorting directed edge keys.
fn twins(tris: &[[u32; 3]]) -> Vec<u32> {
    let mut dir: Vec<(u64, u32)> = Vec::with_capacity(3 * tris.len());
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            dir.push(((u64::from(a) << 32) | u64::from(b), (3 * t + k) as u32));
        }
    }
    dir.sort_unstable();
    let mut twin = vec![NONE; dir.len()];
    for &(w, h) in &dir {
        let rev = w.rotate_right(32);
        if let Ok(i) = dir.binary_search_by_key(&rev, |e| e.0) {
            twin[h as usize] = dir[i].1;
        }
    }
    twin
}

/// Twice the area over the longest squared edge (0 for degenerate, about 0.87 for equilateral).
fn shape(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let d2 = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
    let area2 = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
    area2 / d2(a, b).max(d2(b, c)).max(d2(c, a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validate::{CdtCheck, validate_cdt_with};

    /// A contour at z = 10 bending sharply at v = (2, 1): u = (0, 0), v, w = (4, 0). Below it a
    /// point at z = 5, above it one at z = 15, and the flat triangle (u, w, v) in the bend.
    type Mesh = (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<[u32; 2]>);

    fn bend() -> Mesh {
        let v = vec![
            [0., 0., 10.], // 0 u
            [2., 1., 10.], // 1 v
            [4., 0., 10.], // 2 w
            [2., -3., 5.], // 3 below
            [2., 4., 15.], // 4 above
        ];
        let t = vec![[0, 2, 1], [0, 3, 2], [0, 1, 4], [1, 2, 4]];
        (v, t, vec![[0, 1], [1, 2]])
    }

    #[test]
    fn flips_the_flat_triangle_away() {
        let (v, mut t, c) = bend();
        let check = CdtCheck {
            convex_hull: true,
            delaunay: false,
        };
        let segs = [[[0., 0.], [2., 1.]], [[2., 1.], [4., 0.]]];
        validate_cdt_with(&v, &t, &segs, &check).unwrap();
        assert_eq!(count_flat_triangles(&v, &t, &c, &[7, 7]), 1);
        // Different lines: not flat by the same-line rule.
        assert_eq!(count_flat_triangles(&v, &t, &c, &[7, 8]), 0);
        let s = remove_flat_triangles(&v, &mut t, &c, &[7, 7]);
        assert_eq!(
            s,
            FlatStats {
                flat: 1,
                flips: 1,
                remaining: 0
            }
        );
        assert_eq!(count_flat_triangles(&v, &t, &c, &[7, 7]), 0);
        validate_cdt_with(&v, &t, &segs, &check).unwrap();
        assert!(t.contains(&[1, 0, 3]) || t.contains(&[3, 1, 0]) || t.contains(&[0, 3, 1]));
    }

    #[test]
    fn unfixable_flat_triangle_stays() {
        // The bend alone: the flat triangle's third edge is on the hull.
        let v = vec![[0., 0., 10.], [2., 1., 10.], [4., 0., 10.], [2., 4., 15.]];
        let mut t = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3]];
        let s = remove_flat_triangles(&v, &mut t, &[[0, 1], [1, 2]], &[0, 0]);
        assert_eq!(
            s,
            FlatStats {
                flat: 1,
                flips: 0,
                remaining: 1
            }
        );
        // A flip that would make another flat triangle is refused: the point below on the contour.
        let (mut v, mut t, c) = bend();
        v[3][2] = 10.0;
        let c2 = [c[0], c[1], [0, 3]];
        let s = remove_flat_triangles(&v, &mut t, &c2, &[0, 0, 0]);
        assert_eq!(s.flips, 0);
        assert_eq!(s.remaining, s.flat);
    }

    #[test]
    fn twins_are_mutual() {
        let (_, t, _) = bend();
        let tw = twins(&t);
        for (h, &o) in tw.iter().enumerate() {
            if o != NONE {
                assert_eq!(tw[o as usize], h as u32);
            }
        }
        assert_eq!(tw.iter().filter(|&&o| o == NONE).count(), 4);
    }
}
