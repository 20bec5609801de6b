//! Ground classification: progressive TIN densification (Axelsson 2000) on the exact TIN, in
//! blocks of a global grid, so that every point's class depends only on the points near it.
//!
//! **Definition.** Space is cut into square *ground blocks* of side `32 × step` (16 for steps
//! over 6.25, 8 over 12.5, 4 over 25: blocks of 100 to 200 units), aligned at the origin: block
//! `(i, j)` holds the points with `floor(x / B) = i`, `floor(y / B) = j`. The points a block
//! owns are classified by running
//! the densification (`ptd.rs`) on the points of the block grown by a buffer of `2 × step` on
//! every side (the seed cells of side `step`, aligned at the origin too, two cells deep), the
//! block alone deciding. So a point's class is a function of the points within the block's
//! rectangle plus `2 × step`: the same for any `--threads`, any `--mem`, any order or split of
//! the input files, any tiling made of whole blocks. Points are in the crate's global input
//! order (files in the order given, then points in file order), which breaks every tie.
//!
//! **Classes.** Ground → 2; low noise (a seed far below the seeds around it, or a point left
//! over far below the ground TIN: more than `low_noise`) → 7; every other point keeps its class,
//! except that a point of class 2 the filter does not accept becomes 1 (class 2 in the output
//! is exactly this filter's ground), and with `reset` every other point becomes 1. Withheld
//! points and points already classified as noise (7, 18) never take part (neither seeds nor
//! candidates) and keep their class, with `reset` too.
//!
//! **Memory.** The points are read once into the tiles' block index (an external sort by seed
//! cell, spilled beyond half of `--mem`; 64-byte sort records, 24 + 8 bytes a point stored),
//! each block's run holds its buffered rectangle (at most [`RUN_BYTES_PER_POINT`] bytes a
//! point; a run that does not fit what `--mem` leaves after the index and the class store is
//! refused before any block runs), and the new
//! classes go to a [`ClassStore`] (one byte a point; a temporary file past an eighth of `--mem`).

mod blocks;
mod densify;
mod ptd;

pub(crate) use blocks::check_reach;
pub use blocks::{ClassStore, Feed, GroundInput, RUN_BYTES_PER_POINT, classify_stream};
/// What the class store holds in memory at least (a temporary file's read piece).
pub(crate) const CLASS_READ_PIECE: u64 = blocks::READ_PIECE as u64;

use crate::error::{Error, Result};
use crate::input::las::{Filter, LidarPoint, LidarReader, ReadOptions};
use crate::tiles::grid::TileGrid;
use std::path::{Path, PathBuf};

/// Seed cells of buffer around a block (the buffer is `BUFFER_CELLS × step` wide).
pub const BUFFER_CELLS: i64 = 2;

/// The ground filter's parameters.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GroundParams {
    /// Side of the seed cells (the lowest point of each is a seed): larger than the largest
    /// building (metres, or the data's horizontal unit).
    pub step: f64,
    /// Largest distance from a candidate to the plane of its ground triangle.
    pub max_distance: f64,
    /// Largest angle (degrees) between the plane of the ground triangle and the lines from a
    /// candidate to its three vertices.
    pub max_angle: f64,
    /// A seed lower than the median of its neighbour seeds, or a point left over lower than
    /// the ground TIN, by more than this is low noise (class 7).
    pub low_noise: f64,
    /// A point left over within this vertical distance of the final ground TIN is ground too
    /// (LAStools' `-offset`).
    pub offset: f64,
    /// Mirror candidates that fail only on the angles through the nearest vertex (Axelsson's
    /// treatment of steep edges).
    pub mirror: bool,
    /// Side of the densification cells: only the lowest point of each cell (aligned at the
    /// origin) densifies the TIN; the others are judged once against the final ground TIN
    /// (the densification's test, or `offset`). 0 (the default): every point densifies. A
    /// plan written before this parameter existed reads as 0.
    #[serde(default)]
    pub densify_cell: f64,
    /// Points that are not ground (nor noise, nor withheld) become class 1.
    pub reset: bool,
}

/// Kinds of terrain with their parameters (LAStools `lasground`'s names, and lasR's advice).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Terrain {
    /// No buildings, dense detail: step 3.
    Wilderness,
    /// Open natural terrain: step 5.
    Nature,
    /// Villages, small buildings: step 10.
    Town,
    /// Cities: step 25.
    City,
    /// Large industrial or urban buildings: step 50.
    Metro,
    /// Forest under canopy (no buildings): step 10.
    Forest,
    /// Steep terrain: step 10, `max_angle` 12, `max_distance` 1.5, `low_noise` 10.
    Mountains,
}

impl Terrain {
    /// The parameters of this terrain.
    pub fn params(self) -> GroundParams {
        let base = GroundParams::default();
        match self {
            Terrain::Wilderness => GroundParams { step: 3.0, ..base },
            Terrain::Nature => GroundParams { step: 5.0, ..base },
            Terrain::Town => GroundParams { step: 10.0, ..base },
            Terrain::City => GroundParams { step: 25.0, ..base },
            Terrain::Metro => GroundParams { step: 50.0, ..base },
            Terrain::Forest => GroundParams { step: 10.0, ..base },
            Terrain::Mountains => GroundParams {
                step: 10.0,
                max_angle: 12.0,
                max_distance: 1.5,
                low_noise: 10.0,
                ..base
            },
        }
    }
}

impl Default for GroundParams {
    fn default() -> Self {
        GroundParams {
            step: 20.0,
            max_distance: 1.0,
            max_angle: 6.0,
            low_noise: 5.0,
            offset: 0.2,
            mirror: true,
            densify_cell: 0.0,
            reset: false,
        }
    }
}

impl GroundParams {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`Error::Options`] naming the bad one.
    pub fn check(&self) -> Result<()> {
        let positive = |v: f64, name: &str, what: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::Options(format!("{name} {v}: give {what}")))
            }
        };
        positive(self.step, "--step", "a positive cell side, e.g. 5 (metres)")?;
        positive(
            self.max_distance,
            "--max-distance",
            "a positive distance, e.g. 1",
        )?;
        positive(self.low_noise, "--low-noise", "a positive height, e.g. 5")?;
        if !(self.offset.is_finite() && self.offset >= 0.0) {
            return Err(Error::Options(format!(
                "--offset {}: give a vertical distance >= 0, e.g. 0.2 (the default)",
                self.offset
            )));
        }
        if !(self.densify_cell.is_finite() && self.densify_cell >= 0.0) {
            return Err(Error::Options(format!(
                "--densify-cell {}: give a cell side >= 0, e.g. 1 (0: every point densifies)",
                self.densify_cell
            )));
        }
        if !(self.max_angle > 0.0 && self.max_angle < 90.0) {
            return Err(Error::Options(format!(
                "--max-angle {}: give an angle in degrees between 0 and 90, e.g. 6 (the default)",
                self.max_angle
            )));
        }
        Ok(())
    }

    /// Halvings of a ground block into seed cells (a block is `2^shift` cells a side): blocks
    /// of 100 to 200 units. (Blocks of 50 to 100 units ran each point in up to four runs: the
    /// buffer's overhead was 4× the points, 2.3× now; ARSO's densest 160 m block with its
    /// buffer holds 1.11 M points, which at [`RUN_BYTES_PER_POINT`] fits `--mem 128M`.)
    pub fn shift(&self) -> u32 {
        if self.step <= 6.25 {
            5
        } else if self.step <= 12.5 {
            4
        } else if self.step <= 25.0 {
            3
        } else {
            2
        }
    }

    /// The grid: ground blocks of `2^shift` seed cells, cells of side `step`.
    pub(crate) fn grid(&self) -> Result<TileGrid> {
        TileGrid::new(self.step * f64::from(1u32 << self.shift()), self.shift())
    }

    /// The side of a ground block.
    pub fn block_side(&self) -> f64 {
        self.step * f64::from(1u32 << self.shift())
    }

    /// The buffer around a block that its run reads.
    pub fn buffer(&self) -> f64 {
        BUFFER_CELLS as f64 * self.step
    }
}

/// What a classification did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct GroundSummary {
    /// Points classified (all the points of the inputs).
    pub points: u64,
    /// Points classified as ground (class 2).
    pub ground: u64,
    /// Points written as low noise (class 7): those the filter flags, and those that were class
    /// 7 already (they keep it; `changed` in the CLI's summary counts what changed).
    pub low_noise: u64,
    /// Seeds (a point can be a seed in the runs of several blocks).
    pub seeds: u64,
    /// Ground blocks with points.
    pub blocks: u64,
    /// Side of a ground block.
    pub block: f64,
    /// Buffer around a block.
    pub buffer: f64,
    /// Points of the largest run (a block and its buffer).
    pub largest_run_points: u64,
    /// Bytes of the run that held the most (its points and tables at their peak).
    pub largest_run_bytes: u64,
    /// Most densification iterations of a run.
    pub iterations: u64,
    /// Seconds reading and indexing the points.
    pub read_seconds: f64,
    /// Seconds classifying the blocks.
    pub classify_seconds: f64,
}

/// A point's tag in the block index: its global index, its class and whether it may be ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Tag(pub u64);

impl Tag {
    const ELIGIBLE: u64 = 1 << 8;
    /// Set only within a block's run: the block owns the point.
    const OWNED: u64 = 1 << 9;

    fn of(p: &GroundInput) -> Tag {
        let eligible = !p.withheld && p.class != 7 && p.class != 18;
        Tag((p.index << 16) | if eligible { Tag::ELIGIBLE } else { 0 } | u64::from(p.class))
    }

    pub(crate) fn index(self) -> u64 {
        self.0 >> 16
    }

    fn class(self) -> u8 {
        self.0 as u8
    }

    pub(crate) fn eligible(self) -> bool {
        self.0 & Tag::ELIGIBLE != 0
    }

    /// The same tag, marked as owned by the block being run.
    pub(crate) fn owned(self) -> Tag {
        Tag(self.0 | Tag::OWNED)
    }

    /// Does the block being run own the point?
    pub(crate) fn is_owned(self) -> bool {
        self.0 & Tag::OWNED != 0
    }

    /// The class the point gets.
    fn new_class(self, label: ptd::Label, reset: bool) -> u8 {
        match label {
            ptd::Label::Ground => 2,
            ptd::Label::LowNoise => 7,
            ptd::Label::Other if !self.eligible() => self.class(),
            ptd::Label::Other if reset || self.class() == 2 => 1,
            ptd::Label::Other => self.class(),
        }
    }
}

/// Classifies every point of the LAS/LAZ/COPC files `paths` (taken together: a block's buffer
/// reaches into the neighbouring file), within `mem` bytes, temporary files under `tmp`. The
/// classes are by global input index (files in the order given).
///
/// # Errors
/// The readers' errors; those of [`classify_stream`].
pub fn classify_files(
    paths: &[PathBuf],
    params: &GroundParams,
    mem: u64,
    tmp: &Path,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<(ClassStore, GroundSummary)> {
    params.check()?;
    // Seed cells too small for a file's coordinates: refused naming it, before any point.
    for p in paths {
        if let Ok(info) = crate::input::las::FileInfo::read(p)
            && let Some(r) = info.known_rect()
        {
            check_reach(params, p, r)?;
        }
    }
    let options = ReadOptions::for_budget(mem);
    let mut reader = LidarReader::open_with(paths, &Filter::keep_all(), options)?;
    let total = reader.point_count();
    let mut feed = |push: &mut dyn FnMut(GroundInput) -> Result<()>| -> Result<()> {
        crate::tiles::read::prefetched(&mut reader, |buf: &[LidarPoint], _| {
            for p in buf {
                push(GroundInput {
                    index: p.index,
                    xyz: [p.x, p.y, p.z],
                    class: p.classification,
                    withheld: p.flags & LidarPoint::WITHHELD != 0,
                })?;
            }
            Ok(())
        })
    };
    classify_stream(params, total, mem, tmp, &mut feed, progress)
}

/// Classifies points in memory: `points[i]` of class `classes[i]` (withheld when
/// `withheld[i]`), the same classes as [`classify_files`] gives the same points in the same
/// order.
///
/// # Errors
/// [`Error::Options`] when the slices differ in length; those of [`classify_stream`].
pub fn classify(
    points: &[[f64; 3]],
    classes: &[u8],
    withheld: &[bool],
    params: &GroundParams,
    mem: u64,
) -> Result<Vec<u8>> {
    if classes.len() != points.len() || withheld.len() != points.len() {
        return Err(Error::Options(format!(
            "ground: {} points, {} classes and {} withheld flags: give one of each per point",
            points.len(),
            classes.len(),
            withheld.len()
        )));
    }
    let tmp = std::env::temp_dir();
    let mut feed = |push: &mut dyn FnMut(GroundInput) -> Result<()>| -> Result<()> {
        for (i, p) in points.iter().enumerate() {
            push(GroundInput {
                index: i as u64,
                xyz: *p,
                class: classes[i],
                withheld: withheld[i],
            })?;
        }
        Ok(())
    };
    let (mut store, _) = classify_stream(
        params,
        points.len() as u64,
        mem,
        &tmp,
        &mut feed,
        &mut |_, _, _| {},
    )?;
    (0..points.len() as u64).map(|i| store.get(i)).collect()
}
