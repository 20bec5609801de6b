#!/usr/bin/env bash
# Grid-to-TIN benchmark: sweeptin simplify (windows on every core, one thread, one whole-grid
# window) beside delatin (npm; a JS port of fogleman's hmm) and, when built, hmm itself, on the
# same grid and maximum error. Runs are interleaved; the minimum wall time and the minimum CPU
# time (user + sys) of N runs are reported, which is robust on a shared machine.
#
# usage: scripts/bench-simplify.sh [DEM] [MAX_ERROR] [RUNS]
#   DEM defaults to Big Tujunga (shared/data/dem), MAX_ERROR to 5, RUNS to 5.
# needs: node + `npm install delatin` in $PEERS (default /tmp/peers); optional: $HMM = path to
# hmm's triangulator built with our raw-grid driver (see scripts/peers/README.md); $WINDOWS =
# extra --window values to time (e.g. "64 256 512").
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
dem=${1:-$here/../shared/data/dem/topotoolbox_srtm_bigtujunga30m_utm11.tif}
[ -n "$dem" ] || dem=$here/../shared/data/dem/topotoolbox_srtm_bigtujunga30m_utm11.tif
err=${2:-5}
runs=${3:-5}
peers=${PEERS:-/tmp/peers}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cargo build --release --quiet --manifest-path "$here/Cargo.toml" --bin sweeptin --example dem_to_raw
bin=$here/target/release/sweeptin
read -r cols rows < <("$here/target/release/examples/dem_to_raw" "$dem" "$work/grid.f64")

# time_run NAME CMD...: appends "wall cpu" of one run to $work/NAME.t, keeps its stdout as
# $work/NAME.json
time_run() {
  local name=$1
  shift
  /usr/bin/time -f "%e %U %S" -o "$work/time" "$@" >"$work/$name.json" 2>"$work/err" || {
    cat "$work/err" >&2
    exit 1
  }
  awk '{print $1, $2 + $3}' "$work/time" >>"$work/$name.t"
}

names=()
for i in $(seq "$runs"); do
  time_run ours "$bin" simplify "$dem" -o "$work/tin.ply" --max-error "$err" --json
  time_run ours_t1 "$bin" simplify "$dem" -o "$work/tin1.ply" --max-error "$err" --threads 1 --json
  cmp -s "$work/tin.ply" "$work/tin1.ply" || { echo "--threads 1 and 2 differ" >&2; exit 1; }
  time_run greedy "$bin" simplify "$dem" -o "$work/tin.ply" --max-error "$err" --no-decimate --json
  time_run whole "$bin" simplify "$dem" -o "$work/tin.ply" --max-error "$err" --window 1000000 --json
  for w in ${WINDOWS:-}; do
    time_run "window$w" "$bin" simplify "$dem" -o "$work/tin.ply" --max-error "$err" --window "$w" --json
  done
  if [ -d "$peers/node_modules/delatin" ]; then
    cp "$here/scripts/peers/delatin_run.mjs" "$peers/"
    time_run delatin node "$peers/delatin_run.mjs" "$work/grid.f64" "$cols" "$rows" "$err"
  fi
  if [ -n "${HMM:-}" ]; then
    time_run hmm "$HMM" "$work/grid.f64" "$cols" "$rows" "$err"
  fi
done

field() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
best() { sort -g -k"$2" "$1" | head -1 | awk -v k="$2" '{print $k}'; }
row() { # label name points-expr triangles-expr error-expr
  printf '| %s | %s | %s | %s | %s | %s |\n' "$1" \
    "$(field "$work/$2.json" "$3")" "$(field "$work/$2.json" "$4")" \
    "$(field "$work/$2.json" "$5")" "$(best "$work/$2.t" 1)" "$(best "$work/$2.t" 2)"
}
ours() { row "$1" "$2" "d['stats']['points']" "d['stats']['triangles']" "round(d['stats']['max_error'], 4)"; }
echo "grid: $dem (${cols}×${rows}), max error $err, minimum of $runs interleaved runs"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg), cores: $(nproc)"
echo
echo "| tool | points | triangles | max error | wall s | CPU s |"
echo "|---|---:|---:|---:|---:|---:|"
ours "sweeptin (default: windows of 128, every core)" ours
ours "sweeptin --threads 1" ours_t1
ours "sweeptin --no-decimate" greedy
ours "sweeptin, one window (the whole grid)" whole
for w in ${WINDOWS:-}; do ours "sweeptin --window $w" "window$w"; done
if [ -f "$work/delatin.t" ]; then
  row "delatin $(node -p "require('$peers/node_modules/delatin/package.json').version")" delatin \
    "d['points']" "d['triangles']" "d['max_error']"
fi
if [ -f "$work/hmm.t" ]; then
  row "hmm (fogleman, C++)" hmm "d['points']" "d['triangles']" "d['max_error']"
fi
echo
echo "border points of the default run: $(field "$work/ours.json" "d['stats']['border_points']") in $(field "$work/ours.json" "d['stats']['windows']") windows"
