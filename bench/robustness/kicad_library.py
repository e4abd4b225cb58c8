#!/usr/bin/env python3
"""The whole KiCad 3D library through `rdmesh batch` (issue 35): statuses, failures, time.

Runs `rdmesh batch ROOT -o OUT --jobs N --format msh --timeout S --json -q` over an extracted
`kicad-packages3d` (apt-get download kicad-packages3d && dpkg-deb -x kicad-packages3d_*.deb DIR;
ROOT is DIR/usr/share/kicad/3dmodels) and writes a Markdown table of what became of every file,
from the batch's manifest. With --manifest, only re-renders from an existing run's manifest and
summary.

The statuses are rdmesh's own account (every face meshed or not, crashes, timeouts); whether a
mesh is clean by the yardstick (watertight within each solid, no fold, deviation within 1.2x)
needs an eval of every mesh (bench/quality), which this does not run.

  bench/robustness/kicad_library.py --root ROOT --out-dir /tmp/kicad_all/out \\
      --summary /tmp/kicad_all/summary.json --md bench/robustness/KICAD_LIBRARY.md
"""
import argparse
import collections
import datetime
import json
import os
import pathlib
import subprocess
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[2]


def run_batch(args):
    command = [args.rdmesh, "batch", args.root, "-o", args.out_dir, "--jobs", str(args.jobs),
               "--format", "msh", "--timeout", str(args.timeout), "--json", "-q"]
    start = time.perf_counter()
    before = os.times()
    completed = subprocess.run(command, capture_output=True, text=True)
    after = os.times()
    wall = time.perf_counter() - start
    cpu = (after.children_user - before.children_user) + (after.children_system -
                                                           before.children_system)
    lines = [line for line in completed.stdout.splitlines() if line.strip()]
    summary = json.loads(lines[-1]) if lines else {}
    summary["measured_wall_seconds"] = wall
    summary["measured_cpu_seconds"] = cpu
    summary["command"] = " ".join(command)
    pathlib.Path(args.summary).write_text(json.dumps(summary))
    return summary


def render(args, summary):
    rows = [json.loads(line) for line in open(pathlib.Path(args.out_dir) / "manifest.jsonl")]
    counts = collections.Counter(row["status"] for row in rows)
    over = [row for row in rows if row["status"] == "ok" and row.get("reason")]
    short = lambda path: path.split("3dmodels/")[-1]
    out = ["# The whole KiCad 3D library through `rdmesh batch`", "",
           "Written by `bench/robustness/kicad_library.py` (its docstring says how). The run:", "",
           "```", summary.get("command", "(not recorded)"), "```", ""]
    out.append(f"- rendered {datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC from "
               f"`{args.out_dir}/manifest.jsonl`; {len(rows)} files")
    if "measured_wall_seconds" in summary:
        wall = summary["measured_wall_seconds"]
        out.append(f"- wall {wall:.0f} s ({len(rows) / wall * 60:.0f} files a minute), CPU "
                   f"{summary['measured_cpu_seconds']:.0f} s, on a 2-core machine shared "
                   "with other work")
    out += ["", "| status | files | share |", "|---|---:|---:|"]
    for status in ("ok", "failed", "crashed", "timed_out", "unreadable"):
        out.append(f"| {status} | {counts[status]} | {counts[status] / len(rows):.2%} |")
    out += ["", f"`ok` means every face meshed; {len(over)} of them have faces meshed over the "
            "criteria (the reason names them).", ""]
    problems = [row for row in rows if row["status"] != "ok"] + over
    if problems:
        out += ["## Files not ok, and ok files with a reason", "", "| file | status | reason |",
                "|---|---|---|"]
        for row in problems:
            reason = (row.get("reason") or "").replace("|", "/")[:300]
            out.append(f"| {short(row['path'])} | {row['status']} | {reason} |")
        out.append("")
    slow = sorted(rows, key=lambda row: -(row.get("seconds") or 0))[:10]
    out += ["## The slowest files", "", "| file | seconds | faces | triangles |",
            "|---|---:|---:|---:|"]
    for row in slow:
        out.append(f"| {short(row['path'])} | {row.get('seconds') or 0:.1f} | "
                   f"{row.get('faces')} | {row.get('triangles')} |")
    pathlib.Path(args.md).write_text("\n".join(out) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", help="the extracted 3dmodels folder")
    parser.add_argument("--rdmesh", default=str(REPO / "build" / "bin" / "rdmesh"))
    parser.add_argument("--out-dir", required=True, help="the batch's OUTDIR")
    parser.add_argument("--summary", required=True, help="the run's summary JSON (written)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=120.0)
    parser.add_argument("--manifest", action="store_true",
                        help="render from an existing run (OUTDIR and --summary) only")
    parser.add_argument("--md", default=str(REPO / "bench" / "robustness" / "KICAD_LIBRARY.md"))
    args = parser.parse_args()
    if args.manifest:
        summary = json.loads(pathlib.Path(args.summary).read_text())
    else:
        if not args.root:
            sys.exit("kicad_library.py: --root is needed to run the batch")
        summary = run_batch(args)
    render(args, summary)


if __name__ == "__main__":
    main()
