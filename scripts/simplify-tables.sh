#!/usr/bin/env bash
# Soomart & Paitoonwattanakij's tables 1–2, reproduced with sweeptin simplify on one DEM.
# usage: scripts/simplify-tables.sh DEM "E1 E2 …"   (prints two markdown tables; one window, the whole grid)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
dem=$1
bounds=$2
cargo build --release --quiet --manifest-path "$here/Cargo.toml" --bin sweeptin
bin=$here/target/release/sweeptin
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for mode in greedy removal; do
  flag=""
  [ "$mode" = greedy ] && flag="--no-decimate"
  for e in $bounds; do
    "$bin" simplify "$dem" -o "$out/t.ply" --max-error "$e" $flag --window 1000000 --json >"$out/$mode-$e.json" 2>/dev/null
  done
done
python3 - "$out" "$bounds" <<'PY'
import json, sys
out, bounds = sys.argv[1], sys.argv[2].split()
rows = [
    ("Split points (insertions)", lambda s: s["insertions"]),
    ("Swapped diagonals (flips)", lambda s: s["flips"]),
    ("Triangle scans", lambda s: s["scans"]),
    ("Points removed again", lambda s: s["removed"]),
    ("Subset points", lambda s: s["points"]),
    ("Irregular triangles", lambda s: s["triangles"]),
    ("Time (s)", lambda s: f'{s["seconds"]:.3f}'),
    ("Point's ratio (%)", lambda s: f'{100 * s["point_ratio"]:.2f}'),
    ("Triangle's ratio (%)", lambda s: f'{100 * s["triangle_ratio"]:.2f}'),
    ("Max error", lambda s: f'{s["max_error"]:.3f}'),
    ("RMS error", lambda s: f'{s["rms_error"]:.3f}'),
]
for mode, title in [("greedy", "(a) greedy insertion (`--no-decimate`)"),
                    ("removal", "(b) greedy insertion + redundant-point removal (default)")]:
    stats = {e: json.load(open(f"{out}/{mode}-{e}.json"))["stats"] for e in bounds}
    print(f"\n{title}\n")
    print("| Distance threshold | " + " | ".join(bounds) + " |")
    print("|---|" + "---|" * len(bounds))
    for name, f in rows:
        print(f"| {name} | " + " | ".join(str(f(stats[e])) for e in bounds) + " |")
PY
