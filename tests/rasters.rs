//! Raster outputs checked by independent readers: COGs that `rio cogeo validate` and GDAL accept,
//! with the plain GeoTIFF's values; the grid lattice (`--align edges`, the default, against
//! `centres`) on real tiles and against IGN's own DTM; plan mosaics (GeoTIFF and COG) equal to
//! one run with either alignment; `.prj` beside `.asc`; the hillshade's georeferencing.

use crate::cli;
use crate::data;
use crate::plans;

use std::path::{Path, PathBuf};
use std::process::Command;
use sweeptin::input::raster::RasterReader;

use cli::ok as sweeptin;
use plans::cells;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn ign_ground(tile: &str) -> PathBuf {
    data::shared(&format!(
        "lidar/ign_50m_tiles/test_data_{tile}_LA93_IGN69_ground.las"
    ))
}

/// `rio cogeo validate --strict` and GDAL's own reading of a COG.
fn validate_cog(path: &Path, test: &str) {
    if data::tool("rio", test) {
        let out = Command::new("rio")
            .args(["cogeo", "validate", "--strict", s(path)])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success() && text.contains("is a valid cloud optimized GeoTIFF"),
            "rio cogeo validate: {text}"
        );
    }
    if data::tool("gdalinfo", test) {
        let out = Command::new("gdalinfo").arg(s(path)).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "gdalinfo failed");
        assert!(
            text.contains("LAYOUT=COG"),
            "GDAL sees no COG layout: {text}"
        );
        assert!(text.contains("Block=512x512"), "{text}");
    }
}

/// A COG (DEFLATE and ZSTD, BigTIFF forced) of a real tile is valid for rio-cogeo and GDAL, has
/// overviews, and holds the plain GeoTIFF's cells bit for bit; so does a compressed plain
/// GeoTIFF. The 50 m tile at 0.05 m is 1000 × 1000 cells with the default edge alignment.
#[test]
fn cog_is_valid_and_equals_the_plain_geotiff() {
    let las = ign_ground("77055_627760");
    let t = tempfile::tempdir().unwrap();
    let plain = t.path().join("plain.tif");
    let base = ["dem", s(&las), "--cell", "0.05", "-q"];
    let run = |extra: &[&str], out: &Path| {
        let mut a: Vec<&str> = base.to_vec();
        a.extend(extra);
        a.extend(["-o", s(out)]);
        sweeptin(&a);
    };
    run(&[], &plain);
    let want = cells(&plain);
    assert_eq!((want.0, want.1), (1000, 1000));
    assert_eq!((want.2[0], want.2[3]), (770_550.0, 6_277_600.0));
    for (name, extra) in [
        ("deflate", vec!["--format", "cog"]),
        (
            "zstd",
            vec!["--format", "cog", "--compress", "zstd", "--bigtiff"],
        ),
    ] {
        let cog = t.path().join(format!("{name}.tif"));
        run(&extra, &cog);
        validate_cog(&cog, "cog_is_valid_and_equals_the_plain_geotiff");
        assert_eq!(cells(&cog), want, "{name} COG cells differ");
        assert!(std::fs::metadata(&cog).unwrap().len() < std::fs::metadata(&plain).unwrap().len());
    }
    let packed = t.path().join("packed.tif");
    run(&["--compress", "lzw"], &packed);
    assert_eq!(cells(&packed), want, "LZW GeoTIFF cells differ");
    if data::tool("gdalinfo", "cog_is_valid_and_equals_the_plain_geotiff") {
        let cog = t.path().join("deflate.tif");
        let out = Command::new("gdalinfo")
            .args(["-checksum", s(&cog), "-oo", "OVERVIEW_LEVEL=0"])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("Size is 500, 500"), "overview: {text}");
    }
    // Refused before any work: a predictor without compression, options on an ASCII grid.
    let out = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["dem", s(&las), "--predictor", "float", "-o"])
        .arg(t.path().join("x.tif"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("needs compression"));
}

/// Edges on multiples (the default): a 1 km IGN tile at 1 m is 1000 × 1000 cells from its own
/// bounds; `--align centres` keeps the old lattice (1001 × 1001).
#[test]
fn a_1_km_tile_gives_1000_by_1000_cells() {
    let laz = data::shared("lidar/ign_test_semis_2023_0299_6802_LA93_IGN69.laz");
    let t = tempfile::tempdir().unwrap();
    let edges = t.path().join("edges.tif");
    let out = sweeptin(&["dem", s(&laz), "--json", "-q", "-o", s(&edges)]);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (j["dem"]["cols"].as_u64(), j["dem"]["rows"].as_u64()),
        (Some(1000), Some(1000))
    );
    let c = cells(&edges);
    assert_eq!(c.2, [299_000.0, 1.0, 0.0, 6_802_000.0, 0.0, -1.0]);
    let centres = t.path().join("centres.asc");
    let out = sweeptin(&[
        "dem",
        s(&laz),
        "--align",
        "centres",
        "--json",
        "-q",
        "-o",
        s(&centres),
    ]);
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (j["dem"]["cols"].as_u64(), j["dem"]["rows"].as_u64()),
        (Some(1001), Some(1001))
    );
    // The LAS 1.4 file declares its CRS as WKT: the grid gets a .prj that GDAL reads.
    let prj = centres.with_extension("prj");
    assert!(std::fs::read_to_string(&prj).unwrap().contains("Lambert"));
    if data::tool("gdalsrsinfo", "a_1_km_tile_gives_1000_by_1000_cells") {
        let out = Command::new("gdalsrsinfo")
            .args(["-e", s(&centres)])
            .output()
            .unwrap();
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("EPSG:2154"),
            "{}",
            String::from_utf8_lossy(&out.stdout)
        );
    }
}

/// IGN's DTM of tile 77055_627760 is 100 × 100 cells of 0.5 m whose centres lie on the tile's
/// 0.5 m lattice: `--align centres` with the tile's box gives its geotransform exactly and its
/// values (within 1 mm on most cells); the default (edges) gives 100 × 100 cells covering the
/// tile exactly.
#[test]
fn ign_tile_matches_igns_dtm_lattice() {
    let las = ign_ground("77055_627760");
    let ign = data::shared("dem/ign_DTM_test_data_77055_627760_LA93_IGN69_50CM.tif");
    let t = tempfile::tempdir().unwrap();
    let ours = t.path().join("centres.tif");
    let bbox = "770550,6277550,770600,6277600";
    sweeptin(&[
        "dem",
        s(&las),
        "--cell",
        "0.5",
        "--align",
        "centres",
        "--bbox",
        bbox,
        "-q",
        "-o",
        s(&ours),
    ]);
    let theirs = RasterReader::open(&ign).unwrap().spec().clone();
    let mut r = RasterReader::open(&ours).unwrap();
    let spec = r.spec().clone();
    assert_eq!((spec.cols, spec.rows), (theirs.cols, theirs.rows));
    assert_eq!(spec.transform, theirs.transform);
    let a = r.read_all().unwrap();
    let b = RasterReader::open(&ign).unwrap().read_all().unwrap();
    let both = a.iter().zip(&b).filter(|(x, y)| !x.is_nan() && !y.is_nan());
    let (n, close) = both.fold((0, 0), |(n, c), (x, y)| {
        (n + 1, c + usize::from((x - y).abs() <= 1e-3))
    });
    assert!(
        n > 9_900 && close as f64 / n as f64 > 0.9,
        "{close} of {n} within 1 mm"
    );
    let edges = t.path().join("edges.tif");
    sweeptin(&[
        "dem",
        s(&las),
        "--cell",
        "0.5",
        "--bbox",
        bbox,
        "-q",
        "-o",
        s(&edges),
    ]);
    let e = cells(&edges);
    assert_eq!((e.0, e.1), (100, 100));
    assert_eq!(e.2, [770_550.0, 0.5, 0.0, 6_277_600.0, 0.0, -0.5]);
}

/// A plan over two IGN tiles with `--align centres` merges into the cells of one run (bit for
/// bit), as a GeoTIFF and as a COG written by the same bounded-memory writer.
#[test]
fn plan_mosaic_equals_one_run_with_centre_alignment_and_as_cog() {
    let files = [ign_ground("77055_627760"), ign_ground("77060_627760")];
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let mut args = vec!["plan", "--buffer", "5", "dem"];
    args.extend(files.iter().map(|p| s(p)));
    args.extend([
        "--cell",
        "0.5",
        "--align",
        "centres",
        "--tile",
        "50",
        "-o",
        s(&job),
    ]);
    sweeptin(&args);
    let plan = job.join("plan.json");
    sweeptin(&["run", s(&plan), "--all", "-q"]);
    let mosaic = t.path().join("mosaic.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&mosaic)]);
    let m = cells(&mosaic);
    // One run over the same box (the union of the plan's tiles), reading everything.
    let x0 = m.2[0] + 0.25;
    let y1 = m.2[3] - 0.25;
    let bbox = format!(
        "{},{},{},{}",
        x0,
        y1 - f64::from(m.1) * 0.5,
        x0 + f64::from(m.0) * 0.5,
        y1
    );
    let single = t.path().join("single.tif");
    let mut one = vec!["dem"];
    one.extend(files.iter().map(|p| s(p)));
    one.extend([
        "--cell",
        "0.5",
        "--align",
        "centres",
        "--bbox",
        &bbox,
        "--buffer",
        "10000",
        "-q",
        "-o",
        s(&single),
    ]);
    sweeptin(&one);
    assert_eq!(
        m,
        cells(&single),
        "the centre-aligned mosaic differs from one run"
    );
    let cog = t.path().join("mosaic_cog.tif");
    sweeptin(&["merge", s(&plan), "-o", s(&cog), "--format", "cog"]);
    validate_cog(
        &cog,
        "plan_mosaic_equals_one_run_with_centre_alignment_and_as_cog",
    );
    assert_eq!(cells(&cog), m, "the COG mosaic differs");
}

/// A hillshade GeoTIFF / COG is 8-bit and georeferenced like its DEM; a PNG gets a world file.
#[test]
fn hillshade_outputs_are_georeferenced() {
    let las = ign_ground("77055_627760");
    let t = tempfile::tempdir().unwrap();
    let dem = t.path().join("dem.tif");
    let png = t.path().join("shade.png");
    sweeptin(&[
        "dem",
        s(&las),
        "--cell",
        "0.5",
        "--hillshade",
        s(&png),
        "-q",
        "-o",
        s(&dem),
    ]);
    let pgw = std::fs::read_to_string(png.with_extension("pgw")).unwrap();
    assert_eq!(pgw, "0.5\n0.0\n0.0\n-0.5\n770550.25\n6277599.75\n");
    let cog = t.path().join("shade.tif");
    sweeptin(&["hillshade", s(&dem), "-o", s(&cog), "--format", "cog"]);
    let r = RasterReader::open(&cog).unwrap();
    assert_eq!(
        r.spec().transform,
        RasterReader::open(&dem).unwrap().spec().transform
    );
    assert_eq!(r.sample_type(), sweeptin::input::raster::SampleType::U8);
    validate_cog(&cog, "hillshade_outputs_are_georeferenced");
    // A hillshade name no format fits, or a DEM that is not a GeoTIFF: refused before the DEM
    // is made (the first failed after writing it, the second named a .prj clash).
    for (out, shade, says) in [
        ("h2.tif", "h2.pgw", "PNG (.png) or GeoTIFF"),
        ("d.asc", "d.png", "needs a GeoTIFF DEM"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
            .current_dir(t.path())
            .args([
                "dem",
                s(&las),
                "--cell",
                "0.5",
                "-o",
                out,
                "--hillshade",
                shade,
            ])
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(e.contains(says), "{e}");
        assert!(!t.path().join(out).exists(), "{out} was written");
    }
    // The same DEM stored south-up (rows from the south, a positive pixel height): refused,
    // naming the way out (it was shaded with north and south swapped, a raster's height off).
    if !data::python(&["rasterio"], "hillshade_outputs_are_georeferenced") {
        return;
    }
    let south = t.path().join("south.tif");
    let flip = "import sys, rasterio\n\
                from affine import Affine\n\
                with rasterio.open(sys.argv[1]) as r:\n\
                \x20   a, t, p = r.read(1)[::-1], r.transform, r.profile\n\
                p.update(transform=Affine(t.a, 0, t.c, 0, -t.e, t.f + t.e * r.height))\n\
                with rasterio.open(sys.argv[2], 'w', **p) as w:\n\
                \x20   w.write(a, 1)\n";
    let o = Command::new("python3")
        .args(["-c", flip, s(&dem), s(&south)])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new(env!("CARGO_BIN_EXE_sweeptin"))
        .args(["hillshade", s(&south), "-o", s(&t.path().join("s.png"))])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("north-up"));
    assert!(!t.path().join("s.png").exists());
}
