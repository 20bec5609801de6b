//! Every integration test in one binary: one link instead of one per file, and the tests of
//! all files share the test threads (a file with one long test no longer leaves a core idle).
//! Each file under `tests/` is a module here; a new test file gets its `mod` line below. Run one
//! file's tests with `cargo test --test all NAME::` (e.g. `cargo test --test all plan_ground::`).

// Helpers shared by the test files (each file `use crate::NAME;`).
#[path = "support/cli.rs"]
mod cli;
#[path = "support/data.rs"]
mod data;
#[path = "support/geojson.rs"]
mod geojson;
#[path = "support/grid_tin.rs"]
mod grid_tin;
#[path = "support/mesh.rs"]
mod mesh;
#[path = "support/plans.rs"]
mod plans;
#[path = "support/remote.rs"]
mod remote_server;
#[path = "support/saddle.rs"]
mod saddle;
#[path = "support/tin_errors.rs"]
mod tin_errors;

mod architecture;
mod bigrid;
mod breaklines_pipeline;
mod cdt_core;
mod cdttiles;
mod cli_info;
mod cli_io;
mod cli_tin;
mod contours_output;
mod ground;
mod ground_cli;
mod ground_on_the_fly;
mod hardening;
mod hardening_inputs;
mod height;
mod inputs;
mod io_interrupt;
mod io_ply_read;
mod io_python;
mod io_writers;
mod las_write;
mod lidar_data;
mod lidar_errors;
mod lidar_sample;
mod memory_bound;
mod pipeline;
mod plan;
mod plan_chunks;
mod plan_edges;
mod plan_extent;
mod plan_ground;
mod plan_jobs;
mod plan_lines;
mod plan_report;
mod products_accuracy;
mod products_cli;
mod products_gdal;
mod prop_core;
mod raster_data;
mod rasters;
mod refine;
mod regressions;
mod remote;
mod remote_outputs;
mod remote_plan_dir;
mod remote_plans;
mod simplify;
mod smoke;
mod stac_wgs84;
mod synth_inputs;
mod thin;
mod thintiles;
mod tiles;
mod vectors;
