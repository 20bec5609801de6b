#!/usr/bin/env bash
# Memory-bounded streaming benchmark (issue: streaming out-of-core triangulation).
#
# Generates lidar-like LAZ files of 1M, 10M and 100M points (synth::lidar_like: scan rows,
# a second overlapping flight line, ~1% duplicates, holes; written in acquisition order) on disk
# outside the repository, then runs `sweeptin tin` to the streaming format (.stin) and to PLY with
# --mem 128M, under /usr/bin/time -v, and also on the real 13.2M-point ARSO tile.
# Prints a Markdown table: wall time, points/s, peak RSS, peak anonymous memory, front and
# live-triangle peaks.
#
#   scripts/bench-stream.sh [--sizes "1M 10M 100M"] [--mem 128M] [--out DIR] [--no-real]
set -euo pipefail
cd "$(dirname "$0")/.."
SIZES="1M 10M 100M"; MEM=128M; OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench}; REAL=1
while [ $# -gt 0 ]; do
    case "$1" in
        --sizes) SIZES=$2; shift 2;;
        --mem) MEM=$2; shift 2;;
        --out) OUT=$2; shift 2;;
        --no-real) REAL=0; shift;;
        *) echo "unknown option $1" >&2; exit 2;;
    esac
done
mkdir -p "$OUT"
command -v /usr/bin/time >/dev/null || { apt-get install -y -qq time >/dev/null; }
cargo build --release --quiet --bin sweeptin --example gen_laz
BIN=target/release/sweeptin
RESULTS="$OUT/stream-results.jsonl"; : > "$RESULTS"

run() { # name input output
    local name=$1 input=$2 output=$3
    local log="$OUT/$name.time"
    /usr/bin/time -v "$BIN" tin "$input" -o "$output" --mem "$MEM" --tmp-dir "$OUT" --json \
        2> "$log" > "$OUT/$name.json"
    python3 - "$name" "$OUT/$name.json" "$log" "$output" >> "$RESULTS" <<'PY'
import json, sys, re, os
name, js, log, out = sys.argv[1:5]
d = json.load(open(js)); t = open(log).read()
wall = t.split("Elapsed (wall clock) time (h:mm:ss or m:ss):")[1].split("\n")[0].strip()
parts = [float(x) for x in wall.split(":")]
secs = parts[-1] + 60 * parts[-2] + (3600 * parts[-3] if len(parts) > 2 else 0)
rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) * 1024
print(json.dumps({"name": name, "points": d["points_read"], "wall_s": secs,
  "pts_per_s": d["points_read"] / secs, "max_rss": rss, "peak_anon": d.get("peak_anon_bytes"),
  "peak_front": d["sweep"]["peak_front"], "peak_live_tris": d["stream"]["peak_live_triangles"],
  "peak_live_verts": d["stream"]["peak_live_vertices"], "runs": d["sort"]["runs"],
  "seconds": d["seconds"], "triangles": d["triangles"], "out_bytes": os.path.getsize(out)}))
PY
    rm -f "$output"
}

for s in $SIZES; do
    f="$OUT/lidar-$s.laz"
    [ -f "$f" ] || target/release/examples/gen_laz "$s" "$f"
    run "$s-stin" "$f" "$OUT/out-$s.stin"
    run "$s-ply" "$f" "$OUT/out-$s.ply"
done
if [ "$REAL" = 1 ]; then
    ARSO=../shared/data/lidar/arso_TM_511_122_from_ept.laz
    [ -f "$ARSO" ] && { run "arso-stin" "$ARSO" "$OUT/out-arso.stin"; run "arso-ply" "$ARSO" "$OUT/out-arso.ply"; }
fi
python3 - "$RESULTS" <<'PY'
import json, sys, subprocess
rows = [json.loads(l) for l in open(sys.argv[1])]
mb = lambda b: f"{b/2**20:.0f} MB" if b else "?"
cpu = [l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")][0]
load = open("/proc/loadavg").read().split()[:3]
print(f"\nmachine: {subprocess.getoutput('nproc')} cores, {cpu}, load average {' '.join(load)}")
print("| run | points | wall s | M points/s | peak RSS | peak anon | front peak | live triangles peak | spill runs | read+sort s | sweep+write s |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for r in rows:
    print(f"| {r['name']} | {r['points']:,} | {r['wall_s']:.1f} | {r['pts_per_s']/1e6:.2f} | {mb(r['max_rss'])} | {mb(r['peak_anon'])} | {r['peak_front']:,} | {r['peak_live_tris']:,} | {r['runs']} | {r['seconds']['read_sort']:.1f} | {r['seconds']['triangulate_write']:.1f} |")
PY
