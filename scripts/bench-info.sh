#!/usr/bin/env bash
# `sweeptin info --classes` (issue 12: at the decoder's speed, on every core) beside laspy on the
# same file, side by side in one run: the 13.2M-point ARSO tile by default. Rows: sweeptin on
# every core and on one (RAYON_NUM_THREADS=1), the bare reader (decode + filter, no statistics),
# and laspy (lazrs backend, parallel when available) reading the file and counting classes.
# Prints a Markdown table (median of --runs wall times).
#
#   scripts/bench-info.sh [--runs 3] [FILE]
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=3
FILE=${SWEEPTIN_DATA:-../shared/data}/lidar/arso_TM_511_122_from_ept.laz
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) RUNS=$2; shift 2;;
        *) FILE=$1; shift;;
    esac
done
python3 -c 'import laspy, lazrs' 2>/dev/null ||
    python3 -m pip install --quiet --disable-pip-version-check laspy==2.7.0 lazrs==0.8.2
cargo build --release --quiet --bin sweeptin --example read_lidar
BIN=target/release/sweeptin
READ=target/release/examples/read_lidar

median() { # env-prefixed command… → median wall seconds over $RUNS runs
    python3 - "$RUNS" "$@" <<'PY'
import os, subprocess, sys, time, statistics
runs, cmd = int(sys.argv[1]), sys.argv[2:]
env = dict(os.environ)
while cmd and "=" in cmd[0]:
    k, v = cmd.pop(0).split("=", 1)
    env[k] = v
t = []
for _ in range(runs):
    s = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, env=env)
    t.append(time.perf_counter() - s)
print(f"{statistics.median(t):.3f}")
PY
}
all=$(median $BIN info --classes "$FILE")
one=$(median RAYON_NUM_THREADS=1 $BIN info --classes "$FILE")
read=$(median $READ "$FILE")
laspy=$(median python3 -c "
import sys, laspy, numpy as np
l = laspy.read('$FILE')
np.unique(np.asarray(l.classification), return_counts=True)
np.unique(np.asarray(l.return_number), return_counts=True)
")
points=$($BIN info "$FILE" | sed -n 's/^  points: *\([0-9]*\).*/\1/p' | head -1)
echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores; $(python3 -c 'import laspy, importlib.metadata as m; print("laspy", laspy.__version__, "lazrs", m.version("lazrs"))' 2>/dev/null)"
echo
echo "| $(basename "$FILE") ($points points) | wall (median of $RUNS) | M points/s |"
echo "|---|---:|---:|"
python3 - "$points" "$all" "$one" "$read" "$laspy" <<'PY'
import sys
n = int(sys.argv[1])
for label, t in zip(["sweeptin info --classes, every core", "sweeptin info --classes, one thread",
                     "sweeptin reader alone (decode + filter)",
                     "laspy.read + class and return counts"], map(float, sys.argv[2:])):
    print(f"| {label} | {t:.2f} s | {n / t / 1e6:.2f} |")
PY
