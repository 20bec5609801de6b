//! Heights of the TIN at query points, answered as the triangles stream past.
//!
//! # Input and output
//!
//! The queries are a text file with `x` and `y` as the first two fields of each line (separated
//! by commas, semicolons, tabs or spaces under the XYZ reader's rules, so that an empty field or
//! a decimal comma is an error, never a column read in the wrong place; `#` comments and blank
//! lines skipped). A first line that does not start with a number is a header, which names the
//! columns of x and y, whatever the case (`x`, `easting`, `lon`…, as PDAL and GDAL read them):
//! `id,x,y` reads x and y from the second and third columns (split by the line's comma or
//! semicolon as CSV is, an empty field a column of its own); a header that names no x and y is
//! refused with its line. The output repeats every query line unchanged, in the same order, with
//! one more field: the height `z`, or an **empty field** when the point is outside the TIN (a
//! header line gets the field name `z`, or `z_tin` when it has a `z` column already). A point exactly on an edge or vertex
//! gets the value computed from that edge or vertex alone ([`super::geom`]), the same whichever
//! triangle answers.
//!
//! # Memory
//!
//! When the queries are sorted by `y` (checked in a first pass over the file), they are read
//! lazily: a query is loaded once the *level* (the highest top of the triangles seen, rounded up to
//! a row of buckets) reaches its `y`, and forgotten as soon as a triangle answers it. A *tall*
//! triangle (more than 16 buckets (`TALL_BUCKETS`) from its bottom to its top) raises the level
//! only to its bottom: it is kept aside and meets the queries as later triangles load them. A tiled
//! run delivers its triangles by rows of tiles, and the long thin triangles along the data's hull
//! that its first tiles own reach the top of the data: raising the level to their tops loaded
//! almost every query at once (ARSO, a million queries on a 1 m lattice: 0.70 M held, 259 MB at
//! `--mem 128M`; kept aside: see `docs/BENCHMARKS.md`). At most 65,536 triangles wait; beyond that
//! a tall triangle raises the level as any other. Queries outside the bounds of the input points
//! are answered "outside" at once. Loaded queries that no triangle has answered yet stay until the
//! end (a late triangle may still answer them), so memory is bounded by the queries near the level
//! plus those outside the TIN but inside its bounding box. Unsorted queries are all loaded at the
//! start (memory proportional to their number). Answers go to an anonymous scratch file (8 bytes
//! per query, written in batches) and the output is written at the end in the queries' order.
//!
//! The queries are read three times (checked, loaded, copied to the output): queries from a pipe
//! or a device (`/dev/stdin`, `<(…)`) are first copied, once, to a temporary file.

use super::geom::{Location, Tri};
use crate::error::{Error, Result};
use crate::idmap::FastMap;
use crate::output::AtomicFile;
use crate::sink::{ProductSummary, SampleSummary, StreamInfo, TriangleSink};
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Heights of an in-memory TIN at the points `xy` (NaN outside it), with the same values as
/// the streamed [`SampleSink`] and the DEM: each point is found by a walk from the previous one
/// ([`crate::Tin::locate`], exact), then valued by [`Tri::value_at`] (on an edge or vertex
/// from that edge or vertex alone).
pub fn heights(tin: &mut crate::tin::Tin, xy: &[[f64; 2]]) -> Vec<f64> {
    use crate::tin::PointLocation;
    xy.iter()
        .map(|&p| match tin.locate(p) {
            PointLocation::Outside(_) => f64::NAN,
            PointLocation::OnVertex(v) => tin.z(v),
            PointLocation::OnEdge(e) => {
                let (a, b) = (tin.point(tin.org(e)), tin.point(tin.dst(e)));
                super::geom::edge_value(&a, &b, p)
            }
            // A TIN's triangles are counter-clockwise: only the canonical first vertex is
            // needed (the value inside does not depend on anything else).
            PointLocation::Inside(t) => {
                Tri::canonical_ccw(tin.tri_vertices(t).map(|v| tin.point(v))).plane_value(p)
            }
        })
        .collect()
}

/// A triangle taller than this many buckets (1/1024 of the data's extent) whose top is above the
/// loading level waits aside instead of loading the queries below its top (see the module docs).
/// Its height, not its reach above the level: a fan of slivers from one corner would otherwise
/// raise the level a step at a time.
const TALL_BUCKETS: f64 = 16.0;

/// Most tall triangles waiting aside (about 5 MB); beyond, they load queries as any other.
const MAX_DEFERRED: usize = 1 << 16;

/// Answers held before they are written to the scratch file (256 KiB).
const ANSWER_BATCH: usize = 1 << 14;

/// A query point: its number in the file (0-based, data lines only) and position.
#[derive(Clone, Copy, Debug)]
struct Query {
    n: u64,
    x: f64,
    y: f64,
}

mod text;

use crate::sort::external::{Merge, SortRecord};

/// Where the queries come from: text lines, or points sorted by the external sort.
enum Queries {
    Text(QueryReader),
    Points(Merge<SortRecord>),
}

impl Queries {
    fn next(&mut self) -> Result<Option<Query>> {
        match self {
            Queries::Text(r) => r.next(),
            Queries::Points(m) => match m.next() {
                Some(r) => Ok(Some(Query {
                    n: r.index,
                    x: r.x,
                    y: r.y,
                })),
                None => m.take_error().map_or(Ok(None), Err),
            },
        }
    }
}

use text::{FIRST_TWO, Line, QueryReader, classify, spool_stream};

/// A [`TriangleSink`] answering height queries (see the module docs).
pub struct SampleSink {
    /// The file the queries are read from (a copy of a pipe's).
    queries: PathBuf,
    /// The queries as the user named them (for messages).
    name: PathBuf,
    /// The copy of queries given as a pipe or a device, deleted with the sink.
    _spool: Option<(tempfile::TempPath, crate::output::atomic::TempRegistration)>,
    output: PathBuf,
    count: u64,
    sorted: bool,
    reader: Option<Queries>,
    /// Queries given as points sorted by `y` ([`SampleSink::for_points`]), until `begin`.
    points: Option<Merge<SortRecord>>,
    /// Answers only: no text output ([`SampleSink::take_answers`]).
    answers_only: bool,
    /// The next query not yet loaded.
    next: Option<Query>,
    /// Loaded, unanswered queries by bucket.
    pending: FastMap<(i64, i64), Vec<Query>>,
    pending_count: usize,
    max_pending: usize,
    bucket: f64,
    bounds: [f64; 4],
    /// Every query at `y <= level` is loaded (sorted queries).
    level: f64,
    /// Tall triangles whose tops are above `level`: they meet the queries as these are loaded.
    deferred: Vec<Tri>,
    answers: Option<File>,
    /// Answers not yet written: (query number, height).
    batch: Vec<(u64, f64)>,
    answered: u64,
}

impl SampleSink {
    /// Reads `queries` once (validating every line, checking whether they are sorted by `y`);
    /// answers go to `output` at the end.
    ///
    /// # Errors
    /// [`Error::Io`] / [`Error::Parse`] naming the queries file and line.
    pub fn new(queries: &Path, output: &Path) -> Result<SampleSink> {
        let spool = spool_stream(queries)?;
        let name = queries;
        let queries = spool.as_ref().map_or(queries, |(p, _)| &**p);
        let mut r = QueryReader::open(queries)?;
        r.path = name.to_path_buf();
        let mut count = 0;
        let mut sorted = true;
        let mut last = f64::NEG_INFINITY;
        while let Some(q) = r.next()? {
            count += 1;
            sorted &= q.y >= last;
            last = q.y;
        }
        Ok(SampleSink {
            queries: queries.to_path_buf(),
            name: name.to_path_buf(),
            _spool: spool,
            sorted,
            ..SampleSink::idle(output, count)
        })
    }

    /// A sink of `count` queries answered into `output`, before any is read: text queries,
    /// nothing pending, nothing answered.
    fn idle(output: &Path, count: u64) -> SampleSink {
        SampleSink {
            queries: PathBuf::new(),
            name: PathBuf::new(),
            _spool: None,
            output: output.to_path_buf(),
            count,
            sorted: true,
            reader: None,
            points: None,
            answers_only: false,
            next: None,
            pending: FastMap::default(),
            pending_count: 0,
            max_pending: 0,
            bucket: 1.0,
            bounds: [0.0; 4],
            level: f64::NEG_INFINITY,
            deferred: Vec::new(),
            answers: None,
            batch: Vec::new(),
            answered: 0,
        }
    }

    /// A sink answering `count` query points given sorted by `y` (then `x`), each numbered by
    /// its `index` (below `count`), such as a file's own points through the external sort
    /// (`sweeptin height`): read lazily as the triangles stream past, as sorted text queries
    /// are. The answers stay in a scratch file beside `scratch` ([`SampleSink::take_answers`]).
    pub fn for_points(points: Merge<SortRecord>, count: u64, scratch: &Path) -> SampleSink {
        SampleSink {
            name: PathBuf::from("the points"),
            points: Some(points),
            answers_only: true,
            ..SampleSink::idle(scratch, count)
        }
    }

    /// After `finish`, the answers: the height at query `n` as the little-endian double at byte
    /// `8 n` (NaN outside the TIN), the file rewound.
    ///
    /// # Errors
    /// [`Error::Write`] when the scratch file cannot be rewound; [`Error::Internal`] before
    /// `begin`.
    pub fn take_answers(&mut self) -> Result<File> {
        self.flush_answers()?;
        let mut f = self
            .answers
            .take()
            .ok_or_else(|| Error::Internal("no answers before the run began".into()))?;
        f.seek(SeekFrom::Start(0))
            .map_err(|e| Error::write(&self.output, e))?;
        Ok(f)
    }

    /// Are the queries sorted by `y` (so that they are read lazily)?
    pub fn sorted(&self) -> bool {
        self.sorted
    }

    fn key(&self, x: f64, y: f64) -> (i64, i64) {
        (
            ((x - self.bounds[0]) / self.bucket).floor() as i64,
            ((y - self.bounds[1]) / self.bucket).floor() as i64,
        )
    }

    fn answer(&mut self, n: u64, z: f64) -> Result<()> {
        self.batch.push((n, z));
        self.answered += 1;
        if self.batch.len() >= ANSWER_BATCH {
            self.flush_answers()?;
        }
        Ok(())
    }

    /// Writes the batched answers to the scratch file, one write per run of consecutive queries
    /// (a lattice of queries is answered a row of a tile at a time).
    fn flush_answers(&mut self) -> Result<()> {
        let f = self.answers.as_mut().expect("created in begin");
        self.batch.sort_unstable_by_key(|a| a.0);
        let mut bytes = Vec::with_capacity(8 * self.batch.len());
        let mut i = 0;
        while i < self.batch.len() {
            let first = self.batch[i].0;
            bytes.clear();
            while i < self.batch.len() && self.batch[i].0 == first + (bytes.len() / 8) as u64 {
                bytes.extend_from_slice(&self.batch[i].1.to_le_bytes());
                i += 1;
            }
            f.seek(SeekFrom::Start(first * 8))
                .and_then(|_| crate::sort::write_pieces(f, &bytes))
                .map_err(|e| Error::write(&self.output, e))?;
        }
        self.batch.clear();
        Ok(())
    }

    /// Loads queries up to `y` (all of them when unsorted).
    fn load_until(&mut self, y: f64) -> Result<()> {
        loop {
            if self.next.is_none() {
                self.next = match self.reader.as_mut() {
                    Some(r) => r.next()?,
                    None => None,
                };
                if self.next.is_none() {
                    self.reader = None;
                    return Ok(());
                }
            }
            let q = self.next.expect("just read");
            if self.sorted && q.y > y {
                return Ok(());
            }
            self.next = None;
            let b = self.bounds;
            if q.x < b[0] || q.x > b[2] || q.y < b[1] || q.y > b[3] {
                continue; // outside the data: stays NaN
            }
            let k = self.key(q.x, q.y);
            self.pending.entry(k).or_default().push(q);
            self.pending_count += 1;
            self.max_pending = self.max_pending.max(self.pending_count);
        }
    }

    fn try_bucket(&mut self, k: (i64, i64), t: &Tri) -> Result<()> {
        let Some(v) = self.pending.get_mut(&k) else {
            return Ok(());
        };
        let mut found = Vec::new();
        v.retain(|q| {
            let p = [q.x, q.y];
            let loc = t.locate(p);
            if loc == Location::Outside {
                return true;
            }
            found.push((q.n, t.value_at(p, loc)));
            false
        });
        if v.is_empty() {
            self.pending.remove(&k);
        }
        self.pending_count -= found.len();
        for (n, z) in found {
            self.answer(n, z)?;
        }
        Ok(())
    }

    /// Loads the queries up to `y` (rounded up to the top of its row of buckets, so that the
    /// waiting triangles are tried once per row), then tries the waiting triangles on them.
    fn raise(&mut self, y: f64) -> Result<()> {
        let old = self.level;
        let level = if y.is_finite() {
            let row = self.key(self.bounds[0], y).1;
            (self.bounds[1] + (row + 1) as f64 * self.bucket).max(y)
        } else {
            y
        };
        self.load_until(level)?;
        self.level = level;
        let mut waiting = std::mem::take(&mut self.deferred);
        for t in &waiting {
            let [x0, y0, x1, y1] = t.bbox();
            let (lo, hi) = (y0.max(old), y1.min(level));
            if lo <= hi {
                self.test(t, [x0, lo, x1, hi])?;
            }
        }
        waiting.retain(|t| t.bbox()[3] > level);
        self.deferred = waiting;
        Ok(())
    }

    /// Tries triangle `t` on the loaded queries of the buckets that meet `b` (part of its box).
    fn test(&mut self, t: &Tri, b: [f64; 4]) -> Result<()> {
        if self.pending_count == 0 {
            return Ok(());
        }
        let [x0, y0, x1, y1] = b;
        let (k0, k1) = (self.key(x0, y0), self.key(x1, y1));
        let cells = (k1.0 - k0.0 + 1) as u64 * (k1.1 - k0.1 + 1) as u64;
        if cells > self.pending.len() as u64 {
            let keys: Vec<(i64, i64)> = self.pending.keys().copied().collect();
            for k in keys {
                if (k0.0..=k1.0).contains(&k.0) && (k0.1..=k1.1).contains(&k.1) {
                    self.try_bucket(k, t)?;
                }
            }
        } else {
            for ky in k0.1..=k1.1 {
                for kx in k0.0..=k1.0 {
                    self.try_bucket((kx, ky), t)?;
                }
            }
        }
        Ok(())
    }

    /// Writes the output: every query line with its answer.
    fn write_output(&mut self) -> Result<u64> {
        self.flush_answers()?;
        let answers = self.answers.as_mut().expect("created in begin");
        answers
            .seek(SeekFrom::Start(0))
            .map_err(|e| Error::write(&self.output, e))?;
        let mut answers = BufReader::with_capacity(1 << 16, answers);
        let f = File::open(&self.queries).map_err(|e| Error::io(&self.name, e))?;
        let mut out = AtomicFile::create(&self.output)?;
        let mut w = BufWriter::with_capacity(1 << 16, &mut out);
        let io = |e| Error::write(&self.output, e);
        let mut seen_data = false;
        let mut cols = FIRST_TWO;
        for line in BufReader::with_capacity(1 << 16, f).lines() {
            let line = line.map_err(|e| Error::io(&self.name, e))?;
            let sep = if line.contains(',') {
                ","
            } else if line.contains(';') {
                ";"
            } else if line.contains('\t') {
                "\t"
            } else {
                " "
            };
            match classify(&line, !seen_data, cols) {
                Ok(Line::Skip) => writeln!(w, "{line}").map_err(io)?,
                Ok(Line::Header(c, z)) => {
                    seen_data = true;
                    cols = c;
                    writeln!(w, "{line}{sep}{z}").map_err(io)?;
                }
                Ok(Line::Point(..)) => {
                    seen_data = true;
                    let mut b = [0u8; 8];
                    answers.read_exact(&mut b).map_err(io)?;
                    let z = f64::from_le_bytes(b);
                    if z.is_nan() {
                        writeln!(w, "{line}{sep}").map_err(io)?;
                    } else {
                        writeln!(w, "{line}{sep}{z}").map_err(io)?;
                    }
                }
                Err(message) => {
                    return Err(Error::Parse {
                        path: self.name.clone(),
                        line: 0,
                        message: format!("the file changed while it was read: {message}"),
                    });
                }
            }
        }
        w.flush().map_err(io)?;
        drop(w);
        out.commit()
    }
}

impl TriangleSink for SampleSink {
    fn begin(&mut self, info: &StreamInfo) -> Result<()> {
        self.bounds = info.bounds;
        let extent = (info.bounds[2] - info.bounds[0]).max(info.bounds[3] - info.bounds[1]);
        self.bucket = if extent > 0.0 && extent.is_finite() {
            extent / 1024.0
        } else {
            1.0
        };
        let dir = crate::output::target::scratch_dir(&self.output);
        let f = tempfile::tempfile_in(&dir).map_err(|e| Error::write(&dir, e))?;
        let mut w = BufWriter::with_capacity(1 << 16, f);
        for _ in 0..self.count {
            w.write_all(&f64::NAN.to_le_bytes())
                .map_err(|e| Error::write(&dir, e))?;
        }
        self.answers = Some(
            w.into_inner()
                .map_err(|e| Error::write(&dir, e.into_error()))?,
        );
        self.reader = Some(match self.points.take() {
            Some(points) => Queries::Points(points),
            None => {
                let mut reader = QueryReader::open(&self.queries)?;
                reader.path = self.name.clone();
                Queries::Text(reader)
            }
        });
        if !self.sorted {
            self.load_until(f64::INFINITY)?;
            self.level = f64::INFINITY;
        }
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        let b = t.bbox();
        if b[3] > self.level {
            if b[3] - b[1] > TALL_BUCKETS * self.bucket && self.deferred.len() < MAX_DEFERRED {
                // The stream has reached its bottom: load up to there (a coarse TIN, where every
                // triangle is tall, would otherwise load nothing until the end).
                if b[1] > self.level {
                    self.raise(b[1])?;
                }
                self.test(&t, b)?; // against the queries loaded so far
                self.deferred.push(t);
                return Ok(());
            }
            self.raise(b[3])?;
        }
        self.test(&t, b)
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        self.raise(f64::INFINITY)?;
        let bytes = if self.answers_only {
            self.flush_answers()?;
            0
        } else {
            self.write_output()?
        };
        Ok(ProductSummary::Sample(SampleSummary {
            path: self.output.clone(),
            queries: self.count,
            answered: self.answered,
            outside: self.count - self.answered,
            sorted_by_y: self.sorted,
            max_pending_queries: self.max_pending as u64,
            bytes,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Query positions follow the XYZ reader's separator rules: `1,5;3,5` (decimal commas) was
    /// read as (1, 5), `1,,2` as (1, 2).
    #[test]
    fn queries_follow_the_xyz_separator_rules() {
        for bad in ["1,5;3,5", "1\t5,3", "1,,2", "1"] {
            assert!(classify(bad, false, FIRST_TWO).is_err(), "{bad}");
        }
        assert!(matches!(
            classify("x,y", true, FIRST_TWO),
            Ok(Line::Header(FIRST_TWO, "z"))
        ));
        assert!(matches!(
            classify("  # note", false, FIRST_TWO),
            Ok(Line::Skip)
        ));
        assert!(matches!(
            classify("1.5 3.5 extra", false, FIRST_TWO),
            Ok(Line::Point(1.5, 3.5))
        ));
    }
    use crate::products::testutil::{
        feed, grid_tin, in_sweep_order, random_tin, shuffled_with_watermarks,
    };

    fn run(queries: &str, steps: &[crate::products::testutil::Step]) -> (String, SampleSummary) {
        let dir = tempfile::tempdir().unwrap();
        let q = dir.path().join("q.csv");
        std::fs::write(&q, queries).unwrap();
        let out = dir.path().join("out.csv");
        let mut sink = SampleSink::new(&q, &out).unwrap();
        let info = StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 100.0, 100.0],
        };
        let ProductSummary::Sample(s) = feed(&mut sink, &info, steps) else {
            panic!("not a sample summary")
        };
        (std::fs::read_to_string(&out).unwrap(), s)
    }

    #[test]
    fn plane_heights_outside_empty_in_any_order() {
        let f = |x: f64, y: f64| 0.5 * x + 0.25 * y - 3.0;
        let tris = random_tin(300, 100.0, 11, f);
        let mut text = String::from("# points\nx,y,name\n");
        let mut r = crate::geom::rng::SplitMix64::new(3);
        let mut pts = Vec::new();
        for i in 0..200 {
            let (x, y) = (r.next_f64() * 120.0 - 10.0, r.next_f64() * 100.0);
            pts.push((x, y, i));
        }
        pts.push((0.0, 0.0, 999)); // a corner vertex
        pts.push((50.0, 100.0, 998)); // on the top edge
        pts.sort_by(|a, b| a.1.total_cmp(&b.1));
        for (x, y, i) in &pts {
            text.push_str(&format!("{x},{y},p{i}\n"));
        }
        let (a, sa) = run(&text, &in_sweep_order(&tris));
        let (b, _) = run(&text, &shuffled_with_watermarks(&tris, 8));
        assert_eq!(a, b);
        assert!(sa.sorted_by_y);
        let lines: Vec<&str> = a.lines().collect();
        assert_eq!(lines[0], "# points");
        assert_eq!(lines[1], "x,y,name,z");
        for l in &lines[2..] {
            let c: Vec<&str> = l.split(',').collect();
            let (x, y): (f64, f64) = (c[0].parse().unwrap(), c[1].parse().unwrap());
            if (0.0..=100.0).contains(&x) {
                let z: f64 = c[3].parse().unwrap();
                assert!((z - f(x, y)).abs() < 1e-9, "{l}");
            } else {
                assert_eq!(c[3], "", "{l}");
            }
        }
    }

    #[test]
    fn unsorted_queries_are_all_loaded_and_still_answered() {
        let tris = random_tin(50, 100.0, 2, |x, _| x);
        let (out, s) = run("50 60\n10 20\n", &in_sweep_order(&tris));
        assert!(!s.sorted_by_y);
        let z: Vec<f64> = out
            .lines()
            .map(|l| l.split(' ').nth(2).unwrap().parse().unwrap())
            .collect();
        assert!((z[0] - 50.0).abs() < 1e-9 && (z[1] - 10.0).abs() < 1e-9);
    }

    /// A tiled run's order: rows of tiles from the bottom, and among the first tile's triangles
    /// a fan reaching the top of the data (as the hull's slivers do). The fan waits aside
    /// instead of loading every query, and every query still gets its height.
    #[test]
    fn tall_triangles_wait_instead_of_loading_every_query() {
        let f = |x: f64, y: f64| 2.0 * x - y + 7.0;
        let p = |x: f64, y: f64| [x, y, f(x, y)];
        let mut tris: Vec<[[f64; 3]; 3]> = grid_tin(100, 100, 1.0, f)
            .into_iter()
            .filter(|t| t.iter().all(|v| v[0] >= 1.0))
            .collect();
        // The strip 0 <= x <= 1, only its corners (0, 0) and (0, 100) on the left: a fan.
        for j in 0..100 {
            tris.push([p(0.0, 0.0), p(1.0, j as f64), p(1.0, j as f64 + 1.0)]);
        }
        tris.push([p(0.0, 0.0), p(1.0, 100.0), p(0.0, 100.0)]);
        let low = |t: &[[f64; 3]; 3]| {
            t.iter()
                .map(|v| (v[1], v[0]))
                .fold((f64::MAX, 0.0), |a, b| if b < a { b } else { a })
        };
        let tile = |t: &[[f64; 3]; 3]| {
            let (y, x) = low(t);
            ((y / 20.0).floor() as i64, (x / 20.0).floor() as i64)
        };
        tris.sort_by_key(tile);
        let steps: Vec<crate::products::testutil::Step> = tris.iter().map(|t| (*t, None)).collect();
        let mut text = String::from("x,y\n");
        for j in 0..100 {
            for i in 0..100 {
                text.push_str(&format!("{},{}\n", i as f64 + 0.5, j as f64 + 0.5));
            }
        }
        let (out, s) = run(&text, &steps);
        assert!(s.sorted_by_y);
        assert_eq!(s.answered, 10_000);
        // A row of tiles (20 rows of queries) and the reach of a short triangle, not all 100.
        assert!(s.max_pending_queries < 2_600, "{}", s.max_pending_queries);
        for l in out.lines().skip(1) {
            let c: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            assert!((c[2] - f(c[0], c[1])).abs() < 1e-9, "{l}");
        }
    }

    /// A coarse TIN (every triangle tall: 5 m high, buckets of 0.1 m) in sweep order and a
    /// sorted 1 m lattice of queries: the queries are still loaded as the stream advances (a
    /// review found them all loaded at the end: 10,201 held).
    #[test]
    fn a_coarse_tin_still_loads_its_queries_lazily() {
        let f = |x: f64, y: f64| 0.5 * x - 0.25 * y + 1.0;
        let steps = in_sweep_order(&grid_tin(20, 20, 5.0, f));
        let mut text = String::new();
        for j in 0..=100 {
            for i in 0..=100 {
                text.push_str(&format!("{i},{j}\n"));
            }
        }
        let (_, s) = run(&text, &steps);
        assert!(s.sorted_by_y);
        assert_eq!(s.answered, 101 * 101);
        assert!(s.max_pending_queries < 2_000, "{}", s.max_pending_queries);
    }

    /// Query columns are read by the header's names (`id,x,y` was read as x = id, y = x: every
    /// query outside the TIN, exit 0), other columns kept, a `z` column kept beside the TIN's
    /// (`z_tin`); a header that names no x and y, or a line without the named column, is refused
    /// with its line number.
    #[test]
    fn headers_name_the_query_columns() {
        let f = |x: f64, y: f64| 0.5 * x + 0.25 * y - 3.0;
        let steps = in_sweep_order(&grid_tin(10, 10, 10.0, f));
        let (out, s) = run("id,x,y\n1,10,20\n2,30.5,40\n3,500,500\n", &steps);
        assert_eq!((s.queries, s.answered), (3, 2));
        let want = format!(
            "id,x,y,z\n1,10,20,{}\n2,30.5,40,{}\n3,500,500,\n",
            f(10.0, 20.0),
            f(30.5, 40.0)
        );
        assert_eq!(out, want);
        let (out, s) = run("\"Name\";Northing;Easting;Z\n\"a;b\";20;10;7\n", &steps);
        assert_eq!(s.answered, 1);
        assert_eq!(
            out,
            format!(
                "\"Name\";Northing;Easting;Z;z_tin\n\"a;b\";20;10;7;{}\n",
                f(10.0, 20.0)
            )
        );
        let (out, _) = run("X Y\n10 20\n", &steps);
        assert_eq!(out, format!("X Y z\n10 20 {}\n", f(10.0, 20.0)));
        let dir = tempfile::tempdir().unwrap();
        let q = dir.path().join("q.csv");
        for (text, line, want) in [
            ("a,b\n1,2\n", 1, "does not name the x and y columns"),
            ("x,y,x\n1,2,3\n", 1, "names x twice"),
            ("id,x,y\n1,2,3\n4,5\n", 3, "y is read from column 3"),
            ("id,x,y\n1,,3\n", 2, "x is an empty field"),
            ("id,x,y\n1,2,3,5\n", 0, ""),
            ("id;x;y\n1;2,5;3\n", 2, "mixes"),
        ] {
            std::fs::write(&q, text).unwrap();
            match SampleSink::new(&q, &dir.path().join("o.csv")) {
                Ok(_) => assert_eq!(line, 0, "{text}"),
                Err(e) => {
                    assert!(
                        matches!(e, Error::Parse { line: l, .. } if l == line),
                        "{text}: {e}"
                    );
                    assert!(
                        !want.is_empty() && e.to_string().contains(want),
                        "{text}: {e}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_bad_line_is_reported_with_its_number() {
        let dir = tempfile::tempdir().unwrap();
        let q = dir.path().join("q.csv");
        std::fs::write(&q, "x,y\n1,2\n3,oops\n").unwrap();
        let e = SampleSink::new(&q, &dir.path().join("o.csv"))
            .err()
            .unwrap();
        assert!(matches!(e, Error::Parse { line: 3, .. }), "{e}");
    }
}
