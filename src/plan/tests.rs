use super::*;

#[test]
fn tiles_cover_the_files_and_list_their_neighbours() {
    let sample = PathBuf::from("data/sample/startinpy_small.laz");
    let job = Job::new(Product::Dem {
        cell: 0.5,
        align: crate::raster::Align::Edges,
        nodata: -9999.0,
        raster: crate::output::raster::RasterOptions::default(),
        contours: None,
    });
    let p = Plan::new(
        job.clone(),
        vec![],
        vec![],
        std::slice::from_ref(&sample),
        16.0,
        4.0,
    )
    .unwrap();
    // 85699.665 – 85740.506 × 447195.328 – 447243.504: tiles 5356..=5358 × 27949..=27952.
    assert_eq!(p.tiles.len(), 3 * 4);
    assert_eq!((p.tiles[0].tx, p.tiles[0].ty), (5356, 27949));
    assert!(p.tiles.iter().all(|t| t.files == vec![0]));
    assert!(
        Plan::new(
            job,
            vec![],
            vec![],
            std::slice::from_ref(&sample),
            16.3,
            4.0
        )
        .is_err()
    );
    let dir = tempfile::tempdir().unwrap();
    let d = PlanDir::Local(dir.path().to_path_buf());
    let path = p.save(&d).unwrap();
    assert_eq!(Plan::load(&path).unwrap(), p);
    assert!(p.record(&d, 0).unwrap().is_none());
    assert!(p.task(12).is_err());
}
