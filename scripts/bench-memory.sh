#!/usr/bin/env bash
# Memory-bounded benchmark suite (issue 40): the one-sweep engine's peak memory against --mem on
# distributions whose bounding box says little about where the points are, side by side with
# spade's in-core bulk load of the same files.
#
# Distributions (dev/gen_points.rs): square (uniform), disc, kuzmin (PBBS 2DKuzmin), disc-far
# (a disc plus one point 10^6 units away), lidar (synth::lidar_like), clustered, line (all
# collinear but one), circle. Each at every size, written as XYZ text in random order (the
# streaming engine sorts externally; XYZ always runs the one sweep), then:
#   * `sweeptin tin F.xyz -o out.stin` and `sweeptin dem F.xyz --cell C -o out.tif` (C: the
#     longer side / 1000, at most the shorter / 4) at every --mem, under /usr/bin/time (wall time, peak RSS);
#   * spade_xyz (spade 2.x bulk load, in memory) on the same file;
#   * the input orders (sorted, reversed, random, tiles, gpstime, octree) on lidar at the
#     largest size and the middle --mem, `tin` only.
# Prints a Markdown table per part; every row's peak RSS is checked against --mem + 64 MB.
#
#   scripts/bench-memory.sh [--sizes "1M 10M"] [--mems "64M 128M 512M"] [--dists "..."]
#                           [--out DIR] [--no-orders] [--no-spade] [--report] [--build DIR]
#                           [--tin-only] [--spade-timeout SECONDS]
# --report prints the tables of the results already in DIR (a run cut short).
# --tin-only skips the `dem` rows (the 10 M line's DEM takes many minutes a row).
# --build DIR uses the release build in DIR (DIR/sweeptin, DIR/examples/...) instead of building
# target/release (e.g. a faster non-LTO build made with CARGO_TARGET_DIR).
# --spade-timeout stops spade's bulk load after SECONDS (default 900: on the 10 M line it runs
# for hours); the table then says "> SECONDS".
set -euo pipefail
cd "$(dirname "$0")/.."
SIZES="1M 10M"; MEMS="64M 128M 512M"
DISTS="square disc kuzmin disc-far lidar clustered line circle"
OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench-memory}; ORDERS=1; SPADE=1; REPORT=0; BUILD=; TIN_ONLY=0
SPADE_TIMEOUT=900
while [ $# -gt 0 ]; do
    case "$1" in
        --sizes) SIZES=$2; shift 2;;
        --mems) MEMS=$2; shift 2;;
        --dists) DISTS=$2; shift 2;;
        --out) OUT=$2; shift 2;;
        --no-orders) ORDERS=0; shift;;
        --no-spade) SPADE=0; shift;;
        --report) REPORT=1; shift;;
        --build) BUILD=$2; shift 2;;
        --tin-only) TIN_ONLY=1; shift;;
        --spade-timeout) SPADE_TIMEOUT=$2; shift 2;;
        *) echo "unknown option $1" >&2; exit 2;;
    esac
done
mkdir -p "$OUT"
RESULTS="$OUT/memory-results.jsonl"
report() {
python3 - "$RESULTS" <<'PY'
import json, subprocess, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
mib = lambda s: int(s[:-1]) * (1 << 20)
cpu = [l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")][0]
print(f"\nmachine: {subprocess.getoutput('nproc')} cores, {cpu}, load {open('/proc/loadavg').read().split()[0]}")
spade = {(r["dist"], r["size"]): r for r in rows if r["part"] == "spade"}
bad = 0
for part, title in (("dists", "distributions (random order)"), ("orders", "input orders (lidar)")):
    sel = [r for r in rows if r["part"] == part]
    if not sel:
        continue
    print(f"\n### {title}\n")
    print("| distribution | points | order | --mem | command | wall s | M points/s | peak RSS MB | bound MB | within | live triangles | spade s | spade RSS MB |")
    print("|---|---:|---|---:|---|---:|---:|---:|---:|:-:|---:|---:|---:|")
    for r in sel:
        bound = mib(r["mem"]) + (64 << 20)
        ok = r["status"] == 0 and r["max_rss"] <= bound
        bad += not ok
        pts = r.get("points", 0)
        s = spade.get((r["dist"], r["size"]))
        sp = "– | –"
        if s and s["status"] == 0:
            sp = f"{s['wall_s']:.1f} | {s['max_rss']/2**20:.0f}"
        elif s and s.get("timeout"):
            sp = f"> {s['timeout']} (stopped) | {s['max_rss']/2**20:.0f}"
        flag = "yes" if ok else ("**no**" if r["status"] == 0 else f"**exit {r['status']}**")
        print(f"| {r['dist']} | {pts:,} | {r['order']} | {r['mem']} | {r['cmd']} | {r['wall_s']:.1f} | "
              f"{pts / max(r['wall_s'], 1e-9) / 1e6:.2f} | {r['max_rss']/2**20:.0f} | {bound/2**20:.0f} | {flag} | "
              f"{r.get('live', 0):,} | {sp} |")
def total(dist):
    out = {}
    for r in rows:
        if r["part"] == "dists" and r["dist"] == dist and r["cmd"] == "tin":
            out[r["size"]] = out.get(r["size"], 0.0) + r["wall_s"]
    return out
disc, kuz = total("disc"), total("kuzmin")
for size in disc:
    if size in kuz:
        print(f"\nkuzmin / disc time, tin, {size} (summed over --mem): {kuz[size] / disc[size]:.2f}")
print(f"\nrows over the bound: {bad}")
PY
}
if [ "$REPORT" = 1 ]; then report; exit 0; fi
command -v /usr/bin/time >/dev/null || { apt-get install -y -qq time >/dev/null; }
if [ -z "$BUILD" ]; then
    cargo build --release --quiet --bin sweeptin --example gen_points --example spade_xyz
    BUILD=target/release
fi
BIN=$BUILD/sweeptin
: > "$RESULTS"
echo "commit $(git rev-parse --short HEAD)$(git diff --quiet || echo +changes), $(date -u +%FT%TZ)" >&2

record() { # part dist size order mem cmd log json
    python3 - "$@" >> "$RESULTS" <<'PY'
import json, re, sys
part, dist, size, order, mem, cmd, log, js = sys.argv[1:9]
t = open(log).read()
m = re.search(r"^TIME (\S+) (\d+) (\d+)$", t, re.M)
wall, rss, status = float(m.group(1)), int(m.group(2)) * 1024, int(m.group(3))
row = {"part": part, "dist": dist, "size": size, "order": order, "mem": mem, "cmd": cmd,
       "wall_s": wall, "max_rss": rss, "status": status}
if js != "-":
    try:
        d = json.load(open(js))
        d = d.get("run", d)  # dem nests the run's summary
        row.update(points=d["points_read"], live=d["stream"]["peak_live_triangles"],
                   front=d["sweep"]["peak_front"], warnings=len(d.get("warnings", [])))
    except Exception as e:  # a failed run: its status says so
        row.update(error=str(e))
elif status == 124:  # stopped by `timeout`
    row.update(timeout=int(sys.argv[9]))
else:
    n, tris, load, secs = open(log).read().split("\n")[0].split()
    row.update(points=int(n), triangulate_s=float(secs))
print(json.dumps(row))
PY
}

timed() { # log cmd...
    local log=$1; shift
    /usr/bin/time -f "TIME %e %M %x" -a -o "$log" "$@" || true
}

gen() { # dist size order -> file; sets CELL
    local f="$OUT/$1-$2-$3.xyz"
    if [ ! -f "$f" ] || [ ! -f "$f.extent" ]; then
        $BUILD/examples/gen_points "$1" "$2" "$f" --order "$3" > "$f.extent"
    fi
    CELL=$(python3 -c "import sys; x0,y0,x1,y1=map(float,open(sys.argv[1]).read().split()); w,h=x1-x0,y1-y0; c=max(w,h,1e-6)/1000; c=min(c,min(w,h)/4) if min(w,h)>0 else c; print(f'{c:.6g}')" "$f.extent")
    FILE=$f
}

run_pair() { # part dist size order mem
    local part=$1 dist=$2 size=$3 order=$4 mem=$5 name="$1-$2-$3-$4-$5"
    : > "$OUT/$name.tin.log"
    timed "$OUT/$name.tin.log" "$BIN" tin "$FILE" -o "$OUT/out.stin" --mem "$mem" \
        --tmp-dir "$OUT" --json --quiet > "$OUT/$name.tin.json" 2>> "$OUT/$name.tin.log"
    record "$part" "$dist" "$size" "$order" "$mem" tin "$OUT/$name.tin.log" "$OUT/$name.tin.json"
    rm -f "$OUT/out.stin"
    [ "$part" = orders ] || [ "$TIN_ONLY" = 1 ] && return 0
    : > "$OUT/$name.dem.log"
    timed "$OUT/$name.dem.log" "$BIN" dem "$FILE" --cell "$CELL" -o "$OUT/out.tif" \
        --mem "$mem" --tmp-dir "$OUT" --json --quiet > "$OUT/$name.dem.json" 2>> "$OUT/$name.dem.log"
    record "$part" "$dist" "$size" "$order" "$mem" dem "$OUT/$name.dem.log" "$OUT/$name.dem.json"
    rm -f "$OUT/out.tif"
}

for size in $SIZES; do
    for dist in $DISTS; do
        gen "$dist" "$size" random
        for mem in $MEMS; do
            run_pair dists "$dist" "$size" random "$mem"
        done
        if [ "$SPADE" = 1 ]; then
            log="$OUT/spade-$dist-$size.log"; : > "$log"
            timed "$log" timeout "$SPADE_TIMEOUT" $BUILD/examples/spade_xyz "$FILE" >> "$log" 2>&1
            # The spade line first, then /usr/bin/time's.
            sort "$log" -o "$log"
            record spade "$dist" "$size" random - spade "$log" - "$SPADE_TIMEOUT"
        fi
        rm -f "$FILE"
    done
done
if [ "$ORDERS" = 1 ]; then
    size=${SIZES##* }; set -- $MEMS; mem=${2:-$1}
    for order in sorted reversed random tiles gpstime octree; do
        gen lidar "$size" "$order"
        run_pair orders lidar "$size" "$order" "$mem"
        rm -f "$FILE"
    done
fi

report
