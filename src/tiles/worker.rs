//! One tile: read the blocks of its buffered extent, triangulate them in memory, certify, grow the
//! buffer until everything the tile owns is certified, and keep what it owns.
//!
//! **Ownership.** A triangle belongs to the tile holding its lowest vertex in sweep order (least
//! `y`, then least `x`); a vertex to the tile holding it. Tiles are unions of blocks, and a point's
//! block is one function of its coordinates, so every triangle and vertex has exactly one owner.
//!
//! **When a tile is done.** Let `R` be the tile's closed rectangle. The run is accepted when every
//! triangle of the run that meets `R` is certified ([`super::certify`]) and every edge of the
//! run's convex hull whose outer half-plane meets `R` is an edge of the whole hull. Then the
//! certified triangles cover `R` as far as the whole triangulation does, so the run agrees with
//! the whole triangulation on `R`: in particular every owned triangle is there, the star of every
//! owned vertex is complete (its degree is known), and the parts of `R` outside the run's hull
//! are outside the whole hull. Otherwise the loaded rectangle grows to take in the circumdisks that
//! failed (or doubles its buffer for a hull edge or a degenerate disk) and the tile runs again.
//! When the loaded blocks hold every non-empty block, every certificate holds.

use super::certify::{Certifier, Loaded, Missing};
use super::grid::{BlockRect, TileGrid};
use super::index::BlockIndex;
use crate::error::{Error, Result};
use crate::geom::predicates::{Orientation, circumdisk_bounds, orient};
use crate::sort::DuplicatePolicy;
use crate::triangulation::{Options, triangulate};

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
    /// For each vertex: its number of triangles in the whole triangulation when this tile owns
    /// it, else [`NOT_OWNED`].
    pub degree: Vec<u32>,
    /// Points read in the owned blocks (after filters).
    pub points_read: u64,
    /// Distinct owned vertices.
    pub points_kept: u64,
    /// Runs of the tile (1 when the first buffer was enough).
    pub runs: u32,
    /// The buffer the tile ended with, in blocks (the widest side).
    pub buffer_blocks: i64,
    /// Points triangulated in the last run (owned plus buffer).
    pub loaded_points: u64,
}

/// Runs tile `(tx, ty)`, starting with a buffer of `buffer` blocks.
///
/// # Errors
/// Reading the index; [`Error::Internal`] if a run over every block still fails a certificate.
pub(crate) fn run_tile(
    index: &BlockIndex,
    tile: (i64, i64),
    policy: DuplicatePolicy,
    buffer: i64,
) -> Result<TileOutput> {
    let g = index.grid;
    let owned = g.tile_blocks(tile.0, tile.1);
    let mut out = TileOutput {
        tile,
        ..TileOutput::default()
    };
    out.points_read = index.count(&owned);
    if out.points_read == 0 {
        return Ok(out);
    }
    let occ = index.occupied();
    let mut loaded = Loaded {
        rect: owned.expand(buffer.max(0)).intersect(&occ),
        extra: Vec::new(),
    };
    let mut pts = Vec::new();
    loop {
        out.runs += 1;
        pts.clear();
        index.read(&loaded.rect, &mut pts)?;
        for &k in &loaded.extra {
            index.read_block(k, &mut pts)?;
        }
        let own = pts.len();
        // Corners of the whole hull from blocks not read: they make the run's hull the whole hull.
        for p in index.hull() {
            let (bx, by) = g.block_of(p[0], p[1]);
            if !loaded.contains(TileGrid::key(bx, by), bx, by) {
                pts.push(*p);
            }
        }
        let full = loaded.rect.contains_rect(&occ);
        let tri = match triangulate(&pts, &Options { duplicates: policy }) {
            Ok(t) => Some(t),
            Err(Error::TooFewPoints { .. } | Error::AllCollinear { .. }) if !full => None,
            Err(e) => return Err(e),
        };
        let grow = match &tri {
            None => Grow::Double,
            Some(_) if full => Grow::Done,
            Some(t) => check(index, t, &owned, &loaded, own)?,
        };
        let before = loaded.clone();
        if std::env::var_os("SWEEPTIN_DEBUG_TILES").is_some() {
            let what = match &grow {
                Grow::Done => "done".to_string(),
                Grow::Blocks(m) => format!(
                    "missing {} blocks, e.g. {:?}",
                    m.len(),
                    m.iter()
                        .take(3)
                        .map(|&k| TileGrid::unkey(k))
                        .collect::<Vec<_>>()
                ),
                Grow::Double => "double".into(),
            };
            eprintln!(
                "tile {tile:?} run {}: {} points ({} extra blocks) rect {:?}: {what}",
                out.runs,
                pts.len(),
                loaded.extra.len(),
                loaded.rect
            );
        }
        match grow {
            Grow::Done => {
                let t = tri.expect("a triangulation was checked");
                keep(index, &t, &owned, &mut out);
                out.loaded_points = own as u64;
                out.buffer_blocks = buffer_of(&owned, &loaded.rect);
                return Ok(out);
            }
            Grow::Blocks(m) => loaded.extra = with_neighbours(index, &loaded, m),
            Grow::Double => {
                let b = buffer_of(&owned, &loaded.rect);
                loaded.rect = owned.expand(2 * b + 1).union(&loaded.rect).intersect(&occ);
                let rect = loaded.rect;
                loaded.extra.retain(|&k| {
                    let (bx, by) = TileGrid::unkey(k);
                    !rect.contains(bx, by)
                });
            }
        }
        if loaded == before {
            if full {
                return Err(Error::Internal(format!(
                    "tile {tile:?}: a run over all the points failed a certificate"
                )));
            }
            loaded.rect = occ;
            loaded.extra.clear();
        }
    }
}

/// The extra blocks of the next run: those already read outside the rectangle, the blocks `m`
/// that withheld certificates, and their non-empty neighbours (so that the triangles near them
/// are right at the next try).
fn with_neighbours(index: &BlockIndex, loaded: &Loaded, m: Missing) -> Vec<u64> {
    let mut out = loaded.extra.clone();
    for &k in &m {
        let (bx, by) = TileGrid::unkey(k);
        for ny in by - 1..=by + 1 {
            out.extend_from_slice(index.keys_in_row(ny, bx - 1, bx + 2));
        }
    }
    out.sort_unstable();
    out.dedup();
    out.retain(|&k| {
        let (bx, by) = TileGrid::unkey(k);
        !loaded.rect.contains(bx, by)
    });
    out
}

/// The widest side of the buffer of `loaded` around `owned`, in blocks.
fn buffer_of(owned: &BlockRect, loaded: &BlockRect) -> i64 {
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

/// The outcome of checking a run.
enum Grow {
    /// Everything the tile owns is certified.
    Done,
    /// Read these blocks too.
    Blocks(Missing),
    /// Double the buffer.
    Double,
}

/// Is the run `t` over the `loaded` blocks certified on the tile `owned`?
fn check(
    index: &BlockIndex,
    t: &crate::Triangulation,
    owned: &BlockRect,
    loaded: &Loaded,
    own: usize,
) -> Result<Grow> {
    let g = index.grid;
    let cert = Certifier::new(index, loaded);
    let w = g.world(owned);
    let mag = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let m = g.margin(mag);
    let r = [w[0] - m, w[1] - m, w[2] + m, w[3] + m];
    let v = &t.vertices;
    let corners = [[r[0], r[1]], [r[2], r[1]], [r[2], r[3]], [r[0], r[3]]];
    let mut missing = Missing::new();
    for tri in &t.triangles {
        let [a, b, c] = tri.map(|i| [v[i as usize][0], v[i as usize][1]]);
        let (x0, x1) = (a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]));
        let (y0, y1) = (a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
        if x1 < r[0] || x0 > r[2] || y1 < r[1] || y0 > r[3] {
            continue;
        }
        let within = x0 >= r[0] && x1 <= r[2] && y0 >= r[1] && y1 <= r[3];
        if !within && separated([a, b, c], &corners) {
            continue;
        }
        // A hull corner whose block was not read (they come after the `own` points read): its
        // height may not be the one the duplicate policy keeps, so the triangle waits for the
        // block.
        for &i in tri {
            if t.input_index[i as usize] as usize >= own {
                let p = v[i as usize];
                let (bx, by) = g.block_of(p[0], p[1]);
                missing.push(TileGrid::key(bx, by));
            }
        }
        match circumdisk_bounds(a, b, c) {
            Some(d) => {
                let before = missing.len();
                cert.disk_clear(d.center, d.radius, &mut missing);
                if missing.len() - before > 1000
                    && std::env::var_os("SWEEPTIN_DEBUG_TILES").is_some()
                {
                    eprintln!(
                        "  big disk r={} at {:?}: {:?} {:?} {:?} ({} blocks)",
                        d.radius,
                        d.center,
                        a,
                        b,
                        c,
                        missing.len() - before
                    );
                }
            }
            None => {
                if std::env::var_os("SWEEPTIN_DEBUG_TILES").is_some() {
                    eprintln!("  degenerate disk: {a:?} {b:?} {c:?}");
                }
                return Ok(Grow::Double);
            }
        }
    }
    Ok(if missing.is_empty() {
        Grow::Done
    } else {
        Grow::Blocks(missing)
    })
}

/// Does an edge line of the counter-clockwise triangle `t` have every corner of a rectangle
/// strictly outside? (Then they do not meet: the exact half of the separating-axis test, the
/// bounding boxes being the other half.)
fn separated(t: [[f64; 2]; 3], corners: &[[f64; 2]; 4]) -> bool {
    (0..3).any(|i| {
        let (p, q) = (t[i], t[(i + 1) % 3]);
        corners
            .iter()
            .all(|&c| orient(p, q, c) == Orientation::Clockwise)
    })
}

/// Fills `out` with the owned triangles of the accepted run `t`.
fn keep(index: &BlockIndex, t: &crate::Triangulation, owned: &BlockRect, out: &mut TileOutput) {
    let g = index.grid;
    let n = t.vertices.len();
    // Clearly inside or outside the tile's rectangle, or else by the block function itself.
    let w = g.world(owned);
    let m = g.margin(w.iter().fold(0.0f64, |m, v| m.max(v.abs())));
    let is_owned: Vec<bool> = t
        .vertices
        .iter()
        .map(|p| {
            let (x, y) = (p[0], p[1]);
            if x > w[0] + m && x < w[2] - m && y > w[1] + m && y < w[3] - m {
                true
            } else if x < w[0] - m || x > w[2] + m || y < w[1] - m || y > w[3] + m {
                false
            } else {
                let (bx, by) = g.block_of(x, y);
                owned.contains(bx, by)
            }
        })
        .collect();
    let mut degree = vec![0u32; n];
    let mut foreign = vec![false; n];
    for tri in &t.triangles {
        let low = tri[0].min(tri[1]).min(tri[2]) as usize;
        for &i in tri {
            degree[i as usize] += 1;
            if !is_owned[low] {
                foreign[i as usize] = true;
            }
        }
    }
    let mut map = vec![u32::MAX; n];
    let mut add = |i: usize, out: &mut TileOutput| -> u32 {
        if map[i] == u32::MAX {
            map[i] = out.vertices.len() as u32;
            out.vertices.push(t.vertices[i]);
            out.degree
                .push(if is_owned[i] { degree[i] } else { NOT_OWNED });
        }
        map[i]
    };
    for tri in &t.triangles {
        let low = tri[0].min(tri[1]).min(tri[2]) as usize;
        if is_owned[low] {
            let o = tri.map(|i| add(i as usize, out));
            out.triangles.push(o);
        }
    }
    for i in 0..n {
        if is_owned[i] && foreign[i] {
            add(i, out);
        }
    }
    out.points_kept = is_owned.iter().filter(|&&o| o).count() as u64;
}
