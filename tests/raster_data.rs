//! The grid reader on the real DEMs of `tests/data/dem` (required under CI, skipped locally when absent).

use crate::data;
use std::path::PathBuf;
use sweeptin::input::raster::{RasterReader, SampleType};

fn dem(name: &str) -> Option<PathBuf> {
    data::optional(&format!("dem/{name}"), "raster_data")
}

struct Facts {
    name: &'static str,
    size: (u32, u32),
    sample: SampleType,
    range: (f64, f64),
    missing: usize,
    crs: Option<&'static str>,
}

fn check(f: &Facts) {
    let Some(p) = dem(f.name) else {
        eprintln!("skipping {}: not found", f.name);
        return;
    };
    let mut r = RasterReader::open(&p).unwrap();
    let s = r.spec().clone();
    assert_eq!((s.cols, s.rows), f.size, "{}", f.name);
    assert_eq!(r.sample_type(), f.sample, "{}", f.name);
    if let Some(c) = f.crs {
        assert_eq!(s.crs.as_deref(), Some(c), "{}", f.name);
    }
    let all = r.read_all().unwrap();
    let valid: Vec<f64> = all.iter().copied().filter(|v| !v.is_nan()).collect();
    assert_eq!(all.len() - valid.len(), f.missing, "{}", f.name);
    let lo = valid.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = valid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (lo - f.range.0).abs() < 0.01 && (hi - f.range.1).abs() < 0.01,
        "{}: {lo} {hi}",
        f.name
    );
    // Windows straddling strip/tile borders equal the same cells of the whole grid.
    let (c0, r0, w, h) = (s.cols / 3, s.rows / 3, s.cols / 2, s.rows / 2);
    let win = r.read_window(c0, r0, w, h).unwrap();
    for y in 0..h {
        for x in 0..w {
            let a = win[(y * w + x) as usize];
            let b = all[((r0 + y) * s.cols + c0 + x) as usize];
            assert!(
                a == b || (a.is_nan() && b.is_nan()),
                "{} ({x}, {y})",
                f.name
            );
        }
    }
}

#[test]
fn big_tujunga_tiled_int16() {
    check(&Facts {
        name: "topotoolbox_srtm_bigtujunga30m_utm11.tif",
        size: (1197, 643),
        sample: SampleType::I16,
        range: (315.0, 2295.0),
        missing: 0,
        crs: Some("EPSG:32611"),
    });
}

#[test]
fn alsroads_deflate_float32() {
    check(&Facts {
        name: "alsroads_j5gr_dtm.tif",
        size: (1000, 2000),
        sample: SampleType::F32,
        range: (387.57, 481.86),
        missing: 0,
        crs: None,
    });
}

#[test]
fn startinpy_lzw_float64() {
    check(&Facts {
        name: "startinpy_dem_01.tif",
        size: (550, 505),
        sample: SampleType::F64,
        range: (0.0, 971.0),
        missing: 0,
        crs: None,
    });
}

#[test]
fn ign_dtm_with_nodata_pixel_centres() {
    check(&Facts {
        name: "ign_DTM_test_data_77055_627760_LA93_IGN69_50CM.tif",
        size: (100, 100),
        sample: SampleType::F32,
        range: (20.78, 21.58),
        missing: 5,
        crs: None,
    });
    if let Some(p) = dem("ign_DTM_test_data_77055_627760_LA93_IGN69_50CM.tif") {
        let s = RasterReader::open(p).unwrap().spec().clone();
        // GDAL bounds 770549.75 … 770599.75: cell centres on the 0.5 m lattice.
        assert_eq!(s.world(0.0, 0.0)[0], 770549.75);
        assert_eq!(s.cell_center(0, 0)[0], 770550.0);
    }
}

#[test]
fn landlab_ascii_grids() {
    check(&Facts {
        name: "landlab_west_bijou_gully.asc",
        size: (43, 89),
        sample: SampleType::Text,
        range: (1680.78, 1725.43),
        missing: 2739,
        crs: None,
    });
    check(&Facts {
        name: "landlab_SRTMGL3_40.09_-105.55_40.21_-105.35.asc",
        size: (240, 144),
        sample: SampleType::Text,
        range: (1943.0, 3286.0),
        missing: 0,
        crs: None,
    });
}
