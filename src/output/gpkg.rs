//! GeoPackage output (OGC GeoPackage 1.3): a features table of `LINESTRING`s with an `elevation`
//! and a `closed` column, written through SQLite (`rusqlite`, SQLite built in).
//!
//! The file has what a reader needs and no more: `application_id` `GPKG` and `user_version`
//! 10300, the `gpkg_spatial_ref_sys` table with the three rows the standard requires (4326, −1
//! and 0) and the layer's CRS (its EPSG code and WKT when known), `gpkg_contents` with the
//! layer's extent, and `gpkg_geometry_columns`. Geometries are GeoPackage binary: the `GP`
//! header (version 0, little-endian, an `xy` envelope) and little-endian WKB. No spatial index
//! is written (`ogr2ogr` adds one).
//!
//! Like every output, the database is written under a temporary name beside the final path and
//! moved into place only when complete ([`AtomicFile`]); a line's blob is written in place
//! (SQLite's incremental blob I/O), so memory does not grow with a line's length.

use super::atomic::AtomicFile;
use crate::crs::{Crs, HorizontalKind};
use crate::error::{Error, Result};
use rusqlite::{Connection, params};
use std::path::{Path, PathBuf};

/// `application_id` of a GeoPackage: `GPKG` in ASCII.
const APPLICATION_ID: i32 = 0x4750_4B47;
/// `user_version` of GeoPackage 1.3.0.
const USER_VERSION: i32 = 10300;

/// The tables and rows every GeoPackage holds (OGC 12-128r18, clauses 1.1.2–1.1.4).
const SCHEMA: &str = "
CREATE TABLE gpkg_spatial_ref_sys (
  srs_name TEXT NOT NULL, srs_id INTEGER NOT NULL PRIMARY KEY,
  organization TEXT NOT NULL, organization_coordsys_id INTEGER NOT NULL,
  definition TEXT NOT NULL, description TEXT);
CREATE TABLE gpkg_contents (
  table_name TEXT NOT NULL PRIMARY KEY, data_type TEXT NOT NULL,
  identifier TEXT UNIQUE, description TEXT DEFAULT '',
  last_change DATETIME NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')),
  min_x DOUBLE, min_y DOUBLE, max_x DOUBLE, max_y DOUBLE,
  srs_id INTEGER, CONSTRAINT fk_gc_r_srs_id FOREIGN KEY (srs_id)
  REFERENCES gpkg_spatial_ref_sys(srs_id));
CREATE TABLE gpkg_geometry_columns (
  table_name TEXT NOT NULL, column_name TEXT NOT NULL,
  geometry_type_name TEXT NOT NULL, srs_id INTEGER NOT NULL,
  z TINYINT NOT NULL, m TINYINT NOT NULL,
  CONSTRAINT pk_geom_cols PRIMARY KEY (table_name, column_name),
  CONSTRAINT uk_gc_table_name UNIQUE (table_name),
  CONSTRAINT fk_gc_tn FOREIGN KEY (table_name) REFERENCES gpkg_contents(table_name),
  CONSTRAINT fk_gc_srs FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys (srs_id));
INSERT INTO gpkg_spatial_ref_sys VALUES
  ('WGS 84 geodetic', 4326, 'EPSG', 4326,
   'GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563,AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],PRIMEM[\"Greenwich\",0,AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],AXIS[\"Latitude\",NORTH],AXIS[\"Longitude\",EAST],AUTHORITY[\"EPSG\",\"4326\"]]',
   'longitude/latitude coordinates in decimal degrees on the WGS 84 spheroid'),
  ('Undefined cartesian SRS', -1, 'NONE', -1, 'undefined', 'undefined cartesian coordinate reference system'),
  ('Undefined geographic SRS', 0, 'NONE', 0, 'undefined', 'undefined geographic coordinate reference system');
";

/// The `srs_id` of the first CRS without an EPSG code (GDAL's choice too).
const CUSTOM_SRS_ID: i64 = 100_000;

/// The line being written: its row, the points it still expects, where its next bytes go.
#[derive(Clone, Copy, Debug)]
struct Line {
    row: i64,
    left: u64,
    offset: usize,
}

/// A GeoPackage layer of line strings written feature by feature.
pub struct GpkgWriter {
    file: Option<AtomicFile>,
    db: Option<Connection>,
    path: PathBuf,
    table: String,
    srs_id: i64,
    features: u64,
    extent: [f64; 4],
    /// The line being written.
    line: Option<Line>,
    buf: Vec<u8>,
}

impl std::fmt::Debug for GpkgWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpkgWriter")
            .field("path", &self.path)
            .field("table", &self.table)
            .field("features", &self.features)
            .finish()
    }
}

fn sql(path: &Path, e: rusqlite::Error) -> Error {
    Error::Output {
        path: path.to_path_buf(),
        message: format!("cannot write the GeoPackage: {e}"),
    }
}

/// The `gpkg_spatial_ref_sys` row of `crs`: `(srs_id, name, organization, code, definition)`,
/// or `None` when it is one of the rows every GeoPackage has (4326) or unknown (−1).
fn srs_row(crs: Option<&Crs>) -> (i64, Option<(String, String, i64, String)>) {
    let Some(crs) = crs else { return (-1, None) };
    let code = crs.horizontal_epsg();
    let definition = crs
        .wkt
        .clone()
        .map(|w| w.trim_end_matches('\0').to_string())
        .or_else(|| crs.prj())
        .unwrap_or_else(|| "undefined".into());
    let name = crs.name.clone();
    match code {
        Some((4326, HorizontalKind::Geographic)) => (4326, None),
        Some((c, _)) => (
            i64::from(c),
            Some((
                name.unwrap_or_else(|| format!("EPSG:{c}")),
                "EPSG".into(),
                i64::from(c),
                definition,
            )),
        ),
        None if definition != "undefined" => (
            CUSTOM_SRS_ID,
            Some((
                name.unwrap_or_else(|| "custom".into()),
                "NONE".into(),
                CUSTOM_SRS_ID,
                definition,
            )),
        ),
        None => (-1, None),
    }
}

impl GpkgWriter {
    /// Starts a GeoPackage at `path` with one layer `table` of line strings in `crs` (under a
    /// temporary name until [`GpkgWriter::finish`]).
    ///
    /// # Errors
    /// [`Error::Write`] naming `path`; [`Error::Options`] for a stream (a GeoPackage is a
    /// database: it needs a file).
    pub fn create(path: &Path, table: &str, crs: Option<&Crs>) -> Result<GpkgWriter> {
        let file = AtomicFile::create_seekable(path, "a GeoPackage")?;
        let temp = file
            .temp_path()
            .map(Path::to_path_buf)
            .ok_or_else(|| Error::Internal("a GeoPackage being written to a stream".into()))?;
        let e = |err| sql(path, err);
        let db = Connection::open(&temp).map_err(e)?;
        // No journal beside the temporary file, and no syncing: the file is synced and moved
        // into place whole when finished.
        db.execute_batch(&format!(
            "PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF; PRAGMA application_id = \
             {APPLICATION_ID}; PRAGMA user_version = {USER_VERSION}; BEGIN;"
        ))
        .map_err(e)?;
        db.execute_batch(SCHEMA).map_err(e)?;
        let (srs_id, row) = srs_row(crs);
        if let Some((name, org, code, def)) = row {
            db.execute(
                "INSERT INTO gpkg_spatial_ref_sys VALUES (?1, ?2, ?3, ?4, ?5, NULL)",
                params![name, srs_id, org, code, def],
            )
            .map_err(e)?;
        }
        let quoted = quote(table);
        db.execute_batch(&format!(
            "CREATE TABLE {quoted} (fid INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, \
             geom LINESTRING, elevation REAL, closed BOOLEAN);"
        ))
        .map_err(e)?;
        Ok(GpkgWriter {
            file: Some(file),
            db: Some(db),
            path: path.to_path_buf(),
            table: table.to_string(),
            srs_id,
            features: 0,
            extent: [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            line: None,
            buf: Vec::new(),
        })
    }

    fn db(&self) -> Result<&Connection> {
        self.db.as_ref().ok_or_else(|| Error::Output {
            path: self.path.clone(),
            message: "the GeoPackage writer got data after finish()".into(),
        })
    }

    /// Starts a line of `points` points within `bbox` (`[xmin, ymin, xmax, ymax]`), at
    /// `elevation`; give its points with [`GpkgWriter::point`] and close it with
    /// [`GpkgWriter::end_line`].
    ///
    /// # Errors
    /// [`Error::Output`] naming the output.
    pub fn start_line(
        &mut self,
        elevation: f64,
        closed: bool,
        points: u64,
        bbox: [f64; 4],
    ) -> Result<()> {
        let n = u32::try_from(points).map_err(|_| Error::Output {
            path: self.path.clone(),
            message: format!("a line of {points} points is more than WKB can hold"),
        })?;
        let size = 8 + 32 + 9 + 16 * u64::from(n);
        let path = self.path.clone();
        let e = |err| sql(&path, err);
        let db = self.db()?;
        db.execute(
            &format!(
                "INSERT INTO {} (geom, elevation, closed) VALUES (zeroblob(?1), ?2, ?3)",
                quote(&self.table)
            ),
            params![size as i64, elevation, closed],
        )
        .map_err(e)?;
        let row = db.last_insert_rowid();
        self.buf.clear();
        self.buf.extend_from_slice(b"GP");
        self.buf.push(0); // version 1
        self.buf.push(0b0000_0011); // little-endian, envelope [minx, maxx, miny, maxy]
        self.buf
            .extend_from_slice(&(self.srs_id as i32).to_le_bytes());
        for v in [bbox[0], bbox[2], bbox[1], bbox[3]] {
            self.buf.extend_from_slice(&v.to_le_bytes());
        }
        self.buf.push(1); // WKB little-endian
        self.buf.extend_from_slice(&2u32.to_le_bytes()); // LineString
        self.buf.extend_from_slice(&n.to_le_bytes());
        self.line = Some(Line {
            row,
            left: points,
            offset: 0,
        });
        self.extent = [
            self.extent[0].min(bbox[0]),
            self.extent[1].min(bbox[1]),
            self.extent[2].max(bbox[2]),
            self.extent[3].max(bbox[3]),
        ];
        Ok(())
    }

    /// One point of the current line.
    ///
    /// # Errors
    /// [`Error::Output`] naming the output.
    pub fn point(&mut self, [x, y]: [f64; 2]) -> Result<()> {
        match self.line.as_mut() {
            Some(l) if l.left > 0 => l.left -= 1,
            _ => {
                return Err(Error::Internal(
                    "a GeoPackage line given more points than it declared".into(),
                ));
            }
        }
        self.buf.extend_from_slice(&x.to_le_bytes());
        self.buf.extend_from_slice(&y.to_le_bytes());
        if self.buf.len() >= 1 << 16 {
            self.write_blob(false)?;
        }
        Ok(())
    }

    /// Writes the buffered bytes of the current line's blob; `last` when the line ends.
    fn write_blob(&mut self, last: bool) -> Result<()> {
        let Some(line) = self.line else {
            return Err(Error::Internal("a GeoPackage line ended twice".into()));
        };
        if last && line.left != 0 {
            return Err(Error::Internal(format!(
                "a GeoPackage line ended {} points short of what it declared",
                line.left
            )));
        }
        let path = self.path.clone();
        let e = |err| sql(&path, err);
        let db = self.db()?;
        let mut blob = db
            .blob_open(
                rusqlite::MAIN_DB,
                self.table.as_str(),
                "geom",
                line.row,
                false,
            )
            .map_err(e)?;
        blob.write_all_at(&self.buf, line.offset).map_err(e)?;
        blob.close().map_err(e)?;
        let offset = line.offset + self.buf.len();
        self.buf.clear();
        self.line = (!last).then_some(Line { offset, ..line });
        Ok(())
    }

    /// Ends the current line.
    ///
    /// # Errors
    /// [`Error::Output`] naming the output.
    pub fn end_line(&mut self) -> Result<()> {
        self.write_blob(true)?;
        self.features += 1;
        Ok(())
    }

    /// Features written so far.
    pub fn features(&self) -> u64 {
        self.features
    }

    /// Records the layer in `gpkg_contents` and `gpkg_geometry_columns`, closes the database
    /// and moves it into place; returns its size in bytes.
    ///
    /// # Errors
    /// [`Error::Output`] or [`Error::Write`] naming the output.
    pub fn finish(mut self) -> Result<u64> {
        if self.line.is_some() {
            return Err(Error::Internal(
                "a GeoPackage finished inside a line".into(),
            ));
        }
        let path = self.path.clone();
        let e = |err| sql(&path, err);
        let ext = self.extent;
        let extent: [Option<f64>; 4] = if ext[0] <= ext[2] {
            ext.map(Some)
        } else {
            [None; 4]
        };
        let db = self.db.take().ok_or_else(|| Error::Output {
            path: path.clone(),
            message: "the GeoPackage writer finished twice".into(),
        })?;
        db.execute(
            "INSERT INTO gpkg_contents (table_name, data_type, identifier, min_x, min_y, \
             max_x, max_y, srs_id) VALUES (?1, 'features', ?1, ?2, ?3, ?4, ?5, ?6)",
            params![
                self.table,
                extent[0],
                extent[1],
                extent[2],
                extent[3],
                self.srs_id
            ],
        )
        .map_err(e)?;
        db.execute(
            "INSERT INTO gpkg_geometry_columns VALUES (?1, 'geom', 'LINESTRING', ?2, 0, 0)",
            params![self.table, self.srs_id],
        )
        .map_err(e)?;
        db.execute_batch("COMMIT;").map_err(e)?;
        db.close().map_err(|(_, err)| e(err))?;
        let file = self
            .file
            .take()
            .ok_or_else(|| Error::Internal("no file".into()))?;
        file.commit()
    }
}

/// `name` as an SQL identifier.
fn quote(name: &str) -> String {
    format!("\"{}\"", name.replace('"', "\"\""))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_lines_that_read_back_with_their_crs() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.gpkg");
        let crs = Crs {
            epsg: Some(3794),
            ..Crs::default()
        };
        let mut w = GpkgWriter::create(&path, "contours", Some(&crs)).unwrap();
        w.start_line(1.5, false, 2, [0.0, 0.1, 2.0, 3.0]).unwrap();
        w.point([0.0, 0.1]).unwrap();
        w.point([2.0, 3.0]).unwrap();
        w.end_line().unwrap();
        assert!(!path.exists(), "nothing under the final name before finish");
        let bytes = w.finish().unwrap();
        assert_eq!(bytes, std::fs::metadata(&path).unwrap().len());
        let db = Connection::open(&path).unwrap();
        let app: i32 = db
            .query_row("PRAGMA application_id", [], |r| r.get(0))
            .unwrap();
        assert_eq!(app, APPLICATION_ID);
        let srs: i64 = db
            .query_row("SELECT srs_id FROM gpkg_geometry_columns", [], |r| r.get(0))
            .unwrap();
        assert_eq!(srs, 3794);
        let lines = crate::input::geojson::read_lines(&path).unwrap();
        assert_eq!(lines, vec![vec![[0.0, 0.1], [2.0, 3.0]]]);
    }
}
