#!/usr/bin/env bash
# Remote inputs (issue 44) over loopback nginx, against the same files read locally:
#  1. bytes transferred by a COPC --bbox read, against the bytes of the chunks of the octree
#     nodes that meet the box plus the hierarchy pages (copclib's count; target <= 1.2x);
#  2. `dem --cell 1` of the ARSO tile as COPC over HTTP against the local COPC (target <= 1.3x).
# The COPC copy of ARSO is written once by scripts/make_copc.py (copclib) into the output
# folder. Release build in its own target dir (no LTO, 16 codegen units: the shared machine).
# Prints a Markdown table (median of --runs wall times).
#
#   scripts/bench-remote.sh [--runs 3] [--out DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=3; OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench-remote}
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) RUNS=$2; shift 2;;
        --out) OUT=$2; shift 2;;
        *) echo "unknown option $1" >&2; exit 2;;
    esac
done
mkdir -p "$OUT/www"
python3 -c 'import copclib' 2>/dev/null ||
    python3 -m pip install --quiet --disable-pip-version-check copclib==2.6.3
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target-rel}
CARGO_PROFILE_RELEASE_LTO=false CARGO_PROFILE_RELEASE_CODEGEN_UNITS=16 \
    cargo build --release --quiet --bin sweeptin
BIN=$CARGO_TARGET_DIR/release/sweeptin
NGINX=$(command -v nginx || echo /usr/sbin/nginx)
ARSO=${SWEEPTIN_DATA:-../shared/data}/lidar/arso_TM_511_122_from_ept.laz
COPC=$OUT/www/arso.copc.laz
[ -f "$COPC" ] || python3 scripts/make_copc.py "$ARSO" "$COPC" --page-depth 3
cp -f tests/data/lidR_Topography.copc.laz "$OUT/www/topo.copc.laz"

PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
USER_LINE=""; [ "$(id -u)" = 0 ] && USER_LINE="user root root;"
cat > "$OUT/nginx.conf" <<CONF
$USER_LINE
worker_processes 2;
pid $OUT/nginx.pid;
error_log $OUT/error.log;
events { worker_connections 256; }
http {
  log_format bytes '\$request \$status \$body_bytes_sent';
  access_log $OUT/access.log bytes;
  client_body_temp_path $OUT; proxy_temp_path $OUT; fastcgi_temp_path $OUT;
  uwsgi_temp_path $OUT; scgi_temp_path $OUT;
  server { listen 127.0.0.1:$PORT; root $OUT/www; location / { } }
}
CONF
"$NGINX" -p "$OUT" -c "$OUT/nginx.conf" -g 'daemon off;' &
NGINX_PID=$!
trap 'kill $NGINX_PID' EXIT
sleep 1
URL=http://127.0.0.1:$PORT

sent() { awk '{s += $NF} END {print s + 0}' "$OUT/access.log"; }
needed() { # file xmin ymin xmax ymax → bytes of the nodes meeting the box + hierarchy EVLRs
    python3 - "$@" <<'PY'
import sys, struct, copclib as copc
path = sys.argv[1]
x0, y0, x1, y1 = map(float, sys.argv[2:6])
nodes = copc.FileReader(path).GetNodesIntersectBox(copc.Box(x0, y0, -1e12, x1, y1, 1e12))
hier = 0
with open(path, "rb") as f:  # the copc/1000 EVLRs: every hierarchy page
    f.seek(235); at, n = struct.unpack("<QI", f.read(12))
    for _ in range(n):
        f.seek(at); h = f.read(60)
        rid, length = struct.unpack("<HQ", h[18:28])
        if h[2:18].rstrip(b"\0") == b"copc" and rid == 1000:
            hier += length
        at += 60 + length
print(sum(n.byte_size for n in nodes) + hier)
PY
}
median() { # command… → median wall seconds over $RUNS runs
    python3 - "$RUNS" "$@" <<'PY'
import subprocess, sys, time, statistics
runs, cmd = int(sys.argv[1]), sys.argv[2:]
t = []
for _ in range(runs):
    s = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t.append(time.perf_counter() - s)
print(f"{statistics.median(t):.3f}")
PY
}

echo "| read | bytes transferred | bytes needed (nodes + hierarchy) | ratio |"
echo "|---|---|---|---|"
for spec in "topo.copc.laz 273400 5274400 273450 5274450" "arso.copc.laz 511400 122400 511500 122500"; do
    set -- $spec
    : > "$OUT/access.log"
    "$BIN" dem "$URL/$1" --bbox "$2,$3,$4,$5" --cell 1 -q -o "$OUT/box.tif"
    s=$(sent); n=$(needed "$OUT/www/$1" "$2" "$3" "$4" "$5")
    echo "| $1 --bbox $2,$3,$4,$5 | $s | $n | $(python3 -c "print(f'{$s/$n:.2f}')") |"
done
echo
echo "| dem --cell 1, ARSO COPC | seconds (median of $RUNS) |"
echo "|---|---|"
L=$(median "$BIN" dem "$COPC" --cell 1 -q -o "$OUT/l.tif")
R=$(median "$BIN" dem "$URL/arso.copc.laz" --cell 1 -q -o "$OUT/r.tif")
echo "| local file | $L |"
echo "| loopback nginx | $R ($(python3 -c "print(f'{$R/$L:.2f}')")×) |"
cmp "$OUT/l.tif" "$OUT/r.tif" && echo "(the two DEMs are byte-identical)"
