//! `--ground` in the triangulating commands and in `height`: the ground found on the fly equals
//! `sweeptin ground` then `--class 2`, byte for byte, for any `--threads` and `--mem`; what it
//! refuses (exit 2).

use crate::cli;
use crate::data;

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::input::las::{Filter, LidarReader};

fn run(args: &[&OsStr]) {
    cli::ok(args);
}

fn os(s: &str) -> &OsStr {
    OsStr::new(s)
}

/// The exit status and stderr of `sweeptin ARGS`.
fn status(args: &[&OsStr]) -> (i32, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// `ground FILES --odir DIR EXTRA` then the classified files.
fn ground_route(files: &[PathBuf], dir: &Path, extra: &[&str]) -> Vec<PathBuf> {
    let mut args: Vec<&OsStr> = vec![os("ground")];
    args.extend(files.iter().map(|f| f.as_os_str()));
    args.extend([os("--odir"), dir.as_os_str(), os("-q")]);
    args.extend(extra.iter().map(|s| os(s)));
    run(&args);
    files
        .iter()
        .map(|f| dir.join(f.file_name().unwrap()))
        .collect()
}

/// `dem FILES --cell 1 -o OUT EXTRA`, the raster's bytes.
fn dem(files: &[PathBuf], out: &Path, extra: &[&str]) -> Vec<u8> {
    let mut args: Vec<&OsStr> = vec![os("dem")];
    args.extend(files.iter().map(|f| f.as_os_str()));
    args.extend([os("--cell"), os("1"), os("-o"), out.as_os_str(), os("-q")]);
    args.extend(extra.iter().map(|s| os(s)));
    run(&args);
    std::fs::read(out).unwrap()
}

#[test]
fn dem_with_ground_equals_ground_then_dem_class_2_for_any_threads_and_mem() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // One file with its own (professional) classes, and six adjacent tiles given together (a
    // block's buffer reaches into the next file; the global indices run across the files).
    let cases: [(Vec<PathBuf>, &[&str]); 2] = [
        (vec![data::shared("lidar/startinpy_small.laz")], &[]),
        (data::ign_tiles(), &["--step", "2"]),
    ];
    for (k, (files, params)) in cases.iter().enumerate() {
        let classified = d.join(format!("classified{k}"));
        std::fs::create_dir(&classified).unwrap();
        let routed = ground_route(files, &classified, params);
        let want = dem(&routed, &d.join("route.tif"), &["--class", "2"]);
        for run in [
            vec!["--threads", "2", "--mem", "1G"],
            vec!["--threads", "1", "--mem", "24M"],
        ] {
            let mut extra = vec!["--ground"];
            extra.extend(params.iter());
            extra.extend(run.iter());
            let got = dem(files, &d.join("fly.tif"), &extra);
            assert!(got == want, "case {k}, {extra:?}: the DEMs differ");
        }
        // --class with --ground selects among the classes `ground` writes.
        let want = dem(&routed, &d.join("route12.tif"), &["--class", "1,2"]);
        let mut extra = vec!["--ground", "--class", "1,2"];
        extra.extend(params.iter());
        assert!(
            dem(files, &d.join("fly12.tif"), &extra) == want,
            "case {k}, --class 1,2"
        );
    }
}

/// Every point's `HeightAboveGround` (NaN outside the ground) by index.
fn heights(path: &Path) -> Vec<(u64, f64)> {
    let f = Filter {
        z_from: Some("HeightAboveGround".into()),
        ..Filter::keep_all()
    };
    let pts = LidarReader::open(&[path], &f).unwrap().read_all().unwrap();
    pts.iter().map(|p| (p.index, p.z)).collect()
}

#[test]
fn height_with_ground_equals_ground_then_height() {
    let input = data::shared("lidar/startinpy_small.laz");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let routed = ground_route(std::slice::from_ref(&input), d, &[]);
    let (a, b) = (d.join("route_hag.laz"), d.join("fly_hag.laz"));
    run(&[
        os("height"),
        routed[0].as_os_str(),
        os("-o"),
        a.as_os_str(),
        os("-q"),
    ]);
    run(&[
        os("height"),
        input.as_os_str(),
        os("--ground"),
        os("--mem"),
        os("24M"),
        os("-o"),
        b.as_os_str(),
        os("-q"),
    ]);
    let (want, got) = (heights(&a), heights(&b));
    assert!(want.len() > 39_000, "{} heights", want.len());
    assert_eq!(want, got);
    // The file's own classes are kept: only the heights are added.
    let read = |p: &Path| -> Vec<u8> {
        let r = LidarReader::open(&[p], &Filter::keep_all())
            .unwrap()
            .read_all();
        r.unwrap().iter().map(|p| p.classification).collect()
    };
    assert_eq!(read(&input), read(&b));
}

#[test]
fn ground_is_refused_where_it_cannot_be_exact_and_its_options_without_it() {
    let input = data::shared("lidar/startinpy_small.laz");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out.tif");
    let xyz = d.join("p.xyz");
    std::fs::write(&xyz, "0 0 0\n1 0 0\n0 1 1\n").unwrap();
    let plan = d.join("plan");
    let cases: Vec<(Vec<&OsStr>, &str)> = vec![
        // The ground filter's options without --ground.
        (
            vec![
                os("dem"),
                input.as_os_str(),
                os("--cell"),
                os("1"),
                os("--town"),
            ],
            "apply with --ground",
        ),
        (
            vec![os("height"), input.as_os_str(), os("--step"), os("5")],
            "apply with --ground",
        ),
        // Not LAS/LAZ points.
        (
            vec![
                os("dem"),
                xyz.as_os_str(),
                os("--cell"),
                os("1"),
                os("--ground"),
            ],
            "LAS/LAZ/COPC",
        ),
        // Bad parameters.
        (
            vec![
                os("dem"),
                input.as_os_str(),
                os("--cell"),
                os("1"),
                os("--ground"),
                os("--max-angle"),
                os("90"),
            ],
            "--max-angle",
        ),
        // A plan: the filter's options without --ground, and bad parameters.
        (
            vec![
                os("plan"),
                os("dem"),
                input.as_os_str(),
                os("--cell"),
                os("1"),
                os("--tile"),
                os("20"),
                os("--town"),
                os("-o"),
                plan.as_os_str(),
            ],
            "apply with --ground",
        ),
        (
            vec![
                os("plan"),
                os("dem"),
                input.as_os_str(),
                os("--cell"),
                os("1"),
                os("--tile"),
                os("20"),
                os("--ground"),
                os("--step"),
                os("0"),
                os("-o"),
                plan.as_os_str(),
            ],
            "--step",
        ),
    ];
    for (mut args, says) in cases {
        if args[0] != "plan" {
            args.extend([os("-o"), out.as_os_str()]);
        }
        let (code, err) = status(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!out.exists() && !plan.exists(), "{args:?} left an output");
    }
    // --ground with --ground-class is a usage error too.
    let (code, err) = status(&[
        os("height"),
        input.as_os_str(),
        os("--ground"),
        os("--ground-class"),
        os("2"),
        os("-o"),
        out.as_os_str(),
    ]);
    assert_eq!(code, 2, "{err}");
}

/// `--json` of a product command with `--ground` carries what the filter found: the summary
/// `ground --json` prints (under the run's summary, `run.ground`; a TIN's is the run's).
#[test]
fn json_of_a_product_with_ground_carries_the_ground_summary() {
    let input = data::shared("lidar/startinpy_small.laz");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let json = |args: &[&OsStr]| -> serde_json::Value {
        serde_json::from_slice(&cli::ok(args).stdout).unwrap()
    };
    let g = d.join("g.laz");
    let want = json(&[
        os("ground"),
        input.as_os_str(),
        os("-o"),
        g.as_os_str(),
        os("--json"),
    ]);
    // `COMMAND INPUT --ground [EXTRA] -o D/OUT --json`.
    let with_ground = |command: &str, extra: &[&str], out: &str| {
        let out = d.join(out);
        let mut args = vec![os(command), input.as_os_str(), os("--ground")];
        args.extend(extra.iter().map(|a| os(a)));
        args.extend([os("-o"), out.as_os_str(), os("--json")]);
        json(&args)
    };
    let got = with_ground("dem", &["--cell", "1"], "d.tif");
    let tin = with_ground("tin", &[], "t.ply");
    for ground in [&got["run"]["ground"], &tin["ground"]] {
        assert!(ground.is_object(), "no ground summary: {got} {tin}");
        for key in [
            "points",
            "ground",
            "low_noise",
            "seeds",
            "blocks",
            "block",
            "buffer",
        ] {
            assert_eq!(ground[key], want[key], "{key}");
        }
    }
    // Without --ground, no such key.
    let plain = json(&[
        os("dem"),
        input.as_os_str(),
        os("--cell"),
        os("1"),
        os("-o"),
        d.join("d.tif").as_os_str(),
        os("--json"),
    ]);
    assert!(plain["run"].get("ground").is_none(), "{plain}");
}
