//! Hillshade of a DEM GeoTIFF, as a PNG, so that a result can be seen at a glance.
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
//! The DEM is read strip by strip (three rows in memory at a time) with the `tiff` crate, which
//! decodes any uncompressed, LZW or Deflate single-band GeoTIFF of integer or float samples; tiled
//! files are read whole. The cell size comes from `ModelPixelScaleTag` and the nodata value from
//! `GDAL_NODATA`.

use crate::error::{Error, Result};
use crate::output::AtomicFile;
use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufReader, Write};
use std::path::Path;
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

/// Light and exaggeration.
#[derive(Clone, Copy, Debug)]
pub struct HillshadeOptions {
    /// Direction the light comes from, degrees clockwise from north.
    pub azimuth: f64,
    /// Height of the light above the horizon, degrees.
    pub altitude: f64,
    /// Vertical exaggeration.
    pub z_factor: f64,
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
        }
    }
}

/// What [`hillshade`] produced.
#[derive(Clone, Copy, Debug, serde::Serialize)]
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

/// Rows of a single-band TIFF, north to south, as `f64` with nodata as NaN.
struct Rows {
    decoder: Decoder<BufReader<File>>,
    path: std::path::PathBuf,
    width: usize,
    height: usize,
    nodata: Option<f64>,
    /// The whole image, for tiled files.
    whole: Option<Vec<f64>>,
    next_chunk: u32,
    next_row: usize,
    ready: VecDeque<Vec<f64>>,
}

fn to_f64(r: DecodingResult) -> Option<Vec<f64>> {
    Some(match r {
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
        _ => return None,
    })
}

impl Rows {
    fn open(path: &Path) -> Result<(Rows, [f64; 2])> {
        let bad = |m: String| Error::Format {
            path: path.to_path_buf(),
            message: m,
        };
        let f = File::open(path).map_err(|e| Error::io(path, e))?;
        let mut d = Decoder::new(BufReader::new(f))
            .map_err(|e| bad(format!("not a TIFF file: {e}")))?
            .with_limits(Limits::unlimited());
        let (w, h) = d.dimensions().map_err(|e| bad(e.to_string()))?;
        match d.colortype().map_err(|e| bad(e.to_string()))? {
            tiff::ColorType::Gray(_) => {}
            other => {
                return Err(bad(format!(
                    "a DEM must have one band, this image is {other:?}"
                )));
            }
        }
        let scale = d
            .find_tag(Tag::ModelPixelScaleTag)
            .ok()
            .flatten()
            .and_then(|v| v.into_f64_vec().ok())
            .filter(|v| v.len() >= 2 && v[0] > 0.0 && v[1] > 0.0)
            .map_or([1.0, 1.0], |v| [v[0], v[1]]);
        let nodata = d
            .find_tag(Tag::GdalNodata)
            .ok()
            .flatten()
            .and_then(|v| v.into_string().ok())
            .and_then(|s| {
                s.trim_matches(|c: char| c == '\0' || c.is_whitespace())
                    .parse()
                    .ok()
            });
        let whole = if d.get_chunk_type() == ChunkType::Tile {
            let img = d.read_image().map_err(|e| bad(e.to_string()))?;
            Some(to_f64(img).ok_or_else(|| bad("unsupported sample type".into()))?)
        } else {
            None
        };
        Ok((
            Rows {
                decoder: d,
                path: path.to_path_buf(),
                width: w as usize,
                height: h as usize,
                nodata,
                whole,
                next_chunk: 0,
                next_row: 0,
                ready: VecDeque::new(),
            },
            scale,
        ))
    }

    fn clean(&self, mut row: Vec<f64>) -> Vec<f64> {
        for v in &mut row {
            if Some(*v) == self.nodata || self.nodata.is_some_and(f64::is_nan) && v.is_nan() {
                *v = f64::NAN;
            }
        }
        row
    }

    /// The next row, or `None` after the last.
    fn next(&mut self) -> Result<Option<Vec<f64>>> {
        if self.next_row >= self.height {
            return Ok(None);
        }
        if let Some(all) = &self.whole {
            let r = all[self.next_row * self.width..(self.next_row + 1) * self.width].to_vec();
            self.next_row += 1;
            return Ok(Some(self.clean(r)));
        }
        if self.ready.is_empty() {
            let chunk = self
                .decoder
                .read_chunk(self.next_chunk)
                .map_err(|e| Error::Format {
                    path: self.path.clone(),
                    message: format!(
                        "strip {}: {}",
                        self.next_chunk,
                        crate::input::raster::tiff_message(&e)
                    ),
                })?;
            self.next_chunk += 1;
            let values = to_f64(chunk).ok_or_else(|| Error::Format {
                path: self.path.clone(),
                message: "unsupported sample type".into(),
            })?;
            for r in values.chunks_exact(self.width) {
                self.ready.push_back(r.to_vec());
            }
        }
        self.next_row += 1;
        let r = self.ready.pop_front().ok_or_else(|| Error::Format {
            path: self.path.clone(),
            message: "a strip holds fewer rows than the image".into(),
        })?;
        Ok(Some(self.clean(r)))
    }
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

/// Shades the DEM at `input` into a grey + alpha PNG at `output`.
///
/// # Errors
/// [`Error::Io`] / [`Error::Format`] naming the file; [`Error::Options`] for options out of range
/// ([`HillshadeOptions::check`]).
pub fn hillshade(input: &Path, output: &Path, o: &HillshadeOptions) -> Result<HillshadeSummary> {
    o.check()?;
    let (mut rows, [ew, ns]) = Rows::open(input)?;
    let (w, h) = (rows.width, rows.height);
    let mut out = AtomicFile::create(output)?;
    let png_err = |e: png::EncodingError| Error::Output {
        path: output.to_path_buf(),
        message: format!("PNG: {e}"),
    };
    let mut shaded = 0u64;
    {
        let mut enc = png::Encoder::new(&mut out, w as u32, h as u32);
        enc.set_color(png::ColorType::GrayscaleAlpha);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(png_err)?;
        let mut stream = writer.stream_writer().map_err(png_err)?;
        let mut prev: Option<Vec<f64>> = None;
        let mut cur = rows.next()?;
        let mut line = vec![0u8; w * 2];
        while let Some(c) = cur.take() {
            let next = rows.next()?;
            let cell = |row: Option<&Vec<f64>>, x: Option<usize>| match (row, x) {
                (Some(r), Some(x)) if x < w => r[x],
                _ => f64::NAN,
            };
            for x in 0..w {
                if c[x].is_nan() {
                    line[2 * x] = 0;
                    line[2 * x + 1] = 0;
                    continue;
                }
                let (l, m, r) = (x.checked_sub(1), Some(x), Some(x + 1));
                let (a, b) = (prev.as_ref(), next.as_ref());
                let win = [
                    [cell(a, l), cell(a, m), cell(a, r)],
                    [cell(Some(&c), l), c[x], cell(Some(&c), r)],
                    [cell(b, l), cell(b, m), cell(b, r)],
                ];
                line[2 * x] = shade(win, ew, ns, o);
                line[2 * x + 1] = 255;
                shaded += 1;
            }
            stream
                .write_all(&line)
                .map_err(|e| Error::write(output, e))?;
            prev = Some(c);
            cur = next;
        }
        stream.finish().map_err(png_err)?;
    }
    out.flush().map_err(|e| Error::write(output, e))?;
    let bytes = out.commit()?;
    Ok(HillshadeSummary {
        cols: w as u32,
        rows: h as u32,
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
    }

    #[test]
    fn not_a_tiff_is_a_format_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.tif");
        std::fs::write(&p, b"hello").unwrap();
        let e = hillshade(&p, &dir.path().join("o.png"), &HillshadeOptions::default());
        assert!(matches!(e, Err(Error::Format { .. })));
    }
}
