//! Which points to keep: classification, returns, withheld flag, bounding box.
//!
//! A point is dropped by the **first** filter that rejects it, in this order: withheld flag,
//! classification, returns, bounding box; [`FilterStats`] counts the drops per filter. The box
//! compares the points' real-world doubles (see [`super::world`]) with the box's, edges included.

use super::LidarPoint;
use crate::error::{Error, Result};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

/// Which returns of each pulse to keep.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Returns {
    /// Every return.
    #[default]
    All,
    /// Only first returns: `return_number == 1`.
    First,
    /// Only last returns: `return_number == number_of_returns` (single returns included).
    Last,
}

/// An axis-aligned box in real-world `x, y` coordinates, bounds included.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BBox {
    xmin: f64,
    ymin: f64,
    xmax: f64,
    ymax: f64,
}

impl BBox {
    /// A box from its corners; `None` unless all four are finite, `xmin <= xmax` and
    /// `ymin <= ymax`.
    pub fn new(xmin: f64, ymin: f64, xmax: f64, ymax: f64) -> Option<BBox> {
        let ok =
            [xmin, ymin, xmax, ymax].iter().all(|v| v.is_finite()) && xmin <= xmax && ymin <= ymax;
        ok.then_some(BBox {
            xmin,
            ymin,
            xmax,
            ymax,
        })
    }

    /// `[xmin, ymin, xmax, ymax]`.
    pub fn corners(&self) -> [f64; 4] {
        [self.xmin, self.ymin, self.xmax, self.ymax]
    }

    /// The part of both boxes, `None` when they do not meet.
    pub fn intersection(&self, other: &BBox) -> Option<BBox> {
        BBox::new(
            self.xmin.max(other.xmin),
            self.ymin.max(other.ymin),
            self.xmax.min(other.xmax),
            self.ymax.min(other.ymax),
        )
    }

    /// Does the box meet the rectangle `[xmin, ymin, xmax, ymax]` grown by `margin` (edges
    /// included)?
    pub fn meets(&self, r: [f64; 4], margin: f64) -> bool {
        r[0] - margin <= self.xmax
            && r[2] + margin >= self.xmin
            && r[1] - margin <= self.ymax
            && r[3] + margin >= self.ymin
    }
}

impl FromStr for BBox {
    type Err = Error;

    /// Parses `xmin,ymin,xmax,ymax`.
    fn from_str(s: &str) -> Result<BBox> {
        let v: Vec<f64> = s
            .split(',')
            .map(|t| t.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| {
                Error::Options(format!(
                    "bounding box \"{s}\": {e} (expected xmin,ymin,xmax,ymax)"
                ))
            })?;
        if v.len() != 4 {
            return Err(Error::Options(format!(
                "bounding box \"{s}\": expected 4 numbers xmin,ymin,xmax,ymax, got {}",
                v.len()
            )));
        }
        BBox::new(v[0], v[1], v[2], v[3]).ok_or_else(|| {
            Error::Options(format!(
                "bounding box \"{s}\": values must be finite with xmin <= xmax and ymin <= ymax"
            ))
        })
    }
}

impl fmt::Display for BBox {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{},{},{}", self.xmin, self.ymin, self.xmax, self.ymax)
    }
}

/// Parses a classification list such as `2,9` (each 0–255).
///
/// # Errors
/// [`Error::Options`] naming the bad item.
pub fn parse_classes(s: &str) -> Result<Vec<u8>> {
    s.split(',')
        .map(|t| {
            t.trim().parse::<u8>().map_err(|_| {
                Error::Options(format!(
                    "classification \"{}\": expected a number from 0 to 255",
                    t.trim()
                ))
            })
        })
        .collect()
}

/// Classes that replace the files' own, by global input index (files in the order given, then
/// points in file order): the ground filter's classes of `--ground` (`crate::ground::ClassStore`).
pub trait PointClasses: Send + Sync {
    /// Fills `out` with the classes of the points `first`, `first + 1`, …
    ///
    /// # Errors
    /// When the classes cannot be read (a temporary file), or there are none that far.
    fn read_classes(&self, first: u64, out: &mut [u8]) -> Result<()>;
}

/// The classes a [`Filter`] reads the points with instead of their own ([`PointClasses`]);
/// equal when they are the same object.
#[derive(Clone)]
pub struct ClassesFrom(pub Arc<dyn PointClasses>);

impl fmt::Debug for ClassesFrom {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ClassesFrom(..)")
    }
}

impl PartialEq for ClassesFrom {
    fn eq(&self, other: &ClassesFrom) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Which points a [`super::LidarReader`] keeps. The default keeps everything except withheld
/// points.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Filter {
    /// Keep only these classification codes (`None`: all). For point formats 0–5 the code is the
    /// 5-bit classification; for formats 6–10 the full byte.
    pub classes: Option<Vec<u8>>,
    /// Which returns to keep.
    pub returns: Returns,
    /// Drop points whose "withheld" flag is set.
    pub drop_withheld: bool,
    /// Keep only points inside this box (real-world `x`, `y`, bounds included).
    pub bbox: Option<BBox>,
    /// Take z from this extra-bytes attribute (by name, as the file's extra bytes VLR names
    /// it: `HeightAboveGround` of `sweeptin height`) instead of the record's z; points whose
    /// value is missing or not finite (NaN) are dropped (`FilterStats::no_value`).
    pub z_from: Option<String>,
    /// Read every point with the class given here for its global input index instead of the
    /// class in its record, before `classes` selects (`--ground`: the ground filter's classes,
    /// as `sweeptin ground` would write them). The reader's global indices must be the ones
    /// the classes were made for: the same files, in the same order.
    #[serde(skip)]
    pub classes_from: Option<ClassesFrom>,
}

impl Default for Filter {
    fn default() -> Self {
        Filter {
            classes: None,
            returns: Returns::All,
            drop_withheld: true,
            bbox: None,
            z_from: None,
            classes_from: None,
        }
    }
}

impl Filter {
    /// A filter that keeps every point, withheld ones included.
    pub fn keep_all() -> Filter {
        Filter {
            drop_withheld: false,
            ..Filter::default()
        }
    }
}

/// How many points each filter dropped. Each dropped point is counted once, under the first
/// filter that rejected it (order: withheld, class, returns, bbox).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct FilterStats {
    /// Points read from the files.
    pub read: u64,
    /// Points that passed every filter.
    pub kept: u64,
    /// Dropped because withheld.
    pub withheld: u64,
    /// Dropped by the classification list.
    pub class: u64,
    /// Dropped by the returns filter.
    pub returns: u64,
    /// Dropped by the bounding box (or the area a reader was asked for), once decoded.
    pub bbox: u64,
    /// Dropped because the `--z-from` attribute has no finite value.
    pub no_value: u64,
    /// Points of files and COPC nodes wholly outside the box, skipped without being decoded
    /// (not counted in `read`).
    pub skipped: u64,
}

impl FilterStats {
    /// What the filters left and dropped, for the message when too little is left: "no point
    /// left after the filters: of 39233 point(s) read, 39233 by --class", with the distinct
    /// positions among the points kept when some were.
    pub fn describe(&self, distinct: u64) -> String {
        if self.read == 0 && self.skipped == 0 {
            return "the files hold no point".into();
        }
        let mut dropped = Vec::new();
        for (n, what) in [
            (self.withheld, "withheld (--keep-withheld keeps them)"),
            (self.class, "by --class"),
            (self.returns, "by --returns"),
            (self.bbox, "outside --bbox"),
            (
                self.skipped,
                "in files or COPC nodes outside --bbox (not read)",
            ),
        ] {
            if n > 0 {
                dropped.push(format!("{n} {what}"));
            }
        }
        let what = format!("of {} point(s) read, {}", self.read, dropped.join(", "));
        if self.kept == 0 {
            return format!("no point left after the filters: {what}");
        }
        format!(
            "fewer than 3 distinct points left after the filters ({distinct} distinct): {what}; \
             {} kept, {} of them exact (x, y) duplicates",
            self.kept,
            self.kept.saturating_sub(distinct)
        )
    }
}

/// Why a point was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    Keep,
    Withheld,
    Class,
    Returns,
    BBox,
}

impl FilterStats {
    #[inline]
    pub(crate) fn count(&mut self, v: Verdict) {
        self.read += 1;
        match v {
            Verdict::Keep => self.kept += 1,
            Verdict::Withheld => self.withheld += 1,
            Verdict::Class => self.class += 1,
            Verdict::Returns => self.returns += 1,
            Verdict::BBox => self.bbox += 1,
        }
    }
}

impl std::ops::AddAssign for FilterStats {
    fn add_assign(&mut self, o: FilterStats) {
        self.read += o.read;
        self.kept += o.kept;
        self.withheld += o.withheld;
        self.class += o.class;
        self.returns += o.returns;
        self.bbox += o.bbox;
        self.no_value += o.no_value;
        self.skipped += o.skipped;
    }
}

/// A [`Filter`] turned into table look-ups and comparisons.
#[derive(Clone, Debug)]
pub(crate) struct CompiledFilter {
    classes: Option<Box<[bool; 256]>>,
    /// `Filter::classes_from`.
    pub(crate) classes_from: Option<ClassesFrom>,
    returns: Returns,
    drop_withheld: bool,
    /// The filter's box met with the area asked for, `[xmin, ymin, xmax, ymax]`, edges
    /// included (empty, `xmin > xmax`, when they do not meet).
    bbox: Option<[f64; 4]>,
}

impl CompiledFilter {
    /// The filter, keeping only points inside `area` too.
    pub(crate) fn new(filter: &Filter, area: Option<BBox>) -> CompiledFilter {
        let classes = filter.classes.as_ref().map(|list| {
            let mut table = Box::new([false; 256]);
            for &c in list {
                table[usize::from(c)] = true;
            }
            table
        });
        let bbox = match (filter.bbox, area) {
            (Some(b), Some(a)) => Some(
                b.intersection(&a)
                    .map_or([1.0, 1.0, 0.0, 0.0], |i| i.corners()),
            ),
            (b, a) => b.or(a).map(|b| b.corners()),
        };
        CompiledFilter {
            classes,
            classes_from: filter.classes_from.clone(),
            returns: filter.returns,
            drop_withheld: filter.drop_withheld,
            bbox,
        }
    }

    #[inline]
    pub(crate) fn test(&self, p: &LidarPoint) -> Verdict {
        if self.drop_withheld && p.flags & LidarPoint::WITHHELD != 0 {
            return Verdict::Withheld;
        }
        if let Some(t) = &self.classes
            && !t[usize::from(p.classification)]
        {
            return Verdict::Class;
        }
        let returns_ok = match self.returns {
            Returns::All => true,
            Returns::First => p.return_number == 1,
            Returns::Last => p.return_number == p.number_of_returns,
        };
        if !returns_ok {
            return Verdict::Returns;
        }
        if let Some([x0, y0, x1, y1]) = self.bbox
            && !(p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1)
        {
            return Verdict::BBox;
        }
        Verdict::Keep
    }

    /// Can no point of the rectangle `[xmin, ymin, xmax, ymax]` grown by `margin` pass the box?
    /// (A file's header extent or a COPC node's bounds: then it need not be decoded.)
    pub(crate) fn misses(&self, r: [f64; 4], margin: f64) -> bool {
        match self.bbox {
            None => false,
            Some([x0, y0, x1, y1]) => {
                x0 > x1
                    || y0 > y1
                    || r[0] - margin > x1
                    || r[2] + margin < x0
                    || r[1] - margin > y1
                    || r[3] + margin < y0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_bbox_and_classes() {
        let b: BBox = "1,2,3,4".parse().unwrap();
        assert_eq!(b.corners(), [1.0, 2.0, 3.0, 4.0]);
        assert!("1,2,3".parse::<BBox>().is_err());
        assert!("3,2,1,4".parse::<BBox>().is_err());
        assert!("1,2,x,4".parse::<BBox>().is_err());
        assert!("1,2,inf,4".parse::<BBox>().is_err());
        assert_eq!(parse_classes("2, 9").unwrap(), vec![2, 9]);
        assert!(
            parse_classes("2,256")
                .unwrap_err()
                .to_string()
                .contains("256")
        );
    }

    #[test]
    fn verdicts_follow_the_documented_order() {
        let f = Filter {
            classes: Some(vec![2]),
            returns: Returns::Last,
            drop_withheld: true,
            bbox: Some(BBox::new(1.0, 1.0, 2.0, 2.0).unwrap()),
            z_from: None,
            classes_from: None,
        };
        let c = CompiledFilter::new(&f, None);
        let p = LidarPoint {
            index: 0,
            x: 1.0,
            y: 2.0,
            z: 0.0,
            classification: 2,
            return_number: 2,
            number_of_returns: 2,
            flags: 0,
        };
        assert_eq!(c.test(&p), Verdict::Keep);
        assert_eq!(c.test(&LidarPoint { x: 2.01, ..p }), Verdict::BBox);
        assert_eq!(c.test(&LidarPoint { x: 0.99, ..p }), Verdict::BBox);
        assert_eq!(
            c.test(&LidarPoint {
                return_number: 1,
                x: 0.0,
                ..p
            }),
            Verdict::Returns
        );
        assert_eq!(
            c.test(&LidarPoint {
                classification: 1,
                return_number: 1,
                ..p
            }),
            Verdict::Class
        );
        assert_eq!(
            c.test(&LidarPoint {
                flags: LidarPoint::WITHHELD,
                classification: 1,
                ..p
            }),
            Verdict::Withheld
        );
        let first = CompiledFilter::new(
            &Filter {
                returns: Returns::First,
                ..Filter::default()
            },
            None,
        );
        assert_eq!(
            first.test(&LidarPoint {
                return_number: 1,
                ..p
            }),
            Verdict::Keep
        );
        assert_eq!(first.test(&p), Verdict::Returns);
        let all = CompiledFilter::new(&Filter::keep_all(), None);
        assert_eq!(
            all.test(&LidarPoint {
                flags: LidarPoint::WITHHELD,
                ..p
            }),
            Verdict::Keep
        );
    }

    #[test]
    fn an_area_meets_the_box() {
        let b = BBox::new(0.0, 0.0, 10.0, 10.0).unwrap();
        let f = Filter {
            bbox: Some(b),
            ..Filter::default()
        };
        let inside = CompiledFilter::new(&f, BBox::new(5.0, 5.0, 20.0, 20.0));
        assert!(inside.misses([11.0, 0.0, 12.0, 1.0], 0.0));
        assert!(!inside.misses([9.0, 9.0, 12.0, 12.0], 0.0));
        assert!(!inside.misses([10.5, 0.0, 12.0, 10.0], 1.0));
        let apart = CompiledFilter::new(&f, BBox::new(50.0, 50.0, 60.0, 60.0));
        assert!(apart.misses([0.0, 0.0, 100.0, 100.0], 0.0));
        let p = LidarPoint {
            x: 55.0,
            y: 55.0,
            ..LidarPoint::default()
        };
        assert_eq!(apart.test(&p), Verdict::BBox);
        assert!(!CompiledFilter::new(&Filter::default(), None).misses([0.0; 4], 0.0));
        assert!(b.meets([10.0, 10.0, 11.0, 11.0], 0.0));
        assert!(!b.meets([10.5, 10.0, 11.0, 11.0], 0.0));
    }
}
