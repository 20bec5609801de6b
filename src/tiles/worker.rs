//! One tile: read the blocks of its buffered extent, triangulate them in memory, certify, grow the
//! buffer until everything the tile owns is certified, and keep what it owns.
//!
//! **Ownership.** A triangle belongs to the tile holding its lowest vertex in sweep order (least
//! `y`, then least `x`); a vertex to the tile holding it. Tiles are unions of blocks, and a point's
//! block is one function of its coordinates, so every triangle and vertex has exactly one owner.
//!
//! **When a tile is done.** Let `R` be the tile's closed rectangle. Every run holds the corners of
//! the whole convex hull, so its hull is the whole hull. The first run reads the tile's blocks and
//! a buffer, and judges every triangle that meets `R` ([`super::region`]): certified triangles
//! ([`super::certify`]) are triangles of the whole triangulation. If some fail, a *patch* run reads
//! the blocks around the failed triangles and every non-empty block their circumdisks touch, and
//! must certify every triangle meeting the union `F` of the failed ones; and so on until a run
//! fails nothing. The failed triangles of a run cover exactly the part of its region that its
//! certified triangles do not, and each patch covers that part with certified triangles (its hull
//! holds `F`, whose vertices it reads), so the certified triangles of all runs cover `R`. Being
//! triangles of one triangulation, they are then exactly the whole triangulation's triangles that
//! meet `R`: every owned triangle is there, and every owned vertex has its whole star (its degree).
//! Parts of `R` outside them are outside the whole hull. When the blocks read are every non-empty
//! block, every certificate holds, so this ends.
//!
//! **Breaklines (constrained Delaunay).** Let `B` be the blocks a run reads. The run triangulates
//! its points plus every (cleaned, z-settled) segment that meets `B`, whole, with both ends
//! wherever they lie (ends are points of the whole input; the tie rule is stated in positions,
//! so it is the global one), and the corners of the hull of all points *and* line vertices
//! ([`super::lines`]). A triangle `t` of the run's CDT is a triangle of the whole CDT when
//! (a) no point or line vertex the run did not load lies in its circumdisk where it is visible
//! from `t` (the certificate above, with segment ends as data too), and (b) no segment the run
//! did not load crosses `t` (checked exactly with [`crate::geom::predicates`] on the graph's
//! segment grid). Proof: by (b) every segment of the input that crosses `t` is loaded, and `t`
//! is a CDT triangle of the run, so none does. A vertex of the input inside the disk and visible
//! from `t`'s interior in the whole input is loaded by (a), and visible in the run too (the run's
//! segments are a subset of the input's), against `t` being constrained Delaunay in the run. So
//! `t` is constrained Delaunay for the whole input, and the whole CDT (unique under the tie rule)
//! holds it. "Visible" in (a) is decided conservatively: a point is hidden only when it lies
//! strictly beyond a constrained edge of `t` (in the cap that edge cuts off the disk), outside
//! the region of run triangles reachable from `t` across unconstrained edges that meet the disk
//! (a sight line inside the disk crosses no vertex of the run, else that vertex would be visible
//! in the disk, so it walks through that region), or behind one loaded segment that meets every
//! segment from the point to a corner of `t` ([`super::lines::Sight`]). A point exactly on a
//! loaded segment lies on the chord of the triangles beside it, so it is never hidden: a run
//! that did not load it cannot certify them. A line vertex at a point's position is one vertex
//! whose `z` follows `--duplicates` (the line read last) in every run. The rest of the argument
//! (patches, coverage, ownership) is the unconstrained one. `--no-flat-triangles` stays on the
//! sweep: its flips look across triangles that other tiles own, which no certificate covers.
//!
//! **Covering needs (a DEM alone).** When the only products are covering
//! ([`crate::sink::Wants::covering`]: a DEM uses a triangle only for the cell centres it holds,
//! and wants every triangle whose box holds one) and no mesh, line or trim looks at every
//! triangle, a run (a plan's task's too) leaves unjudged the triangles lying strictly inside the tile (their box in
//! the open tile rectangle, shrunk by the margin) that the products do not want. Every owned
//! triangle `T` the DEM needs is still found. If `T` reaches the tile's border or beyond, take
//! a point `q` of `T` outside the open inner rectangle but in the widened one the region judges
//! (on the way from `T`'s lowest vertex, owned, hence within the margin of the tile, to a
//! corner outside the inner rectangle): every run triangle holding `q` is judged, so the runs go on until the ones
//! holding `q` are certified, and then they are the whole triangulation's triangles holding
//! `q`, `T` among them (certified triangles are true ones, and those holding `q` cover its
//! neighbourhood). If `T` is strictly inside, it holds a centre `c` in the tile, every run
//! triangle holding `c` is wanted, hence judged, and the same argument finds `T`. The triangles
//! left out are counted at the end instead: a triangulation of `V` points, `B` of them on the
//! hull's boundary, has `2V − B − 2` triangles ([`super::hull::boundary_points`]). A plan's task
//! holds only its part of the points: it counts the triangles it certified
//! ([`super::TileStats::skipped_inside`]).

use super::certify::Loaded;
use super::grid::{BlockRect, TileGrid};
use super::index::BlockIndex;
use super::keep::{Owner, Want, from_runs};
use super::lines::TileLines;
use super::region::{Region, Tri2, Tris, judge, tri_meets_rect};
use crate::error::{Error, Result};
use crate::sort::DuplicatePolicy;
use crate::triangulation::{Options, triangulate, triangulate_with_twins};

/// Degree of a vertex this tile does not own (unknown here).
pub(crate) const NOT_OWNED: u32 = u32::MAX;

/// What a tile delivers: its owned triangles and what the writer needs to number their vertices.
#[derive(Debug, Default)]
pub(crate) struct TileOutput {
    /// Tile coordinates.
    pub tile: (i64, i64),
    /// The vertices of the owned triangles, and owned vertices that other tiles' triangles use.
    pub vertices: Vec<[f64; 3]>,
    /// Owned triangles (counter-clockwise, indices into `vertices`), in the run's order.
    pub triangles: Vec<[u32; 3]>,
    /// For a task of a plan: the certified triangles that meet this tile but belong to a tile
    /// outside the task (for the grids of the task's own cells).
    pub boundary: Vec<[u32; 3]>,
    /// For a mesh ([`Want::mesh`]), for each vertex: its number of triangles in the whole
    /// triangulation when this tile owns it, else [`NOT_OWNED`]. Empty otherwise.
    pub degree: Vec<u32>,
    /// Points read in the owned blocks (after filters).
    pub points_read: u64,
    /// Distinct owned vertices.
    pub points_kept: u64,
    /// Runs of the tile (1 when the first buffer was enough; then patches).
    pub runs: u32,
    /// The widest buffer of the first run, in blocks, or of a patch, measured from the tile.
    pub buffer_blocks: i64,
    /// Points triangulated, all runs together.
    pub loaded_points: u64,
    /// Owned triangles left out because no product wanted them ([`crate::sink::Needs`]).
    pub skipped: u64,
    /// CPU time of the tile's stages.
    pub cpu: super::TileCpu,
}

impl TileOutput {
    /// What the output holds on the heap until it is written (its vectors' capacities).
    pub(crate) fn heap_bytes(&self) -> u64 {
        use std::mem::size_of;
        let tris = self.triangles.capacity() + self.boundary.capacity();
        (self.vertices.capacity() * size_of::<[f64; 3]>()
            + tris * size_of::<[u32; 3]>()
            + self.degree.capacity() * size_of::<u32>()) as u64
    }
}

/// Runs tile `(tx, ty)`, starting with a buffer of `buffer` blocks.
///
/// # Errors
/// Reading the index; the triangulation's errors when the whole input has no triangle.
pub(crate) fn run_tile(
    index: &BlockIndex,
    tile: (i64, i64),
    policy: DuplicatePolicy,
    buffer: i64,
    task: Option<&BlockRect>,
    lines: Option<&TileLines>,
    want: &Want,
) -> Result<TileOutput> {
    let g = index.grid;
    let owned = g.tile_blocks(tile.0, tile.1);
    let mut out = TileOutput {
        tile,
        ..TileOutput::default()
    };
    out.points_read = index.count(&owned);
    // A tile without points owns nothing; in a task it still delivers the triangles of other
    // tasks that cover it.
    if out.points_read == 0 && task.is_none() && lines.is_none() {
        return Ok(out);
    }
    let occ = index.occupied();
    let owner = Owner::new(g, owned);
    let task_owner = task.map(|t| Owner::new(g, *t));
    let w = g.world(&owned);
    let m = g.margin(w.iter().fold(0.0f64, |m, v| m.max(v.abs())));
    let rect = [w[0] - m, w[1] - m, w[2] + m, w[3] + m];
    let inner = [w[0] + m, w[1] + m, w[2] - m, w[3] - m];
    let skip = want.skip_inside.then_some((&want.needs, inner));
    let mut region = Region {
        rect,
        failed: None,
        skip,
    };
    let mut loaded = Loaded {
        rect: owned.expand(buffer.max(0)).intersect(&occ),
        extra: Vec::new(),
    };
    // The first run, with what it certified; then the certified triangles of the patches.
    let mut first: Option<(crate::Triangulation, Vec<u32>)> = None;
    let mut patched: Vec<[[f64; 3]; 3]> = Vec::new();
    let mut first_rect = loaded.rect;
    let mut pts = Vec::new();
    loop {
        out.runs += 1;
        pts.clear();
        let mut blocks = 0.0;
        crate::clock::timed(&mut blocks, || -> Result<()> {
            index.read(&loaded.rect, &mut pts)?;
            for &k in &loaded.extra {
                index.read_block(k, &mut pts)?;
            }
            Ok(())
        })?;
        out.cpu.blocks += blocks;
        let own = pts.len();
        out.loaded_points += own as u64;
        out.buffer_blocks = out.buffer_blocks.max(buffer_of(&owned, &loaded.rect));
        // Corners of the whole hull from blocks not read: they make the run's hull the whole hull.
        for p in index.hull() {
            let (bx, by) = g.block_of(p[0], p[1]);
            if !loaded.contains(TileGrid::key(bx, by), bx, by) {
                pts.push(*p);
            }
        }
        // The segments meeting the blocks read, whole, with their ends (after the points: a
        // vertex at a point's position is one vertex, the line read last).
        let run_lines = lines.map(|l| l.run(&g, &loaded.rect, &loaded.extra));
        let segments = run_lines
            .as_ref()
            .map(|l| l.append(&mut pts))
            .unwrap_or_default();
        // Every point there is: all the blocks, every segment, and (for a task) nothing unread
        // in the files.
        let full = loaded.rect.contains_rect(&occ)
            && index.scope.as_ref().is_none_or(|sc| sc.complete())
            && run_lines.as_ref().is_none_or(|l| l.all());
        let mut cpu = 0.0;
        let t = crate::clock::timed(&mut cpu, || {
            let options = Options { duplicates: policy };
            if run_lines.is_none() {
                triangulate(&pts, &options).map(|t| (t, Vec::new()))
            } else {
                triangulate_with_twins(&pts, &segments, &options)
            }
        });
        out.cpu.triangulate += cpu;
        let (t, twins) = match t {
            Ok(t) => t,
            Err(Error::TooFewPoints { .. } | Error::AllCollinear { .. }) if !full => {
                if loaded.rect.contains_rect(&occ) {
                    // Every block of a task read, and points may lie beyond them.
                    let buffer = index.scope.as_ref().map_or(0.0, |sc| sc.buffer);
                    return Err(Error::BufferTooSmall { buffer, reach: 0.0 });
                }
                loaded = doubled(&owned, &first_rect, &loaded, &occ);
                first_rect = loaded.rect;
                continue;
            }
            Err(e) => return Err(e),
        };
        if t.constraint_stats.crossing_skipped > 0 {
            return Err(Error::Internal(format!(
                "tile {tile:?}: {} breakline segments of a cleaned graph crossed",
                t.constraint_stats.crossing_skipped
            )));
        }
        let mut cpu = 0.0;
        let verdict = crate::clock::timed(&mut cpu, || {
            judge(
                index,
                &t,
                &region,
                &loaded,
                full,
                out.runs,
                run_lines.as_ref().map(|l| (l, &twins[..])),
            )
        })?;
        out.cpu.certify += cpu;
        if std::env::var_os("SWEEPTIN_DEBUG_TILES").is_some() {
            eprintln!(
                "tile {tile:?} run {}: {own} points ({} extra blocks): {} certified, {} failed, \
                 {} blocks wanted, {} points in {} blocks tested{}",
                out.runs,
                loaded.extra.len(),
                verdict.certified.len(),
                verdict.failed.len(),
                verdict.blocks.len(),
                verdict.tested.0,
                verdict.tested.1,
                if verdict.degenerate {
                    ", degenerate"
                } else {
                    ""
                }
            );
        }
        if verdict.unknown > 0.0 {
            let buffer = index.scope.as_ref().map_or(0.0, |sc| sc.buffer);
            return Err(Error::BufferTooSmall {
                buffer,
                reach: verdict.unknown,
            });
        }
        let failed: Vec<Tri2> = verdict
            .failed
            .iter()
            .map(|&k| {
                t.triangles[k as usize]
                    .map(|i| [t.vertices[i as usize][0], t.vertices[i as usize][1]])
            })
            .collect();
        let next = if failed.is_empty() {
            None
        } else if verdict.degenerate {
            Some(doubled(&owned, &first_rect, &loaded, &occ))
        } else {
            // Patches only grow (the first starts afresh, without the first run's rectangle), so
            // the runs end: each reads at least one block more, or everything.
            let mut p = patch(index, &owned, &failed, verdict.blocks.clone());
            if first.is_some() {
                p.extra.extend_from_slice(&loaded.extra);
                p.extra.sort_unstable();
                p.extra.dedup();
                p.rect = loaded.rect;
                let rect = p.rect;
                p.extra.retain(|&k| {
                    let (bx, by) = TileGrid::unkey(k);
                    !rect.contains(bx, by)
                });
            }
            Some(p)
        };
        match &first {
            None => first = Some((t, verdict.certified)),
            Some(_) => patched.extend(
                verdict
                    .certified
                    .iter()
                    .map(|&k| t.triangles[k as usize].map(|i| t.vertices[i as usize])),
            ),
        }
        let Some(mut next) = next else { break };
        if next == loaded && loaded.rect.contains_rect(&occ) {
            // Everything read and still not judged: only a wider buffer can help (a task).
            let buffer = index.scope.as_ref().map_or(0.0, |sc| sc.buffer);
            return Err(Error::BufferTooSmall { buffer, reach: 0.0 });
        }
        if next == loaded {
            next = Loaded {
                rect: occ,
                extra: Vec::new(),
            };
        }
        loaded = next;
        if !failed.is_empty() {
            region = Region {
                rect,
                failed: Some(Tris::new(failed)),
                skip,
            };
        }
    }
    let (t, certified) = first.expect("a first run");
    let mut cpu = 0.0;
    crate::clock::timed(&mut cpu, || {
        from_runs(
            &owner,
            task_owner.as_ref(),
            want,
            &t,
            &certified,
            &patched,
            &mut out,
        );
    });
    out.cpu.keep += cpu;
    // A test's stand-in for a certification bug: every tile loses an owned triangle, which the
    // run's count must catch (tests/hardening.rs).
    if std::env::var_os("SWEEPTIN_TEST_LOSE").is_some_and(|v| v == "triangle") {
        out.triangles.pop();
    }
    Ok(out)
}

/// The blocks of a patch run: the blocks the failed triangles meet within the tile (and a
/// block around), and the blocks holding a point inside a failed triangle's circumdisk
/// (`blocks`). Blocks, not rectangles: a failed triangle may be a long sliver across the tile
/// (to a corner of the hull far away), and failed triangles may lie far apart (a lens along the
/// data's edge, a lake's shore).
fn patch(index: &BlockIndex, owned: &BlockRect, failed: &[Tri2], blocks: Vec<u64>) -> Loaded {
    let g = index.grid;
    let mut extra = blocks;
    let area = owned.expand(1).intersect(&index.occupied());
    let mut met = Vec::new();
    for t in failed {
        let (mut x0, mut y0) = g.block_of(t[0][0], t[0][1]);
        let (mut x1, mut y1) = (x0, y0);
        for p in &t[1..] {
            let (bx, by) = g.block_of(p[0], p[1]);
            (x0, y0, x1, y1) = (x0.min(bx), y0.min(by), x1.max(bx), y1.max(by));
        }
        // A block rectangle one wider: points may lie a rounding outside their block.
        let r = BlockRect {
            x0: x0 - 1,
            y0: y0 - 1,
            x1: x1 + 2,
            y1: y1 + 2,
        }
        .intersect(&area);
        let m = g.margin(g.world(&r).iter().fold(0.0f64, |m, v| m.max(v.abs())));
        for by in r.y0..r.y1 {
            for bx in r.x0..r.x1 {
                let w = g.world(&BlockRect {
                    x0: bx,
                    y0: by,
                    x1: bx + 1,
                    y1: by + 1,
                });
                if tri_meets_rect(t, &[w[0] - m, w[1] - m, w[2] + m, w[3] + m]) {
                    met.push((bx, by));
                }
            }
        }
    }
    met.sort_unstable();
    met.dedup();
    let occ = index.occupied();
    for &(bx, by) in &met {
        for dy in -1..=1 {
            for dx in -1..=1 {
                if occ.contains(bx + dx, by + dy) {
                    let k = TileGrid::key(bx + dx, by + dy);
                    if index.extent(k).is_some() {
                        extra.push(k);
                    }
                }
            }
        }
    }
    extra.sort_unstable();
    extra.dedup();
    Loaded {
        rect: BlockRect {
            x0: 0,
            y0: 0,
            x1: 0,
            y1: 0,
        },
        extra,
    }
}

/// The loaded blocks with the buffer of the first run's rectangle `first` around `owned` doubled
/// (for a run that could not be judged).
fn doubled(owned: &BlockRect, first: &BlockRect, loaded: &Loaded, occ: &BlockRect) -> Loaded {
    let mut b = buffer_of(owned, first);
    let mut rect = owned.expand(2 * b + 1).union(&loaded.rect).intersect(occ);
    // Around an empty tile the first rings may hold no block: grow until one more is read.
    while rect == loaded.rect && !rect.contains_rect(occ) {
        b = 2 * b + 1;
        rect = owned.expand(2 * b + 1).union(&loaded.rect).intersect(occ);
    }
    let mut extra = loaded.extra.clone();
    extra.retain(|&k| {
        let (bx, by) = TileGrid::unkey(k);
        !rect.contains(bx, by)
    });
    Loaded { rect, extra }
}

/// The widest side of the buffer of `loaded` around `owned`, in blocks.
fn buffer_of(owned: &BlockRect, loaded: &BlockRect) -> i64 {
    if loaded.is_empty() {
        return 0;
    }
    [
        owned.x0 - loaded.x0,
        owned.y0 - loaded.y0,
        loaded.x1 - owned.x1,
        loaded.y1 - owned.y1,
    ]
    .into_iter()
    .max()
    .unwrap_or(0)
    .max(0)
}
