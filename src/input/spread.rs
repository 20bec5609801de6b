//! Far points: a handful of points far from the rest of the data — a GPS glitch kilometres away,
//! a point at (0, 0), a bird — make the data's extent, and with it a DEM's grid or a tile grid,
//! far larger than the data (ARSO's 1 km tile plus one point 15 km away: a 16,000 × 16,000 DEM).
//! [`Spread`] watches every point read and says which points those are.
//!
//! The rule: from a sample of the points (the 2,048 whose position hashes lowest, so the same
//! set gives the same sample whatever the order, the memory budget or the threads), the 1st and
//! 99th percentiles of `x` and of `y`; a point is *far* when it lies more than four times that
//! range beyond them, in `x` or in `y`. The [`EXTREMES`] lowest and highest `x` and `y` are kept
//! exactly, so the far points are counted and named exactly — when there are at most that many on
//! each side. More than that is a distribution (Kuzmin's heavy tail, clustered surveys), not a
//! handful of stray points, and nothing is said.

use std::collections::BinaryHeap;

/// Points kept at each end of `x` and of `y`.
pub const EXTREMES: usize = 16;
/// Points in the sample the percentiles come from.
const SAMPLE: usize = 2048;
/// How many percentile ranges beyond the percentiles a point must lie to be far.
const FENCE: f64 = 4.0;
/// The fewest points for which the rule says anything.
const FEWEST: u64 = 1000;

/// What [`Spread::far_points`] found.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FarPoints {
    /// Number of far points.
    pub count: u64,
    /// Their positions (world `x`, `y`), at most [`EXTREMES`] of them.
    pub points: Vec<[f64; 2]>,
    /// The extent of all the points, `[xmin, ymin, xmax, ymax]`.
    pub extent: [f64; 4],
    /// The extent of the other points.
    pub rest: [f64; 4],
}

impl FarPoints {
    /// The warning a run prints.
    pub fn warning(&self) -> String {
        let [x0, y0, x1, y1] = self.rest;
        let [ex0, ey0, ex1, ey1] = self.extent;
        let shown: Vec<String> = self
            .points
            .iter()
            .take(4)
            .map(|p| format!("({}, {})", p[0], p[1]))
            .collect();
        let more = if self.count as usize > shown.len() {
            ", …"
        } else {
            ""
        };
        let (what, verb, is) = if self.count == 1 {
            ("1 point lies", "it", "it is")
        } else {
            ("points lie", "them", "they are")
        };
        let what = if self.count == 1 {
            what.to_string()
        } else {
            format!("{} {what}", self.count)
        };
        format!(
            "{what} far from the others: {}{more}; the data's extent is {} × {}, the other \
             points lie within {} × {} ({x0},{y0},{x1},{y1}). A DEM or tile grid covers the \
             whole extent: drop {verb} with --bbox {x0},{y0},{x1},{y1} or with a class filter \
             (--class) if {is} classified as noise",
            shown.join(", "),
            length(ex1 - ex0),
            length(ey1 - ey0),
            length(x1 - x0),
            length(y1 - y0),
        )
    }
}

/// A length for a message: metres (or the data's unit) to the millimetre.
fn length(v: f64) -> String {
    format!("{}", (v * 1000.0).round() / 1000.0)
}

/// The `K` lowest values of a key with their points (a max-heap of the kept ones).
#[derive(Debug, Default, Clone)]
struct Lowest {
    heap: BinaryHeap<(Key, [u64; 2])>,
}

/// A total order on doubles (`f64::total_cmp` as an integer).
type Key = u64;

fn key(v: f64) -> Key {
    let b = v.to_bits();
    if b >> 63 == 1 { !b } else { b | 1 << 63 }
}

impl Lowest {
    #[inline]
    fn add(&mut self, k: Key, p: [u64; 2], cap: usize) {
        if self.heap.len() < cap {
            self.heap.push((k, p));
        } else if let Some(top) = self.heap.peek()
            && (k, p) < *top
        {
            self.heap.pop();
            self.heap.push((k, p));
        }
    }

    /// The kept entries, lowest first.
    fn sorted(&self) -> Vec<(Key, [u64; 2])> {
        let mut v: Vec<_> = self.heap.iter().copied().collect();
        v.sort_unstable();
        v
    }
}

/// Watches the points of a run (see the [module docs](self)).
#[derive(Debug, Default, Clone)]
pub struct Spread {
    n: u64,
    extent: Option<[f64; 4]>,
    /// Lowest `x`, highest `x` (negated key), lowest `y`, highest `y`.
    ends: [Lowest; 4],
    sample: Lowest,
}

impl Spread {
    /// Counts one point.
    #[inline]
    pub fn add(&mut self, x: f64, y: f64) {
        self.n += 1;
        let e = self.extent.get_or_insert([x, y, x, y]);
        *e = [e[0].min(x), e[1].min(y), e[2].max(x), e[3].max(y)];
        let p = [x.to_bits(), y.to_bits()];
        let (kx, ky) = (key(x), key(y));
        self.ends[0].add(kx, p, EXTREMES);
        self.ends[1].add(!kx, p, EXTREMES);
        self.ends[2].add(ky, p, EXTREMES);
        self.ends[3].add(!ky, p, EXTREMES);
        self.sample.add(mix(p[0] ^ mix(p[1])), p, SAMPLE);
    }

    /// The points' extent, `[xmin, ymin, xmax, ymax]` (infinities the wrong way round before the
    /// first point).
    pub fn extent(&self) -> [f64; 4] {
        self.extent.unwrap_or([
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ])
    }

    /// The far points, if there are a few (at most [`EXTREMES`] beyond each side).
    pub fn far_points(&self) -> Option<FarPoints> {
        let extent = self.extent?;
        if self.n < FEWEST {
            return None;
        }
        let pts: Vec<[f64; 2]> = self
            .sample
            .heap
            .iter()
            .map(|(_, p)| p.map(f64::from_bits))
            .collect();
        let fence = |axis: usize| {
            let mut v: Vec<f64> = pts.iter().map(|p| p[axis]).collect();
            v.sort_unstable_by(f64::total_cmp);
            let (lo, hi) = (v[v.len() / 100], v[v.len() - 1 - v.len() / 100]);
            let w = (hi - lo).max(f64::MIN_POSITIVE);
            (lo - FENCE * w, hi + FENCE * w)
        };
        let fences = [fence(0), fence(1)];
        let far = |p: [f64; 2]| {
            p[0] < fences[0].0 || p[0] > fences[0].1 || p[1] < fences[1].0 || p[1] > fences[1].1
        };
        let mut found: Vec<[u64; 2]> = Vec::new();
        let mut rest = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for (side, end) in self.ends.iter().enumerate() {
            let sorted = end.sorted();
            let mut inner = None;
            for (_, p) in &sorted {
                let q = p.map(f64::from_bits);
                if far(q) {
                    if !found.contains(p) {
                        found.push(*p);
                    }
                } else if inner.is_none() {
                    inner = Some(q);
                }
            }
            // All kept points of a side far: more than a handful.
            let inner = inner?;
            let (axis, low) = (side / 2, side % 2 == 0);
            let v = inner[axis];
            if low {
                rest[axis] = v;
            } else {
                rest[axis + 2] = v;
            }
        }
        if found.is_empty() {
            return None;
        }
        found.sort_unstable();
        Some(FarPoints {
            count: found.len() as u64,
            points: found.iter().map(|p| p.map(f64::from_bits)).collect(),
            extent,
            rest,
        })
    }
}

/// SplitMix64's finaliser: a well-mixed hash of 64 bits.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> Vec<[f64; 2]> {
        (0..n * n)
            .map(|i| [(i % n) as f64, (i / n) as f64])
            .collect()
    }

    #[test]
    fn one_far_point_is_named_with_the_box_of_the_others() {
        let mut s = Spread::default();
        let mut pts = grid(100);
        pts.insert(5000, [15_000.0, 20.0]);
        for p in &pts {
            s.add(p[0], p[1]);
        }
        let f = s.far_points().expect("found");
        assert_eq!(f.count, 1);
        assert_eq!(f.points, vec![[15_000.0, 20.0]]);
        assert_eq!(f.rest, [0.0, 0.0, 99.0, 99.0]);
        assert_eq!(f.extent, [0.0, 0.0, 15_000.0, 99.0]);
        let w = f.warning();
        assert!(
            w.contains("1 point lies far") && w.contains("--bbox 0,0,99,99"),
            "{w}"
        );
    }

    #[test]
    fn order_does_not_matter_and_plain_data_says_nothing() {
        let pts = grid(60);
        let mut a = Spread::default();
        let mut b = Spread::default();
        for p in &pts {
            a.add(p[0], p[1]);
        }
        for p in pts.iter().rev() {
            b.add(p[0], p[1]);
        }
        assert_eq!(a.far_points(), None);
        assert_eq!(b.far_points(), None);
        let mut far = pts.clone();
        far.extend([[-1.0e6, 0.0], [0.0, 3.0e5], [7.0, -9.0e4]]);
        let (mut a, mut b) = (Spread::default(), Spread::default());
        for p in &far {
            a.add(p[0], p[1]);
        }
        for p in far.iter().rev() {
            b.add(p[0], p[1]);
        }
        let fa = a.far_points().unwrap();
        assert_eq!(fa.count, 3);
        assert_eq!(Some(fa), b.far_points());
    }

    #[test]
    fn heavy_tails_are_not_a_handful() {
        let mut s = Spread::default();
        for p in crate::synth::heavy::kuzmin(100_000, 3) {
            s.add(p[0], p[1]);
        }
        assert_eq!(s.far_points(), None);
    }
}
