//! The report of a night's job ([`report`], `sweeptin report`): every task's state read from its
//! records — done, empty, failed (`tiles/task_<i>.failed.json`, [`TaskFailure`], written by a
//! task that fails) or not run — with totals and throughput, as a typed summary ([`Report`],
//! the `--json` of the command) and as one static HTML page ([`html`]): an SVG map of the
//! tiles coloured by state, a hover title per tile, the overview of a DEM's mosaic (a small
//! hillshade, [`Overview`], embedded as a `data:` URI) and the failed tasks with their messages
//! and the command that runs each again. Every string from a record is escaped.

pub use super::overview::Overview;
use super::{Plan, TaskRecord};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What a task that failed records in `tiles/task_<i>.failed.json` (removed when it runs
/// again): why, for the report. A task killed by a signal records nothing itself; `run --all`
/// records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskFailure {
    /// The task.
    pub index: usize,
    /// The [`Plan::id`] of the plan it ran under.
    pub plan: String,
    /// The error, as `run` printed it.
    pub message: String,
    /// Seconds it ran before failing.
    pub seconds: f64,
}

impl Plan {
    /// Where task `i` records that it failed.
    pub fn failure_marker(&self, dir: &super::PlanDir, i: usize) -> PathBuf {
        dir.join("tiles").join(format!("task_{i}.failed.json"))
    }

    /// Records that task `i` failed with `message` after `seconds`.
    ///
    /// # Errors
    /// [`Error::Io`] naming the record; [`Error::Options`] for a task that does not exist.
    pub fn record_failure(
        &self,
        dir: &super::PlanDir,
        i: usize,
        message: &str,
        seconds: f64,
    ) -> Result<()> {
        self.task(i)?;
        let f = TaskFailure {
            index: i,
            plan: self.id().to_string(),
            message: message.to_string(),
            seconds,
        };
        let p = self.failure_marker(dir, i);
        let text = serde_json::to_string_pretty(&f).map_err(|e| Error::Internal(e.to_string()))?;
        dir.write(&p, text.as_bytes())
    }

    /// The failure record of task `i` under this plan, if any (one of another plan is none).
    ///
    /// # Errors
    /// [`Error::Format`] for a damaged record.
    pub fn failure(&self, dir: &super::PlanDir, i: usize) -> Result<Option<TaskFailure>> {
        let p = self.failure_marker(dir, i);
        match dir.read_to_string(&p)? {
            Some(t) => {
                let f = serde_json::from_str::<TaskFailure>(&t).map_err(|e| Error::Format {
                    path: p.clone(),
                    message: format!("damaged failure record: {e} (delete it)"),
                })?;
                Ok(Some(f).filter(|f| f.plan == self.id() && f.index == i))
            }
            None => Ok(None),
        }
    }

    /// Removes the failure record of task `i`, if any (the task runs again).
    pub(super) fn forget_failure(&self, dir: &super::PlanDir, i: usize) {
        let _ = dir.remove(&self.failure_marker(dir, i));
    }
}

/// The state of a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TaskState {
    /// Finished with its outputs.
    Done,
    /// Finished with no point or no cell of its own (its part of the mosaic is nodata).
    Empty,
    /// Failed (its failure record), or finished with an output since damaged.
    Failed,
    /// No record: not run yet, or still running.
    NotRun,
}

impl TaskState {
    /// Its name in the page's classes and the JSON.
    pub fn name(self) -> &'static str {
        match self {
            TaskState::Done => "done",
            TaskState::Empty => "empty",
            TaskState::Failed => "failed",
            TaskState::NotRun => "not_run",
        }
    }

    /// Its colour on the map.
    pub fn colour(self) -> &'static str {
        match self {
            TaskState::Done => "#2ca02c",
            TaskState::Empty => "#a0a0a0",
            TaskState::Failed => "#d62728",
            TaskState::NotRun => "#1f5fd6",
        }
    }
}

/// One task in the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TaskReport {
    /// The task.
    pub index: usize,
    /// Its tile `[xmin, ymin, xmax, ymax]`.
    pub bounds: [f64; 4],
    /// Its state.
    pub state: TaskState,
    /// Points triangulated (0 unless finished).
    pub points: u64,
    /// Seconds it ran (finished or failed).
    pub seconds: f64,
    /// Peak resident memory of its process, in bytes, when recorded.
    pub peak_memory: Option<u64>,
    /// The buffer it ended with (finished tasks).
    pub buffer: Option<f64>,
    /// Its runs (more than 1 when the buffer grew).
    pub runs: u32,
    /// Why it failed.
    pub message: Option<String>,
    /// The command that runs it (failed and not run tasks).
    pub rerun: Option<String>,
}

/// What a plan's tasks did ([`report`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The plan file.
    pub plan: PathBuf,
    /// Its product command.
    pub command: String,
    /// Its tile side.
    pub tile: f64,
    /// Tasks in the plan.
    pub tasks: usize,
    /// Tasks done.
    pub done: usize,
    /// Tasks finished empty.
    pub empty: usize,
    /// Tasks failed.
    pub failed: usize,
    /// Tasks not run.
    pub not_run: usize,
    /// Points triangulated by the finished tasks.
    pub points: u64,
    /// Points decoded by them.
    pub decoded: u64,
    /// Points they read from the plan's point store instead (docs/SCALING.md).
    pub stored: u64,
    /// Triangles they own. `None` when a task counted only the triangles it certified (a DEM
    /// alone: [`TaskRecord::inside_uncounted`]).
    pub triangles: Option<u64>,
    /// The sum of every task's seconds (finished and failed): the job's work, not its wall
    /// time (tasks run side by side).
    pub task_seconds: f64,
    /// `points / task_seconds` of the finished tasks.
    pub points_per_second: Option<f64>,
    /// The largest peak memory recorded.
    pub peak_memory: Option<u64>,
    /// Every task, in plan order.
    pub task_list: Vec<TaskReport>,
    /// The overview of the mosaic, drawn from the finished tasks' DEM tiles, or why there is
    /// none.
    pub overview: Overview,
}

/// The report of the plan `plan` (its file) in `dir`, from its tasks' records.
///
/// # Errors
/// [`Error::Format`] for a damaged record.
pub fn report(plan: &Plan, path: &Path, dir: &super::PlanDir) -> Result<Report> {
    let mut r = Report {
        plan: path.to_path_buf(),
        command: plan.command.clone(),
        tile: plan.tile,
        tasks: plan.tiles.len(),
        done: 0,
        empty: 0,
        failed: 0,
        not_run: 0,
        points: 0,
        decoded: 0,
        stored: 0,
        triangles: None,
        task_seconds: 0.0,
        points_per_second: None,
        peak_memory: None,
        task_list: Vec::with_capacity(plan.tiles.len()),
        overview: Overview::default(),
    };
    let mut finished_seconds = 0.0;
    let (mut triangles, mut uncounted) = (0, false);
    let mut dem = Vec::new();
    for t in &plan.tiles {
        let i = t.index;
        let rerun = Some(format!("sweeptin run {} --task {i}", path.display()));
        let mut task = TaskReport {
            index: i,
            bounds: t.bounds,
            state: TaskState::NotRun,
            points: 0,
            seconds: 0.0,
            peak_memory: None,
            buffer: None,
            runs: 0,
            message: None,
            rerun: rerun.clone(),
        };
        if let Some(rec) = plan.record(dir, i)? {
            finished(&mut task, &rec);
            if let Err(e) = plan.check_task_outputs(dir, &rec) {
                task.state = TaskState::Failed;
                task.message = Some(e.to_string());
            } else {
                r.points += rec.points;
                r.decoded += rec.decoded;
                r.stored += rec.stored;
                triangles += rec.triangles;
                uncounted |= rec.inside_uncounted;
                finished_seconds += rec.seconds;
                if let Some((_, p)) = rec.outputs.iter().find(|(n, _)| n == "dem") {
                    dem.push((i, p.clone()));
                }
            }
        } else if let Some(f) = plan.failure(dir, i)? {
            task.state = TaskState::Failed;
            task.seconds = f.seconds;
            task.message = Some(f.message);
        }
        match task.state {
            TaskState::Done => r.done += 1,
            TaskState::Empty => r.empty += 1,
            TaskState::Failed => r.failed += 1,
            TaskState::NotRun => r.not_run += 1,
        }
        r.task_seconds += task.seconds;
        r.peak_memory = r.peak_memory.max(task.peak_memory);
        r.task_list.push(task);
    }
    r.triangles = (!uncounted).then_some(triangles);
    r.points_per_second = (finished_seconds > 0.0).then(|| r.points as f64 / finished_seconds);
    r.overview = super::overview::overview(plan, dir, &dem);
    Ok(r)
}

fn finished(task: &mut TaskReport, rec: &TaskRecord) {
    task.state = if rec.status == "empty" {
        TaskState::Empty
    } else {
        TaskState::Done
    };
    task.points = rec.points;
    task.seconds = rec.seconds;
    task.peak_memory = rec.peak_memory;
    task.buffer = Some(rec.buffer);
    task.runs = rec.runs;
    task.rerun = None;
}

fn mib(b: Option<u64>) -> String {
    b.map_or("not recorded".into(), |b| {
        format!("{:.1} MiB", b as f64 / 1048576.0)
    })
}

/// Width of the map in the page, in pixels.
const MAP_WIDTH: f64 = 720.0;

/// The report as one static HTML page (no script, nothing fetched).
pub fn html(r: &Report) -> String {
    let mut h = String::new();
    let title = format!("sweeptin report: {}", r.plan.display());
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n\
         <style>body{{font-family:sans-serif;margin:1em}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}\
         svg rect{{stroke:#fff;stroke-width:0.5}}",
        crate::output::escape_markup(&title)
    );
    for s in [
        TaskState::Done,
        TaskState::Empty,
        TaskState::Failed,
        TaskState::NotRun,
    ] {
        let _ = write!(h, " .{}{{fill:{}}}", s.name(), s.colour());
    }
    let _ = writeln!(
        h,
        "</style></head><body>\n<h1>{}</h1>",
        crate::output::escape_markup(&title)
    );
    let rate = r
        .points_per_second
        .map_or("not recorded".into(), |p| format!("{p:.0}"));
    let _ = writeln!(
        h,
        "<table><tr><th>command</th><td>{}</td></tr><tr><th>tasks</th><td>{}</td></tr>\
         <tr><th>done / empty / failed / not run</th><td>{} / {} / {} / {}</td></tr>\
         <tr><th>points</th><td>{}</td></tr><tr><th>triangles</th><td>{}</td></tr>\
         <tr><th>task seconds (sum; not wall time)</th><td>{:.2}</td></tr>\
         <tr><th>points per task second</th><td>{}</td></tr>\
         <tr><th>largest peak memory</th><td>{}</td></tr></table>",
        crate::output::escape_markup(&r.command),
        r.tasks,
        r.done,
        r.empty,
        r.failed,
        r.not_run,
        r.points,
        r.triangles.map_or(
            "not counted (a DEM's tasks count the triangles they certify)".into(),
            |t| t.to_string()
        ),
        r.task_seconds,
        rate,
        mib(r.peak_memory)
    );
    map(&mut h, r);
    overview(&mut h, r);
    failures(&mut h, r);
    h.push_str("</body></html>\n");
    h
}

/// The tiles' extent and the map's pixels per unit; none without tasks.
fn frame(r: &Report) -> Option<([f64; 4], f64)> {
    let mut b = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
    for t in &r.task_list {
        b = [
            b[0].min(t.bounds[0]),
            b[1].min(t.bounds[1]),
            b[2].max(t.bounds[2]),
            b[3].max(t.bounds[3]),
        ];
    }
    let scale = MAP_WIDTH / (b[2] - b[0]).max(b[3] - b[1]).max(f64::MIN_POSITIVE);
    (!r.task_list.is_empty()).then_some((b, scale))
}

/// The SVG map: one rect per task, y up.
fn map(h: &mut String, r: &Report) {
    let Some((b, scale)) = frame(r) else {
        return;
    };
    let (w, ht) = ((b[2] - b[0]) * scale, (b[3] - b[1]) * scale);
    let _ = writeln!(
        h,
        "<h2>Tiles</h2><p>{}</p>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" \
         height=\"{ht:.0}\" viewBox=\"0 0 {w:.3} {ht:.3}\">",
        [
            TaskState::Done,
            TaskState::Empty,
            TaskState::Failed,
            TaskState::NotRun
        ]
        .map(|s| format!(
            "<span style=\"color:{}\">&#9632;</span> {}",
            s.colour(),
            s.name().replace('_', " ")
        ))
        .join(" &nbsp; ")
    );
    for t in &r.task_list {
        let x = (t.bounds[0] - b[0]) * scale;
        let y = (b[3] - t.bounds[3]) * scale;
        let tw = (t.bounds[2] - t.bounds[0]) * scale;
        let th = (t.bounds[3] - t.bounds[1]) * scale;
        let mut tip = format!(
            "task {}: {}; {} points, {:.2} s, peak memory {}, runs {}",
            t.index,
            t.state.name().replace('_', " "),
            t.points,
            t.seconds,
            mib(t.peak_memory),
            t.runs
        );
        if let Some(bu) = t.buffer {
            let _ = write!(tip, ", buffer {bu}");
        }
        if let Some(m) = &t.message {
            let _ = write!(tip, "\n{m}");
        }
        let _ = writeln!(
            h,
            "<rect class=\"{}\" fill=\"{}\" data-task=\"{}\" x=\"{x:.3}\" y=\"{y:.3}\" \
             width=\"{tw:.3}\" height=\"{th:.3}\"><title>{}</title></rect>",
            t.state.name(),
            t.state.colour(),
            t.index,
            crate::output::escape_markup(&tip)
        );
    }
    h.push_str("</svg>\n");
}

/// The overview of the mosaic under the map, on the map's scale, or why there is none.
fn overview(h: &mut String, r: &Report) {
    let o = &r.overview;
    let size = o
        .bounds
        .zip(frame(r))
        .map(|(ob, (_, scale))| ((ob[2] - ob[0]) * scale, (ob[3] - ob[1]) * scale));
    match size {
        Some((w, ht)) if o.drawn => {
            let _ = writeln!(
                h,
                "<h2>Overview</h2><p>{}</p>\n<img class=\"overview\" alt=\"hillshade of the \
                 mosaic\" width=\"{w:.0}\" height=\"{ht:.0}\" src=\"{}\">",
                crate::output::escape_markup(&o.note),
                o.data_uri()
            );
        }
        _ => {
            let _ = writeln!(
                h,
                "<h2>Overview</h2><p class=\"no-overview\">No overview: {}.</p>",
                crate::output::escape_markup(&o.note)
            );
        }
    }
}

/// The table of failed tasks, with the command that runs each again.
fn failures(h: &mut String, r: &Report) {
    let failed: Vec<&TaskReport> = r
        .task_list
        .iter()
        .filter(|t| t.state == TaskState::Failed)
        .collect();
    if failed.is_empty() {
        h.push_str("<h2>Failed tasks</h2><p>None.</p>\n");
        return;
    }
    h.push_str(
        "<h2>Failed tasks</h2><table><tr><th>task</th><th>message</th><th>run it again</th></tr>\n",
    );
    for t in failed {
        let _ = writeln!(
            h,
            "<tr class=\"failed-task\"><td>{}</td><td>{}</td><td><code>{}</code></td></tr>",
            t.index,
            crate::output::escape_markup(t.message.as_deref().unwrap_or("")),
            crate::output::escape_markup(t.rerun.as_deref().unwrap_or(""))
        );
    }
    h.push_str("</table>\n");
}

/// Writes the page of `r` to `out` (atomically), refusing a name that is not a regular file
/// and the plan's own files in `dir`.
///
/// # Errors
/// [`Error::Options`] for such a name; [`Error::Io`].
pub fn write_html(r: &Report, dir: &super::PlanDir, out: &Path) -> Result<()> {
    dir.outside("the report", out)?;
    let inputs = [dir.join("plan.json")];
    if inputs.iter().any(|p| same_file(p, out)) {
        return Err(Error::Options(format!(
            "the report {}: that is the plan itself; write the report elsewhere",
            out.display()
        )));
    }
    if let Ok(m) = std::fs::symlink_metadata(out)
        && !m.file_type().is_file()
    {
        return Err(Error::Options(format!(
            "the report {}: {} is there; the report replaces only a regular file (give              another name)",
            out.display(),
            if m.file_type().is_symlink() {
                "a symbolic link"
            } else {
                "not a regular file"
            }
        )));
    }
    use std::io::Write as _;
    let mut f = crate::output::AtomicFile::create(out)?;
    f.write_all(html(r).as_bytes())
        .map_err(|e| Error::write(out, e))?;
    f.commit()?;
    Ok(())
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}
