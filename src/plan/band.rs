//! The data's hull band of a plan ([`crate::HullBand`]): computed when the plan is saved, after
//! the chunk indexes it decodes through, and stored in `DIR/index/band`; every task reads it
//! (through [`Plan::task_band`], into its [`crate::TaskScope::band`]).
//!
//! The file holds a magic string, the [`Plan::id`] of the plan it was computed for (which pins
//! the job's filters and duplicate policy and the files' stamps), whether the band is used, its
//! width, the hull's corners, the inner polygon's, the band's points, and the SHA-256 of all
//! that: a task refuses a band file that is missing, truncated, edited or of another plan (exit
//! status 3), as it refuses such a chunk index; `plan` computes it again when the one in the
//! directory is not of this plan.

use super::{Job, Plan, PlanDir, PlanFile, bad};
use crate::error::Result;
use crate::tiles::HullBand;
use crate::tiles::band::{BAND_WIDTH, BandSource};
use std::path::PathBuf;
use std::sync::Arc;

const MAGIC: &[u8; 8] = b"STBAND01";
/// Magic, plan id (64 hex digits), used flag, width, three counts.
const HEAD: usize = 8 + 64 + 8 + 8 + 24;
const SUM: usize = 32;

/// The band width a new plan over `files` running `job` gives its tasks, or `None` where the
/// band is not used yet (docs/SCALING.md): several files with points, a file that is not a
/// local plain LAZ/LAS (COPC, a URL), breaklines or trimming rings, `--ground`.
pub(super) fn width_for(job: &Job, files: &[PlanFile]) -> Option<f64> {
    let mut with_points = files.iter().filter(|f| f.points > 0);
    let one = with_points.next()?;
    let plain = one.indexed && one.stamp.is_some() && one.version.is_none();
    (with_points.next().is_none() && plain && job.lines.is_none() && job.ground.is_none())
        .then_some(BAND_WIDTH)
}

impl Plan {
    /// The plan without a hull band: its tasks run as before (the same outputs; along the
    /// data's edge, more runs with wider buffers), and without a point store, which comes with
    /// the band. `plan --no-hull-band`, for comparison.
    pub fn without_hull_band(mut self) -> Plan {
        self.hull_band = None;
        self.point_store = None;
        self.id = super::PlanId::default();
        self.fingerprint = self.id().to_string();
        self
    }

    /// Where the plan's band lies under `dir`.
    pub fn band_path(dir: &PlanDir) -> PathBuf {
        dir.join("index").join("band")
    }

    /// Computes and writes (atomically) the plan's band when it has one ([`Plan::hull_band`])
    /// and `dir` holds none of this plan: its hull's chunks and then the band's, decoded through
    /// the chunk indexes (written first), or the point store's cells, read (written first).
    ///
    /// # Errors
    /// The chunk indexes' and the decoder's errors; [`crate::Error::Io`] naming the file.
    pub(super) fn write_band(&self, dir: &PlanDir) -> Result<()> {
        let Some(width) = self.hull_band else {
            return Ok(());
        };
        if self.read_band(dir).is_ok() {
            return Ok(());
        }
        // From the point store's cells when the plan has one (it has no chunk index then).
        let store = self.task_store(dir)?;
        let mut paths = Vec::new();
        let mut chunks = Vec::new();
        for (k, f) in self.files.iter().enumerate().filter(|(_, f)| f.points > 0) {
            paths.push(f.path.clone());
            if store.is_none() {
                chunks.push((f.path.clone(), Arc::new(self.chunk_index(dir, k)?)));
            }
        }
        let src = BandSource {
            paths: &paths,
            filter: &self.job.filter(),
            chunks: &chunks,
            store: store.as_deref(),
            policy: self.job.duplicates,
            crs: self.job.crs()?,
            mem: self.task_mem(),
        };
        let band = HullBand::compute(&src, width)?;
        dir.make_dir("index")?;
        dir.write(
            &Self::band_path(dir),
            &encode(self.id(), width, band.as_ref()),
        )
    }

    /// The band the plan's tasks are given: `None` when the plan has none, or when its data had
    /// none worth giving (written so by `plan`).
    ///
    /// # Errors
    /// [`crate::Error::Format`] naming the file when it is missing, truncated, edited or of
    /// another plan; the plan directory's I/O errors when it cannot be read.
    pub fn task_band(&self, dir: &PlanDir) -> Result<Option<Arc<HullBand>>> {
        if self.hull_band.is_none() {
            return Ok(None);
        }
        Ok(self.read_band(dir)?.map(Arc::new))
    }

    fn read_band(&self, dir: &PlanDir) -> Result<Option<HullBand>> {
        let p = Self::band_path(dir);
        let again = "the plan's tasks read the data's hull from it: make the plan again";
        let bytes = match dir.read(&p) {
            Ok(Some(b)) => b,
            Ok(None) => return Err(bad(&p, format!("the plan's hull band is missing; {again}"))),
            // A read that fails (a transient S3 error, a permission) is an I/O error, exit 4: the
            // plan is not known to be bad.
            Err(e) => return Err(e),
        };
        decode(&bytes, self.id())
            .map_err(|what| bad(&p, format!("the plan's hull band is {what}; {again}")))
    }
}

/// The bytes of the band file of the plan `id` (`band`: none worth giving).
fn encode(id: &str, width: f64, band: Option<&HullBand>) -> Vec<u8> {
    let (hull, inner, points) = band.map_or((&[][..], &[][..], &[][..]), |b| {
        (&b.hull[..], &b.inner[..], &b.points[..])
    });
    let mut b = Vec::with_capacity(HEAD + 16 * (hull.len() + inner.len()) + 24 * points.len());
    b.extend_from_slice(MAGIC);
    let mut idb = [b'0'; 64];
    for (d, s) in idb.iter_mut().zip(id.bytes()) {
        *d = s;
    }
    b.extend_from_slice(&idb);
    b.extend_from_slice(&u64::from(band.is_some()).to_le_bytes());
    b.extend_from_slice(&width.to_bits().to_le_bytes());
    for n in [hull.len(), inner.len(), points.len()] {
        b.extend_from_slice(&(n as u64).to_le_bytes());
    }
    for v in hull
        .iter()
        .chain(inner)
        .flatten()
        .chain(points.iter().flatten())
    {
        b.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    let sum = sha(&b);
    b.extend_from_slice(&sum);
    b
}

/// The band in `bytes` of the plan `id`, or what is wrong with them.
fn decode(bytes: &[u8], id: &str) -> std::result::Result<Option<HullBand>, &'static str> {
    if bytes.len() < HEAD + SUM || &bytes[..8] != MAGIC {
        return Err("not a sweeptin hull band (or truncated)");
    }
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap_or_default());
    let count = |o: usize| usize::try_from(u64_at(o)).unwrap_or(usize::MAX);
    let (nh, ni, np) = (count(88), count(96), count(104));
    let len = nh
        .checked_add(ni)
        .and_then(|n| n.checked_mul(16))
        .and_then(|n| np.checked_mul(24).and_then(|m| m.checked_add(n)))
        .and_then(|n| n.checked_add(HEAD + SUM));
    if len != Some(bytes.len()) {
        return Err("truncated or extended (its length is not what it says)");
    }
    let body = bytes.len() - SUM;
    if sha(&bytes[..body]) != bytes[body..] {
        return Err("damaged or edited (its checksum does not match)");
    }
    if bytes[8..72] != *id.as_bytes() {
        return Err("of another plan (made into this directory before)");
    }
    if u64_at(72) == 0 {
        return Ok(None);
    }
    let f = |i: usize| f64::from_bits(u64_at(HEAD + 8 * i));
    let hull = (0..nh).map(|i| [f(2 * i), f(2 * i + 1)]).collect();
    let o = 2 * nh;
    let inner = (0..ni).map(|i| [f(o + 2 * i), f(o + 2 * i + 1)]).collect();
    let o = 2 * (nh + ni);
    let points = (0..np)
        .map(|i| [f(o + 3 * i), f(o + 3 * i + 1), f(o + 3 * i + 2)])
        .collect();
    HullBand::from_parts(f64::from_bits(u64_at(80)), hull, inner, points)
        .map(Some)
        .ok_or("damaged (its polygons have fewer than three corners)")
}

fn sha(bytes: &[u8]) -> Vec<u8> {
    use sha2::Digest;
    sha2::Sha256::digest(bytes).to_vec()
}
