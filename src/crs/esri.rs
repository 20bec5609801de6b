//! ESRI's WKT1, the text GDAL writes in a `.prj` (`gdalsrsinfo -o wkt_esri`), for the EPSG codes
//! lidar most often comes in, spelled without a CRS database: the geographic CRSs of the common
//! datums, UTM zones on them (WGS 84, NAD83, NAD83(2011), NAD83(CSRS), ETRS89), MGA zones (GDA94,
//! GDA2020), NAD83(CSRS) MTM zones 3–10, and a few national grids (Lambert-93, RD New, the
//! Slovene grid, Oregon Lambert in feet, Web Mercator), with the NAP and NAVD88 heights of a
//! compound. `tests/products_gdal.rs` checks every family against GDAL's own text.

/// A geographic CRS: its code and ESRI's names.
struct Geographic {
    code: u32,
    gcs: &'static str,
    datum: &'static str,
    spheroid: &'static str,
    /// Semi-major axis (metres) and inverse flattening.
    a: f64,
    rf: f64,
}

const fn grs80(code: u32, gcs: &'static str, datum: &'static str) -> Geographic {
    Geographic {
        code,
        gcs,
        datum,
        spheroid: "GRS_1980",
        a: 6378137.0,
        rf: 298.257222101,
    }
}

const WGS84: u32 = 4326;
const NAD83: u32 = 4269;
const NAD83_CSRS: u32 = 4617;
const NAD83_2011: u32 = 6318;
const ETRS89: u32 = 4258;
const RGF93: u32 = 4171;
const AMERSFOORT: u32 = 4289;
const GDA94: u32 = 4283;
const GDA2020: u32 = 7844;
const SLOVENIA_1996: u32 = 4765;

const GEOGRAPHIC: [Geographic; 10] = [
    Geographic {
        code: WGS84,
        gcs: "GCS_WGS_1984",
        datum: "D_WGS_1984",
        spheroid: "WGS_1984",
        a: 6378137.0,
        rf: 298.257223563,
    },
    grs80(NAD83, "GCS_North_American_1983", "D_North_American_1983"),
    grs80(
        NAD83_CSRS,
        "GCS_North_American_1983_CSRS",
        "D_North_American_1983_CSRS",
    ),
    grs80(NAD83_2011, "GCS_NAD_1983_2011", "D_NAD_1983_2011"),
    grs80(ETRS89, "GCS_ETRS_1989", "D_ETRS_1989"),
    grs80(RGF93, "GCS_RGF_1993", "D_RGF_1993"),
    Geographic {
        code: AMERSFOORT,
        gcs: "GCS_Amersfoort",
        datum: "D_Amersfoort",
        spheroid: "Bessel_1841",
        a: 6377397.155,
        rf: 299.1528128,
    },
    grs80(GDA94, "GCS_GDA_1994", "D_GDA_1994"),
    grs80(GDA2020, "GCS_GDA2020", "GDA2020"),
    grs80(
        SLOVENIA_1996,
        "GCS_Slovenia_1996",
        "D_Slovenia_Geodetic_Datum_1996",
    ),
];

/// A projected CRS: ESRI's name, its geographic CRS, the projection and its parameters in the
/// order GDAL writes them, and the unit (`("Meter", 1.0)` or `("foot", 0.3048)`).
struct Projected {
    name: String,
    geographic: u32,
    projection: &'static str,
    parameters: Vec<(&'static str, f64)>,
    unit: (&'static str, f64),
}

const METRE: (&str, f64) = ("Meter", 1.0);

fn transverse_mercator(
    name: String,
    geographic: u32,
    [fe, fn_, cm, k]: [f64; 4],
) -> Option<Projected> {
    Some(Projected {
        name,
        geographic,
        projection: "Transverse_Mercator",
        parameters: vec![
            ("False_Easting", fe),
            ("False_Northing", fn_),
            ("Central_Meridian", cm),
            ("Scale_Factor", k),
            ("Latitude_Of_Origin", 0.0),
        ],
        unit: METRE,
    })
}

/// UTM zone `zone` (north, or south with a false northing of 10,000 km) named `prefix_{zone}`
/// plus `N`/`S` when `hemisphere` says so.
fn utm(prefix: &str, geographic: u32, zone: u32, south: bool, letter: bool) -> Option<Projected> {
    let cm = -183.0 + 6.0 * f64::from(zone);
    let hemisphere = match (letter, south) {
        (false, _) => "",
        (true, false) => "N",
        (true, true) => "S",
    };
    let fn_ = if south { 10_000_000.0 } else { 0.0 };
    transverse_mercator(
        format!("{prefix}_{zone}{hemisphere}"),
        geographic,
        [500_000.0, fn_, cm, 0.9996],
    )
}

/// NAD83(CSRS) UTM zones (their codes are not in zone order).
const CSRS_UTM: [(u32, u32); 16] = [
    (3154, 7),
    (3155, 8),
    (3156, 9),
    (3157, 10),
    (2955, 11),
    (2956, 12),
    (2957, 13),
    (3158, 14),
    (3159, 15),
    (3160, 16),
    (2958, 17),
    (2959, 18),
    (2960, 19),
    (2961, 20),
    (2962, 21),
    (3761, 22),
];

fn projected(code: u32) -> Option<Projected> {
    match code {
        32601..=32660 => utm("WGS_1984_UTM_Zone", WGS84, code - 32600, false, true),
        32701..=32760 => utm("WGS_1984_UTM_Zone", WGS84, code - 32700, true, true),
        26901..=26923 => utm("NAD_1983_UTM_Zone", NAD83, code - 26900, false, true),
        6328 | 6329 => utm(
            "NAD_1983_2011_UTM_Zone",
            NAD83_2011,
            code - 6269,
            false,
            true,
        ),
        6330..=6348 => utm(
            "NAD_1983_2011_UTM_Zone",
            NAD83_2011,
            code - 6329,
            false,
            true,
        ),
        25828..=25838 => utm("ETRS_1989_UTM_Zone", ETRS89, code - 25800, false, true),
        28348..=28358 => utm("GDA_1994_MGA_Zone", GDA94, code - 28300, true, false),
        7846..=7859 => utm("GDA2020_MGA_Zone", GDA2020, code - 7800, true, false),
        2945..=2952 => {
            let zone = code - 2942;
            transverse_mercator(
                format!("NAD_1983_CSRS_MTM_{zone}"),
                NAD83_CSRS,
                [304_800.0, 0.0, -49.5 - 3.0 * f64::from(zone), 0.9999],
            )
        }
        3794 => transverse_mercator(
            "Slovenia_1996_Slovene_National_Grid".into(),
            SLOVENIA_1996,
            [500_000.0, -5_000_000.0, 15.0, 0.9999],
        ),
        2154 => Some(Projected {
            name: "RGF_1993_Lambert_93".into(),
            geographic: RGF93,
            projection: "Lambert_Conformal_Conic",
            parameters: vec![
                ("False_Easting", 700_000.0),
                ("False_Northing", 6_600_000.0),
                ("Central_Meridian", 3.0),
                ("Standard_Parallel_1", 49.0),
                ("Standard_Parallel_2", 44.0),
                ("Latitude_Of_Origin", 46.5),
            ],
            unit: METRE,
        }),
        2992 => Some(Projected {
            name: "NAD_1983_Oregon_Statewide_Lambert_Feet_Intl".into(),
            geographic: NAD83,
            projection: "Lambert_Conformal_Conic",
            parameters: vec![
                ("False_Easting", 1_312_335.958),
                ("False_Northing", 0.0),
                ("Central_Meridian", -120.5),
                ("Standard_Parallel_1", 43.0),
                ("Standard_Parallel_2", 45.5),
                ("Latitude_Of_Origin", 41.75),
            ],
            unit: ("foot", 0.3048),
        }),
        28992 => Some(Projected {
            name: "RD_New".into(),
            geographic: AMERSFOORT,
            projection: "Double_Stereographic",
            parameters: vec![
                ("False_Easting", 155_000.0),
                ("False_Northing", 463_000.0),
                ("Central_Meridian", 5.38763888888889),
                ("Scale_Factor", 0.9999079),
                ("Latitude_Of_Origin", 52.1561605555556),
            ],
            unit: METRE,
        }),
        3857 => Some(Projected {
            name: "WGS_1984_Web_Mercator_Auxiliary_Sphere".into(),
            geographic: WGS84,
            projection: "Mercator_Auxiliary_Sphere",
            parameters: vec![
                ("False_Easting", 0.0),
                ("False_Northing", 0.0),
                ("Central_Meridian", 0.0),
                ("Standard_Parallel_1", 0.0),
                ("Auxiliary_Sphere_Type", 0.0),
            ],
            unit: METRE,
        }),
        _ => CSRS_UTM
            .iter()
            .find(|(c, _)| *c == code)
            .and_then(|&(_, zone)| utm("NAD_1983_CSRS_UTM_Zone", NAD83_CSRS, zone, false, true)),
    }
}

/// Compound codes: the horizontal and the vertical code.
const COMPOUND: [(u32, u32, u32); 1] = [(7415, 28992, 5709)];

/// ESRI's vertical CRS for a code.
fn vertical(code: u32) -> Option<&'static str> {
    match code {
        5709 => Some(
            "VERTCS[\"NAP\",VDATUM[\"Normaal_Amsterdams_Peil\"],PARAMETER[\"Vertical_Shift\",0.0],\
             PARAMETER[\"Direction\",1.0],UNIT[\"Meter\",1.0]]",
        ),
        5703 => Some(
            "VERTCS[\"NAVD_1988\",VDATUM[\"North_American_Vertical_Datum_1988\"],\
             PARAMETER[\"Vertical_Shift\",0.0],PARAMETER[\"Direction\",1.0],UNIT[\"Meter\",1.0]]",
        ),
        _ => None,
    }
}

/// A number as GDAL's ESRI WKT writes it: the shortest text that reads back, with `.0` on
/// whole numbers.
fn num(v: f64) -> String {
    format!("{v:?}")
}

fn geogcs(code: u32) -> Option<String> {
    let g = GEOGRAPHIC.iter().find(|g| g.code == code)?;
    Some(format!(
        "GEOGCS[\"{}\",DATUM[\"{}\",SPHEROID[\"{}\",{},{}]],PRIMEM[\"Greenwich\",0.0],\
         UNIT[\"Degree\",0.0174532925199433]]",
        g.gcs,
        g.datum,
        g.spheroid,
        num(g.a),
        num(g.rf)
    ))
}

/// ESRI's WKT1 for the horizontal code `h` (projected, geographic or one of the compounds it
/// knows), with the vertical code `v` appended as a `VERTCS` when it knows that one (else the
/// horizontal part alone). `None` for a code it cannot spell.
pub(super) fn wkt(h: u32, v: Option<u32>) -> Option<String> {
    if let Some(&(_, h, v)) = COMPOUND.iter().find(|c| c.0 == h) {
        return wkt(h, Some(v));
    }
    let mut s = match projected(h) {
        Some(p) => {
            let mut s = format!(
                "PROJCS[\"{}\",{},PROJECTION[\"{}\"]",
                p.name,
                geogcs(p.geographic)?,
                p.projection
            );
            for (name, value) in &p.parameters {
                s.push_str(&format!(",PARAMETER[\"{name}\",{}]", num(*value)));
            }
            s.push_str(&format!(",UNIT[\"{}\",{}]]", p.unit.0, num(p.unit.1)));
            s
        }
        None => geogcs(h)?,
    };
    if let Some(vs) = v.and_then(vertical) {
        s.push(',');
        s.push_str(vs);
    }
    Some(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spells_what_gdal_writes() {
        // `gdalsrsinfo -o wkt_esri --single-line EPSG:26915` (GDAL 3.6).
        assert_eq!(
            wkt(26915, None).unwrap(),
            "PROJCS[\"NAD_1983_UTM_Zone_15N\",GEOGCS[\"GCS_North_American_1983\",\
             DATUM[\"D_North_American_1983\",SPHEROID[\"GRS_1980\",6378137.0,298.257222101]],\
             PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]],\
             PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"False_Easting\",500000.0],\
             PARAMETER[\"False_Northing\",0.0],PARAMETER[\"Central_Meridian\",-93.0],\
             PARAMETER[\"Scale_Factor\",0.9996],PARAMETER[\"Latitude_Of_Origin\",0.0],\
             UNIT[\"Meter\",1.0]]"
        );
        assert_eq!(wkt(7415, None), wkt(28992, Some(5709)));
        assert!(wkt(7415, None).unwrap().contains("]],VERTCS[\"NAP\""));
        assert!(
            wkt(2992, Some(1))
                .unwrap()
                .ends_with("UNIT[\"foot\",0.3048]]")
        );
        assert_eq!(wkt(2056, None), None);
        // Every family (`tests/products_gdal.rs` compares these with GDAL's text).
        for c in [
            32601, 32760, 26923, 6328, 6348, 25838, 28348, 7859, 2945, 2952, 3761, 3857,
        ] {
            assert!(wkt(c, None).is_some(), "{c}");
        }
    }
}
