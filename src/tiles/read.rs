//! Reading for the tiles: every point of the files (filters applied) decoded once, sorted by
//! block into the block index, with the CRS and the headers' warnings; breaklines added to it.

use super::grid::{MAX_SHIFT, TileGrid, pow2, side_for};
use super::{hull, lines};
use super::index::{self, BlockIndex, BlockRecord, IndexRecord, PackedRecord, Packing};
use super::{BLOCK_POINTS, MAX_BLOCKS, TILE_BLOCKS, TaskScope, TileCpu, TileJob, TileOptions};
use crate::error::Result;
use crate::input::las::{ChunkIndex, LidarPoint, LidarReader, ReadOptions};
use crate::input::spread::Spread;
use crate::sort::external::ExternalSorter;
use std::time::Instant;

/// Reads the LAS/LAZ files of `job` into a block index.
pub(super) fn read_index(
    job: &TileJob,
    options: &TileOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(BlockIndex, Declared, [f64; 4], TileCpu)> {
    let scope = options.scope.as_ref();
    let (mut reader, mut outside, by_area) = open_for(job, scope)?;
    // The data's hull band (a plan's): its points beyond the area, as read points.
    let band = by_area.and_then(|a| Some((scope?.band.as_deref()?, a)));
    let extra: Vec<[f64; 3]> = band.map_or_else(Vec::new, |(h, a)| {
        h.points
            .iter()
            .filter(|c| !(c[0] >= a[0] && c[0] <= a[2] && c[1] >= a[1] && c[1] <= a[3]))
            .copied()
            .collect()
    });
    let b = reader.bounds();
    let total = reader.point_count();
    let area = ((b.max[0] - b.min[0]) * (b.max[1] - b.min[1])).max(f64::MIN_POSITIVE);
    let base = options.base.unwrap_or(1.0);
    // Over the boxes that say where their points are, those points (files whose box says
    // nothing would make the density look higher).
    let density = reader.points_in_header_boxes() as f64 / area;
    let block_points = block_points(total);
    let tile_points = block_points * TILE_BLOCKS;
    let rect = [b.min[0], b.min[1], b.max[0], b.max[1]];
    // Blocks no finer than their keys allow (coordinates far from 0: at 10^15, blocks of half
    // a million units), whatever the density; a density from a box of no area (one point, or
    // points on one line) is no reason to fail here: the triangulation says what is wrong.
    let finest = TileGrid::min_block(rect);
    let block = match options.tile {
        Some(t) => {
            let k = side_for(base, density, block_points);
            let s = ((t / pow2(base, k)).log2().round().max(0.0) as u32).min(12);
            let most = (t / finest).log2().floor().clamp(0.0, 12.0) as u32;
            t / f64::from(1u32 << s.min(most))
        }
        None => {
            // At least the base over 2^MAX_SHIFT: a tile is at least the base, and at most
            // 2^MAX_SHIFT blocks a side.
            let mut k = side_for(base, density, block_points).max(-(MAX_SHIFT as i32));
            while pow2(base, k) < finest && k < 1000 {
                k += 1;
            }
            pow2(base, k)
        }
    };
    let probe = TileGrid::new(block, 0)?;
    probe.check_bounds(rect)?;
    let mut declared = Declared {
        crs: reader.crs().cloned(),
        warnings: reader.warnings(),
        decoded: 0,
        stored: 0,
    };
    let packing = reader.lattice().and_then(|l| Packing::new(l, &probe));
    // The plan's point store in place of the LAZ file, when every block lies in one of its cells.
    let store = match (scope.and_then(|s| s.store.as_deref()), by_area) {
        (Some(s), Some(a)) if s.nests(block) => Some((s, a)),
        _ => None,
    };
    let mut from = Points { reader: &mut reader, store, read: None };
    let (mut index, spread, cpu) = match packing {
        Some(_) => index_points::<PackedRecord>(&mut from, probe, packing, job, &extra, progress)?,
        None => index_points::<BlockRecord>(&mut from, probe, None, job, &extra, progress)?,
    };
    if let Some(r) = from.read {
        outside = r.unread;
        declared.stored = r.scanned;
    }
    declared.decoded = reader.stats().read;
    let bounds = spread.extent();
    if let Some(far) = spread.far_points() {
        declared.warnings.push(far.warning());
    }
    if let Some(sc) = scope {
        index.scope = Some(index::Scope {
            unknown: sc.unread.clone(),
            beyond: outside,
            tile: sc.tile,
            buffer: sc.buffer,
            hull: band.map(|(h, _)| h.hull.clone()),
            inner: band.map(|(h, _)| h.inner.clone()),
        });
    }
    // The tile: as given, or about `tile_points` at the density over the non-empty blocks; for
    // a task, its plan tile halved until it holds about `tile_points`.
    let tile = match options.tile {
        Some(t) if scope.is_some() => {
            let covered = index.blocks().max(1) as f64 * block * block;
            let d = index.len() as f64 / covered;
            let mut sub = t;
            while sub / 2.0 >= block && sub / 2.0 >= base && sub * sub * d > 2.0 * tile_points {
                sub /= 2.0;
            }
            sub
        }
        Some(t) => t,
        None => {
            let covered = index.blocks().max(1) as f64 * block * block;
            let d = index.len() as f64 / covered;
            let k = side_for(block, d, tile_points).clamp(0, 12);
            // A whole multiple of the base (blocks may be finer than the base).
            let mut t = pow2(block, k);
            while t < base {
                t *= 2.0;
            }
            t
        }
    };
    let shift = (tile / block).log2().round() as u32;
    index.grid = TileGrid::new(tile, shift)?;
    debug_assert_eq!(index.grid.block, block);
    Ok((index, declared, bounds, cpu))
}

/// What the files' headers declare: the CRS and the warnings.
pub(super) struct Declared {
    pub crs: Option<crate::crs::Crs>,
    pub warnings: Vec<String>,
    /// Points decoded from the files ([`super::TileStats::points_decoded`]).
    pub decoded: u64,
    /// Points read from the plan's point store ([`super::TileStats::points_stored`]).
    pub stored: u64,
}

/// Where a run's points come from: the reader, or a plan's point store over the area read.
struct Points<'a> {
    reader: &'a mut LidarReader,
    store: Option<(&'a super::store::PointStore, [f64; 4])>,
    /// What the store read.
    read: Option<super::store::AreaRead>,
}

/// Reads every point of `reader` into the block index's sort as records `R` (packed with
/// `packing`, or wide), and builds the index: with what [`Spread`] saw of the points (their
/// bounding box, far points) and the CPU time of both steps.
fn index_points<R: IndexRecord>(
    from: &mut Points,
    grid: TileGrid,
    packing: Option<Packing>,
    job: &TileJob,
    extra: &[[f64; 3]],
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(BlockIndex, Spread, TileCpu)> {
    let total = from.reader.point_count();
    let t0 = Instant::now();
    let c0 = crate::clock::process_cpu();
    let budget = index_sort_budget(job.mem, total, std::mem::size_of::<R>());
    let mut sorter = ExternalSorter::<R>::new(budget, job.tmp);
    let mut spread = Spread::default();
    match from.store {
        Some((store, area)) => {
            from.read = Some(store.read_area(area, |buf, done| {
                for &[x, y, z] in buf {
                    spread.add(x, y);
                    sorter.push(R::pack(packing.as_ref(), grid.block_of(x, y), [x, y, z])?)?;
                }
                progress(done.min(total), total);
                Ok(())
            })?);
        }
        None => prefetched(from.reader, |buf, done| {
            for p in buf {
                let (x, y) = (p.x, p.y);
                spread.add(x, y);
                sorter.push(R::pack(packing.as_ref(), grid.block_of(x, y), [x, y, p.z])?)?;
            }
            progress(done, total);
            Ok(())
        })?,
    }
    let reader = &*from.reader;
    for p in extra {
        sorter.push(R::pack(packing.as_ref(), grid.block_of(p[0], p[1]), *p)?)?;
    }
    let t_read = Instant::now();
    let merge = sorter.finish()?;
    let c1 = crate::clock::process_cpu();
    let t_fin = Instant::now();
    let index = BlockIndex::build(grid, merge, packing, job.tmp, job.duplicates)?;
    let cpu = TileCpu {
        read_sort: c1 - c0,
        decode: reader.decode_cpu(),
        index: crate::clock::process_cpu() - c1,
        ..TileCpu::default()
    };
    if std::env::var_os("SWEEPTIN_DEBUG_PHASES").is_some() {
        eprintln!(
            "phase1: read {:?} finish {:?} build {:?} (packed: {})",
            t_read - t0,
            t_fin - t_read,
            t_fin.elapsed(),
            packing.is_some()
        );
    }
    Ok((index, spread, cpu))
}

/// Opens the files of `job`. A task of a plan whose files are all COPC, or all plain files with
/// a chunk index whose chunks meeting the task's tile and buffer hold at most half of the
/// points ([`pays_to_read_by_area`]), reads only the points of its tile and buffer and returns
/// where the points it did not read may lie ([`unread_of`]), like the files it does not read at
/// all. Other tasks keep every point of their files (decoding LAZ costs the same whatever is
/// kept, and the points farther out settle the triangles along the data's edge without another
/// run), unless their scope reads by area ([`TaskScope::by_area`]: `--ground`).
#[allow(clippy::type_complexity)]
fn open_for(
    job: &TileJob,
    scope: Option<&TaskScope>,
) -> Result<(LidarReader, Vec<[f64; 4]>, Option<[f64; 4]>)> {
    if let Some(sc) = scope {
        let infos = job
            .paths
            .iter()
            .map(crate::input::las::FileInfo::read)
            .collect::<Result<Vec<_>>>()?;
        let (t, b) = (sc.tile, sc.buffer);
        let area = [t[0] - b, t[1] - b, t[2] + b, t[3] + b];
        // A COPC file whose header box says nothing is read whole (its box cannot say what
        // lies outside the area); a plain LAZ/LAS file is read by area with its chunk index.
        let indexed = |i: &crate::input::las::FileInfo| {
            i.copc.is_some() || sc.chunks.iter().any(|(p, _)| *p == i.path)
        };
        let known = infos.iter().all(|i| i.known_rect().is_some());
        if sc.by_area && !known {
            return Err(crate::error::Error::Options(
                "a task that reads only its area (--ground) needs every file's header extent: \
                 one says nothing (rewrite the file with a true header)"
                    .into(),
            ));
        }
        if !infos.is_empty()
            && known
            && (sc.by_area
                || sc.store.is_some()
                || infos.iter().all(indexed)
                    && (infos.iter().all(|i| i.copc.is_some())
                        || pays_to_read_by_area(&sc.chunks, area)))
            && let Some(bbox) = crate::input::las::BBox::new(area[0], area[1], area[2], area[3])
        {
            let options = ReadOptions {
                area: Some(bbox),
                chunks: sc.chunks.clone(),
                crs: job.crs.cloned(),
                ..ReadOptions::for_budget(job.mem)
            };
            let reader = LidarReader::open_with(job.paths, job.filter, options)?;
            let outside = infos.iter().flat_map(|i| unread_of(i, sc, area)).collect();
            return Ok((reader, outside, Some(area)));
        }
    }
    let options = ReadOptions {
        crs: job.crs.cloned(),
        ..ReadOptions::for_budget(job.mem)
    };
    let reader = LidarReader::open_with(job.paths, job.filter, options)?;
    Ok((reader, Vec::new(), None))
}

/// Where points of the file `i` that a read of `area` skips may lie: the boxes of its chunks
/// that do not meet `area` and the parts outside `area` of those that do (a chunk index
/// bounds every chunk's points), else the file's extent outside `area`. Along the data's edge
/// the hull's long triangles then reach only where chunks are, not the whole extent.
fn unread_of(i: &crate::input::las::FileInfo, sc: &TaskScope, area: [f64; 4]) -> Vec<[f64; 4]> {
    match sc.chunks.iter().find(|(p, _)| *p == i.path) {
        Some((_, ix)) if i.copc.is_none() => ix
            .boxes()
            .flat_map(|(r, _)| {
                if meets(&r, &area) {
                    outside_of(r, area)
                } else {
                    vec![r]
                }
            })
            .collect(),
        _ => outside_of(i.rect(), area),
    }
}

/// Whether reading plain files by area through their chunk indexes `chunks` saves work: when
/// the chunks that meet `area` hold at most half of the files' points. Chunks in acquisition
/// order are long strips, and a task that decodes most of them anyway is better off with every
/// point: the points beyond its area settle the triangles along the data's edge, where a read
/// by area may run again with a wider buffer (decoding again). Both ways give the same output.
fn pays_to_read_by_area(chunks: &[(std::path::PathBuf, std::sync::Arc<ChunkIndex>)], area: [f64; 4]) -> bool {
    let (mut all, mut near) = (0u64, 0u64);
    for (_, ix) in chunks {
        for (r, n) in ix.boxes() {
            all += n;
            if meets(&r, &area) {
                near += n;
            }
        }
    }
    2 * near <= all
}

/// Do the closed rectangles `a` and `b` meet?
pub(super) fn meets(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] && a[2] >= b[0] && a[1] <= b[3] && a[3] >= b[1]
}

/// The parts of the closed rectangle `e` outside the closed rectangle `a`, as at most four closed
/// rectangles (sharing `a`'s edges: points on them are read, and counted as unknown too).
pub(super) fn outside_of(e: [f64; 4], a: [f64; 4]) -> Vec<[f64; 4]> {
    let mut out = Vec::new();
    if e[1] < a[1] {
        out.push([e[0], e[1], e[2], a[1].min(e[3])]);
    }
    if e[3] > a[3] {
        out.push([e[0], a[3].max(e[1]), e[2], e[3]]);
    }
    let (y0, y1) = (e[1].max(a[1]), e[3].min(a[3]));
    if y0 <= y1 {
        if e[0] < a[0] {
            out.push([e[0], y0, a[0].min(e[2]), y1]);
        }
        if e[2] > a[2] {
            out.push([a[2].max(e[0]), y0, e[2], y1]);
        }
    }
    out
}

/// The breaklines `p` of a run over `index`: their vertices' `z` settled against the points
/// (`--duplicates`), their blocks occupied, the hull of points and vertices as the index's hull.
pub(super) fn with_lines(
    index: &mut BlockIndex,
    p: &crate::breaklines::Pslg,
    policy: crate::DuplicatePolicy,
) -> Result<lines::TileLines> {
    let g = index.grid;
    let mut l = lines::TileLines::new(&p.vertices, &p.segments);
    if let Some(b) = l.bounds() {
        g.check_bounds(b)?;
    }
    l.merge(index, policy)?;
    let mut corners: Vec<[f64; 3]> = index.hull().to_vec();
    corners.extend_from_slice(&l.vertices);
    let mut h = hull::hull(&mut corners);
    // A corner at a vertex's position has the vertex's (settled) z.
    for c in &mut h {
        if let Some(z) = l.z_at([c[0], c[1]]) {
            c[2] = z;
        }
    }
    index.add_lines(l.blocks(&g), h);
    Ok(l)
}

/// Points per batch handed from the reader's thread.
const BATCH: usize = 1 << 16;

/// Reads every point of `reader` on a thread of its own, a few batches ahead, and hands each
/// batch to `f` with the points read (or skipped) so far: decoding (on every core) goes on while
/// `f` works (the sort's chunks are sorted and spilled meanwhile).
pub(crate) fn prefetched(
    reader: &mut LidarReader,
    mut f: impl FnMut(&[LidarPoint], u64) -> Result<()>,
) -> Result<()> {
    let (full_tx, full_rx) = crossbeam_channel::bounded::<Result<(Vec<LidarPoint>, u64)>>(2);
    let (free_tx, free_rx) = crossbeam_channel::bounded::<Vec<LidarPoint>>(4);
    std::thread::scope(|scope| {
        scope.spawn(move || {
            loop {
                let mut buf = free_rx
                    .try_recv()
                    .unwrap_or_else(|_| Vec::with_capacity(BATCH));
                buf.clear();
                let r = reader.read_chunk(&mut buf, BATCH).map(|n| {
                    let s = reader.stats();
                    (n, s.read + s.skipped)
                });
                let (stop, msg) = match r {
                    Ok((0, _)) => (true, None),
                    Ok((_, done)) => (false, Some(Ok((buf, done)))),
                    Err(e) => (true, Some(Err(e))),
                };
                if let Some(m) = msg
                    && full_tx.send(m).is_err()
                {
                    break;
                }
                if stop {
                    break;
                }
            }
        });
        // Dropped on an error before the scope waits for the reader, which then stops.
        let (rx, free) = (full_rx, free_tx);
        for m in rx.iter() {
            let (buf, done) = m?;
            f(&buf, done)?;
            let _ = free.try_send(buf);
        }
        Ok(())
    })
}

/// Runs the block index's sort aims at: halves of about a sixteenth of the input (a radix sort's
/// budget is three halves).
const INDEX_RUNS: u64 = 16;

/// The smallest budget of the block index's sort (halves of about 2.7 MB).
const MIN_INDEX_SORT: u64 = 8 << 20;

/// The block index's sort budget: half of `mem`, or less when the input (`points` of `record`
/// bytes, the count from the headers) would fill fewer than [`INDEX_RUNS`] halves. Small halves
/// are sorted and spilled while decoding goes on; a few large ones (or one vector sorted after
/// the last point) leave that work to the end, with nothing beside it: ARSO (13.2 M points, 32-byte
/// records) at `--mem 1G` took 6.9 s and 555 MB against 6.0 s and 107 MB at `--mem 128M`. The
/// order of the records is the same whatever the budget.
pub(super) fn index_sort_budget(mem: u64, points: u64, record: usize) -> u64 {
    let bytes = points.saturating_mul(record as u64);
    (mem / 2).min((bytes / INDEX_RUNS * 3).max(MIN_INDEX_SORT))
}

/// Points per block: [`BLOCK_POINTS`], or more for inputs so large that the block table would
/// pass [`MAX_BLOCKS`]. A function of the input's point count only (the output must not depend
/// on anything else).
fn block_points(total: u64) -> f64 {
    BLOCK_POINTS.max(total as f64 / MAX_BLOCKS)
}
