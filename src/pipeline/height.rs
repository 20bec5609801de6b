//! `sweeptin height`: the height of every point above the ground TIN, written back into the
//! points (issue 42, item 3).
//!
//! 1. Every point of every input is sorted by `y` with the external sort (half of `--mem`).
//! 2. The ground TIN — the exact TIN of the ground points ([`Ground`]) — runs through the usual
//!    engine (tiles or sweep, the other half of `--mem`) into a
//!    [`SampleSink::for_points`](crate::products::sample::SampleSink::for_points), which
//!    answers the sorted points as its triangles stream past, exactly as `sweeptin sample`
//!    answers its queries (the same location and plane value: on an edge or vertex from that
//!    edge or vertex alone). Answers go to a scratch file, 8 bytes a point.
//! 3. Each input is rewritten ([`crate::output::las::rewrite_points_with`]) with
//!    `HeightAboveGround = z − ground(x, y)` as a double in the extra bytes (PDAL's name; PDAL's
//!    `filters.hag_delaunay` makes it a double too), or with z replaced by it (`replace_z`,
//!    lidR's `normalize_height`).
//!
//! **Outside the ground TIN's hull** there is no ground: the point's `HeightAboveGround` is NaN
//! (readers such as `--z-from` skip it), and with `replace_z` its z is kept and it is flagged
//! *withheld* (which every command skips by default), never given a made-up height.
//!
//! Memory is bounded by `--mem` whatever the input size: the sort spills, the sample sink holds
//! the queries near the sweep's level, the writer streams batches.

use super::{Input, LineOptions, RunConfig, RunOptions, RunSummary};
use crate::error::{Error, Result};
use crate::input::las::{FileInfo, Filter, LidarReader};
use crate::output::las::{
    AddedAttribute, RewriteOptions, RewriteSummary, check_point_output, rewrite_points_with,
};
use crate::products::sample::SampleSink;
use crate::sort::external::{ExternalSorter, SortRecord};
use crate::sort::memory::DuplicatePolicy;
use serde::Serialize;
use std::io::{BufReader, Read};
use std::path::PathBuf;

/// The name of the attribute written (PDAL's dimension).
pub const HEIGHT_ATTRIBUTE: &str = "HeightAboveGround";

/// Where the ground comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Ground {
    /// The points already classified with these classes (2, ground, by default).
    Classes(Vec<u8>),
    /// The ground the filter finds in the inputs with these parameters (`--ground`: the
    /// points `sweeptin ground` would write as class 2, [`super::ground::ground_input`]).
    Classify(crate::ground::GroundParams),
}

impl Default for Ground {
    fn default() -> Self {
        Ground::Classes(vec![2])
    }
}

/// A height job: each input rewritten to its output.
#[derive(Clone, Debug, Default)]
pub struct HeightJob {
    /// LAS/LAZ files: one point set for the ground, one output each.
    pub inputs: Vec<PathBuf>,
    /// One output per input (`.laz` compressed, `.las` not; other names are refused).
    pub outputs: Vec<PathBuf>,
    /// The ground.
    pub ground: Ground,
    /// Replace z by the height instead of adding `HeightAboveGround`.
    pub replace_z: bool,
}

/// What a height job did.
#[derive(Clone, Debug, Serialize)]
pub struct HeightSummary {
    /// Points of all inputs.
    pub points: u64,
    /// Ground points in the TIN (after duplicates).
    pub ground_points: u64,
    /// Points outside the ground TIN's hull (no height: NaN, or withheld with `replace_z`).
    pub outside: u64,
    /// Each output.
    pub files: Vec<RewriteSummary>,
    /// The ground TIN's run.
    pub ground: RunSummary,
}

/// Runs `job` with `options` (memory, threads, temporary directory, progress).
///
/// # Errors
/// [`Error::Options`] for a job whose inputs and outputs do not pair up, or an output that is
/// an input; [`Error::NothingLeft`] when the inputs hold no ground point (classify them first);
/// the readers', the engine's and the writer's errors. No output is left for a file that
/// failed; outputs already finished stay.
pub fn height(job: &HeightJob, options: &RunOptions) -> Result<HeightSummary> {
    if job.inputs.is_empty() {
        return Err(Error::NoInput);
    }
    if job.inputs.len() != job.outputs.len() {
        return Err(Error::Options(format!(
            "height: {} inputs but {} outputs (one output per input)",
            job.inputs.len(),
            job.outputs.len()
        )));
    }
    let outputs: Vec<(String, &std::path::Path)> = job
        .outputs
        .iter()
        .enumerate()
        .map(|(k, o)| (format!("output {}", k + 1), o.as_path()))
        .collect();
    let named: Vec<(&str, &std::path::Path)> =
        outputs.iter().map(|(f, o)| (f.as_str(), *o)).collect();
    crate::output::distinct_outputs(&named, &job.inputs, "height")?;
    for o in &job.outputs {
        check_point_output(o, &job.inputs)?;
        crate::output::las::refuse_plain_copc(o, "height")?;
    }
    let mut counts = Vec::with_capacity(job.inputs.len());
    for i in &job.inputs {
        counts.push(FileInfo::read(i)?.point_count);
    }
    let total: u64 = counts.iter().sum();
    let say = |m: &str| {
        if options.progress {
            eprintln!("sweeptin: height: {m}");
        }
    };
    // The ground's points: those of the classes, or those the filter finds (classified first,
    // within the whole of `--mem`; the classes then wait in what is left).
    let input = Input {
        paths: job.inputs.clone(),
        filter: Filter::default(),
        duplicates: DuplicatePolicy::First,
        lines: LineOptions::default(),
    };
    let (input, options) = match &job.ground {
        Ground::Classes(classes) => {
            let mut input = input;
            input.filter.classes = Some(classes.clone());
            (input, options.clone())
        }
        Ground::Classify(params) => {
            say(&format!("classifying the ground of {total} points"));
            let g = super::ground::ground_input(&input, params, options, &mut |_, _, _| {})?;
            (g.input, g.options)
        }
    };
    let options = &options;

    // 1. Every point, sorted by y (the queries).
    say(&format!("sorting {total} points by y"));
    let tmp = options.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let mut sorter = ExternalSorter::<SortRecord>::new(options.mem / 2, &tmp);
    let mut reader = LidarReader::open(&job.inputs, &Filter::keep_all())?;
    let mut chunk = Vec::new();
    while reader.read_chunk(&mut chunk, 1 << 16)? > 0 {
        for p in &chunk {
            sorter.push(SortRecord {
                x: p.x,
                y: p.y,
                z: p.z,
                index: p.index,
            })?;
        }
        chunk.clear();
    }
    drop(reader);
    let queries = sorter.finish()?;

    // 2. The ground TIN answers them.
    say("triangulating the ground");
    let mut ground_options = options.clone();
    ground_options.mem = options.mem / 2;
    let config = RunConfig::new(input, ground_options)?;
    let mut sink = SampleSink::for_points(queries, total, &job.outputs[0]);
    let ground = super::run(&config, None, &mut [&mut sink])?;
    let mut answers = BufReader::with_capacity(1 << 16, sink.take_answers()?);
    drop(sink);

    // 3. Each file rewritten with its heights.
    let rewrite = RewriteOptions {
        add: if job.replace_z {
            Vec::new()
        } else {
            vec![AddedAttribute {
                name: HEIGHT_ATTRIBUTE.into(),
                description: "height above the ground TIN".into(),
            }]
        },
    };
    let mut outside = 0;
    let mut files = Vec::with_capacity(job.inputs.len());
    for (input, output) in job.inputs.iter().zip(&job.outputs) {
        say(&format!("writing {}", output.display()));
        let scratch = &job.outputs[0];
        let s = rewrite_points_with(input, output, &rewrite, &mut |p| {
            let mut b = [0u8; 8];
            answers
                .read_exact(&mut b)
                .map_err(|e| Error::write(scratch, e))?;
            let g = f64::from_le_bytes(b);
            let h = p.xyz().2 - g;
            if g.is_nan() {
                outside += 1;
            }
            match (job.replace_z, g.is_nan()) {
                (false, _) => p.set_added(0, h),
                (true, false) => p.set_z(h)?,
                (true, true) => p.set_withheld(),
            }
            Ok(())
        })?;
        files.push(s);
    }
    Ok(HeightSummary {
        points: total,
        ground_points: ground.points_kept.saturating_sub(ground.duplicates),
        outside,
        files,
        ground,
    })
}
