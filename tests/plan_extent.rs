//! The extent of a plan's DEM mosaic (issue 43 item 5): `merge` writes the file one run writes
//! (the grid over the points kept, decided from the tasks' records), byte for byte as a GeoTIFF
//! or a COG, the same header as a VRT; `--extent tiles` keeps the whole tiles; records of an
//! older build (without the extent of their points) give the tiles, with a warning.

use crate::data;
use crate::plans;

use plans::{bin, cells, ok, plan_extent, records, s, sweeptin};
use std::path::{Path, PathBuf};
use std::process::Command;

fn sample() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/sample/startinpy_small.laz")
}

/// The size and geotransform a VRT declares.
fn vrt_header(p: &Path) -> (u32, u32, [f64; 6]) {
    let x = std::fs::read_to_string(p).unwrap();
    let attr = |name: &str| -> u32 {
        let a = x.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
        x[a..a + x[a..].find('"').unwrap()].parse().unwrap()
    };
    let a = x.find("<GeoTransform>").unwrap() + "<GeoTransform>".len();
    let b = x.find("</GeoTransform>").unwrap();
    let t: Vec<f64> = x[a..b]
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    (
        attr("rasterXSize"),
        attr("rasterYSize"),
        [t[0], t[1], t[2], t[3], t[4], t[5]],
    )
}

/// The merged DEM covered whole tiles of the plan's grid (2000 × 2500 cells, 67 % nodata,
/// where one run gives 1142 × 1552): the mosaic is now one run's file, byte for byte (GeoTIFF
/// and COG), with a class filter that keeps part of the points; a VRT declares one run's size
/// and geotransform (and GDAL reads one run's cells from it).
#[test]
fn the_mosaic_is_the_file_one_run_writes() {
    let t = tempfile::tempdir().unwrap();
    let (input, job) = (sample(), t.path().join("job"));
    // Buildings only: their extent (48 × 45 cells) is not the file's (82 × 96).
    let filter = ["--class", "6", "--cell", "0.5"];
    let mut args = vec!["plan", "dem", s(&input)];
    args.extend(filter);
    args.extend(["--tile", "16", "-o", s(&job)]);
    sweeptin(&args, "plan");
    let plan = job.join("plan.json");
    let (tiles_box, n) = plan_extent(&plan);
    sweeptin(&["run", s(&plan), "--all", "-q"], "run --all");
    let recs = records(&job, n);
    assert!(
        recs.iter()
            .all(|r| r["status"] != "done" || r["extent"].is_array()),
        "a finished task recorded no extent: {recs:?}"
    );

    for format in ["tif", "cog"] {
        let (one, mosaic) = (
            t.path().join(format!("one-{format}.tif")),
            t.path().join(format!("mosaic-{format}.tif")),
        );
        let mut single = vec!["dem", s(&input)];
        single.extend(filter);
        single.extend(["--format", format, "-q", "-o", s(&one)]);
        sweeptin(&single, "one run");
        let out = sweeptin(
            &[
                "merge",
                s(&plan),
                "-o",
                s(&mosaic),
                "--format",
                format,
                "--json",
            ],
            "merge",
        );
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(summary["dem"]["extent"], "data");
        let (a, b) = (cells(&mosaic), cells(&one));
        assert_eq!((a.0, a.1, a.2), (b.0, b.1, b.2), "{format}: another grid");
        assert!(a.3 == b.3, "{format}: other cells");
        assert!(
            std::fs::read(&mosaic).unwrap() == std::fs::read(&one).unwrap(),
            "{format}: the mosaic is not one run's file byte for byte"
        );
    }

    // A VRT over the tiles: one run's size and geotransform; GDAL reads one run's cells.
    let one = t.path().join("one-tif.tif");
    let vrt = t.path().join("mosaic.vrt");
    sweeptin(&["merge", s(&plan), "-o", s(&vrt)], "merge to VRT");
    let c = cells(&one);
    assert_eq!(vrt_header(&vrt), (c.0, c.1, c.2), "the VRT's header");
    if data::tool("gdal_translate", "the_mosaic_is_the_file_one_run_writes") {
        let from_vrt = t.path().join("from_vrt.tif");
        let out = Command::new("gdal_translate")
            .args(["-q", s(&vrt), s(&from_vrt)])
            .output()
            .unwrap();
        ok(out, "gdal_translate of the VRT");
        assert!(cells(&from_vrt) == c, "GDAL reads other cells in the VRT");
    }

    // `--extent tiles`: the whole tiles, as one run over their union.
    let tiles = t.path().join("tiles.tif");
    let out = sweeptin(
        &[
            "merge",
            s(&plan),
            "-o",
            s(&tiles),
            "--extent",
            "tiles",
            "--json",
        ],
        "merge --extent tiles",
    );
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["dem"]["extent"], "tiles");
    let boxed = t.path().join("boxed.tif");
    let mut single = vec!["dem", s(&input)];
    single.extend(filter);
    single.extend(["--bbox", &tiles_box, "--buffer", "10000", "-q", "-o"]);
    single.push(s(&boxed));
    sweeptin(&single, "one run over the tiles");
    let (a, b) = (cells(&tiles), cells(&boxed));
    assert!(
        a == b,
        "the mosaic of the tiles differs from one run over them"
    );
    assert!(
        u64::from(a.0) * u64::from(a.1) > u64::from(c.0) * u64::from(c.1),
        "the tiles hold no more cells than the data"
    );
}

/// Records written before tasks recorded the extent of their points: the merge cannot know one
/// run's grid, so it covers the tiles and says so (exit 0); the tasks run again give one run's.
#[test]
fn records_without_an_extent_give_the_tiles_with_a_warning() {
    let t = tempfile::tempdir().unwrap();
    let (input, job) = (sample(), t.path().join("job"));
    sweeptin(
        &[
            "plan",
            "dem",
            s(&input),
            "--cell",
            "1",
            "--tile",
            "32",
            "-o",
            s(&job),
        ],
        "plan",
    );
    let plan = job.join("plan.json");
    let (tiles_box, n) = plan_extent(&plan);
    sweeptin(&["run", s(&plan), "--all", "-q"], "run --all");
    for i in 0..n {
        let p = job.join("tiles").join(format!("task_{i}.json"));
        let mut r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        r.as_object_mut().unwrap().remove("extent");
        std::fs::write(&p, serde_json::to_string_pretty(&r).unwrap()).unwrap();
    }
    let mosaic = t.path().join("m.tif");
    let out = ok(
        bin()
            .args(["merge", s(&plan), "-o", s(&mosaic)])
            .output()
            .unwrap(),
        "merge of old records",
    );
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("warning") && e.contains("older sweeptin") && e.contains("whole tiles"),
        "{e}"
    );
    let boxed = t.path().join("boxed.tif");
    sweeptin(
        &[
            "dem",
            s(&input),
            "--cell",
            "1",
            "--bbox",
            &tiles_box,
            "--buffer",
            "10000",
            "-q",
            "-o",
            s(&boxed),
        ],
        "one run over the tiles",
    );
    assert!(cells(&mosaic) == cells(&boxed), "not the tiles' mosaic");
    // An extent that is neither: a usage error.
    let o = bin()
        .args([
            "merge",
            s(&plan),
            "-o",
            s(&mosaic),
            "--extent",
            "everything",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{o:?}");
}
