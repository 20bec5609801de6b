//! Which points to keep: classification, returns, withheld flag, bounding box.
//!
//! A point is dropped by the **first** filter that rejects it, in this order: withheld flag,
//! classification, returns, bounding box; [`FilterStats`] counts the drops per filter.

use super::LidarPoint;
use super::combine::Quantization;
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// Which returns of each pulse to keep.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
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
}

impl FromStr for BBox {
    type Err = String;

    /// Parses `xmin,ymin,xmax,ymax`.
    fn from_str(s: &str) -> Result<BBox, String> {
        let v: Vec<f64> = s
            .split(',')
            .map(|t| t.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("bounding box \"{s}\": {e} (expected xmin,ymin,xmax,ymax)"))?;
        if v.len() != 4 {
            return Err(format!(
                "bounding box \"{s}\": expected 4 numbers xmin,ymin,xmax,ymax, got {}",
                v.len()
            ));
        }
        BBox::new(v[0], v[1], v[2], v[3]).ok_or_else(|| {
            format!(
                "bounding box \"{s}\": values must be finite with xmin <= xmax and ymin <= ymax"
            )
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
/// A message naming the bad item.
pub fn parse_classes(s: &str) -> Result<Vec<u8>, String> {
    s.split(',')
        .map(|t| {
            t.trim().parse::<u8>().map_err(|_| {
                format!(
                    "classification \"{}\": expected a number from 0 to 255",
                    t.trim()
                )
            })
        })
        .collect()
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
}

impl Default for Filter {
    fn default() -> Self {
        Filter {
            classes: None,
            returns: Returns::All,
            drop_withheld: true,
            bbox: None,
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
    /// Dropped by the bounding box.
    pub bbox: u64,
}

impl FilterStats {
    /// What the filters left and dropped, for the message when too little is left: "no point
    /// left after the filters: of 39233 point(s) read, 39233 by --class", with the distinct
    /// positions among the points kept when some were.
    pub fn describe(&self, distinct: u64) -> String {
        if self.read == 0 {
            return "the files hold no point".into();
        }
        let mut dropped = Vec::new();
        for (n, what) in [
            (self.withheld, "withheld (--keep-withheld keeps them)"),
            (self.class, "by --class"),
            (self.returns, "by --returns"),
            (self.bbox, "outside --bbox"),
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

/// A [`Filter`] turned into table look-ups and integer comparisons in the reader's common
/// integer coordinates.
#[derive(Clone, Debug)]
pub(crate) struct CompiledFilter {
    classes: Option<Box<[bool; 256]>>,
    returns: Returns,
    drop_withheld: bool,
    /// Integer `[xmin, ymin, xmax, ymax]`, inclusive.
    bbox: Option<[i64; 4]>,
}

impl CompiledFilter {
    pub(crate) fn new(filter: &Filter, q: &Quantization) -> CompiledFilter {
        let classes = filter.classes.as_ref().map(|list| {
            let mut table = Box::new([false; 256]);
            for &c in list {
                table[usize::from(c)] = true;
            }
            table
        });
        let bbox = filter.bbox.map(|b| {
            [
                q.ceil_index(0, b.xmin),
                q.ceil_index(1, b.ymin),
                q.floor_index(0, b.xmax),
                q.floor_index(1, b.ymax),
            ]
        });
        CompiledFilter {
            classes,
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
        if let Some([x0, y0, x1, y1]) = self.bbox {
            let (x, y) = (i64::from(p.x), i64::from(p.y));
            if x < x0 || x > x1 || y < y0 || y > y1 {
                return Verdict::BBox;
            }
        }
        Verdict::Keep
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
        assert!(parse_classes("2,256").unwrap_err().contains("256"));
    }

    #[test]
    fn verdicts_follow_the_documented_order() {
        let q = Quantization {
            scale: [0.01; 3],
            offset: [0.0; 3],
        };
        let f = Filter {
            classes: Some(vec![2]),
            returns: Returns::Last,
            drop_withheld: true,
            bbox: Some(BBox::new(1.0, 1.0, 2.0, 2.0).unwrap()),
        };
        let c = CompiledFilter::new(&f, &q);
        let p = LidarPoint {
            index: 0,
            x: 100,
            y: 200,
            z: 0,
            classification: 2,
            return_number: 2,
            number_of_returns: 2,
            flags: 0,
        };
        assert_eq!(c.test(&p), Verdict::Keep);
        assert_eq!(c.test(&LidarPoint { x: 201, ..p }), Verdict::BBox);
        assert_eq!(c.test(&LidarPoint { x: 99, ..p }), Verdict::BBox);
        assert_eq!(
            c.test(&LidarPoint {
                return_number: 1,
                x: 0,
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
            &q,
        );
        assert_eq!(
            first.test(&LidarPoint {
                return_number: 1,
                ..p
            }),
            Verdict::Keep
        );
        assert_eq!(first.test(&p), Verdict::Returns);
        let all = CompiledFilter::new(&Filter::keep_all(), &q);
        assert_eq!(
            all.test(&LidarPoint {
                flags: LidarPoint::WITHHELD,
                ..p
            }),
            Verdict::Keep
        );
    }
}
