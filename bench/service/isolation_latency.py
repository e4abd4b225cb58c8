#!/usr/bin/env python3
"""Measures what crash isolation costs a client: the latency of Mesh calls on a cached model,
through one rdmeshd or another (e.g. a build from before the worker processes), in one run.

    /usr/bin/python3 bench/service/isolation_latency.py \
        --daemon before=/path/to/old/rdmeshd --daemon after=build/bin/rdmeshd \
        [--models tests/data/cq_red_cube_blue_cylinder.step ../shared/corpus/nist_mbe_pmi_2.stp]
        [--rounds 15] [--rel 1e-3]

Every daemon runs on its own loopback port with the same flags; each model is uploaded (and so
parsed) once per daemon and meshed once to warm up. The timed calls then alternate between the
daemons, round after round, so that both see the same machine. Reports per model and daemon the
median and 90th percentile of the call's wall time (request sent to Summary received), the
ratio to the first daemon's median, and the median CPU time the call cost the daemon's process
tree (the daemon and its worker processes, from /proc): on a busy machine the CPU time is the
steadier figure.
"""

import argparse
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "clients" / "python"))
from rdmesh import Client  # noqa: E402

DEFAULT_MODELS = [REPO / "tests" / "data" / "cq_red_cube_blue_cylinder.step",
                  REPO.parent / "shared" / "corpus" / "nist_mbe_pmi_2.stp"]


def tree_cpu_seconds(root):
    """User + system CPU seconds of `root` and of every process below it (reaped ones included,
    through the root's cutime/cstime), from /proc."""
    stats = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            text = pathlib.Path("/proc", entry, "stat").read_text()
        except OSError:
            continue
        fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) "
        stats[int(entry)] = (int(fields[1]), [int(f) for f in fields[11:15]])
    total, todo = 0, [root]
    while todo:
        pid = todo.pop()
        if pid not in stats:
            continue
        utime, stime, cutime, cstime = stats[pid][1]
        total += utime + stime + (cutime + cstime if pid == root else 0)
        todo.extend(child for child, (ppid, _) in stats.items() if ppid == pid)
    return total / os.sysconf("SC_CLK_TCK")


def start(binary, log_path, threads):
    log = open(log_path, "w")
    proc = subprocess.Popen([binary, "--listen", "127.0.0.1:0", "--threads", str(threads)],
                            stdout=log, stderr=subprocess.STDOUT)
    end = time.monotonic() + 20
    while time.monotonic() < end:
        match = re.search(r"listening on (\S+):(\d+)", pathlib.Path(log_path).read_text())
        if match:
            return proc, "%s:%s" % match.groups()
        time.sleep(0.05)
    proc.kill()
    raise SystemExit("%s did not start:\n%s" % (binary, pathlib.Path(log_path).read_text()))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--daemon", action="append", required=True, metavar="LABEL=BINARY")
    parser.add_argument("--models", nargs="+", default=[str(m) for m in DEFAULT_MODELS])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--rel", type=float, default=1e-3)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()

    daemons = []
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="isolation-bench-"))
    try:
        for spec in args.daemon:
            label, binary = spec.split("=", 1)
            proc, address = start(binary, tmp / (label + ".log"), args.threads)
            daemons.append((label, proc, Client(address)))
        models = {}
        for label, _, client in daemons:
            for path in args.models:
                info = client.upload(path)
                client.mesh(info, max_deviation_rel=args.rel)  # warm-up
                models[(label, path)] = info
        times = {key: [] for key in models}
        cpu = {key: [] for key in models}
        triangles = {}
        for _ in range(args.rounds):
            for path in args.models:
                for label, proc, client in daemons:
                    start_cpu = tree_cpu_seconds(proc.pid)
                    start_time = time.perf_counter()
                    result = client.mesh(models[(label, path)], max_deviation_rel=args.rel)
                    times[(label, path)].append(time.perf_counter() - start_time)
                    cpu[(label, path)].append(tree_cpu_seconds(proc.pid) - start_cpu)
                    triangles[(label, path)] = result.summary.triangles
        print("Mesh call wall time on a cached model, %d rounds, max_deviation_rel %g, "
              "--threads %d" % (args.rounds, args.rel, args.threads))
        print("| model | daemon | triangles | median s | p90 s | ratio | CPU s (daemon + workers) "
              "| CPU ratio |")
        print("|---|---|---:|---:|---:|---:|---:|---:|")
        for path in args.models:
            base = statistics.median(times[(daemons[0][0], path)])
            base_cpu = statistics.median(cpu[(daemons[0][0], path)])
            for label, _, _ in daemons:
                samples = sorted(times[(label, path)])
                median = statistics.median(samples)
                p90 = samples[min(len(samples) - 1, int(0.9 * len(samples)))]
                cpu_median = statistics.median(cpu[(label, path)])
                print("| %s | %s | %d | %.4f | %.4f | %.3f | %.3f | %.3f |" % (
                    pathlib.Path(path).name, label, triangles[(label, path)], median, p90,
                    median / base, cpu_median, cpu_median / base_cpu if base_cpu else 0.0))
    finally:
        for _, proc, client in daemons:
            client.close()
            proc.terminate()
            proc.wait()


if __name__ == "__main__":
    main()
