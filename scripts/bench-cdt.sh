#!/usr/bin/env bash
# Constrained Delaunay (breaklines): sweeptin's triangulate_cdt beside spade (bulk_load_cdt) and
# cdt, on the same cleaned input, one process per (tool, input), minimum of --repeat runs, peak
# RSS per tool, Markdown table on stdout (and in the output directory).
#
#   scripts/bench-cdt.sh [--repeat N] [--inputs "contours coastline"] [--points N]
#                        [--contour-segments N] [--coast-vertices N] [--out DIR]
#
# Inputs (dev/bench_cdt.rs, seed 1), each generated and cleaned once (`bench_cdt prep`,
# which also times `breaklines::clean::clean`) into a scratch file, then read by every tool:
#   contours   synth::contours(~1M segments) + synth::contour_points(1M)
#   coastline  synth::coastline(~2.9M vertices) + synth::coastline_points(1M)
# Tools: sweeptin (rayon's default pool, used by its sort), sweeptin-1t (one thread), spade, cdt.
# Every run is wrapped in /usr/bin/time -v when it exists (whole-process max RSS).
# --out DIR  where results.jsonl, the logs and table.md go (default bench-out/cdt-<date>, ignored
#            by git). The scratch inputs go to $SWEEPTIN_CDT_DIR (default $TMPDIR/sweeptin-cdt).
set -euo pipefail

root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
cd "$root"

repeat=3
inputs="contours coastline"
points=1M
contour_segments=1M
coast_vertices=2.9M
out=""
while [ $# -gt 0 ]; do
    case "$1" in
        --repeat) repeat=$2; shift ;;
        --inputs) inputs=$2; shift ;;
        --points) points=$2; shift ;;
        --contour-segments) contour_segments=$2; shift ;;
        --coast-vertices) coast_vertices=$2; shift ;;
        --out) out=$2; shift ;;
        -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
        *) echo "bench-cdt: unknown option $1" >&2; exit 2 ;;
    esac
    shift
done
out=${out:-bench-out/cdt-$(date -u +%Y%m%d-%H%M%S)}
mkdir -p "$out/logs"
results="$out/results.jsonl"
: > "$results"
scratch=${SWEEPTIN_CDT_DIR:-${TMPDIR:-/tmp}/sweeptin-cdt}
mkdir -p "$scratch"

say() { echo "bench-cdt: $*" >&2; }

if [ -x /usr/bin/time ]; then timer=(/usr/bin/time -v -o); else
    say "no /usr/bin/time: the 'max RSS (time -v)' column stays empty"; timer=(); fi

say "building the runner (release)"
cargo build --release --example bench_cdt >&2
runner="$root/target/release/examples/bench_cdt"

# run LABEL INPUT CMD...: one process; appends its JSON line (plus label and time -v max RSS).
run() {
    local label=$1 input=$2; shift 2
    local log="$out/logs/$label-$input.time" json rc=0
    say "$label $input"
    if [ ${#timer[@]} -gt 0 ]; then
        json=$("${timer[@]}" "$log" "$@") || rc=$?
    else
        json=$("$@") || rc=$?
    fi
    python3 scripts/bench_cdt_report.py record "$results" "$label" "$input" "$rc" "$log" "$json"
}

load_before=$(cut -d' ' -f1-3 /proc/loadavg)
for input in $inputs; do
    case "$input" in
        contours) lines=$contour_segments ;;
        coastline) lines=$coast_vertices ;;
        *) say "unknown input $input"; exit 2 ;;
    esac
    file="$scratch/$input.bin"
    run clean "$input" "$runner" prep "$input" "$file" --lines "$lines" --points "$points" \
        --repeat "$repeat"
    run sweeptin "$input" "$runner" sweeptin "$file" --repeat "$repeat"
    run sweeptin-1t "$input" "$runner" sweeptin "$file" --repeat "$repeat" --threads 1
    run spade "$input" "$runner" spade "$file" --repeat "$repeat"
    run cdt "$input" "$runner" cdt "$file" --repeat "$repeat"
    rm -f "$file"
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

cmd="scripts/bench-cdt.sh"
[ "$repeat" != 3 ] && cmd="$cmd --repeat $repeat"
[ "$inputs" != "contours coastline" ] && cmd="$cmd --inputs \"$inputs\""
[ "$points" != 1M ] && cmd="$cmd --points $points"
[ "$contour_segments" != 1M ] && cmd="$cmd --contour-segments $contour_segments"
[ "$coast_vertices" != 2.9M ] && cmd="$cmd --coast-vertices $coast_vertices"
python3 scripts/bench_cdt_report.py table "$results" \
    --command "$cmd" --load-before "$load_before" --load-after "$load_after" | tee "$out/table.md"
say "results in $out"
