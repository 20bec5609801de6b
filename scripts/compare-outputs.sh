#!/usr/bin/env bash
# Runs a fixed set of commands on the real files in ../shared/data with one sweeptin binary and
# prints the sha256 of every output, so two builds (before and after a refactor) can be compared:
#
#   scripts/compare-outputs.sh OLD_BIN /tmp/out-old > old.sha
#   scripts/compare-outputs.sh target/release/sweeptin /tmp/out-new > new.sha
#   diff old.sha new.sha && echo identical
#
# TRI_ARGS is appended to every triangulating command (e.g. TRI_ARGS="--engine sweep" to compare
# the sweep of a newer binary with an older one; the DEMs of the two engines are the same bytes).
#
# Timing-dependent fields (seconds, peak memory) are not in any output file, and the LandXML
# header's date and time are blanked, so the hashes are deterministic. Set FULL=1 to include the 13.2M-point ARSO tile (about a minute more).
set -euo pipefail
BIN=$(realpath "$1"); OUT=$2
D=${SWEEPTIN_DATA:-$(realpath "$(dirname "$0")/../../shared/data")}
rm -rf "$OUT"; mkdir -p "$OUT"; cd "$OUT"
L=$D/lidar; T=$L/ign_50m_tiles; LN=$D/lines
run() { "$BIN" "$@" ${TRI_ARGS:-} -q >/dev/null 2>&1 || { echo "FAILED: $*" >&2; exit 1; }; }
run tin "$L/startinpy_small.laz" -o small.ply
run tin "$L/startinpy_small.laz" -o small.obj
run tin "$L/startinpy_small.laz" -o small.xml
run tin "$L/startinpy_small.laz" -o small.stin
run tin "$T"/*_IGN69.laz --class 2 -o ign.ply --mem 8M
run tin "$L/ahn3_delft_cropped_1.laz" "$L/ahn3_delft_cropped_2.laz" --class 2 -o ahn.ply
printf '84850 447450 1.0\n84950 447600 2.0\n\n84850 447600\n84950 447450\n84990 447500\n' > bl.txt
run tin "$L/ahn3_delft_cropped_1.laz" --class 2 --breaklines bl.txt -o ahn_bl.ply
run dem "$L/ahn3_delft_cropped_1.laz" --class 2 --breaklines bl.txt --cell 0.5 -o ahn_bl.tif
run tin "$L/lidR_Topography.laz" --max-edge 5 -o topo_trim.ply
run tin "$L/ign_test_semis_2023_0299_6802_LA93_IGN69.laz" --sweep-axis x -o semis_x.ply
run dem "$T"/*_IGN69.laz --class 2 --cell 0.5 -o ign.tif --contours ign_c.geojson --hillshade ign_h.png
run dem "$T"/*_IGN69.laz --class 2 --cell 0.5 -o ign.asc
run dem "$L/lidR_Topography.laz" --class 2 --cell 1 -o topo.tif --max-edge 20
run dem small.stin --cell 0.5 -o small_stin.tif
run dem "$T"/*_IGN69.laz --class 2 --cell 0.5 --bbox 770550,6277550,770600,6277600 --buffer 10 -o ign_bbox.tif
run contours "$L/lidR_Topography.laz" --interval 0.5 -o topo_c.geojson
run volume "$L/lidR_Topography.laz" --class 2 --plane 800 --json > vol.json 2>/dev/null || true
"$BIN" volume "$L/lidR_Topography.laz" --class 2 --plane 800 ${TRI_ARGS:-} -q > vol.txt
printf '273400 5274400\n273500 5274500\n273600 5274600\n' > q.csv
run sample "$L/lidR_Topography.laz" --class 2 --points q.csv -o sample.csv
"$BIN" hillshade ign.tif -o shade.png >/dev/null 2>&1
"$BIN" simplify "$D/dem/topotoolbox_srtm_bigtujunga30m_utm11.tif" --max-error 5 -o tuj.ply -q >/dev/null 2>&1
if [ "${FULL:-0}" = 1 ]; then
    run tin "$L/arso_TM_511_122_from_ept.laz" --mem 128M -o arso.ply
    run dem "$L/arso_TM_511_122_from_ept.laz" --mem 128M --cell 1 -o arso.tif
    run dem "$L/arso_TM_511_122_from_ept.laz" --mem 128M --cell 1 --class 2 -o arso_g.tif --contours arso_g.geojson
fi
rm -f vol.json q.csv bl.txt
# The volume text summary carries the elapsed time; keep only its numbers that are not times.
grep -v -i -E 'second|[0-9] s\b|memory|MiB|MB' vol.txt > vol.clean || true; rm vol.txt
# LandXML requires the writing date and time in its header: blank them.
sed -i -E '2s/ date="[^"]*" time="[^"]*"//' small.xml
sha256sum $(ls | sort)
