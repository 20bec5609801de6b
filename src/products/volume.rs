//! Cut and fill volumes and areas of the TIN against a horizontal plane, optionally within a
//! boundary polygon (see [`super::overlay`] for a second surface).
//!
//! # What is computed
//!
//! With `d = z_surface − z_reference`:
//! - **cut**: where the surface is above the reference (`d > 0`): the volume `∫ d` and the area;
//! - **fill**: where it is below (`d < 0`): the volume `∫ −d` and the area;
//! - **net** = cut − fill, and the **area** covered (where the TIN exists, inside the boundary).
//!
//! (Cut is material above the reference, to excavate down to it; fill is the room below it.)
//!
//! # How
//!
//! Each triangle is clipped to the boundary's trapezoids ([`super::boundary`]) and each piece
//! split by the line where it meets the reference plane; every resulting piece is a convex
//! polygon on which `d` is linear, so its volume is its area times the mean of `d` at the
//! vertices of a fan — exact up to rounding (prisms, no sampling). Triangles are independent, so
//! the order of the stream does not matter; sums are exact ([`ExactSum`]), so the result is the
//! same bits in any order.

use super::boundary::Boundary;
use super::geom::{ExactSum, PV, Tri, clip, integrate};
use crate::error::{Error, Result};
use crate::sink::{
    CutFillTotals, ProductSummary, StreamInfo, TriangleSink, VolumeReference, VolumeSummary,
};

/// Cut/fill accumulators (exact sums).
#[derive(Clone, Debug, Default)]
pub struct CutFill {
    cut: ExactSum,
    fill: ExactSum,
    cut_area: ExactSum,
    fill_area: ExactSum,
    area: ExactSum,
    scratch: (Vec<PV>, Vec<PV>),
}

impl CutFill {
    /// Adds a convex counter-clockwise polygon whose vertices carry `d` (surface − reference).
    pub fn add(&mut self, poly: &[PV]) {
        let (a, _) = integrate(poly);
        self.area.add(a);
        let (above, below) = (&mut self.scratch.0, &mut self.scratch.1);
        clip(poly, |p| p[2], false, above);
        let (a, v) = integrate(above);
        if above.iter().any(|p| p[2] != 0.0) {
            self.cut_area.add(a);
        }
        self.cut.add(v);
        clip(poly, |p| -p[2], true, below);
        let (a, v) = integrate(below);
        // A piece level with the reference is neither cut nor fill.
        if below.iter().any(|p| p[2] != 0.0) {
            self.fill_area.add(a);
        }
        self.fill.add(-v);
    }

    /// The exact sums so far (cut, fill, cut area, fill area, area), as the non-overlapping
    /// partials whose sum they are: summing the partials of several parts gives the same totals,
    /// bit for bit, as one pass over all of them (a plan's tasks).
    pub fn partials(&self) -> [Vec<f64>; 5] {
        [
            self.cut.partials().to_vec(),
            self.fill.partials().to_vec(),
            self.cut_area.partials().to_vec(),
            self.fill_area.partials().to_vec(),
            self.area.partials().to_vec(),
        ]
    }

    /// The totals of exact sums given as partials (see [`CutFill::partials`]).
    pub fn totals_of(parts: &[[Vec<f64>; 5]]) -> CutFillTotals {
        let mut acc = CutFill::default();
        for p in parts {
            for (s, v) in [
                &mut acc.cut,
                &mut acc.fill,
                &mut acc.cut_area,
                &mut acc.fill_area,
                &mut acc.area,
            ]
            .into_iter()
            .zip(p)
            {
                for &x in v {
                    s.add(x);
                }
            }
        }
        acc.totals()
    }

    /// The totals so far. Volumes and areas are sums of parts that are never negative: a sum
    /// below zero is the clipping's rounding (±1e-11 where two surfaces meet), reported as 0
    /// (never `-0`).
    pub fn totals(&self) -> CutFillTotals {
        let whole = |s: &ExactSum| {
            let v = s.value();
            if v > 0.0 { v } else { 0.0 }
        };
        let cut = whole(&self.cut);
        let fill = whole(&self.fill);
        let mut net = ExactSum::new();
        net.add(cut);
        net.add(-fill);
        CutFillTotals {
            cut_volume: cut,
            fill_volume: fill,
            net_volume: net.value(),
            cut_area: whole(&self.cut_area),
            fill_area: whole(&self.fill_area),
            area: whole(&self.area),
        }
    }
}

/// Refuses a reference plane that is not a finite height (`--plane nan` gave volumes of 0,
/// `inf` nonsense): the one check of the command line, plans and the Python package.
///
/// # Errors
/// [`Error::Options`] naming the value.
pub fn check_plane(plane: f64) -> Result<()> {
    if plane.is_finite() {
        return Ok(());
    }
    Err(Error::Options(format!(
        "the volume's plane must be a finite height, not {plane}"
    )))
}

/// A [`TriangleSink`] computing cut and fill against the plane `z = plane`.
#[derive(Debug)]
pub struct VolumeSink {
    plane: f64,
    boundary: Option<Boundary>,
    acc: CutFill,
    triangles: u64,
}

impl VolumeSink {
    /// Against `z = plane`, inside `boundary` when given.
    ///
    /// # Errors
    /// [`Error::Options`] for a plane that is not a finite height ([`check_plane`]).
    pub fn new(plane: f64, boundary: Option<Boundary>) -> Result<VolumeSink> {
        check_plane(plane)?;
        Ok(VolumeSink {
            plane,
            boundary,
            acc: CutFill::default(),
            triangles: 0,
        })
    }

    /// The totals so far.
    pub fn totals(&self) -> CutFillTotals {
        self.acc.totals()
    }
}

impl TriangleSink for VolumeSink {
    fn begin(&mut self, _info: &StreamInfo) -> Result<()> {
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        self.triangles += 1;
        let Some(t) = Tri::new(t) else {
            return Ok(());
        };
        let poly: Vec<PV> =
            t.v.iter()
                .map(|p| [p[0], p[1], p[2] - self.plane])
                .collect();
        match &self.boundary {
            None => self.acc.add(&poly),
            Some(b) => {
                let acc = &mut self.acc;
                b.clip(&poly, |piece| acc.add(piece));
            }
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        Ok(ProductSummary::Volume(VolumeSummary {
            totals: self.acc.totals(),
            partials: Some(self.acc.partials()),
            reference: VolumeReference::Plane(self.plane),
            boundary_area: self.boundary.as_ref().map(Boundary::area),
            triangles: self.triangles,
            overlay: None,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::products::testutil::{feed, in_sweep_order, random_tin, shuffled_with_watermarks};

    fn info() -> StreamInfo {
        StreamInfo {
            crs: None,
            bounds: [0.0, 0.0, 100.0, 100.0],
        }
    }

    /// A plane against a plane it crosses: the cut and fill are two exact prisms.
    #[test]
    fn plane_against_plane_is_exact() {
        // z = x / 10 on [0, 100]²: above z = 5 for x > 50.
        let tris = random_tin(500, 100.0, 3, |x, _| x / 10.0);
        let mut sink = VolumeSink::new(5.0, None).unwrap();
        let ProductSummary::Volume(s) = feed(&mut sink, &info(), &in_sweep_order(&tris)) else {
            panic!("not a volume summary")
        };
        let v = s.totals;
        // Each side: ∫_0^50 (x/10) dx × 100 = 125 × 100.
        let close = |a: f64, b: f64| (a - b).abs() < 1e-8 * b.max(1.0);
        assert!(close(v.cut_volume, 12_500.0), "{v:?}");
        assert!(close(v.fill_volume, 12_500.0), "{v:?}");
        assert!(close(v.cut_area, 5_000.0), "{v:?}");
        assert!(close(v.fill_area, 5_000.0), "{v:?}");
        assert!(close(v.area, 10_000.0), "{v:?}");
        assert!(v.net_volume.abs() < 1e-8, "{v:?}");
        assert_eq!(s.reference, VolumeReference::Plane(5.0));
    }

    /// Inside a boundary (a triangle with a hole), against a plane, in any order.
    #[test]
    fn boundary_and_order_independence() {
        let tris = random_tin(800, 100.0, 8, |x, y| 0.2 * x + 0.1 * y);
        let boundary = Boundary::new(&[vec![
            vec![[10.0, 10.0], [90.0, 10.0], [10.0, 90.0]],
            vec![[20.0, 20.0], [30.0, 20.0], [30.0, 30.0], [20.0, 30.0]],
        ]])
        .unwrap();
        assert_eq!(boundary.area(), 3200.0 - 100.0);
        let run = |steps: &[crate::products::testutil::Step]| {
            let mut sink = VolumeSink::new(0.0, Some(boundary.clone())).unwrap();
            feed(&mut sink, &info(), steps);
            sink.totals()
        };
        let a = run(&in_sweep_order(&tris));
        let b = run(&shuffled_with_watermarks(&tris, 2));
        assert_eq!(a, b);
        // ∫ (0.2x + 0.1y) over the triangle (area 3200, centroid (36.67, 36.67)) minus the square
        // (area 100, centroid (25, 25)).
        let want = 3200.0 * (0.3 * 110.0 / 3.0) - 100.0 * (0.3 * 25.0);
        assert!((a.cut_volume - want).abs() < 1e-8 * want, "{a:?} vs {want}");
        assert_eq!(a.fill_volume, 0.0);
        assert!((a.area - 3100.0).abs() < 1e-9);
    }

    /// A flat triangle exactly at the plane counts in the area but neither in cut nor fill.
    #[test]
    fn flat_at_the_plane() {
        let mut sink = VolumeSink::new(2.0, None).unwrap();
        let t = [[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.0]];
        feed(&mut sink, &info(), &[(t, None)]);
        let r = sink.totals();
        assert_eq!((r.cut_area, r.fill_area, r.area), (0.0, 0.0, 0.5));
        assert_eq!((r.cut_volume, r.fill_volume), (0.0, 0.0));
    }
}
