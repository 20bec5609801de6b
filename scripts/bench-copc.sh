#!/usr/bin/env bash
# COPC read through its octree (issue 12): a 100 m box of a COPC copy of the 13.2M-point ARSO
# tile against the full read of the same file, side by side in one run; the same box on the
# plain LAZ (which must decode everything); and laspy's COPC query of the same box as a peer.
# The COPC copy is written once by scripts/make_copc.py (copclib) into the output folder.
# Prints a Markdown table (median of --runs wall times).
#
#   scripts/bench-copc.sh [--runs 5] [--out DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=5; OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench}
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) RUNS=$2; shift 2;;
        --out) OUT=$2; shift 2;;
        *) echo "unknown option $1" >&2; exit 2;;
    esac
done
mkdir -p "$OUT"
python3 -c 'import copclib, laspy, lazrs' 2>/dev/null ||
    python3 -m pip install --quiet --disable-pip-version-check copclib==2.6.3 laspy==2.7.0 lazrs==0.8.2
cargo build --release --quiet --example read_lidar
READ=target/release/examples/read_lidar
ARSO=${SWEEPTIN_DATA:-../shared/data}/lidar/arso_TM_511_122_from_ept.laz
COPC=$OUT/arso.copc.laz
[ -f "$COPC" ] || python3 scripts/make_copc.py "$ARSO" "$COPC" --page-depth 3
BOX=511400,122400,511500,122500   # 100 m × 100 m in the middle of the 1 km tile

median() { # command… → median wall seconds over $RUNS runs
    python3 - "$RUNS" "$@" <<'PY'
import subprocess, sys, time, statistics
runs, cmd = int(sys.argv[1]), sys.argv[2:]
t = []
for _ in range(runs):
    s = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    t.append(time.perf_counter() - s)
print(f"{statistics.median(t):.3f}")
PY
}
full=$(median $READ "$COPC")
box=$(median $READ --bbox $BOX "$COPC")
noindex=$(median $READ --no-index --bbox $BOX "$COPC")
laz=$(median $READ --bbox $BOX "$ARSO")
laspy=$(median python3 -c "
import laspy, numpy as np, sys
r = laspy.CopcReader.open('$COPC')
p = r.query(bounds=laspy.copc.Bounds(mins=np.array([511400., 122400.]), maxs=np.array([511500., 122500.])))
" )
pystart=$(median python3 -c "import laspy, numpy")
counts=$($READ --bbox $BOX "$COPC")
echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores; $counts"
echo
echo "| read of ARSO (13.2 M points) | wall (median of $RUNS) | vs full COPC read |"
echo "|---|---:|---:|"
python3 - "$full" "$box" "$noindex" "$laz" "$laspy" "$pystart" <<'PY'
import sys
full, box, noindex, laz, laspy, pystart = map(float, sys.argv[1:])
for label, t in [("COPC, whole file", full), ("COPC, 100 m box through the octree", box),
                 ("COPC, 100 m box, octree not used", noindex), ("plain LAZ, 100 m box", laz),
                 ("laspy CopcReader.query, 100 m box (Python start-up included)", laspy),
                 ("(Python start-up and imports alone)", pystart)]:
    print(f"| {label} | {t:.3f} s | {100 * t / full:.1f} % |")
PY
