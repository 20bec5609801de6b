//! Joining the outputs of a plan's tasks ([`merge_plan`], for the command line and Python alike):
//! DEM tiles into a GDAL VRT or one GeoTIFF or COG (and its hillshade), contour lines stitched
//! across tile edges, volumes summed exactly.

use super::{Plan, TaskRecord};
use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::input::raster::RasterReader;
use crate::output::raster::{RasterFormat, RasterOptions, create_grid_writer_within};
use crate::products::hillshade::{self, HillshadeSummary};
use crate::raster::{Align, GridExtent, GridPlan};
use std::path::{Path, PathBuf};

pub use super::stitch::{StitchOptions, StitchSummary, merge_contours, stitch};

/// The least `--mem` a merge takes: its fixed buffers (a DEM tile read 2^20 cells at a time, the
/// contours' spill buffer and line writer, the hillshade's band of rows, the TIN merge's
/// readers), which hold a few MiB whatever the plan's size. A merge's memory beyond them is
/// bounded by its budget: a compressed GeoTIFF or COG compresses at most a quarter of it at a
/// time, a ground plan's single point file decodes at most a quarter of it at a time, and the
/// contour lines open at the tasks' edges may hold half of it.
pub const MIN_MERGE_MEM: u64 = 16 << 20;

/// The share of a merge's budget (`--mem`) that one batch of a compressed output takes.
fn batch_share(mem: u64) -> u64 {
    mem / 4
}

/// The records of every task of `plan` under `dir`, each output of the size its task wrote
/// ([`Plan::check_task_outputs`]).
///
/// # Errors
/// [`Error::Options`] naming the tasks that have not finished; [`Error::Format`] for an output
/// missing or of another size.
pub fn records(plan: &Plan, dir: &super::PlanDir) -> Result<Vec<TaskRecord>> {
    let mut out = Vec::with_capacity(plan.tiles.len());
    let mut missing = Vec::new();
    for t in &plan.tiles {
        match plan.record(dir, t.index)? {
            Some(r) => out.push(r),
            None => missing.push(t.index),
        }
    }
    if missing.is_empty() {
        for r in &out {
            plan.check_task_outputs(dir, r)?;
        }
    }
    if !missing.is_empty() {
        let list: Vec<String> = missing.iter().take(20).map(|i| i.to_string()).collect();
        return Err(Error::Options(format!(
            "{} of {} tasks have not finished under this plan (run them first: `sweeptin run {} \
             --task I`, or `--all --resume`): {}{}",
            missing.len(),
            plan.tiles.len(),
            dir.join("plan.json").display(),
            list.join(", "),
            if missing.len() > 20 { ", …" } else { "" }
        )));
    }
    Ok(out)
}

/// The output `name` of every task that wrote one, with the task's index, in task order. An
/// empty task writes none (its tile is nodata, with no lines).
pub(super) fn outputs<'a>(records: &'a [TaskRecord], name: &str) -> Result<Vec<(usize, &'a Path)>> {
    records
        .iter()
        .filter(|r| !(r.status == "empty" && r.outputs.is_empty()))
        .map(|r| {
            r.outputs
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, p)| (r.index, p.as_path()))
                .ok_or_else(|| Error::Options(format!("task {} wrote no {name} output", r.index)))
        })
        .collect()
}

/// What a DEM merge wrote.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DemMergeSummary {
    /// The file written.
    pub path: PathBuf,
    /// Columns and rows of the mosaic.
    pub cols: u32,
    /// See `cols`.
    pub rows: u32,
    /// Tiles joined.
    pub tiles: u64,
    /// The extent the mosaic covers: `"data"` (one run's grid) or `"tiles"`.
    pub extent: MosaicExtent,
}

/// Which cells a DEM mosaic has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MosaicExtent {
    /// One run's grid: every cell whose centre lies inside the extent of the points kept
    /// (and the lines' vertices), as `sweeptin dem` over the same files and filters writes it,
    /// header and cells. Decided from the tasks' records ([`TaskRecord::extent`]).
    #[default]
    Data,
    /// The whole tiles of the plan's grid (cells outside the data are nodata).
    Tiles,
}

impl std::str::FromStr for MosaicExtent {
    type Err = Error;
    fn from_str(s: &str) -> Result<MosaicExtent> {
        match s {
            "data" => Ok(MosaicExtent::Data),
            "tiles" => Ok(MosaicExtent::Tiles),
            _ => Err(Error::Options(format!(
                "--extent {s}: give `data` (one run's grid, the default) or `tiles` (the whole \
                 tiles)"
            ))),
        }
    }
}

/// The mosaic's grid, on the plan's cell lattice: with [`MosaicExtent::Data`] the grid one run
/// over the plan's files makes (every centre inside the union of the tasks' point extents and
/// the lines' vertices, as [`GridPlan::grid`] decides for [`GridExtent::Auto`]); with
/// [`MosaicExtent::Tiles`], or records of older builds without extents (with a warning), the
/// union of the tiles. Returns the grid, the extent it covers, and the warning.
fn mosaic_grid(
    plan: &Plan,
    dir: &super::PlanDir,
    recs: &[TaskRecord],
    options: &MosaicOptions,
    crs: Option<&Crs>,
) -> Result<(crate::raster::GridSpec, MosaicExtent, Option<String>)> {
    let cell = plan
        .cell
        .ok_or_else(|| Error::Options("the plan makes no DEM".into()))?;
    let union = |b: [f64; 4], t: [f64; 4]| {
        [
            b[0].min(t[0]),
            b[1].min(t[1]),
            b[2].max(t[2]),
            b[3].max(t[3]),
        ]
    };
    let none = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let tiles = || plan.tiles.iter().fold(none, |b, t| union(b, t.bounds));
    // A finished task that read points and recorded no extent: a record of an older build.
    let old = recs
        .iter()
        .filter(|r| r.status == "done" && r.extent.is_none())
        .count();
    let (extent, warning) = match options.extent {
        MosaicExtent::Data if old > 0 => (
            MosaicExtent::Tiles,
            Some(format!(
                "{old} of {} task records were written by an older sweeptin and hold no extent \
                 of their points: the mosaic covers the whole tiles ({} of one run's grid); run \
                 the tasks again (`sweeptin run {} --all`) for one run's extent",
                recs.len(),
                "a superset",
                dir.join("plan.json").display()
            )),
        ),
        e => (e, None),
    };
    let mut g = match extent {
        MosaicExtent::Tiles => {
            let b = tiles();
            GridPlan::new(
                cell,
                GridExtent::BBox {
                    bbox: b,
                    snap: false,
                },
                options.align,
            )?
            .grid(b, options.nodata)?
        }
        MosaicExtent::Data => {
            let mut b = recs.iter().filter_map(|r| r.extent).fold(none, union);
            // One run adds the lines' vertices to the points' extent (the sweep's bounds).
            if let Some(l) = &plan.job.lines {
                for v in l.graph()?.vertices {
                    let (x, y) = (v[0] + 0.0, v[1] + 0.0);
                    b = union(b, [x, y, x, y]);
                }
            }
            GridPlan::new(cell, GridExtent::Auto, options.align)?.grid(b, options.nodata)?
        }
    };
    g.crs = crs.cloned();
    Ok((g, extent, warning))
}

/// Where a tile lies in a mosaic: the first column and row of the mosaic it covers, the first
/// column and row of the tile that fall inside, and how many (`cols`, `rows`: 0 for a tile
/// wholly outside the mosaic, whose cells are all nodata).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Placed {
    col: u32,
    row: u32,
    src_col: u32,
    src_row: u32,
    cols: u32,
    rows: u32,
}

/// Opens the DEM tile of task `i` (`path`, of the plan in `dir`) and finds where it sits in the
/// mosaic `g`: its header must read, and place it on the mosaic's cells (a whole number of
/// cells from its origin); with `whole`, wholly inside it (the mosaic of the tiles). Checked
/// for the VRT as for the `.tif` (a VRT over a damaged tile was written with exit 0, and GDAL
/// failed on it later).
///
/// # Errors
/// [`Error::Format`] naming the tile and the task to run again.
fn open_tile(
    g: &crate::raster::GridSpec,
    dir: &super::PlanDir,
    i: usize,
    path: &Path,
    whole: bool,
) -> Result<(RasterReader, Placed)> {
    let bad = |what: String| Error::Format {
        path: path.to_path_buf(),
        message: format!(
            "the dem output of task {i} {what}; {}",
            super::task::run_again(dir, i, false)
        ),
    };
    // A tile on S3 is copied to the temporary directory first (the reader takes a file); the
    // copy goes when the reader is made (its file stays open).
    let copy = dir.local(path)?;
    let r = RasterReader::open(&copy.path).map_err(|e| match e {
        Error::Format { message, .. } => bad(format!("cannot be read: {message}")),
        e => e,
    })?;
    let (o, spec) = (g.origin(), r.spec());
    let t = spec.transform;
    let col = (t[0] - o[0]) / g.cell;
    let row = (o[1] - t[3]) / g.cell;
    let same = |c: f64| (c - g.cell).abs() <= 1e-9 * g.cell;
    let lattice = |k: f64| (k - k.round()).abs() <= 1e-6 && k.round().abs() < 1e9;
    let inside = |k: f64, n: u32, of: u32| {
        !whole || (k.round() >= 0.0 && k.round() + f64::from(n) <= f64::from(of))
    };
    let fits = same(t[1])
        && same(-t[5])
        && t[2] == 0.0
        && t[4] == 0.0
        && lattice(col)
        && lattice(row)
        && inside(col, spec.cols, g.cols)
        && inside(row, spec.rows, g.rows);
    if !fits {
        return Err(bad(format!(
            "is not a tile of this plan's mosaic: its header says {} × {} cells of {} from \
             ({}, {}), the mosaic {} × {} cells of {} from ({}, {})",
            spec.cols, spec.rows, t[1], t[0], t[3], g.cols, g.rows, g.cell, o[0], o[1]
        )));
    }
    // The overlap of the tile's cells [k, k + n) with the mosaic's [0, of), on one axis.
    let span = |k: i64, n: u32, of: u32| -> (u32, u32, u32) {
        let lo = k.max(0);
        let hi = (k + i64::from(n)).min(i64::from(of));
        if hi <= lo {
            return (0, 0, 0);
        }
        (lo as u32, (lo - k) as u32, (hi - lo) as u32)
    };
    let (c0, sc, nc) = span(col.round() as i64, spec.cols, g.cols);
    let (r0, sr, nr) = span(row.round() as i64, spec.rows, g.rows);
    let empty = nc == 0 || nr == 0;
    let placed = Placed {
        col: c0,
        row: r0,
        src_col: sc,
        src_row: sr,
        cols: if empty { 0 } else { nc },
        rows: if empty { 0 } else { nr },
    };
    Ok((r, placed))
}

/// How a DEM mosaic is written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MosaicOptions {
    /// The value of cells without data.
    pub nodata: f32,
    /// The plan's cell alignment (the tasks' rasters were made with it).
    pub align: Align,
    /// Format (a `.vrt` extension writes a VRT), compression, predictor, BigTIFF.
    pub output: RasterOptions,
    /// The cells the mosaic has: one run's (the default) or the whole tiles'.
    pub extent: MosaicExtent,
    /// The merge's memory budget (`--mem`): a compressed GeoTIFF or COG compresses a quarter of
    /// it at a time (at most [`crate::output::cog::BATCH_BYTES`]).
    pub mem: u64,
}

/// Joins the DEM tiles into `out`: a GDAL VRT (`.vrt`) over the tile GeoTIFFs, or one GeoTIFF
/// or COG (`.tif`) written tile by tile into the writer's stage, in bounded memory. Its grid is
/// one run's ([`MosaicExtent::Data`]) or the whole tiles'; a warning, if any, says
/// why it is not the one asked for.
///
/// # Errors
/// Reading the tiles or writing; [`Error::Options`] for unfinished tasks or an unknown extension.
pub fn merge_dem(
    plan: &Plan,
    dir: &super::PlanDir,
    out: &Path,
    options: &MosaicOptions,
    crs: Option<&Crs>,
) -> Result<(DemMergeSummary, Option<String>)> {
    let recs = records(plan, dir)?;
    let tiles = outputs(&recs, "dem")?;
    let nodata = options.nodata;
    let (g, extent, warning) = mosaic_grid(plan, dir, &recs, options, crs)?;
    let whole = extent == MosaicExtent::Tiles;
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() == Some("vrt") && options.output.format.is_none() {
        write_vrt(&g, dir, &tiles, out, whole)?;
    } else {
        let mut o = options.output;
        if o.format.is_none() {
            o.format = Some(RasterFormat::GeoTiff);
        }
        let batch = usize::try_from(batch_share(options.mem)).unwrap_or(usize::MAX);
        let mut w = create_grid_writer_within(out, &o, &g, batch)?;
        for &(i, path) in &tiles {
            let (mut r, at) = open_tile(&g, dir, i, path, whole)?;
            let rows_at_once = (1 << 20) / at.cols.max(1);
            let mut row = 0;
            while row < at.rows {
                let n = rows_at_once.clamp(1, at.rows - row);
                let v = r.read_window(at.src_col, at.src_row + row, at.cols, n)?;
                for k in 0..n {
                    let a = (k * at.cols) as usize;
                    let vals: Vec<f32> = v[a..a + at.cols as usize]
                        .iter()
                        .map(|&x| if x.is_nan() { nodata } else { x as f32 })
                        .collect();
                    w.write_span(at.row + row + k, at.col, &vals)?;
                }
                row += n;
            }
        }
        w.finish()?;
    }
    let summary = DemMergeSummary {
        path: out.to_path_buf(),
        cols: g.cols,
        rows: g.rows,
        tiles: tiles.len() as u64,
        extent,
    };
    Ok((summary, warning))
}

fn write_vrt(
    g: &crate::raster::GridSpec,
    dir: &super::PlanDir,
    tiles: &[(usize, &Path)],
    out: &Path,
    whole: bool,
) -> Result<()> {
    use std::fmt::Write as _;
    let o = g.origin();
    let mut x = String::new();
    let _ = writeln!(
        x,
        "<VRTDataset rasterXSize=\"{}\" rasterYSize=\"{}\">",
        g.cols, g.rows
    );
    if let Some(def) = g.crs.as_ref().and_then(|c| c.definition()) {
        let _ = writeln!(x, "  <SRS>{}</SRS>", crate::output::escape_markup(&def));
    }
    let _ = writeln!(
        x,
        "  <GeoTransform>{:?}, {:?}, 0, {:?}, 0, {:?}</GeoTransform>",
        o[0], g.cell, o[1], -g.cell
    );
    let _ = writeln!(x, "  <VRTRasterBand dataType=\"Float32\" band=\"1\">");
    let _ = writeln!(x, "    <NoDataValue>{:?}</NoDataValue>", g.nodata);
    for &(i, path) in tiles {
        let (_, at) = open_tile(g, dir, i, path, whole)?;
        if at.cols == 0 {
            // Wholly outside one run's grid: nodata there.
            continue;
        }
        let abs = std::fs::canonicalize(path).map_err(|e| Error::io(path, e))?;
        let _ = writeln!(x, "    <SimpleSource>");
        let _ = writeln!(
            x,
            "      <SourceFilename relativeToVRT=\"0\">{}</SourceFilename>",
            crate::output::escape_markup(&abs.to_string_lossy())
        );
        let _ = writeln!(x, "      <SourceBand>1</SourceBand>");
        let _ = writeln!(
            x,
            "      <SrcRect xOff=\"{sc}\" yOff=\"{sr}\" xSize=\"{c}\" ySize=\"{r}\"/>\n      \
             <DstRect xOff=\"{c0}\" yOff=\"{r0}\" xSize=\"{c}\" ySize=\"{r}\"/>",
            sc = at.src_col,
            sr = at.src_row,
            c0 = at.col,
            r0 = at.row,
            c = at.cols,
            r = at.rows
        );
        let _ = writeln!(x, "    </SimpleSource>");
    }
    let _ = writeln!(x, "  </VRTRasterBand>\n</VRTDataset>");
    super::write_atomic(out, x.as_bytes())
}

/// The exact totals of the tasks' volumes (the same, bit for bit, as one run over all points).
///
/// # Errors
/// Unfinished tasks, or a task without volume sums.
pub fn merge_volume(plan: &Plan, dir: &super::PlanDir) -> Result<crate::sink::CutFillTotals> {
    let recs = records(plan, dir)?;
    let mut parts = Vec::with_capacity(recs.len());
    // An empty task that read no point has no sums (zero).
    for r in recs
        .iter()
        .filter(|r| !(r.status == "empty" && r.volume.is_none()))
    {
        parts.push(
            r.volume
                .clone()
                .ok_or_else(|| Error::Options(format!("task {} recorded no volume", r.index)))?,
        );
    }
    Ok(crate::products::volume::CutFill::totals_of(&parts))
}

/// Where [`merge_plan`] writes, and how. Every path left out is taken from the plan when it
/// was given one (`contours`, `hillshade`), or not written.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MergeOutputs {
    /// The DEM mosaic (`.vrt` over the tiles, or one `.tif`), or the contours (`.geojson`); a
    /// volume plan writes no file.
    pub out: Option<PathBuf>,
    /// A DEM plan's stitched contours.
    pub contours: Option<PathBuf>,
    /// A hillshade of a DEM plan's `.tif` mosaic: a `.png` with a world file, or an 8-bit
    /// GeoTIFF (`.tif`).
    pub hillshade: Option<PathBuf>,
    /// The `.tif` mosaic's format (GeoTIFF or COG) and compression; all left out: the plan's.
    pub raster: RasterOptions,
    /// The DEM mosaic's cells: one run's grid (the default) or the whole tiles.
    pub extent: MosaicExtent,
    /// The memory budget, at least [`MIN_MERGE_MEM`] (`--mem`; e.g.
    /// [`crate::pipeline::default_mem`]): see [`MIN_MERGE_MEM`] for what it bounds.
    pub mem: u64,
}

/// A hillshade written by [`merge_plan`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MergedHillshade {
    /// The file written.
    pub path: PathBuf,
    /// Its size and cells.
    #[serde(flatten)]
    pub summary: HillshadeSummary,
}

/// What [`merge_plan`] made. Serialises as the `--json` summary of `sweeptin merge`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MergeSummary {
    /// The DEM mosaic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dem: Option<DemMergeSummary>,
    /// The stitched contours.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contours: Option<StitchSummary>,
    /// The mosaic's hillshade.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hillshade: Option<MergedHillshade>,
    /// The summed volumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub volume: Option<crate::sink::CutFillTotals>,
    /// The joined TIN.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tin: Option<super::mesh::TinMergeSummary>,
    /// A ground plan's points: a VPC of its tiles or one file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points: Option<super::ground_points::PointsMergeSummary>,
    /// Tasks joined.
    pub tasks: usize,
    /// Tasks that found no point.
    pub empty_tasks: usize,
    /// The widest buffer a task needed.
    pub max_buffer: f64,
    /// What the merge warns of (a mosaic of the tiles where one run's grid was asked for, from
    /// records of an older build); the command line prints them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// The lower-case extension of `p`.
fn extension(p: &Path) -> Option<String> {
    p.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// The CRS of the plan's output: its `--crs`, or the one its files declare, from their headers
/// as a single run over them all takes it (from the first file alone, a first file without one
/// left the mosaic without a CRS).
fn plan_crs(plan: &Plan) -> Result<Option<Crs>> {
    if let Some(c) = plan.job.crs()? {
        return Ok(Some(c));
    }
    let paths: Vec<PathBuf> = plan.files.iter().map(|f| f.path.clone()).collect();
    if paths.is_empty() {
        return Ok(None);
    }
    let r = crate::input::las::LidarReader::open(&paths, &crate::input::las::Filter::default())?;
    Ok(r.crs().cloned())
}

/// Why a plan of `product` has no contour lines for a merge's `--contours`: what it holds, and
/// what to do.
fn no_contours(product: &super::Product) -> String {
    use super::Product;
    match product {
        Product::Dem { .. } => "the plan makes a DEM without contour lines (it was made without --contours, so no task drew any): make the plan again with --contours FILE --interval N, or draw them from the mosaic (`sweeptin contours`)"
            .into(),
        Product::Contours(_) => "the plan makes contour lines, written to -o OUT.geojson: leave --contours out"
            .into(),
        Product::Volume { .. } => "the plan makes volumes, printed (--json for a summary), and no contour lines: leave --contours out"
            .into(),
        Product::Tin => "the plan makes a TIN (-o OUT.ply, .obj, .xml or .stin) and no contour lines: leave --contours out"
            .into(),
        Product::Ground => "the plan classifies points (-o OUT.vpc, .laz or .las) and draws no contour lines: leave --contours out"
            .into(),
    }
}

/// An output the plan was given (`"contours"`, `"hillshade"`).
fn planned(plan: &Plan, name: &str) -> Option<PathBuf> {
    plan.outputs
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, p)| p.clone())
}

/// The DEM mosaic's options: those given, or the plan's for a `.tif` when none is given.
///
/// # Errors
/// [`Error::Options`] for a mosaic that is neither `.vrt` nor `.tif`, an ESRI ASCII format, or
/// raster options given for a `.vrt`.
fn mosaic_options(
    plan: &Plan,
    dir: &super::PlanDir,
    out: &Path,
    given: &RasterOptions,
    given_extent: MosaicExtent,
    mem: u64,
) -> Result<MosaicOptions> {
    let super::Product::Dem {
        align,
        nodata,
        raster,
        ..
    } = &plan.job.product
    else {
        return Err(Error::Options("the plan makes no DEM".into()));
    };
    let ext = extension(out);
    if !matches!(ext.as_deref(), Some("vrt" | "tif" | "tiff")) {
        return Err(Error::Options(format!(
            "{}: a DEM mosaic is a .vrt or a .tif",
            out.display()
        )));
    }
    if ext.as_deref() == Some("vrt") && dir.is_remote() {
        return Err(Error::Options(format!(
            "{}: a .vrt mosaic names the plan's tile files, which are on S3 ({}): merge into a \
             .tif",
            out.display(),
            dir.display()
        )));
    }
    if ext.as_deref() == Some("vrt") && crate::input::source::is_remote(out) {
        return Err(Error::Options(format!(
            "{}: a .vrt mosaic names the plan's local tile files, which a reader of the object \
             cannot open: merge into a .tif (or write the .vrt beside the plan)",
            out.display()
        )));
    }
    super::task::check_mosaic(given)?;
    let default = RasterOptions::default();
    let output = match (ext.as_deref(), *given == default) {
        (Some("vrt"), true) => default,
        (Some("vrt"), false) => {
            return Err(Error::Options(format!(
                "{}: a .vrt mosaic points at the tiles as they are: leave --format, --compress, \
                 --predictor and --bigtiff out, or merge into a .tif",
                out.display()
            )));
        }
        // The plan's own --format / --compress, as one run would have written.
        (_, true) => *raster,
        (_, false) => *given,
    };
    Ok(MosaicOptions {
        nodata: *nodata,
        align: *align,
        output,
        extent: given_extent,
        mem,
    })
}

/// Joins the finished tasks of `plan` (in `dir`) into the job's result: the DEM mosaic (`.vrt`
/// or `.tif`, GeoTIFF or COG) with, when asked or planned, its stitched contours and its
/// hillshade; the contours (`.geojson`); the summed volumes (no file). Every output is checked
/// before anything is written.
///
/// # Errors
/// [`Error::Options`] for unfinished tasks, a missing or wrong output, an output that is an
/// input, the plan, a task's output or another output; [`Error::NothingLeft`] when no task
/// found a point; the readers' and writers' errors.
pub fn merge_plan(plan: &Plan, dir: &super::PlanDir, o: &MergeOutputs) -> Result<MergeSummary> {
    use super::Product;
    if o.mem < MIN_MERGE_MEM {
        return Err(Error::Options(format!(
            "--mem {}: a merge needs at least {} (its fixed buffers; the output's size does not \
             matter)",
            crate::human_bytes(o.mem),
            crate::human_bytes(MIN_MERGE_MEM)
        )));
    }
    crate::limits::check_address_space(o.mem, 0, "the merge's memory budget (--mem)")?;
    let out = o.out.as_deref();
    let dem = matches!(plan.job.product, Product::Dem { .. });
    if let Some(c) = &o.contours
        && !matches!(
            plan.job.product,
            Product::Dem {
                contours: Some(_),
                ..
            }
        )
    {
        // The tasks drew no lines to stitch: refused, never an exit 0 that writes nothing.
        return Err(Error::Options(format!(
            "--contours {}: {}",
            c.display(),
            no_contours(&plan.job.product)
        )));
    }
    let contours = o.contours.clone().or_else(|| planned(plan, "contours"));
    let contours_out = match &plan.job.product {
        Product::Contours(_) => out,
        _ => contours.as_deref(),
    };
    let hillshade = o.hillshade.clone().or_else(|| planned(plan, "hillshade"));
    let mut outs: Vec<(&str, &Path)> = Vec::new();
    if let Some(o) = out {
        outs.push((out_name(&plan.job.product), o));
    }
    if let Some(c) = &contours {
        outs.push(("the contours", c));
    }
    if let Some(h) = &hillshade {
        outs.push(("the hillshade", h));
    }
    let mut protected = plan.read_files();
    protected.push(dir.join("plan.json"));
    crate::output::distinct_outputs(&outs, &protected, "the plan")?;
    if let Some(c) = contours_out {
        // Before anything is written (a DEM plan's mosaic comes first).
        crate::output::lines::LineFormat::of(c)?;
    }
    for (what, o) in &outs {
        crate::output::check_output(o)?;
        dir.outside(what, o)?;
    }
    fn need<'a>(o: Option<&'a Path>, what: &str) -> Result<&'a Path> {
        o.ok_or_else(|| Error::Options(format!("give the {what}")))
    }
    let mosaic = if dem {
        let out = need(out, "mosaic (OUT.vrt or OUT.tif)")?;
        let m = mosaic_options(plan, dir, out, &o.raster, o.extent, o.mem)?;
        if hillshade.is_some() && extension(out).as_deref() == Some("vrt") {
            return Err(Error::Options(
                "--hillshade shades a GeoTIFF mosaic: merge with -o OUT.tif".into(),
            ));
        }
        Some((out, m))
    } else {
        if hillshade.is_some() {
            return Err(Error::Options(
                "--hillshade shades a DEM plan's mosaic".into(),
            ));
        }
        if o.extent != MosaicExtent::default() {
            return Err(Error::Options(
                "--extent applies to a DEM plan's mosaic".into(),
            ));
        }
        if o.raster != RasterOptions::default() {
            return Err(Error::Options(
                "--format, --compress, --predictor and --bigtiff apply to a DEM plan's mosaic"
                    .into(),
            ));
        }
        None
    };
    let recs = records(plan, dir)?;
    super::record::nothing_to_merge(plan, dir, &recs)?;
    let mut summary = MergeSummary {
        tasks: recs.len(),
        empty_tasks: recs.iter().filter(|r| r.status == "empty").count(),
        max_buffer: recs.iter().map(|r| r.buffer).fold(0.0, f64::max),
        ..MergeSummary::default()
    };
    match &plan.job.product {
        Product::Dem {
            contours: levels, ..
        } => {
            let Some((out, m)) = mosaic else {
                return Err(Error::Internal("a DEM plan without its mosaic".into()));
            };
            let crs = plan_crs(plan)?;
            let (dem, warning) = merge_dem(plan, dir, out, &m, crs.as_ref())?;
            summary.dem = Some(dem);
            summary.warnings.extend(warning);
            if let (Some(c), Some(_)) = (&contours, levels) {
                summary.contours = Some(merge_contours(plan, dir, c, crs.as_ref(), o.mem)?);
            }
            if let Some(h) = hillshade {
                let s = hillshade::hillshade(out, &h, &hillshade::HillshadeOptions::default())?;
                summary.hillshade = Some(MergedHillshade {
                    path: h,
                    summary: s,
                });
            }
        }
        Product::Contours(_) => {
            let out = need(out, "contours (OUT.geojson or OUT.gpkg)")?;
            let crs = plan_crs(plan)?;
            summary.contours = Some(merge_contours(plan, dir, out, crs.as_ref(), o.mem)?);
        }
        Product::Volume { .. } => {
            if let Some(o) = out {
                return Err(Error::Options(format!(
                    "{}: a volume plan writes no file (its totals are printed; --json for a \
                     summary)",
                    o.display()
                )));
            }
            summary.volume = Some(merge_volume(plan, dir)?);
        }
        Product::Tin => {
            let out = need(out, "mesh (OUT.ply, OUT.obj, OUT.xml or OUT.stin)")?;
            let crs = plan_crs(plan)?;
            let def = crs.as_ref().and_then(Crs::definition);
            summary.tin = Some(super::mesh::merge_tin(plan, dir, &recs, out, def)?);
        }
        Product::Ground => {
            let out = need(out, "points (OUT.vpc, OUT.laz or OUT.las)")?;
            let batch = batch_share(o.mem);
            let p = super::ground_points::merge_points(plan, dir, &recs, out, batch)?;
            summary.points = Some(p);
        }
    }
    Ok(summary)
}

/// What `merge -o` writes for `product`, as its messages name it.
fn out_name(product: &super::Product) -> &'static str {
    use super::Product;
    match product {
        Product::Dem { .. } => "the mosaic",
        Product::Contours(_) => "the contours",
        Product::Tin => "the mesh",
        Product::Ground => "the merged points",
        Product::Volume { .. } => "the volume report",
    }
}
