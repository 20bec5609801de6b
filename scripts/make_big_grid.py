#!/usr/bin/env python3
"""Writes a large synthetic DEM as a tiled float32 GeoTIFF, band of tiles by band of tiles (never
the whole grid in memory), for scripts/bench-bigrid.sh.

usage: make_big_grid.py OUT.tif [SIZE] [TILE]
  SIZE x SIZE cells of 1 m (default 20000), tiles of TILE x TILE (default 512), EPSG:32633,
  nodata -9999: a round lake of missing cells and a missing corner. Heights are smooth hills with
  ripples (metres), the same for the same SIZE.
"""
import sys

import numpy as np
import rasterio
from rasterio.transform import from_origin


def heights(rows, cols):
    y = rows[:, None].astype(np.float64)
    x = cols[None, :].astype(np.float64)
    z = (500.0 + 80.0 * np.sin(x / 900.0) * np.cos(y / 700.0)
         + 20.0 * np.sin(x / 130.0 + y / 170.0)
         + 3.0 * np.sin(x / 17.0) * np.cos(y / 23.0))
    return z


def main():
    out = sys.argv[1]
    size = int(sys.argv[2]) if len(sys.argv) > 2 else 20000
    tile = int(sys.argv[3]) if len(sys.argv) > 3 else 512
    profile = dict(driver="GTiff", width=size, height=size, count=1, dtype="float32",
                   crs="EPSG:32633", transform=from_origin(400000.0, 5200000.0 + size, 1.0, 1.0),
                   nodata=-9999.0, tiled=True, blockxsize=tile, blockysize=tile,
                   BIGTIFF="IF_SAFER")
    cols = np.arange(size)
    lake = (size * 0.6, size * 0.4, size * 0.05)
    with rasterio.open(out, "w", **profile) as dst:
        for r0 in range(0, size, tile):
            rows = np.arange(r0, min(r0 + tile, size))
            z = heights(rows, cols).astype(np.float32)
            d = np.hypot(cols[None, :] - lake[0], rows[:, None] - lake[1])
            z[d < lake[2]] = -9999.0
            if r0 == 0:
                z[0, 0] = -9999.0
            dst.write(z, 1, window=rasterio.windows.Window(0, r0, size, len(rows)))
    print(f"{out}: {size} x {size} float32, tiles {tile}")


if __name__ == "__main__":
    main()
