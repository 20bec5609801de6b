//! Issue 13: every failure a hostile but realistic user found, kept fixed, through the command
//! line; and the exit statuses (issue 12). docs/RELIABILITY.md lists the cases and these tests.
//!
//! Inputs are small: a 50 × 50 grid of XYZ points made here and `startinpy_small.laz` (39,233
//! points) from the shared data.

use crate::data;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn sweeptin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sweeptin"))
}

fn run(dir: &Path, args: &[&str]) -> Output {
    sweeptin().current_dir(dir).args(args).output().unwrap()
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn code(o: &Output) -> i32 {
    o.status.code().unwrap_or(-1)
}

/// `grid.xyz`: 50 × 50 points 1 m apart, z = (i·j mod 7)/10.
fn grid(dir: &Path) -> PathBuf {
    let p = dir.join("grid.xyz");
    let mut s = String::new();
    for i in 0..50 {
        for j in 0..50 {
            s.push_str(&format!("{i} {j} {}\n", f64::from((i * j) % 7) / 10.0));
        }
    }
    std::fs::write(&p, s).unwrap();
    p
}

fn small_laz() -> PathBuf {
    data::shared("lidar/startinpy_small.laz")
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

// ---- Item 1: what is at the output path ------------------------------------------------------

#[cfg(unix)]
#[test]
fn output_symlink_replaces_its_target_and_keeps_the_mode() {
    use std::os::unix::fs::PermissionsExt;
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    std::fs::write(dir.join("target.ply"), b"old").unwrap();
    std::fs::set_permissions(
        dir.join("target.ply"),
        std::fs::Permissions::from_mode(0o640),
    )
    .unwrap();
    std::os::unix::fs::symlink("target.ply", dir.join("link.ply")).unwrap();
    let o = run(dir, &["tin", "grid.xyz", "-o", "link.ply", "-q"]);
    assert_eq!(code(&o), 0, "{}", err(&o));
    let link = std::fs::symlink_metadata(dir.join("link.ply")).unwrap();
    assert!(link.file_type().is_symlink(), "the link was replaced");
    let target = std::fs::metadata(dir.join("target.ply")).unwrap();
    assert_eq!(target.permissions().mode() & 0o777, 0o640);
    let direct = run(dir, &["tin", "grid.xyz", "-o", "direct.ply", "-q"]);
    assert_eq!(code(&direct), 0);
    assert_eq!(
        std::fs::read(dir.join("target.ply")).unwrap(),
        std::fs::read(dir.join("direct.ply")).unwrap()
    );
    // A dangling link: its target is created.
    std::os::unix::fs::symlink("made.ply", dir.join("dangling.ply")).unwrap();
    let o = run(dir, &["tin", "grid.xyz", "-o", "dangling.ply", "-q"]);
    assert_eq!(code(&o), 0, "{}", err(&o));
    assert!(dir.join("made.ply").is_file());
}

#[cfg(unix)]
#[test]
fn fifo_device_and_stdout_are_streamed_where_the_format_allows() {
    use std::os::unix::fs::FileTypeExt;
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let o = run(dir, &["tin", "grid.xyz", "-o", "file.ply", "-q"]);
    assert_eq!(code(&o), 0);
    let file = std::fs::read(dir.join("file.ply")).unwrap();
    // Standard output.
    let o = run(
        dir,
        &["tin", "grid.xyz", "-o", "-", "--format", "ply", "-q"],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    assert_eq!(
        o.stdout, file,
        "PLY on standard output differs from the file"
    );
    // A FIFO: its reader gets the whole PLY.
    let fifo = dir.join("fifo");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let reader = std::thread::spawn({
        let fifo = fifo.clone();
        move || std::fs::read(fifo).unwrap()
    });
    let o = run(
        dir,
        &["tin", "grid.xyz", "-o", "fifo", "--format", "ply", "-q"],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    assert!(
        reader.join().unwrap() == file,
        "the FIFO's reader got another PLY"
    );
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    // The null device stays the null device; ASCII grids stream too.
    let o = run(
        dir,
        &[
            "tin",
            "grid.xyz",
            "-o",
            "/dev/null",
            "--format",
            "ply",
            "-q",
        ],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    let args = ["dem", "grid.xyz", "-o", "-", "--raster-format", "asc", "-q"];
    let o = run(dir, &args);
    assert_eq!(code(&o), 0, "{}", err(&o));
    assert!(
        o.stdout.starts_with(b"ncols "),
        "not an ASCII grid on standard output"
    );
    assert!(!dir.join("-.prj").exists());
    assert!(
        std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );
    // A GeoTIFF needs seeking: refused before any work, nothing written.
    let o = run(
        dir,
        &[
            "dem",
            "grid.xyz",
            "-o",
            "/dev/null",
            "--raster-format",
            "tif",
        ],
    );
    assert_eq!(code(&o), 2, "{}", err(&o));
    assert!(err(&o).contains("needs seeking"), "{}", err(&o));
    // A directory is never replaced; --json and -o - would mix on standard output.
    std::fs::create_dir(dir.join("sub.ply")).unwrap();
    let o = run(dir, &["tin", "grid.xyz", "-o", "sub.ply", "-q"]);
    assert_eq!(code(&o), 4, "{}", err(&o));
    assert!(err(&o).contains("a directory"), "{}", err(&o));
    let o = run(
        dir,
        &["tin", "grid.xyz", "-o", "-", "--format", "ply", "--json"],
    );
    assert_eq!(code(&o), 2, "{}", err(&o));
    let mut left = names(dir);
    left.retain(|n| n.starts_with('.'));
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

// ---- Item 2: filters on XYZ ------------------------------------------------------------------

#[test]
fn bbox_applies_to_xyz_and_lidar_filters_are_refused_there() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let o = run(
        dir,
        &[
            "tin",
            "grid.xyz",
            "--bbox",
            "0,0,10,10",
            "-o",
            "t.ply",
            "--json",
        ],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["points_read"], 121, "{j}");
    let o = run(
        dir,
        &[
            "volume",
            "grid.xyz",
            "--bbox",
            "0,0,10,10",
            "--plane",
            "0",
            "--json",
        ],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let area = j["area"].as_f64().unwrap();
    assert_eq!(area, 100.0, "{j}");
    for (flag, value) in [("--class", "2"), ("--returns", "first")] {
        let o = run(dir, &["tin", "grid.xyz", flag, value, "-o", "t.ply"]);
        assert_eq!(code(&o), 2, "{}", err(&o));
        assert!(
            err(&o).contains(flag) && err(&o).contains("XYZ"),
            "{}",
            err(&o)
        );
    }
}

/// Issue 12: nothing left after the filters names the filters and what each dropped (exit 3).
#[test]
fn nothing_left_after_the_filters_names_them() {
    let d = tempfile::tempdir().unwrap();
    let laz = small_laz();
    let o = sweeptin()
        .args(["tin", "--class", "200", "-o"])
        .arg(d.path().join("t.ply"))
        .arg(&laz)
        .output()
        .unwrap();
    assert_eq!(code(&o), 3, "{}", err(&o));
    let e = err(&o);
    assert!(e.contains("no point left after the filters"), "{e}");
    assert!(e.contains("39233 by --class"), "{e}");
    let o = sweeptin()
        .args([
            "tin",
            "--class",
            "2",
            "--bbox",
            "85700,447200,85700.5,447200.5",
            "-o",
        ])
        .arg(d.path().join("t.ply"))
        .arg(&laz)
        .output()
        .unwrap();
    assert_eq!(code(&o), 3, "{}", err(&o));
    let e = err(&o);
    assert!(
        e.contains("by --class") && e.contains("outside --bbox"),
        "{e}"
    );
    assert!(names(d.path()).is_empty());
}

// ---- Item 3: pipes as inputs -----------------------------------------------------------------

#[cfg(unix)]
#[test]
fn pipes_work_as_inputs_or_are_refused_clearly() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let g = grid(dir);
    let points = std::fs::read(&g).unwrap();
    let piped = |args: &[&str], input: &[u8]| {
        let mut c = sweeptin()
            .current_dir(dir)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut stdin = c.stdin.take().unwrap();
        let input = input.to_vec();
        let feeder = std::thread::spawn(move || {
            let _ = stdin.write_all(&input);
        });
        let o = c.wait_with_output().unwrap();
        feeder.join().unwrap();
        o
    };
    // Points from a pipe, once.
    let o = piped(&["tin", "-", "-o", "piped.ply", "-q"], &points);
    assert_eq!(code(&o), 0, "{}", err(&o));
    let o = run(dir, &["tin", "grid.xyz", "-o", "file.ply", "-q"]);
    assert_eq!(code(&o), 0);
    // The same mesh (the header's comment names the input: compare what follows it).
    let body = |name: &str| {
        let b = std::fs::read(dir.join(name)).unwrap();
        let end = b.windows(11).position(|w| w == b"end_header\n").unwrap();
        b[end..].to_vec()
    };
    assert!(
        body("piped.ply") == body("file.ply"),
        "the piped mesh differs"
    );
    // Query points from a pipe.
    let o = piped(
        &[
            "sample",
            "grid.xyz",
            "--points",
            "/dev/stdin",
            "-o",
            "s.csv",
            "-q",
        ],
        b"x,y\n10.5,20.25\n60,60\n3,4\n",
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    let csv = std::fs::read_to_string(dir.join("s.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 4, "{csv}");
    assert_eq!(lines[0], "x,y,z");
    assert!(lines[1].len() > "10.5,20.25,".len(), "{csv}");
    assert_eq!(lines[2], "60,60,");
    // Lines without z need a second pass over the points: refused for a pipe.
    std::fs::write(dir.join("l.txt"), "1 1\n30 40\n").unwrap();
    let o = piped(
        &["tin", "/dev/stdin", "--breaklines", "l.txt", "-o", "t.ply"],
        &points,
    );
    assert_eq!(code(&o), 2, "{}", err(&o));
    assert!(err(&o).contains("read only once"), "{}", err(&o));
    // LAS/LAZ from a pipe: refused (the reader opens the file more than once).
    let laz = std::fs::read(small_laz()).unwrap();
    let o = piped(&["tin", "/dev/stdin", "-o", "t.ply"], &laz);
    assert_ne!(code(&o), 0);
    assert!(!dir.join("t.ply").exists());
}

// ---- Item 4: outputs never overwrite inputs or each other -----------------------------------

#[cfg(unix)]
#[test]
fn outputs_never_overwrite_an_input_or_each_other() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let before = std::fs::read(dir.join("grid.xyz")).unwrap();
    std::os::unix::fs::symlink("grid.xyz", dir.join("alias.ply")).unwrap();
    // A side file (an ASCII grid's .prj, a PNG's world file) through a link to an input: the
    // .prj replaced the input.
    std::os::unix::fs::symlink("grid.xyz", dir.join("alias.prj")).unwrap();
    std::os::unix::fs::symlink("grid.xyz", dir.join("shade.pgw")).unwrap();
    std::fs::write(dir.join("grid.shp"), b"not read").unwrap();
    std::os::unix::fs::symlink("grid.shp", dir.join("alias.shp")).unwrap();
    std::fs::write(dir.join("q.csv"), "1 1\n").unwrap();
    std::fs::write(
        dir.join("l.geojson"),
        r#"{"type":"LineString","coordinates":[[1,1],[5,5]]}"#,
    )
    .unwrap();
    let cases: &[&[&str]] = &[
        &["tin", "grid.xyz", "-o", "grid.xyz", "--format", "ply"],
        &["tin", "grid.xyz", "-o", "./grid.xyz", "--format", "ply"],
        &["tin", "grid.xyz", "-o", "alias.ply"],
        &["dem", "grid.xyz", "-o", "a.tif", "--hillshade", "a.tif"],
        &["dem", "grid.xyz", "-o", "a.tif", "--contours", "a.tif"],
        &["contours", "grid.xyz", "-o", "grid.xyz"],
        &["sample", "grid.xyz", "--points", "q.csv", "-o", "q.csv"],
        &[
            "profile",
            "grid.xyz",
            "--line",
            "l.geojson",
            "-o",
            "l.geojson",
        ],
        &["products", "grid.xyz", "--dem", "a.tif", "--mesh", "a.tif"],
        &["dem", "grid.xyz", "-o", "alias.asc"],
        &["dem", "grid.xyz", "-o", "a.tif", "--hillshade", "shade.png"],
        &["dem", "grid.xyz", "-o", "a.asc", "--contours", "a.prj"],
        // An ASCII grid by --format writes its .prj whatever its extension.
        &["dem", "grid.xyz", "--format", "asc", "-o", "alias.txt"],
        &[
            "products",
            "grid.xyz",
            "--raster-format",
            "asc",
            "--dem",
            "alias",
        ],
        // An input's own side file: a shapefile's .prj, also through a link to the shapefile.
        &[
            "dem",
            "grid.xyz",
            "--breaklines",
            "road.shp",
            "-o",
            "road.asc",
        ],
        &[
            "dem",
            "grid.xyz",
            "--breaklines",
            "alias.shp",
            "-o",
            "grid.asc",
        ],
        &[
            "tin",
            "grid.xyz",
            "--breaklines",
            "l.geojson",
            "-o",
            "l.geojson",
            "--format",
            "ply",
        ],
    ];
    for args in cases {
        let o = run(dir, args);
        assert_eq!(code(&o), 2, "{args:?}: {}", err(&o));
        assert!(
            err(&o).contains("an input") || err(&o).contains("the same file"),
            "{args:?}: {}",
            err(&o)
        );
    }
    // A side file in the way (a directory) is refused before the grid is written.
    std::fs::create_dir(dir.join("b.prj")).unwrap();
    let o = run(dir, &["dem", "grid.xyz", "-o", "b.asc"]);
    assert_eq!(code(&o), 4, "{}", err(&o));
    assert_eq!(std::fs::read(dir.join("grid.xyz")).unwrap(), before);
    assert_eq!(
        names(dir),
        [
            "alias.ply",
            "alias.prj",
            "alias.shp",
            "b.prj",
            "grid.shp",
            "grid.xyz",
            "l.geojson",
            "q.csv",
            "shade.pgw"
        ],
        "something was written"
    );
}

// ---- Item 5: grid size ----------------------------------------------------------------------

#[test]
fn rasters_too_large_are_refused_before_any_work() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let laz = small_laz();
    let laz = laz.to_str().unwrap();
    let cases: &[&[&str]] = &[
        // From the LAS header, before reading a point.
        &["dem", laz, "--cell", "1e-6", "-o", "x.tif"],
        &[
            "dem",
            laz,
            "--bbox",
            "0,0,1e6,1e7",
            "--cell",
            "1",
            "-o",
            "x.tif",
        ],
        &[
            "dem",
            laz,
            "--cell",
            "0.1",
            "--max-cells",
            "1000",
            "-o",
            "x.tif",
        ],
        // XYZ: from the data's extent, once read.
        &["dem", "grid.xyz", "--cell", "1e-4", "-o", "x.tif"],
        // A row wider than the DEM's share of --mem.
        &[
            "dem",
            "grid.xyz",
            "--cell",
            "1e-5",
            "--max-cells",
            "1e14",
            "--mem",
            "64M",
            "-o",
            "x.tif",
        ],
    ];
    for args in cases {
        let start = std::time::Instant::now();
        let o = run(dir, args);
        assert_eq!(code(&o), 2, "{args:?}: {}", err(&o));
        let e = err(&o);
        assert!(e.contains("cells") && e.contains(" × "), "{args:?}: {e}");
        assert!(start.elapsed().as_secs() < 20, "{args:?} took too long");
    }
    assert_eq!(names(dir), ["grid.xyz"]);
}

/// Cells and contour levels whose indices pass 2^52 (where a float no longer counts them
/// exactly) are refused: `--cell 1e-14` at these coordinates spun forever, `--interval 1e-19`
/// hung, `--interval 1e-30` and `--base 1e19` wrote no line with exit 0.
#[test]
fn cells_and_levels_beyond_exact_indices_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let laz = small_laz();
    let laz = laz.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["dem", laz, "--cell", "1e-14", "-o", "x.tif"], "2^52"),
        (
            &[
                "dem",
                laz,
                "--cell",
                "1e-14",
                "--bbox",
                "85700,447200,85720,447220",
                "-o",
                "x.tif",
            ],
            "2^52",
        ),
        (
            &["contours", laz, "--interval", "1e-19", "-o", "c.geojson"],
            "too small",
        ),
        (
            &["contours", laz, "--interval", "1e-30", "-o", "c.geojson"],
            "too small",
        ),
        (
            &[
                "contours",
                laz,
                "--interval",
                "1",
                "--base",
                "1e19",
                "-o",
                "c.geojson",
            ],
            "2^52",
        ),
    ];
    for (args, says) in cases {
        let o = run(dir, args);
        assert_eq!(code(&o), 2, "{args:?}: {}", err(&o));
        assert!(err(&o).contains(says), "{args:?}: {}", err(&o));
    }
    assert!(names(dir).is_empty(), "{:?}", names(dir));
}

/// The DEM's rows count against --mem: with a budget of a few rows, rows go to the file early and
/// later cells are written there, and the raster is the same bytes.
#[test]
fn dem_within_a_small_memory_budget_is_the_same_raster() {
    let d = tempfile::tempdir().unwrap();
    let laz = small_laz();
    let dem = |name: &str, mem: &str| {
        let o = sweeptin()
            .args(["dem", "--cell", "0.1", "-q", "--json", "--mem", mem, "-o"])
            .arg(d.path().join(name))
            .arg(&laz)
            .output()
            .unwrap();
        assert_eq!(code(&o), 0, "{}", err(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (
            std::fs::read(d.path().join(name)).unwrap(),
            j["dem"].clone(),
        )
    };
    let (big, sb) = dem("big.tif", "1G");
    let (small, ss) = dem("small.tif", "96K");
    assert!(ss["late_cell_writes"].as_u64().unwrap() > 0, "{ss}");
    assert!(ss["max_rows_in_memory"].as_u64().unwrap() <= 12, "{ss}");
    assert_eq!(sb["late_cell_writes"], 0, "{sb}");
    assert!(big == small, "the raster depends on --mem");
}

// ---- Exit statuses ---------------------------------------------------------------------------

#[test]
fn exit_statuses_sort_the_failures() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    std::fs::write(dir.join("bad.xyz"), "1 2 3\n4 five 6\n").unwrap();
    std::fs::write(dir.join("bad.laz"), b"LASF but not really a LAZ file").unwrap();
    let cases: &[(&[&str], i32)] = &[
        (&["tin", "grid.xyz", "-o", "t.ply", "--no-such-flag"], 2),
        (&["tin", "grid.xyz", "-o", "t.unknown"], 2),
        (
            &["contours", "grid.xyz", "-o", "c.geojson", "--interval", "0"],
            2,
        ),
        // A size the engine in use ignores is still refused (it was, only by the tiles).
        (&["tin", "grid.xyz", "-o", "t.ply", "--tile", "0"], 2),
        (
            &[
                "tin",
                "grid.xyz",
                "-o",
                "t.ply",
                "--engine",
                "sweep",
                "--tile=-5",
            ],
            2,
        ),
        (
            &[
                "tin", "grid.xyz", "-o", "t.ply", "--engine", "sweep", "--tile", "NaN",
            ],
            2,
        ),
        // A typo'd thread count is refused before any thread starts (100,000 were spawned).
        (
            &["tin", "grid.xyz", "-o", "t.ply", "--threads", "100000"],
            2,
        ),
        (&["run", "p/plan.json", "--all", "--jobs", "5000"], 2),
        // Outputs that cannot say what was asked: contours in another format (GeoJSON was
        // written under a .shp name), a NODATA an ASCII grid cannot hold, a float32 overflow.
        (
            &["contours", "grid.xyz", "-o", "c.shp", "--interval", "1"],
            2,
        ),
        (&["dem", "grid.xyz", "-o", "n.asc", "--nodata", "nan"], 2),
        (&["dem", "grid.xyz", "-o", "n.tif", "--nodata", "1e40"], 2),
        (&["tin", "grid.xyz", "-o", "t.ply", "--crs", "nonsense"], 2),
        (&["tin", "missing.xyz", "-o", "t.ply"], 3),
        (&["tin", "bad.xyz", "-o", "t.ply"], 3),
        (&["tin", "bad.laz", "-o", "t.ply"], 3),
        (&["tin", "grid.xyz", "-o", "no/such/dir/t.ply"], 4),
        (&["tin", "grid.xyz", "-o", "/sys/sweeptin-test.ply"], 4),
        (
            &["tin", "grid.xyz", "-o", "t.ply", "--tmp-dir", "no/such/dir"],
            4,
        ),
    ];
    for (args, want) in cases {
        let o = run(dir, args);
        assert_eq!(code(&o), *want, "{args:?}: {}", err(&o));
    }
    let o = sweeptin()
        .current_dir(dir)
        .env("SWEEPTIN_TEST_PANIC", "writer")
        .args(["tin", "grid.xyz", "-o", "t.ply"])
        .output()
        .unwrap();
    assert_eq!(code(&o), 5, "{}", err(&o));
    assert!(err(&o).contains("internal error"), "{}", err(&o));
    assert!(err(&o).contains("injected panic"), "{}", err(&o));
    assert_eq!(names(dir), ["bad.laz", "bad.xyz", "grid.xyz"]);
    // The most threads allowed run (the decoding pool is capped beside the cores: 1,024 idle
    // workers of it took 1.9 s on this tiny grid).
    let o = run(
        dir,
        &["tin", "grid.xyz", "-o", "t.ply", "--threads", "1024"],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    let help = sweeptin().arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for line in ["Exit status:", "  2 ", "  3 ", "  4 ", "  5 ", "  130 "] {
        assert!(help.contains(line), "--help lacks {line:?}:\n{help}");
    }
}

/// A batch job that parses `--json` found nothing on standard output when a command failed. A
/// failure is one object there too, with the status, the kind and the message of stderr.
#[test]
fn json_failures_are_one_object_on_stdout() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    std::fs::write(dir.join("bad.xyz"), "1 2 3\n4 five 6\n").unwrap();
    let cases: &[(&[&str], i32, &str)] = &[
        (&["tin", "bad.xyz", "-o", "t.ply", "--json"], 3, "input"),
        (
            &["dem", "grid.xyz", "--cell", "0", "-o", "d.tif", "--json"],
            2,
            "usage",
        ),
        (
            &["info", "missing.laz", "--json", "@missing_list.txt"],
            3,
            "input",
        ),
        (&["run", "missing/plan.json", "--all", "--json"], 3, "input"),
        // Found while parsing the command line.
        (
            &["tin", "grid.xyz", "-o", "t.ply", "--json", "--threads", "x"],
            2,
            "usage",
        ),
        (
            &["dem", "grid.xyz", "-o", "d.tif", "--json", "--no-such-flag"],
            2,
            "usage",
        ),
    ];
    for (args, status, kind) in cases {
        let o = run(dir, args);
        assert_eq!(code(&o), *status, "{args:?}: {}", err(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        let v: serde_json::Value = serde_json::from_str(out.trim())
            .unwrap_or_else(|e| panic!("{args:?}: stdout is not one JSON object ({e}): {out:?}"));
        let e = &v["error"];
        assert_eq!(e["status"], *status, "{args:?}: {v}");
        assert_eq!(e["kind"], *kind, "{args:?}: {v}");
        let message = e["message"].as_str().unwrap();
        assert!(
            err(&o).contains(message),
            "{args:?}: {message:?} not on stderr"
        );
    }
    // `info` reports files it cannot read in its own summary: one object, not two.
    let o = run(dir, &["info", "missing.laz", "--json"]);
    assert_eq!(code(&o), 3);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["files"][0]["error"].is_string(), "{v}");
    // Without --json, standard output stays empty.
    let o = run(dir, &["tin", "bad.xyz", "-o", "t.ply"]);
    assert_eq!(code(&o), 3);
    assert!(o.stdout.is_empty());
}

// ---- A low limit on open files -----------------------------------------------------------------

/// The external sort keeps a file per spilled run: at `--mem 64K` this sample spills 39 runs,
/// more than a process limited to 24 open files may hold (the build before this test stopped
/// with "Too many open files"). The sort merges runs as they come, so the job runs and gives the
/// bytes of a run that spilled nothing.
#[cfg(unix)]
#[test]
fn a_low_open_file_limit_merges_runs_early_with_the_same_output() {
    let dir = tempfile::tempdir().unwrap();
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let args = |mem: &str, out: &str| -> Vec<String> {
        let sample = sample.to_str().unwrap();
        [
            "dem", sample, "--cell", "1", "--mem", mem, "--engine", "sweep",
        ]
        .iter()
        .chain(&["-q", "-o", out])
        .map(|s| s.to_string())
        .collect()
    };
    // Nothing spilled: the reference.
    let free = sweeptin()
        .current_dir(dir.path())
        .args(args("1G", "free.tif"))
        .output()
        .unwrap();
    assert_eq!(code(&free), 0, "{}", err(&free));
    // `ulimit -n` sets the soft and the hard limit: the binary cannot lift it.
    let limited = Command::new("sh")
        .current_dir(dir.path())
        .arg("-c")
        .arg("ulimit -n 24 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args("64K", "limited.tif"))
        .output()
        .unwrap();
    assert_eq!(code(&limited), 0, "{}", err(&limited));
    let a = std::fs::read(dir.path().join("free.tif")).unwrap();
    let b = std::fs::read(dir.path().join("limited.tif")).unwrap();
    assert!(a == b, "the DEMs differ");
}

/// A summary printed to standard output (`info`, `--json`, `volume`) whose reader went away is
/// exit 0, as for streamed outputs; a full device is exit 4 with a message. Both were a panic
/// (exit 5, "failed printing to stdout").
#[cfg(unix)]
#[test]
fn summaries_to_a_closed_pipe_or_a_full_disk_are_not_internal_errors() {
    let dir = tempfile::tempdir().unwrap();
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    let sample = sample.to_str().unwrap();
    let mut child = sweeptin()
        .current_dir(dir.path())
        .args(["tin", sample, "-o", "a.ply", "--json", "-q"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert_eq!(code(&o), 0, "{}", err(&o));
    // Under CI a missing /dev/full fails the test instead of skipping its half.
    let has_full = Path::new("/dev/full").exists();
    assert!(
        has_full || std::env::var("CI").as_deref() != Ok("true"),
        "/dev/full is missing"
    );
    if !has_full {
        eprintln!("skipped: no /dev/full here");
    }
    if has_full {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = sweeptin()
            .args(["info", sample])
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(code(&o), 4, "{}", err(&o));
        assert!(err(&o).contains("standard output"), "{}", err(&o));
    }
}

/// A `--max-edge` shorter than every edge removes every triangle: an option to change (exit 2,
/// saying so), not "all points are collinear" (exit 3) as it was; no output is left, through
/// the tiles and the sweep alike.
#[test]
fn a_trim_that_removes_every_triangle_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let laz = data::shared("lidar/startinpy_small.laz");
    for engine in ["tiles", "sweep"] {
        let out = dir.path().join(format!("{engine}.tif"));
        let o = run(
            dir.path(),
            &[
                "dem",
                laz.to_str().unwrap(),
                "--cell",
                "1",
                "--max-edge",
                "0.001",
                "--engine",
                engine,
                "-o",
                out.to_str().unwrap(),
                "-q",
            ],
        );
        assert_eq!(code(&o), 2, "{engine}: {}", err(&o));
        assert!(err(&o).contains("removed all"), "{engine}: {}", err(&o));
        assert!(!out.exists(), "{engine}: an output was left");
    }
}

/// A tile that lost an owned triangle (a certification bug, injected) fails the run as an
/// internal error (exit 5) with no output left, rather than writing a mesh or raster with a
/// hole: the tiles' triangles are counted against Euler's `2V − B − 2`.
#[test]
fn a_lost_triangle_is_an_internal_error() {
    let dir = tempfile::tempdir().unwrap();
    let laz = data::shared("lidar/startinpy_small.laz");
    // Without the injection the count holds, with trimming too (trimmed triangles count).
    for trim in [None, Some("--max-edge=2")] {
        let mut args = vec!["tin", laz.to_str().unwrap(), "-o", "ok.ply", "-q", "--json"];
        args.extend(trim);
        let o = run(dir.path(), &args);
        assert_eq!(code(&o), 0, "{trim:?}: {}", err(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(j["tiles"]["uncertified_owned"], 0, "{trim:?}");
        // The stages' CPU: decoding (on every core) is part of the read phase.
        let cpu = |k: &str| j["tiles"]["cpu"][k].as_f64().unwrap();
        if cfg!(target_os = "linux") {
            assert!(
                cpu("decode") > 0.0 && cpu("decode") <= cpu("read_sort"),
                "{j}"
            );
        }
        std::fs::remove_file(dir.path().join("ok.ply")).unwrap();
    }
    for (cmd, out, extra) in [
        ("tin", "t.ply", None),
        ("dem", "d.tif", Some("--contours=c.geojson")),
    ] {
        let mut args = vec![cmd, laz.to_str().unwrap(), "-o", out, "-q"];
        if cmd == "dem" {
            args.extend(["--cell", "1"]);
        }
        args.extend(extra);
        let o = sweeptin()
            .current_dir(dir.path())
            .env("SWEEPTIN_TEST_LOSE", "triangle")
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(code(&o), 5, "{cmd}: {}", err(&o));
        assert!(err(&o).contains("owned by no tile"), "{cmd}: {}", err(&o));
        assert!(
            names(dir.path()).is_empty(),
            "{cmd}: {:?}",
            names(dir.path())
        );
    }
}

/// The longest run of digits in `s` (a number printed in full: 1e300 as 301 digits).
fn longest_digits(s: &str) -> usize {
    s.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// Issue 41, item 15: figures in messages are written one way (`sweeptin::fmt`): 1e300 and
/// 1e-300 as such, not in three hundred digits; counts with thousands separators in every
/// summary and message.
#[test]
fn figures_in_messages_are_short_and_grouped() {
    let dir = tempfile::tempdir().unwrap();
    let laz = small_laz();
    let l = laz.to_str().unwrap();
    // The plane and the volumes against it.
    let o = run(dir.path(), &["volume", l, "--plane", "1e300"]);
    let out = String::from_utf8_lossy(&o.stdout).into_owned() + &err(&o);
    assert!(longest_digits(&out) < 20, "{out}");
    assert!(out.contains("z = 1e300"), "{out}");
    // A cell larger than the data.
    let o = run(dir.path(), &["dem", l, "-o", "x.tif", "--cell", "1e300"]);
    assert_eq!(code(&o), 2, "{}", err(&o));
    assert!(longest_digits(&err(&o)) < 20, "{}", err(&o));
    assert!(err(&o).contains("of size 1e300"), "{}", err(&o));
    // Counts: the TIN's summary and the trimming's refusal.
    let o = run(dir.path(), &["tin", l, "-o", "t.ply"]);
    assert!(err(&o).contains("39,233 points"), "{}", err(&o));
    let o = run(
        dir.path(),
        &["tin", l, "-o", "t2.ply", "--max-edge", "1e-300", "-q"],
    );
    let e = err(&o);
    assert!(e.contains("removed all 78,430 triangles"), "{e}");
    assert!(longest_digits(&e) <= 3, "{e}");
    // A product summary: every count grouped.
    let o = run(
        dir.path(),
        &[
            "dem",
            l,
            "-o",
            "d.tif",
            "--cell",
            "0.1",
            "--contours",
            "c.geojson",
        ],
    );
    let e = err(&o);
    assert!(o.status.success(), "{e}");
    for line in e.lines().filter(|l| !l.contains(" in ")) {
        assert!(longest_digits(line) <= 3, "{line}");
    }
}
