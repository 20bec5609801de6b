//! COPC (Cloud Optimized Point Cloud) files: a LAZ 1.4 file whose chunks are the nodes of an
//! octree, listed with their bounds in a hierarchy EVLR.
//!
//! A COPC file is an ordinary LAZ file (it reads as one, chunk after chunk); its index lets a
//! reader decode only the chunks whose octree node meets the area asked for. Here the info VLR
//! is read (160 bytes), the hierarchy pages are walked from the root page (which may lie anywhere
//! in the hierarchy EVLR: a reader must not assume it comes first), and every node with points is
//! tied to the LAZ chunk that holds it (same byte offset, size and point count, else the file is refused),
//! and the keys must make one octree (no node listed twice, every node with points under nodes
//! listed up to the root, counts adding up to the header's: `check_tree`; a moved key would make
//! a box read skip the node's points), so a point keeps the input index it has when the file is read as plain LAZ, and reading
//! through the index gives exactly the points, in the same order, that a plain read keeps.

use super::header::{Chunk, format_error};
use super::vlrs::Evlr;
use crate::error::Result;
use serde::Serialize;
use std::path::Path;

/// What a COPC file's info VLR and hierarchy say (shown by `sweeptin info`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CopcInfo {
    /// Centre of the octree's root cube.
    pub center: [f64; 3],
    /// Half the side of the root cube.
    pub halfsize: f64,
    /// Spacing between points at the root, halved at every level.
    pub spacing: f64,
    /// GPS time range of the points.
    pub gps_time: [f64; 2],
    /// Octree nodes that hold points.
    pub nodes: usize,
    /// Deepest level with points (the root is level 0).
    pub depth: i32,
}

/// One node with points: the LAZ chunk that holds them and the node's `[xmin, ymin, xmax, ymax]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Node {
    pub(crate) chunk: usize,
    /// The node's key: level, x, y, z.
    pub(crate) key: [i32; 4],
    pub(crate) rect: [f64; 4],
}

/// The COPC index of a file, when its first VLR is a COPC info VLR: the summary and one node per
/// chunk, in chunk order. `Ok(None)` for files that are not COPC. `evlrs` are the file's EVLRs,
/// with the payloads of the hierarchy ones.
///
/// # Errors
/// [`crate::Error::Format`] when the hierarchy is missing, damaged, does not make one octree (a
/// key listed twice, outside the octree or its page's branch, a node with points whose parent
/// is not listed, counts that do not add up to the header's `points`), or does not match the
/// LAZ chunk table (a node at a byte offset where no chunk starts, or with another size or
/// count).
pub(crate) fn index(
    path: &Path,
    header: &las::Header,
    evlrs: &[Evlr],
    chunks: &[Chunk],
    points: u64,
) -> Result<Option<(CopcInfo, Vec<Node>)>> {
    let Some(first) = header
        .vlrs()
        .first()
        .filter(|v| v.user_id == "copc" && v.record_id == 1)
    else {
        return Ok(None);
    };
    let bad = |what: String| format_error(path, format!("invalid COPC file: {what}"));
    let d = &first.data;
    if d.len() < 160 {
        return Err(bad(format!("the info VLR has {} bytes, not 160", d.len())));
    }
    let f64_at = |i: usize| f64::from_le_bytes(d[8 * i..8 * i + 8].try_into().unwrap_or_default());
    let u64_at = |i: usize| u64::from_le_bytes(d[8 * i..8 * i + 8].try_into().unwrap_or_default());
    let (center, halfsize, spacing) = ([f64_at(0), f64_at(1), f64_at(2)], f64_at(3), f64_at(4));
    let (root_at, root_len) = (u64_at(5), u64_at(6));
    // The hierarchy pages lie in EVLRs `copc`/1000 (one, or one per page as copclib writes
    // them), found by their file offsets.
    let hierarchy: Vec<(u64, &Vec<u8>)> = evlrs
        .iter()
        .filter_map(|e| Some((e.at, e.data.as_ref()?)))
        .collect();
    if hierarchy.is_empty() {
        return Err(bad("the hierarchy EVLR is missing".into()));
    }
    let total: usize = hierarchy.iter().map(|(_, d)| d.len()).sum();
    let page = |offset: u64, len: u64| -> Result<&[u8]> {
        hierarchy
            .iter()
            .find_map(|(data_at, data)| {
                let s = usize::try_from(offset.checked_sub(*data_at)?).ok()?;
                data.get(s..s.checked_add(usize::try_from(len).ok()?)?)
            })
            .filter(|p| p.len() % 32 == 0)
            .ok_or_else(|| {
                bad(format!(
                    "a hierarchy page ({len} bytes at byte {offset}) lies outside the hierarchy \
                     EVLRs"
                ))
            })
    };
    // Every entry of the pages reached from the root page, each with the key of the page's
    // own node (the root page's is the root's): a node's key, byte offset, size and count.
    let mut entries: Vec<([i32; 4], u64, i32, i32)> = Vec::new();
    let mut pages = vec![(page(root_at, root_len)?, ROOT)];
    let mut seen_pages = 0usize;
    while let Some((p, page_key)) = pages.pop() {
        seen_pages += 1;
        if seen_pages > total / 32 + 1 {
            return Err(bad(
                "the hierarchy pages refer to each other in a loop".into()
            ));
        }
        for e in p.chunks_exact(32) {
            let i32_at = |o: usize| i32::from_le_bytes(e[o..o + 4].try_into().unwrap_or_default());
            let key = [i32_at(0), i32_at(4), i32_at(8), i32_at(12)];
            let offset = u64::from_le_bytes(e[16..24].try_into().unwrap_or_default());
            let (bytes, count) = (i32_at(24), i32_at(28));
            let name = key_name(key);
            if !(0..31).contains(&key[0]) || key[1..].iter().any(|k| *k < 0 || *k >> key[0] != 0) {
                return Err(bad(format!(
                    "node {name} lies outside the octree (level L has 2^L nodes a side, \
                     numbered from 0)"
                )));
            }
            if !within(key, page_key) {
                return Err(bad(format!(
                    "node {name} is listed in the hierarchy page of node {}, outside that \
                     node's branch of the octree",
                    key_name(page_key)
                )));
            }
            if count < -1 {
                return Err(bad(format!("node {name} has {count} points")));
            }
            if count == -1 {
                pages.push((page(offset, u64::try_from(bytes).unwrap_or(0))?, key));
            }
            entries.push((key, offset, bytes, count));
        }
    }
    check_tree(&entries, points).map_err(|m| {
        bad(format!(
            "{m}; a box read through it would skip points: write the file again from its source"
        ))
    })?;
    let mut by_chunk: Vec<Option<Node>> = vec![None; chunks.len()];
    let mut depth = 0;
    for &(key, offset, bytes, count) in entries.iter().filter(|e| e.3 > 0) {
        let name = key_name(key);
        let k = chunks
            .binary_search_by_key(&offset, |c| c.offset)
            .map_err(|_| {
                bad(format!(
                    "node {name} points at byte {offset}, where no LAZ chunk starts"
                ))
            })?;
        let c = chunks[k];
        if i64::from(bytes) != c.bytes as i64 || i64::from(count) != c.points as i64 {
            return Err(bad(format!(
                "node {name} has {count} points in {bytes} bytes, but its LAZ chunk has {} in {}",
                c.points, c.bytes
            )));
        }
        if by_chunk[k].is_some() {
            return Err(bad(format!("two nodes share the chunk at byte {offset}")));
        }
        let side = 2.0 * halfsize / f64::from(1u32 << key[0]);
        let lo = |a: usize| center[a] - halfsize + side * f64::from(key[a + 1]);
        by_chunk[k] = Some(Node {
            chunk: k,
            key,
            rect: [lo(0), lo(1), lo(0) + side, lo(1) + side],
        });
        depth = depth.max(key[0]);
    }
    let nodes: Vec<Node> = by_chunk
        .iter()
        .enumerate()
        .map(|(k, n)| {
            n.ok_or_else(|| {
                bad(format!(
                    "the LAZ chunk at byte {} belongs to no node of the hierarchy",
                    chunks[k].offset
                ))
            })
        })
        .collect::<Result<_>>()?;
    let summary = CopcInfo {
        center,
        halfsize,
        spacing,
        gps_time: [f64_at(7), f64_at(8)],
        nodes: nodes.len(),
        depth,
    };
    Ok(Some((summary, nodes)))
}

/// The root node's key.
const ROOT: [i32; 4] = [0, 0, 0, 0];

/// A node's key as COPC and EPT write it: `level-x-y-z`.
fn key_name(key: [i32; 4]) -> String {
    format!("{}-{}-{}-{}", key[0], key[1], key[2], key[3])
}

/// The key of a node's parent (`None` for the root).
fn parent(key: [i32; 4]) -> Option<[i32; 4]> {
    (key[0] > 0).then(|| [key[0] - 1, key[1] >> 1, key[2] >> 1, key[3] >> 1])
}

/// Whether node `key` is node `root` or lies in its branch of the octree.
fn within(key: [i32; 4], root: [i32; 4]) -> bool {
    let up = key[0] - root[0];
    (0..31).contains(&up) && (1..4).all(|a| key[a] >> up == root[a])
}

/// Checks that the hierarchy's entries (key, offset, bytes, count; a count of -1 for a page)
/// make one octree: no node listed twice (nor two pages for one node), every node with points
/// or with a page of its own reached from the root through nodes listed, and the points of the
/// nodes adding up to the `points` the header announces. A damaged or hand-edited key fails one
/// of these, and a box read through the index would otherwise skip the points of the node it
/// moved.
fn check_tree(
    entries: &[([i32; 4], u64, i32, i32)],
    points: u64,
) -> std::result::Result<(), String> {
    let mut nodes = std::collections::HashSet::with_capacity(entries.len());
    let mut pages = std::collections::HashSet::new();
    for &(key, _, _, count) in entries {
        let fresh = if count == -1 {
            pages.insert(key)
        } else {
            nodes.insert(key)
        };
        if !fresh {
            let what = if count == -1 {
                "hierarchy pages"
            } else {
                "entries"
            };
            return Err(format!(
                "node {} has two {what} in the hierarchy (a damaged or edited key: one of them \
                 belongs elsewhere in the octree)",
                key_name(key)
            ));
        }
    }
    let listed = |k: &[i32; 4]| nodes.contains(k) || pages.contains(k);
    let mut reached = std::collections::HashSet::from([ROOT]);
    for &(key, ..) in entries.iter().filter(|e| e.3 != 0) {
        let mut k = key;
        while !reached.contains(&k) {
            let up = parent(k).filter(|p| listed(p)).ok_or_else(|| {
                let missing = parent(k).map_or_else(|| key_name(k), key_name);
                format!(
                    "node {} has no parent: node {missing} is not in the hierarchy (a damaged or \
                     edited key)",
                    key_name(key)
                )
            })?;
            reached.insert(k);
            k = up;
        }
    }
    let held: u64 = entries
        .iter()
        .map(|e| u64::try_from(e.3).unwrap_or(0))
        .sum();
    if held != points {
        return Err(format!(
            "the hierarchy's nodes hold {held} points, but the header announces {points}"
        ));
    }
    Ok(())
}
