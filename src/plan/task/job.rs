//! What a plan's tasks run, typed: the [`Job`] (its [`Product`], and how the points are read),
//! stored in `plan.json` and checked when a plan is made or loaded.

use super::nodata;
use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::input::las::{Filter, Returns};
use crate::output::raster::{RasterFormat, RasterOptions};
use crate::products::contours::ContourOptions;
use crate::raster::Align;
use crate::sort::memory::DuplicatePolicy;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Contour levels: `base + k × interval`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Levels {
    /// Distance between levels (> 0).
    pub interval: f64,
    /// A level through which the others are counted.
    pub base: f64,
    /// Decimals of the merged lines' coordinates (`--precision`; `None`: the data's,
    /// [`crate::pipeline::contour_decimals`]). The tasks write every bit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decimals: Option<u32>,
    /// The merge leaves out lines shorter than this (`--min-length`).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub min_length: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Levels {
    /// The contour sink's options, with end edges for the merge (`edges`).
    pub(super) fn options(&self, edges: bool, mem: u64) -> ContourOptions {
        ContourOptions {
            interval: self.interval,
            base: self.base,
            edges,
            ..ContourOptions::default()
        }
        .within(mem)
    }
}

/// The product a plan makes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Product {
    /// A DEM of cells of `cell` (tiles are whole multiples of it), optionally with contours.
    Dem {
        /// Cell size.
        cell: f64,
        /// Where the cells lie: edges (the default) or centres on multiples of `cell`.
        align: Align,
        /// Value of cells without data (stored as a string when not finite: `"NaN"`).
        #[serde(with = "nodata")]
        nodata: f32,
        /// The mosaic's format (GeoTIFF or COG; by its extension when not given), compression,
        /// predictor, BigTIFF. The tasks write plain GeoTIFF tiles whatever it says; `merge`
        /// writes the mosaic with it unless told otherwise.
        raster: RasterOptions,
        /// Contours from the same pass.
        contours: Option<Levels>,
    },
    /// Contour lines.
    Contours(Levels),
    /// The TIN itself: each task writes its tiles' triangles as mesh pieces
    /// ([`crate::output::pieces`]); `merge` joins them into one mesh (PLY, OBJ, LandXML or a
    /// streaming mesh, by the output's extension), each vertex once.
    Tin,
    /// The ground classification itself (`plan ground`, with [`Job::ground`]): each task
    /// writes the points its tile owns with the classes one `sweeptin ground` run gives them
    /// (`plan::ground_points`); `merge` writes a VPC of those tiles or one LAS/LAZ file.
    Ground,
    /// Cut and fill against the plane `z = plane`, within an optional boundary polygon.
    Volume {
        /// The plane's height.
        plane: f64,
        /// The boundary polygon file (absolute), with its size and SHA-256: every task checks
        /// that it still holds what the plan saw (an edit between tasks mixed two polygons).
        #[serde(deserialize_with = "pinned")]
        boundary: Option<crate::plan::LineFile>,
    },
}

/// A volume's boundary: pinned ([`crate::plan::LineFile`]); a bare path (a plan of an older build,
/// which tasks could not check) is refused with what to do.
fn pinned<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<crate::plan::LineFile>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Form {
        Pinned(crate::plan::LineFile),
        Path(PathBuf),
    }
    match Option::<Form>::deserialize(d)? {
        None => Ok(None),
        Some(Form::Pinned(f)) => Ok(Some(f)),
        Some(Form::Path(p)) => Err(serde::de::Error::custom(format!(
            "the volume boundary {} is not pinned by size and SHA-256 (a plan of an older \
             sweeptin): make the plan again",
            p.display()
        ))),
    }
}

/// A plan's job: the product and how the points are read (everything a task needs besides its
/// tile, its files and its buffer).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Job {
    /// What is made.
    pub product: Product,
    /// Classification codes kept (`None`: all).
    pub classes: Option<Vec<u8>>,
    /// Returns kept.
    pub returns: Returns,
    /// Drop withheld points.
    pub drop_withheld: bool,
    /// Which point survives among exact (x, y) duplicates.
    pub duplicates: DuplicatePolicy,
    /// Drop triangles with a horizontal edge longer than this.
    pub max_edge: Option<f64>,
    /// The CRS recorded in the outputs (`EPSG:code`, `EPSG:h+v` or WKT) instead of the input's.
    pub crs: Option<String>,
    /// Memory budget of a task's sort, in bytes.
    pub mem: u64,
    /// Where a task's spill files go.
    pub tmp_dir: Option<PathBuf>,
    /// Breaklines and trimming rings every task inserts (every vertex with its z; see
    /// [`crate::plan::PlanLines`]). Absent from the plans of versions before 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lines: Option<crate::plan::PlanLines>,
    /// `--ground`: every task classifies the ground of its area first (as one run would,
    /// `plan::ground`) and reads the points with those classes (`classes` then selects,
    /// class 2 when `None`). Absent from the plans of versions before 4.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<crate::ground::GroundParams>,
}

impl Job {
    /// A job making `product` from every point (withheld ones dropped), with the defaults of a
    /// single run.
    pub fn new(product: Product) -> Job {
        let f = Filter::default();
        Job {
            product,
            classes: f.classes,
            returns: f.returns,
            drop_withheld: f.drop_withheld,
            duplicates: DuplicatePolicy::default(),
            max_edge: None,
            crs: None,
            mem: crate::pipeline::default_mem(),
            tmp_dir: None,
            lines: None,
            ground: None,
        }
    }

    /// The command that makes the product (`dem`, `contours`, `volume`).
    pub fn command(&self) -> &'static str {
        match self.product {
            Product::Dem { .. } => "dem",
            Product::Contours(_) => "contours",
            Product::Volume { .. } => "volume",
            Product::Tin => "tin",
            Product::Ground => "ground",
        }
    }

    /// What a task with no point writes, for a message: `a nodata raster`, `no contour line`,
    /// `zero volumes`, `no triangle`.
    pub fn empty_outputs(&self) -> &'static str {
        match self.product {
            Product::Dem {
                contours: Some(_), ..
            } => "a nodata raster and no contour line",
            Product::Dem { .. } => "a nodata raster",
            Product::Contours(_) => "no contour line",
            Product::Volume { .. } => "zero volumes",
            Product::Tin => "no triangle",
            Product::Ground => "no point",
        }
    }

    /// The DEM's cell size, when the job makes one.
    pub fn cell(&self) -> Option<f64> {
        match self.product {
            Product::Dem { cell, .. } => Some(cell),
            _ => None,
        }
    }

    /// The points' filter.
    pub fn filter(&self) -> Filter {
        Filter {
            classes: self.classes.clone(),
            returns: self.returns,
            drop_withheld: self.drop_withheld,
            bbox: None,
            z_from: None,
            classes_from: None,
        }
    }

    /// The CRS given, parsed.
    ///
    /// # Errors
    /// [`Error::Options`] for a CRS that is not one.
    pub fn crs(&self) -> Result<Option<Crs>> {
        self.crs.as_deref().map(Crs::parse).transpose()
    }

    /// Checks the product's options as its sinks would (before a plan is written).
    ///
    /// # Errors
    /// [`Error::Options`] naming the bad value.
    pub fn check(&self) -> Result<()> {
        let positive = |v: f64, what: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::Options(format!(
                    "{what} must be a positive number, not {v}"
                )))
            }
        };
        let levels = |l: &Levels| {
            positive(l.interval, "the contour interval")?;
            if !(l.min_length.is_finite() && l.min_length >= 0.0) {
                return Err(Error::Options(format!(
                    "--min-length must be a length >= 0 in map units, not {}",
                    l.min_length
                )));
            }
            if l.decimals
                .is_some_and(|d| d > crate::output::lines::MAX_DECIMALS)
            {
                return Err(Error::Options(format!(
                    "--precision: at most {} decimals",
                    crate::output::lines::MAX_DECIMALS
                )));
            }
            if l.base.is_finite() {
                Ok(())
            } else {
                Err(Error::Options(format!(
                    "the contour base must be finite, not {}",
                    l.base
                )))
            }
        };
        match &self.product {
            Product::Dem {
                cell,
                raster,
                contours,
                ..
            } => {
                positive(*cell, "the cell size")?;
                contours.as_ref().map_or(Ok(()), levels)?;
                check_mosaic(raster)?;
            }
            Product::Contours(l) => levels(l)?,
            Product::Volume { plane, .. } => crate::products::volume::check_plane(*plane)?,
            Product::Tin => {}
            Product::Ground if self.ground.is_none() => {
                return Err(Error::Options(
                    "a ground plan needs the filter's parameters (Job::ground)".into(),
                ));
            }
            Product::Ground => {}
        }
        if let Some(m) = self.max_edge {
            positive(m, "--max-edge")?;
        }
        if let Some(g) = &self.ground {
            g.check()?;
        }
        self.crs()?;
        Ok(())
    }
}

/// Refuses mosaic options that `merge` could not write: an ESRI ASCII mosaic, or compression
/// options that do not go together.
///
/// # Errors
/// [`Error::Options`] naming the option.
pub(in crate::plan) fn check_mosaic(raster: &RasterOptions) -> Result<()> {
    if raster.format == Some(RasterFormat::Ascii) {
        return Err(Error::Options(
            "--format asc: a DEM mosaic is a GeoTIFF (tif, cog) or a VRT".into(),
        ));
    }
    match raster.resolve(Path::new("mosaic.tif"), false) {
        Ok(_) => Ok(()),
        Err(Error::Output { message, .. }) => Err(Error::Options(message)),
        Err(e) => Err(e),
    }
}
