//! Breaklines and trimming in the streaming pipeline.
//!
//! ```text
//! --breaklines FILES, --boundary FILE, --holes FILE
//!   ─► read (GeoJSON / text) ─► clean into a planar graph (crossings split, overlaps merged;
//!      streamed by the sweep axis, `breaklines::clean::stream`)
//!   ─► [2-D vertices only] drape: z from a first pass over the points (no breaklines)
//!   ─► graph vertices join the sorted point stream as flagged records (index = LINE_FLAG | id),
//!      each with where its segments go (`line_feed`)
//!   ─► the sweep inserts each segment when its upper end is swept (edge events)
//!   ─► writer: [--no-flat-triangles: in-memory flips] ─► trim (boundary, holes, max-edge)
//! ```
//!
//! **Boundary and hole rings** are inserted as breaklines too, so no triangle straddles a ring and
//! the exact symbolic inside test of [`crate::breaklines::trim`] decides each whole triangle.
//!
//! **Lines without z** (2-D GeoJSON, text lines with two columns, boundary polygons) get their
//! heights from the point cloud's own TIN: a first streaming pass triangulates the points alone,
//! and each such vertex takes the height of the (first, in stream order) triangle that contains it,
//! by linear interpolation. A vertex outside the points' triangulation has no height to take:
//! that is an error naming the line. Vertices where a line with z meets one without take the
//! known z (breakline cleaning interpolates along the line that has it). A plan and its tasks
//! prepare the lines without a draping pass ([`prepare`] without `drape`): every vertex must
//! have its z after cleaning, and `--clip-breaklines` is refused, both needing all the points.
//!
//! **Duplicates**: a breakline vertex at exactly the (x, y) of a lidar point is one vertex; its z
//! follows `--duplicates` like any other duplicate, where the breakline vertex counts as read
//! after every point (so `first` keeps the point's z, `last` the line's), and the merged vertex is
//! always a breakline vertex.
//!
//! **Memory**: a run ([`prepare_with`] with a budget) reads the line files polyline by polyline
//! ([`LineStream`]: a text file one polyline at a time, other formats one file at a time),
//! cleans them in bounded memory and streams the graph into the sweep ([`super::line_feed`]):
//! held are the boundary and hole rings, the heights of 2-D vertices, the sorts' budgets and the
//! cleaner's and the sweep's windows; lidar points are never held. `--clip-breaklines` reads the
//! lines whole to cut them. `--no-flat-triangles` takes the polylines and the cleaned graph in
//! memory (32 bytes per line vertex plus 12 per segment and the sweep's constraint index), as do
//! a plan's tasks and the tiles engine ([`prepare`]), and its flips need the whole
//! triangulation, which the writer then holds (about 40 bytes per point), so use it on
//! tile-sized inputs.

use super::TriangleSink;
use crate::breaklines::clean::stream::PolylineSource;
use crate::breaklines::flat::FlatStats;
use crate::breaklines::{CleanOptions, CleanStats, Lines, Pslg, Source, Trim};
use crate::error::{Error, Result};
use crate::geom::grid::{Buckets, Grid};
use crate::geom::predicates::check_coord;
use crate::input::lines::LineStream;
use crate::products::geom::{Location, Tri};
use crate::sink::ProductSummary;
use crate::sweep::{ConstraintGraph, ConstraintStats};
use std::path::{Path, PathBuf};

/// Sort-record index bit marking a breakline vertex (the rest is its vertex id in the graph).
pub(crate) const LINE_FLAG: u64 = 1 << 63;

/// Why a plan refuses `--clip-breaklines`: the one wording of the refusal, by `sweeptin plan`
/// before anything is written and by a task's run (which never sees all the points).
pub const PLAN_REFUSES_CLIP: &str = "--clip-breaklines cuts the lines to the convex hull of all \
     the points, which no task of a plan sees (each reads the files near its tile), so a plan \
     refuses it: cut the lines to the data beforehand, or run the job as one command without \
     `plan`";

/// Breaklines and trimming for a run.
#[derive(Clone, Debug, Default)]
pub struct LineOptions {
    /// Breakline files (GeoJSON or text; see [`crate::input::lines`]).
    pub breaklines: Vec<PathBuf>,
    /// Polygons: keep only the triangles inside.
    pub boundary: Option<PathBuf>,
    /// Polygons: drop the triangles inside (lakes, buildings).
    pub holes: Option<PathBuf>,
    /// Drop triangles with an edge longer than this (the data's xy units).
    pub max_edge: Option<f64>,
    /// Report breakline z disagreements larger than this at shared vertices and crossings.
    pub z_tolerance: Option<f64>,
    /// Flip away triangles lying flat on one contour line (Herva 2009, 4.2.2).
    pub no_flat_triangles: bool,
    /// Cut the breaklines to the points' convex hull instead of refusing lines that run outside
    /// it (cut by `clip`; costs one more pass over the points).
    pub clip: bool,
}

impl LineOptions {
    /// No breaklines and no trimming: the plain pipeline.
    pub fn is_empty(&self) -> bool {
        self.breaklines.is_empty()
            && self.boundary.is_none()
            && self.holes.is_none()
            && self.max_edge.is_none()
    }

    /// What these lines make of a mesh ([`crate::validate::MeshKind`]): breaklines and the rings of
    /// a boundary or holes are constraints; a boundary, holes and `--max-edge` trim it;
    /// `--no-flat-triangles` leaves it not Delaunay.
    pub fn mesh_kind(&self) -> crate::validate::MeshKind {
        let rings = self.boundary.is_some() || self.holes.is_some();
        crate::validate::MeshKind {
            constrained: !self.breaklines.is_empty() || rings,
            trimmed: rings || self.max_edge.is_some(),
            not_delaunay: self.no_flat_triangles,
        }
    }
}

/// What the breakline machinery did (part of the `--json` summary).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct LineSummary {
    /// Polylines read (breaklines, then boundary and hole rings).
    pub polylines: u64,
    /// Vertices of the cleaned graph.
    pub vertices: u64,
    /// Segments of the cleaned graph.
    pub segments: u64,
    /// What cleaning did (crossings split, overlaps merged, …).
    pub clean: CleanStats,
    /// z disagreements beyond `--z-tolerance` (the first few; `clean.z_conflicts` counts all).
    pub z_conflicts: Vec<crate::breaklines::clean::ZConflict>,
    /// Vertices that took their z from the points' TIN (lines without z).
    pub draped: u64,
    /// What the sweep's edge events did.
    pub constraints: ConstraintStats,
    /// Triangles not emitted (outside the boundary, inside holes, edges over `--max-edge`).
    pub trimmed_triangles: u64,
    /// `--no-flat-triangles` flips.
    pub flat: Option<FlatStats>,
    /// What `--clip-breaklines` cut.
    pub clipped: Option<ClipSummary>,
    /// What the streamed cleaner held at most (`null` when the lines were cleaned in memory:
    /// `--no-flat-triangles`, or a plan's task).
    pub cleaner: Option<crate::breaklines::clean::stream::StreamStats>,
    /// The most line vertices (24 bytes each) held at once as read: every input vertex when the
    /// lines are read whole (`--no-flat-triangles`, `--clip-breaklines`, a plan's task, mixed
    /// heights); streamed, the longest polyline of a text file or the vertices of a GeoJSON,
    /// GeoPackage or Shapefile file (read whole), plus the boundary and hole rings.
    pub read_held_vertices: u64,
    /// Breakline heights far outside the points' (a warning: wrong units or vertical datum?).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub far_heights: Option<FarHeights>,
}

/// Breakline vertices whose z lies farther outside the points' range of heights than that range
/// is tall (at least 1 unit): lines in another unit or vertical datum, or placeholder heights.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FarHeights {
    /// How many vertices.
    pub vertices: u64,
    /// Lowest and highest z of those vertices.
    pub lines_z: [f64; 2],
    /// Lowest and highest z of the points.
    pub points_z: [f64; 2],
}

impl FarHeights {
    /// The breakline vertices of `p` far from the points' heights `points_z` (see the type).
    pub(crate) fn of(p: &Prepared, points_z: [f64; 2]) -> Option<FarHeights> {
        let g = p.pslg.as_ref()?;
        let mut far = FarTally::new(points_z);
        for v in &g.vertices {
            far.add(v[2]);
        }
        far.finish()
    }
}

/// [`FarHeights`] counted one vertex at a time (the streamed lines).
pub(crate) struct FarTally {
    far: FarHeights,
    /// The lowest and highest height not far, `None` when the points' range is not finite.
    near: Option<[f64; 2]>,
}

impl FarTally {
    pub(crate) fn new(points_z: [f64; 2]) -> FarTally {
        let [lo, hi] = points_z;
        let margin = (hi - lo).max(1.0);
        FarTally {
            far: FarHeights {
                vertices: 0,
                lines_z: [f64::INFINITY, f64::NEG_INFINITY],
                points_z,
            },
            near: (lo.is_finite() && hi.is_finite()).then_some([lo - margin, hi + margin]),
        }
    }

    pub(crate) fn add(&mut self, z: f64) {
        if let Some([lo, hi]) = self.near
            && (z < lo || z > hi)
        {
            let f = &mut self.far;
            f.vertices += 1;
            f.lines_z = [f.lines_z[0].min(z), f.lines_z[1].max(z)];
        }
    }

    pub(crate) fn finish(self) -> Option<FarHeights> {
        (self.far.vertices > 0).then_some(self.far)
    }
}

/// What `--clip-breaklines` cut off the breaklines (outside the points' convex hull).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ClipSummary {
    /// Breaklines read.
    pub lines: u64,
    /// Lines cut (some of their length lay outside).
    pub lines_cut: u64,
    /// Lines left out whole (entirely outside).
    pub lines_dropped: u64,
    /// Horizontal length of all the lines.
    pub length: f64,
    /// Horizontal length cut off.
    pub length_cut: f64,
}

/// Breaklines ready for the sweep.
pub(crate) struct Prepared {
    /// The cleaned graph with every z known (in memory).
    pub pslg: Option<Pslg>,
    /// Or the cleaned graph streamed ([`super::line_feed`]), taken by the run that sweeps it.
    pub feed: std::sync::Mutex<Option<super::line_feed::LineFeed>>,
    /// Trimming rules (keeps all when none were given).
    pub trim: Trim,
    /// `--no-flat-triangles`.
    pub flat: bool,
    pub summary: LineSummary,
}

impl Prepared {
    /// No lines: only trimming (and `flat`).
    fn none(trim: Trim, flat: bool, summary: LineSummary) -> Prepared {
        Prepared {
            pslg: None,
            feed: Default::default(),
            trim,
            flat,
            summary,
        }
    }

    /// The sweep's view of the graph.
    pub(crate) fn graph(&self) -> Option<ConstraintGraph> {
        self.pslg.as_ref().map(|g| {
            let xy = g
                .vertices
                .iter()
                .map(|v| [v[0] + 0.0, v[1] + 0.0])
                .collect();
            ConstraintGraph::new(xy, &g.segments)
        })
    }
}

/// The points-only pass that lines without z, and `--clip-breaklines`, need: it runs the
/// caller's pipeline over the points alone into the given sink.
pub(crate) type Drape<'a> = &'a mut dyn FnMut(&mut dyn TriangleSink) -> Result<()>;

/// How a run reads each line file (breaklines, boundary, holes):
/// [`crate::breaklines::read_file`] for a run; a plan and its tasks check each file's
/// fingerprint on the very bytes they parse ([`crate::plan::PlanLines`]).
pub(crate) type ReadLines<'a> = dyn Fn(&Path) -> Result<Lines> + Send + Sync + 'a;

/// Reads (with `read`), cleans and (when needed) drapes the breaklines of a run.
///
/// `drape` runs the points-only pass with the given sink (the caller's pipeline). Without one
/// (a plan and its tasks, which never see all the points) every vertex must have a `z` after
/// cleaning and `clip` must be off.
///
/// # Errors
/// The readers' and cleaning's errors; [`Error::Options`] without `drape` for
/// `--clip-breaklines`, and for a vertex without `z`, naming the first such vertex of the input
/// (file, feature or line, vertex); the draping pass's errors.
pub(crate) fn prepare(
    o: &LineOptions,
    read: &ReadLines<'_>,
    drape: Option<Drape>,
) -> Result<Prepared> {
    prepare_with(o, read, drape, None)
}

/// What a run gives its lines ([`prepare_with`]): `--mem` and the scratch directory.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LineBudget<'a> {
    pub mem: u64,
    pub tmp: &'a Path,
    /// The breakline files may be read by path, polyline by polyline, as often as needed (the
    /// run's own reader; a plan's task parses only the bytes it fingerprinted, read whole).
    pub reread: bool,
}

/// [`prepare`], and with `stream` the lines are cleaned by the streamed cleaner and handed to
/// the sweep as a stream ([`super::line_feed`]) when `drape` is given and `--no-flat-triangles`
/// is off; otherwise they are cleaned in memory (the flips need the whole graph). Streamed, the
/// breakline files are read polyline by polyline ([`LineStream`]) and never held, unless
/// `--clip-breaklines` (which cuts them whole) or a plan's reader needs them in memory.
///
/// # Errors
/// As [`prepare`], and the external sorts'.
pub(crate) fn prepare_with(
    o: &LineOptions,
    read: &ReadLines<'_>,
    mut drape: Option<Drape>,
    stream: Option<LineBudget>,
) -> Result<Prepared> {
    let stream = stream.filter(|_| !o.no_flat_triangles && drape.is_some());
    if let Some(b) = stream.filter(|b| b.reread && !o.clip)
        && let Some(drape) = drape
    {
        let (boundary, holes, trim) = read_trim(o, read)?;
        let mut then = Lines::default();
        for l in [boundary, holes].into_iter().flatten() {
            then.append(l)?;
        }
        let lines = LineStream {
            paths: o.breaklines.clone(),
            then,
        };
        return streamed(&lines, o, b, drape, trim, LineSummary::default());
    }
    let mut lines = Lines::default();
    for p in &o.breaklines {
        lines.append(read(p)?)?;
    }
    let mut clipped = None;
    if o.clip && !lines.is_empty() {
        let Some(drape) = drape.as_mut() else {
            return Err(Error::Options(PLAN_REFUSES_CLIP.into()));
        };
        let mut hull = super::clip::HullSink::default();
        drape(&mut hull)?;
        let h = hull.finish_hull();
        let (cut, summary) = super::clip::clip(&lines, &h);
        lines = cut;
        clipped = Some(summary);
    }
    let (boundary, holes, trim) = read_trim(o, read)?;
    for l in [boundary, holes].into_iter().flatten() {
        lines.append(l)?;
    }
    let mut summary = LineSummary {
        polylines: lines.len() as u64,
        read_held_vertices: lines.vertex_count() as u64,
        clipped,
        ..LineSummary::default()
    };
    if lines.is_empty() {
        return Ok(Prepared::none(trim, o.no_flat_triangles, summary));
    }
    for (i, p) in lines.polylines.iter().enumerate() {
        check_coords(p, &lines.sources[i])?;
    }
    if let Some(b) = stream
        && let Some(drape) = drape
    {
        let lines = LineStream {
            paths: Vec::new(),
            then: lines,
        };
        return streamed(&lines, o, b, drape, trim, summary);
    }
    let mut pslg = lines.clean(&clean_options(o))?;
    summary.vertices = pslg.vertices.len() as u64;
    summary.segments = pslg.segments.len() as u64;
    summary.clean = pslg.stats;
    summary.z_conflicts = pslg.warnings.clone();
    let unknown: Vec<u32> = (0..pslg.vertices.len() as u32)
        .filter(|&v| pslg.vertices[v as usize][2].is_nan())
        .collect();
    if !unknown.is_empty() {
        let Some(drape) = drape else {
            return Err(no_z_error(&lines, &pslg, unknown.len()));
        };
        let xy: Vec<[f64; 2]> = unknown
            .iter()
            .map(|&v| {
                let p = pslg.vertices[v as usize];
                [p[0], p[1]]
            })
            .collect();
        let mut sink = DrapeSink::new(xy);
        drape(&mut sink)?;
        for (k, &v) in unknown.iter().enumerate() {
            let z = sink.z[k];
            if z.is_nan() {
                return Err(outside_error(&lines, &pslg, v));
            }
            pslg.vertices[v as usize][2] = z;
        }
        summary.draped = unknown.len() as u64;
    }
    Ok(Prepared {
        pslg: Some(pslg),
        feed: Default::default(),
        trim,
        flat: o.no_flat_triangles,
        summary,
    })
}

fn clean_options(o: &LineOptions) -> CleanOptions {
    let mut opts = CleanOptions::default();
    if let Some(t) = o.z_tolerance {
        opts.z_tolerance = t;
    }
    opts
}

/// [`Error::Format`] naming the vertex of the polyline `p` (from `source`) outside the range of
/// the predicates.
fn check_coords(p: &[[f64; 3]], source: &Source) -> Result<()> {
    for (k, v) in p.iter().enumerate() {
        if !(check_coord(v[0]) && check_coord(v[1])) {
            return Err(Error::Format {
                path: source.path.to_path_buf(),
                message: format!(
                    "{source}, vertex {k}: coordinate ({}, {}) is outside the supported range",
                    v[0], v[1]
                ),
            });
        }
    }
    Ok(())
}

/// The polylines of a [`LineStream`] for the streamed cleaner: each checked as it is read
/// ([`check_coords`]), and counted.
struct Checked<'a> {
    lines: &'a LineStream,
    count: std::cell::Cell<u64>,
    /// The most vertices the reader held at once.
    held: std::cell::Cell<u64>,
}

impl PolylineSource for Checked<'_> {
    fn for_each_polyline(&self, f: &mut dyn FnMut(&[[f64; 3]]) -> Result<()>) -> Result<()> {
        let mut n = 0u64;
        let held = self.lines.for_each(&mut |l, s| {
            check_coords(l, s)?;
            n += 1;
            f(l)
        })?;
        self.count.set(n);
        self.held.set(self.held.get().max(held));
        Ok(())
    }
}

/// The lines of `lines` cleaned by the streamed cleaner within `b`, draped with `drape`, their
/// graph sorted for the sweep ([`super::line_feed`]): the polylines are read once (twice with
/// mixed heights) and never held.
///
/// # Errors
/// The readers', the cleaner's, the sorts' and the draping pass's.
fn streamed(
    lines: &LineStream,
    o: &LineOptions,
    b: LineBudget,
    drape: Drape,
    trim: Trim,
    mut summary: LineSummary,
) -> Result<Prepared> {
    let source = Checked {
        lines,
        count: Default::default(),
        held: Default::default(),
    };
    // Half of --mem for the cleaner's sorts, a quarter for the half-edges', which stay open (as
    // much as fits in that quarter) while the points are read with the other half.
    let cleaned = crate::breaklines::clean::stream::clean_streamed(
        &source,
        &clean_options(o),
        b.mem / 2,
        b.tmp,
    )
    .map_err(|e| crate::input::lines::name_bad_line(e, |p| lines.source(p)))?;
    summary.polylines = source.count.get();
    // Mixed heights: the cleaner read them all into memory.
    summary.read_held_vertices = if cleaned.held.in_memory {
        cleaned.stats.input_vertices
    } else {
        source.held.get()
    };
    if summary.polylines == 0 {
        return Ok(Prepared::none(trim, false, summary));
    }
    summary.vertices = cleaned.stats.vertices;
    summary.segments = cleaned.stats.segments;
    summary.clean = cleaned.stats;
    summary.z_conflicts = cleaned.warnings.clone();
    summary.cleaner = Some(cleaned.held);
    let mut feed = super::line_feed::build(cleaned, b.mem / 4, b.tmp)?;
    summary.draped = feed.drape(drape, &|l| lines.source(l))?;
    Ok(Prepared {
        pslg: None,
        feed: std::sync::Mutex::new(Some(feed)),
        trim,
        flat: false,
        summary,
    })
}

/// The boundary and hole rings of `o` as read with `read`, and the trimming rules they make
/// with `--max-edge`.
///
/// # Errors
/// The readers' errors; [`Error::Format`] for rings that are not closed or an empty boundary,
/// naming the file.
fn read_trim(
    o: &LineOptions,
    read: &ReadLines<'_>,
) -> Result<(Option<Lines>, Option<Lines>, Trim)> {
    let boundary = o.boundary.as_deref().map(read).transpose()?;
    let holes = o.holes.as_deref().map(read).transpose()?;
    let trim = Trim::from_lines(boundary.as_ref(), holes.as_ref(), o.max_edge).map_err(|e| {
        match (e, &o.boundary) {
            // `Trim` has no file name for an empty boundary: add it.
            (Error::Format { path, message }, Some(b)) if path.as_os_str().is_empty() => {
                Error::Format {
                    path: b.clone(),
                    message,
                }
            }
            (e, _) => e,
        }
    })?;
    Ok((boundary, holes, trim))
}

/// The trimming rules of `o` alone (boundary, holes, `--max-edge`), the rings read with
/// `read`: what a TIN plan's merge applies to the tasks' pieces, which hold every triangle.
///
/// # Errors
/// As [`read_trim`].
pub(crate) fn trim(o: &LineOptions, read: &ReadLines<'_>) -> Result<Trim> {
    read_trim(o, read).map(|(_, _, t)| t)
}

/// The error for `count` vertices of the cleaned graph without z when nothing can drape them:
/// names the first input vertex without z that cleaning left without one (file, feature or
/// line, vertex), and what to do.
fn no_z_error(lines: &Lines, pslg: &Pslg, count: usize) -> Error {
    let key = |x: f64, y: f64| ((x + 0.0).to_bits(), (y + 0.0).to_bits());
    let unknown: crate::idmap::FastSet<(u64, u64)> = pslg
        .vertices
        .iter()
        .filter(|v| v[2].is_nan())
        .map(|v| key(v[0], v[1]))
        .collect();
    let first = lines.polylines.iter().enumerate().find_map(|(i, p)| {
        p.iter()
            .position(|v| v[2].is_nan() && unknown.contains(&key(v[0], v[1])))
            .map(|k| (i, k, p[k]))
    });
    let more = match count {
        1 => String::new(),
        2 => " (nor has one more vertex of the cleaned lines)".to_string(),
        n => format!(" (nor have {} more vertices of the cleaned lines)", n - 1),
    };
    let what = "a plan's tasks cannot drape lines on the points (each reads only the files near \
                its tile): give every vertex a z (for lines as text, `x y` a line and a blank \
                line between lines, `sweeptin sample FILES… --points lines.txt -o lines_z.txt` \
                appends the TIN's height to every line), or run the job as one command without \
                `plan`, which drapes them";
    match first {
        Some((i, k, v)) => {
            let s = &lines.sources[i];
            Error::Options(format!(
                "{s}, vertex {k} ({}, {}) has no z{more}: {what}",
                v[0], v[1]
            ))
        }
        None => Error::Options(format!(
            "breaklines: {count} vertices of the cleaned lines have no z: {what}"
        )),
    }
}

/// The error for a vertex without z outside the points' TIN, naming a line through it.
fn outside_error(lines: &Lines, pslg: &Pslg, v: u32) -> Error {
    let p = pslg.vertices[v as usize];
    let line = pslg
        .segments
        .iter()
        .position(|s| s.contains(&v))
        .map(|s| pslg.lines[s] as usize);
    outside_error_at([p[0], p[1]], line.and_then(|l| lines.sources.get(l)))
}

/// The error for the vertex at `p` without z outside the points' TIN, naming a line `source`
/// through it if there is one.
pub(super) fn outside_error_at(p: [f64; 2], source: Option<&Source>) -> Error {
    let message = format!(
        "breakline vertex ({}, {}) has no z and lies outside the triangulation of the points, so \
         no height can be taken from them: give the line z values or clip it to the point cloud",
        p[0], p[1]
    );
    match source {
        Some(s) => Error::Format {
            path: s.path.to_path_buf(),
            message: format!("{s}: {message}"),
        },
        None => Error::Invalid(message),
    }
}

/// Heights of query points from the triangle stream (the draping pass).
pub(super) struct DrapeSink {
    xy: Vec<[f64; 2]>,
    /// The height of each query point (NaN: outside the triangulation).
    pub(super) z: Vec<f64>,
    grid: Grid,
    buckets: Buckets,
}

impl DrapeSink {
    pub(super) fn new(xy: Vec<[f64; 2]>) -> DrapeSink {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &xy {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let grid = Grid::new(lo, hi, xy.len());
        let buckets = Buckets::points(&grid, &xy);
        DrapeSink {
            z: vec![f64::NAN; xy.len()],
            xy,
            grid,
            buckets,
        }
    }
}

impl TriangleSink for DrapeSink {
    fn begin(&mut self, _info: &super::StreamInfo) -> Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        let lo = [
            t[0][0].min(t[1][0]).min(t[2][0]),
            t[0][1].min(t[1][1]).min(t[2][1]),
        ];
        let hi = [
            t[0][0].max(t[1][0]).max(t[2][0]),
            t[0][1].max(t[1][1]).max(t[2][1]),
        ];
        // The products' canonical triangle and valuation (on an edge or a vertex, from that edge
        // or vertex alone), so a draped height does not depend on which of the triangles around
        // it comes first or how its corners are rotated: tiles and the sweep give them in other
        // orders, and gave heights 1 ulp apart.
        let Some(tri) = Tri::new(t) else {
            return Ok(());
        };
        let (xy, z, buckets) = (&self.xy, &mut self.z, &self.buckets);
        self.grid.box_cells(lo, hi, |c| {
            for &q in buckets.cell(c) {
                let q = q as usize;
                if z[q].is_nan() {
                    let loc = tri.locate(xy[q]);
                    if loc != Location::Outside {
                        z[q] = tri.value_at(xy[q], loc);
                    }
                }
            }
        });
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        Ok(ProductSummary::None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draping_is_linear_closed_and_independent_of_order() {
        let drape = |tris: &[[[f64; 3]; 3]], q: &[[f64; 2]]| {
            let mut s = DrapeSink::new(q.to_vec());
            for t in tris {
                s.triangle(t).unwrap();
            }
            s.z
        };
        let t = [[0.0, 0.0, 0.0], [4.0, 0.0, 4.0], [0.0, 4.0, 8.0]];
        let q = [[1.0, 1.0], [2.0, 2.0], [0.0, 0.0], [2.0, 2.1]];
        let z = drape(&[t], &q);
        assert_eq!(&z[..3], &[3.0, 6.0, 0.0]); // inside, on the edge, a corner
        assert!(z[3].is_nan());
        assert_eq!(drape(&[[t[0], t[2], t[1]]], &q[..1]), vec![3.0]); // clockwise
        // Two triangles on one edge, in either order and with their corners rotated: a point on
        // the shared edge, and inside, gets the same bits (tiles and the sweep differ in both).
        let (a, b) = ([0.0, 0.0, 2.9], [4.0, 4.0, 0.7]);
        let (c, d) = ([4.0, 0.0, 1.3], [0.0, 4.0, 0.3]);
        let q = [[2.0, 2.0], [3.1, 0.7], [0.3, 2.9]];
        let want = drape(&[[a, c, b], [a, b, d]], &q);
        assert!(want.iter().all(|z| !z.is_nan()));
        for tris in [[[b, a, d], [c, b, a]], [[d, a, b], [b, a, c]]] {
            let got = drape(&tris, &q);
            let bits = |z: &[f64]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&want), bits(&got));
        }
    }
}
