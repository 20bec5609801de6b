use super::*;
use crate::raster::Align;

#[test]
fn a_job_round_trips_through_json_nan_nodata_included() {
    let mut job = Job::new(Product::Dem {
        cell: 0.5,
        align: Align::Centres,
        nodata: f32::NAN,
        raster: RasterOptions {
            format: Some(RasterFormat::Cog),
            ..RasterOptions::default()
        },
        contours: Some(Levels {
            interval: 0.25,
            base: 0.1,
            decimals: Some(2),
            min_length: 0.0,
        }),
    });
    job.classes = Some(vec![2, 9]);
    job.crs = Some("EPSG:2154".into());
    let text = serde_json::to_string(&job).unwrap();
    assert!(text.contains(r#""nodata":"NaN""#), "{text}");
    let back: Job = serde_json::from_str(&text).unwrap();
    assert!(text.contains(r#""align":"centres""#), "{text}");
    assert!(text.contains(r#""format":"cog""#), "{text}");
    let Product::Dem {
        nodata,
        align,
        raster,
        ..
    } = back.product
    else {
        panic!("{back:?}")
    };
    assert!(nodata.is_nan());
    assert_eq!(
        (align, raster.format),
        (Align::Centres, Some(RasterFormat::Cog))
    );
    let mut asc = Job::new(Product::Dem {
        cell: 1.0,
        align: Align::Edges,
        nodata: -9999.0,
        raster: RasterOptions {
            format: Some(RasterFormat::Ascii),
            ..RasterOptions::default()
        },
        contours: None,
    });
    assert!(
        asc.check()
            .unwrap_err()
            .to_string()
            .contains("a DEM mosaic is")
    );
    if let Product::Dem { raster, .. } = &mut asc.product {
        *raster = RasterOptions {
            predictor: Some(crate::output::raster::Predictor::Float),
            ..RasterOptions::default()
        };
    }
    assert!(
        asc.check()
            .unwrap_err()
            .to_string()
            .contains("needs compression")
    );
    job.product = Product::Contours(Levels {
        interval: 1.0,
        base: 0.0,
        decimals: None,
        min_length: 5.0,
    });
    let back: Job = serde_json::from_str(&serde_json::to_string(&job).unwrap()).unwrap();
    assert_eq!(back, job);
    assert_eq!(back.command(), "contours");
    assert!(back.check().is_ok());
    job.crs = Some("nonsense".into());
    assert!(job.check().is_err());
}
