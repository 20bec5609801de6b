//! Contour lines (height lines) from the triangle stream, stitched into polylines.
//!
//! # Levels and the rule at a level
//!
//! Levels are `base + k × interval` for whole `k`. A vertex whose `z` equals a level exactly
//! counts as **above** it (as if raised by an infinitesimal amount). Then every triangle crosses a
//! level in at most one segment, from one edge to another edge whose endpoints lie on opposite
//! sides; a triangle lying flat at a level is above it and has no segment. Segments of
//! neighbouring triangles meet on their shared edge, at a point computed from that edge alone (the
//! same bits from both sides), so lines have no gaps and no segment is produced twice. Where a
//! vertex lies exactly at a level, several segments meet at that vertex, and zero-length segments
//! may occur; they are kept for the topology and their repeated points dropped on output.
//!
//! Every line runs with the higher ground on its **left**.
//!
//! # Stitching across the stream
//!
//! A segment is keyed by the two edges it crosses (edge = its two endpoints in canonical order,
//! plus the level). Open polylines are found by the edge where they start and the edge where they
//! end (two hash maps): a new segment extends, prepends to or joins open polylines, or closes one
//! into a ring, which is written at once. This works for triangles in any order; the watermark is
//! not needed. Polylines that reach the outer boundary of the TIN stay open until the end of the
//! stream and are then written as open lines.
//!
//! # Memory
//!
//! Open polylines keep their two end points and end edges in memory; when their points exceed
//! [`ContourOptions::memory_points`], the inner points are moved to an anonymous scratch file and
//! read back when the line is written. Memory is thus bounded by the number of open polylines
//! (those crossing the sweep's front, and those ending on the TIN's boundary so far), not by their
//! length.

use super::geom::{Tri, cmp_xy};
use crate::error::{Error, Result};
use crate::output::lines::LineWriter;
use crate::sink::{ContourSummary, Needs, ProductSummary, StreamInfo, TriangleSink, Wants};
use serde_json::json;
use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Options of a [`ContourSink`].
#[derive(Clone, Debug)]
pub struct ContourOptions {
    /// Distance between levels (> 0).
    pub interval: f64,
    /// A level through which the others are counted (levels are `base + k × interval`).
    pub base: f64,
    /// Points of open polylines held in memory before the inner ones move to a scratch file.
    pub memory_points: usize,
    /// For a task of a plan: write open lines whole (repeated points and one-point pieces
    /// kept) with the edges they start and end on (`start_edge`, `end_edge`: the edge's
    /// endpoints `[x0, y0, x1, y1]` in canonical order), so that the merge joins them exactly
    /// as one run would. Such lines are written exactly: `decimals` and `min_length` apply
    /// when the merge joins them.
    pub edges: bool,
    /// Decimals of the written coordinates (`None`: every bit, the shortest decimal that reads
    /// back as the same double). [`default_decimals`] gives the data's.
    pub decimals: Option<u32>,
    /// Lines (rings included) shorter than this, in map units, are left out (0: none).
    pub min_length: f64,
}

/// Decimals of contour coordinates when the input's scale is unknown (XYZ text, `.stin`):
/// millimetres in metric data.
pub const DEFAULT_DECIMALS: u32 = 3;

/// The decimals contour coordinates of the points in `inputs` are written with by default:
/// those of the finest horizontal scale of LAS/LAZ inputs (`0.01` gives 2: no finer than the
/// points themselves; [`crate::input::las::LidarReader::xy_decimals`]), else
/// [`DEFAULT_DECIMALS`].
pub fn default_decimals(inputs: &[PathBuf]) -> u32 {
    match crate::pipeline::Source::of(inputs) {
        Ok(crate::pipeline::Source::Lidar) => {
            crate::input::las::LidarReader::header_xy_decimals(inputs)
        }
        _ => None,
    }
    .unwrap_or(DEFAULT_DECIMALS)
}

impl Default for ContourOptions {
    fn default() -> Self {
        ContourOptions {
            interval: 1.0,
            base: 0.0,
            memory_points: 1 << 22,
            edges: false,
            decimals: None,
            min_length: 0.0,
        }
    }
}

impl ContourOptions {
    /// These options holding the open polylines' points within an eighth of `mem` bytes (the
    /// run's `--mem`), at 32 bytes a point (the point and its deque's slack): between 4096
    /// points and the default.
    #[must_use]
    pub fn within(mut self, mem: u64) -> Self {
        let points = usize::try_from(mem / 8 / 32).unwrap_or(usize::MAX);
        self.memory_points = points.clamp(1 << 12, ContourOptions::default().memory_points);
        self
    }
}

/// Most levels one triangle may cross (a guard against a tiny interval).
const MAX_LEVELS_PER_TRIANGLE: i64 = 1_000_000;

/// The levels of a contour sink: `base + k × interval` ([`level_value`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContourLevels {
    /// A level through which the others are counted.
    pub base: f64,
    /// Distance between levels (> 0).
    pub interval: f64,
}

/// The least and greatest height of a triangle's vertices.
fn heights(t: &[[f64; 3]; 3]) -> (f64, f64) {
    (
        t[0][2].min(t[1][2]).min(t[2][2]),
        t[0][2].max(t[1][2]).max(t[2][2]),
    )
}

impl ContourLevels {
    /// The heights of `t`, and the levels `k_lo..=k_hi` it may cross (one more on each side),
    /// as floating-point numbers (a tiny interval or a far base gives indices beyond `i64`).
    fn span(&self, t: &[[f64; 3]; 3]) -> (f64, f64, f64, f64) {
        let (zmin, zmax) = heights(t);
        let k_lo = ((zmin - self.base) / self.interval).floor() - 1.0;
        let k_hi = ((zmax - self.base) / self.interval).ceil() + 1.0;
        (zmin, zmax, k_lo, k_hi)
    }

    /// The levels `t` crosses (`zmin < level ≤ zmax`), or `Err` with its heights and its span
    /// of levels when that is more than [`MAX_LEVELS_PER_TRIANGLE`], or its levels lie more
    /// than 2^52 intervals from the base (where level indices are no longer exact: an
    /// interval of 1e-19 hung, a base of 1e19 wrote no line).
    fn crossed(
        &self,
        t: &[[f64; 3]; 3],
    ) -> std::result::Result<impl Iterator<Item = i64>, (f64, f64, f64)> {
        let (zmin, zmax, lo, hi) = self.span(t);
        const EXACT: f64 = (1u64 << 52) as f64;
        let span = hi - lo;
        if !(span <= MAX_LEVELS_PER_TRIANGLE as f64 && lo.abs() <= EXACT && hi.abs() <= EXACT) {
            return Err((zmin, zmax, span));
        }
        let (k_lo, k_hi) = (lo as i64, hi as i64);
        let levels = *self;
        Ok((k_lo..=k_hi).filter(move |&k| {
            let l = level_value(levels.base, levels.interval, k);
            zmin < l && l <= zmax
        }))
    }
}

/// What a contour sink needs: the triangles that cross a level, or span too many (an error the
/// sink must raise). The sink's own test (`ContourLevels::crossed`).
///
/// Most triangles of dense lidar lie between two levels: a quick test rejects them without the
/// levels' rounding. A level `L` of index `k` is within `E = 4e-9 · max(|z|, |base|, 1)` of
/// `base + k × interval` (`level_value` cleans it by at most `1e-9 · max(|L|, 1)`; the floating
/// sums err by far less), so a level in `(zmin, zmax]` has `k` in `[a, b]`, with
/// `a = (zmin − base − E) / interval` and `b = (zmax − base + E) / interval` (their own rounding
/// is below `1e-15` of the magnitudes, far inside `E`): with no integer in `[a, b]` there is no
/// such level.
impl Wants for ContourLevels {
    fn wants(&self, t: &[[f64; 3]; 3]) -> bool {
        let (zmin, zmax) = heights(t);
        let e = 4e-9 * zmin.abs().max(zmax.abs()).max(self.base.abs()).max(1.0);
        let a = (zmin - self.base - e) / self.interval;
        let b = (zmax - self.base + e) / self.interval;
        if a.is_finite() && b.is_finite() && b.floor() < a.ceil() {
            return false;
        }
        self.crossed(t).map_or(true, |mut ks| ks.next().is_some())
    }
}

/// Level `k` as a number: `base + k × interval`, cleaned of binary noise (`0.30000000000000004`
/// becomes `0.3`) when that changes it by less than a billionth.
pub fn level_value(base: f64, interval: f64, k: i64) -> f64 {
    let l = base + k as f64 * interval;
    let r = (l * 1e6).round() / 1e6;
    if (r - l).abs() <= 1e-9 * l.abs().max(1.0) {
        r
    } else {
        l
    }
}

/// An edge at a level: `(k, bits of the smaller endpoint's x, y, of the larger's x, y)`.
type EdgeKey = (i64, [u64; 4]);

fn edge_key(k: i64, a: &[f64; 3], b: &[f64; 3]) -> EdgeKey {
    let (a, b) = if cmp_xy(a, b).is_gt() { (b, a) } else { (a, b) };
    (
        k,
        [
            a[0].to_bits(),
            a[1].to_bits(),
            b[0].to_bits(),
            b[1].to_bits(),
        ],
    )
}

/// Where the edge `a b` crosses `level` (one endpoint below, the other at or above), computed
/// from the endpoints in canonical order.
fn crossing(level: f64, a: &[f64; 3], b: &[f64; 3]) -> [f64; 2] {
    let (a, b) = if cmp_xy(a, b).is_gt() { (b, a) } else { (a, b) };
    let t = (level - a[2]) / (b[2] - a[2]);
    if t <= 0.0 {
        [a[0], a[1]]
    } else if t >= 1.0 {
        [b[0], b[1]]
    } else {
        [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
    }
}

/// A run of points of an open polyline: in memory, or moved to the scratch file.
#[derive(Debug)]
enum Piece {
    Mem(VecDeque<[f64; 2]>),
    Disk { offset: u64, len: u64 },
}

#[derive(Debug)]
struct Poly {
    k: i64,
    pieces: VecDeque<Piece>,
    first: [f64; 2],
    start: EdgeKey,
    end: EdgeKey,
}

impl Poly {
    fn push_back(&mut self, p: [f64; 2]) {
        match self.pieces.back_mut() {
            Some(Piece::Mem(v)) => v.push_back(p),
            _ => self.pieces.push_back(Piece::Mem(VecDeque::from([p]))),
        }
    }

    fn push_front(&mut self, p: [f64; 2]) {
        self.first = p;
        match self.pieces.front_mut() {
            Some(Piece::Mem(v)) => v.push_front(p),
            _ => self.pieces.push_front(Piece::Mem(VecDeque::from([p]))),
        }
    }

    /// Appends `other`'s pieces, merging two touching in-memory pieces.
    fn append(&mut self, other: Poly) {
        for piece in other.pieces {
            match (self.pieces.back_mut(), piece) {
                (Some(Piece::Mem(a)), Piece::Mem(b)) => a.extend(b),
                (_, piece) => self.pieces.push_back(piece),
            }
        }
        self.end = other.end;
    }

    /// Prepends `other`'s pieces.
    fn prepend(&mut self, other: Poly) {
        for piece in other.pieces.into_iter().rev() {
            match (self.pieces.front_mut(), piece) {
                (Some(Piece::Mem(a)), Piece::Mem(b)) => {
                    for p in b.into_iter().rev() {
                        a.push_front(p);
                    }
                }
                (_, piece) => self.pieces.push_front(piece),
            }
        }
        self.first = other.first;
        self.start = other.start;
    }

    fn mem_points(&self) -> usize {
        self.pieces
            .iter()
            .map(|p| match p {
                Piece::Mem(v) => v.len(),
                Piece::Disk { .. } => 0,
            })
            .sum()
    }
}

/// Open polylines, found by their start and end edges.
#[derive(Debug, Default)]
struct Stitcher {
    polys: Vec<Option<Poly>>,
    free: Vec<usize>,
    starts: HashMap<EdgeKey, usize>,
    ends: HashMap<EdgeKey, usize>,
    max_open: usize,
}

/// What adding a segment did: the points it added to open polylines, or the ring it closed.
enum Added {
    Open(usize),
    Closed(Poly),
}

impl Stitcher {
    fn store(&mut self, p: Poly) -> usize {
        let (start, end) = (p.start, p.end);
        let id = match self.free.pop() {
            Some(i) => {
                self.polys[i] = Some(p);
                i
            }
            None => {
                self.polys.push(Some(p));
                self.polys.len() - 1
            }
        };
        self.starts.insert(start, id);
        self.ends.insert(end, id);
        self.max_open = self.max_open.max(self.starts.len());
        id
    }

    fn take(&mut self, id: usize) -> Poly {
        self.free.push(id);
        let p = self.polys[id].take().expect("a live polyline");
        self.starts.remove(&p.start);
        self.ends.remove(&p.end);
        p
    }

    /// Adds the segment `s → e`, which crosses edge `se` at `s` and edge `ee` at `e`.
    fn add(&mut self, k: i64, se: EdgeKey, s: [f64; 2], ee: EdgeKey, e: [f64; 2]) -> Added {
        let before = self.ends.get(&se).copied();
        let after = self.starts.get(&ee).copied();
        match (before, after) {
            (None, None) => {
                self.store(Poly {
                    k,
                    pieces: VecDeque::from([Piece::Mem(VecDeque::from([s, e]))]),
                    first: s,
                    start: se,
                    end: ee,
                });
                Added::Open(2)
            }
            (Some(a), None) => {
                let mut p = self.take(a);
                p.push_back(e);
                p.end = ee;
                self.store(p);
                Added::Open(1)
            }
            (None, Some(b)) => {
                let mut p = self.take(b);
                p.push_front(s);
                p.start = se;
                self.store(p);
                Added::Open(1)
            }
            (Some(a), Some(b)) if a == b => {
                let mut p = self.take(a);
                p.push_back(e);
                Added::Closed(p)
            }
            (Some(a), Some(b)) => {
                let pa = self.take(a);
                let pb = self.take(b);
                let joined = if pa.mem_points() >= pb.mem_points() {
                    let mut pa = pa;
                    pa.append(pb);
                    pa
                } else {
                    let mut pb = pb;
                    pb.prepend(pa);
                    pb
                };
                self.store(joined);
                Added::Open(0)
            }
        }
    }
}

/// Counters reported by [`ContourSink::finish`].
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
struct Stats {
    segments: u64,
    rings: u64,
    open_lines: u64,
    degenerate_dropped: u64,
    short_dropped: u64,
    points_spilled: u64,
}

/// A [`TriangleSink`] writing contour lines to GeoJSON (see the module docs).
pub struct ContourSink {
    path: PathBuf,
    options: ContourOptions,
    out: Option<LineWriter>,
    stitcher: Stitcher,
    scratch: Option<File>,
    scratch_len: u64,
    mem_points: usize,
    /// Points in memory that make the next spill: [`ContourOptions::memory_points`] more than a
    /// spill left (short pieces stay), so that a spill that frees little is not repeated at
    /// every segment.
    spill_at: usize,
    stats: Stats,
}

impl ContourSink {
    /// A contour sink writing to `path` (created when the stream begins).
    ///
    /// # Errors
    /// [`Error::Options`] for an interval that is not a positive number, a non-finite base,
    /// a minimum length that is not a distance `>= 0`, too many decimals or an output that is
    /// neither GeoJSON nor GeoPackage ([`crate::output::lines::LineFormat::of`]).
    pub fn new(path: &Path, options: ContourOptions) -> Result<ContourSink> {
        if !(options.interval.is_finite() && options.interval > 0.0 && options.base.is_finite()) {
            return Err(Error::Options(format!(
                "the contour interval must be a positive number and the base finite \
                 (--interval {}, --base {})",
                options.interval, options.base
            )));
        }
        if !(options.min_length.is_finite() && options.min_length >= 0.0) {
            return Err(Error::Options(format!(
                "--min-length must be a length >= 0 in map units, not {}",
                options.min_length
            )));
        }
        if let Some(d) = options
            .decimals
            .filter(|&d| d > crate::output::lines::MAX_DECIMALS)
        {
            return Err(Error::Options(format!(
                "--precision {d}: at most {} decimals (a double holds no more)",
                crate::output::lines::MAX_DECIMALS
            )));
        }
        // GeoJSON or GeoPackage: `-o x.shp` once wrote GeoJSON under that name.
        let format = crate::output::lines::LineFormat::of(path)?;
        if options.edges && format != crate::output::lines::LineFormat::GeoJson {
            return Err(Error::Internal(
                "a plan's task writes its contour pieces as GeoJSON".into(),
            ));
        }
        Ok(ContourSink {
            path: path.to_path_buf(),
            spill_at: options.memory_points,
            options,
            out: None,
            stitcher: Stitcher::default(),
            scratch: None,
            scratch_len: 0,
            mem_points: 0,
            stats: Stats::default(),
        })
    }

    fn out(&mut self) -> Result<&mut LineWriter> {
        let path = &self.path;
        self.out.as_mut().ok_or_else(|| Error::Output {
            path: path.clone(),
            message: "the contour sink got data before begin() or after finish()".into(),
        })
    }

    fn level(&self, k: i64) -> f64 {
        level_value(self.options.base, self.options.interval, k)
    }

    fn levels(&self) -> ContourLevels {
        ContourLevels {
            base: self.options.base,
            interval: self.options.interval,
        }
    }

    /// Writes a finished polyline (ring or open line), its points rounded to the output's
    /// decimals and repeated points dropped; leaves out degenerate lines and those shorter
    /// than [`ContourOptions::min_length`].
    fn emit(&mut self, p: Poly, closed: bool) -> Result<()> {
        let level = self.level(p.k);
        // A plan's task writes its pieces exactly, for the merge to join.
        let pieces = self.options.edges && !closed;
        let out = self.out.take().expect("checked by the caller");
        let round = |q: [f64; 2]| if pieces { q } else { out.round(q) };
        // First pass: count distinct consecutive points, measure the line and its box, to
        // drop degenerate and short lines without writing them.
        let mut distinct = 0u64;
        let mut length = 0.0;
        let mut bbox = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut last: Option<[f64; 2]> = None;
        let r = self.for_each_point(&p, |q| {
            let q = round(q);
            if pieces || last != Some(q) {
                distinct += 1;
                if let Some(l) = last {
                    length += (q[0] - l[0]).hypot(q[1] - l[1]);
                }
                bbox = [
                    bbox[0].min(q[0]),
                    bbox[1].min(q[1]),
                    bbox[2].max(q[0]),
                    bbox[3].max(q[1]),
                ];
                last = Some(q);
            }
            Ok(())
        });
        if let Err(e) = r {
            self.out = Some(out);
            return Err(e);
        }
        if distinct < if closed { 4 } else { 2 } && !pieces {
            self.stats.degenerate_dropped += 1;
            self.out = Some(out);
            self.forget(&p);
            return Ok(());
        }
        if !pieces && length < self.options.min_length {
            self.stats.short_dropped += 1;
            self.out = Some(out);
            self.forget(&p);
            return Ok(());
        }
        if closed {
            self.stats.rings += 1;
        } else {
            self.stats.open_lines += 1;
        }
        let props = if pieces {
            let edge = |e: &EdgeKey| e.1.map(f64::from_bits);
            json!({
                "elevation": level, "closed": false,
                "start_edge": edge(&p.start), "end_edge": edge(&p.end)
            })
        } else {
            json!({ "elevation": level, "closed": closed })
        };
        let mut out = out;
        let r = out.start_line(&props, distinct, bbox).and_then(|_| {
            let mut last: Option<[f64; 2]> = None;
            self.for_each_point(&p, |q| {
                let q = if pieces { q } else { out.round(q) };
                if pieces || last != Some(q) {
                    last = Some(q);
                    out.point(q)?;
                }
                Ok(())
            })
        });
        let r = r.and_then(|_| out.end_line());
        self.out = Some(out);
        self.forget(&p);
        r
    }

    fn forget(&mut self, p: &Poly) {
        self.mem_points -= p.mem_points();
    }

    fn for_each_point(
        &mut self,
        p: &Poly,
        mut f: impl FnMut([f64; 2]) -> Result<()>,
    ) -> Result<()> {
        for piece in &p.pieces {
            match piece {
                Piece::Mem(v) => {
                    for &q in v {
                        f(q)?;
                    }
                }
                Piece::Disk { offset, len } => {
                    let path = self.path.clone();
                    let file = self.scratch.as_mut().expect("spilled points have a file");
                    let io = |e| Error::write(&path, e);
                    file.seek(SeekFrom::Start(*offset)).map_err(io)?;
                    let mut r = BufReader::with_capacity(1 << 16, &mut *file);
                    let mut b = [0u8; 16];
                    for _ in 0..*len {
                        r.read_exact(&mut b).map_err(io)?;
                        let x = f64::from_le_bytes(b[..8].try_into().expect("8 bytes"));
                        let y = f64::from_le_bytes(b[8..].try_into().expect("8 bytes"));
                        f([x, y])?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Moves the inner points of every open polyline to the scratch file.
    fn spill(&mut self) -> Result<()> {
        if self.scratch.is_none() {
            let dir = crate::output::target::scratch_dir(&self.path);
            self.scratch = Some(tempfile::tempfile_in(&dir).map_err(|e| Error::write(&dir, e))?);
        }
        let file = self.scratch.as_mut().expect("created above");
        let path = &self.path;
        file.seek(SeekFrom::End(0))
            .map_err(|e| Error::write(path, e))?;
        let mut w = std::io::BufWriter::with_capacity(1 << 16, &mut *file);
        for poly in self.stitcher.polys.iter_mut().flatten() {
            for piece in poly.pieces.iter_mut() {
                let Piece::Mem(v) = piece else { continue };
                if v.len() < 64 {
                    continue;
                }
                for q in v.iter() {
                    w.write_all(&q[0].to_le_bytes())
                        .and_then(|_| w.write_all(&q[1].to_le_bytes()))
                        .map_err(|e| Error::write(path, e))?;
                }
                let len = v.len() as u64;
                self.mem_points -= v.len();
                self.stats.points_spilled += len;
                *piece = Piece::Disk {
                    offset: self.scratch_len,
                    len,
                };
                self.scratch_len += len * 16;
            }
        }
        w.flush().map_err(|e| Error::write(path, e))
    }

    fn segment(&mut self, k: i64, t: &Tri) -> Result<()> {
        let l = self.level(k);
        let v = &t.v;
        let above = [v[0][2] >= l, v[1][2] >= l, v[2][2] >= l];
        // Edge i runs from vertex i to i + 1. The line enters the triangle through the edge that
        // goes from above to below and leaves through the one from below to above, so that the
        // higher ground is on its left.
        let mut enter = None;
        let mut leave = None;
        for i in 0..3 {
            let j = (i + 1) % 3;
            match (above[i], above[j]) {
                (true, false) => enter = Some(i),
                (false, true) => leave = Some(i),
                _ => {}
            }
        }
        let (Some(i), Some(o)) = (enter, leave) else {
            return Ok(());
        };
        let (a, b) = (&v[i], &v[(i + 1) % 3]);
        let (c, d) = (&v[o], &v[(o + 1) % 3]);
        let (s, e) = (crossing(l, a, b), crossing(l, c, d));
        self.stats.segments += 1;
        let added = self
            .stitcher
            .add(k, edge_key(k, a, b), s, edge_key(k, c, d), e);
        match added {
            Added::Open(n) => self.mem_points += n,
            Added::Closed(p) => {
                self.mem_points += 1;
                self.out()?;
                self.emit(p, true)?;
            }
        }
        // Lines that closed since the last spill took their short pieces with them.
        self.spill_at = self
            .spill_at
            .min(self.mem_points + self.options.memory_points);
        if self.mem_points > self.spill_at {
            self.spill()?;
            self.spill_at = self.options.memory_points + self.mem_points;
        }
        Ok(())
    }
}

impl TriangleSink for ContourSink {
    fn begin(&mut self, info: &StreamInfo) -> Result<()> {
        let decimals = self.options.decimals.filter(|_| !self.options.edges);
        self.out = Some(LineWriter::create(
            &self.path,
            "contours",
            info.crs.as_ref(),
            decimals,
        )?);
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        let levels = self.levels();
        match levels.crossed(&t.v) {
            Err((zmin, zmax, span)) if span <= MAX_LEVELS_PER_TRIANGLE as f64 => {
                Err(Error::Options(format!(
                    "{}: the levels near z {zmin} .. {zmax} lie more than 2^52 intervals \
                     (--interval {:e}) from --base {:e}: no level can be told exactly there; \
                     use a base nearer the heights or a larger interval",
                    self.path.display(),
                    levels.interval,
                    levels.base
                )))
            }
            Err((zmin, zmax, span)) => Err(Error::Options(format!(
                "{}: a triangle spans {span:.3e} contour levels (z {zmin} .. {zmax}, --interval \
                 {:e}): the interval is too small",
                self.path.display(),
                levels.interval
            ))),
            Ok(ks) => {
                for k in ks {
                    self.segment(k, &t)?;
                }
                Ok(())
            }
        }
    }

    fn needs(&self) -> Needs {
        Needs::Only(vec![Arc::new(self.levels())])
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        self.out()?;
        let max_open = self.stitcher.max_open;
        let open: Vec<usize> = (0..self.stitcher.polys.len())
            .filter(|&i| self.stitcher.polys[i].is_some())
            .collect();
        for id in open {
            let p = self.stitcher.take(id);
            self.emit(p, false)?;
        }
        let out = self.out.take().expect("checked above");
        let features = out.features();
        let bytes = out.finish()?;
        Ok(ProductSummary::Contours(ContourSummary {
            path: self.path.clone(),
            interval: self.options.interval,
            base: self.options.base,
            features,
            segments: self.stats.segments,
            rings: self.stats.rings,
            open_lines: self.stats.open_lines,
            degenerate_dropped: self.stats.degenerate_dropped,
            short_dropped: self.stats.short_dropped,
            min_length: self.options.min_length,
            decimals: self.options.decimals.filter(|_| !self.options.edges),
            points_spilled: self.stats.points_spilled,
            max_open_polylines: max_open as u64,
            bytes,
        }))
    }
}

#[cfg(test)]
mod tests;
