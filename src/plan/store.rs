//! The plan's point store (`DIR/index/points`, [`crate::PointStore`]): written when the plan is
//! saved where the hull band is used (one plain local LAZ/LAS file, no breaklines, no
//! `--ground`) and the plan's directory is local, in place of the file's chunk index (one
//! decoding pass), before the band, which is computed from its cells; read by every task
//! instead of the file (docs/SCALING.md). `plan --no-store` keeps the chunk index's route.

use super::{Plan, PlanDir};
use crate::error::{Error, Result};
use crate::input::las::{LidarReader, ReadOptions};
use crate::tiles::PointStore;
use std::path::PathBuf;
use std::sync::Arc;

/// The store's cells a side: a quarter of the tile. A task reads the cells meeting its tile
/// and buffer (with the default buffer, a tenth of the tile: 6 × 6 cells, 2.25 tiles' worth of
/// points scanned, those beyond the area left out), and its blocks must be no larger than a
/// cell (a tile of at least 16 blocks of 64 points: 1,024 points; sparser tasks decode the file).
const CELLS_A_TILE: f64 = 4.0;

/// Fewer points a tile than this on average (over the files' boxes): no store. A cell then
/// holds about 16 points, fewer than a block's, so the tasks' blocks would be larger than a
/// cell and they would decode the file instead of reading the store, with no chunk index to
/// read it by ([`crate::PointStore`]'s `nests`). (lidR_Topography at tiles of 32, about 950
/// points a tile, reads the store in every task.)
const LEAST_TILE_POINTS: f64 = 256.0;

/// The store's cell side for a plan whose hull band is `band`, with tiles of side `tile`, over
/// `files`: none without a band, for data too sparse for its tasks to read it, or when the
/// cells would be finer than the block keys allow so far from the origin.
pub(super) fn cell_for(band: Option<f64>, tile: f64, files: &[super::PlanFile]) -> Option<f64> {
    band?;
    let with = files.iter().filter(|f| f.points > 0);
    let rect = with.clone().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |r, f| {
            let b = f.bounds;
            [
                r[0].min(b[0]),
                r[1].min(b[1]),
                r[2].max(b[2]),
                r[3].max(b[3]),
            ]
        },
    );
    let points: u64 = with.map(|f| f.points).sum();
    let area = ((rect[2] - rect[0]) * (rect[3] - rect[1])).max(tile * tile);
    let cell = tile / CELLS_A_TILE;
    (points as f64 * tile * tile / area >= LEAST_TILE_POINTS
        && cell >= crate::tiles::grid::TileGrid::min_block(rect))
    .then_some(cell)
}

impl Plan {
    /// The plan without a point store: its tasks decode the files (the same outputs).
    /// `plan --no-store`, for comparison, and for a plan directory that is not local.
    pub fn without_point_store(mut self) -> Plan {
        if self.point_store.is_some() {
            self.point_store = None;
            self.id = super::PlanId::default();
            self.fingerprint = self.id().to_string();
        }
        self
    }

    /// Where the plan's point store lies under `dir`.
    pub fn point_store_path(dir: &PlanDir) -> PathBuf {
        dir.join("index").join("points")
    }

    /// Decodes the plan's file once more (its filters applied) into its point store, when it
    /// has one ([`Plan::point_store`]) and `dir` holds none of this plan.
    ///
    /// # Errors
    /// [`Error::Options`] for a plan directory that is not local; the reader's errors;
    /// [`Error::Write`] naming the store (written under a temporary name: none is left).
    pub(super) fn write_point_store(&self, dir: &PlanDir) -> Result<()> {
        let Some(cell) = self.point_store else {
            return Ok(());
        };
        if dir.is_remote() {
            return Err(Error::Options(format!(
                "a plan's point store is written in a local plan directory, not {}: plan with \
                 --no-store",
                dir.display()
            )));
        }
        let p = Self::point_store_path(dir);
        dir.own_file(&p)?;
        // Made again into the same directory: this plan's store is kept when every cell is
        // whole (a damaged one is written anew: "make the plan again" repairs it).
        if PointStore::open(&p, self.id())
            .and_then(|s| s.verify())
            .is_ok()
        {
            return Ok(());
        }
        dir.make_dir("index")?;
        let paths = self.paths_with_points();
        let mem = self.task_mem();
        let options = ReadOptions {
            crs: self.job.crs()?,
            ..ReadOptions::for_budget(mem)
        };
        let mut reader = LidarReader::open_with(&paths, &self.job.filter(), options)?;
        let tmp = self.job.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
        PointStore::write(&mut reader, cell, self.id(), &p, mem, &tmp)?;
        Ok(())
    }

    /// The boxes of the data near task `i` (its plan buffer), where the plan knows them: its
    /// point store's cells, or the chunks of its files when every file is indexed.
    ///
    /// # Errors
    /// As [`Plan::task_store`] and [`Plan::chunk_index`].
    pub(super) fn data_boxes(&self, dir: &PlanDir, i: usize) -> Result<Option<Vec<[f64; 4]>>> {
        if let Some(s) = self.task_store(dir)? {
            return Ok(Some(s.rects().collect()));
        }
        let chunks = self.task_chunks(dir, i, self.buffer)?;
        if chunks.is_empty() || chunks.len() < self.task_files(i, self.buffer)?.len() {
            return Ok(None);
        }
        Ok(Some(chunks.iter().flat_map(|(_, c)| c.rects()).collect()))
    }

    /// The point store the plan's tasks read (`None` when the plan has none).
    ///
    /// # Errors
    /// [`Error::Format`] naming the store when it is missing, truncated, edited or of another
    /// plan; [`Error::Io`] when it cannot be read.
    pub fn task_store(&self, dir: &PlanDir) -> Result<Option<Arc<PointStore>>> {
        if self.point_store.is_none() {
            return Ok(None);
        }
        PointStore::open(&Self::point_store_path(dir), self.id()).map(|s| Some(Arc::new(s)))
    }
}
