//! One integer coordinate system for several LAS/LAZ files.
//!
//! Each file stores `real = offset + scale × N` with its own `scale` and `offset` per axis. To
//! treat adjacent tiles as one point set, the reader converts every file's integers into one
//! common system, exactly:
//!
//! - **common scale** (per axis) = the finest scale among the files; every other file's scale
//!   must be a whole multiple `k` of it (relative tolerance [`SCALE_TOLERANCE`], to absorb the
//!   binary rounding of values such as 0.01 vs 0.001);
//! - **common offset** (per axis) = the first file's offset; every other file's offset must differ
//!   from it by a whole number `d` of common steps (up to [`OFFSET_TOLERANCE`] of a step);
//! - a file's integer `N` becomes `k × N + d`, computed in `i64` and required to fit in `i32`.
//!
//! With a single file, or files sharing scale and offset, the integers are the stored ones.
//! If the files cannot be combined exactly, opening fails with an [`Error::Format`] naming both
//! files and their scales and offsets.

use super::LidarPoint;
use super::header::{Bounds3, format_error};
use crate::error::{Error, Result};
use serde::Serialize;
use std::path::Path;

/// Largest relative difference between a file's scale and `k ×` the common scale.
pub const SCALE_TOLERANCE: f64 = 1e-9;
/// Largest difference, in common steps, between an offset difference and a whole number.
pub const OFFSET_TOLERANCE: f64 = 1e-4;

/// Maps the reader's integer coordinates to real-world coordinates:
/// `real[a] = offset[a] + scale[a] × N[a]`, the LAS convention.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Quantization {
    /// Scale factors for x, y, z.
    pub scale: [f64; 3],
    /// Offsets for x, y, z.
    pub offset: [f64; 3],
}

impl Quantization {
    /// Real-world coordinate of integer `n` on `axis` (0 = x, 1 = y, 2 = z).
    #[inline]
    pub fn axis_to_world(&self, axis: usize, n: i64) -> f64 {
        self.offset[axis] + self.scale[axis] * n as f64
    }

    /// Real-world `[x, y, z]` of a point.
    #[inline]
    pub fn to_world(&self, p: &LidarPoint) -> [f64; 3] {
        [
            self.axis_to_world(0, i64::from(p.x)),
            self.axis_to_world(1, i64::from(p.y)),
            self.axis_to_world(2, i64::from(p.z)),
        ]
    }

    /// The smallest integer `n` with `axis_to_world(axis, n) >= v` (saturating at the `i64`
    /// range). Consistent with [`Quantization::axis_to_world`], so integer comparisons give the
    /// same answers as comparing real-world values.
    pub fn ceil_index(&self, axis: usize, v: f64) -> i64 {
        let guess = ((v - self.offset[axis]) / self.scale[axis]).ceil();
        const LIMIT: f64 = (1u64 << 62) as f64;
        if guess.is_nan() || guess.abs() >= LIMIT {
            return if guess > 0.0 { i64::MAX } else { i64::MIN };
        }
        let mut n = guess as i64;
        while self.axis_to_world(axis, n - 1) >= v {
            n -= 1;
        }
        while self.axis_to_world(axis, n) < v {
            n += 1;
        }
        n
    }

    /// The largest integer `n` with `axis_to_world(axis, n) <= v` (saturating).
    pub fn floor_index(&self, axis: usize, v: f64) -> i64 {
        let n = self.ceil_index(axis, v);
        if n == i64::MAX || n == i64::MIN {
            return n;
        }
        if self.axis_to_world(axis, n) == v {
            n
        } else {
            n - 1
        }
    }
}

/// How one file's integers become common integers on one axis: `k × N + d`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct AxisMap {
    pub(crate) k: i64,
    pub(crate) d: i64,
}

/// How one file's integers become common integers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FileMap {
    pub(crate) axes: [AxisMap; 3],
}

impl FileMap {
    /// Whether the file's integers are already the common ones.
    pub(crate) fn is_identity(&self) -> bool {
        self.axes.iter().all(|a| a.k == 1 && a.d == 0)
    }

    /// Converts `n` on `axis`; `None` if the result does not fit in `i32`.
    #[inline]
    pub(crate) fn apply(&self, axis: usize, n: i32) -> Option<i32> {
        let m = self.axes[axis];
        i32::try_from(m.k * i64::from(n) + m.d).ok()
    }
}

/// One file's quantization, as input to [`combine`].
pub(crate) struct FileQuant<'a> {
    pub(crate) path: &'a Path,
    pub(crate) scale: [f64; 3],
    pub(crate) offset: [f64; 3],
    /// Header bounds, when the file has points (used to refuse early what cannot fit `i32`).
    pub(crate) bounds: Option<Bounds3>,
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Finds the common quantization and each file's map into it (see the module docs).
pub(crate) fn combine(files: &[FileQuant<'_>]) -> Result<(Quantization, Vec<FileMap>)> {
    let first = files.first().ok_or(Error::NoInput)?;
    let mut q = Quantization {
        scale: first.scale,
        offset: first.offset,
    };
    let mut finest = [0usize; 3];
    for (i, f) in files.iter().enumerate() {
        for (a, fin) in finest.iter_mut().enumerate() {
            if f.scale[a] < q.scale[a] {
                q.scale[a] = f.scale[a];
                *fin = i;
            }
        }
    }
    let mut maps = Vec::with_capacity(files.len());
    for f in files {
        let mut axes = [AxisMap { k: 1, d: 0 }; 3];
        for a in 0..3 {
            let k = scale_multiple(f.scale[a], q.scale[a]).ok_or_else(|| {
                incompatible(
                    f,
                    &files[finest[a]],
                    &format!(
                        "its {} scale {} is not a whole multiple of the finest {} scale {}",
                        AXES[a], f.scale[a], AXES[a], q.scale[a]
                    ),
                )
            })?;
            let d = offset_steps(f.offset[a], q.offset[a], q.scale[a]).ok_or_else(|| {
                incompatible(
                    f,
                    first,
                    &format!(
                        "its {} offset {} differs from the first file's {} by {} steps of {}, \
                         not a whole number",
                        AXES[a],
                        f.offset[a],
                        q.offset[a],
                        (f.offset[a] - q.offset[a]) / q.scale[a],
                        q.scale[a]
                    ),
                )
            })?;
            axes[a] = AxisMap { k, d };
            check_range(f, a, axes[a], &q)?;
        }
        maps.push(FileMap { axes });
    }
    Ok((q, maps))
}

/// Refuses a file whose header extent cannot be expressed in `i32` on the common lattice (the
/// reader also checks every point, since headers can lie).
fn check_range(f: &FileQuant<'_>, a: usize, m: AxisMap, q: &Quantization) -> Result<()> {
    let Some(b) = f.bounds else { return Ok(()) };
    let to_common = |v: f64| ((v - f.offset[a]) / f.scale[a]).round() * m.k as f64 + m.d as f64;
    let (lo, hi) = (to_common(b.min[a]), to_common(b.max[a]));
    let fits = |v: f64| !v.is_finite() || (f64::from(i32::MIN)..=f64::from(i32::MAX)).contains(&v);
    if fits(lo) && fits(hi) {
        return Ok(());
    }
    Err(format_error(
        f.path,
        format!(
            "its {} range {} .. {} does not fit in 32-bit integers on the common lattice of the \
             files read together (scale {}, offset {}): read it separately",
            AXES[a], b.min[a], b.max[a], q.scale[a], q.offset[a]
        ),
    ))
}

fn scale_multiple(scale: f64, common: f64) -> Option<i64> {
    let r = scale / common;
    let k = r.round();
    ((1.0..=1e9).contains(&k) && (r - k).abs() <= SCALE_TOLERANCE * k).then_some(k as i64)
}

fn offset_steps(offset: f64, common_offset: f64, common_scale: f64) -> Option<i64> {
    let q = (offset - common_offset) / common_scale;
    let d = q.round();
    (d.abs() < 2f64.powi(53) && (q - d).abs() <= OFFSET_TOLERANCE).then_some(d as i64)
}

fn incompatible(f: &FileQuant<'_>, other: &FileQuant<'_>, why: &str) -> Error {
    let describe = |g: &FileQuant<'_>| {
        format!(
            "{} (scale {:?}, offset {:?})",
            g.path.display(),
            g.scale,
            g.offset
        )
    };
    format_error(
        f.path,
        format!(
            "cannot be combined exactly with {}: {why}; this file has {}. Files read together \
             must share one integer lattice: every scale a whole multiple of the finest, every \
             offset difference a whole number of finest steps",
            describe(other),
            describe(f)
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fq(path: &str, scale: [f64; 3], offset: [f64; 3]) -> FileQuant<'_> {
        FileQuant {
            path: Path::new(path),
            scale,
            offset,
            bounds: None,
        }
    }

    #[test]
    fn identical_files_are_identity() {
        let a = fq("a.laz", [0.01; 3], [0.0; 3]);
        let b = fq("b.laz", [0.01; 3], [0.0; 3]);
        let (q, maps) = combine(&[a, b]).unwrap();
        assert_eq!(q.scale, [0.01; 3]);
        assert!(maps.iter().all(FileMap::is_identity));
    }

    #[test]
    fn finer_scale_and_shifted_offset() {
        let a = fq("a.laz", [0.01, 0.01, 0.01], [1000.0, 2000.0, 0.0]);
        let b = fq("b.laz", [0.001, 0.01, 0.01], [1000.5, 1999.99, 0.0]);
        let (q, maps) = combine(&[a, b]).unwrap();
        assert_eq!(q.scale, [0.001, 0.01, 0.01]);
        assert_eq!(q.offset, [1000.0, 2000.0, 0.0]);
        assert_eq!(maps[0].axes[0], AxisMap { k: 10, d: 0 });
        assert_eq!(maps[1].axes[0], AxisMap { k: 1, d: 500 });
        assert_eq!(maps[1].axes[1], AxisMap { k: 1, d: -1 });
        // b's x = 1000.5 + 0.001 * 7 = 1000.507 -> common 507
        assert_eq!(maps[1].apply(0, 7), Some(507));
        assert_eq!(q.axis_to_world(0, 507), 1000.0 + 0.001 * 507.0);
    }

    #[test]
    fn incompatible_scale_names_both_files() {
        let a = fq("a.laz", [0.002; 3], [0.0; 3]);
        let b = fq("b.laz", [0.003; 3], [0.0; 3]);
        let e = combine(&[a, b]).unwrap_err().to_string();
        assert!(e.contains("b.laz") && e.contains("a.laz"), "{e}");
        assert!(e.contains("whole multiple"), "{e}");
    }

    #[test]
    fn incompatible_offset_names_both_files() {
        let a = fq("a.laz", [0.01; 3], [0.0; 3]);
        let b = fq("b.laz", [0.01; 3], [511500.025, 0.0, 0.0]);
        let e = combine(&[a, b]).unwrap_err().to_string();
        assert!(e.contains("b.laz") && e.contains("a.laz"), "{e}");
        assert!(e.contains("511500.025"), "{e}");
    }

    #[test]
    fn extent_beyond_i32_is_refused_at_open() {
        let a = fq("a.laz", [0.001; 3], [0.0; 3]);
        let mut b = fq("b.laz", [0.01; 3], [0.0; 3]);
        b.bounds = Some(Bounds3 {
            min: [300000.0, 6801000.0, 100.0],
            max: [301000.0, 6802000.0, 200.0],
        });
        let e = combine(&[a, b]).unwrap_err().to_string();
        assert!(
            e.contains("b.laz") && e.contains("y range") && e.contains("32-bit"),
            "{e}"
        );
    }

    #[test]
    fn overflow_is_detected() {
        let m = FileMap {
            axes: [AxisMap { k: 10, d: 0 }; 3],
        };
        assert_eq!(m.apply(0, i32::MAX / 5), None);
        assert_eq!(m.apply(0, -3), Some(-30));
    }

    #[test]
    fn ceil_floor_match_world_comparisons() {
        let q = Quantization {
            scale: [0.01, 0.00025, 0.001],
            offset: [511500.025, 5270000.0, 0.0],
        };
        for (axis, v) in [
            (0, 511000.0),
            (0, 511500.025),
            (1, 5274357.14475),
            (2, -0.5),
        ] {
            let lo = q.ceil_index(axis, v);
            assert!(q.axis_to_world(axis, lo) >= v && q.axis_to_world(axis, lo - 1) < v);
            let hi = q.floor_index(axis, v);
            assert!(q.axis_to_world(axis, hi) <= v && q.axis_to_world(axis, hi + 1) > v);
        }
        assert_eq!(q.ceil_index(0, 1e300), i64::MAX);
        assert_eq!(q.floor_index(0, -1e300), i64::MIN);
    }
}
