#!/usr/bin/env bash
# Plans with 3-D breaklines (issue 11, item 4 for plan/run/merge), side by side in one run on the
# IGN LiDAR HD pair (2 × 1 km², 519k points, 1 m DEM, tiles of 250 m, `run --all --jobs 2`):
#   - a plan without lines;
#   - a plan with a 200 m grid of 3-D breaklines (15 lines, 1985 vertices, 50 crossings split by
#     cleaning), made with the recipe `plan` gives for 2-D lines: `sweeptin sample` appends the
#     TIN's height to every `x y` line of a text breakline file;
#   - one sweep with those 3-D lines over the plan's extent (the mosaic must be its bytes), and one
#     run with the 2-D lines (draped), the alternative to the recipe.
# Usage: scripts/bench-planlines.sh [path/to/sweeptin]   (default: target/release/sweeptin)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-target/release/sweeptin}
D=${SWEEPTIN_DATA:-../shared/data}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
IGN="$D/lidar/ign_test_semis_2023_0299_6802_LA93_IGN69.laz $D/lidar/ign_test_semis_2023_0300_6802_LA93_IGN69.laz"
echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
run() { # name, command...
    local name=$1; shift
    /usr/bin/time -f "$name: %e s wall, %U s user, %M KB peak RSS" "$@" 2>&1 >/dev/null |
        grep -v "warning\|not a failure\|next:\|tasks (tiles\|^sweeptin: \|^  [a-z]* -> " || true
}
# A grid of lines every 200 m inside the data (vertices every 10 m), as `x y` text.
python3 - "$OUT/xy.txt" <<'PY'
import sys
out = []
for x in range(299100, 301000, 200):
    out.append("\n".join(f"{x} {y}" for y in range(6801010, 6801991, 10)))
for y in range(6801100, 6802000, 200):
    out.append("\n".join(f"{x} {y}" for x in range(299010, 300991, 10)))
open(sys.argv[1], "w").write("\n\n".join(out) + "\n")
PY
# shellcheck disable=SC2086
run "sample (the recipe: heights for the 2-D lines)" "$BIN" sample $IGN --points "$OUT/xy.txt" -o "$OUT/xyz.txt" -q
for n in 0 1; do
    lines=()
    [ "$n" = 1 ] && lines=(--breaklines "$OUT/xyz.txt")
    # shellcheck disable=SC2086
    "$BIN" plan dem $IGN --cell 1 --tile 250 "${lines[@]}" -o "$OUT/p$n" >/dev/null 2>&1
    run "plan $n ($([ "$n" = 1 ] && echo "3-D lines" || echo "no lines")): run --all --jobs 2" \
        "$BIN" run "$OUT/p$n/plan.json" --all --jobs 2 -q
    "$BIN" merge "$OUT/p$n/plan.json" -o "$OUT/m$n.tif" 2>/dev/null
    python3 - "$OUT/p$n" <<'PY'
import json, glob, sys
recs = [json.load(open(f)) for f in glob.glob(sys.argv[1] + "/tiles/task_*.json")]
print(f"  {len(recs)} tasks, {sum(r['runs'] > 1 for r in recs)} ran again with a wider buffer, "
      f"largest task {max(r['seconds'] for r in recs):.2f} s")
PY
done
EXT=$(python3 -c "
import json; t = json.load(open('$OUT/p1/plan.json'))['tiles']
print(','.join(str(f(b['bounds'][i] for b in t)) for i, f in [(0, min), (1, min), (2, max), (3, max)]))")
# shellcheck disable=SC2086
run "one sweep, 3-D lines" "$BIN" dem $IGN --cell 1 --breaklines "$OUT/xyz.txt" --engine sweep \
    --bbox "$EXT" --buffer 10000 -o "$OUT/one.tif" -q
cmp "$OUT/m1.tif" "$OUT/one.tif" && echo "the plan's mosaic is the sweep's bytes"
# shellcheck disable=SC2086
run "one sweep, 2-D lines (draped)" "$BIN" dem $IGN --cell 1 --breaklines "$OUT/xy.txt" -o "$OUT/draped.tif" -q
# Issue 43 item 1: one big plain LAZ (ARSO, 13.2 M points), planned in tiles of 510 m: `plan`
# writes the chunk index (one decoding pass), each task decodes only the chunks that meet its
# tile and buffer. Total CPU (plan + run --all) against one run.
ARSO="$D/lidar/arso_TM_511_122_from_ept.laz"
if [ -f "$ARSO" ]; then
    run "one run, ARSO dem --cell 3" "$BIN" dem "$ARSO" --cell 3 -o "$OUT/arso_one.tif" -q
    run "plan (chunk index), ARSO --tile 510" "$BIN" plan dem "$ARSO" --cell 3 --tile 510 -o "$OUT/arso"
    run "run --all, ARSO" "$BIN" run "$OUT/arso/plan.json" --all -q
    python3 - "$OUT/arso" <<'PY'
import json, glob, sys
recs = [json.load(open(f)) for f in glob.glob(sys.argv[1] + "/tiles/task_*.json")]
print(f"  {len(recs)} tasks, {sum(r['status'] == 'empty' for r in recs)} empty, points decoded "
      f"{sum(r.get('decoded', 0) for r in recs)} in all")
PY
fi
