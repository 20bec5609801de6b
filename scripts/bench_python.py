"""Benchmark of the Python package against startinpy (run by scripts/bench-python.sh).

    python scripts/bench_python.py prepare LAZ OUT.npy       # class-2 points, with laspy
    python scripts/bench_python.py run {sweeptin|startinpy} POINTS.npy RESULT.json

`run` loads the points, then times each step and measures its peak resident memory (Linux:
VmHWM, reset before every step through /proc/self/clear_refs), reported beside the memory the
process held before the step (the points array and the interpreter). Steps:
`triangulate` (sweeptin.triangulate / startinpy DT.insert), `interpolate_1m` (heights at the
1 m cell centres of the points' extent, edge-aligned: Tin.interpolate / DT.interpolate with
"TIN"), and for sweeptin `rasterize_1m` (Tin.rasterize(1.0), the library's DEM sink).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np


def status(field: str) -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field):
                return int(line.split()[1]) * 1024
    raise KeyError(field)


def reset_peak() -> None:
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def step(results: dict, name: str, fn):
    reset_peak()
    before = status("VmRSS:")
    t = time.perf_counter()
    out = fn()
    seconds = time.perf_counter() - t
    peak = status("VmHWM:")
    results[name] = {
        "seconds": round(seconds, 3),
        "peak_rss_mb": round(peak / 2**20, 1),
        "added_peak_mb": round((peak - before) / 2**20, 1),
    }
    print(f"  {name}: {seconds:.2f} s, peak {peak / 2**20:.0f} MB (+{(peak - before) / 2**20:.0f} MB)", flush=True)
    return out


def grid(xyz: np.ndarray) -> np.ndarray:
    lo = np.ceil(xyz[:, :2].min(0) - 0.5)
    hi = np.floor(xyz[:, :2].max(0) - 0.5)
    xs = np.arange(lo[0], hi[0] + 1) + 0.5
    ys = np.arange(hi[1], lo[1] - 1, -1) + 0.5
    gx, gy = np.meshgrid(xs, ys)
    return np.column_stack([gx.ravel(), gy.ravel()])


def run(lib: str, points: str, result: str) -> None:
    xyz = np.load(points)
    q = grid(xyz)
    r: dict = {"library": lib, "points": len(xyz), "queries": len(q)}
    print(f"{lib}: {len(xyz)} points, {len(q)} queries", flush=True)
    if lib == "sweeptin":
        import sweeptin

        r["version"] = sweeptin.__version__
        tin = step(r, "triangulate", lambda: sweeptin.triangulate(xyz))
        r["triangles"] = tin.number_of_triangles()
        z = step(r, "interpolate_1m", lambda: tin.interpolate(q))
        dem, _ = step(r, "rasterize_1m", lambda: tin.rasterize(1.0))
        r["rasterize_equals_interpolate"] = bool(
            np.array_equal(dem.ravel(), z.astype(np.float32), equal_nan=True)
        )
    else:
        import startinpy
        from importlib.metadata import version

        r["version"] = version("startinpy")
        dt = startinpy.DT()
        step(r, "triangulate", lambda: dt.insert(xyz))
        r["triangles"] = int(dt.number_of_triangles())
        z = step(r, "interpolate_1m", lambda: dt.interpolate({"method": "TIN"}, q))
    np.save(result.replace(".json", ".z.npy"), z)
    with open(result, "w") as f:
        json.dump(r, f, indent=1)


def prepare(laz: str, out: str) -> None:
    import laspy

    las = laspy.read(laz)
    keep = np.asarray(las.classification) == 2
    xyz = np.column_stack([las.x[keep], las.y[keep], las.z[keep]])
    np.save(out, np.ascontiguousarray(xyz))
    print(f"{out}: {len(xyz)} class-2 points of {len(keep)}")


if __name__ == "__main__":
    if sys.argv[1] == "prepare":
        prepare(sys.argv[2], sys.argv[3])
    else:
        run(sys.argv[2], sys.argv[3], sys.argv[4])
