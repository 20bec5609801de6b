#!/usr/bin/env bash
# Remote inputs (issue 44) over loopback nginx, against the same files read locally:
#  1. bytes transferred by a COPC --bbox read, against the bytes of the chunks of the octree
#     nodes that meet the box plus the hierarchy pages (copclib's count; target <= 1.2x);
#  2. `dem --cell 1` of the ARSO tile as COPC over HTTP against the local COPC (target <= 1.3x);
#  3. `plan dem VPC --cell 1 --class 2 --tile 25`, `run --all`, `merge` of the six IGN tiles:
#     (a) local files, local plan directory; (b) the VPC over nginx, local plan directory;
#     (c) the VPC over nginx, the plan directory and the mosaic on S3 (moto_server, as
#     tests/support/remote.rs starts it). Wall and user+sys seconds of each step (sweeptin's
#     own, not the servers'), medians of --runs; the three mosaics compared byte for byte.
# The COPC copy of ARSO is written once by scripts/make_copc.py (copclib) into the output
# folder. Release build in its own target dir (no LTO, 16 codegen units: the shared machine).
# Prints a Markdown table (median of --runs wall times).
#
#   scripts/bench-remote.sh [--runs 3] [--out DIR] [--plan-only]   (--plan-only: only 3.)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=3; OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench-remote}; PLAN_ONLY=
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) RUNS=$2; shift 2;;
        --out) OUT=$2; shift 2;;
        --plan-only) PLAN_ONLY=1; shift;;
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
[ -n "$PLAN_ONLY" ] || [ -f "$COPC" ] || python3 scripts/make_copc.py "$ARSO" "$COPC" --page-depth 3
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
MOTO_PID=
trap 'kill $NGINX_PID $MOTO_PID' EXIT
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

plans() { # 3.: the six IGN tiles, local / remote VPC / remote VPC and plan directory on S3
    mkdir -p "$OUT/www/ign"
    cp -f tests/data/lidar/ign_50m_tiles/*_IGN69.laz "$OUT/www/ign/"
    (cd "$OUT/www/ign" && "$BIN" index *.laz -o ign.vpc >/dev/null)
    local mport
    mport=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
    moto_server -H 127.0.0.1 -p "$mport" >/dev/null 2>&1 &
    MOTO_PID=$!
    until curl -s -o /dev/null "http://127.0.0.1:$mport/"; do sleep 0.2; done
    curl -s -f -X PUT "http://127.0.0.1:$mport/jobs" >/dev/null
    AWS_ENDPOINT_URL=http://127.0.0.1:$mport AWS_ACCESS_KEY_ID=benchkey \
    AWS_SECRET_ACCESS_KEY=benchsecret AWS_REGION=us-east-1 \
    python3 - "$RUNS" "$BIN" "$OUT" "$OUT/www/ign/ign.vpc" "$URL/ign/ign.vpc" <<'PY'
import os, shutil, statistics, subprocess, sys, time, boto3
runs, bin_, out, local_vpc, url_vpc = int(sys.argv[1]), *sys.argv[2:]
s3env = {k: os.environ.pop(k) for k in list(os.environ) if k.startswith("AWS_")}
job = ["dem", None, "--cell", "1", "--class", "2", "--tile", "25"]

def timed(args, env):
    quiet = [] if args[0] == "plan" else ["-q"]
    start = time.perf_counter()
    with open(os.path.join(out, "stderr.txt"), "w+") as err:
        p = subprocess.Popen([bin_, *args, *quiet], env={**os.environ, **env},
                             stdout=subprocess.DEVNULL, stderr=err)
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.perf_counter() - start
        if status != 0:
            err.seek(0)
            sys.exit(f"sweeptin {' '.join(args)}: {err.read()}")
    return wall, ru.ru_utime + ru.ru_stime

cases = [("local files, local plan directory", local_vpc, False),
         ("VPC over nginx, local plan directory", url_vpc, False),
         ("VPC over nginx, plan directory and mosaic on S3 (moto)", url_vpc, True)]
mosaics, rows = [], []
for name, vpc, on_s3 in cases:
    times = {"plan": [], "run --all": [], "merge": []}
    env = s3env if on_s3 else {}
    for i in range(runs):
        if on_s3:
            d, m = f"s3://jobs/run{i}/", f"s3://jobs/mosaic{i}.tif"
        else:
            d, m = os.path.join(out, f"plan{len(mosaics)}"), os.path.join(out, f"m{len(mosaics)}.tif")
            shutil.rmtree(d, ignore_errors=True)
        plan = d.rstrip("/") + "/plan.json"
        times["plan"].append(timed(["plan", *[vpc if a is None else a for a in job], "-o", d], env))
        times["run --all"].append(timed(["run", plan, "--all"], env))
        times["merge"].append(timed(["merge", plan, "-o", m], env))
    if on_s3:
        local_m = os.path.join(out, "m_s3.tif")
        boto3.client("s3", endpoint_url=s3env["AWS_ENDPOINT_URL"],
                     aws_access_key_id=s3env["AWS_ACCESS_KEY_ID"],
                     aws_secret_access_key=s3env["AWS_SECRET_ACCESS_KEY"],
                     region_name="us-east-1").download_file("jobs", f"mosaic{runs - 1}.tif", local_m)
        m = local_m
    mosaics.append(open(m, "rb").read())
    cells = []
    for step, t in times.items():
        cells.append(f"{statistics.median(w for w, _ in t):.2f} / {statistics.median(c for _, c in t):.2f}")
    total = statistics.median(sum(times[k][i][0] for k in times) for i in range(runs))
    rows.append((name, cells, total))
print(f"| {runs} runs, median wall / user+sys s | plan | run --all | merge | total wall | ratio |")
print("|---|---|---|---|---|---|")
for name, cells, total in rows:
    print(f"| {name} | {' | '.join(cells)} | {total:.2f} | {total / rows[0][2]:.2f} |")
same = all(x == mosaics[0] for x in mosaics)
print(f"\n(the three mosaics, {len(mosaics[0]):,} bytes, are {'byte-identical' if same else 'NOT identical'})")
sys.exit(0 if same else 1)
PY
}
if [ -n "$PLAN_ONLY" ]; then plans; exit; fi

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
echo
plans
