//! Phase 1: read every input point (with filters) into the external sorter, in the local frame.

use super::config::{self, Source};
use super::{Frame, Input, RunConfig, STRIP_RATIO, SweepAxis};
use crate::error::{Error, Result};
use crate::geom::predicates;
use crate::input::las::{Crs, FilterStats, LidarPoint, LidarReader};
use crate::input::spread::Spread;
use crate::input::xyz::XyzReader;
use crate::sort::external::{ExternalSorter, SortRecord};

/// What reading found out.
#[derive(Debug)]
pub(crate) struct ReadResult {
    pub frame: Frame,
    pub crs: Option<Crs>,
    /// The headers' warnings ([`LidarReader::warnings`]).
    pub warnings: Vec<String>,
    /// Local-frame extent of the points read: `[xmin, ymin, xmax, ymax]`.
    pub bounds: [f64; 4],
    /// Lowest and highest z of the points read.
    pub z_range: [f64; 2],
    pub points: u64,
    /// What the filters read, kept and dropped.
    pub stats: FilterStats,
    /// Every `2^k`-th point's local x (at most [`SAMPLE`] values), for the front's index.
    pub x_sample: Vec<f64>,
}

/// Size of the x sample.
const SAMPLE: usize = 4096;

/// Keeps every `stride`-th value; halves the sample and doubles the stride when it is full, so it
/// stays evenly spread over the input, deterministically.
#[derive(Debug)]
struct Sampler {
    xs: Vec<f64>,
    stride: u64,
    seen: u64,
}

impl Sampler {
    #[inline]
    fn add(&mut self, x: f64) {
        if self.seen.is_multiple_of(self.stride) {
            if self.xs.len() == SAMPLE {
                let mut k = 0;
                self.xs.retain(|_| {
                    k += 1;
                    k % 2 == 1
                });
                self.stride *= 2;
                if !self.seen.is_multiple_of(self.stride) {
                    self.seen += 1;
                    return;
                }
            }
            self.xs.push(x);
        }
        self.seen += 1;
    }
}

/// Progress callback: points read so far, and the total if known.
pub(crate) type Progress<'a> = &'a mut dyn FnMut(u64, Option<u64>);

const CHUNK: usize = 1 << 16;

/// Reads all of the input into `sorter`, exchanging x and y when the sweep goes along x (the
/// configured axis; `Auto` may choose x only when `free_axis`, i.e. nothing downstream needs y
/// order).
pub(crate) fn read_into(
    config: &RunConfig,
    free_axis: bool,
    sorter: &mut ExternalSorter,
    progress: Progress,
) -> Result<ReadResult> {
    let input = config.input();
    let axis = config.options().sweep_axis;
    let mut bounds = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut sample = Sampler {
        xs: Vec::with_capacity(SAMPLE),
        stride: 1,
        seen: 0,
    };
    let mut swap = axis == SweepAxis::X;
    let mut z_range = [f64::INFINITY, f64::NEG_INFINITY];
    let mut spread = Spread::default();
    let mut add = |s: &mut ExternalSorter, swap: bool, r: SortRecord| -> Result<()> {
        z_range = [z_range[0].min(r.z), z_range[1].max(r.z)];
        spread.add(r.x, r.y);
        let r = if swap {
            SortRecord {
                x: r.y,
                y: r.x,
                ..r
            }
        } else {
            r
        };
        sample.add(r.x);
        bounds[0] = bounds[0].min(r.x);
        bounds[1] = bounds[1].min(r.y);
        bounds[2] = bounds[2].max(r.x);
        bounds[3] = bounds[3].max(r.y);
        s.push(r)
    };
    if config.source() == Source::Lidar {
        let options = crate::input::las::ReadOptions::for_budget(config.options().mem);
        let mut reader = config.open_lidar(options)?;
        if axis == SweepAxis::Auto && free_axis {
            let b = reader.bounds();
            let (w, h) = (b.max[0] - b.min[0], b.max[1] - b.min[1]);
            swap = w > STRIP_RATIO * h;
        }
        let total = reader.point_count();
        sorter.reserve(total)?;
        let crs = reader.crs().cloned();
        let mut buf: Vec<LidarPoint> = Vec::with_capacity(CHUNK);
        let mut n = 0u64;
        loop {
            buf.clear();
            if reader.read_chunk(&mut buf, CHUNK)? == 0 {
                break;
            }
            for p in &buf {
                // Real-world doubles, exactly as written to the outputs: the triangulation is
                // Delaunay for the coordinates in the output file (see docs/ARCHITECTURE.md).
                add(
                    sorter,
                    swap,
                    SortRecord {
                        x: p.x,
                        y: p.y,
                        z: p.z,
                        index: p.index,
                    },
                )?;
            }
            n += buf.len() as u64;
            // The bar counts the points read (and skipped outside the box) against the
            // headers' total, not the points kept.
            let s = reader.stats();
            progress(s.read + s.skipped, Some(total));
        }
        let mut warnings = reader.warnings();
        warnings.extend(spread.far_points().map(|f| f.warning()));
        return Ok(ReadResult {
            frame: Frame { swap },
            crs,
            warnings,
            bounds,
            z_range,
            points: n,
            stats: *reader.stats(),
            x_sample: sample.xs,
        });
    }
    // XYZ text: the box filter (the only one that applies, `RunConfig::new` refuses the others).
    let bbox = input.filter.bbox.map(|b| b.corners());
    let mut stats = FilterStats::default();
    let mut n = 0u64;
    let mut buf: Vec<[f64; 3]> = Vec::with_capacity(CHUNK);
    for path in &input.paths {
        let mut reader = XyzReader::open(path)?;
        loop {
            buf.clear();
            if reader.read_chunk(&mut buf, CHUNK)? == 0 {
                break;
            }
            for p in &buf {
                stats.read += 1;
                if let Some([x0, y0, x1, y1]) = bbox
                    && !(p[0] >= x0 && p[0] <= x1 && p[1] >= y0 && p[1] <= y1)
                {
                    stats.bbox += 1;
                    continue;
                }
                stats.kept += 1;
                for v in [p[0], p[1]] {
                    if !predicates::check_coord(v) {
                        return Err(Error::Format {
                            path: path.clone(),
                            message: format!(
                                "point {n}: coordinate {v} is outside the supported range \
                                 (|v| <= {:e}, and 0 or |v| >= {:e})",
                                predicates::MAX_COORD,
                                predicates::MIN_NONZERO_COORD
                            ),
                        });
                    }
                }
                // `+ 0.0` makes -0.0 and 0.0 one position.
                add(
                    sorter,
                    swap,
                    SortRecord {
                        x: p[0] + 0.0,
                        y: p[1] + 0.0,
                        z: p[2],
                        index: stats.read - 1,
                    },
                )?;
                n += 1;
            }
            progress(stats.read, None);
        }
    }
    Ok(ReadResult {
        frame: Frame { swap },
        crs: None,
        warnings: spread
            .far_points()
            .map(|f| f.warning())
            .into_iter()
            .collect(),
        bounds,
        z_range,
        points: n,
        stats,
        x_sample: sample.xs,
    })
}

/// Reads all points of `input` into memory, in real-world coordinates, with the CRS when known
/// (for commands that need the whole set, such as `crossval`).
///
/// # Errors
/// Reader errors; [`Error::NoInput`]; [`Error::Format`] for LAS/LAZ files mixed with XYZ or a
/// streaming mesh, which holds a triangulation rather than points to read.
pub fn read_points(input: &Input) -> Result<(Vec<[f64; 3]>, Option<Crs>)> {
    let source = Source::of(&input.paths)?;
    if source == Source::Stream {
        return Err(Error::Format {
            path: input.paths[0].clone(),
            message: "a streaming mesh (.stin) cannot be read as points".into(),
        });
    }
    if source == Source::Lidar {
        let mut r = LidarReader::open(&input.paths, &input.filter)?;
        let pts = r.read_all()?;
        let crs = r.crs().cloned();
        Ok((pts.iter().map(|p| [p.x, p.y, p.z]).collect(), crs))
    } else {
        config::check_filter(source, &input.filter, &input.paths)?;
        let mut all = Vec::new();
        for p in &input.paths {
            all.extend(crate::input::xyz::read_xyz(p)?);
        }
        if let Some([x0, y0, x1, y1]) = input.filter.bbox.map(|b| b.corners()) {
            all.retain(|p| p[0] >= x0 && p[0] <= x1 && p[1] >= y0 && p[1] <= y1);
        }
        Ok((all, None))
    }
}
