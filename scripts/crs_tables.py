#!/usr/bin/env python3
"""Writes src/crs/codes.rs: which EPSG codes are geographic, and which projected CRSs count in
feet or US survey feet, as sorted inclusive ranges, from PROJ's proj.db (the EPSG dataset).

    python3 scripts/crs_tables.py [/usr/share/proj/proj.db] > src/crs/codes.rs
"""
import sqlite3
import sys

db = sqlite3.connect(sys.argv[1] if len(sys.argv) > 1 else "/usr/share/proj/proj.db")
meta = dict(db.execute("select key, value from metadata"))


def runs(codes):
    out = []
    for x in sorted(set(codes)):
        if out and out[-1][1] == x - 1:
            out[-1][1] = x
        else:
            out.append([x, x])
    return out


def table(name, doc, codes):
    r = runs(codes)
    print(f"/// {doc}")
    print("#[rustfmt::skip]")
    print(f"pub(super) const {name}: [(u32, u32); {len(r)}] = [")
    line = "   "
    for a, b in r:
        item = f" ({a}, {b}),"
        if len(line) + len(item) > 99:
            print(line)
            line = "   "
        line += item
    print(line)
    print("];")
    print()


geographic = [
    int(c)
    for (c,) in db.execute(
        "select code from geodetic_crs where auth_name = 'EPSG' "
        "and type in ('geographic 2D', 'geographic 3D')"
    )
]
unit = """select cast(p.code as integer) from projected_crs p join axis a
          on a.coordinate_system_auth_name = p.coordinate_system_auth_name
          and a.coordinate_system_code = p.coordinate_system_code and a.coordinate_system_order = 1
          where p.auth_name = 'EPSG' and a.uom_auth_name = 'EPSG' and a.uom_code = ?"""
print(
    f"""//! EPSG codes by kind and unit, from the EPSG dataset {meta['EPSG.VERSION']} \
({meta['EPSG.DATE']}) in PROJ {meta['PROJ.VERSION']}'s
//! proj.db, deprecated codes included (old files carry them). Written by
//! `scripts/crs_tables.py`; do not edit.
"""
)
table("GEOGRAPHIC", "Geographic 2-D and 3-D CRSs (coordinates in degrees).", geographic)
table("FOOT", "Projected CRSs whose easting is in international feet (EPSG unit 9002).",
      [c for (c,) in db.execute(unit, (9002,))])
table("US_SURVEY_FOOT", "Projected CRSs whose easting is in US survey feet (EPSG unit 9003).",
      [c for (c,) in db.execute(unit, (9003,))])
