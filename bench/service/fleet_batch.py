#!/usr/bin/python3
"""Throughput of a dataset through the service (docs/BATCH.md, "Through the service"): the same
sample of KiCad files meshed by `rdmesh-py batch` against one rdmeshd, by `rdmesh-py batch`
against three rdmeshd replicas behind nginx (the shipped deploy/nginx/rdmesh-grpc.conf, routed on
x-rdmesh-model, as tests/python/test_routing.py runs it), and by the local C++ `rdmesh batch
--jobs 2`, all on loopback, in alternation; prints one Markdown table.

    /usr/bin/python3 bench/service/fleet_batch.py [--build build] [--rounds 2] [--out table.md]

The sample: `random.Random(35).sample(sorted(str(p) for p in root.rglob('*.step')), 200)` with
root the extracted kicad-packages3d (/tmp/kicad/usr/share/kicad/3dmodels; `cd /tmp && apt-get
download kicad-packages3d && dpkg-deb -x kicad-packages3d_*.deb /tmp/kicad`), the sample of
docs/BATCH.md's throughput table. Every run writes .msh at the default 1e-3 of the diagonal into
a fresh folder. Each replica is `rdmeshd --threads 1` (one engine thread per job, as the C++
batch gives each child on 2 cores) with `--max-jobs 2` alone or `--max-jobs 1` as one of three
(deploy/k8s's RDMESH_MAX_JOBS); the client keeps 2 calls per job slot in flight (--jobs 4 and
6). `py1s` is the one-replica run with `--cache-dir` on (the parsed-model store deploy/k8s
turns on): what writing every model to the store costs, and its size. CPU seconds are user +
system of every process of the run (client, daemons and their workers, nginx; for the C++
batch, its children), from getrusage(RUSAGE_CHILDREN) once all are reaped, so the daemons'
start-up is included (about 0.1 s each).
"""

import argparse
import json
import os
import pathlib
import random
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "clients" / "python"))
sys.path.insert(0, str(REPO / "tests" / "python"))
from test_routing import Nginx  # noqa: E402

KICAD = pathlib.Path("/tmp/kicad/usr/share/kicad/3dmodels")
RDMESH_PY = REPO / "clients" / "python" / "rdmesh-py"


def sample(root, count, seed):
    files = sorted(str(p) for p in root.rglob("*.step"))
    if len(files) < count:
        sys.exit("fleet_batch: %d .step files under %s; extract kicad-packages3d there first"
                 % (len(files), root))
    return random.Random(seed).sample(files, count)


def children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


class Replica:
    """rdmeshd on 127.0.0.1:<free port>, its log in `log`."""

    def __init__(self, binary, log, max_jobs, store=None):
        self.log_path = log
        self._log = open(log, "w")
        extra = ["--cache-dir", str(store)] if store else []
        self.proc = subprocess.Popen(
            [binary, "--listen", "127.0.0.1:0", "--threads", "1", "--max-jobs", str(max_jobs),
             *extra], stdout=self._log, stderr=subprocess.STDOUT)
        end = time.monotonic() + 30
        while time.monotonic() < end:
            match = re.search(r"listening on (\S+):(\d+) ", log.read_text())
            if match:
                self.address = "%s:%s" % match.groups()
                return
            if self.proc.poll() is not None:
                break
            time.sleep(0.05)
        raise RuntimeError("rdmeshd did not start:\n" + log.read_text())

    def stop(self):
        self.proc.terminate()
        self.proc.wait(timeout=60)
        self._log.close()


def run_py(address, listing, out, jobs):
    proc = subprocess.run(["/usr/bin/python3", str(RDMESH_PY), "--address", address, "batch",
                           "@%s" % listing, "-o", str(out), "--format", "msh", "--jobs",
                           str(jobs), "--json", "-q"], capture_output=True, text=True)
    if proc.returncode not in (0, 1):
        raise RuntimeError("rdmesh-py batch exited %d:\n%s" % (proc.returncode, proc.stderr))
    return json.loads(proc.stdout.strip().splitlines()[-1])


def measure(kind, args, listing, work, run_id):
    """One run: (row dict, manifest entries by path)."""
    out = work / ("out-%s" % run_id)
    load_before = os.getloadavg()[0]
    cpu_before = children_cpu()
    start = time.monotonic()
    client_cpu = None
    replicas, nginx = [], None
    try:
        if kind == "cpp":
            proc = subprocess.run([str(args.build / "bin" / "rdmesh"), "batch", "@%s" % listing,
                                   "-o", str(out), "--jobs", "2", "--format", "msh", "--json",
                                   "-q"], capture_output=True, text=True)
            summary = json.loads(proc.stdout.strip().splitlines()[-1])
            label = "C++ `rdmesh batch --jobs 2` (local, a process per file)"
        else:
            count = 3 if kind == "py3" else 1
            store = work / ("store-%s" % run_id) if kind == "py1s" else None
            replicas = [Replica(str(args.build / "bin" / "rdmeshd"),
                                work / ("%s-replica%d.log" % (run_id, i)), 2 if count == 1 else 1,
                                store)
                        for i in range(count)]
            address = replicas[0].address
            if count > 1:
                (work / run_id).mkdir()
                nginx = Nginx(work / run_id, [r.address for r in replicas])
                address = nginx.address
            jobs = 4 if count == 1 else 6
            start = time.monotonic()  # the daemons' start-up is not the batch's wall time
            client_before = children_cpu()
            summary = run_py(address, listing, out, jobs)
            client_cpu = children_cpu() - client_before
            label = ("`rdmesh-py batch --jobs 4`, 1 rdmeshd (--max-jobs 2)" if count == 1 else
                     "`rdmesh-py batch --jobs 6`, 3 rdmeshd (--max-jobs 1 each) behind nginx")
            if store:
                label = label.replace("--max-jobs 2", "--max-jobs 2 --cache-dir, the store "
                                                      "deploy/k8s turns on")
        wall = time.monotonic() - start
    finally:
        if nginx is not None:
            nginx.stop()
        for replica in replicas:
            replica.stop()
    cpu = children_cpu() - cpu_before
    with open(out / "manifest.jsonl") as file:
        entries = {e["path"]: e for e in map(json.loads, file)}
    counts = summary["counts"]
    output_mb = sum(p.stat().st_size for p in out.rglob("*.msh")) / 1e6
    store_mb = None
    if kind == "py1s":
        store_mb = sum(p.stat().st_size for p in (work / ("store-%s" % run_id)).rglob("*")
                       if p.is_file()) / 1e6
    row = {"output_mb": output_mb, "store_mb": store_mb, "run": run_id, "kind": kind,
           "label": label, "wall": wall, "files_per_min": 60.0 * len(entries) / wall,
           "cpu": cpu, "client_cpu": client_cpu,
           "ok": counts["ok"], "not_ok": sum(v for k, v in counts.items() if k != "ok"),
           "load": (load_before, os.getloadavg()[0])}
    return row, entries


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", type=pathlib.Path, default=REPO / "build",
                        help="build folder holding bin/rdmesh and bin/rdmeshd (%(default)s)")
    parser.add_argument("--root", type=pathlib.Path, default=KICAD)
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seed", type=int, default=35)
    parser.add_argument("--rounds", type=int, default=2,
                        help="each configuration this many times, in alternation")
    parser.add_argument("--kinds", default="cpp,py1,py3",
                        help="which runs, in order: cpp, py1 (one rdmeshd), py3 (three "
                             "behind nginx), py1s (one rdmeshd with --cache-dir)")
    parser.add_argument("--out", type=pathlib.Path, help="also write the table here")
    parser.add_argument("--keep", action="store_true", help="keep the meshes and logs")
    args = parser.parse_args()
    args.build = args.build.resolve()

    files = sample(args.root, args.count, args.seed)
    work = pathlib.Path(tempfile.mkdtemp(prefix="fleet-batch-"))
    listing = work / "sample.txt"
    listing.write_text("".join(f + "\n" for f in files))
    megabytes = sum(os.path.getsize(f) for f in files) / 1e6
    rows, manifests = [], {}
    kinds = args.kinds.split(",")
    try:
        for r in range(args.rounds):
            for kind in kinds:
                run_id = "%s-%d" % (kind, r + 1)
                print("fleet_batch: %s ..." % run_id, file=sys.stderr, flush=True)
                row, entries = measure(kind, args, listing, work, run_id)
                rows.append(row)
                manifests[run_id] = entries
                print("fleet_batch: %s: %.1f s, %.1f files/min, CPU %.1f s, load %.2f -> %.2f"
                      % (run_id, row["wall"], row["files_per_min"], row["cpu"], *row["load"]),
                      file=sys.stderr, flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)

    # The meshes agree: triangles per file of each service run against the first C++ run.
    reference = next((m for k, m in manifests.items() if k.startswith("cpp")), None)
    lines = ["%d KiCad files (%.1f MB, `random.Random(%d)` sample of %s), .msh at 1e-3, "
             "build %s, %s, %d cores (`nproc`)." % (len(files), megabytes, args.seed, args.root,
                                                    args.build.name,
                                                    time.strftime("%Y-%m-%d %H:%M UTC",
                                                                  time.gmtime()),
                                                    os.cpu_count()),
             "",
             "| run | what | wall s | files/min | CPU s (all processes) | CPU s per file "
             "| of which the Python client | ok / not ok | same triangles as C++ | .msh MB "
             "| load average before → after |",
             "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---|"]
    for row in rows:
        same = "-"
        if reference is not None and not row["kind"].startswith("cpp"):
            entries = manifests[row["run"]]
            same = "%d of %d" % (sum(1 for p, e in entries.items()
                                     if p in reference
                                     and e["triangles"] == reference[p]["triangles"]),
                                 len(entries))
        lines.append("| %s | %s | %.1f | %.1f | %.1f | %.3f | %s | %d / %d | %s | %.1f "
                     "| %.2f → %.2f |"
                     % (row["run"], row["label"], row["wall"], row["files_per_min"], row["cpu"],
                        row["cpu"] / len(files),
                        "%.1f" % row["client_cpu"] if row["client_cpu"] is not None else "-",
                        row["ok"], row["not_ok"], same, row["output_mb"], *row["load"]))
    for row in rows:
        if row["store_mb"] is not None:
            lines.append("")
            lines.append("%s: the store held %.1f MB after the run (%.0f KB a file)."
                         % (row["run"], row["store_mb"], 1e3 * row["store_mb"] / len(files)))
    table = "\n".join(lines) + "\n"
    print(table)
    if args.out:
        args.out.write_text(table)


if __name__ == "__main__":
    main()
