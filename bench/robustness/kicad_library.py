#!/usr/bin/env python3
"""The whole KiCad 3D library through `rdmesh batch` (issue 35): statuses, time, yardstick.

Runs `rdmesh batch ROOT -o OUT --jobs N --format msh --timeout S --max-deviation-rel R --json -q`
over an extracted `kicad-packages3d` (apt-get download kicad-packages3d && dpkg-deb -x
kicad-packages3d_*.deb DIR; ROOT is DIR/usr/share/kicad/3dmodels), under `nice -n 5`, and writes
a Markdown table of what became of every file, from the batch's manifest. With --manifest, only
re-renders from an existing run's manifest and summary. With --sample N, meshes N files of ROOT
instead: two per folder drawn with random.Random(--seed), then more from the rest to reach N.

With --eval CACHE, every mesh is also scored by the yardstick (kicad_yardstick.py: two evals at a
time under `nice -n 10`, a per-file timeout, results cached in CACHE by the meshes' sha256), and
the Markdown gets the files clean and not clean by class, with every file not clean.

  bench/robustness/kicad_library.py --root ROOT --rdmesh build-lib/bin/rdmesh \\
      --out-dir /tmp/kl35/out --summary /tmp/kl35/summary.json --eval /tmp/kl35/eval.jsonl \\
      --md bench/robustness/KICAD_LIBRARY.md
  bench/robustness/kicad_library.py --root ROOT --rdmesh build-lib/bin/rdmesh --sample 300 \\
      --seed 35 --rel 1e-4 --out-dir /tmp/kl35_1e4/out --summary /tmp/kl35_1e4/summary.json \\
      --eval /tmp/kl35_1e4/eval.jsonl --md bench/robustness/KICAD_1E4.md
"""
import argparse
import collections
import datetime
import json
import os
import pathlib
import random
import subprocess
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import kicad_yardstick  # noqa: E402


def sample(root, count, seed):
    """Two files per folder, then more from the rest, to COUNT: the list, sorted."""
    rng = random.Random(seed)
    files = sorted(str(p) for p in pathlib.Path(root).rglob("*")
                   if p.suffix.lower() in (".step", ".stp"))
    folders = collections.defaultdict(list)
    for path in files:
        folders[os.path.dirname(path)].append(path)
    chosen = []
    for folder in sorted(folders):
        chosen += rng.sample(folders[folder], min(2, len(folders[folder])))
    rest = sorted(set(files) - set(chosen))
    chosen += rng.sample(rest, max(0, count - len(chosen)))
    return sorted(chosen)


def run_batch(args):
    inputs = args.root
    if args.sample:
        inputs = str(pathlib.Path(args.summary).with_suffix(".list"))
        pathlib.Path(inputs).write_text("\n".join(sample(args.root, args.sample, args.seed)) + "\n")
        inputs = "@" + inputs
    command = ["nice", "-n", "5", args.rdmesh, "batch", inputs, "-o", args.out_dir, "--jobs",
               str(args.jobs), "--format", "msh", "--timeout", str(args.timeout),
               "--max-deviation-rel", f"{args.rel:g}", "--json", "-q"]
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


def render(args, summary, scored=None):
    rows = [json.loads(line) for line in open(pathlib.Path(args.out_dir) / "manifest.jsonl")]
    counts = collections.Counter(row["status"] for row in rows)
    over = [row for row in rows if row["status"] == "ok" and row.get("reason")]
    short = lambda path: path.split("3dmodels/")[-1]
    title = (f"{len(rows)} KiCad 3D files (a sample) through `rdmesh batch` at {args.rel:g}"
             if args.sample else "The whole KiCad 3D library through `rdmesh batch`")
    out = [f"# {title}", "",
           "Written by `bench/robustness/kicad_library.py` (its docstring says how). The run:", "",
           "```", summary.get("command", "(not recorded)"), "```", ""]
    if args.commit:
        out.append(f"- rdmesh built at {args.commit}")
    out.append(f"- rendered {datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC from "
               f"`{args.out_dir}/manifest.jsonl`; {len(rows)} files")
    if "measured_wall_seconds" in summary:
        wall = summary["measured_wall_seconds"]
        cpu = (f", CPU {summary['measured_cpu_seconds']:.0f} s"
               if "measured_cpu_seconds" in summary else "")
        out.append(f"- wall {wall:.0f} s ({len(rows) / wall * 60:.0f} files a minute){cpu}, on a "
                   "2-core machine shared with other work")
    if summary.get("note"):
        out.append(f"- {summary['note']}")
    out += ["", "| status | files | share |", "|---|---:|---:|"]
    for status in ("ok", "failed", "crashed", "timed_out", "unreadable"):
        out.append(f"| {status} | {counts[status]} | {counts[status] / len(rows):.2%} |")
    out += ["", f"`ok` means every face meshed; {len(over)} of them have faces meshed over the "
            "criteria (the reason names them).", ""]
    if scored is not None:
        out += kicad_yardstick.section(scored, args.rel, "Clean by the yardstick")
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
    parser.add_argument("--rel", type=float, default=1e-3, help="--max-deviation-rel")
    parser.add_argument("--sample", type=int, default=0, help="mesh N files of ROOT, not all")
    parser.add_argument("--seed", type=int, default=35, help="of --sample")
    parser.add_argument("--eval", metavar="CACHE", help="score by the yardstick, cached in CACHE")
    parser.add_argument("--eval-timeout", type=float, default=300.0, help="per eval, seconds")
    parser.add_argument("--commit", default="", help="the commit rdmesh was built at")
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
    scored = None
    if args.eval:
        scored = kicad_yardstick.score(args.out_dir, args.eval, args.rel, args.jobs,
                                       args.eval_timeout)
    render(args, summary, scored)


if __name__ == "__main__":
    main()
