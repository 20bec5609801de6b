#!/usr/bin/env bash
# Breaklines in bounded memory (issue 40, item 3): a synth::roads network cleaned by clean()
# (the graph in memory) and by the streamed cleaner (breaklines::clean::stream, --mem 128M), one
# process each under /usr/bin/time -v (peak RSS, wall time), and the CLI's tin with the network
# as breaklines (cleaned streamed, the graph fed to the sweep vertex by vertex: what its --json
# summary says was held is printed, the line reader's too). Both cleaners' counters are printed,
# to compare. The clean_timing rows generate the polylines and hold them whole (O(lines)); tin
# reads the line file polyline by polyline.
#
#   scripts/bench-breaklines-memory.sh [SEGMENTS] [POINTS] [MEM]   (default 5000000 1000000 128M)
# Needs a release build of sweeptin and the examples dump_lines and clean_timing in
# ${CARGO_TARGET_DIR:-target}/release; SWEEPTIN_BENCH_TIN_ONLY=1 runs only the tin row (no
# clean_timing needed).
set -euo pipefail
cd "$(dirname "$0")/.."
N=${1:-5000000}; P=${2:-1000000}; MEM=${3:-128M}
BIN=${CARGO_TARGET_DIR:-target}/release
OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench-breaklines}
mkdir -p "$OUT"
echo "load: $(uptime)"
run() { # name, command...
    local name=$1; shift
    /usr/bin/time -v "$@" > "$OUT/$name.out" 2> "$OUT/$name.time" || { cat "$OUT/$name.time"; exit 1; }
    local rss wall
    rss=$(awk -F: '/Maximum resident/ {print $2}' "$OUT/$name.time")
    wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$OUT/$name.time")
    echo "| $name | $wall | $((rss / 1024)) MiB |"
    grep -v '^threads' "$OUT/$name.out" | head -4 | cut -c1-400 | sed 's/^/    /'
}
echo "| run | wall | peak RSS |"
echo "|---|---|---|"
if [ -z "${SWEEPTIN_BENCH_TIN_ONLY:-}" ]; then
    run "clean-grid-$N" "$BIN/examples/clean_timing" "$N" roads-grid
    run "clean-stream-$N" "$BIN/examples/clean_timing" "$N" roads-stream
fi
if [ "$P" != 0 ]; then
    "$BIN/examples/dump_lines" roads "$N" > "$OUT/net.txt"
    "$BIN/examples/dump_lines" road-points "$P" > "$OUT/pts.xyz"
    echo "lines: $(du -h "$OUT/net.txt" | cut -f1)"
    run "tin-$N-mem$MEM" "$BIN/sweeptin" tin "$OUT/pts.xyz" --breaklines "$OUT/net.txt" \
        --mem "$MEM" -o "$OUT/out.stin" --json
    # What the run's own summary says it held.
    python3 - "$OUT/tin-$N-mem$MEM.out" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
r = s.get("run", s)
b = r["breaklines"]
print("    summary: peak_rss_bytes", r["peak_rss_bytes"], "segments", b["segments"],
      "cleaner", b["cleaner"], "read_held_vertices", b.get("read_held_vertices"),
      "peak_anon_bytes", r.get("peak_anon_bytes"),
      "peak_pending_segments", r["stream"]["peak_pending_segments"],
      "peak_live_triangles", r["stream"]["peak_live_triangles"])
PY
    rm -f "$OUT/net.txt" "$OUT/pts.xyz" "$OUT/out.stin"
fi
