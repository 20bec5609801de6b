//! What a batch engine tells a task: its index in a job array.

use crate::error::{Error, Result};

/// The task index a batch engine gives: `SLURM_ARRAY_TASK_ID`, `JOB_COMPLETION_INDEX`
/// (Kubernetes Indexed Job), `AWS_BATCH_JOB_ARRAY_INDEX`, `PBS_ARRAY_INDEX` (0-based) or
/// `SGE_TASK_ID` (Grid Engine counts from 1: task 1 is the plan's task 0), the first one set.
///
/// # Errors
/// [`Error::Options`] naming the variable when its value is not a task number.
pub fn task_from_env() -> Result<Option<usize>> {
    for (var, base) in [
        ("SLURM_ARRAY_TASK_ID", 0),
        ("JOB_COMPLETION_INDEX", 0),
        ("AWS_BATCH_JOB_ARRAY_INDEX", 0),
        ("PBS_ARRAY_INDEX", 0),
        ("SGE_TASK_ID", 1),
    ] {
        let Ok(v) = std::env::var(var) else {
            continue;
        };
        return match v
            .trim()
            .parse::<usize>()
            .ok()
            .and_then(|i| i.checked_sub(base))
        {
            Some(i) => Ok(Some(i)),
            None => Err(Error::Options(format!(
                "{var}={v:?} is not a task number (counted from {base})"
            ))),
        };
    }
    Ok(None)
}
