#!/usr/bin/env bash
# One billion points → 1 m DEM in one process on this machine (issue 11's scale target):
# ten generated 100M-point LAZ tiles (gen_laz, seeds 1–10, a 5 × 2 mosaic at a 4600 m pitch,
# ≈ 1.2 GB of LAZ) triangulated by the exact tiles on every core with `--mem 512M`, under
# /usr/bin/time -v, while the free space of the temporary directory is sampled every 2 s (the
# spill files are unlinked, so only the file system's free space shows them).
# Prints the time, peak RSS, peak temporary disk and the run's --json summary.
#
#   scripts/bench-billion.sh [--mem 512M] [--tiles 10] [--out DIR] [--tmp DIR]
# Needs ≈ 35 GB free under --tmp (the sorted runs; consumed parts are given back as the merge
# goes) and ≈ 2.2 GB under --out.
set -euo pipefail
cd "$(dirname "$0")/.."
MEM=512M; OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench}/billion; TMP=""; TILES=10
while [ $# -gt 0 ]; do
    case "$1" in
        --mem) MEM=$2; shift 2;;
        --out) OUT=$2; shift 2;;
        --tmp) TMP=$2; shift 2;;
        --tiles) TILES=$2; shift 2;;
        *) echo "unknown option $1" >&2; exit 2;;
    esac
done
TMP=${TMP:-$OUT}
mkdir -p "$OUT" "$TMP"
command -v /usr/bin/time >/dev/null || { apt-get install -y -qq time >/dev/null; }
cargo build --release --quiet --bin sweeptin --example gen_laz
BIN=target/release/sweeptin
FILES=()
for k in $(seq 0 $((TILES - 1))); do
    i=$((k % 5)); j=$((k / 5))
    f="$OUT/t${i}_${j}.laz"
    [ -f "$f" ] || target/release/examples/gen_laz 100M "$f" --seed $((k + 1)) --offset $((i * 4600)),$((j * 4600))
    FILES+=("$f")
done
free_kb() { df -Pk "$TMP" | awk 'NR == 2 { print $4 }'; }
BASE=$(free_kb)
( low=$BASE; while sleep 2; do f=$(free_kb); [ "$f" -lt "$low" ] && low=$f; echo "$low" > "$OUT/low.kb"; done ) &
SAMPLER=$!
trap 'kill $SAMPLER 2>/dev/null || true' EXIT
/usr/bin/time -v "$BIN" dem "${FILES[@]}" --cell 1 --mem "$MEM" --engine tiles --tmp-dir "$TMP" \
    -o "$OUT/dem.tif" --json --quiet > "$OUT/run.json" 2> "$OUT/run.time"
kill $SAMPLER 2>/dev/null || true
LOW=$(cat "$OUT/low.kb" 2>/dev/null || echo "$BASE")
python3 - "$OUT/run.time" "$OUT/run.json" "$BASE" "$LOW" <<'PY'
import json, re, sys
log, js, base, low = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
t = open(log).read()
wall = t.split("Elapsed (wall clock) time (h:mm:ss or m:ss):")[1].split("\n")[0].strip()
p = [float(x) for x in wall.split(":")]
secs = p[-1] + 60 * p[-2] + (3600 * p[-3] if len(p) > 2 else 0)
user = float(re.search(r"User time \(seconds\): ([\d.]+)", t).group(1))
sys_ = float(re.search(r"System time \(seconds\): ([\d.]+)", t).group(1))
rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) / 1024
d = json.load(open(js)); run = d["run"]; tiles = run.get("tiles") or {}
n = run["points_read"]
print(f"points read {n:,}, kept {run['points_kept']:,}; wall {secs:.0f} s ({secs / 60:.1f} min), "
      f"user {user:.0f} s, system {sys_:.0f} s, peak RSS {rss:.0f} MB, "
      f"peak temporary disk {(base - low) / 1024 / 1024:.1f} GB (output included), "
      f"{n / secs / 1e6:.2f} M points/s")
print("tiles:", json.dumps(tiles))
print("dem:", json.dumps({k: d["dem"][k] for k in ("cols", "rows", "cells_with_data", "bytes")}))
PY
