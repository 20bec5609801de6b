//! What a finished task records ([`TaskRecord`], `tiles/task_<i>.json`).

#[cfg(doc)]
use super::Plan;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// What a finished task records in `tiles/task_<i>.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskRecord {
    /// The task.
    pub index: usize,
    /// `"done"`, or `"empty"` when no point is left in the tile after the filters (no tile
    /// written: its part of the mosaic is nodata; not a failure).
    pub status: String,
    /// The buffer the task ended with.
    pub buffer: f64,
    /// Runs (1, or more when the buffer had to grow).
    pub runs: u32,
    /// Points triangulated and triangles owned.
    pub points: u64,
    /// Points decoded from the input files over all runs' last: the chunks (and COPC nodes)
    /// that meet the tile and buffer of an indexed file, every point of the others.
    #[serde(default)]
    pub decoded: u64,
    /// Points read from the plan's point store instead ([`Plan::point_store`]), over all runs'
    /// last: those of its cells that meet the tile and buffer.
    #[serde(default)]
    pub stored: u64,
    /// See `points`. With `inside_uncounted`, the triangles it certified only.
    pub triangles: u64,
    /// The task's products all cover (a DEM alone): the unwanted triangles deep inside its
    /// sub-tiles were neither certified nor counted, as one run leaves them (one run counts
    /// them by Euler's formula over all the points, which no task holds), and `triangles`
    /// misses them; the report gives no total then.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub inside_uncounted: bool,
    /// Seconds.
    pub seconds: f64,
    /// Peak resident memory of the task's process when it finished (VmHWM), in bytes, when
    /// the system reports it. `None` in records of older builds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_memory: Option<u64>,
    /// The task's outputs, by product name.
    pub outputs: Vec<(String, PathBuf)>,
    /// The [`Plan::id`] of the plan the task ran under: a record of another plan (made into
    /// the same directory before, or before the plan was edited) is no record of this one.
    /// Empty in records of older builds.
    #[serde(default)]
    pub plan: String,
    /// The sizes of `outputs` in bytes when the task finished: `--resume` runs a task again
    /// when one no longer has its size (a truncated tile). Empty in records of older builds.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bytes: Vec<u64>,
    /// What the headers of the files the task read said (as [`Plan::warnings`], for these
    /// files); `run` prints them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Exact volume partial sums (cut, fill, cut area, fill area, area), for `volume`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<[Vec<f64>; 5]>,
    /// The extent `[xmin, ymin, xmax, ymax]` of the points the task read after the filters
    /// (its tile, buffer and beyond): their union over the tasks is the extent of the points
    /// one run keeps, from which `merge` decides one run's DEM grid
    /// ([`super::merge::MosaicExtent::Data`]). `None` for a task that read no point, and in records of
    /// older builds (the mosaic then covers the tiles, with a warning).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extent: Option<[f64; 4]>,
    /// Tiles of the tiled engine the task ran (its last run): those holding points, or for a
    /// DEM every one of its plan tile (their cells may lie under other tasks' triangles).
    #[serde(default)]
    pub subtiles: u64,
}

/// Refuses to merge a plan whose tasks hold nothing, as one run refuses such a job: no task
/// found a point after the filters (the input's verdict, exit 3), or every task is empty
/// because `--max-edge` trimmed every triangle (exit 2: it wrote an all-nodata mosaic).
///
/// # Errors
/// [`crate::Error::NothingLeft`], [`crate::Error::Options`].
pub(super) fn nothing_to_merge(
    plan: &super::Plan,
    dir: &super::PlanDir,
    recs: &[TaskRecord],
) -> crate::error::Result<()> {
    if recs.is_empty() {
        return Ok(());
    }
    if recs.iter().all(|r| r.points == 0) {
        return Err(crate::Error::NothingLeft {
            files: vec![dir.join("plan.json")],
            what: "no task found a point after the filters: nothing to merge (check --class \
                   and the other filters of the plan)"
                .into(),
        });
    }
    if plan.job.max_edge.is_some() && recs.iter().all(|r| r.status == "empty") {
        return Err(crate::Error::Options(
            "the trimming (--max-edge) removed every task's triangles: nothing is left to merge \
             (a longer --max-edge keeps some)"
                .into(),
        ));
    }
    Ok(())
}
