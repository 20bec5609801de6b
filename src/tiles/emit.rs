//! The writer side of a tiled run: tiles' outputs in tile order into the sinks.
//!
//! Terrain products get each owned triangle with its coordinates, and a watermark when a row of
//! tiles is complete (later triangles are owned by higher rows, so they lie above it). Triangles
//! no product wants ([`crate::sink::Needs`]: a DEM's that hold no cell centre, about 24 in 25 at
//! 1 m cells on dense lidar; contours' that cross no level) were left out by the workers and are
//! only counted ([`crate::sink::TriangleSink::skipped`]). A mesh
//! writer gets numbered vertices: a vertex is numbered when a triangle first uses it, and its
//! entry is dropped (`vertex_done`) when all its triangles have been written; its degree comes
//! from the tile that owns it, whose run holds its whole star. Only vertices with some but not
//! all triangles written are held: a band along the tile edges. A vertex whose whole star is in
//! one tile (its owner's degree equals its uses there: most of them) never enters the map; it is
//! numbered and finished through the tile's own arrays, in the same order.

use super::worker::{NOT_OWNED, TileOutput};
use crate::breaklines::Trim;
use crate::error::{Error, Result};
use crate::idmap::{FastMap, FastSet};
use crate::sink::{MeshSink, TriangleSink};

/// State of a vertex some triangle has used or will use.
#[derive(Debug, Clone, Copy)]
struct Live {
    /// Number in the mesh, once written.
    id: Option<u64>,
    /// Triangles written that use it.
    seen: u32,
    /// Its triangles in the whole triangulation, once its owner tile said.
    degree: u32,
}

/// Feeds tiles to the sinks.
pub(crate) struct TileWriter<'m, 'a, 'b> {
    mesh: Option<&'m mut (dyn MeshSink + Send)>,
    sinks: &'a mut [&'b mut dyn TriangleSink],
    /// `--max-edge`: triangles it drops still count for their vertices, but are not written.
    trim: Option<Trim>,
    live: FastMap<(u64, u64), Live>,
    /// A task's boundary triangles already given (they can meet two of its tiles).
    boundary: FastSet<[(u64, u64); 3]>,
    next_id: u64,
    /// Triangles and vertices written, triangles trimmed.
    pub triangles: u64,
    pub trimmed: u64,
    pub vertices: u64,
    /// Largest number of live vertex entries.
    pub peak_live: usize,
    /// Per vertex of the current tile: triangles left to write when the whole star is in the
    /// tile, else [`NOT_LOCAL`]; and its number once written.
    local_left: Vec<u32>,
    local_id: Vec<u64>,
    /// Has the mesh been told what the trimming makes of it ([`MeshSink::declare`])?
    declared: bool,
}

/// A vertex of the tile with triangles in other tiles too (it goes through the map).
const NOT_LOCAL: u32 = u32::MAX;
/// A local vertex not numbered yet.
const NO_ID: u64 = u64::MAX;

fn key(p: &[f64; 3]) -> (u64, u64) {
    (p[0].to_bits(), p[1].to_bits())
}

impl<'m, 'a, 'b> TileWriter<'m, 'a, 'b> {
    pub fn new(
        mesh: Option<&'m mut (dyn MeshSink + Send)>,
        sinks: &'a mut [&'b mut dyn TriangleSink],
        trim: Option<Trim>,
    ) -> Self {
        TileWriter {
            mesh,
            sinks,
            trim,
            live: FastMap::default(),
            boundary: Default::default(),
            next_id: 0,
            triangles: 0,
            trimmed: 0,
            vertices: 0,
            peak_live: 0,
            local_left: Vec::new(),
            local_id: Vec::new(),
            declared: false,
        }
    }

    /// Tells the mesh, before its first record, what the trimming makes of it: trimmed, and
    /// constrained by the rings of a boundary or holes.
    fn declare(&mut self) -> Result<()> {
        if self.declared {
            return Ok(());
        }
        self.declared = true;
        if let (Some(m), Some(t)) = (self.mesh.as_mut(), self.trim.as_ref())
            && !t.keeps_all()
        {
            m.declare(crate::validate::MeshKind {
                constrained: !t.rings().is_empty(),
                trimmed: true,
                not_delaunay: false,
            })?;
        }
        Ok(())
    }

    /// Writes one tile's triangles.
    ///
    /// # Errors
    /// Any sink's error.
    pub fn tile(&mut self, t: &TileOutput) -> Result<()> {
        self.declare()?;
        let kept: Vec<bool> = t
            .triangles
            .iter()
            .map(|tri| {
                self.trim
                    .as_ref()
                    .is_none_or(|tr| tr.keep(&tri.map(|i| t.vertices[i as usize])))
            })
            .collect();
        for s in self.sinks.iter_mut() {
            for (tri, _) in t.triangles.iter().zip(&kept).filter(|(_, k)| **k) {
                let p = tri.map(|i| t.vertices[i as usize]);
                s.triangle(&p)?;
            }
            if t.skipped > 0 {
                s.skipped(t.skipped);
            }
        }
        // A task's triangles of other tasks that meet its tiles: to the grids, once each.
        for tri in &t.boundary {
            let p = tri.map(|i| t.vertices[i as usize]);
            let mut k = p.map(|v| (v[0].to_bits(), v[1].to_bits()));
            k.sort_unstable();
            if self.trim.as_ref().is_none_or(|tr| tr.keep(&p)) && self.boundary.insert(k) {
                for s in self.sinks.iter_mut() {
                    s.boundary_triangle(&p)?;
                }
            }
        }
        let n = kept.iter().filter(|&&k| k).count() as u64;
        // Triangles the workers left out (no product wanted them) count as written.
        self.triangles += n + t.skipped;
        self.trimmed += t.triangles.len() as u64 - n;
        let Some(mesh) = self.mesh.as_mut() else {
            return Ok(());
        };
        if mesh.takes_pieces() {
            // A plan's task: the merge numbers the vertices of all the tasks' pieces.
            return mesh.piece(t.tile, &t.vertices, &t.degree, &t.triangles);
        }
        self.find_local(t);
        // Degrees of the owned vertices first: some were used by earlier tiles already.
        for (i, &d) in t.degree.iter().enumerate() {
            if d != NOT_OWNED && self.local_left[i] == NOT_LOCAL {
                let k = key(&t.vertices[i]);
                let e = self.live_entry(k);
                e.degree = d;
                if e.seen == d {
                    self.done(k)?;
                }
            }
        }
        for (tri, &keep) in t.triangles.iter().zip(&kept) {
            if keep {
                let mut ids = [0u64; 3];
                for (j, &i) in tri.iter().enumerate() {
                    ids[j] = self.use_vertex(t, i as usize)?;
                }
                self.mesh.as_mut().expect("a mesh").triangle(ids)?;
            }
            for &i in tri {
                self.seen(t, i as usize)?;
            }
        }
        self.peak_live = self.peak_live.max(self.live.len());
        Ok(())
    }

    /// Marks the tile's vertices whose whole star is in the tile: owned, with as many triangles
    /// here as their degree (so no other tile has used them or will).
    fn find_local(&mut self, t: &TileOutput) {
        let n = t.vertices.len();
        debug_assert_eq!(t.degree.len(), n, "a degree for every vertex");
        self.local_left.clear();
        self.local_left.resize(n, 0);
        self.local_id.clear();
        self.local_id.resize(n, NO_ID);
        for tri in &t.triangles {
            for &i in tri {
                self.local_left[i as usize] += 1;
            }
        }
        for (left, &d) in self.local_left.iter_mut().zip(&t.degree) {
            if d == NOT_OWNED || *left != d {
                *left = NOT_LOCAL;
            }
        }
    }

    /// The number of vertex `i` of tile `t`, written when a triangle first uses it.
    fn use_vertex(&mut self, t: &TileOutput, i: usize) -> Result<u64> {
        let p = &t.vertices[i];
        if self.local_left[i] != NOT_LOCAL {
            if self.local_id[i] == NO_ID {
                self.local_id[i] = self.new_vertex(p)?;
            }
            return Ok(self.local_id[i]);
        }
        let next = self.next_id;
        let e = self.live_entry(key(p));
        if let Some(id) = e.id {
            return Ok(id);
        }
        // Numbered before it is written, as `new_vertex` numbers it.
        e.id = Some(next);
        self.new_vertex(p)
    }

    fn new_vertex(&mut self, p: &[f64; 3]) -> Result<u64> {
        let id = self.next_id;
        self.next_id += 1;
        self.vertices += 1;
        self.mesh.as_mut().expect("a mesh").vertex(*p)?;
        Ok(id)
    }

    /// One more triangle of vertex `i` of tile `t` written (or trimmed): finishes the vertex
    /// after its last.
    fn seen(&mut self, t: &TileOutput, i: usize) -> Result<()> {
        let left = &mut self.local_left[i];
        if *left != NOT_LOCAL {
            *left -= 1;
            if *left == 0 && self.local_id[i] != NO_ID {
                let id = self.local_id[i];
                self.mesh.as_mut().expect("a mesh").vertex_done(id)?;
            }
            return Ok(());
        }
        let k = key(&t.vertices[i]);
        let e = self.live_entry(k);
        e.seen += 1;
        if e.seen == e.degree {
            self.done(k)?;
        }
        Ok(())
    }

    /// The map's entry of the vertex at `k`, new (unnumbered, nothing seen, degree unknown) if
    /// absent.
    fn live_entry(&mut self, k: (u64, u64)) -> &mut Live {
        self.live.entry(k).or_insert(Live {
            id: None,
            seen: 0,
            degree: NOT_OWNED,
        })
    }

    fn done(&mut self, k: (u64, u64)) -> Result<()> {
        if let Some(Live { id: Some(id), .. }) = self.live.remove(&k) {
            self.mesh.as_mut().expect("a mesh").vertex_done(id)?;
        }
        Ok(())
    }

    /// Later triangles lie at `y >= y`.
    ///
    /// # Errors
    /// Any sink's error.
    pub fn watermark(&mut self, y: f64) -> Result<()> {
        self.declare()?;
        for s in self.sinks.iter_mut() {
            s.watermark(y)?;
        }
        if let Some(m) = self.mesh.as_mut() {
            m.watermark(y)?;
        }
        Ok(())
    }

    /// Ends the vertices still waiting whose `(x, y)` no tile of the run owns (`orphan`): all
    /// their triangles, owned by other tiles, are written. (A plan has no task for the tiles
    /// just beyond the data's last row and column, which own the points on its top and right
    /// edges but no triangle.) Returns how many.
    ///
    /// # Errors
    /// The mesh writer's.
    pub fn release(&mut self, orphan: impl Fn(f64, f64) -> bool) -> Result<u64> {
        let mut keys: Vec<(u64, u64)> = self
            .live
            .keys()
            .filter(|k| orphan(f64::from_bits(k.0), f64::from_bits(k.1)))
            .copied()
            .collect();
        keys.sort_unstable_by_key(|k| self.live[k].id);
        for &k in &keys {
            self.done(k)?;
        }
        Ok(keys.len() as u64)
    }

    /// Accounts for every triangle of a points-only run over all the data: there are `2V − B − 2`
    /// for `kept` distinct points ([`super::hull::boundary_points`]). With `unseen` (a DEM alone:
    /// [`super::keep::Want::skip_inside`]) the triangles no tile looked at count as written, as
    /// the workers' skipped ones do, and nothing is measured (`None`). Otherwise every triangle
    /// was owned by one tile, certified and written or trimmed: the owned triangles missing
    /// (`Some(0)`, or the error below).
    ///
    /// # Errors
    /// Reading the index; [`Error::Internal`] if the tiles counted more triangles than there
    /// are, or (all seen) fewer: an owned triangle never certified.
    pub fn account(
        &mut self,
        index: &super::index::BlockIndex,
        kept: u64,
        unseen: bool,
    ) -> Result<Option<u64>> {
        if index.hull().len() < 3 {
            return Ok((!unseen).then_some(0));
        }
        let all = (2 * kept).saturating_sub(super::hull::boundary_points(index)? + 2);
        let counted = self.triangles + self.trimmed;
        if counted > all {
            return Err(Error::Internal(format!(
                "the tiles counted {counted} triangles, but {kept} points make {all}"
            )));
        }
        let n = all - counted;
        if !unseen {
            if n > 0 {
                return Err(Error::Internal(format!(
                    "{n} of the {all} triangles of {kept} points were owned by no tile that \
                     certified them"
                )));
            }
            return Ok(Some(0));
        }
        for s in self.sinks.iter_mut() {
            s.skipped(n);
        }
        self.triangles += n;
        Ok(None)
    }

    /// Vertices still waiting for triangles (none after the last tile).
    pub fn pending(&self) -> usize {
        self.live.len()
    }
}
