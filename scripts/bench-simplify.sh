#!/usr/bin/env bash
# Grid-to-TIN benchmark: sweeptin simplify beside delatin (npm; a JS port of fogleman's hmm) and,
# when built, hmm itself, on the same grid and maximum error. Runs are interleaved and the
# minimum CPU time (user + sys) of N runs is reported, which is robust on a shared machine.
#
# usage: scripts/bench-simplify.sh [DEM] [MAX_ERROR] [RUNS]
#   DEM defaults to Big Tujunga (shared/data/dem), MAX_ERROR to 5, RUNS to 5.
# needs: node + `npm install delatin` in $PEERS (default /tmp/peers); optional: $HMM = path to
# hmm's triangulator built with our raw-grid driver (see scripts/peers/README.md).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
dem=${1:-$here/../shared/data/dem/topotoolbox_srtm_bigtujunga30m_utm11.tif}
err=${2:-5}
runs=${3:-5}
peers=${PEERS:-/tmp/peers}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cargo build --release --quiet --manifest-path "$here/Cargo.toml" --bin sweeptin --example dem_to_raw
bin=$here/target/release/sweeptin
read -r cols rows < <("$here/target/release/examples/dem_to_raw" "$dem" "$work/grid.f64")

cpu() { # prints user+sys seconds of one run of "$@"; the command's stdout goes to $work/out
  /usr/bin/time -f "%U %S" -o "$work/time" "$@" >"$work/out" 2>"$work/err"
  awk '{print $1 + $2}' "$work/time"
}
min() { sort -g | head -1; }

declare -A best
for i in $(seq "$runs"); do
  echo "$(cpu "$bin" simplify "$dem" -o "$work/tin.ply" --max-error "$err" --json)" >>"$work/ours"
  cp "$work/out" "$work/ours.json"
  echo "$(cpu "$bin" simplify "$dem" -o "$work/tin.ply" --max-error "$err" --no-decimate --json)" >>"$work/greedy"
  cp "$work/out" "$work/greedy.json"
  if [ -d "$peers/node_modules/delatin" ]; then
    cp "$here/scripts/peers/delatin_run.mjs" "$peers/"
    echo "$(cpu node "$peers/delatin_run.mjs" "$work/grid.f64" "$cols" "$rows" "$err")" >>"$work/delatin"
    cp "$work/out" "$work/delatin.json"
  fi
  if [ -n "${HMM:-}" ]; then
    echo "$(cpu "$HMM" "$work/grid.f64" "$cols" "$rows" "$err")" >>"$work/hmm"
    cp "$work/out" "$work/hmm.json"
  fi
done

field() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
echo "grid: $dem (${cols}×${rows}), max error $err, min CPU seconds of $runs runs"
printf '%-28s %10s %10s %10s %8s\n' tool points triangles max_error cpu_s
printf '%-28s %10s %10s %10s %8s\n' "sweeptin (greedy+removal)" \
  "$(field "$work/ours.json" "d['stats']['points']")" "$(field "$work/ours.json" "d['stats']['triangles']")" \
  "$(field "$work/ours.json" "round(d['stats']['max_error'], 4)")" "$(min <"$work/ours")"
printf '%-28s %10s %10s %10s %8s\n' "sweeptin --no-decimate" \
  "$(field "$work/greedy.json" "d['stats']['points']")" "$(field "$work/greedy.json" "d['stats']['triangles']")" \
  "$(field "$work/greedy.json" "round(d['stats']['max_error'], 4)")" "$(min <"$work/greedy")"
if [ -f "$work/delatin" ]; then
  printf '%-28s %10s %10s %10s %8s\n' "delatin $(node -p "require('$peers/node_modules/delatin/package.json').version")" \
    "$(field "$work/delatin.json" "d['points']")" "$(field "$work/delatin.json" "d['triangles']")" \
    "$(field "$work/delatin.json" "d['max_error']")" "$(min <"$work/delatin")"
fi
if [ -f "$work/hmm" ]; then
  printf '%-28s %10s %10s %10s %8s\n' "hmm (fogleman, C++)" \
    "$(field "$work/hmm.json" "d['points']")" "$(field "$work/hmm.json" "d['triangles']")" \
    "$(field "$work/hmm.json" "d['max_error']")" "$(min <"$work/hmm")"
fi
