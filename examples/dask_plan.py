"""A sweeptin tile plan run on Dask, checked against one run over all the points.

    python examples/dask_plan.py [FILES…] [--cell 0.5] [--tile 50] [--class 2] [--workers 2]

Without files it uses the six IGN 50 m tiles of the repository's test data
(tests/data/lidar/ign_50m_tiles, docs/DATA.md). It makes a DEM plan (`sweeptin.plan`), runs
every task on a `dask.distributed` cluster (here a `LocalCluster` of worker *processes*; pass
`--scheduler tcp://host:8786` to use any Dask cluster that sees the files: the same code runs
there), merges the tiles (`sweeptin.merge`), and checks that the mosaic is the GeoTIFF of one
`sweeptin.dem` run over all the points, byte for byte. Exits 1 when they differ.

The tasks read points past their tiles (a buffer), so the mosaic holds the triangles of all the
points, also of points just outside the plan's tiles (a file whose edge crosses a tile line by
less than half a cell gets no tile there), and the merge writes one run's extent (the cells
whose centres lie inside the points kept).
"""

from __future__ import annotations

import argparse
import glob
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

    # One run over all the points: the mosaic is its file (`merge` writes one run's extent).
    single = os.path.join(work, "single.tif")
    sweeptin.dem(a.files, single, cell=a.cell, classes=classes)
    with open(mosaic, "rb") as m, open(single, "rb") as s1:
        same = m.read() == s1.read()
    print("mosaic == single run (the same GeoTIFF bytes):", same)
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
