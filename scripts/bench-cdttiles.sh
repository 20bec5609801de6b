#!/usr/bin/env bash
# Breaklines in exact tiles (issue 11, item 4): the streaming sweep against the tiled engine on
# one and two threads, side by side in one run, on real lidar with real breaklines:
#   - the IGN LiDAR HD pair (2 × 1 km², 519k points) with IGN's constraint lines (2-D, cut to the
#     data with --clip-breaklines and draped) → 1 m DEM;
#   - AHN3 Delft (849k points) with the BGT planar partition (13 131 vertices) → PLY mesh.
# Every tiled output is compared with the sweep's (DEM bytes; mesh triangle count).
# Usage: scripts/bench-cdttiles.sh [path/to/sweeptin]   (default: target/release/sweeptin)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-target/release/sweeptin}
D=${SWEEPTIN_DATA:-../shared/data}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
IGN="$D/lidar/ign_test_semis_2023_0299_6802_LA93_IGN69.laz $D/lidar/ign_test_semis_2023_0300_6802_LA93_IGN69.laz"
DELFT="$D/lidar/ahn3_delft_cropped_1.laz $D/lidar/ahn3_delft_cropped_2.laz"
echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
run() { # name, command...
    local name=$1; shift
    /usr/bin/time -f "$name: %e s wall, %U s user, %M KB peak RSS" "$@" -q 2>&1 >/dev/null |
        grep -v warning || true
}
for e in "sweep" "tiles --threads 1" "tiles --threads 2"; do
    # shellcheck disable=SC2086
    run "IGN dem --cell 1, $e" "$BIN" dem $IGN --breaklines "$D/lines/ign_NUALHD_1-0_DF_lignes_contrainte.geojson" \
        --clip-breaklines --cell 1 --engine $e -o "$OUT/ign_${e// /_}.tif"
done
cmp "$OUT/ign_sweep.tif" "$OUT/ign_tiles_--threads_1.tif" && cmp "$OUT/ign_sweep.tif" "$OUT/ign_tiles_--threads_2.tif" &&
    echo "IGN: the three DEMs are the same bytes"
for e in "sweep" "tiles --threads 1" "tiles --threads 2"; do
    # shellcheck disable=SC2086
    run "Delft tin, $e" "$BIN" tin $DELFT --breaklines "$D/lines/bgt_delft_all_layers.geojson" \
        --clip-breaklines --engine $e -o "$OUT/delft_${e// /_}.ply"
done
for f in "$OUT"/delft_*.ply; do head -c 300 "$f" | grep -a "element face"; done
