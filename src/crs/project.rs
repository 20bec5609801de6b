//! Inverse map projections, from projected coordinates to longitude and latitude, without a
//! projection library: what a STAC item's `geometry` and `bbox` need (RFC 7946: WGS84 degrees).
//!
//! - **Transverse Mercator** (EPSG method 9807) by Krüger's series to the sixth order in `n`
//!   (Karney 2011, "Transverse Mercator with an accuracy of a few nanometers": better than 0.1 mm
//!   within 4,000 km of the central meridian), the conformal latitude turned into the geodetic one
//!   by Newton's method; natural origin on the equator (every UTM zone and the grids below).
//! - **Lambert Conformal Conic 2SP** (EPSG method 9802), inverse as in IOGP Guidance Note 7-2.
//!
//! The parameters come from a table of EPSG codes ([`Projection::of_epsg`]): UTM zones on WGS 84
//! (326xx, 327xx), ETRS89 (25828–25838), NAD83 (26901–26923) and NAD83(CSRS) (2955–2962: zones
//! 11–13 and 17–21 north), NAD83(CSRS) MTM zones 3–10 (2945–2952), Slovenia's
//! D96/TM (3794) and France's Lambert-93 (2154). The latitude and longitude are on the CRS's own
//! datum: ETRS89, RGF93, D96 and NAD83 are treated as WGS 84, which they match within about 1 m
//! (2 m for NAD83 in North America), well inside what an index's footprint needs. Datums far from
//! WGS 84 (the Dutch RD on Bessel 1841: about 100 m) are not in the table.

use std::f64::consts::FRAC_PI_4;

/// An ellipsoid: semi-major axis `a` and flattening `f`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    /// Semi-major axis, metres.
    pub a: f64,
    /// Flattening.
    pub f: f64,
}

const GRS80: Ellipsoid = Ellipsoid {
    a: 6_378_137.0,
    f: 1.0 / 298.257_222_101,
};
const WGS84: Ellipsoid = Ellipsoid {
    a: 6_378_137.0,
    f: 1.0 / 298.257_223_563,
};

impl Ellipsoid {
    fn e2(&self) -> f64 {
        self.f * (2.0 - self.f)
    }
}

/// A projection whose inverse is known (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Transverse Mercator with its natural origin on the equator.
    TransverseMercator {
        /// The ellipsoid.
        ellipsoid: Ellipsoid,
        /// Longitude of the central meridian, degrees.
        lon0: f64,
        /// Scale factor on the central meridian.
        k0: f64,
        /// False easting.
        fe: f64,
        /// False northing.
        fnorth: f64,
    },
    /// Lambert Conformal Conic with two standard parallels.
    LambertConic2Sp {
        /// The ellipsoid.
        ellipsoid: Ellipsoid,
        /// Latitude of the false origin, degrees.
        lat0: f64,
        /// Longitude of the false origin, degrees.
        lon0: f64,
        /// First standard parallel, degrees.
        lat1: f64,
        /// Second standard parallel, degrees.
        lat2: f64,
        /// Easting at the false origin.
        fe: f64,
        /// Northing at the false origin.
        fnorth: f64,
    },
}

fn utm(ellipsoid: Ellipsoid, zone: u32, south: bool) -> Projection {
    Projection::TransverseMercator {
        ellipsoid,
        lon0: -183.0 + 6.0 * f64::from(zone),
        k0: 0.9996,
        fe: 500_000.0,
        fnorth: if south { 10_000_000.0 } else { 0.0 },
    }
}

impl Projection {
    /// The projection of a projected CRS's EPSG code, when it is in the table (module docs).
    pub fn of_epsg(code: u32) -> Option<Projection> {
        Some(match code {
            32601..=32660 => utm(WGS84, code - 32600, false),
            32701..=32760 => utm(WGS84, code - 32700, true),
            25828..=25838 => utm(GRS80, code - 25800, false),
            26901..=26923 => utm(GRS80, code - 26900, false),
            2955..=2957 => utm(GRS80, code - 2944, false),
            2958..=2962 => utm(GRS80, code - 2941, false),
            2945..=2952 => Projection::TransverseMercator {
                ellipsoid: GRS80,
                lon0: -(49.5 + 3.0 * f64::from(code - 2942)),
                k0: 0.9999,
                fe: 304_800.0,
                fnorth: 0.0,
            },
            3794 => Projection::TransverseMercator {
                ellipsoid: GRS80,
                lon0: 15.0,
                k0: 0.9999,
                fe: 500_000.0,
                fnorth: -5_000_000.0,
            },
            2154 => Projection::LambertConic2Sp {
                ellipsoid: GRS80,
                lat0: 46.5,
                lon0: 3.0,
                lat1: 49.0,
                lat2: 44.0,
                fe: 700_000.0,
                fnorth: 6_600_000.0,
            },
            _ => return None,
        })
    }

    /// `[longitude, latitude]` in degrees of the projected point `(x, y)`, the longitude in
    /// `[-180, 180]`.
    pub fn inverse(&self, x: f64, y: f64) -> [f64; 2] {
        let [lon, lat] = self.inverse_unwrapped(x, y);
        let lon = if lon.abs() > 180.0 {
            lon - 360.0 * (lon / 360.0).round()
        } else {
            lon
        };
        [lon, lat]
    }

    fn inverse_unwrapped(&self, x: f64, y: f64) -> [f64; 2] {
        match *self {
            Projection::TransverseMercator {
                ellipsoid,
                lon0,
                k0,
                fe,
                fnorth,
            } => tm_inverse(ellipsoid, lon0, k0, x - fe, y - fnorth),
            Projection::LambertConic2Sp {
                ellipsoid,
                lat0,
                lon0,
                lat1,
                lat2,
                fe,
                fnorth,
            } => lcc_inverse(ellipsoid, [lat0, lon0, lat1, lat2], x - fe, y - fnorth),
        }
    }

    /// The rectangle `[xmin, ymin, xmax, ymax]` as a closed longitude/latitude ring: its corners
    /// and `per_edge − 1` points between each two, counter-clockwise from the lower left (the
    /// edges of a projected box are curves in degrees).
    pub fn ring(&self, rect: [f64; 4], per_edge: usize) -> Vec<[f64; 2]> {
        let n = per_edge.max(1);
        let corners = [
            [rect[0], rect[1]],
            [rect[2], rect[1]],
            [rect[2], rect[3]],
            [rect[0], rect[3]],
        ];
        let mut out = Vec::with_capacity(4 * n + 1);
        for i in 0..4 {
            let (a, b) = (corners[i], corners[(i + 1) % 4]);
            for k in 0..n {
                let t = k as f64 / n as f64;
                out.push(self.inverse(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])));
            }
        }
        out.push(out[0]);
        out
    }
}

/// Geodetic latitude (radians) of the conformal latitude whose tangent is `taup` (Karney 2011,
/// eqs. 7–9 and 19–21, by Newton's method).
fn geodetic_of_conformal(taup: f64, e2: f64) -> f64 {
    let e = e2.sqrt();
    let taup_of = |tau: f64| {
        let sigma = (e * (e * tau / tau.hypot(1.0)).atanh()).sinh();
        tau * sigma.hypot(1.0) - sigma * tau.hypot(1.0)
    };
    let mut tau = taup / (1.0 - e2);
    for _ in 0..8 {
        let d = (taup - taup_of(tau)) * (1.0 + (1.0 - e2) * tau * tau)
            / ((1.0 - e2) * tau.hypot(1.0) * taup_of(tau).hypot(1.0));
        tau += d;
        if d.abs() < 1e-15 * tau.abs().max(1.0) {
            break;
        }
    }
    tau.atan()
}

/// Inverse Transverse Mercator (Krüger's series; module docs) of the offsets from the false
/// origin `(dx, dy)`.
fn tm_inverse(el: Ellipsoid, lon0: f64, k0: f64, dx: f64, dy: f64) -> [f64; 2] {
    let n = el.f / (2.0 - el.f);
    let (n2, n3) = (n * n, n * n * n);
    let (n4, n5, n6) = (n2 * n2, n2 * n3, n3 * n3);
    let big_a = el.a / (1.0 + n) * (1.0 + n2 / 4.0 + n4 / 64.0 + n6 / 256.0);
    let beta = [
        n / 2.0 - 2.0 * n2 / 3.0 + 37.0 * n3 / 96.0 - n4 / 360.0 - 81.0 * n5 / 512.0
            + 96199.0 * n6 / 604800.0,
        n2 / 48.0 + n3 / 15.0 - 437.0 * n4 / 1440.0 + 46.0 * n5 / 105.0
            - 1118711.0 * n6 / 3870720.0,
        17.0 * n3 / 480.0 - 37.0 * n4 / 840.0 - 209.0 * n5 / 4480.0 + 5569.0 * n6 / 90720.0,
        4397.0 * n4 / 161280.0 - 11.0 * n5 / 504.0 - 830251.0 * n6 / 7257600.0,
        4583.0 * n5 / 161280.0 - 108847.0 * n6 / 3991680.0,
        20648693.0 * n6 / 638668800.0,
    ];
    let xi = dy / (k0 * big_a);
    let eta = dx / (k0 * big_a);
    let (mut xi1, mut eta1) = (xi, eta);
    for (j, b) in beta.iter().enumerate() {
        let m = 2.0 * (j + 1) as f64;
        xi1 -= b * (m * xi).sin() * (m * eta).cosh();
        eta1 -= b * (m * xi).cos() * (m * eta).sinh();
    }
    // The conformal latitude and the longitude from the central meridian (on the sphere).
    let taup = xi1.sin() / eta1.sinh().hypot(xi1.cos());
    let lon = eta1.sinh().atan2(xi1.cos());
    let lat = geodetic_of_conformal(taup, el.e2());
    [lon0 + lon.to_degrees(), lat.to_degrees()]
}

/// Inverse Lambert Conformal Conic 2SP (IOGP 7-2, method 9802) of the offsets from the false
/// origin; `p` is `[lat0, lon0, lat1, lat2]` in degrees.
fn lcc_inverse(el: Ellipsoid, p: [f64; 4], dx: f64, dy: f64) -> [f64; 2] {
    let e2 = el.e2();
    let e = e2.sqrt();
    let [lat0, lon0, lat1, lat2] = p.map(f64::to_radians);
    let m = |phi: f64| phi.cos() / (1.0 - e2 * phi.sin() * phi.sin()).sqrt();
    let t = |phi: f64| {
        let s = e * phi.sin();
        (FRAC_PI_4 - phi / 2.0).tan() / ((1.0 - s) / (1.0 + s)).powf(e / 2.0)
    };
    let n = if (lat1 - lat2).abs() < 1e-12 {
        lat1.sin()
    } else {
        (m(lat1).ln() - m(lat2).ln()) / (t(lat1).ln() - t(lat2).ln())
    };
    let f = m(lat1) / (n * t(lat1).powf(n));
    let r_f = el.a * f * t(lat0).powf(n);
    let (u, v) = (dx, r_f - dy);
    let r = n.signum() * u.hypot(v);
    let tp = (r / (el.a * f)).powf(1.0 / n);
    let theta = if n < 0.0 { (-u).atan2(-v) } else { u.atan2(v) };
    let mut phi = std::f64::consts::FRAC_PI_2 - 2.0 * tp.atan();
    for _ in 0..20 {
        let s = e * phi.sin();
        let next =
            std::f64::consts::FRAC_PI_2 - 2.0 * (tp * ((1.0 - s) / (1.0 + s)).powf(e / 2.0)).atan();
        let done = (next - phi).abs() < 1e-14;
        phi = next;
        if done {
            break;
        }
    }
    [(theta / n + lon0).to_degrees(), phi.to_degrees()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PROJ 9.x's answers (pyproj 3.7, to each CRS's own geographic CRS), for the tests.
    const REFERENCE: [(u32, [f64; 2], [f64; 2]); 8] = [
        (
            3794,
            [511000.0, 122000.0],
            [15.142628816227, 46.237656956902],
        ),
        (
            2154,
            [770520.0, 6277520.0],
            [3.873020687922, 43.593227928606],
        ),
        (
            2154,
            [299000.0, 6802000.0],
            [-2.400862972213, 48.194883027047],
        ),
        (
            2949,
            [273357.0, 5274357.0],
            [-70.918225700055, 47.607615420227],
        ),
        (
            32631,
            [300000.0, 5500000.0],
            [0.230942252786, 49.619417191888],
        ),
        (
            32760,
            [700000.0, 4000000.0],
            [-179.940406316644, -54.109206447639],
        ),
        (
            2952,
            [454800.0, 5000000.0],
            [-77.593267167474, 45.124053869174],
        ),
        (
            2958,
            [700000.0, 6000000.0],
            [-77.940406316595, 54.109206448754],
        ),
    ];

    /// Reference coordinates from PROJ 9 (pyproj 3, `Transformer.from_crs(crs,
    /// crs.geodetic_crs, always_xy=True)`: the projection alone, on the CRS's own datum; to
    /// EPSG:4326 PROJ moves NAD83(CSRS) by about 1 m, the tolerance the module docs state).
    #[test]
    fn inverse_projections_agree_with_proj_to_the_millimetre() {
        let cases = REFERENCE;
        for (code, xy, want) in cases {
            let p = Projection::of_epsg(code).unwrap();
            let got = p.inverse(xy[0], xy[1]);
            // 1e-8 degree is about 1 mm.
            let dlon = (got[0] - want[0]).abs() * want[1].to_radians().cos();
            let dlat = (got[1] - want[1]).abs();
            assert!(
                dlon < 1e-8 && dlat < 1e-8,
                "EPSG:{code} {xy:?}: {got:?}, PROJ gives {want:?}"
            );
        }
        assert!(Projection::of_epsg(28992).is_none(), "RD is on Bessel 1841");
    }
}
