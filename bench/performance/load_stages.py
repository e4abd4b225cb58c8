#!/usr/bin/python3
"""The load's stages on one core against two (issue 34's scaling bar), summed over files.

    bench/performance/load_stages.py [--rdmesh build/bin/rdmesh] [--rounds 3] FILE... | @LIST

Per file, ROUNDS alternating runs of `taskset -c 0 rdmesh mesh FILE --threads 1` (one core) and
`rdmesh mesh FILE --threads 2` (two), both `--max-deviation-rel 1e-3 --json`; the median of each
stage's seconds (the report's load stages as parse_e2e.py flattens them, and load_seconds as
"load") per file, summed over the
files, and the ratio one core / two. Where a stage does not scale, it runs on one thread: that
is the part the bar of 1.7x leaves no room for. Timings: run it on a quiet machine.
"""
import argparse
import collections
import json
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import parse_e2e  # noqa: E402  (the report's stages, read as the end-to-end table reads them)

REPO = pathlib.Path(__file__).resolve().parents[2]


def run(rdmesh, path, out, one_core):
    command = (["taskset", "-c", "0"] if one_core else []) + [
        rdmesh, "mesh", path, "-o", out, "--max-deviation-rel", "1e-3", "--json",
        "--threads", "1" if one_core else "2"]
    proc = subprocess.run(command, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit("%s failed on %s: %s" % (rdmesh, path, proc.stderr.strip()[-300:]))
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    stages = parse_e2e.flat_stages(parse_e2e.load_stages(report))
    stages["load"] = report["load_seconds"]
    return stages


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rdmesh", default=str(REPO / "build" / "bin" / "rdmesh"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("files", nargs="+", help="STEP files, or @LIST (one path a line)")
    args = parser.parse_args()
    if not shutil.which("taskset"):
        sys.exit("taskset is not installed (util-linux)")
    files = []
    for item in args.files:
        if item.startswith("@"):
            files += [line.strip() for line in open(item[1:]) if line.strip()]
        else:
            files.append(item)
    totals = {True: collections.Counter(), False: collections.Counter()}
    with tempfile.TemporaryDirectory() as work:
        out = str(pathlib.Path(work) / "load_stages.msh")
        for path in files:
            samples = {True: [], False: []}
            for r in range(args.rounds):
                for one_core in ((True, False) if r % 2 == 0 else (False, True)):
                    samples[one_core].append(run(args.rdmesh, path, out, one_core))
            for one_core, runs in samples.items():
                for stage in runs[0]:
                    if all(stage in s for s in runs):
                        totals[one_core][stage] += statistics.median(s[stage] for s in runs)
    print("%d files, median of %d runs each; seconds summed" % (len(files), args.rounds))
    print("%-26s %8s %8s %6s" % ("stage", "1 core", "2 cores", "x"))
    for stage, one in totals[True].items():
        two = totals[False][stage]
        print("%-26s %8.3f %8.3f %6.2f" % (stage, one, two, one / two if two else 0.0))


if __name__ == "__main__":
    main()
