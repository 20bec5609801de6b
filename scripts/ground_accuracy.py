#!/usr/bin/env python3
"""Accuracy of `sweeptin ground` against professionally classified lidar (docs/ACCURACY.md).

For each file: the classes are dropped (every point written again with class 0), the copy is
classified by sweeptin (the `ground` command, or `--classes-tool` giving one byte a point) and by
CSF (PyPI cloth-simulation-filter, its documented defaults) on the same points, and each result is
compared with the file's own class 2:
  type I  = reference ground not classified ground / reference ground
  type II = reference non-ground classified ground / reference non-ground
  total   = all disagreements / points;  Cohen's kappa
Points the reference left unclassified (0: never classified, ARSO's hold ground-level points),
calls noise (7, 18) or water (9), and withheld points are left out of the counts (water is the
ground surface of a DTM, and progressive densification takes it as ground). Then the DEM of
each ground (`sweeptin dem --class 2 --cell 1`) is compared with the DEM of the reference ground
on the cells both have: share of cells within 0.15 m, RMSE, p99 of |difference|.

With `--whitebox BIN`, WhiteboxTools' LidarGroundPointFilter too (its documented defaults).

usage: ground_accuracy.py [--sweeptin BIN] [--classes-tool BIN] [--no-csf] [--whitebox BIN]
                          [--args "..."] FILES...
Prints a Markdown table row per file (and per method).
"""
import argparse
import os
import shlex
import subprocess
import sys
import tempfile
import time

import laspy
import numpy as np


def metrics(ref, got, keep):
    r, g = ref[keep], got[keep]
    n = len(r)
    a = np.count_nonzero(r & g)
    b = np.count_nonzero(r & ~g)  # type I
    c = np.count_nonzero(~r & g)  # type II
    d = np.count_nonzero(~r & ~g)
    t1 = b / max(a + b, 1)
    t2 = c / max(c + d, 1)
    tot = (b + c) / max(n, 1)
    po = (a + d) / max(n, 1)
    pe = ((a + b) * (a + c) + (c + d) * (b + d)) / max(n, 1) ** 2
    kappa = (po - pe) / (1 - pe) if pe < 1 else 1.0
    return t1, t2, tot, kappa


def dem(sweeptin, las, out):
    subprocess.run(
        [sweeptin, "dem", las, "--class", "2", "--cell", "1", "-o", out],
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def dem_compare(a, b):
    import rasterio

    with rasterio.open(a) as ra, rasterio.open(b) as rb:
        # Both grids are aligned on whole metres; read the overlap window.
        ba, bb = ra.bounds, rb.bounds
        left, right = max(ba.left, bb.left), min(ba.right, bb.right)
        bottom, top = max(ba.bottom, bb.bottom), min(ba.top, bb.top)
        if right <= left or top <= bottom:
            return float("nan"), float("nan"), float("nan"), 0
        wa = rasterio.windows.from_bounds(left, bottom, right, top, ra.transform).round_offsets().round_lengths()
        wb = rasterio.windows.from_bounds(left, bottom, right, top, rb.transform).round_offsets().round_lengths()
        xa = ra.read(1, window=wa, masked=True).astype(float)
        xb = rb.read(1, window=wb, masked=True).astype(float)
        h, w = min(xa.shape[0], xb.shape[0]), min(xa.shape[1], xb.shape[1])
        xa, xb = xa[:h, :w], xb[:h, :w]
        both = ~np.ma.getmaskarray(xa) & ~np.ma.getmaskarray(xb)
        d = np.abs(np.asarray(xa)[both] - np.asarray(xb)[both])
        if d.size == 0:
            return float("nan"), float("nan"), float("nan"), 0
        return (
            float(np.mean(d <= 0.15)),
            float(np.sqrt(np.mean(d * d))),
            float(np.percentile(d, 99)),
            int(d.size),
        )


def write_with_classes(src, classes, out):
    las = laspy.read(src)
    las.classification = classes.astype(np.uint8)
    las.write(out)


def run_sweeptin(args, bare, tmp):
    start = time.time()
    if args.classes_tool:
        binf = os.path.join(tmp, "classes.bin")
        subprocess.run(
            [args.classes_tool, binf, bare] + shlex.split(args.args),
            check=True,
            stdout=subprocess.DEVNULL,
        )
        secs = time.time() - start
        return np.fromfile(binf, dtype=np.uint8), secs
    out = os.path.join(tmp, "ground.laz")
    subprocess.run(
        [args.sweeptin, "ground", bare, "-o", out] + shlex.split(args.args),
        check=True,
        stdout=subprocess.DEVNULL,
    )
    secs = time.time() - start
    return np.asarray(laspy.read(out).classification), secs


def run_csf(las):
    import CSF

    xyz = np.vstack((las.x, las.y, las.z)).T.copy()
    csf = CSF.CSF()  # the documented defaults
    start = time.time()
    csf.setPointCloud(xyz)
    ground, non_ground = CSF.VecInt(), CSF.VecInt()
    csf.do_filtering(ground, non_ground, False)
    secs = time.time() - start
    got = np.zeros(len(xyz), dtype=bool)
    got[np.asarray(ground, dtype=np.int64)] = True
    return got, secs


def run_whitebox(wbt, bare, tmp):
    """WhiteboxTools' LidarGroundPointFilter (Vosselman's slope-based filter) with the defaults
    its tool documents (radius 2, min_neighbours 0, slope 45°, height 1, classify, slope_norm),
    given explicitly: the command line's own fallbacks differ (slope 15°, no normalisation)."""
    src = os.path.join(tmp, "bare.las")
    laspy.read(bare).write(src)
    out = os.path.join(tmp, "wbt.las")
    start = time.time()
    subprocess.run(
        [wbt, "-r=LidarGroundPointFilter", f"-i={src}", f"-o={out}", "--radius=2.0",
         "--min_neighbours=0", "--slope_threshold=45.0", "--height_threshold=1.0",
         "--classify", "--slope_norm"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    secs = time.time() - start
    return np.asarray(laspy.read(out).classification) == 2, secs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sweeptin", default="target/debug/sweeptin")
    ap.add_argument("--classes-tool")
    ap.add_argument("--args", default="", help="extra arguments for sweeptin ground")
    ap.add_argument("--no-csf", action="store_true")
    ap.add_argument("--no-dem", action="store_true")
    ap.add_argument("--whitebox", help="a whitebox_tools binary: its LidarGroundPointFilter too")
    ap.add_argument("files", nargs="+")
    args = ap.parse_args()
    print("| file | method | points | type I | type II | total | kappa | DEM cells ≤ 0.15 m | RMSE (m) | p99 (m) | seconds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for f in args.files:
        with tempfile.TemporaryDirectory() as tmp:
            las = laspy.read(f)
            cls = np.array(las.classification)  # a copy: the classes are dropped below
            ref = cls == 2
            withheld = np.asarray(las.withheld, dtype=bool) if "withheld" in las.point_format.dimension_names else np.zeros(len(cls), bool)
            keep = (cls != 0) & (cls != 7) & (cls != 18) & (cls != 9) & ~withheld
            bare = os.path.join(tmp, "bare.laz")
            las.classification = np.zeros(len(cls), dtype=np.uint8)
            las.write(bare)
            ref_dem = os.path.join(tmp, "ref.tif")
            if not args.no_dem:
                dem(args.sweeptin, f, ref_dem)
            results = []
            got, secs = run_sweeptin(args, bare, tmp)
            results.append(("sweeptin", got == 2, secs))
            if not args.no_csf:
                g, s = run_csf(las)
                results.append(("CSF", g, s))
            if args.whitebox:
                g, s = run_whitebox(args.whitebox, bare, tmp)
                results.append(("WhiteboxTools", g, s))
            for name, g, secs in results:
                t1, t2, tot, kappa = metrics(ref, g, keep)
                cells = rmse = p99 = float("nan")
                if not args.no_dem:
                    mine = os.path.join(tmp, f"{name}.laz")
                    write_with_classes(bare, np.where(g, 2, 1), mine)
                    mdem = os.path.join(tmp, f"{name}.tif")
                    try:
                        dem(args.sweeptin, mine, mdem)
                        cells, rmse, p99, _ = dem_compare(mdem, ref_dem)
                    except subprocess.CalledProcessError:
                        pass
                print(
                    f"| {os.path.basename(f)} | {name} | {int(keep.sum())} | {100*t1:.2f} % | {100*t2:.2f} % | "
                    f"{100*tot:.2f} % | {kappa:.3f} | {100*cells:.1f} % | {rmse:.3f} | {p99:.3f} | {secs:.1f} |",
                    flush=True,
                )


if __name__ == "__main__":
    sys.exit(main())
