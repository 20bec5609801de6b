#!/usr/bin/env bash
# One billion points → 1 m DEM in one process on this machine (issue 11's scale target):
# ten generated 100M-point LAZ tiles (≈ 1.2 GB of LAZ) in a 5 × 2 mosaic of abutting tiles, as
# a lidar programme's tiles are: one gen_laz tile (seed 1) and nine copies moved by whole tile
# pitches through their LAS offsets (header fields only: the points are the same integers),
# so the tiles meet along their edges (gaps under 1 m) — triangulated by the exact tiles on every core with `--mem 512M`, under
# /usr/bin/time -v, while the free space of the temporary directory is sampled every 2 s (the
# spill files are unlinked, so only the file system's free space shows them).
# Prints the time, peak RSS, peak temporary disk and the run's --json summary. `--gap G` moves
# the copies G metres further apart, so strips G m wide without data lie between the tiles (as
# lakes and rivers make them): the certificates' hard case.
#
#   scripts/bench-billion.sh [--mem 512M] [--tiles 10] [--gap 0] [--out DIR] [--tmp DIR]
# Needs ≈ 35 GB free under --tmp (the sorted runs; consumed parts are given back as the merge
# goes) and ≈ 2.2 GB under --out.
set -euo pipefail
cd "$(dirname "$0")/.."
MEM=512M; OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench}/billion; TMP=""; TILES=10; GAP=0
while [ $# -gt 0 ]; do
    case "$1" in
        --mem) MEM=$2; shift 2;;
        --out) OUT=$2; shift 2;;
        --tmp) TMP=$2; shift 2;;
        --tiles) TILES=$2; shift 2;;
        --gap) GAP=$2; shift 2;;
        *) echo "unknown option $1" >&2; exit 2;;
    esac
done
TMP=${TMP:-$OUT}
SFX=""; [ "$GAP" = 0 ] || SFX="_gap$GAP"
mkdir -p "$OUT" "$TMP"
command -v /usr/bin/time >/dev/null || { apt-get install -y -qq time >/dev/null; }
cargo build --release --quiet --bin sweeptin --example gen_laz
BIN=target/release/sweeptin
FILES=()
FIRST="$OUT/m0_0.laz"
[ -f "$FIRST" ] || target/release/examples/gen_laz 100M "$FIRST" --seed 1
for k in $(seq 0 $((TILES - 1))); do
    i=$((k % 5)); j=$((k / 5))
    f="$OUT/m${i}_${j}.laz"
    [ "$GAP" = 0 ] || f="$OUT/m${i}_${j}_gap$GAP.laz"
    [ -f "$f" ] || [ "$f" = "$FIRST" ] || python3 - "$FIRST" "$f" "$i" "$j" "$GAP" <<'PY'
import math, shutil, struct, sys
src, dst, i, j, gap = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5])
with open(src, "rb") as fh:
    h = bytearray(fh.read(227))
f = lambda at: struct.unpack_from("<d", h, at)[0]
# LAS header: x/y offsets at 155/163, max/min x at 179/187, max/min y at 195/203.
px, py = math.ceil(f(179) - f(187)), math.ceil(f(195) - f(203))
dx, dy = i * (px + gap), j * (py + gap)
for at, d in ((155, dx), (163, dy), (179, dx), (187, dx), (195, dy), (203, dy)):
    struct.pack_into("<d", h, at, f(at) + d)
shutil.copyfile(src, dst + ".part")
with open(dst + ".part", "r+b") as fh:
    fh.write(h)
import os; os.replace(dst + ".part", dst)
PY
    FILES+=("$f")
done
free_kb() { df -Pk "$TMP" | awk 'NR == 2 { print $4 }'; }
BASE=$(free_kb)
( low=$BASE; while sleep 2; do f=$(free_kb); [ "$f" -lt "$low" ] && low=$f; echo "$low" > "$OUT/low.kb"; done ) &
SAMPLER=$!
trap 'kill $SAMPLER 2>/dev/null || true' EXIT
/usr/bin/time -v "$BIN" dem "${FILES[@]}" --cell 1 --mem "$MEM" --engine tiles --tmp-dir "$TMP" \
    -o "$OUT/dem$SFX.tif" --json --quiet > "$OUT/run$SFX.json" 2> "$OUT/run$SFX.time"
kill $SAMPLER 2>/dev/null || true
LOW=$(cat "$OUT/low.kb" 2>/dev/null || echo "$BASE")
python3 - "$OUT/run$SFX.time" "$OUT/run$SFX.json" "$BASE" "$LOW" <<'PY'
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
