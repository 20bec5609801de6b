//! `--ground`: the ground found on the fly. The inputs' points are classified by the ground
//! filter ([`crate::ground::classify_files`], into a [`ClassStore`], no point written), and the
//! run then reads every point with the class `sweeptin ground` would write for it
//! ([`crate::input::las::Filter::classes_from`]), keeping class 2 unless `--class` says
//! otherwise. So `dem raw.laz --ground` triangulates exactly the points of `ground raw.laz -o
//! g.laz && dem g.laz --class 2`, and makes the same DEM byte for byte.

use super::config::Source;
use super::{Input, RunOptions};
use crate::error::{Error, Result};
use crate::ground::{GroundParams, GroundSummary};
use crate::input::las::ClassesFrom;
use std::sync::Arc;

/// The class of the ground the filter finds.
pub const GROUND_CLASS: u8 = 2;

/// What a run with `--ground` triangulates and how: the input reading the filter's classes,
/// the options left for the run.
#[derive(Debug)]
pub struct Grounded {
    /// The input: its filter reads the ground filter's classes (`classes` 2 unless given).
    pub input: Input,
    /// The run's options: `--mem` less what the classes hold in memory.
    pub options: RunOptions,
    /// What the classification did.
    pub summary: GroundSummary,
}

/// Classifies the points of `input` (all of them: a box or the other filters select among the
/// classified points afterwards, as they would in the file `sweeptin ground` writes) with
/// `params` within `options.mem`, and gives the input that reads them with their new classes.
///
/// # Errors
/// [`Error::Options`] for inputs that are not LAS/LAZ/COPC points or a plan's task (its reader
/// sees only some of the files); [`Error::NothingLeft`] when the filter finds no ground and
/// the class filter keeps only ground; those of [`crate::ground::classify_files`].
pub fn ground_input(
    input: &Input,
    params: &GroundParams,
    options: &RunOptions,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<Grounded> {
    params.check()?;
    if Source::of(&input.paths)? != Source::Lidar || input.paths.iter().any(|p| is_stream(p)) {
        return Err(Error::Options(
            "--ground classifies LAS/LAZ/COPC points (or a .vpc of them) given as files: it \
             reads them twice, so not XYZ text, a .stin mesh or a pipe"
                .into(),
        ));
    }
    if options.tiles.as_ref().is_some_and(|t| t.scope.is_some()) {
        return Err(Error::Options(PLAN_REFUSES_GROUND.into()));
    }
    let tmp = options.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let (store, summary) =
        crate::ground::classify_files(&input.paths, params, options.mem, &tmp, progress)?;
    let only_ground = input
        .filter
        .classes
        .as_ref()
        .is_none_or(|c| c.iter().all(|&c| c == GROUND_CLASS));
    if summary.ground == 0 && only_ground {
        return Err(Error::NothingLeft {
            files: input.paths.clone(),
            what: format!(
                "--ground found no ground among {} point(s) (none, or all withheld or noise): \
                 nothing to triangulate",
                summary.points
            ),
        });
    }
    let mut run = options.clone();
    // The classes in memory (at most an eighth of `--mem`) stay for the run.
    run.mem = options.mem - store.memory_bytes().min(options.mem / 8);
    let mut input = input.clone();
    input.filter.classes = Some(
        input
            .filter
            .classes
            .take()
            .unwrap_or_else(|| vec![GROUND_CLASS]),
    );
    input.filter.classes_from = Some(ClassesFrom(Arc::new(store) as Arc<_>));
    Ok(Grounded {
        input,
        options: run,
        summary,
    })
}

/// Why a plan does not take `--ground` (yet): the route that does the same.
pub const PLAN_REFUSES_GROUND: &str = "--ground does not run in a plan's tasks yet (each task \
     reads only the files near its tile, and the ground of a block depends on the points 2 \
     steps around it): classify first with `sweeptin ground FILES --odir classified/`, then \
     plan on the classified files with `--class 2`";

/// A pipe, a FIFO or a device: read once, so not twice.
fn is_stream(p: &std::path::Path) -> bool {
    std::fs::metadata(p).is_ok_and(|m| !m.is_file())
}
