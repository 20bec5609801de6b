//! GeoPackage and OGR-SQLite / SpatiaLite layers, through `rusqlite` (SQLite built in).

use super::wkb::{Sink, gpkg_wkb, read_spatialite, read_wkb};
use super::{epsg_of_wkt, format};
use crate::error::{Error, Result};
use crate::input::geojson::GeoJson;
use rusqlite::{Connection, OpenFlags, OptionalExtension};
use std::io::Read;
use std::path::Path;

/// A geometry layer: its table, geometry column, blob kind and CRS.
struct Layer {
    table: String,
    column: String,
    kind: Blob,
    crs: Option<String>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Blob {
    Gpkg,
    Wkb,
    SpatiaLite,
}

fn sql_error(path: &Path, e: rusqlite::Error) -> Error {
    format(path, format!("cannot read the SQLite database: {e}"))
}

fn quote(name: &str) -> String {
    format!("\"{}\"", name.replace('"', "\"\""))
}

fn has_table(db: &Connection, name: &str) -> rusqlite::Result<bool> {
    db.query_row(
        "SELECT count(*) FROM sqlite_master WHERE type IN ('table', 'view') AND name = ?1",
        [name],
        |r| r.get::<_, i64>(0),
    )
    .map(|n| n > 0)
}

/// The geometry layers of the database.
fn layers(db: &Connection, path: &Path) -> Result<Vec<Layer>> {
    let e = |err| sql_error(path, err);
    let mut out = Vec::new();
    if has_table(db, "gpkg_geometry_columns").map_err(e)? {
        let mut q = db
            .prepare(
                "SELECT g.table_name, g.column_name, s.organization, s.organization_coordsys_id \
                 FROM gpkg_geometry_columns g LEFT JOIN gpkg_spatial_ref_sys s \
                 ON s.srs_id = g.srs_id ORDER BY g.table_name",
            )
            .map_err(e)?;
        let rows = q
            .query_map([], |r| {
                Ok((
                    r.get::<_, String>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, Option<String>>(2)?,
                    r.get::<_, Option<i64>>(3)?,
                ))
            })
            .map_err(e)?;
        for row in rows {
            let (table, column, org, code) = row.map_err(e)?;
            let crs = match (org, code) {
                (Some(o), Some(c)) if o.eq_ignore_ascii_case("EPSG") => Some(format!("EPSG:{c}")),
                _ => None,
            };
            out.push(Layer {
                table,
                column,
                kind: Blob::Gpkg,
                crs,
            });
        }
        return Ok(out);
    }
    if !has_table(db, "geometry_columns").map_err(e)? {
        return Err(format(
            path,
            "a SQLite database without geometry layers (neither gpkg_geometry_columns nor \
             geometry_columns)",
        ));
    }
    // Column names differ between OGR's and SpatiaLite's metadata: read them by name.
    let mut q = db.prepare("SELECT * FROM geometry_columns").map_err(e)?;
    let names: Vec<String> = q.column_names().map(|s| s.to_string()).collect();
    let col = |n: &str| names.iter().position(|c| c.eq_ignore_ascii_case(n));
    let (Some(t), Some(g)) = (col("f_table_name"), col("f_geometry_column")) else {
        return Err(format(
            path,
            "geometry_columns has no f_table_name / f_geometry_column",
        ));
    };
    let (srid, fmt) = (col("srid"), col("geometry_format"));
    let rows = q
        .query_map([], |r| {
            Ok((
                r.get::<_, String>(t)?,
                r.get::<_, String>(g)?,
                srid.map(|k| r.get::<_, Option<i64>>(k))
                    .transpose()?
                    .flatten(),
                fmt.map(|k| r.get::<_, Option<String>>(k))
                    .transpose()?
                    .flatten(),
            ))
        })
        .map_err(e)?;
    let mut found = Vec::new();
    for row in rows {
        found.push(row.map_err(e)?);
    }
    for (table, column, srid, fmt) in found {
        let kind = match fmt.as_deref().map(str::to_ascii_uppercase).as_deref() {
            Some("WKB") => Blob::Wkb,
            Some(other) if other != "SPATIALITE" => {
                return Err(format(
                    path,
                    format!(
                        "layer {table}: geometry format {other} is not supported (WKB or SpatiaLite)"
                    ),
                ));
            }
            _ => Blob::SpatiaLite,
        };
        let crs = match srid {
            Some(s) if has_table(db, "spatial_ref_sys").map_err(e)? => db
                .query_row(
                    "SELECT auth_name, auth_srid, srtext FROM spatial_ref_sys WHERE srid = ?1",
                    [s],
                    |r| {
                        Ok((
                            r.get::<_, Option<String>>(0)?,
                            r.get::<_, Option<rusqlite::types::Value>>(1)?,
                            r.get::<_, Option<String>>(2).unwrap_or(None),
                        ))
                    },
                )
                .optional()
                .map_err(e)?
                .and_then(|(auth, code, wkt)| {
                    let code = match code {
                        Some(rusqlite::types::Value::Integer(i)) => Some(i.to_string()),
                        Some(rusqlite::types::Value::Text(t)) => Some(t),
                        _ => None,
                    };
                    match (auth, code) {
                        (Some(a), Some(c)) if a.eq_ignore_ascii_case("EPSG") => {
                            Some(format!("EPSG:{c}"))
                        }
                        _ => wkt.and_then(|w| epsg_of_wkt(w.as_bytes())),
                    }
                }),
            _ => None,
        };
        out.push(Layer {
            table,
            column,
            kind,
            crs,
        });
    }
    Ok(out)
}

/// The database `path`, opened read-only: the file itself, or a copy in memory of `bytes`, its
/// content.
fn open(path: &Path, bytes: Option<&[u8]>) -> Result<Connection> {
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let Some(bytes) = bytes else {
        return Connection::open_with_flags(path, flags).map_err(|e| sql_error(path, e));
    };
    let mut db = Connection::open_in_memory().map_err(|e| sql_error(path, e))?;
    // Bytes 18 and 19 of the header are 2 for a database in WAL mode, which SQLite does not
    // open in memory; 1 (rollback journal) reads the same pages.
    let (head, rest) = bytes.split_at(bytes.len().min(18));
    let (version, tail) = rest.split_at(rest.len().min(2));
    let version: &[u8] = if version == [2, 2] { &[1, 1] } else { version };
    db.deserialize_read_exact(
        rusqlite::MAIN_DB,
        head.chain(version).chain(tail),
        bytes.len(),
        true,
    )
    .map_err(|e| sql_error(path, e))?;
    Ok(db)
}

/// Reads layer `layer` (or the only one) of the GeoPackage or OGR-SQLite database `path`: the
/// file, or `bytes`, its content.
pub(super) fn read(path: &Path, bytes: Option<&[u8]>, layer: Option<&str>) -> Result<GeoJson> {
    let db = open(path, bytes)?;
    let all = layers(&db, path)?;
    let names = || {
        all.iter()
            .map(|l| l.table.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let chosen = match layer {
        Some(name) => all.iter().find(|l| l.table == name).ok_or_else(|| {
            format(
                path,
                format!("has no geometry layer \"{name}\" (its layers: {})", names()),
            )
        })?,
        None if all.len() == 1 => &all[0],
        None if all.is_empty() => return Err(format(path, "has no geometry layer")),
        None => {
            return Err(format(
                path,
                format!(
                    "has {} geometry layers ({}): name one as {}:LAYER",
                    all.len(),
                    names(),
                    path.display()
                ),
            ));
        }
    };
    let mut out = GeoJson {
        crs: chosen.crs.clone(),
        ..GeoJson::default()
    };
    let sql = format!(
        "SELECT {} FROM {} ORDER BY rowid",
        quote(&chosen.column),
        quote(&chosen.table)
    );
    let mut q = db.prepare(&sql).map_err(|e| sql_error(path, e))?;
    let mut rows = q.query([]).map_err(|e| sql_error(path, e))?;
    let mut feature = 0u64;
    let mut polygons = 0u32;
    while let Some(row) = rows.next().map_err(|e| sql_error(path, e))? {
        let blob: Option<Vec<u8>> = row.get(0).map_err(|e| sql_error(path, e))?;
        if let Some(blob) = blob {
            let mut sink = Sink {
                out: &mut out,
                path,
                feature,
                part: 0,
                polygons,
            };
            match chosen.kind {
                Blob::Gpkg => {
                    if let Some(wkb) = gpkg_wkb(&blob, &sink)? {
                        read_wkb(wkb, &mut sink)?;
                    }
                }
                Blob::Wkb => read_wkb(&blob, &mut sink)?,
                Blob::SpatiaLite => read_spatialite(&blob, &mut sink)?,
            }
            polygons = sink.polygons;
        }
        feature += 1;
    }
    Ok(out)
}
