//! Hillshade of a DEM, as a PNG (with a world file) so that a result can be seen at a glance, or
//! as an 8-bit georeferenced GeoTIFF / COG for a GIS.
//!
//! The shading is the one `gdaldem hillshade` computes (Horn's slope, Lambertian light): for the
//! 3 × 3 window `a b c / d e f / g h i` around a cell, with cell sizes `ew`, `ns` and z factor `k`,
//!
//! ```text
//! x = ((a + 2d + g) − (c + 2f + i)) / (8 ew)      y = ((a + 2b + c) − (g + 2h + i)) / (8 ns)
//! shade = (sin alt − k (y cos az cos alt − x sin az cos alt)) / √(1 + k² (x² + y²))
//! value = 1 + 254 × max(shade, 0)
//! ```
//!
//! with the light from azimuth `az` (degrees clockwise from north; 315 = north-west, the
//! cartographic convention) at altitude `alt` above the horizon. The cell sizes are in the units
//! of the heights: multiplied by `scale` (as `gdaldem hillshade -s`), or, for a DEM in a
//! geographic CRS when neither the scale nor the z factor is given, by the metres a degree
//! spans east and north at the DEM's centre latitude on the WGS 84 ellipsoid (what
//! `gdaldem -s 111120` approximates by hand; a DEM in degrees shaded with metres of height as
//! if both were one unit is black and white). Unlike `gdaldem`'s default, the
//! edge cells and the cells next to nodata are shaded too: missing neighbours are extrapolated
//! linearly from the others (exact on a plane); nodata cells are transparent.
//!
//! The DEM is read a band of rows at a time ([`RasterReader`]: any single-band GeoTIFF the `tiff`
//! crate decodes, striped or tiled, and ESRI ASCII grids); the cell size, origin, CRS and nodata
//! value come from it and go to the output's georeferencing.

use crate::crs::{Crs, LostCrs};
use crate::error::{Error, Result};
use crate::input::raster::{RasterReader, RasterSpec};
use crate::output::AtomicFile;
use crate::output::cog::{TiffGeo, write_u8_image};
use crate::output::raster::{RasterFormat, RasterOptions};
use crate::output::world::{write_aux_xml, write_prj, write_world_file};
use std::collections::VecDeque;
use std::io::Write;
use std::path::Path;

/// Light and exaggeration.
#[derive(Clone, Copy, Debug)]
pub struct HillshadeOptions {
    /// Direction the light comes from, degrees clockwise from north.
    pub azimuth: f64,
    /// Height of the light above the horizon, degrees.
    pub altitude: f64,
    /// Vertical exaggeration; `None`: 1 (and the scale may come from the CRS).
    pub z_factor: Option<f64>,
    /// Horizontal units per unit of height, as `gdaldem hillshade -s` (111120 for degrees and
    /// metres); `None`: from the CRS when it is geographic and no z factor is given, else 1.
    pub scale: Option<f64>,
    /// Output format (PNG by a `.png` extension; GeoTIFF or COG) and compression.
    pub output: RasterOptions,
}

impl HillshadeOptions {
    /// Checks the options: an azimuth in [0, 360], an altitude in [0, 90] degrees, a positive
    /// finite z factor and scale (anything else shades every cell the same).
    ///
    /// # Errors
    /// [`Error::Options`] naming the option and the value.
    pub fn check(&self) -> Result<()> {
        let bad = |what: &str, v: f64, range: &str| {
            Err(Error::Options(format!("--{what} {v}: must be {range}")))
        };
        if !(0.0..=360.0).contains(&self.azimuth) {
            return bad("azimuth", self.azimuth, "from 0 to 360 degrees");
        }
        if !(0.0..=90.0).contains(&self.altitude) {
            return bad("altitude", self.altitude, "from 0 to 90 degrees");
        }
        for (what, v) in [("z-factor", self.z_factor), ("scale", self.scale)] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return bad(what, v, "a positive number");
            }
        }
        Ok(())
    }
}

impl Default for HillshadeOptions {
    fn default() -> Self {
        HillshadeOptions {
            azimuth: 315.0,
            altitude: 45.0,
            z_factor: None,
            scale: None,
            output: RasterOptions::default(),
        }
    }
}

/// What [`hillshade`] produced.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct HillshadeSummary {
    /// Image width.
    pub cols: u32,
    /// Image height.
    pub rows: u32,
    /// Cells with data.
    pub shaded: u64,
    /// Bytes of the PNG.
    pub bytes: u64,
    /// Metres per degree east and north taken from a geographic CRS (at the centre latitude),
    /// when the scale came from it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub metres_per_degree: Option<[f64; 2]>,
    /// What the output lost of the CRS (none known, or no `.prj` for a PNG).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lost_crs: Option<LostCrs>,
    /// Other warnings: cells that look like degrees in a DEM that declares no CRS.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// The shade of the centre of a 3 × 3 window. Missing (NaN) neighbours are extrapolated so that
/// a plane stays a plane: a side neighbour through the centre from the opposite side
/// (`2e − opposite`, or `e` if that is missing too), a corner from the opposite corner the same
/// way, or else from its two side neighbours (`side₁ + side₂ − e`).
fn shade(w: [[f64; 3]; 3], ew: f64, ns: f64, k: f64, o: &HillshadeOptions) -> u8 {
    let e = w[1][1];
    let mut f = w;
    for (r, c) in [(0, 1), (1, 0), (1, 2), (2, 1)] {
        if f[r][c].is_nan() {
            let opposite = w[2 - r][2 - c];
            f[r][c] = if opposite.is_nan() {
                e
            } else {
                2.0 * e - opposite
            };
        }
    }
    for (r, c) in [(0, 0), (0, 2), (2, 0), (2, 2)] {
        if f[r][c].is_nan() {
            let opposite = w[2 - r][2 - c];
            f[r][c] = if opposite.is_nan() {
                f[r][1] + f[1][c] - e
            } else {
                2.0 * e - opposite
            };
        }
    }
    let v = |r: usize, c: usize| f[r][c];
    let x =
        ((v(0, 0) + 2.0 * v(1, 0) + v(2, 0)) - (v(0, 2) + 2.0 * v(1, 2) + v(2, 2))) / (8.0 * ew);
    let y =
        ((v(0, 0) + 2.0 * v(0, 1) + v(0, 2)) - (v(2, 0) + 2.0 * v(2, 1) + v(2, 2))) / (8.0 * ns);
    let (az, alt) = (o.azimuth.to_radians(), o.altitude.to_radians());
    let s = (alt.sin() - k * (y * az.cos() * alt.cos() - x * az.sin() * alt.cos()))
        / (1.0 + k * k * (x * x + y * y)).sqrt();
    (1.0 + 254.0 * s.max(0.0)).round().clamp(1.0, 255.0) as u8
}

/// Rows of a grid read a band at a time (missing cells NaN), north to south.
struct Rows {
    reader: RasterReader,
    next_row: u32,
    ready: VecDeque<Vec<f64>>,
}

impl Rows {
    /// Rows read per band.
    const BAND: u32 = 256;

    fn new(reader: RasterReader) -> Rows {
        Rows {
            reader,
            next_row: 0,
            ready: VecDeque::new(),
        }
    }

    fn next(&mut self) -> Result<Option<Vec<f64>>> {
        let (w, h) = (self.reader.spec().cols, self.reader.spec().rows);
        if self.ready.is_empty() && self.next_row < h {
            let n = Self::BAND.min(h - self.next_row);
            let v = self.reader.read_window(0, self.next_row, w, n)?;
            self.ready
                .extend(v.chunks_exact(w as usize).map(<[f64]>::to_vec));
            self.next_row += n;
        }
        Ok(self.ready.pop_front())
    }
}

/// How the rows are shaded: cell sizes in the heights' units, and the z factor.
#[derive(Clone, Copy, Debug)]
struct Scaled {
    ew: f64,
    ns: f64,
    k: f64,
}

/// What [`shade_rows`] saw: cells shaded, lowest and highest height.
struct Shaded {
    cells: u64,
    z: [f64; 2],
}

/// Shades every row `next` gives (`w` cells each, north to south, missing cells NaN), calling
/// `row` with each (values 1–255, 0 where the DEM has no data).
fn shade_rows(
    w: usize,
    mut next: impl FnMut() -> Result<Option<Vec<f64>>>,
    g: Scaled,
    o: &HillshadeOptions,
    mut row: impl FnMut(u32, &[u8]) -> Result<()>,
) -> Result<Shaded> {
    let Scaled { ew, ns, k } = g;
    let mut shaded = 0u64;
    let mut z = [f64::INFINITY, f64::NEG_INFINITY];
    let mut prev: Option<Vec<f64>> = None;
    let mut cur = next()?;
    let mut line = vec![0u8; w];
    let mut r = 0u32;
    while let Some(c) = cur.take() {
        let below = next()?;
        let cell = |row: Option<&Vec<f64>>, x: Option<usize>| match (row, x) {
            (Some(r), Some(x)) if x < w => r[x],
            _ => f64::NAN,
        };
        for x in 0..w {
            if c[x].is_nan() {
                line[x] = 0;
                continue;
            }
            let (l, m, rr) = (x.checked_sub(1), Some(x), Some(x + 1));
            let (a, b) = (prev.as_ref(), below.as_ref());
            let win = [
                [cell(a, l), cell(a, m), cell(a, rr)],
                [cell(Some(&c), l), c[x], cell(Some(&c), rr)],
                [cell(b, l), cell(b, m), cell(b, rr)],
            ];
            line[x] = shade(win, ew, ns, k, o);
            shaded += 1;
            z = [z[0].min(c[x]), z[1].max(c[x])];
        }
        row(r, &line)?;
        r += 1;
        prev = Some(c);
        cur = below;
    }
    Ok(Shaded { cells: shaded, z })
}

/// Metres per degree east and north at latitude `lat` (degrees) on the WGS 84 ellipsoid: the
/// radii of curvature in the prime vertical (times cos φ) and in the meridian.
pub fn metres_per_degree(lat: f64) -> [f64; 2] {
    let (a, f) = (6_378_137.0_f64, 1.0 / 298.257_223_563);
    let e2 = f * (2.0 - f);
    let phi = lat.clamp(-90.0, 90.0).to_radians();
    let w = (1.0 - e2 * phi.sin().powi(2)).sqrt();
    let n = a / w;
    let m = a * (1.0 - e2) / (w * w * w);
    let rad = std::f64::consts::PI / 180.0;
    [n * phi.cos() * rad, m * rad]
}

/// The CRS a grid reader reports (`EPSG:code` or WKT), as the writers take it.
fn crs_of(text: Option<&str>) -> Option<Crs> {
    let t = text?;
    match t.strip_prefix("EPSG:").and_then(|c| c.parse().ok()) {
        Some(code) => Some(Crs {
            epsg: Some(code),
            ..Crs::default()
        }),
        None => Crs::from_wkt_bytes(t.as_bytes()),
    }
}

/// How a grid of `spec` is shaded: its cell sizes in the heights' units — times the scale
/// given, or, for a geographic CRS when neither the scale nor the z factor is given, times the
/// metres a degree spans at the grid's centre latitude (returned too) — and the z factor.
fn scaling(
    spec: &RasterSpec,
    crs: Option<&Crs>,
    o: &HillshadeOptions,
) -> (Scaled, Option<[f64; 2]>) {
    let (ew, ns) = spec.cell_size();
    let metres_per_degree = (o.scale.is_none()
        && o.z_factor.is_none()
        && crs.is_some_and(Crs::is_geographic))
    .then(|| metres_per_degree(spec.transform[3] + 0.5 * f64::from(spec.rows) * spec.transform[5]));
    let [sx, sy] = metres_per_degree.unwrap_or([o.scale.unwrap_or(1.0); 2]);
    let g = Scaled {
        ew: ew * sx,
        ns: ns * sy,
        k: o.z_factor.unwrap_or(1.0),
    };
    (g, metres_per_degree)
}

/// Writes a grey + alpha PNG of `w × h` to `out` (named `name` in errors): `shade` is given the
/// function that takes each row of shades (0, no data, transparent).
fn write_png<W: Write>(
    out: W,
    w: u32,
    h: u32,
    name: &Path,
    shade: impl FnOnce(&mut dyn FnMut(u32, &[u8]) -> Result<()>) -> Result<Shaded>,
) -> Result<Shaded> {
    let png_err = |e: png::EncodingError| Error::Output {
        path: name.to_path_buf(),
        message: format!("PNG: {e}"),
    };
    let mut enc = png::Encoder::new(out, w, h);
    enc.set_color(png::ColorType::GrayscaleAlpha);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(png_err)?;
    let mut stream = writer.stream_writer().map_err(png_err)?;
    let mut ga = vec![0u8; w as usize * 2];
    let shaded = shade(&mut |_, line| {
        for (x, v) in line.iter().enumerate() {
            ga[2 * x] = *v;
            ga[2 * x + 1] = if *v == 0 { 0 } else { 255 };
        }
        stream.write_all(&ga).map_err(|e| Error::write(name, e))
    })?;
    stream.finish().map_err(png_err)?;
    Ok(shaded)
}

/// The hillshade of a north-up grid held in memory (`values`, row-major from the north-west
/// cell, missing cells NaN; its size, cells and CRS from `spec`) as the bytes of a grey + alpha
/// PNG (nodata transparent), shaded as [`hillshade`] shades a file; with the cells shaded.
/// A plan's report draws the overview of its mosaic with it.
///
/// # Errors
/// [`Error::Options`] for options out of range; [`Error::Internal`] for values that are not
/// `spec`'s cells or a grid that is not north-up.
pub fn hillshade_png(
    values: &[f64],
    spec: &RasterSpec,
    o: &HillshadeOptions,
) -> Result<(Vec<u8>, u64)> {
    o.check()?;
    let (w, h) = (spec.cols, spec.rows);
    if values.len() as u64 != spec.cells()
        || !(spec.is_axis_aligned() && spec.transform[1] > 0.0 && spec.transform[5] < 0.0)
    {
        return Err(Error::Internal(format!(
            "hillshade_png: {} values for a {w} × {h} grid of transform {:?}",
            values.len(),
            spec.transform
        )));
    }
    let crs = crs_of(spec.crs.as_deref());
    let (g, _) = scaling(spec, crs.as_ref(), o);
    let mut bytes = Vec::new();
    let mut rows = values.chunks_exact(w.max(1) as usize);
    let shaded = write_png(&mut bytes, w, h, Path::new("(in memory)"), |line| {
        shade_rows(
            w as usize,
            || Ok(rows.next().map(<[f64]>::to_vec)),
            g,
            o,
            line,
        )
    })?;
    Ok((bytes, shaded.cells))
}

/// Shades the DEM at `input` (GeoTIFF, COG or ESRI ASCII grid, read a band of rows at a time)
/// into `output`: a grey + alpha PNG (nodata transparent) with a world file (`.pgw`) and, when
/// the CRS can be written as WKT ([`Crs::prj`]), a `.prj` and GDAL's `.png.aux.xml`; or, by extension or `o.output.format`, an 8-bit
/// georeferenced GeoTIFF or COG (0 = nodata, as `gdaldem hillshade` writes).
///
/// # Errors
/// [`Error::Io`] / [`Error::Format`] naming the file, for a rotated grid or one not stored
/// north-up; [`Error::Output`] for an unknown output format; [`Error::Options`] for options out of range
/// ([`HillshadeOptions::check`]).
pub fn hillshade(input: &Path, output: &Path, o: &HillshadeOptions) -> Result<HillshadeSummary> {
    o.check()?;
    let reader = RasterReader::open(input)?;
    let spec = reader.spec().clone();
    if !spec.is_axis_aligned() {
        return Err(Error::Format {
            path: input.to_path_buf(),
            message: "a rotated or sheared grid cannot be shaded".into(),
        });
    }
    // Rows run north to south and columns west to east here: a south-up grid was shaded with
    // north and south swapped and placed a raster's height south.
    if !(spec.transform[1] > 0.0 && spec.transform[5] < 0.0) {
        return Err(Error::Format {
            path: input.to_path_buf(),
            message: "the grid is stored south-up or east to west (a pixel height that is not \
                      negative): make it north-up first (gdalwarp in.tif out.tif)"
                .into(),
        });
    }
    let (w, h) = (spec.cols, spec.rows);
    let (ew, ns) = spec.cell_size();
    let origin = [spec.transform[0], spec.transform[3]];
    let crs = crs_of(spec.crs.as_deref());
    let (g, metres_per_degree) = scaling(&spec, crs.as_ref(), o);
    // Heights that vary by more than ten times the grid's extent, over cells under 0.01 units,
    // with no CRS to say so: degrees shaded as if they were metres.
    let no_crs = crs.is_none();
    let looks_like_degrees = |z: [f64; 2]| {
        let extent = (f64::from(w) * ew).max(f64::from(h) * ns);
        no_crs && o.scale.is_none() && ew.max(ns) < 0.01 && z[1] - z[0] > 10.0 * extent
    };
    let warn = |z: [f64; 2]| -> Vec<String> {
        if looks_like_degrees(z) {
            vec![format!(
                "{}: cells of {} look like degrees of latitude and longitude (heights span {} \
                 over a grid {} across) but the DEM declares no CRS, so the shading takes them \
                 as the heights' unit: give --scale 111120 (metres per degree, as gdaldem -s) \
                 or the DEM's CRS",
                input.display(),
                crate::fmt::Figure(ew.max(ns)),
                crate::fmt::Figure(z[1] - z[0]),
                crate::fmt::Figure((f64::from(w) * ew).max(f64::from(h) * ns)),
            )]
        } else {
            Vec::new()
        }
    };
    let png = o.output.format.is_none()
        && output
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !png {
        let r = o.output.resolve(output, true)?;
        if r.format == RasterFormat::Ascii {
            return Err(Error::Output {
                path: output.to_path_buf(),
                message: "a hillshade is written as PNG, GeoTIFF or COG".into(),
            });
        }
        let geo = TiffGeo {
            origin,
            size: [ew, ns],
            crs,
            nodata: 0.0,
        };
        let lost_crs = LostCrs::of(geo.crs.as_ref(), false);
        let mut shaded = Shaded {
            cells: 0,
            z: [0.0; 2],
        };
        let bytes = write_u8_image(output, w, h, &geo, &r, |stage| {
            let mut values = vec![0f32; w as usize];
            let mut rows = Rows::new(reader);
            shaded = shade_rows(
                w as usize,
                || rows.next(),
                g,
                o,
                |row, line| {
                    for (v, b) in values.iter_mut().zip(line) {
                        *v = f32::from(*b);
                    }
                    stage.write(row, 0, &values)
                },
            )?;
            Ok(())
        })?;
        return Ok(HillshadeSummary {
            cols: w,
            rows: h,
            shaded: shaded.cells,
            bytes,
            metres_per_degree,
            lost_crs,
            warnings: warn(shaded.z),
        });
    }
    let mut out = AtomicFile::create(output)?;
    let mut rows = Rows::new(reader);
    let shaded = write_png(&mut out, w, h, output, |line| {
        shade_rows(w as usize, || rows.next(), g, o, line)
    })?;
    out.flush().map_err(|e| Error::write(output, e))?;
    let bytes = out.commit()?;
    write_world_file(output, origin, [ew, ns])?;
    write_prj(output, crs.as_ref())?;
    write_aux_xml(output, crs.as_ref())?;
    Ok(HillshadeSummary {
        cols: w,
        rows: h,
        shaded: shaded.cells,
        bytes,
        metres_per_degree,
        lost_crs: LostCrs::of(crs.as_ref(), true),
        warnings: warn(shaded.z),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::geotiff::GeoTiffWriter;
    use crate::output::raster::GridWriter;
    use crate::raster::GridSpec;
    use std::fs::File;
    use std::io::BufReader;

    fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
        let d = png::Decoder::new(BufReader::new(File::open(path).unwrap()));
        let mut r = d.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        let info = r.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    /// A plane sloping down to the north-west faces the light: every cell gets the same shade, the
    /// one the formula gives; nodata is transparent.
    #[test]
    fn plane_shades_uniformly_and_nodata_is_transparent() {
        let dir = tempfile::tempdir().unwrap();
        let dem = dir.path().join("d.tif");
        let spec = GridSpec::aligned(2.0, 0, 0, 5, 4, -9999.0);
        let mut w: Box<dyn GridWriter> = Box::new(GeoTiffWriter::create(&dem, &spec).unwrap());
        for row in 0..4u32 {
            let y = spec.centre_y(row);
            let v: Vec<f32> = (0..5u32)
                .map(|c| (0.5 * spec.centre_x(c) - 0.5 * y) as f32)
                .collect();
            w.write_row(row, &v).unwrap();
        }
        w.write_cell(0, 0, -9999.0).unwrap();
        w.finish().unwrap();
        let png = dir.path().join("s.png");
        let s = hillshade(&dem, &png, &HillshadeOptions::default()).unwrap();
        assert_eq!((s.cols, s.rows, s.shaded), (5, 4, 19));
        let (pw, ph, px) = read_png(&png);
        assert_eq!((pw, ph), (5, 4));
        assert_eq!(&px[..2], &[0, 0]);
        // Rising to the east and falling to the north: x = −0.5 (west minus east), y = −0.5
        // (north minus south).
        let want = {
            let (az, alt) = (315f64.to_radians(), 45f64.to_radians());
            let (x, y) = (-0.5, -0.5);
            let s = (alt.sin() - (y * az.cos() * alt.cos() - x * az.sin() * alt.cos()))
                / (1.0 + x * x + y * y).sqrt();
            (1.0 + 254.0 * s.max(0.0)).round() as u8
        };
        for p in px.chunks(2).skip(1) {
            assert_eq!(p, [want, 255]);
        }
        // The PNG's world file: cell centre of the upper-left cell.
        let pgw = std::fs::read_to_string(dir.path().join("s.pgw")).unwrap();
        assert_eq!(pgw, "2.0\n0.0\n0.0\n-2.0\n0.0\n6.0\n");
        // The same shades as an 8-bit GeoTIFF, 0 where the DEM has no data.
        let tif = dir.path().join("s.tif");
        let t = hillshade(&dem, &tif, &HillshadeOptions::default()).unwrap();
        assert_eq!(t.shaded, 19);
        let mut d = tiff::decoder::Decoder::new(BufReader::new(File::open(&tif).unwrap())).unwrap();
        let tiff::decoder::DecodingResult::U8(v) = d.read_image().unwrap() else {
            panic!("not 8-bit")
        };
        let grey: Vec<u8> = px.chunks(2).map(|p| p[0]).collect();
        assert_eq!(v, grey);
    }

    /// A grid held in memory shades as the same grid read from a file (a report's overview).
    #[test]
    fn a_grid_in_memory_shades_as_from_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let dem = dir.path().join("d.tif");
        let spec = GridSpec::aligned(2.0, 0, 0, 6, 5, -9999.0);
        let z = |c: u32, r: u32| {
            let (x, y) = (spec.centre_x(c), spec.centre_y(r));
            (0.3 * x * x - 0.2 * x * y + y).round()
        };
        let mut w: Box<dyn GridWriter> = Box::new(GeoTiffWriter::create(&dem, &spec).unwrap());
        for r in 0..5u32 {
            let v: Vec<f32> = (0..6u32).map(|c| z(c, r) as f32).collect();
            w.write_row(r, &v).unwrap();
        }
        w.write_cell(2, 3, -9999.0).unwrap();
        w.finish().unwrap();
        let png = dir.path().join("s.png");
        hillshade(&dem, &png, &HillshadeOptions::default()).unwrap();
        let mut values: Vec<f64> = (0..5u32)
            .flat_map(|r| (0..6u32).map(move |c| (c, r)))
            .map(|(c, r)| z(c, r))
            .collect();
        values[2 * 6 + 3] = f64::NAN;
        let [x0, top] = spec.origin();
        let mem = RasterSpec::north_up(6, 5, x0, top, 2.0);
        let (bytes, shaded) = hillshade_png(&values, &mem, &HillshadeOptions::default()).unwrap();
        assert_eq!(shaded, 29);
        let other = dir.path().join("m.png");
        std::fs::write(&other, bytes).unwrap();
        assert_eq!(read_png(&other), read_png(&png));
    }

    #[test]
    fn not_a_grid_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.tif");
        std::fs::write(&p, b"hello").unwrap();
        let e = hillshade(&p, &dir.path().join("o.png"), &HillshadeOptions::default());
        // Neither TIFF nor ESRI ASCII: the grid reader's error, naming the file.
        let e = e.unwrap_err();
        assert!(
            matches!(e, Error::Format { .. } | Error::Parse { .. }),
            "{e}"
        );
        assert!(e.to_string().contains("x.tif"), "{e}");
    }
}
