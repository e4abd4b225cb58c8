#!/usr/bin/env python3
"""1 thread against 2 on the largest corpus models (issue 13: "2 threads give >= 1.8x the speed
of 1 thread, and the mesh stays byte-identical").

    /usr/bin/python3 bench/performance/thread_speedup.py [--rounds 5] [--tolerances 1e-3,1e-4] [--in-process]
        [--rdmesh build/bin/rdmesh] [MODEL ...]

Per model and tolerance, round by round, alternately `rdmesh mesh MODEL -o tN.msh
--max-deviation-rel TOL --threads N --json -q` with N = 1 and N = 2 (the order flips every round,
so a change of machine load falls on both), and `cmp` of the two meshes of every round. With
`--cache` the model is read from a --cache-dir (filled by a first run that is not reported), so
that the two runs of a round are about a second apart (this machine's speed moves in spells of
about a minute); but the model read from the cache meshes slower than the parsed one. Reports
the medians of the meshing wall seconds (`seconds` of the --json report), of the meshing CPU
seconds (`mesh_cpu_seconds`, all threads) and of the whole process's wall time, the speed-up
(1-thread seconds / 2-thread seconds) three ways: of the medians, the median of the rounds' own
ratios (a round's two runs are seconds apart, so a slow spell of the machine falls on both), and
of the fastest runs (the least disturbed), the 1-minute load average before each run, and the cores
this script could get: before every round two busy processes spin for 0.5 s, and their CPU seconds
over the wall seconds say how many cores they had (2.0 = both free). The load average alone does
not tell: processes of other containers on the same kernel count in it, and the scheduler shares
the cores between containers, whatever the nice level. A wall-clock speed-up means something only
when the cores were near 2.0. Exits 1 when a pair of meshes differs.

With `--in-process`, `build/bin/thread_pairs` (bench/thread_pairs.cpp) does the work instead: the
model loaded once, `--rounds` pairs of one- and two-thread meshes per tolerance a fraction of a
second apart in one process (a warm rdmeshd's case), every mesh compared bit for bit with the
first.
"""

import argparse
import filecmp
import json
import multiprocessing
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORPUS = pathlib.Path("/work/shared/corpus")
DEFAULT_MODELS = ["voron_bowden_module.step", "gmsh_tough_second_order.step", "nist_mbe_pmi_2.stp"]


def _spin(seconds, queue):
    start, cpu = time.perf_counter(), time.process_time()
    while time.perf_counter() - start < seconds:
        pass
    queue.put(time.process_time() - cpu)


def free_cores(seconds=0.5):
    """CPU seconds of two busy processes over their wall time: the cores this script can have."""
    queue = multiprocessing.Queue()
    procs = [multiprocessing.Process(target=_spin, args=(seconds, queue)) for _ in range(2)]
    for p in procs:
        p.start()
    cpu = sum(queue.get() for _ in procs)
    for p in procs:
        p.join()
    return cpu / seconds


def mesh(rdmesh, model, tol, threads, out, cache_dir=None):
    load = os.getloadavg()[0]
    start = time.perf_counter()
    command = [rdmesh, "mesh", str(model), "-o", str(out), "--max-deviation-rel", tol,
               "--threads", str(threads), "--json", "-q"]
    if cache_dir:
        command += ["--cache-dir", str(cache_dir)]
    proc = subprocess.run(command, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit("%s --threads %d failed (%d): %s" % (model, threads, proc.returncode,
                                                               proc.stderr.strip()))
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    return {"seconds": report["seconds"], "cpu": report["mesh_cpu_seconds"], "wall": wall,
            "load1": load, "triangles": report["triangles"]}


def in_process(args):
    """--in-process: thread_pairs per model; one row per model and tolerance. Returns the exit
    code (1 when a mesh differed)."""
    differ = False
    print("| model | tol | triangles | meshing s, 1 thread | 2 threads | speed-up | of pairs "
          "| of fastest | CPU s, 1 thread | 2 threads | cores free | meshes |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---|")
    for model in map(pathlib.Path, args.models):
        cores = free_cores()
        proc = subprocess.run([args.thread_pairs, str(model), "--tolerances", args.tolerances,
                               "--pairs", str(args.rounds)], capture_output=True, text=True)
        if proc.returncode not in (0, 1):
            raise SystemExit("%s: thread_pairs failed (%d): %s" % (model, proc.returncode,
                                                                   proc.stderr.strip()))
        for line in proc.stdout.strip().splitlines():
            r = json.loads(line)
            differ = differ or not r["identical"]
            print("| `%s` | %g | %d | %.3f | %.3f | %.2fx | %.2fx | %.2fx | %.3f | %.3f | %.2f | "
                  "%s |" % (model.name, r["tolerance"], r["triangles"], r["one_thread_seconds"],
                            r["two_thread_seconds"], r["speedup_of_medians"],
                            r["speedup_median_of_pairs"], r["speedup_of_fastest"],
                            r["one_thread_cpu"], r["two_thread_cpu"], cores,
                            "identical" if r["identical"] else "DIFFER"), flush=True)
    print("%d pairs in one process; speed-up of the medians, median of the pairs' ratios, of the "
          "fastest runs; %s; %s" % (args.rounds, args.thread_pairs,
                                    time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())))
    return 1 if differ else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="*", default=[str(CORPUS / m) for m in DEFAULT_MODELS])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--tolerances", default="1e-3,1e-4")
    parser.add_argument("--rdmesh", default=str(ROOT / "build" / "bin" / "rdmesh"))
    parser.add_argument("--in-process", action="store_true",
                        help="run build/bin/thread_pairs instead: the model loaded once, pairs of "
                             "one- and two-thread meshes a fraction of a second apart in one "
                             "process (--rounds pairs per tolerance)")
    parser.add_argument("--thread-pairs", default=str(ROOT / "build" / "bin" / "thread_pairs"))
    parser.add_argument("--cache", action="store_true",
                        help="read the model from a --cache-dir that a first, unreported run "
                             "fills, so a round takes about a second (the cached model meshes "
                             "slower: see docs/TUNING.md, Threads)")
    args = parser.parse_args()
    if args.in_process:
        sys.exit(in_process(args))

    differ = False
    print("| model | tol | triangles | meshing s, 1 thread | 2 threads | speed-up | of rounds "
          "| of fastest | CPU s, 1 thread | 2 threads | process s, 1 / 2 | load avg | cores free "
          "| meshes |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="thread_speedup_") as tmp:
        for model in map(pathlib.Path, args.models):
            for tol in args.tolerances.split(","):
                cache = pathlib.Path(tmp) / "cache" if args.cache else None
                if cache:  # fills the cache; not reported
                    mesh(args.rdmesh, model, tol, 2, pathlib.Path(tmp) / "warm.msh", cache)
                runs = {1: [], 2: []}
                same = True
                cores = []
                for r in range(args.rounds):
                    cores.append(free_cores())
                    outs = {n: pathlib.Path(tmp) / ("t%d.msh" % n) for n in (1, 2)}
                    for n in ((1, 2) if r % 2 == 0 else (2, 1)):
                        runs[n].append(mesh(args.rdmesh, model, tol, n, outs[n], cache))
                    same = same and filecmp.cmp(outs[1], outs[2], shallow=False)
                differ = differ or not same
                med = {n: {k: statistics.median(x[k] for x in runs[n])
                           for k in ("seconds", "cpu", "wall")} for n in (1, 2)}
                loads = [x["load1"] for n in (1, 2) for x in runs[n]]
                paired = statistics.median(a["seconds"] / b["seconds"]
                                           for a, b in zip(runs[1], runs[2]))
                fastest = (min(x["seconds"] for x in runs[1]) /
                           min(x["seconds"] for x in runs[2]))
                print("| `%s` | %s | %d | %.3f | %.3f | %.2fx | %.2fx | %.2fx | %.3f | %.3f | "
                      "%.2f / %.2f | %.1f-%.1f | %.2f-%.2f | %s |" % (
                          model.name, tol, runs[1][0]["triangles"], med[1]["seconds"],
                          med[2]["seconds"], med[1]["seconds"] / med[2]["seconds"], paired,
                          fastest, med[1]["cpu"], med[2]["cpu"], med[1]["wall"], med[2]["wall"],
                          min(loads), max(loads), min(cores), max(cores),
                          "identical" if same else "DIFFER"),
                      flush=True)
    print("%d rounds; speed-up of the medians, median of the rounds' ratios, of the fastest runs; "
          "%s; %s" % (args.rounds, args.rdmesh,
                                          time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())))
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
