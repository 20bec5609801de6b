//! `sweeptin report`: what a plan's tasks did (`plan::report`), as a static HTML page and/or a
//! JSON summary.

use anyhow::Context;
use std::path::PathBuf;
use sweeptin::plan::Plan;
use sweeptin::plan::report::{report, write_html};

/// Arguments of `sweeptin report`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  sweeptin report job/plan.json -o night.html\n  \
                        sweeptin report job/plan.json --json"
)]
pub struct Args {
    /// The plan (DIR/plan.json) whose tasks to report.
    #[arg(value_name = "PLAN")]
    pub plan: PathBuf,
    /// The HTML page to write (one static file: no script, nothing fetched).
    #[arg(short, long, value_name = "HTML", required_unless_present = "json")]
    pub output: Option<PathBuf>,
    /// Print the report as JSON on stdout (counts, totals, every task's state).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let plan = Plan::load(&args.plan)?;
    let dir = Plan::dir_of(&args.plan)?;
    let r = report(&plan, &args.plan, &dir)?;
    if let Some(out) = &args.output {
        write_html(&r, &dir, out)
            .with_context(|| format!("cannot write the report {}", out.display()))?;
    }
    if args.json {
        println!("{}", serde_json::to_string(&r)?);
    } else {
        eprintln!(
            "sweeptin: {} tasks: {} done, {} empty, {} failed, {} not run",
            r.tasks, r.done, r.empty, r.failed, r.not_run
        );
    }
    Ok(())
}
