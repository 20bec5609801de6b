//! The refinement loop of [`super::refine`]: the domain's regions, the queues, segment splits,
//! centre insertions and the straight walk.

use super::{Bad, Encroached, Queue, RefineOptions, RefineStats, Refined, VertexKind, Walk};
use crate::error::{Error, Result};
use crate::geom::predicates::{Orientation, orient};
use crate::tin::{EdgeId, Tin, TriId, VertexId};
use std::collections::HashMap;

const NONE: u32 = u32::MAX;

/// Which regions between constrained edges are refined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Domain {
    /// Those inside the input mesh.
    Mesh,
    /// Those not reached from an unconstrained hull edge (Triangle's `-p`).
    Hull,
}

pub(super) struct Refiner<'a> {
    tin: Tin,
    surface: super::Surface<'a>,
    /// Per triangle slot: is it in the domain?
    inside: Vec<bool>,
    /// Per vertex id.
    kind: Vec<VertexKind>,
    /// Per vertex id: the input segment a segment vertex lies on, else `NONE`.
    seg_of: Vec<u32>,
    /// Input segments (vertex ids of their ends), and their index by sorted ends.
    segs: Vec<[VertexId; 2]>,
    seg_index: HashMap<(u32, u32), u32>,
    /// cos² of the angle bound; Üngör's off-centre constant; the lens test's `(2 cos² − 1)²`.
    good: f64,
    off: f64,
    lens: f64,
    max_area: f64,
    max_steiner: u64,
    /// The angle bound in degrees.
    bound: f64,
    queue: Queue,
    enc: Vec<Encroached>,
    touched: Vec<TriId>,
    stats: RefineStats,
}

impl<'a> Refiner<'a> {
    pub(super) fn new(
        mut tin: Tin,
        surface: super::Surface<'a>,
        o: &RefineOptions,
        stats: RefineStats,
    ) -> Refiner<'a> {
        let n = tin.vertex_slots();

        let mut seg_index = HashMap::new();
        let mut segs = Vec::new();
        for t in tin.triangles().collect::<Vec<_>>() {
            for e in [t.edge(), t.edge().next(), t.edge().prev()] {
                let (a, b) = (tin.org(e), tin.dst(e));
                if tin.is_constrained(e) && a.0 < b.0 {
                    seg_index.insert((a.0, b.0), segs.len() as u32);
                    segs.push([a, b]);
                }
            }
        }
        let cos = o.min_angle.to_radians().cos();
        let good = cos * cos;
        tin.record_touched(true);
        Refiner {
            inside: vec![false; tin.triangle_slots()],
            kind: vec![VertexKind::Input; n],
            seg_of: vec![NONE; n],
            segs,
            seg_index,
            good,
            off: if cos >= 1.0 {
                0.0
            } else {
                0.475 * ((1.0 + cos) / (1.0 - cos)).sqrt()
            },
            lens: (2.0 * good - 1.0) * (2.0 * good - 1.0),
            max_area: o.max_area.unwrap_or(f64::INFINITY),
            bound: o.min_angle,
            max_steiner: o
                .max_steiner
                .unwrap_or(20 * stats.input_vertices + 1_000_000),
            queue: Queue::new(),
            enc: Vec::new(),
            touched: Vec::new(),
            stats,
            surface,
            tin,
        }
    }

    /// Marks the regions between constrained edges in or out of the domain, then queues what
    /// needs work.
    pub(super) fn classify(&mut self, domain: Domain) {
        let slots = self.tin.triangle_slots();
        let mut seen = vec![false; slots];
        let mut stack = Vec::new();
        for s in 0..slots as u32 {
            if !self.tin.is_live(TriId(s)) || seen[s as usize] {
                continue;
            }
            let mut region = Vec::new();
            seen[s as usize] = true;
            stack.push(TriId(s));
            while let Some(t) = stack.pop() {
                region.push(t);
                for e in [t.edge(), t.edge().next(), t.edge().prev()] {
                    if self.tin.is_constrained(e) {
                        continue;
                    }
                    if let Some(f) = self.tin.twin(e)
                        && !seen[f.tri().0 as usize]
                    {
                        seen[f.tri().0 as usize] = true;
                        stack.push(f.tri());
                    }
                }
            }
            let inside = match domain {
                Domain::Mesh => {
                    let best = region
                        .iter()
                        .copied()
                        .max_by(|&a, &b| self.area(a).total_cmp(&self.area(b)))
                        .expect("a region has a triangle");
                    let [a, b, c] = self.tin.tri_vertices(best).map(|v| self.tin.xy(v));
                    let centroid = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
                    self.surface.triangle_at(centroid).is_some()
                }
                Domain::Hull => !region.iter().any(|t| {
                    [t.edge(), t.edge().next(), t.edge().prev()]
                        .into_iter()
                        .any(|e| self.tin.twin(e).is_none() && !self.tin.is_constrained(e))
                }),
            };
            for t in region {
                self.inside[t.0 as usize] = inside;
            }
        }
        let all: Vec<TriId> = self.tin.triangles().collect();
        self.assess(&all);
        self.tin.take_touched(&mut Vec::new());
    }

    /// The domain's area: its triangles' areas added up.
    pub(super) fn domain_area(&self) -> f64 {
        self.tin
            .triangles()
            .filter(|t| self.inside[t.0 as usize])
            .map(|t| self.area(t))
            .sum()
    }

    /// The input's vertices.
    pub(super) fn input_vertices(&self) -> u64 {
        self.stats.input_vertices
    }

    /// The Steiner points allowed.
    pub(super) fn max_steiner(&self) -> u64 {
        self.max_steiner
    }

    pub(super) fn run(&mut self) -> Result<()> {
        loop {
            self.split_encroached()?;
            let Some(bad) = self.queue.pop() else {
                return Ok(());
            };
            // (Still there, so still bad: the test depends on the triangle's vertices only.)
            let Some(t) = self.current(&bad) else {
                continue;
            };
            self.fix_triangle(t, bad)?;
            let steiner = self.stats.free_points + self.stats.segment_points;
            if steiner > self.max_steiner {
                return Err(Error::Refine(self.stopped(steiner)));
            }
        }
    }

    /// Why the run stopped at `steiner` points: the area bound's share, or the angle bound.
    fn stopped(&self, steiner: u64) -> String {
        let head = format!("stopped after {steiner} Steiner points (--max-steiner)");
        if self.max_area.is_finite() {
            let t = super::triangles_implied(self.domain_area(), self.max_area);
            format!(
                "{head}: --max-area {} asks for at least {t:.0} triangles (the domain's area / \
                 max-area) and the angle bound of {} degrees for more near small input angles; \
                 give a larger --max-area or --max-steiner",
                self.max_area, self.bound
            )
        } else {
            format!(
                "{head}: the angle bound of {} degrees cannot be met here (input angles too \
                 small, or a long thin domain); give a smaller --min-angle or a larger \
                 --max-steiner",
                self.bound
            )
        }
    }

    /// The live triangle a queue entry stands for, if its slot still holds it.
    fn current(&self, bad: &Bad) -> Option<TriId> {
        let t = TriId(bad.slot);
        (self.tin.is_live(t)
            && self.inside[t.0 as usize]
            && self.tin.tri_vertices(t).map(|v| v.0) == bad.ids)
            .then_some(t)
    }

    /// Queues `t` again (after an operation that did not touch it).
    fn requeue(&mut self, bad: Bad) {
        if let Some(t) = self.current(&bad)
            && let Some((len2, _)) = self.quality(t)
        {
            self.queue.push(len2, bad);
        }
    }

    fn area(&self, t: TriId) -> f64 {
        let [a, b, c] = self.tin.tri_vertices(t).map(|v| self.tin.xy(v));
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    }

    /// `Some((squared length of its shortest edge, which edge 0..3))` when `t` must be split.
    fn quality(&self, t: TriId) -> Option<(f64, usize)> {
        let v = self.tin.tri_vertices(t);
        let p = v.map(|v| self.tin.xy(v));
        let (cos2, area, l, k) = shape(p);
        if area > self.max_area {
            return Some((l, k));
        }
        if cos2 <= self.good {
            return None;
        }
        // Miller, Pav and Walkington (as Triangle): two points on segments sharing an end, at
        // the same distance from it, joined by the shortest edge: leave the triangle.
        let (a, b) = (v[k], v[(k + 1) % 3]);
        let (sa, sb) = (self.seg_of[a.0 as usize], self.seg_of[b.0 as usize]);
        if sa != NONE && sb != NONE && sa != sb {
            let e = t.edge();
            let e = [e, e.next(), e.prev()][k];
            if !self.tin.is_constrained(e) {
                let (s, r) = (self.segs[sa as usize], self.segs[sb as usize]);
                let join = [s[0], s[1]].into_iter().find(|j| r.contains(j));
                if let Some(j) = join {
                    let pj = self.tin.xy(j);
                    let dist = |q: [f64; 2]| (q[0] - pj[0]).powi(2) + (q[1] - pj[1]).powi(2);
                    let (d1, d2) = (dist(p[k]), dist(p[(k + 1) % 3]));
                    let (u, w) = (
                        [p[k][0] - pj[0], p[k][1] - pj[1]],
                        [p[(k + 1) % 3][0] - pj[0], p[(k + 1) % 3][1] - pj[1]],
                    );
                    // Only at an input angle below 60° (cos² > 1/4 with a positive cosine).
                    let dot = u[0] * w[0] + u[1] * w[1];
                    let small = dot > 0.0 && dot * dot > 0.25 * d1 * d2;
                    if small && d1 < 1.001 * d2 && d1 > 0.999 * d2 {
                        return None;
                    }
                }
            }
        }
        Some((l, k))
    }

    /// Queues the bad triangles among `tris` and checks their constrained edges.
    fn assess(&mut self, tris: &[TriId]) {
        for &t in tris {
            if !self.tin.is_live(t) || !self.inside[t.0 as usize] {
                continue;
            }
            if let Some((len2, _)) = self.quality(t) {
                let ids = self.tin.tri_vertices(t).map(|v| v.0);
                self.queue.push(len2, Bad { ids, slot: t.0 });
            }
            for e in [t.edge(), t.edge().next(), t.edge().prev()] {
                if self.tin.is_constrained(e) && self.encroached_by(e, self.tin.org(e.prev())) {
                    self.enc.push(Encroached {
                        a: self.tin.org(e),
                        b: self.tin.dst(e),
                        hint: e,
                        force: false,
                    });
                }
            }
        }
    }

    /// Does `v` see the edge `e` under an angle of at least `180° − 2 · min_angle` (Triangle's
    /// diametral lens; floating point)?
    fn encroached_by(&self, e: EdgeId, v: VertexId) -> bool {
        let (a, b, p) = (
            self.tin.xy(self.tin.org(e)),
            self.tin.xy(self.tin.dst(e)),
            self.tin.xy(v),
        );
        let (u, w) = ([a[0] - p[0], a[1] - p[1]], [b[0] - p[0], b[1] - p[1]]);
        let dot = u[0] * w[0] + u[1] * w[1];
        dot < 0.0
            && dot * dot >= self.lens * (u[0] * u[0] + u[1] * u[1]) * (w[0] * w[0] + w[1] * w[1])
    }

    /// Is a subsegment encroached by the apex of a domain triangle beside it?
    fn is_encroached(&self, e: EdgeId) -> bool {
        let side = |e: EdgeId| {
            self.inside[e.tri().0 as usize] && self.encroached_by(e, self.tin.org(e.prev()))
        };
        side(e) || self.tin.twin(e).is_some_and(side)
    }

    /// Splits every queued subsegment that is (still) encroached.
    fn split_encroached(&mut self) -> Result<bool> {
        let mut split_any = false;
        while let Some(s) = self.enc.pop() {
            let e = s.hint;
            let e = if self.tin.is_live(e.tri()) && self.tin.org(e) == s.a && self.tin.dst(e) == s.b
            {
                e
            } else if let Some(e) = self.tin.find_edge(s.a, s.b) {
                e
            } else {
                continue;
            };
            if !self.tin.is_constrained(e) || !(s.force || self.is_encroached(e)) {
                continue;
            }
            split_any |= self.split_segment(e)?;
        }
        Ok(split_any)
    }

    /// The input segment the subsegment `a – b` lies on.
    fn segment_of(&mut self, a: VertexId, b: VertexId) -> u32 {
        for v in [a, b] {
            let s = self.seg_of[v.0 as usize];
            if s != NONE {
                return s;
            }
        }
        let key = (a.0.min(b.0), a.0.max(b.0));
        if let Some(&s) = self.seg_index.get(&key) {
            return s;
        }
        self.segs.push([a, b]);
        self.seg_index.insert(key, self.segs.len() as u32 - 1);
        self.segs.len() as u32 - 1
    }

    /// Splits the subsegment `e` (see the module docs); `false` if it is too short to split.
    fn split_segment(&mut self, e: EdgeId) -> Result<bool> {
        let (a, b) = (self.tin.org(e), self.tin.dst(e));
        let s = self.segment_of(a, b);
        // Does another segment meet `a` (or `b`) in a domain triangle beside `e`?
        let mut acute = [false, false];
        let twin = self.tin.twin(e);
        if self.inside[e.tri().0 as usize] {
            acute[0] |= self.tin.is_constrained(e.prev());
            acute[1] |= self.tin.is_constrained(e.next());
        }
        if let Some(f) = twin
            && self.inside[f.tri().0 as usize]
        {
            acute[0] |= self.tin.is_constrained(f.next());
            acute[1] |= self.tin.is_constrained(f.prev());
        }
        let (pa, pb) = (self.tin.point(a), self.tin.point(b));
        let mut split = 0.5;
        if acute[0] != acute[1] {
            let length = ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2)).sqrt();
            let mut p2 = 1.0f64;
            while length > 3.0 * p2 {
                p2 *= 2.0;
            }
            while length < 1.5 * p2 {
                p2 *= 0.5;
            }
            split = p2 / length;
            if acute[1] {
                split = 1.0 - split;
            }
        }
        let p = [
            pa[0] + split * (pb[0] - pa[0]),
            pa[1] + split * (pb[1] - pa[1]),
            pa[2] + split * (pb[2] - pa[2]),
        ];
        if [p[0], p[1]] == [pa[0], pa[1]] || [p[0], p[1]] == [pb[0], pb[1]] {
            self.stats.unsplittable += 1;
            return Ok(false);
        }
        let left = self.inside[e.tri().0 as usize];
        let right = twin.is_some_and(|f| self.inside[f.tri().0 as usize]);
        let Ok(v) = self.tin.split_edge_at(e, p) else {
            self.stats.unsplittable += 1;
            return Ok(false);
        };
        self.new_vertex(VertexKind::Segment, s)?;
        self.stats.segment_points += 1;
        // The star of v: counter-clockwise from v → b to v → a is the left side of a → b.
        self.grow();
        let star = self.tin.out_edges(v);
        let start = star
            .iter()
            .position(|&f| self.tin.dst(f) == b)
            .ok_or_else(|| Error::Internal("split segment lost its end".into()))?;
        let mut side = left;
        for i in 0..star.len() {
            let f = star[(start + i) % star.len()];
            if self.tin.dst(f) == a {
                side = right;
            }
            self.inside[f.tri().0 as usize] = side;
        }
        self.after_change();
        Ok(true)
    }

    /// Records a new vertex. When the mesh's arrays are about to double (the vertex count at a
    /// power of two), checks that an address-space limit leaves room for it.
    fn new_vertex(&mut self, kind: VertexKind, seg: u32) -> Result<()> {
        let n = self.kind.len();
        if n >= 1 << 12 && n.is_power_of_two() {
            super::room(n as u64 * super::GROWTH_BYTES, "the growing mesh")?;
        }
        self.kind.push(kind);
        self.seg_of.push(seg);
        Ok(())
    }

    /// Vertices of the mesh so far (input and Steiner points).
    pub(super) fn vertex_count(&self) -> usize {
        self.kind.len()
    }

    fn grow(&mut self) {
        let n = self.tin.triangle_slots();
        if self.inside.len() < n {
            self.inside.resize(n, false);
        }
    }

    /// Assesses the triangles the last operation touched (and those already in `self.touched`).
    fn after_change(&mut self) {
        let mut t = std::mem::take(&mut self.touched);
        self.tin.take_touched(&mut t);
        t.sort_unstable();
        t.dedup();
        self.assess(&t);
        t.clear();
        self.touched = t;
    }

    /// Inserts the centre of bad triangle `t`, or splits what is in its way.
    fn fix_triangle(&mut self, t: TriId, bad: Bad) -> Result<()> {
        let c = self.centre(t);
        let target = match self.walk(t, c) {
            Walk::Lost => {
                self.stats.unsplittable += 1;
                return Ok(());
            }
            Walk::Blocked(e) => {
                if self.split_segment(e)? {
                    self.requeue(bad);
                }
                return Ok(());
            }
            Walk::Inside(s) => s,
        };
        // A centre exactly on a constrained edge: split that subsegment instead.
        for e in [target.edge(), target.edge().next(), target.edge().prev()] {
            let (a, b) = (self.tin.xy(self.tin.org(e)), self.tin.xy(self.tin.dst(e)));
            if self.tin.is_constrained(e) && orient(a, b, c) == Orientation::Collinear {
                if self.split_segment(e)? {
                    self.requeue(bad);
                }
                return Ok(());
            }
        }
        // Its height comes from the input surface when the mesh is finished (`finish`).
        let Ok(v) = self.tin.insert_in_triangle(target, [c[0], c[1], 0.0]) else {
            self.stats.unsplittable += 1;
            return Ok(());
        };
        self.new_vertex(VertexKind::Free, NONE)?;
        self.grow();
        let mut touched = Vec::new();
        self.tin.take_touched(&mut touched);
        for &s in &touched {
            self.inside[s.0 as usize] = true;
        }
        // Subsegments the new point encroaches: take it out again and split them.
        // (Every triangle of v's star was touched; the edge opposite v is on the cavity's rim.)
        let mut hit = Vec::new();
        for &s in &touched {
            if !self.tin.is_live(s) {
                continue;
            }
            let e = s.edge();
            let Some(f) = [e, e.next(), e.prev()]
                .into_iter()
                .find(|&f| self.tin.org(f.prev()) == v)
            else {
                continue;
            };
            if self.tin.is_constrained(f) && self.encroached_by(f, v) {
                hit.push(Encroached {
                    a: self.tin.org(f),
                    b: self.tin.dst(f),
                    hint: f,
                    force: true,
                });
            }
        }
        if !hit.is_empty() {
            self.tin.remove(v)?;
            self.grow();
            touched.clear();
            self.tin.take_touched(&mut touched);
            for &s in &touched {
                self.inside[s.0 as usize] = true;
            }
            self.stats.rejected_centres += 1;
            // The hole is filled with the triangles of before, `t` among them: queued again.
            self.touched = touched;
            self.after_change();
            hit.sort_unstable_by_key(|h| (h.a.0, h.b.0));
            hit.dedup_by_key(|h| (h.a.0, h.b.0));
            self.enc.extend(hit);
            if !self.split_encroached()? {
                self.stats.unsplittable += 1;
            }
            return Ok(());
        }
        self.stats.free_points += 1;
        self.touched = touched;
        self.after_change();
        Ok(())
    }

    /// The circumcentre of `t`, or Üngör's off-centre on its shortest edge when nearer (the
    /// formulas of Triangle 1.6's `findcircumcenter`).
    fn centre(&self, t: TriId) -> [f64; 2] {
        let [o, d, a] = self.tin.tri_vertices(t).map(|v| self.tin.xy(v));
        let (xdo, ydo, xao, yao) = (d[0] - o[0], d[1] - o[1], a[0] - o[0], a[1] - o[1]);
        let dodist = xdo * xdo + ydo * ydo;
        let aodist = xao * xao + yao * yao;
        let dadist = (d[0] - a[0]).powi(2) + (d[1] - a[1]).powi(2);
        let denominator = 0.5 / (xdo * yao - xao * ydo);
        let mut dx = (yao * dodist - ydo * aodist) * denominator;
        let mut dy = (xdo * aodist - xao * dodist) * denominator;
        let k = self.off;
        if k > 0.0 {
            if dodist < aodist && dodist < dadist {
                let (x, y) = (0.5 * xdo - k * ydo, 0.5 * ydo + k * xdo);
                if x * x + y * y < dx * dx + dy * dy {
                    (dx, dy) = (x, y);
                }
            } else if aodist < dadist {
                let (x, y) = (0.5 * xao + k * yao, 0.5 * yao - k * xao);
                if x * x + y * y < dx * dx + dy * dy {
                    (dx, dy) = (x, y);
                }
            } else {
                let (ex, ey) = (a[0] - d[0], a[1] - d[1]);
                let (x, y) = (0.5 * ex - k * ey, 0.5 * ey + k * ex);
                if x * x + y * y < (dx - xdo).powi(2) + (dy - ydo).powi(2) {
                    (dx, dy) = (xdo + x, ydo + y);
                }
            }
        }
        [o[0] + dx, o[1] + dy]
    }

    /// Straight walk from triangle `t` to `c`, stopping at constrained edges.
    fn walk(&self, t: TriId, c: [f64; 2]) -> Walk {
        let tin = &self.tin;
        let beyond =
            |e: EdgeId| orient(tin.xy(tin.org(e)), tin.xy(tin.dst(e)), c) == Orientation::Clockwise;
        let edges = [t.edge(), t.edge().next(), t.edge().prev()];
        let out: Vec<EdgeId> = edges.into_iter().filter(|&e| beyond(e)).collect();
        let mut g = match out[..] {
            [] => return Walk::Inside(t),
            [e] => e,
            _ => return Walk::Lost,
        };
        // The ray from p (opposite g) to c; g's origin is on its right, its end on its left.
        let p = tin.xy(tin.org(g.prev()));
        for _ in 0..1 << 24 {
            if tin.is_constrained(g) {
                return Walk::Blocked(g);
            }
            let Some(f) = tin.twin(g) else {
                return Walk::Lost;
            };
            if !beyond(f.next()) && !beyond(f.prev()) {
                return Walk::Inside(f.tri());
            }
            let x = tin.xy(tin.org(f.prev()));
            g = match orient(p, c, x) {
                Orientation::CounterClockwise => f.next(),
                Orientation::Clockwise => f.prev(),
                Orientation::Collinear => return Walk::Lost,
            };
        }
        Walk::Lost
    }

    /// The domain's triangles and their vertices, renumbered in vertex-id order.
    ///
    /// The heights of the Steiner points and the triangle pass (renumbering, constrained edges,
    /// statistics) run side by side (`rayon::join`); neither depends on the thread count.
    pub(super) fn finish(self) -> Refined {
        let tin = &self.tin;
        let tris: Vec<TriId> = tin
            .triangles()
            .filter(|t| self.inside[t.0 as usize])
            .collect();
        let mut used = vec![false; tin.vertex_slots()];
        for &t in &tris {
            for v in tin.tri_vertices(t) {
                used[v.0 as usize] = true;
            }
        }
        let mut remap = vec![NONE; used.len()];
        let mut out = Refined::default();
        let mut free = Vec::new();
        for (i, &u) in used.iter().enumerate() {
            if u {
                remap[i] = out.vertices.len() as u32;
                if self.kind[i] == VertexKind::Free {
                    free.push(out.vertices.len());
                }
                out.vertices.push(tin.point(VertexId(i as u32)));
                out.kinds.push(self.kind[i]);
            }
        }
        // Heights of the points inside, on the input surface, in one sweep of short walks.
        let xy: Vec<[f64; 2]> = free
            .iter()
            .map(|&i| [out.vertices[i][0], out.vertices[i][1]])
            .collect();
        let (z, (triangles, constrained, stats)) = rayon::join(
            || super::surface::heights(&self.surface, &xy),
            || self.output_triangles(&tris, &remap),
        );
        for (&i, z) in free.iter().zip(z) {
            out.vertices[i][2] = z;
        }
        out.triangles = triangles;
        out.constrained = constrained;
        out.stats = stats;
        out.stats.vertices = out.vertices.len() as u64;
        out
    }

    /// The triangles `tris` renumbered by `remap`, the constrained edges among their sides (lower
    /// index first, sorted, once each) and the statistics of the output.
    fn output_triangles(
        &self,
        tris: &[TriId],
        remap: &[u32],
    ) -> (Vec<[u32; 3]>, Vec<[u32; 2]>, RefineStats) {
        let tin = &self.tin;
        let mut triangles = Vec::with_capacity(tris.len());
        let mut constrained = Vec::new();
        let mut stats = self.stats.clone();
        let mut worst = (-1.0, TriId(NONE));
        for &t in tris {
            let v = tin.tri_vertices(t);
            triangles.push(v.map(|v| remap[v.0 as usize]));
            // The exact angle (atan2) only near the bound and for the worst triangle.
            let (cos2, area, _, _) = shape(v.map(|v| tin.xy(v)));
            stats.max_area = stats.max_area.max(area);
            if cos2 > self.good * (1.0 - 1e-9)
                && super::min_angle(v.map(|v| tin.point(v))) < self.bound
            {
                stats.skinny += 1;
            }
            if cos2 > worst.0 {
                worst = (cos2, t);
            }
            for e in [t.edge(), t.edge().next(), t.edge().prev()] {
                if tin.is_constrained(e) {
                    let (a, b) = (remap[tin.org(e).0 as usize], remap[tin.dst(e).0 as usize]);
                    constrained.push([a.min(b), a.max(b)]);
                }
            }
        }
        constrained.sort_unstable();
        constrained.dedup();
        stats.min_angle = if worst.1.0 == NONE {
            0.0
        } else {
            super::min_angle(tin.tri_vertices(worst.1).map(|v| tin.point(v)))
        };
        stats.triangles = triangles.len() as u64;
        (triangles, constrained, stats)
    }
}

/// `(cos² of the smallest angle (0 if it is not acute), area, squared length of the shortest
/// edge, which edge that is: k from corner k to k + 1)` of a counter-clockwise triangle.
fn shape(p: [[f64; 2]; 3]) -> (f64, f64, f64, usize) {
    let d = |i: usize, j: usize| [p[j][0] - p[i][0], p[j][1] - p[i][1]];
    let len = |u: [f64; 2]| u[0] * u[0] + u[1] * u[1];
    let l = [len(d(0, 1)), len(d(1, 2)), len(d(2, 0))];
    let k = if l[0] <= l[1] && l[0] <= l[2] {
        0
    } else if l[1] <= l[2] {
        1
    } else {
        2
    };
    // The smallest angle is at the apex opposite edge k.
    let apex = (k + 2) % 3;
    let (u, w) = (d(apex, k), d(apex, (k + 1) % 3));
    let dot = u[0] * w[0] + u[1] * w[1];
    let cos2 = if dot > 0.0 {
        dot * dot / (len(u) * len(w))
    } else {
        0.0
    };
    (cos2, 0.5 * (u[0] * w[1] - u[1] * w[0]).abs(), l[k], k)
}
