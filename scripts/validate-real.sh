#!/usr/bin/env bash
# Triangulates every real lidar file in ../shared/data/lidar (and the IGN 50 m tiles as one
# mosaic) with `sweeptin tin` (streaming, --mem 256M) to PLY, then validates each mesh with
# `sweeptin check` (exact: orientation, adjacency, locally Delaunay edges, convex hull, Euler).
# Prints a Markdown table. Outputs go to $OUT (default /tmp/sweeptin-validate), not the repository.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${SWEEPTIN_DATA:-../shared/data}
OUT=${OUT:-/tmp/sweeptin-validate}
mkdir -p "$OUT"
cargo build --release --quiet --bin sweeptin
BIN=target/release/sweeptin
echo "| input | points read | vertices | triangles | duplicates | tin s | check s | validator |"
echo "|---|---:|---:|---:|---:|---:|---:|---|"
run() { # name files...
    local name=$1; shift
    local ply="$OUT/$name.ply"
    local t0=$(date +%s.%N)
    local js=$("$BIN" tin "$@" -o "$ply" --mem 256M --json)
    local t1=$(date +%s.%N)
    local verdict
    verdict=$("$BIN" check "$ply" 2>&1) || true
    local t2=$(date +%s.%N)
    python3 - "$name" "$js" "$t0" "$t1" "$t2" "$verdict" <<'PY'
import json, sys
name, js, t0, t1, t2, verdict = sys.argv[1:7]
d = json.loads(js)
ok = "valid" if ": valid" in verdict else verdict.replace("\n", " ")[:120]
print(f"| {name} | {d['points_read']:,} | {d['vertices']:,} | {d['triangles']:,} | {d['duplicates']:,} | {float(t1)-float(t0):.1f} | {float(t2)-float(t1):.1f} | {ok} |")
PY
    rm -f "$ply"
}
for f in "$DATA"/lidar/*.laz "$DATA"/lidar/ign_50m_tiles/*_ground.las; do
    run "$(basename "$f")" "$f"
done
run "ign_50m_tiles (6 LAZ, one mosaic)" "$DATA"/lidar/ign_50m_tiles/*.laz
run "arso ground (class 2)" "$DATA"/lidar/arso_TM_511_122_from_ept.laz --class 2
