#!/usr/bin/env bash
# The costs of issue 13's checks, measured side by side:
#  1. LAZ decoding chunk by chunk against the chunk table (input/las/chunks.rs) against the
#     decoder it replaced (laz's ParLasZipDecompressor), as `info --classes` (decode + count) on
#     the 13.2M-point ARSO tile: BASE is a sweeptin binary from before the change, NEW this one;
#     runs alternate, three each, and the script prints each run and the medians.
#  2. `check` of the same mesh as .ply (in memory) and as .stin (streaming): peak RSS and time.
#
# Usage: scripts/bench-hardening.sh BASE_BINARY [LAZ]
#   BASE_BINARY  e.g. a release build of the commit before (git worktree add /tmp/base <rev>)
#   LAZ          default ../shared/data/lidar/arso_TM_511_122_from_ept.laz
# Needs GNU time (/usr/bin/time). Results: docs/BENCHMARKS.md, "Hardening".
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:?usage: scripts/bench-hardening.sh BASE_BINARY [LAZ]}
laz=${2:-../shared/data/lidar/arso_TM_511_122_from_ept.laz}
cargo build --release --quiet
new=target/release/sweeptin
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "load: $(cat /proc/loadavg)"
echo "== info --classes (decode every point), seconds"
declare -a tb tn
for i in 1 2 3; do
    for which in base new; do
        bin=$base
        [ "$which" = new ] && bin=$new
        t=$( { /usr/bin/time -f "%e" "$bin" info --classes "$laz" >/dev/null; } 2>&1 | tail -1)
        echo "run $i $which $t"
        if [ "$which" = base ]; then tb+=("$t"); else tn+=("$t"); fi
    done
done
median() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
echo "median base $(median "${tb[@]}") s, new $(median "${tn[@]}") s"

echo "== check: .ply in memory against .stin streaming"
"$new" tin "$laz" -o "$work/m.ply" -q
"$new" tin "$laz" -o "$work/m.stin" -q
for m in m.ply m.stin; do
    /usr/bin/time -f "$m: %e s, peak RSS %M KiB" "$new" check "$work/$m"
done
echo "load: $(cat /proc/loadavg)"
