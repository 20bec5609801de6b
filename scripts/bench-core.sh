#!/usr/bin/env bash
# Core sweep vs peers: one process per (algorithm, distribution, size), median of --repeat runs,
# peak RSS per algorithm, Markdown table on stdout (and in the output directory).
#
#   scripts/bench-core.sh [--big] [--repeat N] [--sizes "1M 4M"] [--dists "uniform lidar-like clustered"]
#                         [--no-external] [--out DIR]
#
# --big          adds 16M points (spade/delaunator/cdt need several GB there).
# --no-external  skips CGAL and Triangle.
# --out DIR      where results.jsonl, the /usr/bin/time logs and table.md go
#                (default: bench-out/core-<date>, ignored by git).
#
# In-process peers (dev/bench_core.rs): sweeptin (rayon's default pool, used by its sort),
# sweeptin with one thread ("sweeptin-1t"), delaunator, spade (bulk_load), cdt.
# External peers, built in a scratch directory outside the repository ($SWEEPTIN_PEERS_DIR,
# default $TMPDIR/sweeptin-peers), each skipped with a message when it cannot be built:
#   cgal      scripts/peers/cgal_dt.cpp, Delaunay_triangulation_2 + Epick, range insert
#             (Debian libcgal-dev; installed with apt-get when missing and running as root);
#   triangle  scripts/peers/triangle_dt.c linked with Shewchuk's triangle.c from the PyPI `triangle`
#             sdist (pip download --no-binary :all:), -O3, switches "zQNB": divide and conquer,
#             default exact adaptive arithmetic, no quality options.
# Every run is wrapped in /usr/bin/time -v (Debian `time`, installed when missing) for the whole
# process's max RSS, input generation included; the table's "peak RSS" is the runner's own VmHWM
# measured around the triangulation only (input in the algorithm's layout included).
set -euo pipefail

root=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
cd "$root"

sizes="1M 4M"
dists="uniform lidar-like clustered"
repeat=3
external=1
out=""
while [ $# -gt 0 ]; do
    case "$1" in
        --big) sizes="$sizes 16M" ;;
        --repeat) repeat=$2; shift ;;
        --sizes) sizes=$2; shift ;;
        --dists) dists=$2; shift ;;
        --no-external) external=0 ;;
        --out) out=$2; shift ;;
        -h|--help) sed -n '2,25p' "$0"; exit 0 ;;
        *) echo "bench-core: unknown option $1" >&2; exit 2 ;;
    esac
    shift
done
out=${out:-bench-out/core-$(date -u +%Y%m%d-%H%M%S)}
mkdir -p "$out/logs"
results="$out/results.jsonl"
: > "$results"
scratch=${SWEEPTIN_PEERS_DIR:-${TMPDIR:-/tmp}/sweeptin-peers}
mkdir -p "$scratch"

say() { echo "bench-core: $*" >&2; }

can_apt() { [ "$(id -u)" = 0 ] && command -v apt-get > /dev/null; }

# --- /usr/bin/time ---------------------------------------------------------------------------
if [ ! -x /usr/bin/time ] && can_apt; then
    say "installing Debian time"
    apt-get install -y -qq time > "$out/logs/apt-time.log" 2>&1 \
        || { apt-get update -qq && apt-get install -y -qq time; } >> "$out/logs/apt-time.log" 2>&1 || true
fi
if [ -x /usr/bin/time ]; then timer=(/usr/bin/time -v -o); else
    say "no /usr/bin/time: the 'max RSS (time -v)' column stays empty"; timer=(); fi

# --- build -----------------------------------------------------------------------------------
say "building the runner (release)"
cargo build --release --example bench_core >&2
runner="$root/target/release/examples/bench_core"

cgal=""
triangle=""
triangle_version=""
if [ "$external" = 1 ]; then
    if [ ! -f /usr/include/CGAL/Delaunay_triangulation_2.h ] && can_apt; then
        say "installing libcgal-dev"
        { apt-get install -y -qq libcgal-dev || { apt-get update -qq && apt-get install -y -qq libcgal-dev; }; } \
            > "$out/logs/apt-cgal.log" 2>&1 || true
    fi
    if [ -f /usr/include/CGAL/Delaunay_triangulation_2.h ] \
        && g++ -O3 -DNDEBUG -std=c++17 scripts/peers/cgal_dt.cpp -o "$scratch/cgal_dt" -lgmp \
            > "$out/logs/build-cgal.log" 2>&1; then
        cgal="$scratch/cgal_dt"
    else
        say "skipping CGAL: cannot build it (see $out/logs/build-cgal.log; needs libcgal-dev)"
    fi
    build_triangle() {
        local tgz src defs="-DVOID=void -DREAL=double -DNO_TIMER -DTRILIBRARY -DANSI_DECLARATORS"
        tgz=$(ls "$scratch"/triangle-*.tar.gz 2> /dev/null | head -n1 || true)
        if [ -z "$tgz" ]; then
            (cd "$scratch" && pip download --no-binary :all: --no-deps triangle -d .) || return 1
            tgz=$(ls "$scratch"/triangle-*.tar.gz | head -n1)
        fi
        tar -xzf "$tgz" -C "$scratch" || return 1
        src="${tgz%.tar.gz}/c"
        triangle_version=$(basename "${tgz%.tar.gz}")
        # shellcheck disable=SC2086
        gcc -O3 $defs -w -c "$src/triangle.c" -o "$scratch/triangle.o" || return 1
        # shellcheck disable=SC2086
        gcc -O3 $defs -I"$src" scripts/peers/triangle_dt.c "$scratch/triangle.o" -lm \
            -o "$scratch/triangle_dt" || return 1
    }
    if build_triangle > "$out/logs/build-triangle.log" 2>&1; then
        triangle="$scratch/triangle_dt"
    else
        say "skipping Triangle: cannot build it (see $out/logs/build-triangle.log)"
    fi
fi

# --- runs ------------------------------------------------------------------------------------
load_before=$(cut -d' ' -f1-3 /proc/loadavg)

# run LABEL DIST N CMD...: one process; appends its JSON line (plus label and time -v max RSS).
run() {
    local label=$1 dist=$2 n=$3; shift 3
    local log="$out/logs/$label-$dist-$n.time" json rc=0
    say "$label $dist $n"
    if [ ${#timer[@]} -gt 0 ]; then
        json=$("${timer[@]}" "$log" "$@") || rc=$?
    else
        json=$("$@") || rc=$?
    fi
    python3 scripts/bench_core_report.py record "$results" "$label" "$dist" "$n" "$rc" "$log" "$json"
}

count() { # 1M -> 1000000
    python3 -c "import sys; s=sys.argv[1]; m={'k':1e3,'K':1e3,'m':1e6,'M':1e6}.get(s[-1]); \
print(int(round(float(s[:-1])*m)) if m else int(s))" "$1"
}

for size in $sizes; do
    n=$(count "$size")
    for dist in $dists; do
        run sweeptin "$dist" "$n" "$runner" sweeptin "$dist" "$n" --repeat "$repeat"
        run sweeptin-1t "$dist" "$n" "$runner" sweeptin "$dist" "$n" --repeat "$repeat" --threads 1
        for algo in delaunator spade cdt; do
            run "$algo" "$dist" "$n" "$runner" "$algo" "$dist" "$n" --repeat "$repeat"
        done
        if [ -n "$cgal$triangle" ]; then
            bin="$scratch/$dist-$n.bin"
            "$runner" dump "$dist" "$n" "$bin"
            [ -n "$cgal" ] && run cgal "$dist" "$n" "$cgal" "$bin" "$dist" "$n" "$repeat"
            [ -n "$triangle" ] && run triangle "$dist" "$n" "$triangle" "$bin" "$dist" "$n" "$repeat"
            rm -f "$bin"
        fi
    done
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

# --- report ----------------------------------------------------------------------------------
cmd="scripts/bench-core.sh"
[ "$sizes" != "1M 4M" ] && cmd="$cmd --sizes \"$sizes\""
[ "$repeat" != 3 ] && cmd="$cmd --repeat $repeat"
[ "$external" = 0 ] && cmd="$cmd --no-external"
python3 scripts/bench_core_report.py table "$results" \
    --command "$cmd" --load-before "$load_before" --load-after "$load_after" \
    --cgal "$( [ -n "$cgal" ] && dpkg-query -W -f='${Version}' libcgal-dev 2> /dev/null || echo '')" \
    --triangle "$triangle_version" | tee "$out/table.md"
say "results in $out"
