"""A sweeptin tile plan run on Dask, checked against one run over all the points.

    python examples/dask_plan.py [FILES…] [--cell 0.5] [--tile 50] [--class 2] [--workers 2]

Without files it uses the six IGN 50 m tiles of the repository's test data
(tests/data/lidar/ign_50m_tiles, docs/DATA.md). It makes a DEM plan (`sweeptin.plan`), runs
every task on a `dask.distributed` cluster (here a `LocalCluster` of worker *processes*; pass
`--scheduler tcp://host:8786` to use any Dask cluster that sees the files: the same code runs
there), merges the tiles (`sweeptin.merge`), and checks that the mosaic has exactly the cells of
one `sweeptin.dem` run over all the points on the mosaic's extent. Exits 1 when they differ.

The tasks read points past their tiles (a buffer), so the mosaic holds the triangles of all the
points, also of points just outside the plan's tiles (a file whose edge crosses a tile line by
less than half a cell gets no tile there). The reference run reads every point too: over the
tiles' box when the files' headers lie inside it (then the mosaic is its GeoTIFF, byte for
byte), else over a box that also holds the headers, whose cells in the mosaic's window are
compared.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import sys
import tempfile
import time

import sweeptin


def main() -> int:
    here = os.path.dirname(os.path.abspath(__file__))
    default = sorted(glob.glob(os.path.join(here, "..", "tests", "data", "lidar", "ign_50m_tiles", "*.laz")))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", default=default)
    ap.add_argument("--cell", type=float, default=0.5)
    ap.add_argument("--tile", type=float, default=50.0)
    ap.add_argument("--class", dest="classes", type=int, action="append", default=None)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--scheduler", help="address of an existing Dask scheduler")
    ap.add_argument("--out", help="directory for the plan and the results (default: a temp dir)")
    a = ap.parse_args()
    if not a.files:
        print("no input files (give LAS/LAZ files)", file=sys.stderr)
        return 2
    classes = a.classes or [2]

    from dask.distributed import Client, LocalCluster

    work = a.out or tempfile.mkdtemp(prefix="sweeptin-dask-")
    plan = sweeptin.plan("dem", a.files, os.path.join(work, "job"), cell=a.cell, tile=a.tile, classes=classes)
    print(f"{len(plan)} tasks in {plan.path}")

    if a.scheduler:
        client = Client(a.scheduler)
        cluster = None
    else:
        # Worker processes, one thread each: every task is one process's work (its own threads
        # inside, `threads=`), as on a cluster.
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        start = time.perf_counter()
        cores = os.cpu_count() or 1
        threads = max(1, cores // max(1, a.workers))
        futures = client.map(sweeptin.run_task, [plan] * len(plan), list(plan.tasks), threads=threads, pure=False)
        records = client.gather(futures)
        workers = {w for w in client.run(os.getpid).values()}
        print(f"ran {len(records)} tasks on {len(workers)} worker processes in {time.perf_counter() - start:.1f} s")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    mosaic = os.path.join(work, "mosaic.tif")
    merged = sweeptin.merge(plan, mosaic)
    d = merged["dem"]
    print(f"mosaic {d['cols']} x {d['rows']} cells from {d['tiles']} tiles -> {mosaic}")

    # One run over all the points, on the mosaic's extent (the union of the plan's tiles).
    with open(plan.path) as f:
        p = json.load(f)
    box = (
        min(t["bounds"][0] for t in p["tiles"]),
        min(t["bounds"][1] for t in p["tiles"]),
        max(t["bounds"][2] for t in p["tiles"]),
        max(t["bounds"][3] for t in p["tiles"]),
    )
    # The files' headers bound their points: a box holding them and the tiles reads every point.
    every = (
        min([box[0]] + [f["bounds"][0] for f in p["files"]]),
        min([box[1]] + [f["bounds"][1] for f in p["files"]]),
        max([box[2]] + [f["bounds"][2] for f in p["files"]]),
        max([box[3]] + [f["bounds"][3] for f in p["files"]]),
    )
    single = os.path.join(work, "single.tif")
    if every == box:
        sweeptin.dem(a.files, single, cell=a.cell, bbox=box, classes=classes)
        with open(mosaic, "rb") as m, open(single, "rb") as s1:
            same = m.read() == s1.read()
        print("mosaic == single run (the same GeoTIFF bytes):", same)
    else:
        # Outward to whole cells (`snap`): the same cell lattice as the plan's.
        sweeptin.dem(a.files, single, cell=a.cell, bbox=every, snap=True, classes=classes)
        same = same_cells(mosaic, single)
        print("mosaic == single run over every point (the same cells):", same)
    return 0 if same else 1


def cells(path: str):
    """The float32 cells of an uncompressed, stripped GeoTIFF as sweeptin writes it (its tiles,
    mosaics and DEMs), the x and y of its top-left corner and its cell size: GDAL is not needed."""
    import struct

    import numpy as np

    with open(path, "rb") as f:
        b = f.read()
    if b[:4] != b"II*\0":
        raise ValueError(f"{path}: not a little-endian classic TIFF")
    (ifd,) = struct.unpack_from("<I", b, 4)
    (n,) = struct.unpack_from("<H", b, ifd)
    kinds = {1: "B", 2: "B", 3: "H", 4: "I", 11: "f", 12: "d", 16: "Q"}
    tags = {}
    for i in range(n):
        at = ifd + 2 + 12 * i
        tag, kind, count = struct.unpack_from("<HHI", b, at)
        fmt = f"<{count}{kinds[kind]}"
        inline = struct.calcsize(fmt) <= 4
        tags[tag] = struct.unpack_from(fmt, b, at + 8 if inline else struct.unpack_from("<I", b, at + 8)[0])
    if tags.get(259, (1,))[0] != 1 or tags[258][0] != 32 or tags[339][0] != 3 or 322 in tags:
        raise ValueError(f"{path}: not an uncompressed float32 stripped GeoTIFF")
    width, height = tags[256][0], tags[257][0]
    data = b"".join(b[o : o + c] for o, c in zip(tags[273], tags[279]))
    values = np.frombuffer(data, "<f4", width * height).reshape(height, width)
    scale, tie = tags[33550], tags[33922]
    return values, tie[3] - tie[0] * scale[0], tie[4] + tie[1] * scale[1], scale[0]


def same_cells(mosaic: str, single: str) -> bool:
    """Does `single` hold, bit for bit, the cells of `mosaic` where the mosaic lies?"""
    m, mx, my, mc = cells(mosaic)
    s, sx, sy, sc = cells(single)
    if mc != sc:
        return False
    col, row = round((mx - sx) / mc), round((sy - my) / mc)
    if col < 0 or row < 0 or row + m.shape[0] > s.shape[0] or col + m.shape[1] > s.shape[1]:
        return False
    window = s[row : row + m.shape[0], col : col + m.shape[1]]
    return bool((window.view("<u4") == m.view("<u4")).all())

if __name__ == "__main__":
    sys.exit(main())
