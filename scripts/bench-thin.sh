#!/usr/bin/env bash
# Point-cloud thinning benchmark (issue 15, item 1): `sweeptin thin` on the ARSO ground points
# (class 2, 9.0 M points) at several tolerances, beside the grid route (`sweeptin dem --cell 0.5`
# then `sweeptin simplify` of that DEM at the same tolerance). Errors of both TINs are measured
# against every ground point by an independent checker (dev/tin_errors.rs: a grid of triangles,
# barycentric interpolation), wall time and peak RSS by /usr/bin/time -v.
#
# Then `thin --tile T` (bounded memory, per tile) beside the global run at one tolerance, each
# tile size with its own --mem: kept points, border (Steiner) points, errors by the same checker,
# wall time and peak RSS.
#
# usage: scripts/bench-thin.sh [LAZ] [TOLERANCES…]
#   LAZ defaults to ../shared/data/lidar/arso_TM_511_122_from_ept.laz, tolerances to 0.05 0.1 0.5.
#   THIN_TILE_TOL (default 0.1) and THIN_TILES ("T:MEM …", default "250:256M 500:768M") set the
#   tiled runs; THIN_TILES="" skips them.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
laz=${1:-$here/../shared/data/lidar/arso_TM_511_122_from_ept.laz}
shift || true
tols=("$@")
[ ${#tols[@]} -gt 0 ] || tols=(0.05 0.1 0.5)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cargo build --release --quiet --manifest-path "$here/Cargo.toml" --bin sweeptin --example tin_errors
bin=$here/target/release/sweeptin
errors=$here/target/release/examples/tin_errors

timed() { # runs "$@" (stdout to $work/out); prints "wall_s peak_MiB"
  /usr/bin/time -v -o "$work/time" "$@" >"$work/out" 2>"$work/err"
  awk -F': ' '/Elapsed/ {n = split($2, t, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + t[i]}
              /Maximum resident/ {m = $2 / 1024} END {printf "%.1f %.0f\n", s, m}' "$work/time"
}
field() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }

echo "input: $laz --class 2; $(nproc) cores; load: $(cut -d' ' -f1-3 /proc/loadavg)"
read -r dem_s dem_mb < <(timed "$bin" dem "$laz" --class 2 --cell 0.5 -o "$work/dem.tif" --quiet)
echo "dem --cell 0.5: ${dem_s} s, peak ${dem_mb} MiB"
printf '%-26s %6s %9s %8s %9s %9s %9s %7s %8s\n' route tol kept kept_% max_err rms_err uncovered wall_s peak_MiB
for tol in "${tols[@]}"; do
  read -r s mb < <(timed "$bin" thin "$laz" --class 2 --max-error "$tol" -o "$work/thin.ply" --json --quiet)
  cp "$work/out" "$work/thin.json"
  "$errors" "$work/thin.ply" "$tol" "$laz" 2 >"$work/thin.err.json"
  printf '%-26s %6s %9s %8.2f %9.4f %9.4f %9s %7s %8s\n' "thin" "$tol" \
    "$(field "$work/thin.json" "d['thin']['kept']")" \
    "$(field "$work/thin.json" "100 * d['thin']['kept_ratio']")" \
    "$(field "$work/thin.err.json" "d['distinct']['max_error']")" \
    "$(field "$work/thin.err.json" "d['all']['rms_error']")" \
    "$(field "$work/thin.err.json" "d['all']['uncovered']")" "$s" "$mb"
  read -r s2 mb2 < <(timed "$bin" simplify "$work/dem.tif" --max-error "$tol" -o "$work/simp.ply" --json --quiet)
  cp "$work/out" "$work/simp.json"
  "$errors" "$work/simp.ply" "$tol" "$laz" 2 >"$work/simp.err.json"
  pts=$(field "$work/thin.err.json" "d['distinct']['points']")
  printf '%-26s %6s %9s %8.2f %9.4f %9.4f %9s %7s %8s\n' "dem 0.5 m + simplify" "$tol" \
    "$(field "$work/simp.json" "d['stats']['points']")" \
    "$(field "$work/simp.json" "100 * d['stats']['points'] / $pts")" \
    "$(field "$work/simp.err.json" "d['distinct']['max_error']")" \
    "$(field "$work/simp.err.json" "d['all']['rms_error']")" \
    "$(field "$work/simp.err.json" "d['all']['uncovered']")" "$s2" "$mb2"
  echo "  thin: $(field "$work/thin.err.json" "d['distinct']['beyond_tol']") distinct points beyond the tolerance (checker), over all points incl. duplicates max $(field "$work/thin.err.json" "d['all']['max_error']"); dem+simplify: $(field "$work/simp.err.json" "d['distinct']['beyond_tol']") beyond; thin's own summary: max $(field "$work/thin.json" "d['thin']['max_error']"), rms $(field "$work/thin.json" "d['thin']['rms_error']"), $(field "$work/thin.json" "d['thin']['seconds']") s thinning + $(field "$work/thin.json" "d['read_seconds']") s reading"
done

tile_tol=${THIN_TILE_TOL:-0.1}
read -r -a tile_runs <<<"${THIN_TILES-250:256M 500:768M}"
if [ ${#tile_runs[@]} -gt 0 ]; then
  echo
  echo "thin --tile at $tile_tol (load: $(cut -d' ' -f1-3 /proc/loadavg))"
  printf '%-30s %9s %8s %8s %9s %9s %9s %7s %8s\n' route kept kept_% border max_err rms_err uncovered wall_s peak_MiB
  for run in global "${tile_runs[@]}"; do
    if [ "$run" = global ]; then
      args=(); label="thin (global)"
    else
      args=(--tile "${run%%:*}" --mem "${run##*:}"); label="thin --tile ${run%%:*} --mem ${run##*:}"
    fi
    read -r s mb < <(timed "$bin" thin "$laz" --class 2 --max-error "$tile_tol" "${args[@]}" -o "$work/tile.ply" --json --quiet)
    cp "$work/out" "$work/tile.json"
    "$errors" "$work/tile.ply" "$tile_tol" "$laz" 2 >"$work/tile.err.json"
    printf '%-30s %9s %8.2f %8s %9.4f %9.4f %9s %7s %8s\n' "$label" \
      "$(field "$work/tile.json" "d['thin']['kept']")" \
      "$(field "$work/tile.json" "100 * d['thin']['kept_ratio']")" \
      "$(field "$work/tile.json" "d['tiles']['border_points'] if 'tiles' in d else 0")" \
      "$(field "$work/tile.err.json" "d['distinct']['max_error']")" \
      "$(field "$work/tile.err.json" "d['all']['rms_error']")" \
      "$(field "$work/tile.err.json" "d['all']['uncovered']")" "$s" "$mb"
    [ "$run" = global ] || echo "  $(field "$work/tile.json" "d['tiles']")"
  done
fi
