"""Crops a LAS/LAZ file to the points strictly inside a box, keeping the header (LAS version,
point format, scale, offset, VLRs, dates, identifiers) and the point order; laspy updates the
point counts and bounds. Used once to make tests/data/lidar/arso_TM_511_122_sw_250m.laz."""
import sys

import laspy
import numpy as np

src, dst = sys.argv[1], sys.argv[2]
xmin, ymin, xmax, ymax = map(float, sys.argv[3].split(","))
las = laspy.read(src)
# As doubles: laspy compares its scaled views in integer space, rounding the bounds.
x, y = np.asarray(las.x), np.asarray(las.y)
inside = (x > xmin) & (x < xmax) & (y > ymin) & (y < ymax)
out = laspy.LasData(las.header)
out.points = las.points[inside]
out.write(dst, laz_backend=laspy.LazBackend.Lazrs)
