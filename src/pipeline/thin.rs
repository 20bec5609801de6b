//! The input side of `sweeptin thin`: the points of a run (filters, `--bbox`, duplicates merged
//! by `--duplicates`), its breaklines (cleaned and draped as for `tin`), and the thinning itself
//! ([`crate::simplify::thin()`]), whose result the caller writes to a mesh sink.
//!
//! The thinning holds every point in memory (see [`mod@crate::simplify::thin`] for why): about
//! [`THIN_BYTES_PER_POINT`] bytes per point at the peak (reading and sorting). The job is checked
//! against `--mem` from the LAS/LAZ headers' point counts before anything is read, and refused
//! when it does not fit.
//! `sweeptin thin --tile` runs in bounded memory instead: [`super::thin_tiles`].

use super::{RunConfig, Source, lines};
use crate::error::{Error, Result};
use crate::geom::predicates;
use crate::input::las::FilterStats;
use crate::simplify::{ThinLines, ThinOptions, Thinned};
use crate::sort::memory::DuplicatePolicy;
use rayon::prelude::*;

/// Peak bytes per point (of the headers' count, before filters) while reading and sorting: the
/// points, their sort order and distinct copy, then the points with their bucket links (ARSO:
/// 548 MiB for 13.2 M points in the headers, 9.0 M ground points read).
pub const THIN_BYTES_PER_POINT: u64 = 64;

/// What `sweeptin thin` did (its `--json` summary).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ThinSummary {
    /// Points read (after filters).
    pub points_read: u64,
    /// Exact (x, y) duplicates merged away (among the points, and with breakline vertices).
    pub duplicates: u64,
    /// The thinning: kept points, errors, triangles.
    pub thin: crate::simplify::ThinStats,
    /// Triangles left out by `--trim-boundary` / `--holes`.
    pub trimmed_triangles: u64,
    /// Breaklines, when given.
    pub breaklines: Option<lines::LineSummary>,
    /// What the LAS/LAZ filters dropped.
    pub filters: Option<FilterStats>,
    /// The CRS, when known.
    pub crs: Option<String>,
    /// What the output mesh is (constrained by breaklines, trimmed, not Delaunay across
    /// `--tile` borders), for its writer ([`crate::sink::MeshSink::declare`]).
    pub mesh: crate::validate::MeshKind,
    /// Seconds reading (and sorting) the points.
    pub read_seconds: f64,
    /// Peak resident memory (VmHWM), when the OS reports it.
    pub peak_rss_bytes: Option<u64>,
    /// With `--tile`: the tiles.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tiles: Option<super::thin_tiles::ThinTileSummary>,
    /// What the input files' headers say that did not stop the run
    /// ([`crate::input::las::LidarReader::warnings`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Reads the points and breaklines of `config` and thins them within `options.max_error`.
/// Triangles outside `--trim-boundary` or inside `--holes` are left out of the result (their
/// rings are breaklines, so no triangle straddles one).
///
/// # Errors
/// [`Error::Options`] when the job cannot fit in `--mem`, for a streaming mesh as input, or for
/// `--max-edge` and `--no-flat-triangles` (which would uncover points); reader and breakline
/// errors; the errors of [`crate::simplify::thin()`].
pub fn thin(config: &RunConfig, options: &ThinOptions) -> Result<(Thinned, ThinSummary)> {
    let input = config.input();
    let l = &input.lines;
    if l.max_edge.is_some() || l.no_flat_triangles {
        return Err(Error::Options(
            "thin keeps every point within --max-error of its triangles: --max-edge and \
             --no-flat-triangles would break that, and are not available"
                .into(),
        ));
    }
    let source = config.source();
    if source == Source::Stream {
        return Err(Error::Options(
            "thin needs points: a streaming mesh (.stin) holds a triangulation".into(),
        ));
    }
    let mem = config.options().mem;
    let start = std::time::Instant::now();
    let mut summary = ThinSummary::default();
    let points = if source == Source::Lidar {
        let mut r = config.open_lidar(crate::input::las::ReadOptions::default())?;
        let count = r.point_count();
        let need = count.saturating_mul(THIN_BYTES_PER_POINT);
        if need > mem {
            return Err(too_big(count, need, mem));
        }
        let mut pts: Vec<[f64; 3]> = Vec::with_capacity(count as usize);
        let mut chunk = Vec::new();
        loop {
            chunk.clear();
            if r.read_chunk(&mut chunk, 1 << 18)? == 0 {
                break;
            }
            pts.extend(chunk.iter().map(|p| [p.x, p.y, p.z]));
        }
        summary.filters = Some(*r.stats());
        summary.warnings = r.warnings();
        pts
    } else {
        let (pts, _) = super::read_points(input)?;
        let need = (pts.len() as u64).saturating_mul(THIN_BYTES_PER_POINT);
        if need > mem {
            return Err(too_big(pts.len() as u64, need, mem));
        }
        pts
    };
    summary.points_read = points.len() as u64;
    summary.crs = config.input_crs()?;
    for (i, p) in points.iter().enumerate() {
        check_point(i as u64, *p)?;
    }
    let mut points = distinct(points, input.duplicates);
    summary.duplicates = summary.points_read - points.len() as u64;
    summary.read_seconds = start.elapsed().as_secs_f64();

    let points_only = config.points_only();
    let prepared = if l.is_empty() {
        None
    } else {
        let p = lines::prepare(
            l,
            config.read_lines(),
            Some(&mut |sink| {
                if let Some(s) = config.stream_input() {
                    return Err(Error::Options(format!(
                        "{}: lines without z take their heights from a first pass over the points, \
                     but this input is a pipe or a device, which can be read only once: give \
                     the points as a file, or the lines with z",
                        s.display()
                    )));
                }
                super::drive::run(&points_only, None, None, &mut [sink]).map(|_| ())
            }),
        )?;
        Some(p)
    };
    let (line_vertices, segments) = match prepared.as_ref().and_then(|p| p.pslg.as_ref()) {
        Some(g) => {
            let mut v = g.vertices.clone();
            summary.duplicates += merge_line_vertices(&mut points, &mut v, input.duplicates);
            (v, g.segments.clone())
        }
        None => (Vec::new(), Vec::new()),
    };
    let lines = ThinLines {
        vertices: &line_vertices,
        segments: &segments,
    };
    let mut out = crate::simplify::thin(points, lines, options)?;
    if let Some(p) = &prepared {
        summary.breaklines = Some(p.summary.clone());
        if !p.trim.keeps_all() {
            summary.trimmed_triangles = trim(&mut out, &p.trim);
        }
    }
    summary.thin = out.stats.clone();
    summary.mesh = l.mesh_kind();
    Ok((out, summary))
}

/// The predicates' range check of one input point.
pub(super) fn check_point(index: u64, p: [f64; 3]) -> Result<()> {
    if !p.iter().all(|c| c.is_finite()) {
        return Err(Error::NonFinite {
            index,
            x: p[0],
            y: p[1],
            z: p[2],
        });
    }
    for &value in &p[..2] {
        if !predicates::check_coord(value) {
            return Err(Error::CoordinateOutOfRange {
                index,
                value,
                max: predicates::MAX_COORD,
                min: predicates::MIN_NONZERO_COORD,
            });
        }
    }
    Ok(())
}

fn too_big(count: u64, need: u64, mem: u64) -> Error {
    Error::Options(format!(
        "thin holds every point in memory: {count} points (before filters) need about {} \
         ({THIN_BYTES_PER_POINT} bytes each), more than --mem {}: raise --mem, or thin \
         smaller areas with --bbox",
        crate::human_bytes(need),
        crate::human_bytes(mem)
    ))
}

/// The distinct positions of `points`, sorted by `y` then `x`, duplicates merged by `policy`
/// (input order decides ties, as in the sweep).
fn distinct(points: Vec<[f64; 3]>, policy: DuplicatePolicy) -> Vec<[f64; 3]> {
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    let key = |i: u32| {
        let p = points[i as usize];
        (p[1], p[0])
    };
    order.par_sort_unstable_by(|&a, &b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.total_cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then(a.cmp(&b))
    });
    let mut out: Vec<[f64; 3]> = Vec::with_capacity(points.len());
    let mut i = 0;
    while i < order.len() {
        let mut keep = order[i];
        let mut j = i + 1;
        while j < order.len() && key(order[j]) == key(order[i]) {
            let c = order[j];
            let (zc, zk) = (points[c as usize][2], points[keep as usize][2]);
            if policy.prefers((zc, u64::from(c)), (zk, u64::from(keep))) {
                keep = c;
            }
            j += 1;
        }
        out.push(points[keep as usize]);
        i = j;
    }
    out
}

/// Merges points at exactly a breakline vertex's position into that vertex (the line counts as
/// read after every point, as in `tin`: `first` keeps the point's z, `last` the line's); the
/// point leaves `points`. Returns the number of points merged.
fn merge_line_vertices(
    points: &mut Vec<[f64; 3]>,
    vertices: &mut [[f64; 3]],
    policy: DuplicatePolicy,
) -> u64 {
    let mut gone = vec![false; points.len()];
    let mut merged = 0;
    for v in vertices.iter_mut() {
        let found = points.binary_search_by(|p| p[1].total_cmp(&v[1]).then(p[0].total_cmp(&v[0])));
        if let Ok(i) = found {
            let z = points[i][2];
            if !policy.prefers((v[2], u64::MAX), (z, i as u64)) {
                v[2] = z;
            }
            gone[i] = true;
            merged += 1;
        }
    }
    if merged > 0 {
        let mut k = 0;
        points.retain(|_| {
            k += 1;
            !gone[k - 1]
        });
    }
    merged
}

/// Drops the triangles `trim` does not keep, and the vertices no kept triangle uses.
fn trim(out: &mut Thinned, trim: &crate::breaklines::Trim) -> u64 {
    let before = out.triangles.len();
    let v = &out.vertices;
    out.triangles
        .retain(|t| trim.keep(&t.map(|i| v[i as usize])));
    let mut used = vec![u32::MAX; out.vertices.len()];
    let mut vertices = Vec::new();
    let mut index = Vec::new();
    for t in &mut out.triangles {
        for i in t.iter_mut() {
            if used[*i as usize] == u32::MAX {
                used[*i as usize] = vertices.len() as u32;
                vertices.push(out.vertices[*i as usize]);
                index.push(out.is_point[*i as usize]);
            }
            *i = used[*i as usize];
        }
    }
    out.vertices = vertices;
    out.is_point = index;
    out.stats.triangles = out.triangles.len() as u64;
    out.stats.vertices = out.vertices.len() as u64;
    out.stats.kept = out.is_point.iter().filter(|&&p| p).count() as u64;
    out.stats.line_vertices = out.stats.vertices - out.stats.kept;
    out.stats.kept_ratio = out.stats.kept as f64 / out.stats.points.max(1) as f64;
    out.stats.vertex_ratio = out.stats.vertices as f64 / out.stats.points.max(1) as f64;
    (before - out.triangles.len()) as u64
}
