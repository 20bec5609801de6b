//! `sweeptin run PLAN --all`: every task of a plan, each in its own child process (`sweeptin run
//! --task I`), so that one failing task does not stop the others; the exit status is the lowest
//! failed task's.

use super::plan::RunArgs;
use anyhow::Context;
use std::time::Instant;
use sweeptin::fmt::count;
use sweeptin::output::interrupt;
use sweeptin::plan::{Plan, PlanDir};

/// The `--json` summary of `run --all` that finished every task (a failure is the error object
/// that names the failed tasks).
#[derive(serde::Serialize)]
struct RunAllSummary {
    /// Tasks run.
    tasks: usize,
    /// Tasks skipped as already finished (`--resume`).
    skipped: usize,
    /// Wall-clock seconds.
    seconds: f64,
}

/// How a task's process that failed ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Ended {
    /// With this exit status (5 when it could not be waited for).
    Code(i32),
    /// Killed by this signal (the out-of-memory killer's SIGKILL: it exited 5 "a bug", the
    /// signal unnamed).
    Signal(i32),
}

/// How the process of `status` ended (`None`: it could not be waited for).
fn ended(status: Option<std::process::ExitStatus>) -> Ended {
    #[cfg(unix)]
    if let Some(s) = status.and_then(|s| std::os::unix::process::ExitStatusExt::signal(&s)) {
        return Ended::Signal(s);
    }
    Ended::Code(status.and_then(|s| s.code()).unwrap_or(5))
}

/// Set on the tasks `run --all` starts: its process id, so that a task ends with it.
pub const PARENT_ENV: &str = "SWEEPTIN_RUN_ALL_PID";

/// In a task started by `run --all` ([`PARENT_ENV`]): asks the kernel for a SIGTERM when that
/// process dies (killed with SIGKILL, it cannot pass an interruption on, and its tasks ran
/// on, orphaned), and refuses to start when it is already gone.
///
/// # Errors
/// `run --all` is gone.
pub fn end_with_parent(task: usize) -> anyhow::Result<()> {
    let Some(parent) = std::env::var(PARENT_ENV)
        .ok()
        .and_then(|v| v.parse::<i32>().ok())
    else {
        return Ok(());
    };
    #[cfg(target_os = "linux")]
    {
        use rustix::process::{Pid, Signal, getppid, set_parent_process_death_signal};
        let _ = set_parent_process_death_signal(Some(Signal::TERM));
        if Pid::as_raw(getppid()) != parent {
            anyhow::bail!(
                "task {task}: {PARENT_ENV} names process {parent}, which is not its parent: the \
                 `sweeptin run --all` that started it is gone (or the variable was set by hand)"
            );
        }
    }
    Ok(())
}

/// `--all`: every task (not yet finished, with --resume), --jobs at a time, each in its own
/// process so that one failing task does not stop the others.
pub fn run_all(plan: &Plan, dir: &PlanDir, args: &RunArgs) -> anyhow::Result<()> {
    let exe = std::env::current_exe().context("cannot find the sweeptin executable")?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = args.jobs.max(1);
    let threads = args.threads.unwrap_or((cores / jobs).max(1));
    let mut todo = Vec::new();
    for t in &plan.tiles {
        if args.resume && plan.finished(dir, t.index) {
            continue;
        }
        todo.push(t.index);
    }
    let start = Instant::now();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let failed = std::sync::Mutex::new(Vec::new());
    let done = std::sync::atomic::AtomicUsize::new(0);
    let points = std::sync::atomic::AtomicU64::new(0);
    let bar = job_bar(todo.len(), args.quiet);
    std::thread::scope(|s| {
        for _ in 0..jobs.min(todo.len()) {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&i) = todo.get(k) else { break };
                    let mut command = std::process::Command::new(&exe);
                    command
                        .arg("run")
                        .arg(&args.plan)
                        .args(["--task", &i.to_string(), "--quiet"])
                        .args(["--threads", &threads.to_string()])
                        .env(PARENT_ENV, std::process::id().to_string());
                    // An interruption (Ctrl-C, SIGTERM) passes on to the tasks running, and
                    // waits for them; none starts after it.
                    let status = match interrupt::spawn_child(&mut command) {
                        Ok(Some(child)) => interrupt::wait_child(child),
                        Ok(None) => break,
                        Err(e) => Err(e),
                    };
                    let ok = matches!(&status, Ok(s) if s.success());
                    // Counted under the lock that records the failure, so that the line says
                    // how many of the tasks done so far failed ("8/8 tasks finished" was
                    // printed when 3 had failed).
                    let mut f = failed.lock().unwrap_or_else(|e| e.into_inner());
                    if !ok {
                        let how = ended(status.ok());
                        f.push((i, how));
                        // A killed task records nothing itself: the report names the signal.
                        if let Ended::Signal(sig) = how {
                            let _ = plan.record_failure(
                                dir,
                                i,
                                &sweeptin::error::task_killed(i, sig),
                                0.0,
                            );
                        }
                    }
                    let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    let task_points = match plan.record(dir, i) {
                        Ok(Some(r)) if ok => r.points,
                        _ => 0,
                    };
                    let p = points.fetch_add(task_points, std::sync::atomic::Ordering::Relaxed)
                        + task_points;
                    if !args.quiet && !interrupt::interrupted() {
                        let pace = Pace {
                            done: n,
                            total: todo.len(),
                            failed: f.len(),
                            points: p,
                            seconds: start.elapsed().as_secs_f64(),
                        };
                        let what = if ok { "done" } else { "failed" };
                        if bar.is_hidden() {
                            eprintln!("sweeptin: task {i} {what}: {}", pace.line());
                        } else {
                            if !ok {
                                bar.println(format!("sweeptin: task {i} failed"));
                            }
                            bar.set_position(n as u64);
                            bar.set_message(pace.rate());
                        }
                    }
                    drop(f);
                }
            });
        }
    });
    bar.finish_and_clear();
    interrupt::await_interruption();
    let mut failed = failed.into_inner().unwrap_or_else(|e| e.into_inner());
    failed.sort_unstable();
    if let Some(&(_, first)) = failed.first() {
        use sweeptin::ErrorKind;
        return Err(sweeptin::Error::TasksFailed {
            failed: failed.iter().map(|&(i, _)| i).collect(),
            killed: failed
                .iter()
                .filter_map(|&(i, e)| match e {
                    Ended::Signal(s) => Some((i, s)),
                    Ended::Code(_) => None,
                })
                .collect(),
            total: todo.len(),
            kind: match first {
                Ended::Code(c) => ErrorKind::from_exit_code(c).unwrap_or(ErrorKind::Internal),
                Ended::Signal(s) => ErrorKind::from_signal(s),
            },
        }
        .into());
    }
    if args.json {
        let s = RunAllSummary {
            tasks: todo.len(),
            skipped: plan.tiles.len() - todo.len(),
            seconds: start.elapsed().as_secs_f64(),
        };
        println!("{}", serde_json::to_string(&s)?);
    } else if !args.quiet {
        eprintln!(
            "sweeptin: {} tasks in {:.2} s; next: sweeptin merge {} -o OUT",
            count(todo.len() as u64),
            start.elapsed().as_secs_f64(),
            args.plan.display()
        );
    }
    Ok(())
}

/// One bar for the whole job on a terminal (tasks done, points a second, the time left); hidden
/// otherwise, where a line a task goes to the log instead.
fn job_bar(tasks: usize, quiet: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if quiet || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(tasks as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "sweeptin: {bar:30} {pos}/{len} tasks · {msg} · {elapsed} (about {eta} left)",
    ) {
        bar.set_style(style);
    }
    bar
}

/// How far `run --all` has come.
struct Pace {
    done: usize,
    total: usize,
    failed: usize,
    /// Points triangulated by the tasks that finished.
    points: u64,
    seconds: f64,
}

impl Pace {
    /// Points a second and failures so far.
    fn rate(&self) -> String {
        let rate = self.points as f64 / self.seconds.max(1e-9);
        let failures = match self.failed {
            0 => String::new(),
            k => format!(", {} failed", count(k as u64)),
        };
        format!("{:.2} M points/s{failures}", rate / 1e6)
    }

    /// The line a task's end prints to a log: `3 of 12 tasks ran, 1 failed; 1.20 M points/s,
    /// about 40 s left`.
    fn line(&self) -> String {
        let failures = match self.failed {
            0 => String::new(),
            k => format!(", {} failed", count(k as u64)),
        };
        let left = self.seconds / self.done.max(1) as f64 * (self.total - self.done) as f64;
        format!(
            "{} of {} tasks ran{failures}; {:.2} M points/s, about {left:.0} s left",
            count(self.done as u64),
            count(self.total as u64),
            self.points as f64 / self.seconds.max(1e-9) / 1e6,
        )
    }
}
