//! Cut and fill between two surfaces, with bounded memory.
//!
//! Both TINs stream in increasing `y`, but a late triangle of either can arrive below the other's
//! progress, so the two streams are not merged live. Instead:
//!
//! 1. The **reference** surface is streamed first into a [`BandStore`]: its triangles are filed
//!    by horizontal band (a triangle goes to every band its `y` range meets) into an anonymous
//!    scratch file, in chunks; a band's buffer is written out when the watermark passes the band
//!    (or the buffer fills). Memory: the buffers of the bands between the watermark and the front.
//! 2. The **surface** is then streamed into an [`OverlaySink`]. For each of its triangles the
//!    bands it meets are loaded (and indexed by a grid of columns), every reference triangle whose
//!    box meets it is paired with it, and bands below the surface's watermark are dropped.
//!
//! A surface triangle that meets more than 16 bands (`TALL_BANDS`; a long thin triangle along the
//! hull, which a tiled run delivers with its first tiles, or a triangle across a lake) would load
//! most of the reference at once, and so would the late triangles a sweep gives at its end, all
//! along the hull: a tall or late triangle (one meeting a band dropped at a watermark) waits
//! instead, and the waiting triangles meet the reference at the end, one band in memory at a
//! time (or sooner, when 65,536 wait). A pair met in
//! several bands or columns is counted in the first band and column both meet.
//!
//! For a pair, the surface triangle is clipped to the reference triangle (both convex), then to
//! the boundary, and the difference `d = z_surface − z_reference`, linear on each piece, is split
//! at `d = 0` and integrated exactly as for a plane ([`CutFill`]). Each pair is met exactly once
//! (reference triangles are de-duplicated across bands by id), so the overlap of the two TINs is
//! covered once; where only one surface exists nothing is counted.

use super::boundary::Boundary;
use super::geom::{PV, Tri, clip_left};
use super::volume::CutFill;
use crate::error::{Error, Result};
use crate::sink::{
    CutFillTotals, OverlayStats, ProductSummary, StreamInfo, SurfaceStoreSummary, TriangleSink,
    VolumeReference, VolumeSummary,
};
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Bytes of one stored triangle: id + 9 coordinates.
const RECORD: usize = 80;
/// Triangles buffered per band before a chunk is written.
const CHUNK: usize = 4096;
/// A surface triangle meeting more bands than this waits for one pass over the bands.
pub(crate) const TALL_BANDS: usize = 16;
/// Most surface triangles waiting (about 5 MB).
const MAX_TALL: usize = 1 << 16;

/// The layout of the bands: `count` bands of height `h` from `y0`.
#[derive(Clone, Copy, Debug)]
struct Bands {
    y0: f64,
    h: f64,
    count: usize,
    /// `[xmin, xmax]` of the reference surface.
    x: [f64; 2],
}

impl Bands {
    fn of(&self, y: f64) -> usize {
        let b = ((y - self.y0) / self.h).floor();
        if b < 0.0 {
            0
        } else {
            (b as usize).min(self.count - 1)
        }
    }

    fn top(&self, b: usize) -> f64 {
        self.y0 + (b + 1) as f64 * self.h
    }
}

/// Phase 1: a [`TriangleSink`] that files the reference surface's triangles by band.
#[derive(Debug)]
pub struct BandStore {
    dir: PathBuf,
    bands_wanted: usize,
    bands: Option<Bands>,
    file: Option<BufWriter<File>>,
    written: u64,
    buffers: HashMap<usize, Vec<(u64, Tri)>>,
    /// Flushed below this band.
    flushed_below: usize,
    index: Vec<Vec<(u64, u32)>>,
    next_id: u64,
}

impl BandStore {
    /// A store whose scratch file lives in `dir`, with about `bands` bands.
    pub fn new(dir: &Path, bands: usize) -> BandStore {
        BandStore {
            dir: dir.to_path_buf(),
            bands_wanted: bands.max(1),
            bands: None,
            file: None,
            written: 0,
            buffers: HashMap::new(),
            flushed_below: 0,
            index: Vec::new(),
            next_id: 0,
        }
    }

    fn flush_band(&mut self, b: usize) -> Result<()> {
        let Some(buf) = self.buffers.remove(&b) else {
            return Ok(());
        };
        if buf.is_empty() {
            return Ok(());
        }
        let dir = &self.dir;
        let f = self.file.as_mut().expect("opened in begin");
        let mut bytes = Vec::with_capacity(buf.len() * RECORD);
        for (id, t) in &buf {
            bytes.extend_from_slice(&id.to_le_bytes());
            for c in t.v.iter().flatten() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        f.write_all(&bytes).map_err(|e| Error::write(dir, e))?;
        self.index[b].push((self.written, buf.len() as u32));
        self.written += bytes.len() as u64;
        Ok(())
    }

    /// Ends phase 1: the store, ready to be read by an [`OverlaySink`].
    ///
    /// # Errors
    /// [`Error::Write`] if the scratch file cannot be written; [`Error::Internal`] before `finish`.
    pub fn into_reader(mut self) -> Result<BandReader> {
        let bands = self
            .bands
            .ok_or_else(|| Error::Internal("band store read before it was filled".into()))?;
        let keys: Vec<usize> = self.buffers.keys().copied().collect();
        for b in keys {
            self.flush_band(b)?;
        }
        let dir = self.dir.clone();
        let file = self
            .file
            .take()
            .expect("opened in begin")
            .into_inner()
            .map_err(|e| Error::write(&dir, e.into_error()))?;
        Ok(BandReader {
            file,
            dir,
            bands,
            index: self.index,
            triangles: self.next_id,
        })
    }
}

impl TriangleSink for BandStore {
    fn begin(&mut self, info: &StreamInfo) -> Result<()> {
        let [xmin, ymin, xmax, ymax] = info.bounds;
        let height = ymax - ymin;
        let (count, h) = if height > 0.0 && height.is_finite() {
            (self.bands_wanted, height / self.bands_wanted as f64)
        } else {
            (1, 1.0)
        };
        self.bands = Some(Bands {
            y0: ymin,
            h,
            count,
            x: [xmin, xmax],
        });
        self.index = vec![Vec::new(); count];
        let f = tempfile::tempfile_in(&self.dir).map_err(|e| Error::write(&self.dir, e))?;
        self.file = Some(BufWriter::with_capacity(1 << 20, f));
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        let bands = self.bands.expect("set in begin");
        let bb = t.bbox();
        let id = self.next_id;
        self.next_id += 1;
        for b in bands.of(bb[1])..=bands.of(bb[3]) {
            let buf = self.buffers.entry(b).or_default();
            buf.push((id, t));
            if buf.len() >= CHUNK {
                self.flush_band(b)?;
            }
        }
        Ok(())
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        let bands = self.bands.expect("set in begin");
        while self.flushed_below < bands.count && bands.top(self.flushed_below) < y {
            self.flush_band(self.flushed_below)?;
            self.flushed_below += 1;
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        Ok(ProductSummary::SurfaceStore(SurfaceStoreSummary {
            reference_triangles: self.next_id,
            bands: self.index.len() as u64,
        }))
    }
}

/// The reference surface filed by band (phase 1's result).
#[derive(Debug)]
pub struct BandReader {
    file: File,
    dir: PathBuf,
    bands: Bands,
    index: Vec<Vec<(u64, u32)>>,
    triangles: u64,
}

/// A band in memory, with a grid of columns over it.
struct Loaded {
    tris: Vec<(u64, Tri)>,
    cells: Vec<Vec<u32>>,
    x0: f64,
    w: f64,
}

impl Loaded {
    fn column(&self, x: f64) -> usize {
        let c = ((x - self.x0) / self.w).floor();
        if c < 0.0 {
            0
        } else {
            (c as usize).min(self.cells.len() - 1)
        }
    }
}

impl BandReader {
    fn load(&mut self, b: usize) -> Result<Loaded> {
        let mut tris = Vec::new();
        let mut bytes = Vec::new();
        for &(offset, count) in &self.index[b] {
            bytes.resize(count as usize * RECORD, 0);
            self.file
                .seek(SeekFrom::Start(offset))
                .and_then(|_| self.file.read_exact(&mut bytes))
                .map_err(|e| Error::write(&self.dir, e))?;
            for r in bytes.chunks_exact(RECORD) {
                let f =
                    |i: usize| f64::from_le_bytes(r[8 + 8 * i..16 + 8 * i].try_into().expect("8"));
                let id = u64::from_le_bytes(r[..8].try_into().expect("8 bytes"));
                let v = [[f(0), f(1), f(2)], [f(3), f(4), f(5)], [f(6), f(7), f(8)]];
                tris.push((id, Tri { v }));
            }
        }
        let [x0, x1] = self.bands.x;
        let width = (x1 - x0).max(self.bands.h);
        let ncols = ((width / self.bands.h).ceil() as usize).clamp(1, 1 << 16);
        let mut loaded = Loaded {
            tris,
            cells: vec![Vec::new(); ncols],
            x0,
            w: width / ncols as f64,
        };
        for (i, (_, t)) in loaded.tris.iter().enumerate() {
            let bb = t.bbox();
            for c in loaded.column(bb[0])..=loaded.column(bb[2]) {
                loaded.cells[c].push(i as u32);
            }
        }
        Ok(loaded)
    }
}

/// Phase 2: a [`TriangleSink`] for the surface, computing cut and fill against the reference.
pub struct OverlaySink {
    reference: BandReader,
    boundary: Option<Boundary>,
    loaded: HashMap<usize, Loaded>,
    acc: CutFill,
    triangles: u64,
    pairs: u64,
    band_loads: u64,
    max_loaded: usize,
    candidates: Vec<(u64, usize, u32)>,
    scratch: (Vec<PV>, Vec<PV>),
    /// Surface triangles meeting more than `tall_bands` bands, waiting for a pass over the bands.
    tall: Vec<Tri>,
    tall_bands: usize,
    /// The highest watermark seen: bands below it were dropped.
    watermark: f64,
}

impl OverlaySink {
    /// Cut and fill of the streamed surface against `reference`, inside `boundary` when given.
    pub fn new(reference: BandReader, boundary: Option<Boundary>) -> OverlaySink {
        OverlaySink {
            reference,
            boundary,
            loaded: HashMap::new(),
            acc: CutFill::default(),
            triangles: 0,
            pairs: 0,
            band_loads: 0,
            max_loaded: 0,
            candidates: Vec::new(),
            scratch: (Vec::new(), Vec::new()),
            tall: Vec::new(),
            tall_bands: TALL_BANDS,
            watermark: f64::NEG_INFINITY,
        }
    }

    /// Pairs the waiting tall triangles with the reference, band by band: a band already in
    /// memory is used, any other is loaded for the pass and dropped. A pair is counted in the
    /// first band and column where both triangles are filed.
    fn pass_over_bands(&mut self) -> Result<()> {
        let tall = std::mem::take(&mut self.tall);
        let bands = self.reference.bands;
        let span: Vec<(usize, usize)> = tall
            .iter()
            .map(|a| {
                let bb = a.bbox();
                (bands.of(bb[1]), bands.of(bb[3]))
            })
            .collect();
        let (Some(lo), Some(hi)) = (
            span.iter().map(|s| s.0).min(),
            span.iter().map(|s| s.1).max(),
        ) else {
            return Ok(());
        };
        let mut others: Vec<(usize, Tri)> = Vec::new();
        for b in lo..=hi {
            let users = (0..tall.len()).filter(|&k| span[k].0 <= b && b <= span[k].1);
            let mut users = users.peekable();
            if users.peek().is_none() {
                continue;
            }
            let temp;
            let l = match self.loaded.get(&b) {
                Some(l) => l,
                None => {
                    temp = self.reference.load(b)?;
                    self.band_loads += 1;
                    &temp
                }
            };
            others.clear();
            for k in users {
                let bb = tall[k].bbox();
                let c0 = l.column(bb[0]);
                for c in c0..=l.column(bb[2]) {
                    for &i in &l.cells[c] {
                        let t = &l.tris[i as usize].1;
                        let tb = t.bbox();
                        if overlaps(&bb, &tb)
                            && b == span[k].0.max(bands.of(tb[1]))
                            && c == c0.max(l.column(tb[0]))
                        {
                            others.push((k, *t));
                        }
                    }
                }
            }
            for &(k, t) in &others {
                self.pair(&tall[k], &t);
            }
        }
        Ok(())
    }

    /// The totals so far.
    pub fn totals(&self) -> CutFillTotals {
        self.acc.totals()
    }

    /// Adds the pair (surface triangle `a`, reference triangle `b`).
    fn pair(&mut self, a: &Tri, b: &Tri) {
        let (mut p, mut q) = std::mem::take(&mut self.scratch);
        p.clear();
        p.extend(a.v.iter().copied());
        for i in 0..3 {
            let (s, e) = (b.v[i], b.v[(i + 1) % 3]);
            clip_left(&p, [s[0], s[1]], [e[0], e[1]], &mut q);
            std::mem::swap(&mut p, &mut q);
            if p.len() < 3 {
                self.scratch = (p, q);
                return;
            }
        }
        self.pairs += 1;
        let acc = &mut self.acc;
        let mut add = |piece: &[PV]| {
            let d: Vec<PV> = piece
                .iter()
                .map(|v| [v[0], v[1], v[2] - b.plane_value([v[0], v[1]])])
                .collect();
            acc.add(&d);
        };
        match &self.boundary {
            None => add(&p),
            Some(bd) => bd.clip(&p, add),
        }
        self.scratch = (p, q);
    }
}

fn overlaps(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3]
}

impl TriangleSink for OverlaySink {
    fn begin(&mut self, _info: &StreamInfo) -> Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        self.triangles += 1;
        let Some(a) = Tri::new(t) else {
            return Ok(());
        };
        let bb = a.bbox();
        let bands = self.reference.bands;
        let (b0, b1) = (bands.of(bb[1]), bands.of(bb[3]));
        // A late triangle (some of its bands were dropped at a watermark) waits too: the sweep
        // gives the hull's triangles late, all along the data, and they reloaded every band.
        if b1 - b0 >= self.tall_bands || bands.top(b0) < self.watermark {
            if self.tall.len() == MAX_TALL {
                self.pass_over_bands()?;
            }
            self.tall.push(a);
            return Ok(());
        }
        self.candidates.clear();
        for b in b0..=b1 {
            if !self.loaded.contains_key(&b) {
                let l = self.reference.load(b)?;
                self.band_loads += 1;
                self.loaded.insert(b, l);
                self.max_loaded = self.max_loaded.max(self.loaded.len());
            }
            let l = &self.loaded[&b];
            for c in l.column(bb[0])..=l.column(bb[2]) {
                for &i in &l.cells[c] {
                    let (id, t) = &l.tris[i as usize];
                    if overlaps(&bb, &t.bbox()) {
                        self.candidates.push((*id, b, i));
                    }
                }
            }
        }
        self.candidates.sort_unstable_by_key(|c| c.0);
        self.candidates.dedup_by_key(|c| c.0);
        let candidates = std::mem::take(&mut self.candidates);
        for &(_, b, i) in &candidates {
            let other = self.loaded[&b].tris[i as usize].1;
            self.pair(&a, &other);
        }
        self.candidates = candidates;
        Ok(())
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        let bands = self.reference.bands;
        self.watermark = self.watermark.max(y);
        self.loaded.retain(|&b, _| bands.top(b) >= y);
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        self.pass_over_bands()?;
        Ok(ProductSummary::Volume(VolumeSummary {
            partials: None,
            totals: self.acc.totals(),
            reference: VolumeReference::Surface(self.reference.triangles),
            boundary_area: self.boundary.as_ref().map(Boundary::area),
            triangles: self.triangles,
            overlay: Some(OverlayStats {
                pairs: self.pairs,
                band_loads: self.band_loads,
                max_bands_in_memory: self.max_loaded as u64,
            }),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::products::testutil::{
        Step, feed, in_sweep_order, random_tin, shuffled_with_watermarks,
    };
    use crate::products::volume::VolumeSink;

    fn info() -> StreamInfo {
        StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 100.0, 100.0],
        }
    }

    fn overlay(reference: &[Step], surface: &[Step], bands: usize) -> OverlaySink {
        let dir = tempfile::tempdir().unwrap();
        let mut store = BandStore::new(dir.path(), bands);
        feed(&mut store, &info(), reference);
        let mut sink = OverlaySink::new(store.into_reader().unwrap(), None);
        feed(&mut sink, &info(), surface);
        sink
    }

    /// Triangles that wait for a pass over the bands (all but the smallest, with a threshold of
    /// one band) give exactly the totals of pairing each one as it comes (the sums are exact):
    /// each pair counted once, in sweep order and shuffled.
    #[test]
    fn waiting_tall_triangles_give_the_same_totals() {
        let a = random_tin(900, 100.0, 3, |x, y| 15.0 * (x / 7.0).sin() - y / 9.0);
        let b = random_tin(800, 100.0, 4, |x, y| 10.0 * (x / 11.0).cos() + 0.1 * y);
        let run = |tall_bands: usize, shuffled: bool| {
            let dir = tempfile::tempdir().unwrap();
            let mut store = BandStore::new(dir.path(), 64);
            feed(&mut store, &info(), &in_sweep_order(&b));
            let mut sink = OverlaySink::new(store.into_reader().unwrap(), None);
            sink.tall_bands = tall_bands;
            let steps = if shuffled {
                shuffled_with_watermarks(&a, 9)
            } else {
                in_sweep_order(&a)
            };
            feed(&mut sink, &info(), &steps);
            (format!("{:?}", sink.totals()), sink.pairs, sink.max_loaded)
        };
        let want = run(usize::MAX, false);
        for shuffled in [false, true] {
            let got = run(1, shuffled);
            assert_eq!((&got.0, got.1), (&want.0, want.1));
            assert!(got.2 <= want.2);
        }
    }

    /// Two different TINs of planes: the difference is the exact difference of the planes, and
    /// agrees with each surface's volume against z = 0.
    #[test]
    fn two_planes_on_different_tins() {
        let a = random_tin(600, 100.0, 1, |x, y| 0.1 * x + 0.05 * y);
        let b = random_tin(700, 100.0, 2, |x, _| 0.1 * x - 2.5);
        let s = overlay(&in_sweep_order(&b), &in_sweep_order(&a), 16);
        let t = s.totals();
        // d = 0.05 y + 2.5 > 0 everywhere: ∫ = 100 × (0.05 × 5000 + 250) = 50_000.
        assert!((t.cut_volume - 50_000.0).abs() < 1e-6, "{t:?}");
        assert_eq!(t.fill_volume, 0.0);
        assert!((t.area - 10_000.0).abs() < 1e-7, "{t:?}");
    }

    /// Curved surfaces: the net difference equals the difference of the volumes against a plane,
    /// in sweep order and shuffled (late triangles, band reloads), with few or many bands.
    #[test]
    fn net_equals_difference_of_plane_volumes_in_any_order() {
        let f = |x: f64, y: f64| 15.0 * (x / 7.0).sin() - 15.0 * (y / 9.0).sin();
        let g = |x: f64, y: f64| 10.0 * (x / 11.0).cos() + 0.1 * y;
        let a = random_tin(900, 100.0, 3, f);
        let b = random_tin(800, 100.0, 4, g);
        let plane = |tris: &[[[f64; 3]; 3]]| {
            let mut s = VolumeSink::new(0.0, None);
            feed(&mut s, &info(), &in_sweep_order(tris));
            s.totals().net_volume
        };
        let want = plane(&a) - plane(&b);
        let t1 = overlay(&in_sweep_order(&b), &in_sweep_order(&a), 8).totals();
        let s2 = overlay(
            &shuffled_with_watermarks(&b, 5),
            &shuffled_with_watermarks(&a, 6),
            64,
        );
        let t2 = s2.totals();
        assert!(
            (t1.net_volume - want).abs() < 1e-6 * want.abs().max(1.0),
            "{t1:?} {want}"
        );
        assert!(
            (t2.net_volume - want).abs() < 1e-6 * want.abs().max(1.0),
            "{t2:?} {want}"
        );
        assert!((t1.cut_volume - t2.cut_volume).abs() < 1e-6 * t1.cut_volume);
        assert!(t1.cut_volume > 0.0 && t1.fill_volume > 0.0);
        assert!((t1.area - 10_000.0).abs() < 1e-6);
        assert!(s2.band_loads > 64, "late triangles reload bands");
    }
}
