//! Quality mesh refinement: Ruppert's Delaunay refinement with Üngör's off-centres and
//! Shewchuk's rules for small input angles, as Triangle's `-q` does it (Herva 2009 discusses
//! Ruppert's algorithm for design surfaces).
//!
//! [`refine`] takes a mesh (the *original surface*: a TIN, maybe trimmed, with holes) and
//! constraint segments (breaklines, with or without z), and inserts Steiner points until every
//! triangle's smallest angle is at least [`RefineOptions::min_angle`] and its area at most
//! [`RefineOptions::max_area`]:
//!
//! 1. **Domain.** The union of the input triangles; its boundary edges (an edge with one
//!    triangle) become constraint segments, so boundaries and holes are kept exactly. The
//!    constrained Delaunay triangulation (CDT) of the input vertices, the boundary edges and the
//!    breaklines (draped on the original surface when they have no z) is built by the sweep
//!    ([`crate::triangulate_cdt`]) and handed to a dynamic [`Tin`], whose constrained edges
//!    ([`Tin::insert_segment`]), insertions with Lawson flips and deletions do all the
//!    refinement; each region between constrained edges is in or out of the domain, decided once
//!    by its largest triangle's centroid in the original mesh (exact orientation tests).
//! 2. **Encroached segments first.** A subsegment is encroached when the apex of a triangle of
//!    the domain beside it sees it under an angle of at least `180° − 2 · min_angle` (Triangle's
//!    *diametral lens*). It is split at its midpoint, or, when exactly one of its ends is a vertex
//!    where another segment meets it inside a triangle beside it, at the power of two (in the
//!    data's units) nearest its middle from that end: Ruppert's *concentric shells*, so splits
//!    around a small input angle stay equidistant from its vertex. The split point is computed in
//!    floating point and inserted topologically on the edge ([`Tin::split_edge_at`]); its z is
//!    interpolated along the subsegment.
//! 3. **Bad triangles.** A triangle is bad when its area exceeds `max_area`, or when
//!    its smallest angle is below `min_angle`. It gets a Steiner point at its circumcentre, or at
//!    Üngör's off-centre when that is nearer (on the bisector of its shortest edge, where the new
//!    triangle on that edge just meets the bound): fewer points than circumcentres. The point is
//!    found by a straight walk from the triangle (exact
//!    `orient` tests); a constrained edge in the way is split
//!    instead, and so is every subsegment the new point would encroach (the
//!    point is then removed again, [`Tin::remove`], and the triangle tried later). Its z is
//!    interpolated on the original surface at its xy (once the mesh is done: the points in rows
//!    of a grid, each found by a short walk in the input mesh from the one before).
//!
//! **Order.** The bad triangles wait in Triangle's queue: by the length of their shortest edge,
//! the shortest first, in classes of half powers of two of its square; first in, first out
//! within a class (queued in the order the operations create them: the triangles an operation
//! touched, by slot number). Shortest edge first rather than worst angle first: on the
//! benchmark graphs, worst-angle-first made 1.3–1.4 times Triangle's triangles, this order
//! 0.96–1.01 times (docs/BENCHMARKS.md). No threads, no hashing order: the output is the same on
//! every run and machine.
//!
//! **Small input angles (< 60°).** No algorithm can fix an input angle below the bound, and
//! Ruppert's algorithm may not terminate near input angles below 60°. As Triangle (Miller, Pav and
//! Walkington's rule): a skinny triangle whose shortest edge joins two points on two different
//! segments that share an end, at the same distance from it (within 0.1 %), is not split; the
//! concentric shells make such pairs appear. Those triangles, and the triangles at input angles
//! below the bound, are left as they are and counted in [`RefineStats::skinny`]. Every other
//! triangle meets the bound. Past [`RefineOptions::max_steiner`] points the run stops with an
//! error (nothing is written).
//!
//! The quality tests (angles, areas, encroachment) are floating point: they choose where points
//! go, never the mesh's validity, which every orientation and in-circle decision keeps exact.

use crate::error::{Error, Result};
use crate::tin::{EdgeId, Tin, TriId, VertexId};
use std::collections::HashMap;
use surface::Surface;

mod run;
mod surface;

/// What [`refine`] aims for.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RefineOptions {
    /// Smallest angle every triangle must have, in degrees (Triangle's `-q`). Up to 20.7° is
    /// proved to terminate; up to about 33.8° works in practice.
    pub min_angle: f64,
    /// Largest triangle area (the data's xy units squared), if any.
    pub max_area: Option<f64>,
    /// Stop with an error past this many Steiner points (default: 20 per input vertex plus one
    /// million).
    pub max_steiner: Option<u64>,
    /// Memory budget (bytes): the output [`RefineOptions::max_area`] implies (the domain's
    /// area / `max_area` triangles at least) is checked against it before refining, and
    /// refused when it cannot fit ([`Error::Options`]). `None`: not checked.
    pub mem: Option<u64>,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            min_angle: 30.0,
            max_area: None,
            max_steiner: None,
            mem: None,
        }
    }
}

impl RefineOptions {
    /// Checks the options.
    ///
    /// # Errors
    /// [`Error::Options`] for an angle outside (0°, 34°] or an area that is not positive.
    pub fn validate(&self) -> Result<()> {
        if !(self.min_angle > 0.0 && self.min_angle <= 34.0) {
            return Err(Error::Options(format!(
                "--min-angle {}: must be above 0 and at most 34 degrees (Delaunay refinement \
                 is proved to end up to 20.7° and ends in practice up to about 33.8°)",
                self.min_angle
            )));
        }
        if let Some(a) = self.max_area
            && !(a > 0.0 && a.is_finite())
        {
            return Err(Error::Options(format!(
                "--max-area {a}: must be a positive area"
            )));
        }
        Ok(())
    }
}

/// What a vertex of the refined mesh is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum VertexKind {
    /// A vertex of the input mesh or of a breakline.
    Input,
    /// A Steiner point on a constraint segment (z along the segment).
    Segment,
    /// A Steiner point inside the domain (z on the original surface).
    Free,
}

/// What [`refine`] did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RefineStats {
    /// Vertices of the input mesh.
    pub input_vertices: u64,
    /// Triangles of the input mesh.
    pub input_triangles: u64,
    /// Boundary edges of the input mesh (kept as constraints).
    pub boundary_edges: u64,
    /// Breakline segments inserted.
    pub breakline_segments: u64,
    /// Breakline segments left out because an end lies outside the mesh.
    pub breakline_segments_outside: u64,
    /// Steiner points on segments.
    pub segment_points: u64,
    /// Steiner points inside the domain (centres).
    pub free_points: u64,
    /// Centres not kept because they encroached a subsegment (which was split instead).
    pub rejected_centres: u64,
    /// Subsegments too short to split in floating point.
    pub unsplittable: u64,
    /// Output triangles below the angle bound (at input angles below it; see the module docs).
    pub skinny: u64,
    /// Smallest angle of the input mesh, in degrees.
    pub input_min_angle: f64,
    /// Smallest angle of the output, in degrees.
    pub min_angle: f64,
    /// Largest triangle area of the output.
    pub max_area: f64,
    /// Output vertices.
    pub vertices: u64,
    /// Output triangles.
    pub triangles: u64,
}

/// The refined mesh.
#[derive(Clone, Debug, Default)]
pub struct Refined {
    /// `[x, y, z]`: the input vertices first (in input order, then new breakline vertices), then
    /// the Steiner points in insertion order.
    pub vertices: Vec<[f64; 3]>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[u32; 3]>,
    /// What each vertex is.
    pub kinds: Vec<VertexKind>,
    /// The constrained edges (boundary and breakline subsegments), lower index first, sorted.
    pub constrained: Vec<[u32; 2]>,
    /// What was done.
    pub stats: RefineStats,
}

impl Refined {
    /// What the refined mesh is ([`crate::validate::MeshKind`]), for an input mesh of `input`: a
    /// constrained Delaunay triangulation, constrained when breaklines went in; trimmed when the
    /// input was, or when Steiner points split its boundary (rounded off the hull's edges).
    /// Whether the input was Delaunay does not matter: refining triangulates again.
    pub fn kind(&self, input: crate::validate::MeshKind) -> crate::validate::MeshKind {
        crate::validate::MeshKind {
            constrained: self.stats.breakline_segments > 0,
            trimmed: input.trimmed || self.stats.segment_points > 0,
            not_delaunay: false,
        }
    }
}

/// Refines the mesh `vertices`/`triangles` (counter-clockwise; the domain is their union) with the
/// breakline segments `lines` (`[x, y, z]` ends; z `NaN` = take it from the mesh) until every
/// triangle meets `options` (see the module docs).
///
/// # Errors
/// [`Error::Options`] for bad options; [`Error::Refine`] for a bad mesh (index out of range,
/// degenerate or clockwise triangle, duplicate vertices), a breakline crossing the mesh boundary,
/// or past [`RefineOptions::max_steiner`] points; coordinate errors as [`crate::triangulate`].
pub fn refine(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    lines: &[[[f64; 3]; 2]],
    options: &RefineOptions,
) -> Result<Refined> {
    options.validate()?;
    room(
        vertices.len() as u64 * SETUP_BYTES,
        "refine's triangulation",
    )?;
    let surface = check_mesh(vertices, triangles)?;
    let mut stats = RefineStats {
        input_vertices: vertices.len() as u64,
        input_triangles: triangles.len() as u64,
        input_min_angle: triangles
            .iter()
            .map(|t| min_angle(t.map(|v| vertices[v as usize])))
            .fold(180.0, f64::min),
        ..RefineStats::default()
    };
    // Boundary edges: directed edges whose reverse is not in the mesh.
    let mut directed: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .collect();
    directed.sort_unstable();
    let mut segments: Vec<[u32; 2]> = directed
        .iter()
        .filter(|&&(a, b)| directed.binary_search(&(b, a)).is_err())
        .map(|&(a, b)| [a, b])
        .collect();
    stats.boundary_edges = segments.len() as u64;
    // Breakline ends: mesh vertices, or new vertices draped on the surface.
    let mut points = vertices.to_vec();
    let mut at: HashMap<(u64, u64), u32> = vertices
        .iter()
        .enumerate()
        .map(|(i, p)| (((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()), i as u32))
        .collect();
    for line in lines {
        let mut ends = [0u32; 2];
        let mut outside = false;
        for (k, p) in line.iter().enumerate() {
            let key = ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits());
            if let Some(&i) = at.get(&key) {
                ends[k] = i;
                continue;
            }
            let z = match surface.height([p[0], p[1]]) {
                None => {
                    outside = true;
                    break;
                }
                Some(h) if !p[2].is_finite() => h,
                Some(_) => p[2],
            };
            at.insert(key, points.len() as u32);
            ends[k] = points.len() as u32;
            points.push([p[0], p[1], z]);
        }
        if outside {
            stats.breakline_segments_outside += 1;
        } else if ends[0] != ends[1] {
            segments.push(ends);
            stats.breakline_segments += 1;
        }
    }
    let cdt = crate::triangulate_cdt(&points, &segments, &crate::Options::default())?;
    if cdt.duplicates > 0 {
        return Err(Error::Refine(format!(
            "the mesh has {} vertices at the position of another",
            cdt.duplicates
        )));
    }
    let mut tin = Tin::from_triangulation(&cdt)?;
    constrain(&mut tin, &cdt.input_index, &points, &segments)?;
    drop(cdt);
    refine_tin(
        tin,
        surface,
        triangles.len(),
        options,
        stats,
        run::Domain::Mesh,
    )
}

/// Refines the planar straight-line graph `points`/`segments` (Triangle's `-pq`): its
/// constrained Delaunay triangulation, less every region reached from a hull edge that is not a
/// segment (so a graph closed by segments is refined inside them; holes are not supported), with
/// Steiner heights interpolated on that triangulation. See [`refine`].
///
/// # Errors
/// As [`refine`]; crossing segments are [`Error::Refine`].
pub fn refine_pslg(
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
    options: &RefineOptions,
) -> Result<Refined> {
    options.validate()?;
    room(points.len() as u64 * SETUP_BYTES, "refine's triangulation")?;
    let cdt = crate::triangulate_cdt(points, segments, &crate::Options::default())?;
    if cdt.duplicates > 0 {
        return Err(Error::Refine(format!(
            "the graph has {} vertices at the position of another",
            cdt.duplicates
        )));
    }
    let mut tin = Tin::from_triangulation(&cdt)?;
    constrain(&mut tin, &cdt.input_index, points, segments)?;
    let stats = RefineStats {
        input_vertices: points.len() as u64,
        breakline_segments: segments.len() as u64,
        ..RefineStats::default()
    };
    let surface = Surface::new(&cdt.vertices, &cdt.triangles);
    let m = cdt.triangles.len();
    refine_tin(tin, surface, m, options, stats, run::Domain::Hull)
}

/// Address space refining takes (`VmPeak`, on 1.9 M vertices of ARSO ground refined to 3.2 M at
/// 25°), with a margin: setting up the dynamic TIN (the CDT, the boundary's edges, the TIN)
/// about 350 bytes an input vertex; the input surface's grid, built while the regions are
/// classified, 140 bytes an input triangle (its `m`); growing the mesh about 140 bytes a vertex,
/// which arrays take at once when they double; the output, 95 bytes an output vertex beside the
/// mesh. Checked before each step under an address-space limit ([`room`]).
const SETUP_BYTES: u64 = 400;
const GRID_BYTES: u64 = 160;
pub(super) const GROWTH_BYTES: u64 = 160;
const OUTPUT_BYTES: u64 = 120;

/// Fails with [`Error::OutOfMemory`] when an address-space limit leaves less than `bytes`
/// beside what the process maps: refining holds its whole mesh, and an allocation that fails
/// would abort the process.
pub(super) fn room(bytes: u64, what: &str) -> Result<()> {
    crate::limits::check_room(
        bytes,
        what,
        "refine holds its mesh in memory: raise the limit, or refine a smaller area (--bbox, or a \
         trimmed `sweeptin tin` mesh)",
    )
}

/// The fewest triangles `max_area` leaves in a domain of `area`: each holds at most `max_area`.
pub(super) fn triangles_implied(area: f64, max_area: f64) -> f64 {
    (area / max_area).ceil()
}

/// Refuses a `max_area` whose output cannot be made, before any Steiner point: the domain's
/// `area` needs at least `area / max_area` triangles, so about half as many vertices (Euler),
/// each taking [`GROWTH_BYTES`] + [`OUTPUT_BYTES`]; with the input's setup ([`SETUP_BYTES`] an
/// input vertex, [`GRID_BYTES`] an input triangle, `m`) that must fit [`RefineOptions::mem`];
/// and the Steiner points must stay within `max_steiner`. (`refine --max-area 1e-6` on 1,968 m²
/// ran up to `--max-steiner` and then blamed the angle bound.)
fn check_area_bound(
    max_area: f64,
    area: f64,
    input_vertices: u64,
    m: usize,
    options: &RefineOptions,
    max_steiner: u64,
) -> Result<()> {
    let triangles = triangles_implied(area, max_area);
    let vertices = (triangles / 2.0).max(input_vertices as f64);
    let per_vertex = (GROWTH_BYTES + OUTPUT_BYTES) as f64;
    let fixed = (input_vertices * SETUP_BYTES + m as u64 * GRID_BYTES) as f64;
    let need = fixed + vertices * per_vertex;
    let figure = |v: f64| {
        if v < 1e6 {
            format!("{v:.0}")
        } else {
            format!("{v:.2e}")
        }
    };
    let what = format!(
        "--max-area {max_area}: the domain's area of {} in triangles of at most {max_area} makes \
         at least {} triangles and {} vertices",
        figure(area),
        figure(triangles),
        figure(vertices)
    );
    // The smallest bound that fits `room` vertices.
    let smallest = |room: f64| crate::error::round_up_figure(area / (2.0 * room.max(1.0)));
    if let Some(mem) = options.mem
        && need > mem as f64
    {
        let room = (mem as f64 - fixed) / per_vertex;
        let way = if room >= 1.0 {
            format!(
                "give --max-area {} or more, or a larger --mem",
                smallest(room)
            )
        } else {
            "the input alone takes it: give a larger --mem".into()
        };
        return Err(Error::Options(format!(
            "{what}, about {} to refine: more than --mem {}; {way}",
            crate::human_bytes(need as u64),
            crate::human_bytes(mem)
        )));
    }
    let steiner = vertices - input_vertices as f64;
    if steiner > max_steiner as f64 {
        return Err(Error::Options(format!(
            "{what}, {} of them Steiner points: more than --max-steiner {max_steiner}; give \
             --max-area {} or more, or a larger --max-steiner",
            figure(steiner),
            smallest(max_steiner as f64 + input_vertices as f64)
        )));
    }
    Ok(())
}

/// Refines `tin`, whose domain is `domain`, heights from `surface` (of `m` triangles).
fn refine_tin(
    tin: Tin,
    surface: Surface<'_>,
    m: usize,
    options: &RefineOptions,
    stats: RefineStats,
    domain: run::Domain,
) -> Result<Refined> {
    let mut r = run::Refiner::new(tin, surface, options, stats);
    room(m as u64 * GRID_BYTES, "the input surface's grid")?;
    r.classify(domain);
    if let Some(a) = options.max_area {
        let n = r.input_vertices();
        check_area_bound(a, r.domain_area(), n, m, options, r.max_steiner())?;
    }
    r.run()?;
    room(r.vertex_count() as u64 * OUTPUT_BYTES, "the refined mesh")?;
    Ok(r.finish())
}

/// Marks `segments` (indices into `points`, whose triangulation vertex `i` is input point
/// `input_index[i]`) constrained in `tin`.
fn constrain(
    tin: &mut Tin,
    input_index: &[u32],
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
) -> Result<()> {
    let mut id = vec![0u32; points.len()];
    for (i, &j) in input_index.iter().enumerate() {
        id[j as usize] = i as u32;
    }
    for s in segments {
        let [a, b] = s.map(|v| VertexId(id[v as usize]));
        tin.insert_segment(a, b).map_err(|e| {
            let p = |v: u32| points[v as usize];
            Error::Refine(format!(
                "the segment ({}, {}) – ({}, {}) crosses another segment or the mesh boundary \
                 ({e})",
                p(s[0])[0],
                p(s[0])[1],
                p(s[1])[0],
                p(s[1])[1]
            ))
        })?;
    }
    Ok(())
}

/// Checks the input mesh and indexes its surface.
fn check_mesh<'a>(vertices: &'a [[f64; 3]], triangles: &'a [[u32; 3]]) -> Result<Surface<'a>> {
    use crate::geom::predicates::{Orientation, orient};
    if triangles.is_empty() {
        return Err(Error::Refine("the mesh has no triangle".into()));
    }
    for (i, t) in triangles.iter().enumerate() {
        if t.iter().any(|&v| v as usize >= vertices.len()) {
            return Err(Error::Refine(format!(
                "triangle {i} refers to a vertex beyond the {} given",
                vertices.len()
            )));
        }
        let [a, b, c] = t.map(|v| [vertices[v as usize][0], vertices[v as usize][1]]);
        match orient(a, b, c) {
            Orientation::CounterClockwise => {}
            o => {
                return Err(Error::Refine(format!(
                    "triangle {i} ({t:?}) is {}",
                    if o == Orientation::Clockwise {
                        "clockwise"
                    } else {
                        "degenerate (collinear corners)"
                    }
                )));
            }
        }
    }
    Ok(Surface::new(vertices, triangles))
}

/// Smallest angle of a triangle in degrees: `atan2(|u × v|, u · v)` at each corner, which is
/// accurate to a few units in the last place even for tiny angles.
pub fn min_angle(t: [[f64; 3]; 3]) -> f64 {
    let mut m = 180.0f64;
    for k in 0..3 {
        let (o, p, q) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        let (ux, uy, vx, vy) = (p[0] - o[0], p[1] - o[1], q[0] - o[0], q[1] - o[1]);
        let a = (ux * vy - uy * vx).abs().atan2(ux * vx + uy * vy);
        m = m.min(a.to_degrees());
    }
    m
}

/// A triangle waiting in the queue: its vertices (as its slot held them) and its slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Bad {
    ids: [u32; 3],
    slot: u32,
}

/// Bad triangles in refinement order (Triangle's queue): 4096 classes of the squared length of
/// the shortest edge, in half powers of two, the shortest first; first in, first out within a
/// class. O(1) a push or pop, and the same order on every run.
struct Queue {
    classes: Vec<std::collections::VecDeque<Bad>>,
    /// No class below this one holds an entry.
    lowest: usize,
    len: usize,
}

impl Queue {
    fn new() -> Queue {
        Queue {
            classes: vec![std::collections::VecDeque::new(); 4096],
            lowest: 4096,
            len: 0,
        }
    }

    /// The class of a squared edge length: twice its binary exponent, plus one above √2 · 2^e.
    fn class(len2: f64) -> usize {
        let bits = len2.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as usize;
        let mantissa = f64::from_bits((bits & ((1 << 52) - 1)) | (1023 << 52));
        2 * exp + usize::from(mantissa > std::f64::consts::SQRT_2)
    }

    fn push(&mut self, len2: f64, bad: Bad) {
        let c = Queue::class(len2);
        self.classes[c].push_back(bad);
        self.lowest = self.lowest.min(c);
        self.len += 1;
    }

    fn pop(&mut self) -> Option<Bad> {
        if self.len == 0 {
            return None;
        }
        while self.classes[self.lowest].is_empty() {
            self.lowest += 1;
        }
        self.len -= 1;
        self.classes[self.lowest].pop_front()
    }
}

/// A subsegment to check (or, `force`, to split unconditionally).
#[derive(Clone, Copy, Debug)]
struct Encroached {
    a: VertexId,
    b: VertexId,
    /// Where the half-edge `a → b` was (checked).
    hint: EdgeId,
    force: bool,
}

/// The result of a straight walk towards a new point.
enum Walk {
    /// The closed triangle holding it.
    Inside(TriId),
    /// A constrained edge is in the way.
    Blocked(EdgeId),
    /// Rounding or a degenerate path: give up on this point.
    Lost,
}
