#!/usr/bin/env python3
"""Compare a WhiteboxTools LidarTINGridding raster with sweeptin's exact TIN, value by value.

WhiteboxTools evaluates cell (row, col) at the raster's origin + (col, -row) cells, the cell's
upper-left corner, while its GeoTIFF declares PixelIsArea (GDAL reads the value as the cell's
centre, half a cell away). This script asks `sweeptin sample` for the TIN's heights at exactly the
points WhiteboxTools evaluated and reports how many cells agree within 1 mm, 1 cm, 10 cm, 1 m.

    scripts/peers/wbt_compare.py WBT.tif LAZ [--class 2] [--bin target/release/sweeptin]

Needs numpy and rasterio (PyPI).
"""
import argparse, os, subprocess, tempfile

import numpy as np
import rasterio

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("raster")
ap.add_argument("laz")
ap.add_argument("--class", dest="cls")
ap.add_argument("--bin", default="target/release/sweeptin")
a = ap.parse_args()

with rasterio.open(a.raster) as r:
    w = r.read(1).astype(np.float64)
    t, nodata = r.transform, r.nodata
h, n = w.shape
with tempfile.TemporaryDirectory() as d:
    q, s = os.path.join(d, "q.csv"), os.path.join(d, "s.csv")
    with open(q, "w") as f:  # bottom row first: queries sorted by y stream in bounded memory
        f.write("x,y\n")
        for row in range(h - 1, -1, -1):
            y = float(t.f + row * t.e)
            f.writelines(f"{float(t.c + col * t.a)!r},{y!r}\n" for col in range(n))
    cmd = [a.bin, "sample", a.laz, "--points", q, "-o", s, "--mem", "128M", "-q"]
    if a.cls:
        cmd += ["--class", a.cls]
    subprocess.run(cmd, check=True)
    lines = open(s).read().splitlines()[1:]
z = np.array([float(v) if v else np.nan for v in (l.split(",")[2] for l in lines)])
z = z.reshape(h, n)[::-1]
ours, theirs = ~np.isnan(z), w != nodata
both = ours & theirs
diff = np.abs(w[both] - z[both])
print(f"cells: {n} x {h}; with a value in both {both.sum()}, only WhiteboxTools "
      f"{(theirs & ~ours).sum()}, only sweeptin {(ours & ~theirs).sum()}")
for tol in (1e-3, 1e-2, 0.1, 1.0):
    print(f"|difference| <= {tol:g} m: {(diff <= tol).mean() * 100:.3f} % ({(diff > tol).sum()} cells beyond)")
print(f"largest difference {diff.max():.3f} m")
