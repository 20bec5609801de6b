//! Joining the outputs of a plan's tasks: DEM tiles into a GDAL VRT or one GeoTIFF, contour lines
//! stitched across tile edges, volumes summed exactly.

use super::{Plan, TaskRecord};
use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::input::raster::RasterReader;
use crate::output::raster::{RasterFormat, RasterOptions, create_grid_writer};
use crate::raster::{Align, GridExtent, GridPlan};
use std::path::{Path, PathBuf};

pub use super::stitch::{StitchSummary, stitch};

/// The records of every task of `plan` under `dir`.
///
/// # Errors
/// [`Error::Options`] naming the tasks that have not finished.
pub fn records(plan: &Plan, dir: &Path) -> Result<Vec<TaskRecord>> {
    let mut out = Vec::with_capacity(plan.tiles.len());
    let mut missing = Vec::new();
    for t in &plan.tiles {
        match plan.record(dir, t.index)? {
            Some(r) => out.push(r),
            None => missing.push(t.index),
        }
    }
    if !missing.is_empty() {
        let list: Vec<String> = missing.iter().take(20).map(|i| i.to_string()).collect();
        return Err(Error::Options(format!(
            "{} of {} tasks have not finished (run them first: `sweeptin run {} --task I`): {}{}",
            missing.len(),
            plan.tiles.len(),
            dir.join("plan.json").display(),
            list.join(", "),
            if missing.len() > 20 { ", …" } else { "" }
        )));
    }
    Ok(out)
}

/// The output `name` of every task, in task order.
fn outputs<'a>(records: &'a [TaskRecord], name: &str) -> Result<Vec<&'a Path>> {
    records
        .iter()
        .map(|r| {
            r.outputs
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, p)| p.as_path())
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
}

/// The mosaic's grid: the union of the tiles, on the plan's cell lattice.
fn mosaic_grid(
    plan: &Plan,
    nodata: f32,
    align: Align,
    crs: Option<&Crs>,
) -> Result<crate::raster::GridSpec> {
    let cell = plan
        .cell
        .ok_or_else(|| Error::Options("the plan makes no DEM".into()))?;
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for t in &plan.tiles {
        b = [
            b[0].min(t.bounds[0]),
            b[1].min(t.bounds[1]),
            b[2].max(t.bounds[2]),
            b[3].max(t.bounds[3]),
        ];
    }
    let mut g = GridPlan::new(
        cell,
        GridExtent::BBox {
            bbox: b,
            snap: false,
        },
        align,
    )?
    .grid(b, nodata)?;
    g.crs = crs.cloned();
    Ok(g)
}

/// Where tile raster `r` sits in the mosaic `g`: its first column and row.
fn offset(g: &crate::raster::GridSpec, r: &crate::input::raster::RasterSpec) -> (u32, u32) {
    let o = g.origin();
    let col = ((r.transform[0] - o[0]) / g.cell).round() as u32;
    let row = ((o[1] - r.transform[3]) / g.cell).round() as u32;
    (col, row)
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
}

/// Joins the DEM tiles into `out`: a GDAL VRT (`.vrt`) over the tile GeoTIFFs, or one GeoTIFF
/// or COG (`.tif`) written tile by tile into the writer's stage, in bounded memory.
///
/// # Errors
/// Reading the tiles or writing; [`Error::Options`] for unfinished tasks or an unknown extension.
pub fn merge_dem(
    plan: &Plan,
    dir: &Path,
    out: &Path,
    options: &MosaicOptions,
    crs: Option<&Crs>,
) -> Result<DemMergeSummary> {
    let recs = records(plan, dir)?;
    let tiles = outputs(&recs, "dem")?;
    let nodata = options.nodata;
    let g = mosaic_grid(plan, nodata, options.align, crs)?;
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() == Some("vrt") && options.output.format.is_none() {
        write_vrt(&g, &tiles, out)?;
    } else {
        let mut o = options.output;
        if o.format.is_none() {
            o.format = Some(RasterFormat::GeoTiff);
        }
        let mut w = create_grid_writer(out, &o, &g)?;
        for path in &tiles {
            let mut r = RasterReader::open(path)?;
            let spec = r.spec().clone();
            let (c0, r0) = offset(&g, &spec);
            let rows_at_once = (1 << 20) / spec.cols.max(1);
            let mut row = 0;
            while row < spec.rows {
                let n = rows_at_once.clamp(1, spec.rows - row);
                let v = r.read_window(0, row, spec.cols, n)?;
                for k in 0..n {
                    let a = (k * spec.cols) as usize;
                    let vals: Vec<f32> = v[a..a + spec.cols as usize]
                        .iter()
                        .map(|&x| if x.is_nan() { nodata } else { x as f32 })
                        .collect();
                    w.write_span(r0 + row + k, c0, &vals)?;
                }
                row += n;
            }
        }
        w.finish()?;
    }
    Ok(DemMergeSummary {
        path: out.to_path_buf(),
        cols: g.cols,
        rows: g.rows,
        tiles: tiles.len() as u64,
    })
}

fn write_vrt(g: &crate::raster::GridSpec, tiles: &[&Path], out: &Path) -> Result<()> {
    use std::fmt::Write as _;
    let o = g.origin();
    let mut x = String::new();
    let _ = writeln!(
        x,
        "<VRTDataset rasterXSize=\"{}\" rasterYSize=\"{}\">",
        g.cols, g.rows
    );
    if let Some(def) = g.crs.as_ref().and_then(|c| c.definition()) {
        let _ = writeln!(x, "  <SRS>{}</SRS>", xml(&def));
    }
    let _ = writeln!(
        x,
        "  <GeoTransform>{:?}, {:?}, 0, {:?}, 0, {:?}</GeoTransform>",
        o[0], g.cell, o[1], -g.cell
    );
    let _ = writeln!(x, "  <VRTRasterBand dataType=\"Float32\" band=\"1\">");
    let _ = writeln!(x, "    <NoDataValue>{:?}</NoDataValue>", g.nodata);
    for path in tiles {
        let r = RasterReader::open(path)?;
        let spec = r.spec();
        let (c0, r0) = offset(g, spec);
        let abs = std::fs::canonicalize(path).map_err(|e| Error::io(*path, e))?;
        let _ = writeln!(x, "    <SimpleSource>");
        let _ = writeln!(
            x,
            "      <SourceFilename relativeToVRT=\"0\">{}</SourceFilename>",
            xml(&abs.to_string_lossy())
        );
        let _ = writeln!(x, "      <SourceBand>1</SourceBand>");
        let _ = writeln!(
            x,
            "      <SrcRect xOff=\"0\" yOff=\"0\" xSize=\"{c}\" ySize=\"{r}\"/>\n      \
             <DstRect xOff=\"{c0}\" yOff=\"{r0}\" xSize=\"{c}\" ySize=\"{r}\"/>",
            c = spec.cols,
            r = spec.rows
        );
        let _ = writeln!(x, "    </SimpleSource>");
    }
    let _ = writeln!(x, "  </VRTRasterBand>\n</VRTDataset>");
    super::write_atomic(out, x.as_bytes())
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Stitches the tasks' contours into `out`.
///
/// # Errors
/// As [`stitch`]; unfinished tasks.
pub fn merge_contours(
    plan: &Plan,
    dir: &Path,
    out: &Path,
    crs: Option<&Crs>,
) -> Result<StitchSummary> {
    let recs = records(plan, dir)?;
    let parts = outputs(&recs, "contours")?;
    stitch(&parts, out, crs)
}

/// The exact totals of the tasks' volumes (the same, bit for bit, as one run over all points).
///
/// # Errors
/// Unfinished tasks, or a task without volume sums.
pub fn merge_volume(plan: &Plan, dir: &Path) -> Result<crate::sink::CutFillTotals> {
    let recs = records(plan, dir)?;
    let mut parts = Vec::with_capacity(recs.len());
    for r in &recs {
        parts.push(
            r.volume
                .clone()
                .ok_or_else(|| Error::Options(format!("task {} recorded no volume", r.index)))?,
        );
    }
    Ok(crate::products::volume::CutFill::totals_of(&parts))
}
