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
//! cartographic convention) at altitude `alt` above the horizon. Unlike `gdaldem`'s default, the
//! edge cells and the cells next to nodata are shaded too: missing neighbours are extrapolated
//! linearly from the others (exact on a plane); nodata cells are transparent.
//!
//! The DEM is read a band of rows at a time ([`RasterReader`]: any single-band GeoTIFF the `tiff`
//! crate decodes, striped or tiled, and ESRI ASCII grids); the cell size, origin, CRS and nodata
//! value come from it and go to the output's georeferencing.

use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::input::raster::RasterReader;
use crate::output::AtomicFile;
use crate::output::cog::{TiffGeo, write_u8_image};
use crate::output::raster::{RasterFormat, RasterOptions};
use crate::output::world::{write_prj, write_world_file};
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
    /// Vertical exaggeration.
    pub z_factor: f64,
    /// Output format (PNG by a `.png` extension; GeoTIFF or COG) and compression.
    pub output: RasterOptions,
}

impl HillshadeOptions {
    /// Checks the options: an azimuth in [0, 360], an altitude in [0, 90] degrees, a positive
    /// finite z factor (anything else shades every cell the same).
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
        if !(self.z_factor.is_finite() && self.z_factor > 0.0) {
            return bad("z-factor", self.z_factor, "a positive number");
        }
        Ok(())
    }
}

impl Default for HillshadeOptions {
    fn default() -> Self {
        HillshadeOptions {
            azimuth: 315.0,
            altitude: 45.0,
            z_factor: 1.0,
            output: RasterOptions::default(),
        }
    }
}

/// What [`hillshade`] produced.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct HillshadeSummary {
    /// Image width.
    pub cols: u32,
    /// Image height.
    pub rows: u32,
    /// Cells with data.
    pub shaded: u64,
    /// Bytes of the PNG.
    pub bytes: u64,
}

/// The shade of the centre of a 3 × 3 window. Missing (NaN) neighbours are extrapolated so that
/// a plane stays a plane: a side neighbour through the centre from the opposite side
/// (`2e − opposite`, or `e` if that is missing too), a corner from the opposite corner the same
/// way, or else from its two side neighbours (`side₁ + side₂ − e`).
fn shade(w: [[f64; 3]; 3], ew: f64, ns: f64, o: &HillshadeOptions) -> u8 {
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
    let k = o.z_factor;
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

/// Shades every row of `reader`'s grid, calling `row` with each (values 1–255, 0 where the DEM
/// has no data); returns the cells shaded.
fn shade_rows(
    reader: RasterReader,
    o: &HillshadeOptions,
    mut row: impl FnMut(u32, &[u8]) -> Result<()>,
) -> Result<u64> {
    let (ew, ns) = reader.spec().cell_size();
    let w = reader.spec().cols as usize;
    let mut rows = Rows {
        reader,
        next_row: 0,
        ready: VecDeque::new(),
    };
    let mut shaded = 0u64;
    let mut prev: Option<Vec<f64>> = None;
    let mut cur = rows.next()?;
    let mut line = vec![0u8; w];
    let mut r = 0u32;
    while let Some(c) = cur.take() {
        let next = rows.next()?;
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
            let (a, b) = (prev.as_ref(), next.as_ref());
            let win = [
                [cell(a, l), cell(a, m), cell(a, rr)],
                [cell(Some(&c), l), c[x], cell(Some(&c), rr)],
                [cell(b, l), cell(b, m), cell(b, rr)],
            ];
            line[x] = shade(win, ew, ns, o);
            shaded += 1;
        }
        row(r, &line)?;
        r += 1;
        prev = Some(c);
        cur = next;
    }
    Ok(shaded)
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

/// Shades the DEM at `input` (GeoTIFF, COG or ESRI ASCII grid, read a band of rows at a time)
/// into `output`: a grey + alpha PNG (nodata transparent) with a world file (`.pgw`) and, when
/// the CRS is known as WKT, a `.prj`; or, by extension or `o.output.format`, an 8-bit
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
        let mut shaded = 0;
        let bytes = write_u8_image(output, w, h, &geo, &r, |stage| {
            let mut values = vec![0f32; w as usize];
            shaded = shade_rows(reader, o, |row, line| {
                for (v, b) in values.iter_mut().zip(line) {
                    *v = f32::from(*b);
                }
                stage.write(row, 0, &values)
            })?;
            Ok(())
        })?;
        return Ok(HillshadeSummary {
            cols: w,
            rows: h,
            shaded,
            bytes,
        });
    }
    let mut out = AtomicFile::create(output)?;
    let png_err = |e: png::EncodingError| Error::Output {
        path: output.to_path_buf(),
        message: format!("PNG: {e}"),
    };
    let shaded;
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::GrayscaleAlpha);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(png_err)?;
        let mut stream = writer.stream_writer().map_err(png_err)?;
        let mut ga = vec![0u8; w as usize * 2];
        shaded = shade_rows(reader, o, |_, line| {
            for (x, v) in line.iter().enumerate() {
                ga[2 * x] = *v;
                ga[2 * x + 1] = if *v == 0 { 0 } else { 255 };
            }
            stream.write_all(&ga).map_err(|e| Error::write(output, e))
        })?;
        stream.finish().map_err(png_err)?;
    }
    out.flush().map_err(|e| Error::write(output, e))?;
    let bytes = out.commit()?;
    write_world_file(output, origin, [ew, ns])?;
    write_prj(output, crs.as_ref())?;
    Ok(HillshadeSummary {
        cols: w,
        rows: h,
        shaded,
        bytes,
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
