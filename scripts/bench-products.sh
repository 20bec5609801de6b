#!/usr/bin/env bash
# Terrain products benchmark: LAZ -> DEM (float32 GeoTIFF) with sweeptin, timed with
# /usr/bin/time -v (wall time and max RSS of the whole process), beside `gdal_grid -a linear`
# (GDAL's Delaunay/linear interpolation, the common open-source way to grid lidar).
#
#   scripts/bench-products.sh [--file LAZ] [--cell SIZE] [--class LIST] [--mem SIZE]
#                             [--with-gdal] [--out DIR]
#
# Defaults: the 13.2 M-point ARSO tile /work/shared/data/lidar/arso_TM_511_122_from_ept.laz (or
# $SWEEPTIN_DATA/lidar/...), 1 m cells, every point, --mem 1G, output in
# bench-out/products-<date> (ignored by git).
#
# Runs, each in its own process:
#   1. sweeptin dem                       (DEM only)
#   2. sweeptin products --dem --contours (DEM + 1 m contours + hillshade in one pass)
#   3. with --with-gdal: gdal_grid -a linear on the same points (as CSV through an OGR VRT, since
#      GDAL reads no LAS without the PDAL plugin), same extent and cell centres. SLOW and big: it
#      was measured at 284 s and 11.9 GB on this tile; run it once, it is niced.
# PDAL (readers.las -> filters.delaunay -> filters.faceraster -> writers.gdal) is the peer the
# issue names, but it is not installable here (no Debian package, no binary wheel); the script
# runs it when a `pdal` command is found.
set -euo pipefail

root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
cd "$root"

data=${SWEEPTIN_DATA:-/work/shared/data}
file="$data/lidar/arso_TM_511_122_from_ept.laz"
cell=1
class=""
mem=1G
gdal=0
out=""
while [ $# -gt 0 ]; do
    case "$1" in
        --file) file=$2; shift ;;
        --cell) cell=$2; shift ;;
        --class) class=$2; shift ;;
        --mem) mem=$2; shift ;;
        --with-gdal) gdal=1 ;;
        --out) out=$2; shift ;;
        -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
        *) echo "bench-products: unknown option $1" >&2; exit 2 ;;
    esac
    shift
done
out=${out:-bench-out/products-$(date -u +%Y%m%d-%H%M%S)}
mkdir -p "$out"
say() { echo "bench-products: $*" >&2; }

if [ ! -x /usr/bin/time ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get > /dev/null; then
        apt-get install -y time > /dev/null
    else
        say "/usr/bin/time not found (Debian package time)"; exit 1
    fi
fi

cargo build --release --quiet --bin sweeptin --example las_to_csv
bin=target/release/sweeptin
class_args=()
[ -n "$class" ] && class_args=(--class "$class")

# One timed run: NAME then the command. Prints "NAME seconds max_rss_MiB".
timed() {
    local name=$1; shift
    /usr/bin/time -v -o "$out/$name.time" "$@" > "$out/$name.stdout" 2> "$out/$name.stderr"
    local wall rss
    wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$out/$name.time")
    rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$out/$name.time")
    printf '| %s | %s | %.0f MiB |\n' "$name" "$wall" "$(echo "$rss / 1024" | bc -l)" | tee -a "$out/table.md"
}

say "input $file, cell $cell, class ${class:-all}, mem $mem, output in $out"
{
    echo "| run | wall time | max RSS |"
    echo "|---|---:|---:|"
} > "$out/table.md"
cat "$out/table.md"
timed sweeptin-dem "$bin" dem "$file" "${class_args[@]}" -o "$out/dem.tif" --cell "$cell" \
    --mem "$mem" --tmp-dir "$out" --json -q
timed sweeptin-products "$bin" products "$file" "${class_args[@]}" --dem "$out/dem2.tif" \
    --cell "$cell" --contours "$out/contours.geojson" --interval 1 --hillshade "$out/shade.png" \
    --mem "$mem" --tmp-dir "$out" --json -q
cmp -s "$out/dem.tif" "$out/dem2.tif" || say "WARNING: the DEMs of runs 1 and 2 differ"

if command -v pdal > /dev/null; then
    say "pdal found: running readers.las -> filters.delaunay -> filters.faceraster -> writers.gdal"
    cat > "$out/pipeline.json" <<JSON
[ "$file", { "type": "filters.delaunay" },
  { "type": "filters.faceraster", "resolution": $cell },
  { "type": "writers.gdal", "filename": "$out/pdal.tif", "data_type": "float32" } ]
JSON
    timed pdal nice pdal pipeline "$out/pipeline.json"
else
    say "pdal not installed (not installable here): skipped"
fi

if [ "$gdal" = 1 ]; then
    command -v gdal_grid > /dev/null || { say "gdal_grid not found (apt-get install -y gdal-bin)"; exit 1; }
    target/release/examples/las_to_csv "${class_args[@]}" "$out/points.csv" "$file"
    cat > "$out/points.vrt" <<VRT
<OGRVRTDataSource><OGRVRTLayer name="points"><SrcDataSource>$out/points.csv</SrcDataSource>
<GeometryType>wkbPoint</GeometryType><GeometryField encoding="PointFromColumns" x="x" y="y" z="z"/>
</OGRVRTLayer></OGRVRTDataSource>
VRT
    # The same cells as sweeptin's DEM: read its georeferencing.
    read -r x0 y1 cols rows < <(python3 -c "
import json,subprocess
d=json.loads(subprocess.check_output(['gdalinfo','-json','$out/dem.tif']))
g=d['geoTransform']; print(g[0], g[3], d['size'][0], d['size'][1])")
    x1=$(echo "$x0 + $cols * $cell" | bc -l)
    y0=$(echo "$y1 - $rows * $cell" | bc -l)
    timed gdal_grid-linear nice gdal_grid -q -a linear -ot Float32 -of GTiff -l points \
        -txe "$x0" "$x1" -tye "$y1" "$y0" -outsize "$cols" "$rows" \
        "$out/points.vrt" "$out/gdal.tif"
fi
say "table in $out/table.md"
