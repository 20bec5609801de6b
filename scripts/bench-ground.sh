#!/usr/bin/env bash
# Ground classification speed (issue 42, item 6), side by side in one run on the same files:
#   * `sweeptin dem F --class 2 --cell 1`: the DTM from the file's own (professional) ground;
#   * `sweeptin ground F -o G.laz`: progressive TIN densification, every point written back;
#   * `sweeptin dem F --ground --cell 1`: the ground made on the fly (when the build has it);
#   * CSF (PyPI cloth-simulation-filter, its documented defaults) on the same points: the
#     filter's own time (the points already in memory) and its process's peak RSS.
# Each under /usr/bin/time (wall, peak RSS), sweeptin at --mem 128M. Prints a Markdown table.
#
#   scripts/bench-ground.sh [FILES...]   (default: the ARSO tile in ../shared/data/lidar)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${SWEEPTIN_DATA:-../shared/data/lidar}
[ $# -gt 0 ] || set -- "$DATA/arso_TM_511_122_from_ept.laz"
OUT=${SWEEPTIN_BENCH_DIR:-/tmp/sweeptin-bench-ground}
MEM=${SWEEPTIN_BENCH_MEM:-128M}
mkdir -p "$OUT"
VENV=target/venv-py
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
"$VENV/bin/python" -c "import laspy, lazrs, CSF, numpy" 2>/dev/null ||
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
        laspy==2.7.0 lazrs==0.8.2 numpy cloth-simulation-filter
command -v /usr/bin/time >/dev/null || { apt-get install -y -qq time >/dev/null; }
cargo build --release --quiet --bin sweeptin
BIN=${CARGO_TARGET_DIR:-target}/release/sweeptin
RESULTS="$OUT/ground-results.jsonl"
: > "$RESULTS"
echo "commit $(git rev-parse --short HEAD)$(git diff --quiet || echo +changes), $(date -u +%FT%TZ)" >&2

timed() { # name file cmd...
    local name=$1 file=$2; shift 2
    local log="$OUT/$name.log"
    : > "$log"
    /usr/bin/time -f "TIME %e %M %x %U %S" -a -o "$log" "$@" > "$OUT/$name.out" 2>> "$log" || true
    python3 - "$name" "$file" "$log" "$OUT/$name.out" >> "$RESULTS" <<'PY'
import json, re, sys
name, file, log, out = sys.argv[1:5]
m = re.search(r"^TIME (\S+) (\d+) (\d+) (\S+) (\S+)$", open(log).read(), re.M)
row = {"step": name.split("@")[0], "file": file, "wall_s": float(m.group(1)),
       "max_rss": int(m.group(2)) * 1024, "status": int(m.group(3)),
       "cpu_s": float(m.group(4)) + float(m.group(5))}
t = open(out).read()
k = re.search(r"^CSF_FILTER_S (\S+) (\d+)$", t, re.M)
if k:
    row.update(filter_s=float(k.group(1)), ground=int(k.group(2)))
print(json.dumps(row))
PY
}

CSF_PY=$(cat <<'PY'
import sys, time
import laspy, numpy as np, CSF
las = laspy.read(sys.argv[1])
xyz = np.vstack((las.x, las.y, las.z)).T
t = time.perf_counter()
csf = CSF.CSF()  # the documented defaults
csf.setPointCloud(xyz)
ground, off = CSF.VecInt(), CSF.VecInt()
csf.do_filtering(ground, off, False)
print(f"CSF_FILTER_S {time.perf_counter() - t:.3f} {len(ground)}")
PY
)

ground_on_the_fly=0
"$BIN" dem --help 2>/dev/null | grep -q -- "--ground" && ground_on_the_fly=1
for f in "$@"; do
    b=$(basename "$f" .laz)
    timed "dem-class2@$b" "$f" "$BIN" dem "$f" --class 2 --cell 1 --mem "$MEM" -o "$OUT/$b-c2.tif" --quiet
    timed "ground@$b" "$f" "$BIN" ground "$f" -o "$OUT/$b-ground.laz" --mem "$MEM" --quiet
    timed "dem-own-ground@$b" "$f" "$BIN" dem "$OUT/$b-ground.laz" --class 2 --cell 1 --mem "$MEM" -o "$OUT/$b-own.tif" --quiet
    if [ "$ground_on_the_fly" = 1 ]; then
        timed "dem-ground@$b" "$f" "$BIN" dem "$f" --ground --cell 1 --mem "$MEM" -o "$OUT/$b-g.tif" --quiet
    fi
    timed "csf@$b" "$f" "$VENV/bin/python" -c "$CSF_PY" "$f"
    rm -f "$OUT/$b-ground.laz"
done

python3 - "$RESULTS" <<'PY'
import json, subprocess, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
cpu = [l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")][0]
print(f"\nmachine: {subprocess.getoutput('nproc')} cores, {cpu}, load {open('/proc/loadavg').read().split()[0]}\n")
print("| file | step | wall s | CPU s | peak RSS MB | exit | note |")
print("|---|---|---:|---:|---:|:-:|---|")
by = {}
for r in rows:
    by[(r["file"], r["step"])] = r
    note = f"CSF filter alone {r['filter_s']:.1f} s, {r['ground']:,} ground" if "filter_s" in r else ""
    print(f"| {r['file'].split('/')[-1]} | {r['step']} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | "
          f"{r['max_rss'] / 2**20:.0f} | {r['status']} | {note} |")
print()
for f in sorted({r["file"] for r in rows}):
    g, c2, csf = by.get((f, "ground")), by.get((f, "dem-class2")), by.get((f, "csf"))
    own, fly = by.get((f, "dem-own-ground")), by.get((f, "dem-ground"))
    name = f.split("/")[-1]
    if g and csf and "filter_s" in csf:
        print(f"- {name}: CSF's filter alone / `ground` (read, classify, write) = "
              f"{csf['filter_s'] / g['wall_s']:.1f}× (target ≥ 10×)")
    if c2 and g and own:
        print(f"- {name}: (`ground` + `dem --class 2` of its output) / `dem --class 2` = "
              f"{(g['wall_s'] + own['wall_s']) / c2['wall_s']:.2f}×")
    if c2 and fly:
        print(f"- {name}: `dem --ground` / `dem --class 2` = {fly['wall_s'] / c2['wall_s']:.2f}× (target ≤ 2×)")
PY
