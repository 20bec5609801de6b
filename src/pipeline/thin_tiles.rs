//! `sweeptin thin --tile T`: the thinning per tile of a fixed grid, in memory bounded by one
//! tile's points (the geometry and its guarantees: [`mod@crate::simplify::thin_tiles`]).
//!
//! 1. **Borders.** The `tin` pipeline (bounded by `--mem`) streams the exact Delaunay TIN of all
//!    the points into a [`Sections`] sink: the TIN along every grid line. Each line is
//!    simplified in 1-D into the border vertices the tiles on both sides share.
//! 2. **Routing.** A second read puts every point (after filters) into an external sort by
//!    (tile, y, x, input order) — fixed-size records, spilled to anonymous temporary files
//!    beyond a quarter of `--mem` — so that each tile's points come out together; duplicates
//!    are merged per tile by `--duplicates` (a tile holds every copy of its positions).
//! 3. **Tiles.** Tiles come out in row-major order (every tile with points, and every tile
//!    that has border vertices, so that gaps in the data are triangulated as in one run); as
//!    many as fit in half of `--mem` (and at least one per thread) are thinned at once on every
//!    core, then written in tile order: vertices on a tile's boundary lines once, by the first
//!    tile that writes them (their numbers kept while a later tile can use them).
//!
//! The output depends only on the points, the tolerance and `T`.

use super::RunConfig;
use super::config::Source;
use super::thin::{THIN_BYTES_PER_POINT, ThinSummary, check_point};
use crate::error::{Error, Result};
use crate::simplify::thin::KEPT_BYTES;
use crate::simplify::thin_tiles::{Borders, Sections, TileLines, TileThinned};
use crate::simplify::{ThinOptions, ThinStats};
use crate::sink::MeshSink;
use crate::sort::external::{Dedup, ExternalSorter, SortKey, SortRecord};
use crate::validate::MeshKind;
use rayon::prelude::*;
use std::collections::{BTreeSet, HashMap};
use std::time::Instant;

/// Bytes a tile's thinning may take per point, for fitting tiles into `--mem`: the reading
/// peak, and the kept TIN when an eighth of the points is kept.
pub const TILE_BYTES_PER_POINT: u64 = THIN_BYTES_PER_POINT + KEPT_BYTES / 8;

/// What the tiles of `sweeptin thin --tile` did (part of its `--json` summary).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ThinTileSummary {
    /// The tile side.
    pub tile: f64,
    /// Tiles thinned (with points or border vertices).
    pub tiles: u64,
    /// Border vertices written that are not input points (Steiner points on the grid lines).
    pub border_points: u64,
    /// Points of the largest tile.
    pub largest_tile_points: u64,
    /// Bytes the routing sort spilled to temporary files (0: it fit in its quarter of --mem).
    pub spilled_bytes: u64,
    /// Seconds computing the borders (the exact TIN's pass and the 1-D simplification).
    pub border_seconds: f64,
    /// Seconds reading and sorting the points into tiles.
    pub route_seconds: f64,
    /// Seconds thinning and writing the tiles.
    pub thin_seconds: f64,
}

/// A point on its way to its tile: packed tile key (row-major), position, input order. Padded
/// to 64 bytes: the sort's sliding maps (`sort::mmap`) need a record size that divides their
/// window.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct TileRecord {
    key: u64,
    x: f64,
    y: f64,
    z: f64,
    index: u64,
    pad: [u64; 3],
}

impl SortKey for TileRecord {
    #[inline]
    fn order(a: &Self, b: &Self) -> std::cmp::Ordering {
        a.key
            .cmp(&b.key)
            .then(a.y.total_cmp(&b.y))
            .then(a.x.total_cmp(&b.x))
            .then(a.index.cmp(&b.index))
    }
    // The order is total (the input index decides last).
    const STABLE: bool = false;
}

const KEY_BIAS: i64 = 1 << 31;

fn key(tx: i64, ty: i64) -> u64 {
    (((ty + KEY_BIAS) as u64) << 32) | (tx + KEY_BIAS) as u64
}

fn unkey(k: u64) -> (i64, i64) {
    (
        (k & 0xFFFF_FFFF) as i64 - KEY_BIAS,
        (k >> 32) as i64 - KEY_BIAS,
    )
}

/// Thins the points of `config` tile by tile (tiles of side `tile`) within
/// `options.max_error`, writing the mesh to `sink` (not finished).
///
/// # Errors
/// [`Error::Options`] for a bad `--tile`, for inputs other than LAS/LAZ/COPC files, for
/// breaklines, trimming rings, `--max-edge` or `--no-flat-triangles` (not available with
/// `--tile`), or a tile that does not fit in half of `--mem`; the errors of the pipeline, the
/// readers, the sort, the thinning and the sink.
pub fn thin_tiled(
    config: &RunConfig,
    options: &ThinOptions,
    tile: f64,
    sink: &mut dyn MeshSink,
) -> Result<ThinSummary> {
    let grid = TileLines::new(tile)?;
    let input = config.input();
    if !input.lines.is_empty() || input.lines.no_flat_triangles {
        return Err(Error::Options(
            "thin --tile does not take breaklines, --trim-boundary, --holes, --max-edge or \
             --no-flat-triangles: run thin without --tile (one global run) for those"
                .into(),
        ));
    }
    if config.source() != Source::Lidar || config.stream_input().is_some() {
        return Err(Error::Options(
            "thin --tile reads LAS/LAZ/COPC files (twice): give the points as such files, or \
             run thin without --tile"
                .into(),
        ));
    }
    let mem = config.options().mem;
    let mut summary = ThinSummary {
        // The tiles' TINs are joined along the grid lines, and the points where the lines leave
        // the hull are rounded off its edges.
        mesh: MeshKind {
            trimmed: true,
            not_delaunay: true,
            ..MeshKind::default()
        },
        ..ThinSummary::default()
    };
    sink.declare(summary.mesh)?;
    let mut tiles = ThinTileSummary {
        tile,
        ..ThinTileSummary::default()
    };

    // 1. The borders, from the exact TIN.
    let start = Instant::now();
    let mut sections = Sections::new(grid, mem / 8);
    let tin = super::run(
        &config.points_only().engine_tiles(),
        None,
        &mut [&mut sections],
    )?;
    let borders = sections.borders(options, tin.points_kept)?;
    tiles.border_seconds = start.elapsed().as_secs_f64();

    // 2. Every point to its tile.
    let start = Instant::now();
    let read = crate::input::las::ReadOptions::for_budget(mem);
    let mut reader = config.open_lidar(read)?;
    let mut sorter = ExternalSorter::<TileRecord>::new(mem / 4, config.tmp_dir());
    let mut chunk = Vec::new();
    let mut index = 0u64;
    loop {
        chunk.clear();
        if reader.read_chunk(&mut chunk, 1 << 18)? == 0 {
            break;
        }
        for p in &chunk {
            let q = [p.x, p.y, p.z];
            check_point(index, q)?;
            sorter.push(TileRecord {
                key: key(grid.tile_of(q[0])?, grid.tile_of(q[1])?),
                x: q[0],
                y: q[1],
                z: q[2],
                index,
                pad: [0; 3],
            })?;
            index += 1;
        }
    }
    summary.points_read = index;
    summary.filters = Some(*reader.stats());
    summary.warnings = reader.warnings();
    summary.crs = config.input_crs()?;
    drop(reader);
    let mut merge = sorter.finish()?;
    tiles.spilled_bytes = merge.stats().spilled_bytes;
    tiles.route_seconds = start.elapsed().as_secs_f64();
    summary.read_seconds = tiles.border_seconds + tiles.route_seconds;

    // 3. The tiles, in order.
    let start = Instant::now();
    let extra = border_tiles(&borders)?;
    let mut extra = extra.into_iter().peekable();
    let mut records = merge.by_ref().peekable();
    let mut writer = Writer::default();
    let threads = rayon::current_num_threads().max(1);
    let budget = mem / 2;
    let tile_options = ThinOptions {
        mem: Some(budget),
        ..*options
    };
    let mut batch: Vec<(i64, i64, Vec<[f64; 3]>)> = Vec::new();
    let mut batch_bytes = 0u64;
    loop {
        let next = match (records.peek().map(|r| r.key), extra.peek().copied()) {
            (None, None) => None,
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let points = match next {
            Some(k) => {
                if extra.peek() == Some(&k) {
                    extra.next();
                }
                let mut group = Vec::new();
                while let Some(r) = records.next_if(|r| r.key == k) {
                    group.push(SortRecord {
                        x: r.x,
                        y: r.y,
                        z: r.z,
                        index: r.index,
                    });
                }
                let mut dedup = Dedup::new(group.into_iter(), input.duplicates);
                let pts: Vec<[f64; 3]> = dedup.by_ref().map(|r| [r.x, r.y, r.z]).collect();
                summary.duplicates += dedup.duplicates;
                Some((k, pts))
            }
            None => None,
        };
        let need = points
            .as_ref()
            .map_or(0, |(_, p)| p.len() as u64 * TILE_BYTES_PER_POINT);
        if !batch.is_empty()
            && (points.is_none() || batch.len() >= threads || batch_bytes + need > budget)
        {
            let done: Vec<Result<TileThinned>> = std::mem::take(&mut batch)
                .into_par_iter()
                .map(|(tx, ty, p)| borders.thin_tile(tx, ty, p, &tile_options))
                .collect();
            for t in done {
                let t = t?;
                writer.row(&borders, t.tile.1);
                writer.write(t, sink)?;
            }
            batch_bytes = 0;
        }
        let Some((k, pts)) = points else {
            break;
        };
        let (tx, ty) = unkey(k);
        if need > budget {
            // The densest tile decides (the rest only counted): the points of a tile go as its
            // side squared, 10 % kept in hand for denser spots of a finer grid.
            let mut most = pts.len() as u64;
            while let Some(r) = records.next() {
                let mut n = 1u64;
                while records.next_if(|q| q.key == r.key).is_some() {
                    n += 1;
                }
                most = most.max(n);
            }
            let fits = crate::error::round_down_figure(
                tile * (budget as f64 / (most * TILE_BYTES_PER_POINT) as f64).sqrt() * 0.9,
            );
            return Err(Error::Options(format!(
                "thin --tile {tile}: tile ({tx}, {ty}) holds {} points, about {} MiB to thin, \
                 more than half of --mem {} MiB: give --tile {fits} or smaller, or a larger --mem",
                pts.len(),
                need >> 20,
                mem >> 20
            )));
        }
        tiles.tiles += 1;
        tiles.largest_tile_points = tiles.largest_tile_points.max(pts.len() as u64);
        batch.push((tx, ty, pts));
        batch_bytes += need;
    }
    if let Some(e) = merge.take_error() {
        return Err(e);
    }
    tiles.thin_seconds = start.elapsed().as_secs_f64();
    tiles.border_points = writer.border_points;
    let s = &writer.stats;
    let points = s.points;
    summary.thin = ThinStats {
        kept_ratio: s.kept as f64 / points.max(1) as f64,
        line_vertices: s.vertices - s.kept,
        vertex_ratio: s.vertices as f64 / points.max(1) as f64,
        rms_error: (writer.sum_sq / points.max(1) as f64).sqrt(),
        seconds: tiles.border_seconds + tiles.route_seconds + tiles.thin_seconds,
        ..writer.stats.clone()
    };
    summary.tiles = Some(tiles);
    Ok(summary)
}

/// The tiles whose closed rectangle holds a border vertex (thinned even without points), as
/// keys.
fn border_tiles(borders: &Borders) -> Result<BTreeSet<u64>> {
    let grid = borders.grid();
    let mut out = BTreeSet::new();
    for p in borders.vertices() {
        let (tx, ty) = (grid.tile_of(p[0])?, grid.tile_of(p[1])?);
        let xs = if grid.line(tx) == p[0] { tx - 1 } else { tx };
        let ys = if grid.line(ty) == p[1] { ty - 1 } else { ty };
        for x in xs..=tx {
            for y in ys..=ty {
                out.insert(key(x, y));
            }
        }
    }
    Ok(out)
}

/// Writes tiles in order, each vertex on a grid line once.
#[derive(Debug, Default)]
struct Writer {
    /// Numbers of the border vertices written, by position.
    ids: HashMap<[u64; 2], u64>,
    next: u64,
    row: Option<i64>,
    stats: ThinStats,
    sum_sq: f64,
    border_points: u64,
    map: Vec<u64>,
}

impl Writer {
    /// A tile of row `ty` is next: forget the border vertices below it.
    fn row(&mut self, borders: &Borders, ty: i64) {
        if self.row != Some(ty) {
            let y0 = borders.grid().line(ty);
            self.ids.retain(|k, _| f64::from_bits(k[1]) >= y0);
            self.row = Some(ty);
        }
    }

    fn write(&mut self, t: TileThinned, sink: &mut dyn MeshSink) -> Result<()> {
        self.map.clear();
        for (n, &p) in t.vertices.iter().enumerate() {
            let id = if t.on_border[n] {
                let k = [p[0].to_bits(), p[1].to_bits()];
                match self.ids.get(&k) {
                    Some(&id) => {
                        self.map.push(id);
                        continue;
                    }
                    None => {
                        self.ids.insert(k, self.next);
                        self.border_points += u64::from(!t.is_point[n]);
                    }
                }
                self.next
            } else {
                self.next
            };
            sink.vertex(p)?;
            self.stats.kept += u64::from(t.is_point[n]);
            self.stats.vertices += 1;
            self.map.push(id);
            self.next += 1;
        }
        for tri in &t.triangles {
            sink.triangle(tri.map(|v| self.map[v as usize]))?;
        }
        let s = &mut self.stats;
        s.triangles += t.triangles.len() as u64;
        s.points += t.points;
        s.insertions += t.insertions;
        s.removed += t.removed;
        s.flips += t.flips;
        s.exact_tests += t.exact_tests;
        s.max_error = s.max_error.max(t.max_error);
        self.sum_sq += t.sum_sq;
        Ok(())
    }
}
