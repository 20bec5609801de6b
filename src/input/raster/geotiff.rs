//! The GeoTIFF side of [`RasterReader`]: header, georeferencing and CRS from the GeoKeys, nodata
//! from `GDAL_NODATA`, and windows decoded chunk by chunk (see the [parent module](super)).

use super::{RasterReader, RasterSpec, SampleType, Source, format};
use crate::error::{Error, Result};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

/// An open TIFF: its decoder and chunk layout.
pub(super) struct TiffSource {
    pub(super) decoder: Decoder<BufReader<File>>,
    pub(super) chunk_w: u32,
    pub(super) chunk_h: u32,
    pub(super) across: u32,
}

fn tiff_error(path: &Path, e: tiff::TiffError) -> Error {
    match e {
        tiff::TiffError::IoError(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::io(path, io)
        }
        other => format(path, tiff_message(&other)),
    }
}

/// What a TIFF decoder error means to a user: a read past the end of the file is a truncated or
/// damaged file, not "failed to fill whole buffer".
fn tiff_message(e: &tiff::TiffError) -> String {
    match e {
        tiff::TiffError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the TIFF is truncated or damaged: its data runs past the end of the file".into()
        }
        other => format!("cannot read the TIFF: {other}"),
    }
}

pub(super) fn open_tiff(path: &Path, file: File) -> Result<RasterReader> {
    let mut limits = Limits::default();
    limits.ifd_value_size = 64 << 20;
    let mut dec = Decoder::new(BufReader::new(file))
        .map_err(|e| tiff_error(path, e))?
        .with_limits(limits);
    let (cols, rows) = dec.dimensions().map_err(|e| tiff_error(path, e))?;
    let spp: u16 = dec
        .find_tag_unsigned(Tag::SamplesPerPixel)
        .map_err(|e| tiff_error(path, e))?
        .unwrap_or(1);
    if spp != 1 {
        return Err(format(
            path,
            format!("{spp} samples per pixel: only single-band grids are supported"),
        ));
    }
    let bits: u16 = dec
        .find_tag_unsigned(Tag::BitsPerSample)
        .map_err(|e| tiff_error(path, e))?
        .unwrap_or(1);
    let fmt: u16 = dec
        .find_tag_unsigned(Tag::SampleFormat)
        .map_err(|e| tiff_error(path, e))?
        .unwrap_or(1);
    let sample = match (fmt, bits) {
        (1, 8) => SampleType::U8,
        (1, 16) => SampleType::U16,
        (1, 32) => SampleType::U32,
        (1, 64) => SampleType::U64,
        (2, 8) => SampleType::I8,
        (2, 16) => SampleType::I16,
        (2, 32) => SampleType::I32,
        (2, 64) => SampleType::I64,
        (3, 32) => SampleType::F32,
        (3, 64) => SampleType::F64,
        _ => {
            return Err(format(
                path,
                format!("unsupported sample format {fmt} with {bits} bits per sample"),
            ));
        }
    };
    let transform = tiff_transform(path, &mut dec, cols, rows)?;
    let nodata =
        match dec
            .find_tag(Tag::GdalNodata)
            .map_err(|e| tiff_error(path, e))?
        {
            None => None,
            Some(v) => {
                let s = v.into_string().map_err(|e| tiff_error(path, e))?;
                let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
                match s.to_ascii_lowercase().as_str() {
                    "nan" | "-nan" => None, // NaN cells are always missing
                    _ => Some(s.parse::<f64>().map_err(|_| {
                        format(path, format!("GDAL_NODATA tag {s:?} is not a number"))
                    })?),
                }
            }
        };
    let crs = tiff_crs(path, &mut dec)?;
    let (chunk_w, chunk_h) = dec.chunk_dimensions();
    if chunk_w == 0 || chunk_h == 0 {
        return Err(format(path, "TIFF chunks of size zero"));
    }
    let across = match dec.get_chunk_type() {
        ChunkType::Strip => 1,
        ChunkType::Tile => cols.div_ceil(chunk_w),
    };
    Ok(RasterReader {
        path: path.to_path_buf(),
        spec: RasterSpec {
            cols,
            rows,
            transform,
            nodata,
            crs,
        },
        sample,
        source: Source::Tiff(Box::new(TiffSource {
            decoder: dec,
            chunk_w: if across == 1 { cols } else { chunk_w },
            chunk_h,
            across,
        })),
    })
}

fn f64_tag(path: &Path, dec: &mut Decoder<BufReader<File>>, tag: Tag) -> Result<Option<Vec<f64>>> {
    match dec.find_tag(tag).map_err(|e| tiff_error(path, e))? {
        None => Ok(None),
        Some(v) => Ok(Some(v.into_f64_vec().map_err(|e| tiff_error(path, e))?)),
    }
}

fn geo_keys(path: &Path, dec: &mut Decoder<BufReader<File>>) -> Result<Vec<[u16; 4]>> {
    let Some(v) = dec
        .find_tag(Tag::GeoKeyDirectoryTag)
        .map_err(|e| tiff_error(path, e))?
    else {
        return Ok(Vec::new());
    };
    let dir = v.into_u16_vec().map_err(|e| tiff_error(path, e))?;
    if dir.len() < 4 {
        return Err(format(path, "GeoKeyDirectory is too short"));
    }
    let n = dir[3] as usize;
    if dir.len() < 4 + 4 * n {
        return Err(format(
            path,
            "GeoKeyDirectory is shorter than its key count",
        ));
    }
    Ok((0..n)
        .map(|i| {
            let k = &dir[4 + 4 * i..8 + 4 * i];
            [k[0], k[1], k[2], k[3]]
        })
        .collect())
}

/// The value of a SHORT geokey stored in the directory itself.
fn short_key(keys: &[[u16; 4]], id: u16) -> Option<u16> {
    keys.iter().find(|k| k[0] == id && k[1] == 0).map(|k| k[3])
}

const GT_RASTER_TYPE: u16 = 1025;
const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;
const USER_DEFINED: u16 = 32767;

fn tiff_transform(
    path: &Path,
    dec: &mut Decoder<BufReader<File>>,
    cols: u32,
    rows: u32,
) -> Result<[f64; 6]> {
    let keys = geo_keys(path, dec)?;
    let pixel_is_point = short_key(&keys, GT_RASTER_TYPE) == Some(2);
    let mut t = if let Some(m) = f64_tag(path, dec, Tag::ModelTransformationTag)? {
        if m.len() < 16 {
            return Err(format(path, "ModelTransformation needs 16 values"));
        }
        [m[3], m[0], m[1], m[7], m[4], m[5]]
    } else {
        let scale = f64_tag(path, dec, Tag::ModelPixelScaleTag)?;
        let tie = f64_tag(path, dec, Tag::ModelTiepointTag)?;
        match (scale, tie) {
            (Some(s), Some(tp)) if s.len() >= 2 && tp.len() >= 6 => {
                // x = X + (col - I)·sx, y = Y - (row - J)·sy.
                [
                    tp[3] - tp[0] * s[0],
                    s[0],
                    0.0,
                    tp[4] + tp[1] * s[1],
                    0.0,
                    -s[1],
                ]
            }
            _ => {
                // No georeferencing: cell indices, north-up, the first row at the top.
                [0.0, 1.0, 0.0, f64::from(rows), 0.0, -1.0]
            }
        }
    };
    if pixel_is_point {
        // The tie point names a cell centre: move the transform to the corner.
        t[0] -= 0.5 * (t[1] + t[2]);
        t[3] -= 0.5 * (t[4] + t[5]);
    }
    if !t.iter().all(|v| v.is_finite()) || t[1] * t[5] - t[2] * t[4] == 0.0 {
        return Err(format(path, format!("degenerate georeferencing {t:?}")));
    }
    let _ = cols;
    Ok(t)
}

fn tiff_crs(path: &Path, dec: &mut Decoder<BufReader<File>>) -> Result<Option<String>> {
    let keys = geo_keys(path, dec)?;
    for id in [PROJECTED_CS_TYPE, GEOGRAPHIC_TYPE] {
        if let Some(code) = short_key(&keys, id)
            && code != USER_DEFINED
            && code != 0
        {
            return Ok(Some(format!("EPSG:{code}")));
        }
    }
    Ok(None)
}

pub(super) fn read_tiff_window(
    path: &Path,
    t: &mut TiffSource,
    w: [u32; 4],
    out: &mut [f64],
) -> Result<()> {
    let [col0, row0, cols, rows] = w;
    let (cw, ch) = (t.chunk_w, t.chunk_h);
    let (cx0, cx1) = (col0 / cw, (col0 + cols - 1) / cw);
    let (cy0, cy1) = (row0 / ch, (row0 + rows - 1) / ch);
    for cy in cy0..=cy1 {
        for cx in cx0..=cx1 {
            let index = cy * t.across + cx;
            let data = t
                .decoder
                .read_chunk(index)
                .map_err(|e| tiff_error(path, e))?;
            let (dw, dh) = t.decoder.chunk_data_dimensions(index);
            let values = chunk_to_f64(data);
            // The decoded chunk is `dw` wide, or the full chunk width when padded.
            let stride = if values.len() >= (cw * dh) as usize && dw < cw && t.across > 1 {
                cw as usize
            } else {
                dw as usize
            };
            if values.len() < stride * (dh as usize - 1) + dw as usize {
                return Err(format(path, format!("TIFF chunk {index} is truncated")));
            }
            let (gx0, gy0) = (cx * cw, cy * ch);
            let ys = row0.max(gy0)..(row0 + rows).min(gy0 + dh);
            let xs = col0.max(gx0)..(col0 + cols).min(gx0 + dw);
            for y in ys {
                let src = (y - gy0) as usize * stride + (xs.start - gx0) as usize;
                let dst = (y - row0) as usize * cols as usize + (xs.start - col0) as usize;
                let n = xs.len();
                out[dst..dst + n].copy_from_slice(&values[src..src + n]);
            }
        }
    }
    Ok(())
}

fn chunk_to_f64(data: DecodingResult) -> Vec<f64> {
    fn conv<T: Copy>(v: Vec<T>, f: impl Fn(T) -> f64) -> Vec<f64> {
        v.into_iter().map(f).collect()
    }
    match data {
        DecodingResult::U8(v) => conv(v, f64::from),
        DecodingResult::U16(v) => conv(v, f64::from),
        DecodingResult::U32(v) => conv(v, f64::from),
        DecodingResult::U64(v) => conv(v, |x| x as f64),
        DecodingResult::I8(v) => conv(v, f64::from),
        DecodingResult::I16(v) => conv(v, f64::from),
        DecodingResult::I32(v) => conv(v, f64::from),
        DecodingResult::I64(v) => conv(v, |x| x as f64),
        DecodingResult::F16(v) => conv(v, f64::from),
        DecodingResult::F32(v) => conv(v, f64::from),
        DecodingResult::F64(v) => v,
    }
}
