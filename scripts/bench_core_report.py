#!/usr/bin/env python3
"""Helper of scripts/bench-core.sh: records one run, and turns the records into a Markdown table.

  bench_core_report.py record RESULTS LABEL DIST N EXIT_CODE TIME_LOG JSON_LINE
  bench_core_report.py table RESULTS [--command C] [--load-before L] [--load-after L]
                                     [--cgal VERSION] [--triangle VERSION]

The table has, per distribution and size, one row per algorithm: median time (s), ratio to the
fastest peer (every algorithm that is not sweeptin), million points per second, peak RSS of the
triangulation (runner's VmHWM), bytes per input point, the whole process's max RSS from
/usr/bin/time -v, and the triangle count (marked when it differs from sweeptin's).
"""
import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys

SWEEPTIN = ("sweeptin", "sweeptin-1t")
TARGET_RATIO = 0.7
TARGET_BYTES = 100.0


def record(args):
    row = {"label": args.label, "dist": args.dist, "n": int(args.n)}
    if args.code != "0" or not args.json.strip():
        row["error"] = f"exit code {args.code}"
    else:
        try:
            row.update(json.loads(args.json.strip().splitlines()[-1]))
        except ValueError:
            row["error"] = "unreadable output: " + args.json[:200]
    try:
        with open(args.log) as f:
            m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", f.read())
        if m:
            row["time_max_rss_bytes"] = int(m.group(1)) * 1024
    except OSError:
        pass
    with open(args.results, "a") as f:
        f.write(json.dumps(row) + "\n")


def sh(cmd):
    try:
        return subprocess.run(cmd, shell=True, capture_output=True, text=True).stdout.strip()
    except OSError:
        return ""


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def mem_total():
    try:
        with open("/proc/meminfo") as f:
            kb = int(f.readline().split()[1])
        return f"{kb / 1024 / 1024:.1f} GiB"
    except (OSError, ValueError, IndexError):
        return "unknown"


def lock_versions(names):
    out = {}
    try:
        text = open("Cargo.lock").read()
    except OSError:
        return out
    for block in text.split("[[package]]"):
        m = re.search(r'name = "([^"]+)"\s+version = "([^"]+)"', block)
        if m and m.group(1) in names:
            out[m.group(1)] = m.group(2)
    return out


def mb(b):
    return f"{b / 1e6:.0f}" if b else ""


def table(args):
    rows = [json.loads(line) for line in open(args.results) if line.strip()]
    groups = {}
    for r in rows:
        groups.setdefault((r["n"], r["dist"]), []).append(r)
    out = []
    p = out.append
    p("| points | distribution | algorithm | median s | 1st run s | × fastest peer | M points/s | "
      "peak RSS MB | B/point | max RSS MB (time -v) | triangles |")
    p("|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    summary = []
    order = {"uniform": 0, "lidar-like": 1, "clustered": 2}
    for (n, dist), rs in sorted(groups.items(), key=lambda kv: (kv[0][0], order.get(kv[0][1], 9))):
        ok = [r for r in rs if "error" not in r]
        peers = [r for r in ok if r["label"] not in SWEEPTIN]
        fastest = min(peers, key=lambda r: r["median_s"]) if peers else None
        rust = [r for r in peers if r["label"] in ("delaunator", "spade", "cdt")]
        fastest_rust = min(rust, key=lambda r: r["median_s"]) if rust else None
        ref = next((r["triangles"] for r in ok if r["label"] == "sweeptin"), None)
        for r in rs:
            if "error" in r:
                p(f"| {n:,} | {dist} | {r['label']} | failed: {r['error']} | | | | | | "
                  f"{mb(r.get('time_max_rss_bytes'))} | |")
                continue
            ratio = f"{r['median_s'] / fastest['median_s']:.2f}" if fastest else ""
            tri = f"{r['triangles']:,}"
            if ref is not None and r["triangles"] != ref:
                tri += " (≠)"
            first = f"{r['times_s'][0]:.3f}" if r.get("times_s") else ""
            p(f"| {n:,} | {dist} | {r['label']} | {r['median_s']:.3f} | {first} | {ratio} | "
              f"{n / r['median_s'] / 1e6:.2f} | {mb(r['peak_rss_bytes'])} | "
              f"{r['bytes_per_point']:.0f} | {mb(r.get('time_max_rss_bytes'))} | {tri} |")
        sw = next((r for r in ok if r["label"] == "sweeptin"), None)
        if sw and fastest:
            ratio = sw["median_s"] / fastest["median_s"]
            line = (f"- {dist}, {n:,} points: sweeptin {sw['median_s']:.3f} s = "
                    f"{ratio:.2f}× the fastest peer ({fastest['label']}, "
                    f"{fastest['median_s']:.3f} s)")
            if fastest_rust and fastest_rust is not fastest:
                line += (f", {sw['median_s'] / fastest_rust['median_s']:.2f}× the fastest Rust "
                         f"peer ({fastest_rust['label']})")
            line += (f"; {sw['bytes_per_point']:.0f} B/point. Time target "
                     f"{'met' if ratio <= TARGET_RATIO else 'NOT met'}, memory target "
                     f"{'met' if sw['bytes_per_point'] <= TARGET_BYTES else 'NOT met'}.")
            summary.append(line)
    p("")
    p(f"Targets: sweeptin (sort included) ≤ {TARGET_RATIO}× the fastest peer's time, "
      f"peak RSS ≤ {TARGET_BYTES:.0f} bytes per input point.")
    p("")
    out.extend(summary)
    p("")
    versions = lock_versions({"delaunator", "spade", "cdt", "criterion", "robust", "rayon"})
    commit = sh("git rev-parse --short HEAD") + (" (dirty)" if sh("git status --porcelain -uno") else "")
    p("Machine and versions:")
    p("")
    p(f"- date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC")
    p(f"- command: `{args.command}`")
    p(f"- CPU: {cpu_model()}, {os.cpu_count()} logical cores; RAM {mem_total()}; "
      f"kernel {platform.release()}")
    p(f"- load average (1/5/15 min) before: {args.load_before}; after: {args.load_after}")
    p(f"- {sh('rustc -V')}; {sh('gcc --version | head -n1')}")
    p(f"- sweeptin {commit}; " + ", ".join(f"{k} {v}" for k, v in sorted(versions.items())))
    if args.cgal:
        p(f"- CGAL (Debian libcgal-dev) {args.cgal}, Epick kernel, "
          "`Delaunay_triangulation_2::insert(begin, end)` (spatial sort + insertion)")
    if args.triangle:
        p(f"- Triangle 1.6 (C source from the PyPI sdist {args.triangle}), gcc -O3, switches "
          "`zQNB`: divide and conquer, exact adaptive arithmetic (the default, no `-X`)")
    p("- time: median of --repeat runs inside one process per (algorithm, distribution, size); "
      "sweeptin uses rayon's default pool (sorting), sweeptin-1t one thread; all peers are "
      "single-threaded")
    print("\n".join(out))


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    for name in ("results", "label", "dist", "n", "code", "log", "json"):
        r.add_argument(name)
    t = sub.add_parser("table")
    t.add_argument("results")
    t.add_argument("--command", default="scripts/bench-core.sh")
    t.add_argument("--load-before", default="?")
    t.add_argument("--load-after", default="?")
    t.add_argument("--cgal", default="")
    t.add_argument("--triangle", default="")
    args = ap.parse_args()
    record(args) if args.cmd == "record" else table(args)


if __name__ == "__main__":
    sys.exit(main())
