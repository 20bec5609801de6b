//! Issue 13, items 6–10: nonsense numbers, damaged files that decode, messages that say what is
//! wrong, temporary files of killed runs, and the bounded checker of streaming meshes; issue 41:
//! damaged COPC hierarchies, point sets with no triangle or far from 0; through the command line.
//! docs/RELIABILITY.md lists the cases and these tests.

use crate::data;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

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

/// `grid.xyz`: 50 × 50 points 1 m apart.
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

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

// ---- Item 6: nonsense numbers ----------------------------------------------------------------

#[test]
fn nonsense_numbers_are_refused_and_far_heights_warned() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let o = run(dir, &["dem", "grid.xyz", "-o", "d.tif", "-q"]);
    assert_eq!(code(&o), 0, "{}", err(&o));
    let cases: &[&[&str]] = &[
        &["hillshade", "d.tif", "-o", "h.png", "--z-factor", "nan"],
        &["hillshade", "d.tif", "-o", "h.png", "--z-factor", "inf"],
        &["hillshade", "d.tif", "-o", "h.png", "--z-factor", "0"],
        &["hillshade", "d.tif", "-o", "h.png", "--altitude", "nan"],
        &["hillshade", "d.tif", "-o", "h.png", "--altitude", "1000"],
        &["hillshade", "d.tif", "-o", "h.png", "--altitude=-90"],
        &["hillshade", "d.tif", "-o", "h.png", "--azimuth", "inf"],
        &["tin", "grid.xyz", "-o", "t.ply", "--max-edge", "0"],
        &["tin", "grid.xyz", "-o", "t.ply", "--max-edge", "nan"],
        &["tin", "grid.xyz", "-o", "t.ply", "--z-tolerance", "nan"],
        &["volume", "grid.xyz", "--plane", "nan"],
        &["crossval", "grid.xyz", "--samples", "0"],
    ];
    for args in cases {
        let o = run(dir, args);
        assert_eq!(code(&o), 2, "{args:?}: {}", err(&o));
        let e = err(&o);
        assert!(!e.contains("18446744073709551615"), "{args:?}: {e}");
        assert!(!e.contains("cannot triangulate"), "{args:?}: {e}");
    }
    assert_eq!(names(dir), ["d.tif", "grid.xyz"]);
    // Breakline heights a million metres away from points at 0–0.6 m: a warning, not silence.
    std::fs::write(dir.join("l.txt"), "5 5 1000000\n40 40 -1000000\n").unwrap();
    let o = run(
        dir,
        &["tin", "grid.xyz", "--breaklines", "l.txt", "-o", "t.ply"],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    assert!(err(&o).contains("far outside"), "{}", err(&o));
}

// ---- Item 7: damaged LAZ that decodes --------------------------------------------------------

#[test]
fn damaged_lidar_is_corrupt_not_truncated_nor_duplicates() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let good = std::fs::read(data::shared("lidar/ahn3_delft_cropped_2.laz")).unwrap();
    let n = good.len();
    let mut zeroed = good.clone();
    zeroed[n * 2 / 5..n * 3 / 5].fill(0);
    let mut flipped = good.clone();
    let mut r = 1u64;
    for _ in 0..200 {
        r = r
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let k = n / 10 + (r >> 33) as usize % (n * 8 / 10);
        flipped[k] ^= 0xff;
    }
    std::fs::write(dir.join("zeroed.laz"), &zeroed).unwrap();
    std::fs::write(dir.join("flipped.laz"), &flipped).unwrap();
    std::fs::write(dir.join("cut.laz"), &good[..n * 9 / 10]).unwrap();
    for (file, want) in [
        ("zeroed.laz", "corrupt"),
        ("flipped.laz", "corrupt"),
        ("cut.laz", "truncated"),
    ] {
        let o = run(dir, &["tin", file, "-o", "t.ply"]);
        assert_eq!(code(&o), 3, "{file}: {}", err(&o));
        let e = err(&o);
        assert!(e.contains(want) && e.contains(file), "{file}: {e}");
        if want == "corrupt" {
            assert!(
                e.contains("chunk") && !e.contains("truncated"),
                "{file}: {e}"
            );
        }
    }
    // An uncompressed LAS whose points leave the header's bounds, or claim return 3 of 1.
    let las = std::fs::read(data::shared(
        "lidar/ign_50m_tiles/test_data_77055_627760_LA93_IGN69_ground.las",
    ))
    .unwrap();
    let f64_at = |b: &[u8], at: usize| f64::from_le_bytes(b[at..at + 8].try_into().unwrap());
    let mut narrow = las.clone();
    let min_x = f64_at(&las, 187);
    narrow[179..187].copy_from_slice(&(min_x + 1.0).to_le_bytes()); // max x = min x + 1 m
    std::fs::write(dir.join("bounds.las"), &narrow).unwrap();
    let mut returns = las.clone();
    let data_at = u32::from_le_bytes(las[96..100].try_into().unwrap()) as usize;
    returns[data_at + 14] = 3 | (1 << 3); // point 0: return 3 of 1
    std::fs::write(dir.join("returns.las"), &returns).unwrap();
    for (file, want) in [
        ("bounds.las", "outside the header's bounds"),
        ("returns.las", "return number 3 of 1"),
    ] {
        let o = run(dir, &["tin", file, "-o", "t.ply"]);
        assert_eq!(code(&o), 3, "{file}: {}", err(&o));
        let e = err(&o);
        assert!(
            e.contains("corrupt point data") && e.contains(want),
            "{file}: {e}"
        );
    }
    assert!(!dir.join("t.ply").exists());
}

// ---- Item 8: messages ------------------------------------------------------------------------

#[test]
fn messages_say_what_the_file_is_and_name_it_once() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let o = run(dir, &["dem", "grid.xyz", "-o", "d.tif", "-q"]);
    assert_eq!(code(&o), 0);
    let tif = std::fs::read(dir.join("d.tif")).unwrap();
    std::fs::write(dir.join("cut.tif"), &tif[..tif.len() / 2]).unwrap();
    let o = run(dir, &["hillshade", "d.tif", "-o", "h.png"]);
    assert_eq!(code(&o), 0, "{}", err(&o));
    let npz = data::shared("dem/matplotlib_topobathy.npz");
    let cases: &[(&[&str], &str)] = &[
        (
            &["tin", "d.tif", "-o", "t.ply"],
            "is a TIFF image, not XYZ text",
        ),
        (
            &["simplify", "h.png", "-o", "s.ply", "--max-error", "1"],
            "is a PNG image",
        ),
        (
            &[
                "simplify",
                npz.to_str().unwrap(),
                "-o",
                "s.ply",
                "--max-error",
                "1",
            ],
            "ZIP archive",
        ),
        (
            &["simplify", "cut.tif", "-o", "s.ply", "--max-error", "1"],
            "truncated",
        ),
        (&["hillshade", "cut.tif", "-o", "h2.png"], "truncated"),
    ];
    for (args, want) in cases {
        let o = run(dir, args);
        assert_eq!(code(&o), 3, "{args:?}: {}", err(&o));
        let e = err(&o);
        assert!(e.contains(want), "{args:?}: {e}");
        assert!(
            !e.contains("failed to fill") && !e.contains("UTF-8"),
            "{args:?}: {e}"
        );
        assert!(
            !e.contains('\u{0}') && !e.contains('\u{fffd}'),
            "{args:?}: {e}"
        );
    }
    // A breakline error names its file once, without "cannot triangulate" around it.
    std::fs::write(
        dir.join("bad.geojson"),
        r#"{"type":"Point","coordinates":[1,2]}"#,
    )
    .unwrap();
    let o = run(
        dir,
        &[
            "tin",
            "grid.xyz",
            "--breaklines",
            "bad.geojson",
            "-o",
            "t.ply",
        ],
    );
    assert_eq!(code(&o), 3, "{}", err(&o));
    let e = err(&o);
    assert_eq!(e.matches("bad.geojson").count(), 1, "{e}");
    assert!(
        !e.contains("cannot triangulate") && !e.contains("grid.xyz"),
        "{e}"
    );
}

// ---- Item 9: temporary files of killed runs, memory limits -----------------------------------

#[cfg(unix)]
#[test]
fn a_killed_runs_temporary_file_is_removed_by_the_next_run() {
    use std::time::{Duration, Instant};
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let fifo = dir.join("points.xyz");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    // The run creates its temporary output, then blocks opening the FIFO: kill -9 it there.
    let mut child = sweeptin()
        .current_dir(dir)
        .args(["tin", "points.xyz", "-o", "out.ply", "-q"])
        .spawn()
        .unwrap();
    let pid = child.id();
    let started = Instant::now();
    let temp = loop {
        if let Some(t) = names(dir)
            .into_iter()
            .find(|n| n.starts_with(".out.ply.sweeptin-"))
        {
            break t;
        }
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "no temporary file"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!(
        temp.contains(&format!(".{pid}-")),
        "{temp} lacks the pid {pid}"
    );
    child.kill().unwrap(); // SIGKILL: no clean-up possible
    child.wait().unwrap();
    assert!(dir.join(&temp).exists());
    let o = run(dir, &["tin", "grid.xyz", "-o", "out.ply", "-q"]);
    assert_eq!(code(&o), 0, "{}", err(&o));
    assert_eq!(names(dir), ["grid.xyz", "out.ply", "points.xyz"]);
}

/// Under a memory limit below --mem the sort's chunk cannot be had: a message and exit 4, before
/// reading, with no temporary file left (it was an abort, exit 134, with the file left).
#[cfg(unix)]
#[test]
fn a_memory_limit_below_the_budget_is_a_message_not_an_abort() {
    let d = tempfile::tempdir().unwrap();
    let arso = data::shared("lidar/arso_TM_511_122_sw_250m.laz");
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 400000 && exec '{}' tin '{}' -o '{}' --mem 8G -q",
            env!("CARGO_BIN_EXE_sweeptin"),
            arso.display(),
            d.path().join("out.ply").display()
        ))
        .output()
        .unwrap();
    assert_eq!(code(&o), 4, "{}", err(&o));
    assert!(err(&o).contains("cannot allocate"), "{}", err(&o));
    assert!(names(d.path()).is_empty(), "{:?}", names(d.path()));
}

/// A limit just above --mem leaves no room for the program itself (its code, threads' stacks,
/// allocator arenas): refused before any work, naming a --mem that fits (it was an abort, exit
/// 134, "memory allocation failed", whatever --mem). Without --mem, the budget follows the
/// limit and the job runs, tiled or swept.
#[cfg(unix)]
#[test]
fn an_address_space_limit_sets_the_default_budget_and_refuses_a_larger_one() {
    let d = tempfile::tempdir().unwrap();
    let arso = data::shared("lidar/arso_TM_511_122_sw_250m.laz");
    let small = data::shared("lidar/startinpy_small.laz");
    let limited = |limit: u32, args: &str| {
        Command::new("sh")
            .current_dir(d.path())
            .arg("-c")
            .arg(format!(
                "ulimit -v {limit} && exec '{}' {args}",
                env!("CARGO_BIN_EXE_sweeptin"),
            ))
            .output()
            .unwrap()
    };
    let a = arso.display();
    let o = limited(
        270_000,
        &format!("dem '{a}' --cell 1 --mem 256M -o a.tif -q"),
    );
    assert_eq!(code(&o), 4, "{}", err(&o));
    assert!(err(&o).contains("give --mem 135M or less"), "{}", err(&o));
    let o = limited(
        200_000,
        &format!("tin '{a}' --mem 128M -o a.ply -q --engine sweep"),
    );
    assert_eq!(code(&o), 4, "{}", err(&o));
    assert!(names(d.path()).is_empty(), "{:?}", names(d.path()));
    // `ground` too (it aborted, exit 134, "memory allocation of 40992640 bytes failed").
    let o = limited(200_000, &format!("ground '{a}' --mem 128M -o g.laz -q"));
    assert_eq!(code(&o), 4, "{}", err(&o));
    assert!(
        err(&o).contains("classification's memory budget"),
        "{}",
        err(&o)
    );
    assert!(names(d.path()).is_empty(), "{:?}", names(d.path()));
    let s = small.display();
    for (engine, out) in [("tiles", "t.tif"), ("sweep", "s.tif")] {
        let o = limited(
            200_000,
            &format!("dem '{s}' --cell 1 --engine {engine} -o {out} -q --json"),
        );
        assert_eq!(code(&o), 0, "{engine}: {}", err(&o));
    }
    let (t, w) = (
        std::fs::read(d.path().join("t.tif")).unwrap(),
        std::fs::read(d.path().join("s.tif")).unwrap(),
    );
    assert!(t == w, "the tiled and swept DEMs differ");
}

/// `refine` holds its mesh in memory: under an address-space limit too small for it, each step
/// checks for room (collecting the input mesh, the TIN, the surface's grid, the growing mesh,
/// the output) and fails with exit 4, leaving nothing; it was an abort (exit 134, "memory
/// allocation of N bytes failed"). With room enough, the same job runs.
#[cfg(unix)]
#[test]
fn refine_under_a_memory_limit_is_a_message_not_an_abort() {
    let d = tempfile::tempdir().unwrap();
    let arso = data::shared("lidar/arso_TM_511_122_sw_250m.laz");
    let refine = |limit: u32, out: &str| {
        Command::new("sh")
            .current_dir(d.path())
            .arg("-c")
            .arg(format!(
                "ulimit -v {limit} && exec '{}' refine '{}' --class 2 --min-angle 25 \
                 --bbox 511000,122000,511250,122250 -o {out} -q",
                env!("CARGO_BIN_EXE_sweeptin"),
                arso.display(),
            ))
            .output()
            .unwrap()
    };
    for limit in [330_000, 400_000] {
        let o = refine(limit, "small.ply");
        assert_eq!(code(&o), 4, "under {limit} KiB: {}", err(&o));
        assert!(err(&o).contains("cannot allocate"), "{}", err(&o));
        assert!(names(d.path()).is_empty(), "{:?}", names(d.path()));
    }
    let o = refine(800_000, "fits.ply");
    assert_eq!(code(&o), 0, "{}", err(&o));
}

// ---- Item 10: the bounded checker of streaming meshes ----------------------------------------

#[test]
fn streaming_meshes_are_checked_in_bounded_memory() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let laz = data::shared("lidar/startinpy_small.laz");
    let o = sweeptin()
        .current_dir(dir)
        .args(["tin", "-q", "-o", "m.stin"])
        .arg(&laz)
        .output()
        .unwrap();
    assert_eq!(code(&o), 0, "{}", err(&o));
    let o = run(dir, &["check", "m.stin"]);
    assert_eq!(code(&o), 0, "{}", err(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("valid (39232 vertices, 78430 triangles"),
        "{out}"
    );
    let held: u64 = out
        .split("at most ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    assert!(
        held < 39232 / 4,
        "held {held} vertices: not bounded by the front"
    );
    // Swap two corners of a triangle record: clockwise, named.
    let mut b = std::fs::read(dir.join("m.stin")).unwrap();
    let at = (32..b.len())
        .step_by(32)
        .find(|&i| b[i] == 2)
        .expect("a triangle record");
    let (c1, c2) = (b[at + 16..at + 24].to_vec(), b[at + 24..at + 32].to_vec());
    b[at + 16..at + 24].copy_from_slice(&c2);
    b[at + 24..at + 32].copy_from_slice(&c1);
    std::fs::write(dir.join("bad.stin"), &b).unwrap();
    let o = run(dir, &["check", "bad.stin"]);
    assert_eq!(code(&o), 3, "{}", err(&o));
    assert!(err(&o).contains("counter-clockwise"), "{}", err(&o));
    let help = run(dir, &["check", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("Memory:") && help.contains(".stin"), "{help}");
}

/// Header boxes that say nothing (all zero, as some writers leave them; inverted) do not decide
/// a DEM's grid, which the points decide: the same raster as with true boxes, beside a file
/// with a true box too (the union stretched to (0, 0) and the grid was refused). A box far
/// larger than its points is refused before reading, naming the headers' box and the way out
/// (`--bbox`, or repairing the header).
#[test]
fn header_boxes_that_say_nothing_do_not_decide_the_grid() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let tiles = data::shared("lidar/ign_50m_tiles");
    let a = std::fs::read(tiles.join("test_data_77055_627760_LA93_IGN69_ground.las")).unwrap();
    let b = tiles.join("test_data_77060_627760_LA93_IGN69_ground.las");
    std::fs::write(dir.join("a.las"), &a).unwrap();
    let f64_at = |at: usize| f64::from_le_bytes(a[at..at + 8].try_into().unwrap());
    // max x, min x, max y, min y, max z, min z from byte 179.
    let with_box = |name: &str, v: [f64; 6]| {
        let mut c = a.clone();
        for (k, x) in v.iter().enumerate() {
            c[179 + 8 * k..187 + 8 * k].copy_from_slice(&x.to_le_bytes());
        }
        std::fs::write(dir.join(name), c).unwrap();
    };
    with_box("zero.las", [0.0; 6]);
    let (x0, y0) = (f64_at(187), f64_at(203));
    with_box(
        "inverted.las",
        [x0, f64_at(179), y0, f64_at(195), 0.0, 100.0],
    );
    with_box("huge.las", [x0 + 1e6, x0, y0 + 1e6, y0, 1e4, 0.0]);
    let b = b.to_str().unwrap();
    for engine in ["tiles", "sweep"] {
        let dem = |file: &str, out: &str| {
            let o = run(
                dir,
                &[
                    "dem", file, b, "--cell", "0.5", "--engine", engine, "-q", "-o", out,
                ],
            );
            assert_eq!(code(&o), 0, "{file} {engine}: {}", err(&o));
            std::fs::read(dir.join(out)).unwrap()
        };
        let want = dem("a.las", "a.tif");
        assert!(dem("zero.las", "z.tif") == want, "zero box, {engine}");
        assert!(
            dem("inverted.las", "i.tif") == want,
            "inverted box, {engine}"
        );
        let o = run(
            dir,
            &[
                "dem", "huge.las", b, "--cell", "0.5", "--engine", engine, "-o", "h.tif",
            ],
        );
        assert_eq!(code(&o), 2, "{engine}: {}", err(&o));
        let e = err(&o);
        assert!(
            e.contains("header") && e.contains("--bbox") && e.contains("--max-cells"),
            "{engine}: {e}"
        );
        assert!(!dir.join("h.tif").exists());
    }
    // A mesh too: the tiles' grid from the one true box, the same triangles as the sweep's.
    let tin = |file: &str, engine: &str| {
        let out = format!("{engine}.ply");
        let o = run(dir, &["tin", file, b, "--engine", engine, "-q", "-o", &out]);
        assert_eq!(code(&o), 0, "{file} {engine}: {}", err(&o));
        let o = run(dir, &["check", &out]);
        assert_eq!(code(&o), 0, "{}", err(&o));
        let s = String::from_utf8_lossy(&o.stdout).into_owned();
        // "x.ply: valid (V vertices, T triangles)": the counts, whatever the name.
        s[s.find(':').unwrap()..].to_string()
    };
    assert_eq!(tin("zero.las", "tiles"), tin("a.las", "sweep"));
    // A plan places files by their boxes without reading them: one that says nothing is refused.
    let o = run(
        dir,
        &[
            "plan", "dem", "zero.las", b, "--cell", "1", "--tile", "100", "-o", "job",
        ],
    );
    assert_eq!(code(&o), 3, "{}", err(&o));
    assert!(err(&o).contains("zero.las") && err(&o).contains("says nothing"));
    // Nor may such a box prove that a file misses --bbox: its points were skipped without a
    // word beside another file (exit 0, half the DEM nodata). The box straddles both tiles.
    let bbox = format!("{},{},{},{}", x0 + 30.0, y0 + 10.0, x0 + 70.0, y0 + 40.0);
    let clip = |file: &str, out: &str| {
        let o = run(
            dir,
            &[
                "dem", file, b, "--cell", "0.5", "--bbox", &bbox, "-q", "-o", out,
            ],
        );
        assert_eq!(code(&o), 0, "{file}: {}", err(&o));
        std::fs::read(dir.join(out)).unwrap()
    };
    assert!(clip("zero.las", "zb.tif") == clip("a.las", "ab.tif"));
    // A virtual point cloud places files by these boxes: refused, never written with them.
    let o = run(dir, &["index", "zero.las", b, "-o", "z.vpc"]);
    assert_eq!(code(&o), 3, "{}", err(&o));
    assert!(err(&o).contains("zero.las") && err(&o).contains("says nothing"));
    assert!(!dir.join("z.vpc").exists());
}

// ---- Issue 41: damaged COPC hierarchies, degenerate and far point sets -----------------------

/// COPC file `from` with one hierarchy entry rewritten by `edit` (given the entry's key, offset,
/// byte size and point count; it returns the new ones), for the entry whose key is `key` in the
/// page at `page` (the root page when `None`).
fn edited_copc(
    from: &Path,
    to: &Path,
    key: [i32; 4],
    page: Option<[i32; 4]>,
    edit: impl Fn([i32; 4], u64, i32, i32) -> ([i32; 4], u64, i32, i32),
) -> PathBuf {
    let mut d = std::fs::read(from).unwrap();
    let u16_at = |d: &[u8], o: usize| u16::from_le_bytes(d[o..o + 2].try_into().unwrap());
    let u64_at = |d: &[u8], o: usize| u64::from_le_bytes(d[o..o + 8].try_into().unwrap());
    let i32_at = |d: &[u8], o: usize| i32::from_le_bytes(d[o..o + 4].try_into().unwrap());
    // The info VLR is the first VLR (54-byte header); the root page's offset and size are its
    // sixth and seventh 8-byte fields.
    let info = usize::from(u16_at(&d, 94)) + 54;
    let (mut at, mut len) = (
        u64_at(&d, info + 40) as usize,
        u64_at(&d, info + 48) as usize,
    );
    let entry = |d: &[u8], e: usize| {
        let k = [
            i32_at(d, e),
            i32_at(d, e + 4),
            i32_at(d, e + 8),
            i32_at(d, e + 12),
        ];
        (k, u64_at(d, e + 16), i32_at(d, e + 24), i32_at(d, e + 28))
    };
    if let Some(p) = page {
        let e = (at..at + len)
            .step_by(32)
            .find(|e| entry(&d, *e).0 == p && entry(&d, *e).3 == -1)
            .expect("the page's entry");
        (at, len) = (entry(&d, e).1 as usize, entry(&d, e).2 as usize);
    }
    let e = (at..at + len)
        .step_by(32)
        .find(|e| entry(&d, *e).0 == key)
        .expect("the entry");
    let (k, offset, bytes, count) = entry(&d, e);
    let (k, offset, bytes, count) = edit(k, offset, bytes, count);
    for (i, v) in k.iter().enumerate() {
        d[e + 4 * i..e + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
    d[e + 16..e + 24].copy_from_slice(&offset.to_le_bytes());
    d[e + 24..e + 28].copy_from_slice(&bytes.to_le_bytes());
    d[e + 28..e + 32].copy_from_slice(&count.to_le_bytes());
    std::fs::write(to, d).unwrap();
    to.to_path_buf()
}

/// A COPC hierarchy whose keys do not make one octree — a node listed twice (key 1-0-0-0
/// rewritten as 1-1-1-1: a box read dropped the 4,279 points of 1-0-0-0, exit 0), a node whose
/// parent is not listed, a node in another node's page, a key outside the octree, point counts
/// that do not add up to the header's — is refused, exit 3, naming the file and the key, by
/// `info` as by a box read (which would skip the moved node's points). A leaf moved to a free
/// key under a listed parent still makes an octree: its points, once decoded, lie outside its
/// node's square, and are refused there.
#[test]
fn copc_hierarchies_with_moved_or_duplicated_keys_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let copc =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/lidR_Topography.copc.laz");
    let to = |k: [i32; 4]| move |_, o, b, c| (k, o, b, c);
    let moved = edited_copc(&copc, &d("moved.laz"), [2, 2, 2, 1], None, to([2, 0, 0, 0]));
    let cases = [
        (
            edited_copc(&copc, &d("twice.laz"), [1, 0, 0, 0], None, to([1, 1, 1, 1])),
            "node 1-1-1-1 has two entries",
        ),
        (
            edited_copc(
                &copc,
                &d("orphans.laz"),
                [1, 1, 1, 0],
                None,
                to([2, 0, 0, 0]),
            ),
            "node 2-2-2-1 has no parent: node 1-1-1-0 is not in the hierarchy",
        ),
        (
            moved.clone(),
            "node 2-2-2-1 is listed in the hierarchy page of node 2-0-0-0",
        ),
        (
            edited_copc(
                &copc,
                &d("outside.laz"),
                [1, 0, 0, 0],
                None,
                to([1, 2, 0, 0]),
            ),
            "node 1-2-0-0 lies outside the octree",
        ),
        (
            edited_copc(&copc, &d("count.laz"), [0, 0, 0, 0], None, |k, o, b, c| {
                (k, o, b, c + 1)
            }),
            "the hierarchy's nodes hold 73404 points, but the header announces 73403",
        ),
        (
            edited_copc(
                &moved,
                &d("leaf.laz"),
                [2, 2, 2, 1],
                Some([2, 0, 0, 0]),
                to([2, 0, 0, 0]),
            ),
            "lies outside the square of its octree node 2-0-0-0",
        ),
    ];
    let bbox = "273400,5274400,273480,5274480";
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let out = s(&d("out.ply"));
    let out = out.as_str();
    for (file, want) in &cases {
        let f = s(file);
        let f = f.as_str();
        let leaf = file.ends_with("leaf.laz");
        let mut runs = vec![
            vec!["tin", f, "-o", out],
            vec!["tin", f, "--bbox", bbox, "-o", out],
        ];
        if !leaf {
            // `info` does not decode points: the leaf's damage shows only when they are.
            runs.push(vec!["info", f]);
        }
        for args in runs {
            let o = run(dir.path(), &args);
            let e = err(&o);
            assert_eq!(code(&o), 3, "{args:?}: {e}");
            assert!(e.contains(f) && e.contains(want), "{args:?}: {e}");
        }
    }
    // The file unedited reads through its index.
    let o = run(dir.path(), &["tin", &s(&copc), "--bbox", bbox, "-o", out]);
    assert_eq!(code(&o), 0, "{}", err(&o));
}

/// A LAS 1.2 file (format 0) of points `pts`, stored with `offset` and `scale` on every axis.
fn write_las(path: &Path, offset: [f64; 3], scale: f64, pts: &[[f64; 3]]) {
    use las::{Builder, Point, Transform, Vector, Writer};
    let mut b = Builder::from((1, 2));
    let t = |offset| Transform { scale, offset };
    b.transforms = Vector {
        x: t(offset[0]),
        y: t(offset[1]),
        z: t(offset[2]),
    };
    let mut w = Writer::from_path(path, b.into_header().unwrap()).unwrap();
    for p in pts {
        w.write_point(Point {
            x: p[0],
            y: p[1],
            z: p[2],
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
}

/// One point, two, three on one line (across, along an axis), three at one position: facts
/// about the points, exit 3 saying what is wrong with them, with either engine, for a mesh and
/// a DEM (the tiles engine derived blocks of 9.3e-10 from a box of no area and refused its own
/// tile size, exit 2: "the tile size must be a positive number, not 1", "tiles of 9.3e-10 are
/// too small"; a DEM said its grid had no cell, exit 2). Points near 10^15 (inside the range
/// of 2^52) run in tiles as in the sweep: the blocks are no finer than their keys allow there
/// (it was "tiles of 256 are too small", exit 2).
#[test]
fn points_with_no_triangle_or_far_from_zero_are_facts_not_options() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let (x, y) = (500_000.0, 5_000_000.0);
    let utm = [x, y, 0.0];
    let cases: [(&str, Vec<[f64; 3]>, &str); 5] = [
        ("one.las", vec![[x, y, 3.0]], "fewer than 3 distinct points"),
        (
            "two.las",
            vec![[x, y, 3.0], [x + 10.0, y, 4.0]],
            "fewer than 3 distinct points",
        ),
        (
            "along.las",
            vec![[x, y, 3.0], [x, y + 1.0, 4.0], [x, y + 2.0, 5.0]],
            "collinear",
        ),
        (
            "across.las",
            vec![
                [x, y, 3.0],
                [x + 1.0, y + 1.0, 4.0],
                [x + 2.0, y + 2.0, 5.0],
            ],
            "collinear",
        ),
        (
            "same.las",
            vec![[x, y, 3.0], [x, y, 3.0], [x, y, 3.0]],
            "fewer than 3 distinct points",
        ),
    ];
    for (name, pts, want) in &cases {
        write_las(&dir.join(name), utm, 0.01, pts);
        for engine in ["tiles", "sweep"] {
            for (args, out) in [
                (vec!["tin", name, "-o", "t.ply"], "t.ply"),
                (vec!["dem", name, "--cell", "1", "-o", "d.tif"], "d.tif"),
            ] {
                let o = run(dir, &[&args[..], &["--engine", engine]].concat());
                let e = err(&o);
                assert_eq!(code(&o), 3, "{name} {args:?} {engine}: {e}");
                // A DEM's grid over points of no area has no cell: it says so.
                let dem = args[0] == "dem" && !name.starts_with("across");
                let want = if dem { "span no area" } else { want };
                assert!(
                    e.contains(name) && e.contains(want),
                    "{name} {args:?} {engine}: {e}"
                );
                assert!(!dir.join(out).exists());
            }
        }
    }
    // Near 10^15: a grid of 40 × 40 points 25 apart, in eighths (exact there).
    let far = 1e15;
    let pts: Vec<[f64; 3]> = (0..1600)
        .map(|i| {
            let (i, j) = (f64::from(i % 40), f64::from(i / 40));
            [far + 25.0 * i + 0.125 * j, far + 25.0 * j, (i * j) % 7.0]
        })
        .collect();
    write_las(&dir.join("far.las"), [far, far, 0.0], 0.125, &pts);
    let mut meshes = Vec::new();
    let mut dems = Vec::new();
    for engine in ["tiles", "sweep"] {
        let (mesh, dem) = (format!("{engine}.ply"), format!("{engine}.tif"));
        for args in [
            vec!["tin", "far.las", "-o", &mesh],
            vec!["dem", "far.las", "--cell", "5", "-o", &dem],
        ] {
            let o = run(dir, &[&args[..], &["--engine", engine, "-q"]].concat());
            assert_eq!(code(&o), 0, "{args:?} {engine}: {}", err(&o));
        }
        let o = run(dir, &["check", &mesh]);
        assert_eq!(code(&o), 0, "{}", err(&o));
        let s = String::from_utf8_lossy(&o.stdout).into_owned();
        meshes.push(s[s.find(':').unwrap()..].to_string());
        dems.push(std::fs::read(dir.join(&dem)).unwrap());
    }
    assert_eq!(meshes[0], meshes[1]);
    assert!(meshes[0].contains("1600 vertices"), "{}", meshes[0]);
    assert!(dems[0] == dems[1], "the DEMs of the two engines differ");
}

// ---- Issue 41, item 1: the lists and `.vpc` files that name the inputs are inputs ------------

#[test]
fn outputs_never_overwrite_a_file_list_a_vpc_or_a_file_they_name() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    grid(dir);
    let sample = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz");
    std::fs::copy(sample, dir.join("a.laz")).unwrap();
    std::fs::write(dir.join("list.txt"), "grid.xyz\n").unwrap();
    std::fs::write(dir.join("outer.txt"), "@list.txt\n").unwrap();
    std::fs::write(dir.join("laz.txt"), "a.laz\n").unwrap();
    let o = run(dir, &["index", "a.laz", "-o", "tiles.vpc"]);
    assert_eq!(code(&o), 0, "{}", err(&o));
    let o = run(
        dir,
        &[
            "plan", "dem", "@laz.txt", "--cell", "1", "--tile", "100", "-o", "job",
        ],
    );
    assert_eq!(code(&o), 0, "{}", err(&o));
    let kept = [
        "list.txt",
        "outer.txt",
        "laz.txt",
        "tiles.vpc",
        "a.laz",
        "grid.xyz",
    ];
    let before: Vec<Vec<u8>> = kept
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect();
    let cases: &[&[&str]] = &[
        // The list itself (it was replaced by the mesh, exit 0), also named by another list.
        &[
            "tin",
            "@list.txt",
            "-o",
            "list.txt",
            "--format",
            "obj",
            "-q",
        ],
        &[
            "tin",
            "@outer.txt",
            "-o",
            "list.txt",
            "--format",
            "obj",
            "-q",
        ],
        &[
            "tin",
            "@outer.txt",
            "-o",
            "outer.txt",
            "--format",
            "obj",
            "-q",
        ],
        &[
            "dem",
            "@list.txt",
            "--cell",
            "1",
            "-o",
            "d.tif",
            "--contours",
            "list.txt",
        ],
        &[
            "products",
            "@list.txt",
            "--cell",
            "1",
            "--dem",
            "d.tif",
            "--mesh",
            "list.txt",
        ],
        &[
            "thin",
            "@list.txt",
            "--max-error",
            "0.1",
            "-o",
            "list.txt",
            "--format",
            "ply",
        ],
        &["refine", "@list.txt", "-o", "list.txt", "--format", "ply"],
        // A `.vpc` rewrote itself; a run over it replaced one of its files.
        &["index", "tiles.vpc", "-o", "tiles.vpc"],
        &["tin", "tiles.vpc", "-o", "a.laz", "--format", "ply", "-q"],
        &[
            "dem", "@laz.txt", "--cell", "1", "-o", "laz.txt", "--format", "asc",
        ],
        // A plan's outputs, when it is made and when it is merged.
        &[
            "plan",
            "dem",
            "@laz.txt",
            "--cell",
            "1",
            "--tile",
            "100",
            "--contours",
            "laz.txt",
            "-o",
            "p",
        ],
        &[
            "plan",
            "dem",
            "tiles.vpc",
            "--cell",
            "1",
            "--tile",
            "100",
            "--contours",
            "tiles.vpc",
            "-o",
            "p",
        ],
        &["merge", "job/plan.json", "-o", "laz.txt"],
    ];
    for args in cases {
        let o = run(dir, args);
        assert_eq!(code(&o), 2, "{args:?}: {}", err(&o));
        assert!(err(&o).contains("an input"), "{args:?}: {}", err(&o));
    }
    for (f, b) in kept.iter().zip(&before) {
        assert_eq!(&std::fs::read(dir.join(f)).unwrap(), b, "{f} was replaced");
    }
    assert!(!dir.join("d.tif").exists() && !dir.join("p").exists());
}
