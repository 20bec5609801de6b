//! The library's one error type.
//!
//! Every fallible function in `sweeptin` returns [`Result<T>`]. Variants carry the data a user
//! needs to find the problem: the file, the line or point index, and what is wrong with it.
//! Each error has a [`Error::kind`] (usage, bad input data, output or temporary I/O, internal,
//! interrupted), which the binary turns into its exit status ([`ErrorKind::exit_code`]).

use std::path::PathBuf;

/// `Result` with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in `sweeptin`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A coordinate is NaN or infinite.
    #[error("point {index}: coordinate is not finite (x={x}, y={y}, z={z})")]
    NonFinite {
        /// Index of the point in the input (0-based).
        index: u64,
        /// The point's x.
        x: f64,
        /// The point's y.
        y: f64,
        /// The point's z.
        z: f64,
    },

    /// A coordinate is finite but outside the range in which the exact predicates are exact
    /// (see `geom::predicates::MAX_COORD` and `geom::predicates::MIN_NONZERO_COORD`).
    #[error(
        "point {index}: coordinate {value} is outside the supported range \
         (|v| <= {max:e} and either 0 or |v| >= {min:e}, after removing the local origin)"
    )]
    CoordinateOutOfRange {
        /// Index of the point in the input (0-based).
        index: u64,
        /// The offending value.
        value: f64,
        /// Largest magnitude accepted.
        max: f64,
        /// Smallest non-zero magnitude accepted.
        min: f64,
    },

    /// Fewer than three distinct (x, y) positions: no triangle exists.
    #[error(
        "fewer than 3 distinct points: {distinct} distinct (x, y) position(s) out of {total} point(s)"
    )]
    TooFewPoints {
        /// Distinct (x, y) positions after merging duplicates.
        distinct: u64,
        /// Points given.
        total: u64,
    },

    /// All distinct points lie on one straight line: no triangle exists.
    #[error("all {distinct} distinct points are collinear: no triangle can be formed")]
    AllCollinear {
        /// Distinct (x, y) positions after merging duplicates.
        distinct: u64,
    },

    /// The points span no area: all on one line parallel to an axis, or at one position (a
    /// grid over them, a DEM's, has no cell to give). No triangle exists.
    #[error(
        "the points span no area (x {} .. {}, y {} .. {}): they lie on one line or at one \
         position, so no triangle exists",
        bounds[0],
        bounds[2],
        bounds[1],
        bounds[3]
    )]
    NoArea {
        /// The points' extent `[xmin, ymin, xmax, ymax]`.
        bounds: [f64; 4],
    },

    /// More points than the in-memory core can index with 32-bit ids.
    #[error("too many points for one in-memory triangulation: {count} (at most {max})")]
    TooManyPoints {
        /// Points given.
        count: u64,
        /// The limit.
        max: u64,
    },

    /// Points were handed to the sweep out of (y, x) order or twice.
    #[error(
        "point {index} is out of sweep order: points must arrive sorted by (y, x) and distinct"
    )]
    OutOfOrder {
        /// Index of the offending point in the order it was given.
        index: u64,
    },

    /// Reading an input file failed.
    #[error("{}: {source}{}", path.display(), files_hint(source))]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },

    /// A text file has a line that cannot be read.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: u64,
        /// What is wrong with the line.
        message: String,
    },

    /// A file is not in the format it claims to be, or is damaged.
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },

    /// A mesh cannot be written as asked: unknown format, a limit of the format (such as PLY's
    /// 32-bit vertex indices), or a writer used against its contract.
    #[error("{}: cannot write: {message}", path.display())]
    Output {
        /// The output file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A breakline vertex cannot be used (not finite, or outside the predicates' exact range).
    /// [`crate::breaklines::Lines::clean`] turns it into [`Error::Format`] naming the file.
    #[error("breakline {polyline}, vertex {vertex}: {message}")]
    BadLine {
        /// Index of the polyline in the input (0-based).
        polyline: u64,
        /// Index of the vertex in the polyline (0-based).
        vertex: u64,
        /// What is wrong.
        message: String,
    },

    /// A reader was given no input files.
    #[error("no input files given")]
    NoInput,

    /// Options that cannot be used together.
    #[error("{0}")]
    Options(String),

    /// A mesh failed validation.
    #[error("mesh is not a valid Delaunay triangulation: {0}")]
    Invalid(String),

    /// Quality refinement cannot be done on this input (see `refine`).
    #[error("cannot refine: {0}")]
    Refine(String),

    /// The operation was interrupted (Ctrl-C).
    #[error("interrupted")]
    Interrupted,

    /// A task of a plan read the points up to `buffer` around its tile, and a triangle it owns
    /// needs points farther out: run it again with a wider buffer (`sweeptin run` does so).
    #[error(
        "the task's buffer of {buffer} around its tile is too small for the triangles it owns \
         (a wider buffer is needed)"
    )]
    BufferTooSmall {
        /// The buffer that was read.
        buffer: f64,
        /// A buffer that reads the files the certificates reached (0 when not known).
        reach: f64,
    },

    /// Writing an output, a temporary or a spill file failed (disk full, read-only, permissions),
    /// or it cannot be written where asked (a directory, a block device, a stream for a format
    /// that needs seeking).
    #[error("{}: {source}{}", path.display(), files_hint(source))]
    Write {
        /// The output (or temporary) file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },

    /// The filters left fewer than three distinct points to triangulate.
    #[error("{}: {what}", names(.files))]
    NothingLeft {
        /// The input files.
        files: Vec<PathBuf>,
        /// What each filter dropped (`FilterStats::describe` in `input::las`).
        what: String,
    },

    /// A buffer the job needs cannot be allocated (or would exceed the memory budget).
    #[error("cannot allocate {bytes} bytes for {what}: {hint}")]
    OutOfMemory {
        /// What the memory was for.
        what: String,
        /// How much was asked.
        bytes: u64,
        /// What to do about it.
        hint: String,
    },

    /// Tasks of a plan failed (`sweeptin run --all`); `kind` is the first failure's.
    #[error(
        "{} of {total} tasks failed: {failed:?}{}; run them again with --resume",
        failed.len(),
        killed_by(killed)
    )]
    TasksFailed {
        /// The tasks that failed.
        failed: Vec<usize>,
        /// Those of them whose process a signal ended (task, signal number): the out-of-memory
        /// killer's SIGKILL, a crash's SIGSEGV.
        killed: Vec<(usize, i32)>,
        /// Tasks run.
        total: usize,
        /// What kind of failure the lowest-numbered failed task had ([`ErrorKind::from_signal`]
        /// for one a signal ended).
        kind: ErrorKind,
    },

    /// A bug in sweeptin: an internal invariant does not hold. Please report it with the input.
    #[error("internal error (a bug in sweeptin, please report it with the input): {0}")]
    Internal(String),
}

/// What kind of failure an [`Error`] is; the command line exits with [`ErrorKind::exit_code`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum ErrorKind {
    /// The command asks for something impossible: bad or conflicting options, an unknown format,
    /// an output that names an input or another output, a job over its limits (exit 2).
    Usage,
    /// The input data is bad: unreadable, damaged, not in its format, or with nothing to
    /// triangulate (exit 3).
    Input,
    /// An output, temporary or spill file cannot be written, or memory cannot be had: the
    /// environment (disk full, read-only, permissions, memory limit) (exit 4).
    Output,
    /// A bug in sweeptin (exit 5).
    Internal,
    /// Interrupted by a signal (exit 130 for SIGINT; 128 + the signal's number in general).
    Interrupted,
}

impl ErrorKind {
    /// The process exit status of this kind: 2 usage, 3 bad input data, 4 output or temporary
    /// I/O, 5 internal error, 130 interrupted.
    pub const fn exit_code(self) -> u8 {
        match self {
            ErrorKind::Usage => 2,
            ErrorKind::Input => 3,
            ErrorKind::Output => 4,
            ErrorKind::Internal => 5,
            ErrorKind::Interrupted => 130,
        }
    }

    /// The kind an exit status stands for (a child `sweeptin` process's); `None` for 0.
    pub const fn from_exit_code(code: i32) -> Option<ErrorKind> {
        match code {
            0 => None,
            2 => Some(ErrorKind::Usage),
            3 => Some(ErrorKind::Input),
            4 => Some(ErrorKind::Output),
            129..=159 => Some(ErrorKind::Interrupted),
            _ => Some(ErrorKind::Internal),
        }
    }

    /// The kind of failure of a child `sweeptin` process that the signal `signal` ended (it
    /// could not exit with a status of its own): a crash (SIGSEGV, SIGBUS, SIGILL, SIGFPE,
    /// SIGABRT, SIGTRAP, SIGSYS) is a bug; any other signal came from outside, the environment
    /// (SIGKILL from the out-of-memory killer or a job's limit, SIGXCPU, SIGTERM to the task
    /// alone): [`ErrorKind::Output`], exit 4.
    pub const fn from_signal(signal: i32) -> ErrorKind {
        match signal {
            4..=8 | 11 | 31 => ErrorKind::Internal,
            _ => ErrorKind::Output,
        }
    }
}

/// `"; task 3 was killed by SIGKILL (…)"` for each task in `killed` (task, signal).
fn killed_by(killed: &[(usize, i32)]) -> String {
    killed
        .iter()
        .map(|&(task, signal)| format!("; {}", task_killed(task, signal)))
        .collect()
}

/// `"task 3 was killed by SIGKILL (signal 9; …what sends it…)"`: how `run --all` names a task
/// killed by `signal`, in its error and in the task's failure record.
pub fn task_killed(task: usize, signal: i32) -> String {
    let name = match signal {
        1 => "SIGHUP",
        2 => "SIGINT",
        3 => "SIGQUIT",
        4 => "SIGILL",
        5 => "SIGTRAP",
        6 => "SIGABRT",
        7 => "SIGBUS",
        8 => "SIGFPE",
        9 => "SIGKILL",
        11 => "SIGSEGV",
        13 => "SIGPIPE",
        15 => "SIGTERM",
        24 => "SIGXCPU",
        25 => "SIGXFSZ",
        31 => "SIGSYS",
        _ => "a signal",
    };
    let why = match (signal, ErrorKind::from_signal(signal)) {
        (9, _) => {
            "the out-of-memory killer or a job's memory or time limit sends it: run fewer \
             --jobs at once, or plan smaller tiles"
        }
        (_, ErrorKind::Internal) => "a crash: a bug in sweeptin, please report it",
        _ => "sent from outside",
    };
    format!("task {task} was killed by {name} (signal {signal}; {why})")
}

/// The files' names, comma-separated.
fn names(files: &[PathBuf]) -> String {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    names.join(", ")
}

/// `1536` → `1.5 KiB`.
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = bytes as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{v:.1} {}", UNITS[unit])
    }
}

/// `v > 0` rounded up to two significant digits, for a bound a message suggests (`4.23` →
/// `4.3`, `1234` → `1300`, `2.01e-3` → `2.1e-3`); other values as they are.
pub(crate) fn round_up_figure(v: f64) -> f64 {
    if !(v > 0.0 && v.is_finite()) {
        return v;
    }
    let unit = 10f64.powi(v.log10().floor() as i32 - 1);
    let r = (v / unit).ceil() * unit;
    // Without the product's binary noise (4.3, not 4.300000000000001).
    format!("{r:.1e}").parse().unwrap_or(r)
}

/// `v > 0` rounded down to two significant digits (`4.27` → `4.2`), for a bound a message
/// suggests from above; other values as they are.
pub(crate) fn round_down_figure(v: f64) -> f64 {
    if !(v > 0.0 && v.is_finite()) {
        return v;
    }
    let unit = 10f64.powi(v.log10().floor() as i32 - 1);
    let r = (v / unit).floor() * unit;
    format!("{r:.1e}").parse().unwrap_or(r)
}

/// What to do when the process may open no more files (`EMFILE`), or nothing.
fn files_hint(e: &std::io::Error) -> &'static str {
    // EMFILE is 24 on Linux, macOS and the BSDs.
    if e.raw_os_error() == Some(24) {
        " (this process may open too few files at once: raise `ulimit -n`)"
    } else {
        ""
    }
}

impl Error {
    /// Wraps an I/O error reading an input with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// The trimming (`--max-edge`, a boundary, holes) removed every one of the `n` triangles:
    /// an option to change, not a point set without triangles.
    pub fn trimmed_all(n: u64) -> Self {
        Error::Options(format!(
            "the trimming (--max-edge, --trim-boundary, --holes) removed all {} triangles: \
             nothing is left to write (a longer --max-edge or a wider boundary keeps some)",
            crate::fmt::count(n)
        ))
    }

    /// Wraps an I/O error writing an output, temporary or spill file with the path it concerns.
    pub fn write(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Write {
            path: path.into(),
            source,
        }
    }

    /// What kind of failure this is (the exit status of the command line).
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::NoInput | Error::Options(_) => ErrorKind::Usage,
            // Too many open files: the environment's limit, not the input.
            Error::Io { source, .. } if !files_hint(source).is_empty() => ErrorKind::Output,
            Error::NonFinite { .. }
            | Error::CoordinateOutOfRange { .. }
            | Error::TooFewPoints { .. }
            | Error::AllCollinear { .. }
            | Error::NoArea { .. }
            | Error::TooManyPoints { .. }
            | Error::Io { .. }
            | Error::Parse { .. }
            | Error::Format { .. }
            | Error::BadLine { .. }
            | Error::Invalid(_)
            | Error::Refine(_)
            | Error::NothingLeft { .. } => ErrorKind::Input,
            Error::Output { .. } | Error::Write { .. } | Error::OutOfMemory { .. } => {
                ErrorKind::Output
            }
            Error::OutOfOrder { .. } | Error::BufferTooSmall { .. } | Error::Internal(_) => {
                ErrorKind::Internal
            }
            Error::Interrupted => ErrorKind::Interrupted,
            Error::TasksFailed { kind, .. } => *kind,
        }
    }

    /// [`Error::Internal`] for a panic caught in the `thread` thread: its message (the payload
    /// as `&str` or `String`), instead of a re-panic. The Python package reports its panics
    /// with it too.
    pub fn panicked(thread: &str, payload: &(dyn std::any::Any + Send)) -> Self {
        let message = payload
            .downcast_ref::<&str>()
            .copied()
            .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
            .unwrap_or("(no message)");
        Error::Internal(format!("the {thread} thread panicked: {message}"))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn tasks_killed_by_signals_are_named_and_classified() {
        use super::{Error, ErrorKind};
        let e = Error::TasksFailed {
            failed: vec![1, 4],
            killed: vec![(1, 9), (4, 11)],
            total: 6,
            kind: ErrorKind::from_signal(9),
        };
        let text = e.to_string();
        assert!(text.contains("task 1 was killed by SIGKILL (signal 9; the out-of-memory"));
        assert!(text.contains("task 4 was killed by SIGSEGV (signal 11; a crash"));
        assert_eq!(e.kind().exit_code(), 4);
        assert_eq!(ErrorKind::from_signal(6), ErrorKind::Internal);
        assert_eq!(ErrorKind::from_signal(15), ErrorKind::Output);
    }

    #[test]
    fn suggested_bounds_round_up_to_two_digits() {
        let r = super::round_up_figure;
        assert_eq!(
            (r(4.23), r(0.8791), r(1234.0), r(4.3)),
            (4.3, 0.88, 1300.0, 4.3)
        );
        assert_eq!((r(9.95), r(2.01e-3), r(0.0)), (10.0, 2.1e-3, 0.0));
    }

    #[test]
    fn human_bytes() {
        assert_eq!(super::human_bytes(12), "12 B");
        assert_eq!(super::human_bytes(1536), "1.5 KiB");
        assert_eq!(super::human_bytes(5 << 30), "5.0 GiB");
    }
}
