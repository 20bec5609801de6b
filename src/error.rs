//! The library's one error type.
//!
//! Every fallible function in `sweeptin` returns [`Result<T>`]. Variants carry the data a user
//! needs to find the problem: the file, the line or point index, and what is wrong with it.
//! The binary turns them into messages with `anyhow` and exits with code 2.

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
    /// (see [`crate::geom::predicates::MAX_COORD`] and [`crate::geom::predicates::MIN_NONZERO_COORD`]).
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

    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
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

    /// A bug in sweeptin: an internal invariant does not hold. Please report it with the input.
    #[error("internal error (a bug in sweeptin, please report it with the input): {0}")]
    Internal(String),
}

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// [`Error::Internal`] for a panic caught in the `thread` thread: its message (the payload
    /// as `&str` or `String`), instead of a re-panic.
    pub(crate) fn panicked(thread: &str, payload: &(dyn std::any::Any + Send)) -> Self {
        let message = payload
            .downcast_ref::<&str>()
            .copied()
            .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
            .unwrap_or("(no message)");
        Error::Internal(format!("the {thread} thread panicked: {message}"))
    }
}
