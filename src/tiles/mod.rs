//! Exact tiles in parallel: the triangulation of all the points, computed tile by tile on every
//! core, equal to the single sweep's.
//!
//! ```text
//! LAS/LAZ ─► read once (filters) ─► external sort by block (stable) ─► block index (temp file)
//!   ─► tiles on N threads: read own blocks + buffer, triangulate in memory, certify, grow
//!   ─► writer: tiles in order ─► MeshSink / TriangleSinks (the same sinks as the sweep's)
//! ```
//!
//! `grid` defines the tiles and blocks, `read` decodes the files once into `index`, which stores
//! the points by block (and the convex hull, `hull`), `certify` says which triangles of a tile's run are triangles of the whole
//! triangulation, `region` judges a run, `worker` runs one tile (the ownership rule and why a tile
//! is exact are stated there), `keep` collects what a tile owns, `emit` delivers the tiles in order.
//!
//! The tile and block sizes depend on the data only (the headers' density and the points kept by
//! the filters), never on `--mem` or `--threads`, and tiles are delivered in a fixed order, so the
//! output is the same bytes for every memory budget and thread count. The triangle *set* is the
//! one of the streaming sweep along `y` (the same tie rule, stated in positions), in another order.

pub(crate) mod band;
pub(crate) mod certify;
pub(crate) mod emit;
pub(crate) mod grid;
pub(crate) mod hull;
pub(crate) mod index;
pub(crate) mod keep;
pub(crate) mod lines;
pub(crate) mod read;
pub(crate) mod region;
pub(crate) mod store;
pub(crate) mod budget;
pub(crate) mod worker;

use crate::error::{Error, Result};
use crate::sink::{MeshSink, Needs, StreamInfo, TriangleSink};

use budget::Budget;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;
use read::{read_index, with_lines};
use worker::TileOutput;

/// Average points per block the block size aims at (at least; see [`block_points`]).
const BLOCK_POINTS: f64 = 64.0;
/// Non-empty blocks the block table aims to stay under (32 bytes each: key, start, extent).
const MAX_BLOCKS: f64 = (1u64 << 21) as f64;
/// Blocks per tile the tile size aims at (a tile of 32 × 32 blocks: a buffer of one block adds
/// about 13 %).
const TILE_BLOCKS: f64 = 1024.0;
/// Bytes a tile's run holds per point read, at its peak (the points, the in-memory sweep, the
/// triangulation, the certificates and the tile's output), for the memory budget. Measured at a
/// billion points (`scripts/bench-billion.sh`, tiles of about 350 k points): three runs in
/// flight took about 129 MB each, 350 bytes a point, beside the block table and the DEM's rows.
const RUN_BYTES_PER_POINT: f64 = 384.0;
/// The first buffer of a tile, in blocks.
const FIRST_BUFFER: i64 = 1;

/// How to tile.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TileOptions {
    /// Worker threads (0: every core).
    pub threads: usize,
    /// Tile side; default: from the data's density. For a task, the plan's tile side (the task
    /// cuts its tile into smaller ones).
    pub tile: Option<f64>,
    /// Tiles are whole multiples of this (a DEM's cell); default 1.
    pub base: Option<f64>,
    /// Run one tile of a plan only (see [`TaskScope`]).
    pub scope: Option<TaskScope>,
}

/// One task of a plan: the tile it owns, how far around it the files are read, and the extents
/// of the plan's files it does not read (so that it knows where points it has not seen may be).
///
/// The task delivers the triangles it owns (lowest vertex in its tile) to every sink, and to
/// sinks of grids (a DEM) also the other triangles that meet its tile
/// ([`crate::sink::TriangleSink::boundary_triangle`]). When a certificate needs points beyond the
/// buffer, the run fails with [`Error::BufferTooSmall`] before any sink is finished.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TaskScope {
    /// The task's tile `[xmin, ymin, xmax, ymax]`, on the plan's grid of tiles of side `tile`.
    pub tile: [f64; 4],
    /// The files reaching this far around the tile are read (all their points).
    pub buffer: f64,
    /// Extents `[xmin, ymin, xmax, ymax]` of the plan's files with points that the task does not
    /// read, from their headers.
    pub unread: Vec<[f64; 4]>,
    /// Chunk indexes of the plain LAZ/LAS files the task reads, by path
    /// ([`crate::input::las::ReadOptions::chunks`]): when every file is COPC or indexed, the
    /// task decodes only the chunks that meet its tile and buffer.
    pub chunks: Vec<(std::path::PathBuf, std::sync::Arc<crate::input::las::ChunkIndex>)>,
    /// Read only the points of the tile grown by the buffer, whatever the files and their
    /// indexes (what lies beyond counts as unread): a task whose points have known classes only
    /// there (`--ground`, [`crate::plan`]'s tasks classify their own area).
    pub by_area: bool,
    /// The data's hull and the points within its width of it ([`HullBand`], computed by the
    /// plan): a task reading by area adds the band's points beyond its area and knows that what
    /// it did not read lies inside the hull moved inwards, so its edge tiles need no wider buffer.
    pub band: Option<std::sync::Arc<HullBand>>,
    /// The plan's point store ([`PointStore`]): the task reads the points of its tile and
    /// buffer from it instead of decoding the files (the same points in the same order).
    pub store: Option<std::sync::Arc<PointStore>>,
}

pub use band::HullBand;
pub use store::PointStore;

/// What the tiles did (part of the `--json` summary).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TileStats {
    /// Tile side.
    pub tile_size: f64,
    /// Block side (the unit of buffers).
    pub block_size: f64,
    /// Tiles with points.
    pub tiles: u64,
    /// Extra runs of tiles whose first buffer was not enough.
    pub reruns: u64,
    /// Widest buffer a tile ended with, in the data's units.
    pub max_buffer: f64,
    /// Points triangulated over all runs' last attempts (owned plus buffers).
    pub loaded_points: u64,
    /// Owned triangles that were not certified, counted over the whole run: the triangles
    /// there are (Euler's `2V − B − 2`) less those the tiles wrote or trimmed; a run with any
    /// is an internal error, so a summary says 0. `None` where it cannot be counted: products
    /// that all cover (a DEM alone: unwanted triangles are left unseen), breaklines or trimming
    /// polygons, a plan's task.
    pub uncertified_owned: Option<u64>,
    /// The unwanted triangles deep inside the tiles were neither certified nor counted (the
    /// products all cover: a DEM alone). A run over all the data then counts them by Euler's
    /// formula; a plan's task cannot, and its `triangles` are those it certified.
    pub skipped_inside: bool,
    /// Points decoded from the files (COPC nodes and indexed chunks that miss a task's area
    /// are not decoded).
    pub points_decoded: u64,
    /// Points read from a plan's point store ([`TaskScope::store`]) instead (those of the
    /// cells meeting the task's area, kept or not).
    pub points_stored: u64,
    /// Worker threads.
    pub threads: u64,
    /// Tiles' runs allowed at once within `--mem` (at most the workers); finished tiles waiting
    /// to be written in order hold only their outputs' share.
    pub window: u64,
    /// CPU time by stage.
    pub cpu: TileCpu,
    /// The extent `[xmin, ymin, xmax, ymax]` of the points read (after the filters): a DEM's
    /// grid over the data is decided from it ([`crate::raster::GridExtent::Auto`]), and a
    /// plan's merge decides one run's grid from its tasks' ([`crate::plan::TaskRecord::extent`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extent: Option<[f64; 4]>,
}

/// CPU seconds by stage of a tiled run (Linux; zeros elsewhere). Reading is the whole
/// process's CPU while it reads (decoding on every core, the block sort's chunks), the others
/// the threads that do each stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TileCpu {
    /// Decoding, filtering and sorting into blocks (the sort's chunks and spills).
    pub read_sort: f64,
    /// Of `read_sort`, decoding: decompressing, converting and filtering the records (on every
    /// core).
    pub decode: f64,
    /// Merging the sorted runs into the block index, and the hull.
    pub index: f64,
    /// Reading tiles' blocks back from the index (workers).
    pub blocks: f64,
    /// Triangulating tiles' points in memory (workers: the sweep and its sort).
    pub triangulate: f64,
    /// Certifying triangles (workers).
    pub certify: f64,
    /// Collecting what each tile owns, patches combined (workers).
    pub keep: f64,
    /// The writer thread: the products (rasterisation, contours, …) and the mesh output.
    pub write: f64,
}

impl TileCpu {
    /// Adds a tile's worker times.
    fn add(&mut self, t: &TileCpu) {
        self.blocks += t.blocks;
        self.triangulate += t.triangulate;
        self.certify += t.certify;
        self.keep += t.keep;
    }
}

/// What [`run`] hands back to the pipeline.
#[derive(Debug, Default)]
pub(crate) struct TiledRun {
    pub points_read: u64,
    pub points_kept: u64,
    pub triangles: u64,
    /// Triangles `--max-edge` dropped.
    pub trimmed: u64,
    pub vertices: u64,
    pub sort: crate::sort::external::SortStats,
    pub tiles: TileStats,
    pub crs: Option<crate::crs::Crs>,
    /// The headers' warnings ([`LidarReader::warnings`]).
    pub warnings: Vec<String>,
    pub read_sort: f64,
}

/// What a tiled run reads, and with what budget (the pipeline's run configuration, checked).
pub(crate) struct TileJob<'a> {
    /// The LAS/LAZ files.
    pub paths: &'a [std::path::PathBuf],
    /// Their filters.
    pub filter: &'a crate::input::las::Filter,
    /// Which point survives among exact (x, y) duplicates.
    pub duplicates: crate::DuplicatePolicy,
    /// `--max-edge`.
    pub max_edge: Option<f64>,
    /// Breaklines (and trimming rings), cleaned, every `z` known.
    pub lines: Option<&'a crate::breaklines::Pslg>,
    /// Trimming (boundary, holes, `--max-edge`), instead of `max_edge` alone.
    pub trim: Option<&'a crate::breaklines::Trim>,
    /// Memory budget in bytes.
    pub mem: u64,
    /// Where spill files go.
    pub tmp: &'a std::path::Path,
    /// The CRS the user declares for the files (`--crs`; see
    /// [`crate::input::las::ReadOptions::crs`]).
    pub crs: Option<&'a crate::crs::Crs>,
}

/// Runs a tiled triangulation of `job` into `mesh` and `sinks`.
///
/// # Errors
/// Reader, tile and sink errors; [`Error::TooFewPoints`] / [`Error::AllCollinear`] when the whole
/// input has no triangle.
pub(crate) fn run(
    job: &TileJob,
    options: &TileOptions,
    progress: &mut dyn FnMut(&str, u64, u64),
    mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<TiledRun> {
    let start = Instant::now();
    let max_edge = job.max_edge;
    let mut options = options.clone();
    if options.base.is_none() {
        options.base = sinks.iter().find_map(|s| s.grid_cell());
    }
    let options = &options;
    let (index, declared, bounds, cpu) =
        read_index(job, options, &mut |n, t| progress("reading", n, t))?;
    let read_sort = start.elapsed().as_secs_f64();
    if index.len() == 0 {
        // A task that read no point may still lie under triangles of points farther out.
        if index.scope.as_ref().is_some_and(|sc| !sc.complete()) {
            let buffer = index.scope.as_ref().map_or(0.0, |sc| sc.buffer);
            return Err(Error::BufferTooSmall { buffer, reach: 0.0 });
        }
        return Err(Error::TooFewPoints {
            distinct: 0,
            total: 0,
        });
    }
    let mut index = index;
    let lines = match job.lines {
        Some(p) if !p.vertices.is_empty() => Some(with_lines(&mut index, p, job.duplicates)?),
        _ => None,
    };
    let lines = lines.as_ref();
    let index = index;
    let g = index.grid;
    // Tiles holding a breakline vertex run even without points (they own its triangles).
    let line_tiles: crate::idmap::FastSet<(i64, i64)> = lines
        .map(|l| {
            l.vertices
                .iter()
                .map(|v| {
                    let (bx, by) = g.block_of(v[0], v[1]);
                    g.tile_of_block(bx, by)
                })
                .collect()
        })
        .unwrap_or_default();
    // A task whose products include a grid runs every tile of its plan tile, with points or
    // not: triangles of other tasks may cover its empty parts, and its cells need them. Other
    // products (a TIN's pieces, contours, volumes) are owned by points: only the tiles with
    // points run, so a task's cost follows its points, not its area (`plan tin --tile 1e6`
    // visited 16 million empty tiles).
    let covers = options.scope.is_some() && sinks.iter().any(|s| s.wants_boundary());
    let tiles_rect = match &options.scope {
        None => g.tiles_of(&index.occupied()),
        Some(sc) => {
            // The plan's tile is `per × per` tiles of this grid (its side halved `log2 per`
            // times, edges on the multiples of both): those of the plan tile holding its centre.
            // Its edges, products of a side such as 27.9, may round into the tiles beside it.
            let t = sc.tile;
            let tile_at = |x: f64, y: f64| {
                let (bx, by) = g.block_of(x, y);
                g.tile_of_block(bx, by)
            };
            match options.tile {
                Some(side) => {
                    let per = ((side / g.tile).round() as i64).max(1);
                    let (tx, ty) = tile_at((t[0] + t[2]) / 2.0, (t[1] + t[3]) / 2.0);
                    let (x0, y0) = (tx.div_euclid(per) * per, ty.div_euclid(per) * per);
                    grid::BlockRect {
                        x0,
                        y0,
                        x1: x0 + per,
                        y1: y0 + per,
                    }
                }
                // A scope without the plan's side (a library caller): the tiles its corners
                // fall in.
                None => {
                    let (x0, y0) = tile_at(t[0], t[1]);
                    let (x1, y1) = tile_at(t[2], t[3]);
                    grid::BlockRect { x0, y0, x1, y1 }
                }
            }
        }
    };
    let task = options.scope.as_ref().map(|_| {
        let r = tiles_rect;
        let n = 1i64 << g.shift;
        grid::BlockRect {
            x0: r.x0 * n,
            y0: r.y0 * n,
            x1: r.x1 * n,
            y1: r.y1 * n,
        }
    });
    // The tiles looked at: without covering or lines, only those of the occupied blocks. A
    // covering task looks only where triangles can be: in the box of all the data (the points
    // read, the files or parts of files it does not read, the lines' vertices); a plan tile far
    // larger than the data (`plan dem --tile 1e6`) holds millions of tiles no triangle reaches.
    let occupied = g.tiles_of(&index.occupied());
    let walk = if covers || !line_tiles.is_empty() {
        let tile_of = |x: f64, y: f64| {
            let (bx, by) = g.block_of(x, y);
            g.tile_of_block(bx, by)
        };
        let one = |(tx, ty): (i64, i64)| grid::BlockRect {
            x0: tx,
            y0: ty,
            x1: tx + 1,
            y1: ty + 1,
        };
        // Beside the points read: the files not read and the parts of files read only around
        // the tile (COPC, indexed chunks), from their headers.
        let data = index
            .scope
            .iter()
            .flat_map(|sc| sc.unknown.iter().chain(&sc.beyond))
            .flat_map(|b| [tile_of(b[0], b[1]), tile_of(b[2], b[3])])
            .chain(line_tiles.iter().copied())
            .map(one)
            .fold(occupied, |r, t| if r.is_empty() { t } else { r.union(&t) });
        // Grown by a tile: a cell of a tile that only touches the data's box (its centre on the
        // data's edge, `--align centres`) takes its value from the triangles there.
        tiles_rect.intersect(&data.expand(1))
    } else {
        tiles_rect.intersect(&occupied)
    };
    let order: Vec<(i64, i64)> = (walk.y0..walk.y1.max(walk.y0))
        .flat_map(|ty| (walk.x0..walk.x1.max(walk.x0)).map(move |tx| (tx, ty)))
        .filter(|&(tx, ty)| {
            covers
                || index.count(&g.tile_blocks(tx, ty)) > 0
                || line_tiles.contains(&(tx, ty))
        })
        .collect();
    let threads = match options.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    }
    .max(1);
    let info = StreamInfo {
        crs: declared.crs.clone(),
        bounds,
    };
    for s in sinks.iter_mut() {
        s.begin(&info)?;
    }
    let trim = match (job.trim, max_edge) {
        (Some(t), _) if !t.keeps_all() => Some(t.clone()),
        (Some(_), _) => None,
        (None, Some(l)) => Some(crate::breaklines::Trim::new(None, &[], Some(l))?),
        (None, None) => None,
    };
    let shares: u64 = sinks.iter().map(|s| s.memory_share()).sum();
    // The workers keep only the triangles some output wants: a mesh, or `--max-edge` (which
    // counts what it trims), takes every one.
    let needs = if mesh.is_some() || trim.is_some() {
        Needs::All
    } else {
        Needs::together(sinks.iter().map(|s| s.needs()))
    };
    let want = keep::Want {
        mesh: mesh.is_some(),
        skip_inside: needs.covering() && job.lines.is_none(),
        needs,
    };
    let mut writer = emit::TileWriter::new(mesh, sinks, trim);
    let mut stats = TileStats {
        skipped_inside: want.skip_inside,
        tile_size: g.tile,
        block_size: g.block,
        threads: threads as u64,
        points_decoded: declared.decoded,
        points_stored: declared.stored,
        cpu,
        extent: Some(bounds).filter(|b| b.iter().all(|v| v.is_finite())),
        ..TileStats::default()
    };
    let (mut read, mut kept) = (0u64, 0u64);
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    // Memory for tiles' runs in flight and their outputs waiting to be written.
    let budget = {
        let per_block = index.len() as f64 / index.blocks().max(1) as f64;
        let blocks = f64::from(1u32 << index.grid.shift.min(15));
        // A tile's first run: its blocks and a buffer of one block around.
        let run = (per_block * (blocks + 2.0).powi(2) * RUN_BYTES_PER_POINT).max(1.0) as u64;
        let free = job.mem.saturating_sub(shares + index.memory_bytes());
        Budget::new(free, run, threads)
    };
    stats.window = budget.runs as u64;
    let (tx, rx) = crossbeam_channel::unbounded::<(usize, (Result<TileOutput>, u64))>();
    let task = task.as_ref();
    let policy = job.duplicates;
    let total = order.len();
    let result = std::thread::scope(|scope| -> Result<()> {
        let rx = rx;
        for _ in 0..threads {
            let (tx, budget, next, stop, order, index, want) =
                (tx.clone(), &budget, &next, &stop, &order, &index, &want);
            scope.spawn(move || {
                while budget.take(budget.run) {
                    if stop.load(Ordering::Relaxed) {
                        break;
                    }
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= order.len() {
                        break;
                    }
                    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        worker::run_tile(index, order[i], policy, FIRST_BUFFER, task, lines, want)
                    }))
                    .unwrap_or_else(|p| Err(Error::panicked("tile worker", &*p)));
                    // The run's memory is free; its output waits to be written.
                    let held = r.as_ref().map_or(0, TileOutput::heap_bytes).min(budget.run);
                    budget.give(budget.run - held);
                    if tx.send((i, (r, held))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let mut pending = std::collections::BTreeMap::new();
        let mut done = 0usize;
        let writer_cpu = crate::clock::thread_cpu();
        let mut row = order.first().map(|t| t.1);
        let outcome = (|| -> Result<()> {
            while done < total {
                let (i, r) = rx.recv().map_err(|_| {
                    Error::Internal("a tile worker stopped without a result".into())
                })?;
                pending.insert(i, r);
                while let Some((r, held)) = pending.remove(&done) {
                    let t = r?;
                    if row != Some(t.tile.1) {
                        writer.watermark(g.world(&g.tile_blocks(t.tile.0, t.tile.1))[1])?;
                        row = Some(t.tile.1);
                        crate::sort::mmap::release_free_memory_above(job.mem);
                    }
                    writer.tile(&t)?;
                    read += t.points_read;
                    kept += t.points_kept;
                    stats.tiles += 1;
                    stats.reruns += u64::from(t.runs.saturating_sub(1));
                    stats.loaded_points += t.loaded_points;
                    stats.max_buffer = stats.max_buffer.max(t.buffer_blocks as f64 * g.block);
                    stats.cpu.add(&t.cpu);
                    done += 1;
                    progress("triangulating", done as u64, total as u64);
                    budget.give(held);
                }
            }
            Ok(())
        })();
        stats.cpu.write = crate::clock::thread_cpu() - writer_cpu;
        if outcome.is_err() {
            stop.store(true, Ordering::Relaxed);
        }
        // Workers waiting for memory, or to send a result, see the budget or channel closed.
        budget.close();
        drop(rx);
        outcome
    });
    result?;
    if lines.is_none() && options.scope.is_none() {
        stats.uncertified_owned = writer.account(&index, kept, want.skip_inside)?;
    }
    if writer.pending() != 0 {
        return Err(Error::Internal(format!(
            "{} vertices were left waiting for triangles after the last tile",
            writer.pending()
        )));
    }
    // A task may own no triangle (its points all belong to triangles of other tasks).
    if writer.triangles == 0 && options.scope.is_none() {
        return Err(if writer.trimmed > 0 {
            Error::trimmed_all(writer.trimmed)
        } else if kept < 3 {
            Error::TooFewPoints {
                distinct: kept,
                total: read,
            }
        } else {
            Error::AllCollinear { distinct: kept }
        });
    }
    Ok(TiledRun {
        points_read: read,
        points_kept: kept,
        triangles: writer.triangles,
        trimmed: writer.trimmed,
        vertices: writer.vertices,
        sort: crate::sort::external::SortStats::default(),
        tiles: stats,
        crs: declared.crs,
        warnings: declared.warnings,
        read_sort,
    })
}
