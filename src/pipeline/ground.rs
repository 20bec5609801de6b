//! `--ground`: the ground found on the fly. The inputs' points are classified by the ground
//! filter ([`crate::ground::classify_files`], into a [`crate::ground::ClassStore`], no point
//! written), and the
//! run then reads every point with the class `sweeptin ground` would write for it
//! ([`crate::input::las::Filter::classes_from`]), keeping class 2 unless `--class` says
//! otherwise. So `dem raw.laz --ground` triangulates exactly the points of `ground raw.laz -o
//! g.laz && dem g.laz --class 2`, and makes the same DEM byte for byte.

use super::config::Source;
use super::{Input, RunOptions};
use crate::error::{Error, Result};
use crate::ground::{GroundParams, GroundSummary};
use crate::input::las::ClassesFrom;
use crate::output::las::{CopcOutput, is_copc_path, rewrite_points};
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
        return Err(Error::Options(TASK_CLASSIFIES_ITS_AREA.into()));
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

/// Why a run of a task scope ([`crate::TaskScope`]) does not classify its files itself.
const TASK_CLASSIFIES_ITS_AREA: &str = "--ground in a plan's task: its files are only those near \
     its tile, whose ground is not one run's; a plan's tasks classify their own area \
     (`sweeptin plan dem … --ground`, `Job::ground`, `Plan::run_task`)";

/// A pipe, a FIFO or a device: read once, so not twice.
fn is_stream(p: &std::path::Path) -> bool {
    std::fs::metadata(p).is_ok_and(|m| !m.is_file())
}

/// What [`ground_files`] did: the classification, and each output written.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GroundFiles {
    /// The classification.
    #[serde(flatten)]
    pub ground: GroundSummary,
    /// Each output, in the order of the inputs.
    pub files: Vec<crate::output::las::RewriteSummary>,
}

/// `sweeptin ground`: classifies the points of `inputs` together (a block's buffer reaches
/// into the neighbouring file) and writes each input to its output with the new classes,
/// every other attribute kept ([`crate::output::las::rewrite_points`]; an output named
/// `.copc.laz` is a COPC file, its points in the octree's order: [`CopcOutput`]), within
/// `mem` bytes, temporary files under `tmp`. The outputs are checked before any work:
/// distinct, never an input, regular files (or new), COPC only of what it can keep.
///
/// # Errors
/// [`Error::Options`] when inputs and outputs do not pair up; the output checks' (those of
/// [`CopcOutput::check`] too); those of [`crate::ground::classify_files`] and of the writer.
/// An output appears only complete.
pub fn ground_files(
    inputs: &[std::path::PathBuf],
    outputs: &[std::path::PathBuf],
    params: &GroundParams,
    mem: u64,
    tmp: &std::path::Path,
    progress: &mut dyn FnMut(&str, u64, u64),
) -> Result<GroundFiles> {
    params.check()?;
    if inputs.is_empty() {
        return Err(Error::NoInput);
    }
    if inputs.len() != outputs.len() {
        return Err(Error::Options(format!(
            "ground: {} inputs but {} outputs (one output per input)",
            inputs.len(),
            outputs.len()
        )));
    }
    let named: Vec<(String, &std::path::Path)> = outputs
        .iter()
        .enumerate()
        .map(|(k, o)| (format!("output {}", k + 1), o.as_path()))
        .collect();
    let named: Vec<(&str, &std::path::Path)> =
        named.iter().map(|(f, o)| (f.as_str(), *o)).collect();
    crate::output::distinct_outputs(&named, inputs, "ground")?;
    // As every other job: a budget the address space cannot hold, or a temporary directory
    // that is not one, refused before the work (an allocation aborted the process).
    crate::limits::check_address_space(
        mem,
        rayon::current_num_threads(),
        "the classification's memory budget (--mem)",
    )?;
    super::config::check_tmp_dir(tmp)?;
    let mut copc = Vec::with_capacity(outputs.len());
    for (input, o) in inputs.iter().zip(outputs) {
        crate::output::check_output(o)?;
        crate::output::las::check_point_output(o, inputs)?;
        copc.push(match is_copc_path(o) {
            true => Some(CopcOutput::check(input, o)?),
            false => None,
        });
    }
    let (mut classes, ground) = crate::ground::classify_files(inputs, params, mem, tmp, progress)?;
    let mut files = Vec::with_capacity(inputs.len());
    let mut base = 0u64;
    for ((input, output), copc) in inputs.iter().zip(outputs).zip(&copc) {
        progress(&format!("writing {}", output.display()), 0, 0);
        let count = crate::input::las::FileInfo::read(input)?.point_count;
        let mut edit = |p: &mut crate::output::las::PointEdit<'_>| -> Result<()> {
            let c = classes.get(base + p.index())?;
            p.set_classification(c);
            Ok(())
        };
        files.push(match copc {
            Some(c) => c.write(output, tmp, |las| rewrite_points(input, las, &mut edit))?,
            None => rewrite_points(input, output, &mut edit)?,
        });
        base += count;
    }
    Ok(GroundFiles { ground, files })
}
