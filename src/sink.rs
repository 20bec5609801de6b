//! Where final triangles go: push-style sinks. [`MeshSink`] takes numbered vertices and triangles
//! (the mesh writers in [`crate::output`]); [`TriangleSink`] takes triangles with their
//! coordinates (the terrain products in [`crate::products`]); [`Fanout`] feeds several triangle
//! sinks from one pass.
//!
//! # Summaries
//!
//! What a finished sink reports is typed: [`MeshSummary`] for a mesh writer, a
//! [`ProductSummary`] for a triangle sink, one variant per product. The summaries are defined
//! here, next to the traits that return them, rather than in the product modules that fill them
//! in: [`TriangleSink::finish`] returns the closed enum, and this module sits below the products
//! in the layers (they import it, never the reverse), so the enum and its variants live here.
//! They serialise to the products' part of the `--json` summaries.

use crate::crs::Crs;
use crate::error::Result;
use crate::validate::MeshKind;
use serde::{Serialize, Serializer};
use std::path::PathBuf;
use std::sync::Arc;

/// A streaming mesh writer.
///
/// Vertices are numbered 0, 1, 2, … in the order they are pushed; a triangle refers only to
/// vertices already pushed. Vertex and triangle calls may interleave (streaming). Nothing appears
/// under the output path until [`finish`](MeshSink::finish) succeeds; dropping a sink without
/// finishing leaves no file behind.
pub trait MeshSink {
    /// Appends a vertex `[x, y, z]`.
    ///
    /// # Errors
    /// [`crate::Error::Output`] for a non-finite coordinate or after `finish`; [`crate::Error::Io`] if writing
    /// fails.
    fn vertex(&mut self, p: [f64; 3]) -> Result<()>;

    /// Appends a triangle of vertex numbers (counter-clockwise in `x, y` by convention).
    ///
    /// # Errors
    /// [`crate::Error::Output`] if a vertex number has not been pushed yet, exceeds what the format can
    /// store, or after `finish`; [`crate::Error::Io`] if writing fails.
    fn triangle(&mut self, t: [u64; 3]) -> Result<()>;

    /// What the mesh is ([`MeshKind`]), declared by its producer before the first vertex;
    /// several declarations add up ([`MeshKind::union`]). The PLY and `.stin` writers record
    /// it; others ignore it.
    ///
    /// # Errors
    /// [`crate::Error::Internal`] from a writer that has already begun writing records (`.stin`).
    fn declare(&mut self, _kind: MeshKind) -> Result<()> {
        Ok(())
    }

    /// No later triangle refers to vertex `id`. Only the streaming-mesh format records this; other
    /// writers ignore it.
    ///
    /// # Errors
    /// As [`MeshSink::triangle`].
    fn vertex_done(&mut self, _id: u64) -> Result<()> {
        Ok(())
    }

    /// Later triangles normally lie at `y >= y` (see [`TriangleSink`]). Only the
    /// streaming-mesh format records this; other writers ignore it.
    ///
    /// # Errors
    /// As [`MeshSink::triangle`].
    fn watermark(&mut self, _y: f64) -> Result<()> {
        Ok(())
    }

    /// Does this format keep the watermarks (so that whoever reads it back relies on them, and
    /// the sweep must run along y)? Only the streaming-mesh format does.
    fn keeps_watermarks(&self) -> bool {
        false
    }

    /// Does this writer take a tiled run's tiles whole ([`MeshSink::piece`]) instead of numbered
    /// vertices? Only the pieces file of a plan's `tin` task does
    /// ([`crate::output::pieces::PieceWriter`]).
    fn takes_pieces(&self) -> bool {
        false
    }

    /// One tile of a tiled run, whole: its owned triangles (indices into `vertices`), and for
    /// each vertex its number of triangles in the whole mesh when the tile owns it, `u32::MAX`
    /// otherwise. Called instead of the other methods when [`MeshSink::takes_pieces`].
    ///
    /// # Errors
    /// [`crate::Error::Output`] from a writer that takes numbered vertices; as
    /// [`MeshSink::triangle`].
    fn piece(
        &mut self,
        _tile: (i64, i64),
        _vertices: &[[f64; 3]],
        _degree: &[u32],
        _triangles: &[[u32; 3]],
    ) -> Result<()> {
        Err(crate::Error::Internal(
            "this mesh writer takes numbered vertices, not pieces".into(),
        ))
    }

    /// Writes everything out and renames into place; reports errors instead of hiding them in Drop.
    ///
    /// # Errors
    /// [`crate::Error::Io`] naming the output if writing, syncing or renaming fails; [`crate::Error::Output`] if
    /// called twice.
    fn finish(&mut self) -> Result<MeshSummary>;
}

/// A mesh kept in memory: the vertex table and triangles of 32-bit vertex numbers, for a step
/// that needs the whole mesh (`sweeptin refine` of points) and for tests.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MemoryMesh {
    /// Vertices in the order written.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, as written.
    pub triangles: Vec<[u32; 3]>,
    /// What the producer declared.
    pub kind: MeshKind,
}

impl MeshSink for MemoryMesh {
    fn declare(&mut self, kind: MeshKind) -> Result<()> {
        self.kind = self.kind.union(kind);
        Ok(())
    }

    fn vertex(&mut self, p: [f64; 3]) -> Result<()> {
        push(&mut self.vertices, p, "a mesh's vertices in memory")
    }

    fn triangle(&mut self, t: [u64; 3]) -> Result<()> {
        let mut out = [0u32; 3];
        for (o, v) in out.iter_mut().zip(t) {
            *o = u32::try_from(v)
                .ok()
                .filter(|&v| (v as usize) < self.vertices.len())
                .ok_or_else(|| crate::Error::Output {
                    path: PathBuf::from("(memory)"),
                    message: format!("triangle vertex {v} not written (or over 32 bits)"),
                })?;
        }
        push(&mut self.triangles, out, "a mesh's triangles in memory")
    }

    fn finish(&mut self) -> Result<MeshSummary> {
        Ok(MeshSummary {
            vertices: self.vertices.len() as u64,
            triangles: self.triangles.len() as u64,
            bytes: 0,
        })
    }
}

/// Pushes `x`, growing `v` fallibly: a mesh held in memory fails with
/// [`crate::Error::OutOfMemory`] instead of aborting the process when it outgrows an
/// address-space limit.
fn push<T>(v: &mut Vec<T>, x: T, what: &str) -> Result<()> {
    if v.len() == v.capacity() {
        let more = v.len().max(1024);
        v.try_reserve(more).map_err(|_| crate::Error::OutOfMemory {
            what: what.to_string(),
            bytes: (more * std::mem::size_of::<T>()) as u64,
            hint: "the mesh is held in memory: raise the memory limit, or give a smaller \
                       area (--bbox)"
                .to_string(),
        })?;
    }
    v.push(x);
    Ok(())
}

/// What a finished [`MeshSink`] wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshSummary {
    /// Vertices written.
    pub vertices: u64,
    /// Triangles written.
    pub triangles: u64,
    /// Size of the output file in bytes.
    pub bytes: u64,
}

/// Facts about the data, given to every sink before the first triangle.
#[derive(Clone, Debug, Default)]
pub struct StreamInfo {
    /// Coordinate reference system of the input, when known.
    pub crs: Option<Crs>,
    /// Real-world extent of the points: `[xmin, ymin, xmax, ymax]`.
    pub bounds: [f64; 4],
}

/// Which triangles a [`TriangleSink`] needs ([`TriangleSink::needs`]).
#[derive(Clone, Debug)]
pub enum Needs {
    /// Every triangle.
    All,
    /// Only triangles one of these tests wants; a producer may leave the others out and count
    /// them ([`TriangleSink::skipped`]).
    Only(Vec<Arc<dyn Wants>>),
}

/// A test of [`Needs::Only`], implemented by the products (a DEM: triangles whose closed box
/// may hold one of its cell centres; contours: triangles that cross a level).
pub trait Wants: Send + Sync + std::fmt::Debug {
    /// Does the sink want triangle `t`? `false` only for triangles it would ignore.
    fn wants(&self, t: &[[f64; 3]; 3]) -> bool;

    /// Is the test one of *covering*: is there a fixed set of points such that the sink uses a
    /// triangle only for the points of the set it holds (closed), and the test wants every
    /// triangle that holds one, whatever else the triangle is? (A DEM's is: its cell centres.)
    /// Then any triangle of any triangulation that holds such a point is wanted, and the exact
    /// tiles need not certify the unwanted triangles deep inside a tile. `false` unless said.
    fn covering(&self) -> bool {
        false
    }

    /// `Some(g)` only when [`Wants::wants`] is exactly `g.may_hold_centre` (a DEM's test) and
    /// `g` has lattice keys: a producer may then decide it from per-vertex
    /// [`crate::raster::GridSpec::lattice_keys`]. `None` unless said.
    fn centres(&self) -> Option<&crate::raster::GridSpec> {
        None
    }
}

impl Needs {
    /// Does a sink with these needs want triangle `t`?
    #[inline]
    pub fn wants(&self, t: &[[f64; 3]; 3]) -> bool {
        match self {
            Needs::All => true,
            Needs::Only(tests) => tests.iter().any(|w| w.wants(t)),
        }
    }

    /// The one grid of cell centres these needs are, if they are one ([`Wants::centres`]).
    pub fn centres(&self) -> Option<&crate::raster::GridSpec> {
        match self {
            Needs::Only(tests) if tests.len() == 1 => tests[0].centres(),
            _ => None,
        }
    }

    /// Are these needs a filter whose every test is covering ([`Wants::covering`])?
    pub fn covering(&self) -> bool {
        match self {
            Needs::All => false,
            Needs::Only(tests) => tests.iter().all(|w| w.covering()),
        }
    }

    /// What sinks fed the same triangles need together (every triangle when there are none).
    pub fn together(needs: impl IntoIterator<Item = Needs>) -> Needs {
        let mut tests = Vec::new();
        for n in needs {
            match n {
                Needs::All => return Needs::All,
                Needs::Only(t) => tests.extend(t),
            }
        }
        if tests.is_empty() {
            Needs::All
        } else {
            Needs::Only(tests)
        }
    }
}

/// A consumer of final triangles (DEM, contours, volumes, …).
///
/// Triangles arrive roughly in increasing `y`, in real-world coordinates `[x, y, z]`,
/// counter-clockwise in (x, y). [`TriangleSink::watermark`] is a *hint*: later triangles normally lie
/// entirely at `y >= watermark`, so a sink may flush what lies below; but a few triangles can still
/// arrive *late* (long thin triangles along the convex hull, whose circumcircles are too large to
/// finalise early), and every sink must handle a late triangle correctly.
pub trait TriangleSink: Send {
    /// Called once before the first triangle.
    fn begin(&mut self, info: &StreamInfo) -> Result<()>;
    /// One final triangle.
    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()>;
    /// Progress hint (see the trait docs).
    fn watermark(&mut self, _y: f64) -> Result<()> {
        Ok(())
    }
    /// The cell size of the grid this sink fills, if any: a tiled run makes its tiles whole
    /// multiples of it, so that every cell has one owner tile.
    fn grid_cell(&self) -> Option<f64> {
        None
    }
    /// The memory this sink may hold at most (a DEM's rows in memory: its share of `--mem`), so
    /// that a tiled run keeps its tiles in flight within what is left of the budget.
    fn memory_share(&self) -> u64 {
        0
    }
    /// In a task of a plan: a triangle that meets the task's tile but belongs to another task.
    /// A grid needs it for its own cells; every other product ignores it (the default), since the
    /// other task counts it.
    fn boundary_triangle(&mut self, _t: &[[f64; 3]; 3]) -> Result<()> {
        Ok(())
    }
    /// Does this sink take [`TriangleSink::boundary_triangle`]s (a grid)? A task whose sinks
    /// take none runs only the tiles of its plan tile that hold points (or line vertices): the
    /// empty ones would only find triangles of other tasks, and their number grows with the
    /// tile's area, not its points.
    fn wants_boundary(&self) -> bool {
        false
    }
    /// Which triangles this sink needs, asked after [`TriangleSink::begin`]: a producer may
    /// leave out the others (a tiled run filters them in its workers), and tells the sink how
    /// many in [`TriangleSink::skipped`], which a sink that counts triangles must then implement.
    /// Default: every one.
    fn needs(&self) -> Needs {
        Needs::All
    }
    /// `n` triangles were left out because [`TriangleSink::needs`] did not want them (they
    /// still count as triangles of the stream).
    fn skipped(&mut self, _n: u64) {}
    /// Called once after the last triangle; returns what the sink did.
    fn finish(&mut self) -> Result<ProductSummary>;
}

/// What a finished [`TriangleSink`] reports. Serialises as the inner summary (`null` for
/// [`ProductSummary::None`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ProductSummary {
    /// A sink with nothing to report.
    None,
    /// A DEM raster.
    Dem(DemSummary),
    /// Contour lines.
    Contours(ContourSummary),
    /// Cut and fill volumes, against a plane or a second surface.
    Volume(VolumeSummary),
    /// Heights at query points.
    Sample(SampleSummary),
    /// Sections along polylines.
    Profile(ProfileSummary),
    /// The reference surface of an overlay volume, filed into bands.
    SurfaceStore(SurfaceStoreSummary),
    /// Several sinks fed by one [`Fanout`].
    Fanout(FanoutSummary),
}

/// What a DEM sink wrote.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DemSummary {
    /// The raster file.
    pub path: PathBuf,
    /// Columns.
    pub cols: u32,
    /// Rows.
    pub rows: u32,
    /// Cell size.
    pub cell: f64,
    /// Upper-left outer corner of the raster.
    pub origin: [f64; 2],
    /// Extent of the cells' areas: `[xmin, ymin, xmax, ymax]`.
    pub extent: [f64; 4],
    /// Value of cells without data.
    pub nodata: f32,
    /// The CRS recorded in the file, when known.
    pub crs: Option<String>,
    /// What the raster lost of the CRS: none known, or (an ESRI ASCII grid) no `.prj`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lost_crs: Option<crate::crs::LostCrs>,
    /// Cells with a value.
    pub cells_with_data: u64,
    /// Cells written after their row had gone to the file (late triangles).
    pub late_cell_writes: u64,
    /// Largest number of rows held in memory at once.
    pub max_rows_in_memory: u64,
    /// Triangles received.
    pub triangles: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// What a contour sink wrote.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ContourSummary {
    /// The GeoJSON or GeoPackage file.
    pub path: PathBuf,
    /// Distance between levels.
    pub interval: f64,
    /// The level through which the others are counted.
    pub base: f64,
    /// Features written (one polyline each).
    pub features: u64,
    /// Level segments found in triangles.
    pub segments: u64,
    /// Closed rings among the features.
    pub rings: u64,
    /// Open lines (ending on the TIN's boundary).
    pub open_lines: u64,
    /// Degenerate pieces dropped.
    pub degenerate_dropped: u64,
    /// Lines (rings included) left out as shorter than `min_length`.
    pub short_dropped: u64,
    /// The shortest line written, in map units (0: every line).
    pub min_length: f64,
    /// Decimals of the written coordinates (`None`: every bit).
    pub decimals: Option<u32>,
    /// Points of open polylines moved to the scratch file.
    pub points_spilled: u64,
    /// Largest number of open polylines at once.
    pub max_open_polylines: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// Totals of a cut and fill computation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct CutFillTotals {
    /// Volume where the surface is above the reference.
    pub cut_volume: f64,
    /// Volume where the surface is below the reference.
    pub fill_volume: f64,
    /// `cut_volume − fill_volume`.
    pub net_volume: f64,
    /// Area where the surface is above the reference.
    pub cut_area: f64,
    /// Area where the surface is below the reference.
    pub fill_area: f64,
    /// Area covered (cut + fill + where they are equal).
    pub area: f64,
}

/// What a volume sink computed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VolumeSummary {
    /// Cut, fill, net and areas.
    #[serde(flatten)]
    pub totals: CutFillTotals,
    /// The exact sums behind `totals` (cut, fill, cut area, fill area, area) as partials, for
    /// adding up the volumes of a plan's tasks exactly; not in the JSON summary.
    #[serde(skip)]
    pub partials: Option<[Vec<f64>; 5]>,
    /// What the surface was compared with.
    pub reference: VolumeReference,
    /// Area of the boundary polygon, when one was given.
    pub boundary_area: Option<f64>,
    /// Triangles received.
    pub triangles: u64,
    /// How the second surface was read back (against a surface only).
    #[serde(flatten)]
    pub overlay: Option<OverlayStats>,
}

/// The reference of a [`VolumeSummary`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum VolumeReference {
    /// The horizontal plane `z = plane`.
    #[serde(rename = "plane")]
    Plane(f64),
    /// A second surface of this many triangles.
    #[serde(rename = "surface_triangles")]
    Surface(u64),
}

/// The work of a volume against a second surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct OverlayStats {
    /// Pairs of overlapping triangles (surface, reference) intersected.
    pub pairs: u64,
    /// Pieces of the reference (one band's triangles in one block of columns) read from the
    /// scratch file.
    pub loads: u64,
    /// Most bytes of the reference held in memory at once.
    pub max_loaded_bytes: u64,
}

/// What a sample sink wrote.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SampleSummary {
    /// The output file.
    pub path: PathBuf,
    /// Query points read.
    pub queries: u64,
    /// Queries inside the TIN (with a height).
    pub answered: u64,
    /// Queries outside the TIN.
    pub outside: u64,
    /// Were the queries sorted by y (bounded memory)?
    pub sorted_by_y: bool,
    /// Largest number of queries waiting at once.
    pub max_pending_queries: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// What a profile sink wrote.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ProfileSummary {
    /// The output file.
    pub path: PathBuf,
    /// Polylines.
    pub lines: u64,
    /// Points written (line vertices inside the TIN and edge crossings).
    pub points: u64,
    /// Line vertices inside the TIN.
    pub line_vertices_inside: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// What the band store of an overlay's reference surface holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct SurfaceStoreSummary {
    /// Triangles of the reference surface.
    pub reference_triangles: u64,
    /// Bands they are filed into.
    pub bands: u64,
}

/// The summaries of the sinks of a [`Fanout`], by name, in the order of the sinks. Serialises
/// as an object.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FanoutSummary(pub Vec<(String, ProductSummary)>);

impl FanoutSummary {
    /// The summary of the sink called `name`.
    pub fn get(&self, name: &str) -> Option<&ProductSummary> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, s)| s)
    }
}

impl Serialize for FanoutSummary {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(n, v)| (n, v)))
    }
}

/// Several triangle sinks fed by one pass: forwards the stream to every sink, after assigning a
/// CRS (when given).
///
/// [`TriangleSink::finish`] returns a [`ProductSummary::Fanout`] with each sink's summary under
/// its name; calling it again returns the same summary.
pub struct Fanout {
    sinks: Vec<(String, Box<dyn TriangleSink>)>,
    crs: Option<Crs>,
    summary: Option<FanoutSummary>,
}

impl Fanout {
    /// Forwards to `sinks` (name, sink).
    pub fn new(sinks: Vec<(String, Box<dyn TriangleSink>)>) -> Fanout {
        Fanout {
            sinks,
            crs: None,
            summary: None,
        }
    }

    /// The sinks are told that the data are in `crs`, whatever the input declares.
    pub fn with_crs(mut self, crs: Option<Crs>) -> Fanout {
        self.crs = crs;
        self
    }
}

impl TriangleSink for Fanout {
    fn begin(&mut self, info: &StreamInfo) -> Result<()> {
        let mut info = info.clone();
        if self.crs.is_some() {
            info.crs = self.crs.clone();
        }
        for (_, s) in &mut self.sinks {
            s.begin(&info)?;
        }
        Ok(())
    }

    fn triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        for (_, s) in &mut self.sinks {
            s.triangle(t)?;
        }
        Ok(())
    }

    fn watermark(&mut self, y: f64) -> Result<()> {
        for (_, s) in &mut self.sinks {
            s.watermark(y)?;
        }
        Ok(())
    }

    fn boundary_triangle(&mut self, t: &[[f64; 3]; 3]) -> Result<()> {
        for (_, s) in &mut self.sinks {
            s.boundary_triangle(t)?;
        }
        Ok(())
    }

    fn wants_boundary(&self) -> bool {
        self.sinks.iter().any(|(_, s)| s.wants_boundary())
    }

    fn grid_cell(&self) -> Option<f64> {
        self.sinks.iter().find_map(|(_, s)| s.grid_cell())
    }

    fn memory_share(&self) -> u64 {
        self.sinks.iter().map(|(_, s)| s.memory_share()).sum()
    }

    fn needs(&self) -> Needs {
        Needs::together(self.sinks.iter().map(|(_, s)| s.needs()))
    }

    fn skipped(&mut self, n: u64) {
        for (_, s) in &mut self.sinks {
            s.skipped(n);
        }
    }

    fn finish(&mut self) -> Result<ProductSummary> {
        if let Some(s) = &self.summary {
            return Ok(ProductSummary::Fanout(s.clone()));
        }
        let mut all = Vec::with_capacity(self.sinks.len());
        for (name, s) in &mut self.sinks {
            all.push((name.clone(), s.finish()?));
        }
        let summary = FanoutSummary(all);
        self.summary = Some(summary.clone());
        Ok(ProductSummary::Fanout(summary))
    }
}

#[cfg(test)]
mod tests {

    use super::*;
    use std::sync::{Arc, Mutex};

    /// Wants triangles with a vertex above a height.
    #[derive(Debug)]
    struct Above(f64);

    impl Wants for Above {
        fn wants(&self, t: &[[f64; 3]; 3]) -> bool {
            t.iter().any(|v| v[2] > self.0)
        }
    }

    #[test]
    fn needs_together_want_what_any_sink_wants() {
        let t = |z: f64| [[0.0, 0.0, z], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let only = |h: f64| Needs::Only(vec![Arc::new(Above(h))]);
        let both = Needs::together([only(5.0), only(10.0)]);
        assert!(!both.wants(&t(1.0)));
        assert!(both.wants(&t(6.0)), "the first sink wants it");
        assert!(!only(10.0).wants(&t(6.0)));
        assert!(matches!(
            Needs::together([only(5.0), Needs::All]),
            Needs::All
        ));
        assert!(matches!(Needs::together([]), Needs::All));
        assert!(Needs::All.wants(&t(1.0)));
    }

    /// What a probe was given: CRS, triangles, watermarks.
    type Seen = Arc<Mutex<(Option<String>, u64, u64)>>;

    /// Records what it is given.
    #[derive(Default)]
    struct Probe(Seen);

    impl TriangleSink for Probe {
        fn begin(&mut self, info: &StreamInfo) -> Result<()> {
            self.0.lock().unwrap().0 = info.crs.as_ref().and_then(Crs::definition);
            Ok(())
        }
        fn triangle(&mut self, _t: &[[f64; 3]; 3]) -> Result<()> {
            self.0.lock().unwrap().1 += 1;
            Ok(())
        }
        fn watermark(&mut self, _y: f64) -> Result<()> {
            self.0.lock().unwrap().2 += 1;
            Ok(())
        }
        fn finish(&mut self) -> Result<ProductSummary> {
            Ok(ProductSummary::None)
        }
    }

    #[test]
    fn fanout_assigns_crs_forwards_and_finishes_once() {
        let crs = Crs {
            epsg: Some(3794),
            ..Crs::default()
        };
        let (a, b) = (Probe::default(), Probe::default());
        let (seen_a, seen_b) = (a.0.clone(), b.0.clone());
        let mut f = Fanout::new(vec![("a".into(), Box::new(a)), ("b".into(), Box::new(b))])
            .with_crs(Some(crs));
        f.begin(&StreamInfo::default()).unwrap();
        f.triangle(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            .unwrap();
        f.watermark(1.0).unwrap();
        let s = f.finish().unwrap();
        assert_eq!(
            *seen_a.lock().unwrap(),
            (Some("EPSG:3794".to_string()), 1, 1)
        );
        assert_eq!(seen_b.lock().unwrap().1, 1);
        let ProductSummary::Fanout(all) = &s else {
            panic!("{s:?}")
        };
        assert_eq!(all.get("a"), Some(&ProductSummary::None));
        assert_eq!(serde_json::to_string(&s).unwrap(), r#"{"a":null,"b":null}"#);
        assert_eq!(f.finish().unwrap(), s);
    }
}
