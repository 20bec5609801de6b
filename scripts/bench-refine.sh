#!/usr/bin/env bash
# Quality refinement: `sweeptin::refine` beside Shewchuk's Triangle 1.6 (`-pzQq30`, built from
# the PyPI `triangle` sdist outside the repository, as scripts/bench-core.sh does) on the same
# planar straight-line graphs; Markdown table on stdout (and in the output directory).
#
#   scripts/bench-refine.sh [--rounds N] [--min-angle A] [--segments N] [--out DIR]
#
# Inputs (dev/bench_refine.rs `prep`, each closed by its bounding box):
#   bgt        the real BGT partition of Delft (../shared/data/lines/bgt_delft_all_layers.geojson)
#   contours   synth::contours(--segments, seed 1) (default 100,000 segments)
# Each round runs each tool once per input, alternating, one process each (so a busy machine
# slows both alike); the table keeps each tool's fastest round, the ratio of those minima, and
# the median over rounds of the two tools' time ratio in the same round (steadier under load).
# sweeptin's time is triangulate_cdt + refine (which builds its CDT again and interpolates every
# Steiner point's z); Triangle's is its triangulate() call.
# --out DIR  where results.jsonl, the logs and table.md go (default bench-out/refine-<date>).
set -euo pipefail

root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
cd "$root"

rounds=5
angle=30
segments=100000
out=""
while [ $# -gt 0 ]; do
    case "$1" in
        --rounds) rounds=$2; shift ;;
        --min-angle) angle=$2; shift ;;
        --segments) segments=$2; shift ;;
        --out) out=$2; shift ;;
        -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
        *) echo "bench-refine: unknown option $1" >&2; exit 2 ;;
    esac
    shift
done
out=${out:-bench-out/refine-$(date -u +%Y%m%d-%H%M%S)}
mkdir -p "$out/logs"
results="$out/results.jsonl"
: > "$results"
scratch=${SWEEPTIN_PEERS_DIR:-${TMPDIR:-/tmp}/sweeptin-peers}
mkdir -p "$scratch"
say() { echo "bench-refine: $*" >&2; }

say "building the runner (release)"
cargo build --release --example bench_refine >&2
runner="$root/target/release/examples/bench_refine"

build_triangle() {
    local tgz src defs="-DVOID=void -DREAL=double -DNO_TIMER -DTRILIBRARY -DANSI_DECLARATORS"
    tgz=$(ls "$scratch"/triangle-*.tar.gz 2> /dev/null | head -n1 || true)
    if [ -z "$tgz" ]; then
        (cd "$scratch" && pip download --no-binary :all: --no-deps triangle -d .) || return 1
        tgz=$(ls "$scratch"/triangle-*.tar.gz | head -n1)
    fi
    tar -xzf "$tgz" -C "$scratch" || return 1
    src="${tgz%.tar.gz}/c"
    # shellcheck disable=SC2086
    gcc -O3 $defs -w -c "$src/triangle.c" -o "$scratch/triangle.o" || return 1
    # shellcheck disable=SC2086
    gcc -O3 $defs -I"$src" scripts/peers/triangle_refine.c "$scratch/triangle.o" -lm \
        -o "$scratch/triangle_refine" || return 1
}
if ! build_triangle > "$out/logs/build-triangle.log" 2>&1; then
    say "cannot build Triangle (see $out/logs/build-triangle.log)"; exit 1
fi
triangle="$scratch/triangle_refine"
triangle_version=$(basename "$(ls "$scratch"/triangle-*.tar.gz | head -n1)" .tar.gz)

export SWEEPTIN_DATA=${SWEEPTIN_DATA:-$root/../shared/data}
"$runner" prep bgt "$scratch/refine-bgt.bin" 2> "$out/logs/prep-bgt.log"
"$runner" prep contours "$scratch/refine-contours.bin" --segments "$segments" \
    2> "$out/logs/prep-contours.log"

load_before=$(cut -d' ' -f1-3 /proc/loadavg)
for round in $(seq 1 "$rounds"); do
    for input in bgt contours; do
        file="$scratch/refine-$input.bin"
        say "round $round: $input"
        "$runner" sweeptin "$file" --repeat 1 --min-angle "$angle" >> "$results"
        "$triangle" "$file" "$angle" 1 >> "$results"
    done
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

python3 - "$results" "$angle" "$triangle_version" "$load_before" "$load_after" "$rounds" \
    << 'EOF' | tee "$out/table.md"
import json, sys
path, angle, version, before, after, rounds = sys.argv[1:7]
best, runs = {}, {}
for line in open(path):
    r = json.loads(line)
    name = r["input"].rsplit("refine-", 1)[-1].removesuffix(".bin")
    key = (name, r["tool"])
    runs.setdefault(key, []).append(r["seconds"])
    if key not in best or r["seconds"] < best[key]["seconds"]:
        best[key] = r


def paired(name):
    """Median over rounds of sweeptin's time / Triangle's in the same round."""
    pairs = sorted(a / b for a, b in zip(runs.get((name, "sweeptin"), []),
                                         runs.get((name, "triangle"), [])))
    return pairs[len(pairs) // 2] if pairs else float("nan")
print(f"Quality refinement at {angle}°: sweeptin beside Triangle ({version}, -pzQq{angle}); "
      f"fastest of {rounds} alternating rounds; load average {before} before, {after} after.\n")
print("| input | PSLG vertices / segments | tool | vertices | triangles | smallest angle | "
      "triangles < bound | seconds | triangles ÷ Triangle's | time ÷ Triangle's | "
      "median of the rounds' time ratios |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for name in ["bgt", "contours"]:
    t = best.get((name, "triangle"))
    for tool in ["sweeptin", "triangle"]:
        r = best.get((name, tool))
        if r is None:
            continue
        ratio_n = f"{r['triangles'] / t['triangles']:.3f}" if t else ""
        ratio_t = f"{r['seconds'] / t['seconds']:.2f}" if t else ""
        print(f"| {name} | {r['points']} / {r['segments']} | {tool} | {r['vertices']} | "
              f"{r['triangles']} | {r['min_angle']:.2f}° | {r['skinny']} | {r['seconds']:.3f} | "
              f"{ratio_n} | {ratio_t} | {paired(name) if tool == 'sweeptin' else 1:.2f} |")
EOF
