#!/usr/bin/env python3
"""Writes a COPC copy of a LAS/LAZ file with copclib (PyPI `copclib`, independent of sweeptin),
for the tests and scripts/bench-copc.sh.

    python3 scripts/make_copc.py IN.laz OUT.copc.laz [--page-depth K] [--voxels N]

The points keep their stored integers, scale and offset (converted to point format 6, 7 or 8,
which COPC requires). The octree is built the usual way (untwine, PDAL): the root cube around the
data, and each node keeps the first point of every cell of an N x N x N grid over it (N = 128),
passing the others to its children; a node with few points keeps them all. With --page-depth K
the hierarchy is split into pages, one per node at depth K (to exercise readers that must follow
page references). Needs laspy, lazrs and copclib.
"""
import argparse
import sys

import copclib
import laspy
import numpy as np

LEAF = 8192  # a node with at most this many points keeps them all


def octree(xyz, center, halfsize, voxels):
    """Yields (depth, ix, iy, iz, point indices) for every node with points, root first."""
    lo = center - halfsize
    remaining = np.arange(len(xyz))
    depth = 0
    while len(remaining):
        n = 1 << depth
        width = 2 * halfsize / n
        cell = np.clip(np.floor((xyz[remaining] - lo) / width).astype(np.int64), 0, n - 1)
        node = (cell[:, 0] * n + cell[:, 1]) * n + cell[:, 2]
        order = np.argsort(node, kind="stable")
        node_sorted = node[order]
        starts = np.flatnonzero(np.r_[True, node_sorted[1:] != node_sorted[:-1]])
        ends = np.r_[starts[1:], len(order)]
        passed = []
        for s, e in zip(starts, ends):
            idx = remaining[order[s:e]]
            key = cell[order[s]]
            if e - s <= LEAF:
                yield depth, key[0], key[1], key[2], idx
                continue
            # The first point of every voxel of the node stays; the others go one level down.
            vmin = lo + key * width
            v = np.clip(np.floor((xyz[idx] - vmin) / (width / voxels)).astype(np.int64), 0, voxels - 1)
            vid = (v[:, 0] * voxels + v[:, 1]) * voxels + v[:, 2]
            _, first = np.unique(vid, return_index=True)
            keep = np.zeros(len(idx), dtype=bool)
            keep[first] = True
            yield depth, key[0], key[1], key[2], idx[keep]
            passed.append(idx[~keep])
        remaining = np.sort(np.concatenate(passed)) if passed else np.empty(0, dtype=np.int64)
        depth += 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--page-depth", type=int, default=0)
    ap.add_argument("--voxels", type=int, default=128)
    a = ap.parse_args()

    las = laspy.read(a.input)
    pf = las.header.point_format.id
    target = {0: 6, 1: 6, 4: 6, 2: 7, 3: 7, 5: 7, 6: 6, 7: 7, 8: 8, 9: 6, 10: 8}[pf]
    if pf != target or las.header.version.minor != 4:
        las = laspy.convert(las, point_format_id=target, file_version="1.4")
    arr = las.points.array
    h = las.header
    xyz = np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)])
    mins, maxs = xyz.min(axis=0), xyz.max(axis=0)
    center = (mins + maxs) / 2
    halfsize = float((maxs - mins).max() / 2) * (1 + 1e-9) + 1e-6

    # The WKT as the file has it; GeoTIFF keys need pyproj to become WKT (left out without it).
    wkt = next((v.string for v in h.vlrs if type(v).__name__ == "WktCoordinateSystemVlr"), "")
    if not wkt:
        try:
            crs = h.parse_crs()
            wkt = crs.to_wkt() if crs is not None else ""
        except Exception:  # pyproj missing or keys it cannot read
            wkt = ""
    cfg = copclib.CopcConfigWriter(
        target, copclib.Vector3(*h.scales), copclib.Vector3(*h.offsets), wkt
    )
    writer = copclib.FileWriter(a.output, cfg)
    header = writer.copc_config.las_header
    header.min = copclib.Vector3(*mins)
    header.max = copclib.Vector3(*maxs)
    info = writer.copc_config.copc_info
    info.center_x, info.center_y, info.center_z = (float(v) for v in center)
    info.halfsize = halfsize
    info.spacing = 2 * halfsize / a.voxels
    returns = np.asarray(las.return_number)
    header.points_by_return = [int((returns == r).sum()) for r in range(1, 16)]

    nodes = 0
    for d, x, y, z, idx in octree(xyz, center, halfsize, a.voxels):
        key = copclib.VoxelKey(int(d), int(x), int(y), int(z))
        raw = np.ascontiguousarray(arr[np.sort(idx)]).view(np.int8).reshape(-1)
        page = copclib.VoxelKey(0, 0, 0, 0)
        if a.page_depth > 0 and d >= a.page_depth:
            page = key.GetParentAtDepth(a.page_depth)
        writer.AddNode(key, copclib.VectorChar(raw), page)
        nodes += 1
    writer.Close()
    print(f"make_copc: {len(arr)} points in {nodes} nodes -> {a.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
