//! Command-line interface: parse flags, build a validated configuration, call the library.
//! Errors are printed with their whole chain; the exit status is the library error's kind
//! ([`sweeptin::ErrorKind::exit_code`], listed in [`EXIT_STATUS`]), 0 on success (and 0 when the
//! reader of our standard output went away), 128 + the signal when interrupted, after deleting
//! temporary files.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod check;
mod contours;
mod crossval;
mod dem;
mod ground;
mod height;
mod hillshade;
mod index;
mod info;
mod input;
mod plan;
mod plan_ground;
mod products;
mod profile;
mod refine;
mod report;
mod run_all;
mod sample;
mod simplify;
mod thin;
mod tin;
mod volume;

/// The exit statuses, shown after the top-level `--help` (and in the README).
pub const EXIT_STATUS: &str = "\
Exit status:
  0    done (also when the reader of standard output went away)
  2    usage: bad or conflicting options, unknown format, an output naming an input or another
       output, a job over its limits (--max-cells, --mem)
  3    bad input data: unreadable, damaged or not in its format, or nothing left to triangulate
  4    output or temporary I/O: disk full, read-only, permissions, a directory or device in the
       way, memory that cannot be had; `run --all` whose task was killed by a signal from
       outside (SIGKILL: the out-of-memory killer or a job's limit), named with its task
  5    internal error (a bug in sweeptin: please report it with the input), also a task of
       `run --all` that crashed (SIGSEGV, SIGABRT)
  130  interrupted by Ctrl-C (SIGINT); 143 by SIGTERM, 129 by SIGHUP (temporary files removed)
With --json a failure is also one object on standard output:
  {\"error\": {\"status\": 3, \"kind\": \"input\", \"message\": \"…\", \"causes\": […]}}";

/// Exact, bounded-memory Delaunay terrain models from lidar point clouds.
#[derive(Parser, Debug)]
#[command(name = "sweeptin", version, about, long_about = None, after_help = EXIT_STATUS)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Triangulate points into a Delaunay TIN.
    Tin(tin::Args),
    /// Validate a mesh: orientation, adjacency, Delaunay property, convex hull, Euler count.
    Check(check::Args),
    /// Show what LAS/LAZ headers say: version, format, counts, bounds, scale/offset, CRS.
    Info(info::Args),
    /// DEM raster (GeoTIFF or ASCII grid) by linear interpolation in the TIN at cell centres.
    Dem(dem::Args),
    /// Contour lines stitched into polylines (GeoJSON).
    Contours(contours::Args),
    /// Cut and fill volumes against a plane or a second surface, within an optional boundary.
    Volume(volume::Args),
    /// Heights of the TIN at query points.
    Sample(sample::Args),
    /// Height above ground of every point (from the TIN of the class-2 points, or of the ground
    /// found on the fly with --ground), written back as a HeightAboveGround attribute or
    /// replacing z.
    Height(height::Args),
    /// Section of the TIN along polylines, with a point at every edge crossed and chainage.
    Profile(profile::Args),
    /// Shaded relief (PNG) of a DEM GeoTIFF.
    Hillshade(hillshade::Args),
    /// Several products from one pass: DEM, contours, volume, samples, profiles, mesh.
    Products(products::Args),
    /// Leave-one-out accuracy of the TIN: remove a point, interpolate its height, put it back.
    Crossval(crossval::Args),
    /// Simplify a grid DEM (GeoTIFF, ESRI ASCII) into a TIN within an error bound.
    Simplify(simplify::Args),
    /// Cut a `dem`, `contours`, `volume`, `tin` or `ground` job into exact tiles for a batch
    /// engine: writes DIR/plan.json (from the files' headers), after one decoding pass of the
    /// plain LAZ/LAS files into DIR/index/: over one file, a point store its tasks read instead
    /// of decoding (--no-store: a chunk index); over several, each file's chunk index, so that
    /// tasks decode only the chunks near their tile.
    Plan(plan::PlanArgs),
    /// Run one task of a plan (--task I, or the index a job array gives), or all of them.
    Run(plan::RunArgs),
    /// Join the finished tasks of a plan into one result: a VRT or GeoTIFF mosaic, stitched
    /// contours, summed volumes, one mesh, or a ground plan's points (a .vpc of the tiles, or
    /// one .laz/.las).
    Merge(plan::MergeArgs),
    /// The report of a plan's night: a static HTML page (an SVG map of the tiles coloured by
    /// state, the failed tasks with their messages and re-run commands, totals, a hillshade of
    /// a DEM's mosaic) or --json.
    Report(report::Args),
    /// Write a virtual point cloud (.vpc) listing LAS/LAZ/COPC files with their extents, counts
    /// and CRS (headers only), for QGIS, PDAL wrench, lasR and sweeptin's own box reads; or, with
    /// --chunks, each plain LAZ/LAS file's chunk index (FILE.chunks), which plans read.
    Index(index::Args),
    /// Classify the ground (class 2) and low noise (7) of lidar points by progressive TIN
    /// densification, and write the points back with their new classes.
    Ground(ground::Args),
    /// Thin points into the fewest-point TIN that keeps every point within a vertical tolerance
    /// (--max-error), breaklines kept as edges.
    Thin(thin::Args),
    /// Quality mesh: refine a TIN (mesh or points, with breaklines) until every angle is at
    /// least --min-angle (Ruppert / Triangle -q), for hydraulic and FEM models.
    Refine(refine::Args),
}

impl Command {
    /// Whether a one-object JSON summary was asked for on standard output: a failure is then
    /// reported there too ([`ErrorSummary`]), beside the message on standard error.
    fn json(&self) -> bool {
        match self {
            Command::Tin(a) => a.input.json,
            Command::Thin(a) => a.input.json,
            Command::Ground(a) => a.json,
            Command::Refine(a) => a.input.json,
            Command::Dem(a) => a.input.args.json,
            Command::Contours(a) => a.input.args.json,
            Command::Volume(a) => a.input.args.json,
            Command::Sample(a) => a.input.args.json,
            Command::Height(a) => a.json,
            Command::Profile(a) => a.input.args.json,
            Command::Products(a) => a.input.args.json,
            Command::Info(a) => a.json,
            Command::Index(a) => a.json,
            Command::Crossval(a) => a.json,
            Command::Simplify(a) => a.json,
            Command::Run(a) => a.json,
            Command::Merge(a) => a.json,
            Command::Report(a) => a.json,
            Command::Check(_) | Command::Hillshade(_) | Command::Plan(_) => false,
        }
    }
}

/// The `--json` summary of a failed command: `{"error": {...}}` on standard output, so that a
/// batch job that parses it learns why instead of finding nothing.
#[derive(serde::Serialize)]
struct ErrorSummary<'a> {
    error: ErrorReport<'a>,
}

#[derive(serde::Serialize)]
struct ErrorReport<'a> {
    /// The exit status.
    status: u8,
    /// `usage`, `input`, `output`, `internal` or `interrupted`.
    kind: sweeptin::ErrorKind,
    /// The message, as on standard error (without the prefix).
    message: &'a str,
    /// Causes the message does not already spell out.
    causes: Vec<String>,
}

/// Set by a command that printed its `--json` summary and then fails (`info` lists the files
/// it could not read there): no second object follows it.
pub static SUMMARY_PRINTED: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// The last panic's message and place (see `main`).
static LAST_PANIC: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

/// `--io-timeout` and `--io-concurrency` of the (sub)command, set for the process before anything
/// is opened: a remote input's first request may come before the command's options are read.
/// The one place they are set (a plan's job too: `plan::parse_job`).
fn apply_io_options(m: &clap::ArgMatches) {
    use sweeptin::input::source::{set_io_concurrency, set_io_timeout};
    if let Ok(Some(&t)) = m.try_get_one::<u64>("io_timeout") {
        set_io_timeout(t);
    }
    if let Ok(Some(&n)) = m.try_get_one::<u16>("io_concurrency") {
        set_io_concurrency(usize::from(n));
    }
    if let Some((_, sub)) = m.subcommand() {
        apply_io_options(sub);
    }
}

/// Runs the command line; returns the process exit code.
pub fn main() -> ExitCode {
    // Large buffers freed by a tile or run go back to the system at once (glibc).
    sweeptin::tune_allocator();
    let parsed = <Cli as clap::CommandFactory>::command()
        .try_get_matches()
        .and_then(|m| {
            apply_io_options(&m);
            <Cli as clap::FromArgMatches>::from_arg_matches(&m)
        });
    let cli = match parsed {
        Ok(cli) => cli,
        Err(e) => {
            // A usage error found while parsing (a bad number, an unknown flag) is reported as
            // one object too when `--json` is on the command line; help and version are not
            // errors.
            let json = |a: &std::ffi::OsString| {
                a.to_str()
                    .is_some_and(|a| a == "--json" || a.starts_with("--json="))
            };
            if e.use_stderr() && std::env::args_os().skip(1).any(|a| json(&a)) {
                // The message up to the usage (a missing argument's names are on the lines
                // after the first).
                let text = e.render().to_string();
                let lines: Vec<&str> = text
                    .lines()
                    .take_while(|l| !l.trim().is_empty())
                    .map(str::trim)
                    .collect();
                let message = lines.join(" ");
                let message = message.strip_prefix("error: ").unwrap_or(&message);
                print_error_json(sweeptin::ErrorKind::Usage, message, Vec::new());
            }
            e.exit()
        }
    };
    let json = cli.command.json();
    // Ctrl-C / SIGTERM: delete temporary files, exit 130. Without it outputs stay atomic anyway.
    if let Err(e) = sweeptin::output::install_interrupt_handler() {
        eprintln!("sweeptin: warning: {e}");
    }
    // A panic is reported once, as an internal error (exit 5), by whoever catches it: the
    // library turns its threads' panics and its decoders' into errors. The hook only keeps the
    // message and place (and prints a backtrace when RUST_BACKTRACE asks for one).
    std::panic::set_hook(Box::new(|info| {
        if std::env::var_os("RUST_BACKTRACE").is_some_and(|v| v != "0")
            && stdout_failure(&info.to_string()).is_none()
        {
            eprintln!("{info}\n{}", std::backtrace::Backtrace::force_capture());
        }
        *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(info.to_string());
    }));
    let result = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| dispatch(cli))) {
        Ok(r) => r,
        Err(_) => {
            let what = LAST_PANIC
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take()
                .unwrap_or_else(|| "(no message)".into());
            // `println!` on a closed pipe or a full disk: not a bug.
            if let Some(cause) = stdout_failure(&what) {
                if cause.contains("os error 32") || cause.starts_with("Broken pipe") {
                    return ExitCode::SUCCESS;
                }
                eprintln!("sweeptin: error: cannot write to standard output: {cause}");
                return ExitCode::from(sweeptin::ErrorKind::Output.exit_code());
            }
            Err(sweeptin::Error::Internal(what.replace('\n', " ")).into())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if is_broken_pipe(&e) {
                return ExitCode::SUCCESS;
            }
            let message = e.to_string();
            eprintln!("sweeptin: error: {message}");
            let mut causes = Vec::new();
            let mut shown = message.clone();
            for cause in e.chain().skip(1) {
                // Library errors already spell out their source in their own message.
                let text = cause.to_string();
                if !shown.contains(&text) {
                    eprintln!("  caused by: {text}");
                    causes.push(text.clone());
                }
                shown = text;
            }
            let kind = kind(&e);
            if json && !SUMMARY_PRINTED.load(std::sync::atomic::Ordering::Relaxed) {
                print_error_json(kind, &message, causes);
            }
            ExitCode::from(kind.exit_code())
        }
    }
}

/// Prints the `--json` object of a failure on standard output ([`ErrorSummary`]).
fn print_error_json(kind: sweeptin::ErrorKind, message: &str, causes: Vec<String>) {
    let summary = ErrorSummary {
        error: ErrorReport {
            status: kind.exit_code(),
            kind,
            message,
            causes,
        },
    };
    // Standard output may be what failed: the message on stderr stands then.
    if let Ok(text) = serde_json::to_string(&summary) {
        use std::io::Write;
        let _ = writeln!(std::io::stdout(), "{text}");
    }
}

/// The I/O error of a panic of `print!`/`println!` (standard output closed or full), if that is
/// what the panic message `what` says.
fn stdout_failure(what: &str) -> Option<&str> {
    const PREFIX: &str = "failed printing to stdout: ";
    what.find(PREFIX).map(|i| what[i + PREFIX.len()..].trim())
}

/// What kind of failure `e` is: the kind of the library error in its chain; an I/O error of the
/// binary's own (writing standard output) is an output failure; anything else the binary
/// refused itself is a usage error.
pub fn kind(e: &anyhow::Error) -> sweeptin::ErrorKind {
    if let Some(k) = e
        .chain()
        .find_map(|c| c.downcast_ref::<sweeptin::Error>())
        .map(sweeptin::Error::kind)
    {
        return k;
    }
    if e.chain().any(|c| c.is::<std::io::Error>()) {
        return sweeptin::ErrorKind::Output;
    }
    sweeptin::ErrorKind::Usage
}

fn dispatch(mut cli: Cli) -> anyhow::Result<()> {
    // `@list.txt`, quoted globs: the files a command's FILES stand for; the lists read are
    // inputs too, which no output may replace.
    match &mut cli.command {
        Command::Tin(a) => a.input.expand()?,
        Command::Info(a) => {
            input::expand_files(&mut a.files)?;
        }
        Command::Dem(a) => a.input.args.expand()?,
        Command::Contours(a) => a.input.args.expand()?,
        Command::Volume(a) => a.input.args.expand()?,
        Command::Sample(a) => a.input.args.expand()?,
        Command::Profile(a) => a.input.args.expand()?,
        Command::Products(a) => a.input.args.expand()?,
        Command::Index(a) => a.lists = input::expand_files(&mut a.files)?,
        Command::Crossval(a) => {
            input::expand(&mut a.input)?;
        }
        Command::Thin(a) => a.input.expand()?,
        Command::Refine(a) => a.input.expand()?,
        Command::Height(a) => a.lists = input::expand_files(&mut a.inputs)?,
        _ => {}
    }
    match cli.command {
        Command::Tin(a) => tin::run(a),
        Command::Check(a) => check::run(a),
        Command::Info(a) => info::run(a),
        Command::Dem(a) => dem::run(a),
        Command::Contours(a) => contours::run(a),
        Command::Volume(a) => volume::run(a),
        Command::Sample(a) => sample::run(a),
        Command::Height(a) => height::run(a),
        Command::Profile(a) => profile::run(a),
        Command::Hillshade(a) => hillshade::run(a),
        Command::Products(a) => products::run(a),
        Command::Simplify(a) => simplify::run(a),
        Command::Crossval(a) => crossval::run(a),
        Command::Plan(a) => plan::plan(a),
        Command::Run(a) => plan::run(a),
        Command::Merge(a) => plan::merge(a),
        Command::Report(a) => report::run(a),
        Command::Index(a) => index::run(a),
        Command::Thin(a) => thin::run(a),
        Command::Ground(a) => ground::run(a),
        Command::Refine(a) => refine::run(a),
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
