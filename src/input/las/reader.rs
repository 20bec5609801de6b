//! The chunked reader over one or more LAS/LAZ/COPC files (and the files of `.vpc` lists).

use super::LidarPoint;
use super::ahead::{Current, PointCheck, SpanJob};
use super::chunks::ChunkIndex;
use super::decode::{FileDecoder, Spare, spans};
use super::filter::{BBox, CompiledFilter, Filter, FilterStats};
use super::header::{Bounds3, FileInfo, format_error, inspect};
use super::vpc;
use super::world::Quantization;
use crate::crs::Crs;
use crate::error::{Error, Result};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Tuning of a [`LidarReader`].
#[derive(Clone, Debug, PartialEq)]
pub struct ReadOptions {
    /// Decode LAZ chunks (and filter their points) on several threads (rayon's global pool).
    /// The points and their order are the same either way.
    pub parallel: bool,
    /// Point records decoded per batch (at least one LAZ chunk). Parallel reading keeps decoding
    /// ahead at least this many points and two chunks per thread, within `ahead_bytes`.
    pub batch_points: usize,
    /// Memory the points decoding ahead may hold (at least one span is always decoding): the
    /// reader's share of a memory budget. A point is counted as twice its record (compressed
    /// and decompressed) and the decoded [`LidarPoint`]: 96 bytes for point format 1. More
    /// threads decode side by side only while their spans fit.
    pub ahead_bytes: u64,
    /// Keep only the points inside this area too (edges included), on top of the filter's box:
    /// "the points of these files inside this rectangle". Files whose header extent misses it
    /// are not decoded, nor COPC nodes that miss it.
    pub area: Option<BBox>,
    /// Use the octree of COPC files to decode only the nodes that meet the box (`false`: read
    /// them as plain LAZ; the points kept are the same).
    pub copc_index: bool,
    /// Chunk indexes of plain LAZ/LAS files, by path (as given to the reader): with an area, a
    /// file listed here decodes only the spans whose box meets it. An index that does not
    /// match its file ([`ChunkIndex::check`]) is refused.
    pub chunks: Vec<(PathBuf, Arc<ChunkIndex>)>,
    /// The CRS the user declares for the files (`--crs`, PDAL's `override_srs`): the reader's
    /// [`LidarReader::crs`], and files that declare others are read as in it, each named in
    /// [`LidarReader::warnings`], instead of refused.
    pub crs: Option<Crs>,
}

impl ReadOptions {
    /// The default options within a run's memory budget `mem`: a quarter of it decoding ahead
    /// (the engines' sorts have half).
    pub fn for_budget(mem: u64) -> ReadOptions {
        ReadOptions {
            ahead_bytes: mem / 4,
            ..ReadOptions::default()
        }
    }
}

/// What the reader counts per point decoding ahead for records of `record_len` bytes (see
/// [`ReadOptions::ahead_bytes`]).
fn ahead_bytes_per_point(record_len: usize) -> u64 {
    (2 * record_len + std::mem::size_of::<LidarPoint>()) as u64
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            parallel: true,
            batch_points: 200_000,
            ahead_bytes: 96 << 20,
            area: None,
            copc_index: true,
            chunks: Vec::new(),
            crs: None,
        }
    }
}

/// Reads one or more LAS/LAZ files as one point set, chunk by chunk (see the [module
/// docs](super) for the coordinates and the global index).
///
/// The reader is `Send`: it can be opened on one thread and moved to another.
pub struct LidarReader {
    sources: Vec<Source>,
    crs: Option<Crs>,
    /// Files whose CRS is not the one declared ([`ReadOptions::crs`]).
    crs_notes: Vec<String>,
    filter: Arc<CompiledFilter>,
    /// `Filter::z_from`: the attribute z comes from.
    z_from: Option<String>,
    stats: FilterStats,
    options: ReadOptions,
    next_source: usize,
    current: Option<Current>,
    ready: Vec<LidarPoint>,
    ready_pos: usize,
    /// Spans' point buffers, reused batch after batch (fresh ones fault in fresh pages).
    spare: Arc<Spare<LidarPoint>>,
    /// CPU time spent decoding (decompressing, converting and filtering records), every thread.
    decode_cpu: crate::clock::Tally,
}

impl std::fmt::Debug for LidarReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LidarReader")
            .field("files", &self.sources.len())
            .field("crs", &self.crs)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// One input file.
struct Source {
    points: u64,
    bounds: Bounds3,
    /// Global index of the file's first point.
    first_index: u64,
    /// Header facts, unless the file was skipped without being opened (a `.vpc` entry outside
    /// the box).
    info: Option<FileInfo>,
}

impl LidarReader {
    /// Opens `paths` (read in this order; a `.vpc` stands for its files) with the default
    /// [`ReadOptions`].
    ///
    /// # Errors
    /// [`Error::NoInput`] for an empty list; [`Error::Io`] if a file cannot be opened;
    /// [`Error::Format`] if a file is not a valid LAS/LAZ/COPC file or `.vpc`, or if the files
    /// declare different CRSs.
    pub fn open<P: AsRef<Path>>(paths: &[P], filter: &Filter) -> Result<LidarReader> {
        LidarReader::open_with(paths, filter, ReadOptions::default())
    }

    /// Opens `paths` to read only the points inside `area` (and `filter`): what the exact-tiles
    /// engine needs for a tile's buffered extent. Files and COPC nodes outside it are skipped
    /// without being decoded; the points and indices are those a full read keeps in `area`.
    ///
    /// # Errors
    /// As [`LidarReader::open`].
    pub fn open_area<P: AsRef<Path>>(paths: &[P], filter: &Filter, area: BBox) -> Result<Self> {
        let options = ReadOptions {
            area: Some(area),
            ..ReadOptions::default()
        };
        LidarReader::open_with(paths, filter, options)
    }

    /// Opens `paths` with explicit options.
    ///
    /// # Errors
    /// As [`LidarReader::open`].
    pub fn open_with<P: AsRef<Path>>(
        paths: &[P],
        filter: &Filter,
        options: ReadOptions,
    ) -> Result<LidarReader> {
        if paths.is_empty() {
            return Err(Error::NoInput);
        }
        let compiled = CompiledFilter::new(filter, options.area);
        let mut sources = Vec::with_capacity(paths.len());
        let mut declared: Vec<(PathBuf, Crs)> = Vec::new();
        let mut first_index = 0u64;
        let mut push = |s: Source| {
            let n = s.points;
            sources.push(Source { first_index, ..s });
            first_index = first_index.saturating_add(n);
        };
        for p in paths {
            let p = p.as_ref();
            if !vpc::is_vpc(p) {
                let info = inspect(p)?;
                if let Some(c) = &info.crs {
                    declared.push((info.path.clone(), c.clone()));
                }
                push(Source {
                    points: info.point_count,
                    bounds: info.bounds,
                    first_index: 0,
                    info: Some(info),
                });
                continue;
            }
            for e in vpc::read(p)? {
                if let Some(c) = &e.crs {
                    declared.push((p.to_path_buf(), c.clone()));
                }
                let rect = [
                    e.bounds.min[0],
                    e.bounds.min[1],
                    e.bounds.max[0],
                    e.bounds.max[1],
                ];
                // A box that says nothing (another writer's) cannot prove the file misses.
                let misses = e.bounds.usable() && compiled.misses(rect, margin(rect, 0.01));
                let info = if e.points > 0 && !misses {
                    let info = inspect(&e.path)?;
                    if info.point_count != e.points {
                        return Err(format_error(
                            &e.path,
                            format!(
                                "has {} points, but {} lists {}: the file changed since the list \
                                 was written (make it again with `sweeptin index`)",
                                info.point_count,
                                p.display(),
                                e.points
                            ),
                        ));
                    }
                    if let Some(c) = &info.crs {
                        declared.push((info.path.clone(), c.clone()));
                    }
                    Some(info)
                } else {
                    None
                };
                // An opened file's header is the truth; the list's box only decides what to
                // open (it may be stale, or in another CRS).
                push(Source {
                    points: e.points,
                    bounds: info.as_ref().map_or(e.bounds, |i| i.bounds),
                    first_index: 0,
                    info,
                });
            }
        }
        let (crs, crs_notes) = match &options.crs {
            Some(c) => (Some(c.clone()), overridden(c, &declared)),
            None => (common_crs(&declared)?, Vec::new()),
        };
        Ok(LidarReader {
            sources,
            filter: Arc::new(compiled),
            z_from: filter.z_from.clone(),
            crs,
            crs_notes,
            stats: FilterStats::default(),
            options: ReadOptions {
                batch_points: options.batch_points.max(1),
                ..options
            },
            next_source: 0,
            current: None,
            ready: Vec::new(),
            ready_pos: 0,
            spare: Arc::default(),
            decode_cpu: crate::clock::Tally::default(),
        })
    }

    /// The scale and offset of the first file opened (each file's points use their own: this
    /// is what an output that stores integers can reuse).
    pub fn quantization(&self) -> Option<Quantization> {
        self.sources
            .iter()
            .find_map(|s| s.info.as_ref())
            .map(FileInfo::quantization)
    }

    /// Decimals of the finest horizontal scale among the files (`0.01` gives 2; a scale that
    /// is no short decimal gives 9: [`Quantization::decimals`]), or `None` without a file
    /// opened: what outputs that print coordinates may round to without losing a point's place.
    pub fn xy_decimals(&self) -> Option<u32> {
        self.sources
            .iter()
            .filter_map(|s| s.info.as_ref())
            .map(|i| {
                let q = i.quantization();
                q.decimals(0).max(q.decimals(1)) as u32
            })
            .max()
    }

    /// One decimal lattice for the points of every file with points (see
    /// [`Lattice`](super::world::Lattice)), or `None` when a file's scale, offset or box rules
    /// it out.
    pub(crate) fn lattice(&self) -> Option<super::world::Lattice> {
        if self.z_from.is_some() {
            // z comes from an attribute, on no file's lattice.
            return None;
        }
        let mut files = Vec::new();
        for s in &self.sources {
            // (An entry of a `.vpc` left unopened gives no points.)
            let Some(info) = &s.info else { continue };
            if info.point_count > 0 {
                files.push((info.quantization(), [info.bounds.min, info.bounds.max]));
            }
        }
        super::world::Lattice::of(&files)
    }

    /// The CRS declared by the files (the first declaration; all must agree), if any.
    pub fn crs(&self) -> Option<&Crs> {
        self.crs.as_ref()
    }

    /// Header facts of each file opened, in reading order (files of a `.vpc` outside the box
    /// are not opened).
    pub fn files(&self) -> impl Iterator<Item = &FileInfo> {
        self.sources.iter().filter_map(|s| s.info.as_ref())
    }

    /// What the headers of the files opened say that does not stop reading (a point count
    /// that disagrees with the file, an unreadable CRS record, a CRS other than the one
    /// declared in [`ReadOptions::crs`]…), each `FILE: warning`: a run reports them as
    /// `sweeptin info` does.
    pub fn warnings(&self) -> Vec<String> {
        self.files()
            .flat_map(|i| {
                i.warnings
                    .iter()
                    .map(|w| format!("{}: {w}", i.path.display()))
            })
            .chain(self.crs_notes.iter().cloned())
            .collect()
    }

    /// Total number of points in the files, before filtering (an upper bound on what
    /// [`LidarReader::read_chunk`] will return in all).
    pub fn point_count(&self) -> u64 {
        self.sources.iter().map(|s| s.points).sum()
    }

    /// Union of the header bounds of the files that have points (real-world units), leaving
    /// out boxes that say nothing ([`Bounds3::usable`]: all zero, inverted, not finite); all
    /// zero when no file has points and a usable box.
    pub fn bounds(&self) -> Bounds3 {
        self.header_box().unwrap_or(Bounds3 {
            min: [0.0; 3],
            max: [0.0; 3],
        })
    }

    /// The extent `[xmin, ymin, xmax, ymax]` of the usable header boxes of `paths`
    /// ([`LidarReader::header_box`]), without reading a point: `None` when a header cannot be
    /// read (the run then reports it) or none has a usable box. What checks made before any
    /// work (a DEM's size) go by.
    pub fn header_extent<P: AsRef<Path>>(paths: &[P]) -> Option<[f64; 4]> {
        let b = LidarReader::open(paths, &Filter::default())
            .ok()?
            .header_box()?;
        Some([b.min[0], b.min[1], b.max[0], b.max[1]])
    }

    /// [`LidarReader::xy_decimals`] of `paths`, from their headers: `None` when a header
    /// cannot be read (the run then reports it).
    pub fn header_xy_decimals<P: AsRef<Path>>(paths: &[P]) -> Option<u32> {
        LidarReader::open(paths, &Filter::default())
            .ok()?
            .xy_decimals()
    }

    /// The points of the files whose header box is usable: those [`LidarReader::header_box`]
    /// bounds (the density over it counts these).
    pub fn points_in_header_boxes(&self) -> u64 {
        self.sources
            .iter()
            .filter(|s| s.bounds.usable())
            .map(|s| s.points)
            .sum()
    }

    /// [`LidarReader::bounds`], or `None` when no file with points has a usable box: what a
    /// check made before reading (a DEM's size) may go by.
    pub fn header_box(&self) -> Option<Bounds3> {
        self.sources
            .iter()
            .filter(|s| s.points > 0 && s.bounds.usable())
            .map(|s| s.bounds)
            .reduce(|a, b| a.union(&b))
    }

    /// CPU seconds spent so far decoding points (decompressing, converting and filtering
    /// records), added up over every thread that decoded (0 off Linux).
    pub fn decode_cpu(&self) -> f64 {
        self.decode_cpu.seconds()
    }

    /// What the filters kept and dropped so far; `read + skipped` against
    /// [`LidarReader::point_count`] is the progress.
    pub fn stats(&self) -> &FilterStats {
        &self.stats
    }

    /// Appends up to `max` points that pass the filter to `out` and returns how many it
    /// appended. Returns 0 once every file has been read (or when `max` is 0).
    ///
    /// # Errors
    /// [`Error::Io`] or [`Error::Format`] if a file turns out to be damaged while reading. After
    /// an error the reader is finished: later calls return 0. Points appended before the error
    /// stay in `out`.
    pub fn read_chunk(&mut self, out: &mut Vec<LidarPoint>, max: usize) -> Result<usize> {
        let start = out.len();
        if let Err(e) = self.fill(out, start, max) {
            self.current = None;
            self.next_source = self.sources.len();
            self.ready.clear();
            self.ready_pos = 0;
            return Err(e);
        }
        Ok(out.len() - start)
    }

    fn fill(&mut self, out: &mut Vec<LidarPoint>, start: usize, max: usize) -> Result<()> {
        while out.len() - start < max {
            if self.ready_pos < self.ready.len() {
                let n = (max - (out.len() - start)).min(self.ready.len() - self.ready_pos);
                out.extend_from_slice(&self.ready[self.ready_pos..self.ready_pos + n]);
                self.ready_pos += n;
                continue;
            }
            self.ready.clear();
            self.ready_pos = 0;
            if !self.decode_batch()? {
                break;
            }
        }
        Ok(())
    }

    /// Reads every remaining point that passes the filter.
    ///
    /// # Errors
    /// As [`LidarReader::read_chunk`].
    pub fn read_all(&mut self) -> Result<Vec<LidarPoint>> {
        let mut out = Vec::new();
        while self.read_chunk(&mut out, 1 << 20)? > 0 {}
        Ok(out)
    }

    /// Decodes the next span (or batch of spans) into `ready`; `false` when every file is done.
    ///
    /// Parallel reading keeps spans decoding on rayon's pool (a batch's worth, at least two per
    /// thread; see [`Current::submit`]) while this thread hands out the oldest one (and reads
    /// the next one's bytes), so the pool does not wait for the reader; spans still come out in
    /// order. On a thread of the pool itself the wait runs the pool's jobs
    /// ([`super::ahead::InFlight::wait`]). Serial reading decodes a batch in the call.
    fn decode_batch(&mut self) -> Result<bool> {
        loop {
            if let Some(cur) = &mut self.current {
                let job = SpanJob {
                    filter: self.filter.clone(),
                    check: cur.check.clone(),
                    spare: self.spare.clone(),
                    quant: cur.decoder.quant,
                    len: cur.decoder.record_len,
                    ext: cur.decoder.extended,
                    base: cur.first_index,
                    z_from: cur.z_from.clone(),
                };
                let batch = self.options.batch_points as u64;
                let cap = self.options.ahead_bytes / ahead_bytes_per_point(cur.decoder.record_len);
                let parts = if self.options.parallel {
                    cur.submit(batch, cap, &job);
                    match cur.in_flight.pop_front() {
                        Some(f) => {
                            let (parts, bytes) = f.wait();
                            cur.flying -= f.points;
                            cur.decoder.give_back(bytes);
                            let parts = parts?;
                            cur.submit(batch, cap, &job);
                            Some(parts)
                        }
                        None => None,
                    }
                } else if cur.next < cur.spans.len() {
                    let end = cur.batch_end(batch);
                    let spans = &cur.spans[cur.next..end];
                    cur.next = end;
                    Some(
                        cur.decoder
                            .decode(spans, false, job.fields(), |s, raw| job.run(s, raw))?,
                    )
                } else {
                    None
                };
                if let Some(parts) = parts {
                    for (mut kept, stats) in parts {
                        // `ready` is empty here: the first span's points take its place.
                        if self.ready.is_empty() {
                            std::mem::swap(&mut self.ready, &mut kept);
                        } else {
                            self.ready.extend_from_slice(&kept);
                        }
                        self.stats += stats;
                        self.spare.give(kept);
                    }
                    return Ok(true);
                }
            }
            self.current = None;
            if !self.open_next()? {
                return Ok(false);
            }
        }
    }

    /// Opens the next file with points to decode; `false` when there is none left. Points of
    /// files and COPC nodes outside the box count as skipped.
    fn open_next(&mut self) -> Result<bool> {
        while self.next_source < self.sources.len() {
            let s = &self.sources[self.next_source];
            self.next_source += 1;
            let Some(info) = s.info.as_ref().filter(|i| i.point_count > 0) else {
                self.stats.skipped += s.points;
                continue;
            };
            let step = info.scale[0].max(info.scale[1]);
            let m = info.known_rect().map_or(step, |r| margin(r, step));
            if info.known_rect().is_some_and(|r| self.filter.misses(r, m)) {
                self.stats.skipped += s.points;
                continue;
            }
            let filter = &self.filter;
            let keep = |r: [f64; 4]| !filter.misses(r, m);
            let use_index = self.options.copc_index;
            let indexed = self
                .options
                .chunks
                .iter()
                .find(|(p, _)| *p == info.path)
                .filter(|_| self.options.area.is_some() && info.layout.nodes.is_none());
            let spans = match indexed {
                Some((_, ix)) => {
                    ix.check(info)?;
                    ix.spans_kept(&keep)
                }
                None => spans(
                    info,
                    self.options.batch_points as u64,
                    use_index.then_some(&keep as &dyn Fn([f64; 4]) -> bool),
                ),
            };
            let decoded: u64 = spans.iter().map(|c| c.points).sum();
            self.stats.skipped += info.point_count - decoded;
            if spans.is_empty() {
                continue;
            }
            let mut decoder = FileDecoder::open(info)?.tallied(self.decode_cpu.clone());
            decoder.plan(&spans);
            self.current = Some(Current {
                decoder,
                spans,
                next: 0,
                first_index: s.first_index,
                z_from: match &self.z_from {
                    Some(name) => Some(super::extra::find_in_file(info, name)?),
                    None => None,
                },
                check: Arc::new(PointCheck::of(info)),
                in_flight: VecDeque::new(),
                flying: 0,
            });
            return Ok(true);
        }
        Ok(false)
    }
}

/// How far a point may lie outside its file's header extent or its COPC node's bounds through
/// rounding (writers compute both in floating point): one coordinate step, plus a relative
/// 1e-9. Used to decide what need not be decoded, and to check that a COPC node's points lie in
/// its square (`PointCheck`).
pub(super) fn margin(r: [f64; 4], step: f64) -> f64 {
    step + 1e-9 * r.iter().fold(1.0f64, |m, v| m.max(v.abs()))
}

/// The files of `declared` whose CRS is not `given` (the user's), each as a warning.
fn overridden(given: &Crs, declared: &[(PathBuf, Crs)]) -> Vec<String> {
    declared
        .iter()
        .filter(|(_, c)| !given.same_as(c))
        .map(|(p, c)| format!("{}: declares CRS {c}; read as {given} (--crs)", p.display()))
        .collect()
}

/// The files' common CRS: files that declare one must declare the same.
fn common_crs(declared: &[(PathBuf, Crs)]) -> Result<Option<Crs>> {
    let Some((first_path, first)) = declared.first() else {
        return Ok(None);
    };
    let mut common = first.clone();
    for (path, crs) in &declared[1..] {
        // Against what all the files before say together (never a chain of pairs).
        if !common.same_as(crs) {
            return Err(format_error(
                path,
                format!(
                    "declares CRS {crs}, but {} declares {first}: files read together must be in \
                     the same CRS",
                    first_path.display()
                ),
            ));
        }
        common = common.fuller(crs.clone());
    }
    Ok(Some(common))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reader_is_send() {
        fn assert_send<T: Send>() {}
        assert_send::<LidarReader>();
    }

    fn fixture() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lidR_Topography.copc.laz")
    }

    /// The points a read gave (index, position bits, class) and the error that stopped it.
    type Read = (Vec<(u64, [u64; 3], u8)>, Option<String>);

    /// Every point `path` gives, read in batches of one span per thread, and the error that
    /// stopped the read.
    fn read_all(path: &Path, parallel: bool) -> Read {
        let options = ReadOptions {
            parallel,
            batch_points: 1,
            copc_index: false,
            ..ReadOptions::default()
        };
        let mut r = LidarReader::open_with(&[path], &Filter::default(), options).unwrap();
        let mut pts = Vec::new();
        let error = loop {
            match r.read_chunk(&mut pts, 1000) {
                Ok(0) => break None,
                Ok(_) => {}
                Err(e) => break Some(e.to_string()),
            }
        };
        let key = |p: &LidarPoint| {
            let xyz = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            (p.index, xyz, p.classification)
        };
        (pts.iter().map(key).collect(), error)
    }

    /// Reads `path` three ways: decoding ahead on rayon's pool from a thread that is not one of
    /// its workers, decoding ahead from a worker of a pool (its waits run the pool's jobs), and
    /// on one thread.
    fn three_ways(path: &Path) -> [Read; 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        [
            pool.install(|| std::thread::scope(|s| s.spawn(|| read_all(path, true)).join()))
                .unwrap(),
            pool.install(|| read_all(path, true)),
            read_all(path, false),
        ]
    }

    #[test]
    fn decoding_ahead_gives_the_same_points() {
        let [ahead, on_worker, serial] = three_ways(&fixture());
        assert!(ahead.1.is_none(), "{:?}", ahead.1);
        assert!(ahead.0.len() > 50_000);
        assert!(ahead == on_worker, "decoding ahead from a worker differs");
        assert!(ahead == serial, "decoding ahead and one thread differ");
    }

    /// A reader that decoded ahead on one thread and then moves into a rayon job hands out the
    /// spans in flight first: no point is lost.
    #[test]
    fn a_reader_moved_into_a_rayon_job_loses_nothing() {
        let path = fixture();
        let whole = read_all(&path, false).0;
        let options = ReadOptions {
            batch_points: 1,
            copc_index: false,
            ..ReadOptions::default()
        };
        let mut r = LidarReader::open_with(&[&path], &Filter::default(), options).unwrap();
        let mut pts = Vec::new();
        std::thread::scope(|s| s.spawn(|| r.read_chunk(&mut pts, 10).unwrap()).join()).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        pool.install(|| while r.read_chunk(&mut pts, 1000).unwrap() > 0 {});
        let got: Vec<u64> = pts.iter().map(|p| p.index).collect();
        let want: Vec<u64> = whole.iter().map(|p| p.0).collect();
        assert!(got == want, "{} points of {}", got.len(), want.len());
    }

    /// Eight threads decode no more points at once than the memory given to the reader holds
    /// (at least one chunk), and the points are the same.
    #[test]
    fn decoding_ahead_stays_within_its_memory() {
        let path = fixture();
        let whole = read_all(&path, false).0;
        let info = inspect(&path).unwrap();
        let chunk = info.layout.chunks.iter().map(|c| c.points).max().unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(8)
            .build()
            .unwrap();
        let per_point = ahead_bytes_per_point(usize::from(info.record_length));
        for (bytes, most) in [(2 * chunk * per_point, 2 * chunk), (0, chunk)] {
            let options = ReadOptions {
                copc_index: false,
                ahead_bytes: bytes,
                ..ReadOptions::default()
            };
            let mut r = LidarReader::open_with(&[&path], &Filter::default(), options).unwrap();
            let mut pts = Vec::new();
            let mut peak = 0;
            pool.install(|| {
                while r.read_chunk(&mut pts, 1000).unwrap() > 0 {
                    let (flying, spans) = r
                        .current
                        .as_ref()
                        .map_or((0, 0), |c| (c.flying, c.in_flight.len()));
                    assert!(
                        spans <= 1 || flying <= most,
                        "{flying} points decoding ahead"
                    );
                    peak = peak.max(spans);
                }
            });
            // More than one chunk at a time within two chunks' points; one within nothing.
            assert!(
                (peak > 1) == (bytes > 0),
                "{peak} chunks at once within {bytes} bytes"
            );
            let got: Vec<u64> = pts.iter().map(|p| p.index).collect();
            let want: Vec<u64> = whole.iter().map(|p| p.0).collect();
            assert!(got == want, "{} points of {}", got.len(), want.len());
        }
    }

    #[test]
    fn decoding_ahead_meets_errors_in_span_order() {
        let src = fixture();
        let info = inspect(&src).unwrap();
        let chunks = &info.layout.chunks;
        assert!(chunks.len() >= 8, "{} chunks", chunks.len());
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("damaged.laz");
        let mut bytes = std::fs::read(&src).unwrap();
        // Chunks 3 and 6 damaged (decoding side by side): the error is chunk 3's, whichever
        // fails first.
        let c = chunks[3];
        bytes[c.offset as usize..(c.offset + c.bytes) as usize].fill(0);
        let d = chunks[6];
        bytes[d.offset as usize..(d.offset + d.bytes) as usize].fill(0);
        std::fs::write(&path, &bytes).unwrap();
        let [ahead, on_worker, serial] = three_ways(&path);
        let message = ahead.1.clone().unwrap();
        let at = format!("chunk at byte {}", c.offset);
        assert!(message.contains(&at), "{message}");
        // Span by span (decoding ahead, from any thread, or one thread), every point before
        // chunk 3 comes out.
        let before: u64 = chunks[..3].iter().map(|c| c.points).sum();
        assert_eq!(ahead.0.len() as u64, before);
        assert!(ahead == serial, "decoding ahead and one thread differ");
        assert_eq!(on_worker.1, ahead.1);
        assert!(ahead.0.starts_with(&on_worker.0) && !on_worker.0.is_empty());
    }

    #[test]
    fn crs_must_agree() {
        let a = Crs {
            epsg: Some(2154),
            ..Crs::default()
        };
        let b = Crs {
            epsg: Some(2949),
            ..Crs::default()
        };
        let ok = common_crs(&[("a".into(), a.clone()), ("b".into(), a.clone())]).unwrap();
        assert_eq!(ok, Some(a.clone()));
        let e = common_crs(&[("a.laz".into(), a), ("b.laz".into(), b)]).unwrap_err();
        assert!(e.to_string().contains("b.laz") && e.to_string().contains("a.laz"));
        assert_eq!(common_crs(&[]).unwrap(), None);
    }
}
