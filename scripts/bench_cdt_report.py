#!/usr/bin/env python3
"""Helper of scripts/bench-cdt.sh: records one run, and turns the records into Markdown tables.

  bench_cdt_report.py record RESULTS LABEL INPUT EXIT_CODE TIME_LOG JSON_LINE
  bench_cdt_report.py table RESULTS [--command C] [--load-before L] [--load-after L]

Records are the JSON lines of dev/bench_cdt.rs plus the label, the input name and the
/usr/bin/time -v max RSS. `prep` records (label "clean") give the input table; the others give one
row per tool: minimum, median and first-run time, ratio to the faster peer (spade, cdt), peak RSS
of the triangulation, bytes per vertex, triangle count (marked when it differs from spade's).
"""
import argparse
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_core_report import cpu_model, lock_versions, mem_total, sh  # noqa: E402

SWEEPTIN = ("sweeptin", "sweeptin-1t")
TARGET_RATIO = 0.7


def record(args):
    row = {"label": args.label, "input_name": args.input}
    if args.code != "0" or not args.json.strip():
        row["error"] = f"process exit code {args.code}"
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


def mb(b):
    return f"{b / 1e6:.0f}" if b else ""


def table(args):
    rows = [json.loads(line) for line in open(args.results) if line.strip()]
    names = []
    for r in rows:
        if r["input_name"] not in names:
            names.append(r["input_name"])
    out = []
    p = out.append
    p("Inputs (lines cleaned by `breaklines::clean::clean`, minimum of the runs, 2 threads):")
    p("")
    p("| input | polylines | line vertices | PSLG vertices | PSLG segments | points | "
      "vertices in all | clean s (min) | clean M segments/s |")
    p("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in names:
        c = next((r for r in rows if r["input_name"] == name and r["label"] == "clean"), None)
        if c is None or c.get("error"):
            p(f"| {name} | failed: {c and c.get('error')} | | | | | | | |")
            continue
        p(f"| {name} | {c['polylines']:,} | {c['line_vertices']:,} | {c['graph_vertices']:,} | "
          f"{c['segments']:,} | {c['points']:,} | {c['vertices']:,} | {c['clean_min_s']:.3f} | "
          f"{c['line_segments'] / c['clean_min_s'] / 1e6:.2f} |")
    p("")
    p("| input | tool | min s | median s | 1st run s | × faster peer | peak RSS MB | B/vertex | "
      "max RSS MB (time -v) | triangles |")
    p("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    summary = []
    for name in names:
        rs = [r for r in rows if r["input_name"] == name and r["label"] != "clean"]
        ok = [r for r in rs if not r.get("error")]
        peers = [r for r in ok if r["label"] not in SWEEPTIN]
        faster = min(peers, key=lambda r: r["min_s"]) if peers else None
        ref = next((r["triangles"] for r in ok if r["label"] == "spade"), None)
        for r in rs:
            if r.get("error"):
                p(f"| {name} | {r['label']} | **failed**: {r['error'][:160]} | | | | | | "
                  f"{mb(r.get('time_max_rss_bytes'))} | |")
                continue
            ratio = f"{r['min_s'] / faster['min_s']:.2f}" if faster else ""
            tri = f"{r['triangles']:,}"
            if ref is not None and r["triangles"] != ref:
                tri += " (≠ spade)"
            p(f"| {name} | {r['label']} | {r['min_s']:.3f} | {r['median_s']:.3f} | "
              f"{r['first_s']:.3f} | {ratio} | {mb(r['peak_rss_bytes'])} | "
              f"{r['peak_rss_bytes'] / max(r['vertices'], 1):.0f} | "
              f"{mb(r.get('time_max_rss_bytes'))} | {tri} |")
        sw = next((r for r in ok if r["label"] == "sweeptin"), None)
        if sw and faster:
            ratio = sw["min_s"] / faster["min_s"]
            summary.append(
                f"- {name}: sweeptin {sw['min_s']:.3f} s = {ratio:.2f}× the faster peer "
                f"({faster['label']}, {faster['min_s']:.3f} s). Target (≤ {TARGET_RATIO}×) "
                f"{'met' if ratio <= TARGET_RATIO else 'NOT met'}.")
        elif not sw:
            summary.append(f"- {name}: sweeptin failed.")
        else:
            summary.append(f"- {name}: no peer finished, no ratio.")
    p("")
    out.extend(summary)
    p("")
    versions = lock_versions({"spade", "cdt", "robust", "rayon"})
    commit = sh("git rev-parse --short HEAD") + (" (dirty)" if sh("git status --porcelain -uno") else "")
    p("Machine and versions:")
    p("")
    p(f"- command: `{args.command}`")
    p(f"- CPU: {cpu_model()}, {os.cpu_count()} logical cores; RAM {mem_total()}")
    p(f"- load average (1/5/15 min) before: {args.load_before}; after: {args.load_after}")
    p(f"- {sh('rustc -V')}")
    p(f"- sweeptin {commit}; " + ", ".join(f"{k} {v}" for k, v in sorted(versions.items())))
    p("- time: minimum of --repeat runs inside one process per (tool, input); sweeptin uses "
      "rayon's default pool (its sort), sweeptin-1t one thread; the peers are single-threaded")
    print("\n".join(out))


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    for name in ("results", "label", "input", "code", "log", "json"):
        r.add_argument(name)
    t = sub.add_parser("table")
    t.add_argument("results")
    t.add_argument("--command", default="scripts/bench-cdt.sh")
    t.add_argument("--load-before", default="?")
    t.add_argument("--load-after", default="?")
    args = ap.parse_args()
    record(args) if args.cmd == "record" else table(args)


if __name__ == "__main__":
    sys.exit(main())
