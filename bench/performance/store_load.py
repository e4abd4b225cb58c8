#!/usr/bin/python3
"""STEP parse vs persistent-store load (issue 14): for each model, runs `rdmesh info MODEL --json`
without a store (a STEP parse), then once with --cache-dir to write the entry, then again with
--cache-dir (a store load), and reports the medians of the load_seconds that rdmesh reports (wall
time of the load inside the process) and of the process CPU time (user + system, including
process start), and their ratios. With --baseline OLD_RDMESH, also the parse of another binary
(e.g. one without the canonical load, to measure what canonicalisation costs).

  bench/performance/store_load.py [--rdmesh build/bin/rdmesh] [--runs 3] [--baseline OLD] MODEL...

Default models: voron_bowden_module and gmsh_tough_second_order from /work/shared/corpus."""

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import tempfile

CORPUS = os.environ.get("RDMESH_CORPUS", "/work/shared/corpus")
DEFAULT_MODELS = [os.path.join(CORPUS, name) for name in
                  ("voron_bowden_module.step", "gmsh_tough_second_order.step")]


def info(binary, model, *flags):
    """(load_seconds, cpu_seconds, json) of one `rdmesh info` process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    completed = subprocess.run([binary, "info", model, "--json", *flags], capture_output=True,
                               text=True, timeout=3600)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if completed.returncode != 0:
        raise SystemExit(f"{binary} info {model}: {completed.stderr.strip()}")
    report = json.loads(completed.stdout.splitlines()[-1])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return report["load_seconds"], cpu, report


def medians(samples):
    return (statistics.median(s[0] for s in samples), statistics.median(s[1] for s in samples))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rdmesh", default="build/bin/rdmesh")
    parser.add_argument("--baseline", help="another rdmesh binary whose parse is also timed")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("models", nargs="*", default=DEFAULT_MODELS)
    args = parser.parse_args()
    columns = ["model", "faces", "STEP parse s (wall)", "CPU s", "store load s (wall)", "CPU s",
               "ratio wall", "ratio CPU", "entry MB"]
    if args.baseline:
        columns[2:2] = ["baseline parse s (wall)", "CPU s"]
    print("| " + " | ".join(columns) + " |")
    print("|---|" + "---:|" * (len(columns) - 1))
    for model in args.models:
        store = tempfile.mkdtemp(prefix="rdmesh-store-bench-")
        try:
            cells = [os.path.basename(model)]
            baseline = []
            if args.baseline:
                baseline = [info(args.baseline, model) for _ in range(args.runs)]
            parse = [info(args.rdmesh, model) for _ in range(args.runs)]
            written = info(args.rdmesh, model, "--cache-dir", store)
            assert written[2]["from_store"] is False, written[2]
            loads = [info(args.rdmesh, model, "--cache-dir", store) for _ in range(args.runs)]
            assert all(load[2]["from_store"] for load in loads), [load[2] for load in loads]
            for field in ("faces", "bbox", "part_names", "instances"):
                assert loads[0][2][field] == parse[0][2][field], field
            cells.append(str(parse[0][2]["faces"]))
            if baseline:
                cells += ["%.2f" % value for value in medians(baseline)]
            parse_wall, parse_cpu = medians(parse)
            load_wall, load_cpu = medians(loads)
            entry_bytes = sum(os.path.getsize(os.path.join(store, name))
                              for name in os.listdir(store))
            cells += ["%.2f" % parse_wall, "%.2f" % parse_cpu, "%.3f" % load_wall,
                      "%.3f" % load_cpu, "%.0fx" % (parse_wall / load_wall),
                      "%.0fx" % (parse_cpu / load_cpu), "%.2f" % (entry_bytes / 1e6)]
            print("| " + " | ".join(cells) + " |", flush=True)
        finally:
            shutil.rmtree(store, ignore_errors=True)


if __name__ == "__main__":
    main()
