#!/usr/bin/env bash
# A plan over one big plain LAZ file against one run (issue 43, item 1), side by side in one run:
#   * `sweeptin dem F --cell 3`: one run;
#   * `sweeptin plan dem F --cell 3 --tile T` + `sweeptin run job/plan.json --all`: the plan's
#     decoding pass (the point store) and every task, at tiles of 255 and 510;
# user + system CPU of each (wall times on a shared machine are not comparable), the ratio
# (plan + run) / one run, the tasks' runs, and `cmp` of the merged mosaic with one run's DEM.
# The file as published (acquisition order) and a copy in Morton order (laspy, lazrs).
#
#   scripts/bench-plan.sh [FILES...]   (default: the ARSO tile in ../shared/data/lidar and its
#                                       Morton-ordered copy, made once under $OUT)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${SWEEPTIN_DATA:-../shared/data/lidar}
OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench-plan}
TILES=${SWEEPTIN_BENCH_TILES:-255 510}
mkdir -p "$OUT"
VENV=target/venv-py
if [ $# -eq 0 ]; then
    ARSO="$DATA/arso_TM_511_122_from_ept.laz"
    SORTED="$OUT/arso_morton.laz"
    if [ ! -f "$SORTED" ]; then
        [ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
        "$VENV/bin/python" -c "import laspy, lazrs, numpy" 2>/dev/null ||
            "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
                laspy==2.7.0 lazrs==0.8.2 numpy
        "$VENV/bin/python" - "$ARSO" "$SORTED" <<'PY'
import sys, laspy, numpy as np
f = laspy.read(sys.argv[1])
x = np.asarray(f.X, dtype=np.int64); y = np.asarray(f.Y, dtype=np.int64)
q = lambda v: ((v - v.min()) * 65535 // max(1, v.max() - v.min())).astype(np.uint64)
def spread(v):
    for s, m in ((8, 0x00FF00FF), (4, 0x0F0F0F0F), (2, 0x33333333), (1, 0x55555555)):
        v = (v | (v << np.uint64(s))) & np.uint64(m)
    return v
f.points = f.points[np.argsort(spread(q(x)) | (spread(q(y)) << np.uint64(1)), kind="stable")]
f.write(sys.argv[2], do_compress=True)
PY
    fi
    set -- "$ARSO" "$SORTED"
fi
command -v /usr/bin/time >/dev/null || { apt-get install -y -qq time >/dev/null; }
cargo build --release --quiet --bin sweeptin
BIN=$(realpath "${CARGO_TARGET_DIR:-target}/release/sweeptin")
echo "commit $(git rev-parse --short HEAD)$(git diff --quiet || echo +changes), $(date -u +%FT%TZ)" >&2
FILES=()
for F in "$@"; do FILES+=("$(realpath "$F")"); done
cd "$OUT"
cpu() { # prints "user+sys peak_MB" of the command; stops the script if it fails
    /usr/bin/time -f "%U %S %M" -o time.txt "$@" >/dev/null || { echo "failed: $*" >&2; exit 1; }
    awk '{printf "%.2f %d", $1 + $2, $3 / 1024}' time.txt
}
echo "| file | tile | one run CPU s | plan CPU s | run --all CPU s | (plan + run) / one run | tasks | runs | peak MB (one / plan / task) | mosaic |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---|---|"
for F in "${FILES[@]}"; do
    read -r one one_mb <<< "$(cpu "$BIN" dem "$F" --cell 3 -o single.tif -q)"
    [ -n "$one" ] || exit 1
    for TILE in $TILES; do
        rm -rf job
        read -r plan plan_mb <<< "$(cpu "$BIN" plan dem "$F" --cell 3 --tile "$TILE" -o job -q)"
        read -r run run_mb <<< "$(cpu "$BIN" run job/plan.json --all -q)"
        [ -n "$plan" ] && [ -n "$run" ] || exit 1
        "$BIN" merge job/plan.json -o mosaic.tif -q
        same=$(cmp -s mosaic.tif single.tif && echo "cmp-equal" || echo "DIFFERENT")
        read -r tasks runs <<< "$(python3 -c "
import glob, json
r = [json.load(open(p)) for p in glob.glob('job/tiles/task_*.json')]
print(len(r), sum(x['runs'] for x in r))")"
        ratio=$(python3 -c "print(f'{($plan + $run) / $one:.2f}')")
        echo "| $(basename "$F") | $TILE | $one | $plan | $run | **$ratio ×** | $tasks | $runs | $one_mb / $plan_mb / $run_mb | $same |"
    done
done
