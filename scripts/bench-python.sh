#!/usr/bin/env bash
# The Python package against startinpy (PyPI) on the same numpy arrays: the ARSO tile's ground
# points (class 2, 8,978,916 points, read once with laspy), `triangulate` and heights at the
# 1 m cell centres of the tile (1M queries), time and peak memory per step, each library in
# its own process, one after the other in one run (side by side). Prints a Markdown table.
#
#   scripts/bench-python.sh [--out DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench}
[ "${1:-}" = "--out" ] && OUT=$2
mkdir -p "$OUT"
ARSO=${SWEEPTIN_DATA:-../shared/data}/lidar/arso_TM_511_122_from_ept.laz
VENV=target/venv-py
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
PY="$VENV/bin/python"
"$PY" -m pip install --quiet --disable-pip-version-check --no-cache-dir \
    "maturin>=1.9,<2" numpy "laspy[lazrs]>=2.5" "startinpy==0.12.3"
VIRTUAL_ENV="$PWD/$VENV" PATH="$PWD/$VENV/bin:$PATH" \
    maturin develop --release --locked --quiet -m python/Cargo.toml
POINTS="$OUT/arso_class2.npy"
[ -f "$POINTS" ] || "$PY" scripts/bench_python.py prepare "$ARSO" "$POINTS"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
for lib in sweeptin startinpy; do
    "$PY" scripts/bench_python.py run "$lib" "$POINTS" "$OUT/py_$lib.json"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
"$PY" - "$OUT" <<'PY'
import json, sys
import numpy as np
out = sys.argv[1]
s = json.load(open(f"{out}/py_sweeptin.json"))
p = json.load(open(f"{out}/py_startinpy.json"))
zs, zp = np.load(f"{out}/py_sweeptin.z.npy"), np.load(f"{out}/py_startinpy.z.npy")
both = ~np.isnan(zs) & ~np.isnan(zp)
print(f"\n{s['points']} points ({s['triangles']} triangles sweeptin, {p['triangles']} startinpy), "
      f"{s['queries']} queries; heights differ by more than 1e-9 at {int((abs(zs[both] - zp[both]) > 1e-9).sum())} "
      f"queries, NaN in one only at {int((np.isnan(zs) != np.isnan(zp)).sum())}; "
      f"rasterize == interpolate: {s['rasterize_equals_interpolate']}\n")
print("| step | sweeptin s | startinpy s | speed-up | sweeptin peak (+step) MB | startinpy peak (+step) MB | memory ratio |")
print("|---|---|---|---|---|---|---|")
for k in ("triangulate", "interpolate_1m"):
    a, b = s[k], p[k]
    print(f"| {k} | {a['seconds']:.2f} | {b['seconds']:.2f} | {b['seconds'] / a['seconds']:.1f}× | "
          f"{a['peak_rss_mb']:.0f} (+{a['added_peak_mb']:.0f}) | {b['peak_rss_mb']:.0f} (+{b['added_peak_mb']:.0f}) | "
          f"{a['added_peak_mb'] / max(b['added_peak_mb'], 1):.2f} |")
r = s["rasterize_1m"]
print(f"| rasterize_1m (sweeptin only) | {r['seconds']:.2f} | | | {r['peak_rss_mb']:.0f} (+{r['added_peak_mb']:.0f}) | | |")
PY
