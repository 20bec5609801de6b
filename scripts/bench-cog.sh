#!/usr/bin/env bash
# COG writing against the plain GeoTIFF on a large DEM: the ARSO tile (13.2 M points) at 0.25 m,
# 4000 × 4000 cells (64 MB of float32), ground class. Same run twice, only the output differs;
# prints elapsed time and peak RSS of each (GNU time), the file sizes, and validates the COG with
# `rio cogeo validate` when it is installed. Results go in docs/BENCHMARKS.md ("Rasters: COG").
set -euo pipefail
cd "$(dirname "$0")/.."
data="${SWEEPTIN_DATA:-../shared/data}"
laz="$data/lidar/arso_TM_511_122_from_ept.laz"
cell="${1:-0.25}"
cargo build --release --quiet
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
for fmt in tif cog; do
    /usr/bin/time -f "$fmt: %e s elapsed, %M KiB peak RSS" \
        target/release/sweeptin dem "$laz" --class 2 --cell "$cell" --format "$fmt" \
        -o "$out/dem_$fmt.tif" -q
done
ls -l "$out"/dem_*.tif
if command -v rio >/dev/null; then rio cogeo validate --strict "$out/dem_cog.tif"; fi
