#!/usr/bin/env bash
# Big-grid proof (not in CI): a grid larger than the --mem it is simplified with. Writes a
# SIZE × SIZE float32 GeoTIFF tiled 512 (scripts/make_big_grid.py, python rasterio; 1.6 GB at the
# default 20000), then runs `sweeptin simplify` with --mem MEM under /usr/bin/time -v and checks
# that the peak RSS stays under MEM. With CMP=1 it runs again with --threads 1 and a larger --mem
# and compares the bytes.
#
# usage: scripts/bench-bigrid.sh [SIZE] [MEM] [MAX_ERROR]    (defaults 20000 256M 0.5)
# the grid is kept in $BIGRID_DIR (default /tmp/bigrid) for the next run.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
size=${1:-20000}
mem=${2:-256M}
err=${3:-0.5}
dir=${BIGRID_DIR:-/tmp/bigrid}
mkdir -p "$dir"
grid=$dir/g$size.tif
[ -f "$grid" ] || python3 "$here/scripts/make_big_grid.py" "$grid" "$size" 512
cargo build --release --quiet --manifest-path "$here/Cargo.toml" --bin sweeptin
bin=$here/target/release/sweeptin
out=$dir/g$size.ply
trap 'rm -f "$out" "$dir/again.ply"' EXIT

echo "grid: $grid ($size × $size float32, $(du -h "$grid" | cut -f1) on disk, $((size * size * 4 / 1048576)) MiB as float32)"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg), cores: $(nproc)"
/usr/bin/time -v "$bin" simplify "$grid" -o "$out" --max-error "$err" --mem "$mem" --json \
  >"$dir/run.json" 2>"$dir/time.txt"
rss_kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$dir/time.txt")
wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$dir/time.txt")
user=$(awk -F': ' '/User time/ {print $2}' "$dir/time.txt")
sys=$(awk -F': ' '/System time/ {print $2}' "$dir/time.txt")
python3 - "$dir/run.json" "$rss_kb" "$mem" "$wall" "$user" "$sys" "$(stat -c %s "$out")" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
s = d["stats"]
rss = int(sys.argv[2]) * 1024
unit = {"K": 1 << 10, "M": 1 << 20, "G": 1 << 30}
m = sys.argv[3]
budget = int(float(m[:-1]) * unit[m[-1].upper()]) if m[-1].upper() in unit else int(m)
print(f"cells {s['cells']:,} (valid {s['valid_cells']:,}), {s['windows']} windows, "
      f"points {s['points']:,} (border {s['border_points']:,}), triangles {s['triangles']:,}")
print(f"max error {s['max_error']:.4f}, RMS {s['rms_error']:.4f}, uncovered valid cells {s['uncovered_cells']}")
print(f"wall {sys.argv[4]}, user {sys.argv[5]} s, sys {sys.argv[6]} s, output {int(sys.argv[7]):,} bytes")
print(f"peak RSS {rss / 2**20:.1f} MiB against --mem {budget / 2**20:.0f} MiB: "
      + ("within" if rss <= budget else "OVER"))
sys.exit(0 if rss <= budget else 1)
PY
if [ "${CMP:-0}" = 1 ]; then
  "$bin" simplify "$grid" -o "$dir/again.ply" --max-error "$err" --mem 2G --threads 1 -q
  cmp "$out" "$dir/again.ply" && echo "--threads 1 --mem 2G: the same bytes"
fi
