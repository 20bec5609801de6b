//! `plan ground`: the ground classification itself cut into tiles. Each task classifies the
//! ground blocks that meet its tile exactly as one `sweeptin ground` run over all the plan's
//! files does ([`Plan::classify_blocks`], the route of `plan … --ground`), and writes the points
//! its tile owns ([`tile_of`]: `[x0, x1) × (y0, y1]`, the rule that places the plan's cells)
//! with those classes: one LAZ file per input file that has points there,
//! `tiles/ground_f<K>_<tx>_<ty>.laz`, a copy of input `K` with only those points
//! ([`crate::output::las::rewrite_points`]: every other attribute, the header, VLRs and EVLRs
//! kept; the header's counts and bounds those of the points written).
//!
//! [`merge_points`] checks that the tasks wrote every point of the files once (their counts add
//! up to the headers') and writes either a virtual point cloud (`.vpc`) that references the
//! tiles where they are, or one LAS/LAZ file of every point ([`crate::output::las::join_points`]:
//! tasks in order, in each the input files in the plan's order, each file's points in file
//! order), refused when the files' point formats, extra bytes, versions, GPS time types or
//! scales differ.

use super::area::{grown, overlaps, tile_of};
use super::{Plan, PlanDir, TaskRecord};
use crate::error::{Error, Result};
use crate::input::las::FileInfo;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The name of a ground task's outputs in its record.
const POINTS: &str = "points";

impl Plan {
    /// Runs task `i` of a ground plan ([`super::Product::Ground`]): writes the points its tile
    /// owns, classified, and returns its record (to be finished by [`Plan::run_task`]);
    /// `"empty"`, with no output, when the tile owns no point.
    ///
    /// # Errors
    /// [`Error::Format`] for a file changed since the plan was made; those of
    /// [`Plan::classify_blocks`] and of the writer; [`Error::Internal`] for a point of the tile
    /// that was not classified.
    pub(super) fn ground_points_task(&self, dir: &PlanDir, i: usize) -> Result<TaskRecord> {
        let params = self.job.ground.ok_or_else(|| {
            Error::Internal("a ground plan without the filter's parameters".into())
        })?;
        params.check()?;
        let t = self.task(i)?.clone();
        let mem = crate::limits::fit_address_space(self.job.mem, 0);
        // Every file the classification reads is what the plan saw.
        self.check_files(i, self.read_reach(i, 0.0)?)?;
        let (_, mut classified) = self.classify_blocks(dir, i, &params, t.bounds, mem)?;
        // The files that may hold points of the tile (a hair around it: a point's owner is
        // decided by `tile_of`, not by comparing with the tile's bounds).
        let near = grown(t.bounds, self.tile / 1024.0);
        let mut outputs = Vec::new();
        let (mut points, mut decoded) = (0u64, 0u64);
        for (k, f) in self.files.iter().enumerate() {
            if f.points == 0 || !overlaps(&f.bounds, &near) {
                continue;
            }
            let out = self.task_output(dir, i, &format!("ground_f{k}"), "laz")?;
            let mut seen = 0u64;
            let mut edit = |p: &mut crate::output::las::PointEdit<'_>| -> Result<()> {
                seen += 1;
                let (x, y, _) = p.xyz();
                if tile_of(x, y, self.tile) != (t.tx, t.ty) {
                    p.skip();
                    return Ok(());
                }
                let c = classified.class_of(k, p.index())?.ok_or_else(|| {
                    Error::Internal(format!(
                        "task {i}: point {} of {} ({x}, {y}) lies in the tile but was not \
                         classified",
                        p.index(),
                        f.path.display()
                    ))
                })?;
                p.set_classification(c);
                Ok(())
            };
            // Only the chunks that meet the tile, for a file the plan indexed: their points.
            let meet: Option<Vec<(u64, u64)>> = match f.indexed {
                true => Some(
                    self.chunk_index(dir, k)?
                        .span_boxes()
                        .filter(|(_, _, r)| r.is_some_and(|r| overlaps(&r, &near)))
                        .map(|(first, n, _)| (first, first + n))
                        .collect(),
                ),
                false => None,
            };
            let keep = |first: u64, n: u64| {
                meet.as_ref()
                    .is_none_or(|m| m.iter().any(|&(a, b)| a < first + n && first < b))
            };
            let s = crate::output::las::rewrite_points_in(&f.path, &out, &keep, &mut edit)?;
            decoded += seen;
            if s.points == 0 {
                dir.remove(&out)?;
                continue;
            }
            points += s.points;
            outputs.push((POINTS.to_string(), out));
        }
        let status = if outputs.is_empty() { "empty" } else { "done" };
        Ok(TaskRecord {
            index: i,
            status: status.into(),
            buffer: 0.0,
            runs: 1,
            points,
            decoded,
            stored: 0,
            triangles: 0,
            inside_uncounted: false,
            seconds: 0.0,
            peak_memory: None,
            outputs,
            plan: String::new(),
            bytes: Vec::new(),
            warnings: Vec::new(),
            volume: None,
            extent: None,
            subtiles: classified.summary().blocks,
        })
    }
}

/// What [`merge_points`] wrote.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PointsMergeSummary {
    /// The output: a `.vpc` or a LAS/LAZ file.
    pub path: PathBuf,
    /// The tiles' files (the items of a VPC, the files joined into one).
    pub tiles: usize,
    /// Points (every point of the plan's files, once).
    pub points: u64,
    /// Bytes written.
    pub bytes: u64,
}

/// Each task's tiles count in their headers the points its record says it wrote: a tile whose
/// header says otherwise (damaged, replaced, or written by a build that miscounted) would
/// make a merge that leaves points out while its totals look right.
///
/// # Errors
/// [`Error::Format`] naming the tile; the headers' read errors.
fn check_tile_counts(records: &[TaskRecord]) -> Result<()> {
    for r in records {
        let mut counted = 0;
        let mut last = None;
        for (_, p) in r.outputs.iter().filter(|(n, _)| n == POINTS) {
            counted += FileInfo::read(p)?.point_count;
            last = Some(p.clone());
        }
        if let Some(path) = last.filter(|_| counted != r.points) {
            return Err(Error::Format {
                path,
                message: format!(
                    "task {}'s tiles count {counted} points in their headers, but the task \
                     wrote {}: run it again (`sweeptin run PLAN --task {}`)",
                    r.index, r.points, r.index
                ),
            });
        }
    }
    Ok(())
}

/// Merges the tiles of a ground plan whose tasks all finished (`records`, in task order) into
/// `out`: `.vpc` a virtual point cloud referencing the tiles where they are (in a local plan
/// directory by paths relative to the `.vpc`: keep the directory, or merge into one file; on S3
/// by their `s3://` URLs), `.laz`/`.las` one file (decoded and compressed `batch_bytes` of
/// records at a time: a share of the merge's `--mem`).
///
/// # Errors
/// [`Error::Options`] for another extension, and when the tiles cannot make one file
/// (point formats, extra bytes, versions, GPS time types or scales that differ: merge into a
/// `.vpc`); [`Error::Format`] naming a tile whose header miscounts its task's points;
/// [`Error::Format`] naming `plan.json` when the tiles do not hold every point of the files
/// once; the writers' errors.
pub(super) fn merge_points(
    plan: &Plan,
    dir: &PlanDir,
    records: &[TaskRecord],
    out: &Path,
    batch_bytes: u64,
) -> Result<PointsMergeSummary> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("vpc" | "laz" | "las")) {
        return Err(Error::Options(format!(
            "{}: a ground plan merges into a virtual point cloud (OUT.vpc: the tiles, where they \
             are) or one point file (OUT.laz or OUT.las)",
            out.display()
        )));
    }
    crate::output::las::check_output_target(out, &plan.read_files())?;
    crate::output::las::refuse_plain_copc(out, "a ground plan's merge")?;
    let tiles: Vec<PathBuf> = records
        .iter()
        .flat_map(|r| r.outputs.iter().filter(|(n, _)| n == POINTS))
        .map(|(_, p)| p.clone())
        .collect();
    let written: u64 = records.iter().map(|r| r.points).sum();
    let planned: u64 = plan.files.iter().map(|f| f.points).sum();
    if written != planned {
        return Err(Error::Format {
            path: dir.join("plan.json"),
            message: format!(
                "its tasks wrote {written} points, but the files' headers count {planned}: \
                 points lie outside their file's header box (no task owns them), or a file \
                 changed; repair the headers (e.g. lasinfo -repair_bb) and make the plan again"
            ),
        });
    }
    check_tile_counts(records)?;
    if tiles.is_empty() {
        return Err(Error::NothingLeft {
            files: vec![dir.join("plan.json")],
            what: "the plan's files hold no point: nothing to merge".into(),
        });
    }
    let bytes = if ext.as_deref() == Some("vpc") {
        let infos = tiles
            .iter()
            .map(FileInfo::read)
            .collect::<Result<Vec<_>>>()?;
        crate::output::vpc::write_vpc(out, &infos)?
    } else {
        let local = tiles
            .iter()
            .map(|p| dir.local(p))
            .collect::<Result<Vec<_>>>()?;
        let paths: Vec<PathBuf> = local.iter().map(|l| l.path.clone()).collect();
        let s =
            crate::output::las::join_points_within(&paths, out, &mut |_, _| Ok(()), batch_bytes)
                .map_err(|e| match e {
                    Error::Options(m) => Error::Options(format!(
                        "{m}: the plan's input files differ, so their points make no one file \
                     unchanged; merge into a virtual point cloud instead (-o OUT.vpc)"
                    )),
                    e => e,
                })?;
        s.bytes
    };
    Ok(PointsMergeSummary {
        path: out.to_path_buf(),
        tiles: tiles.len(),
        points: written,
        bytes,
    })
}
