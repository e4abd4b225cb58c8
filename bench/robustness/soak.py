#!/usr/bin/env python3
"""Soak: concurrent clients against one rdmeshd for minutes, with some hostile files among the
models, sampling the daemon's and its workers' memory. Measures; asserts nothing.

    /usr/bin/python3 bench/robustness/soak.py [--minutes 10] [--clients 8] [--fuzz-every 5]
                                   [--daemon build/bin/rdmeshd | --address HOST:PORT]
                                   [--models a.step b.stp ...] [--json out.json]

Each client loops: pick a model (every --fuzz-every-th request a mutant: a self-referencing
ORIENTED_EDGE, a truncated file, a repeated EDGE_LOOP, bytes flipped, a deep nest of
parentheses), upload it, mesh it at a relative deviation drawn from 1e-2, 3e-3 and 1e-3 with a
30 s deadline. Every well-formed result is hashed (xyz and triangles); the same model and
deviation must give the same hash every time (determinism across workers). Reports requests
done, errors by gRPC status, mismatches, the daemon's and the workers' RSS at 1, 5 and 10
minutes (or the fractions 0.1, 0.5 and 1.0 of a shorter run), and whether RSS after warm-up
stayed within 10%.
"""

import argparse
import collections
import hashlib
import json
import pathlib
import random
import re
import subprocess
import sys
import tempfile
import threading
import time

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "clients" / "python"))
import grpc  # noqa: E402
from rdmesh import Client, RdmeshError  # noqa: E402

DATA = REPO / "tests" / "data"
CORPUS = REPO.parent / "shared" / "corpus"
DEFAULT_MODELS = [DATA / "cq_red_cube_blue_cylinder.step", DATA / "axom_sliced_cylinder.step",
                  DATA / "nist_mbe_pmi_11.stp", DATA / "pyocc_eight_cyl.stp",
                  CORPUS / "gmsh_cube_filet.stp", CORPUS / "gmsh_part.step",
                  CORPUS / "gmsh_zylkopf.stp", CORPUS / "nist_mbe_pmi_1.stp"]
DEVIATIONS = [1e-2, 3e-3, 1e-3]


def mutants(seed_text, rng):
    """Hostile variants of a STEP text, as (name, bytes)."""
    lines = seed_text.splitlines(keepends=True)
    oriented = [i for i, line in enumerate(lines) if "=ORIENTED_EDGE(" in line]
    loops = [i for i, line in enumerate(lines)
             if "=EDGE_LOOP(" in line and 0 <= line.rfind("(") < line.find(")")]
    out = []
    if oriented:
        i = rng.choice(oriented)
        entity = lines[i].split("=", 1)[0]
        fixed = re.sub(r"#\d+(,\.[TF]\.\);)", entity + r"\1", lines[i])
        out.append(("selfref", "".join(lines[:i] + [fixed] + lines[i + 1:])))
    if loops:
        i = rng.choice(loops)
        inner = lines[i][lines[i].rindex("(") + 1:lines[i].index(")")]
        repeated = lines[i].replace(inner, ",".join([inner] * 40))
        out.append(("loop40", "".join(lines[:i] + [repeated] + lines[i + 1:])))
    cut = rng.randrange(len(seed_text) // 4, len(seed_text))
    out.append(("truncated", seed_text[:cut]))
    flipped = bytearray(seed_text.encode())
    for _ in range(20):
        flipped[rng.randrange(len(flipped))] = rng.randrange(32, 127)
    out.append(("flipped", flipped.decode("ascii", "replace")))
    head, tail = seed_text.split("DATA;", 1)
    out.append(("nested", head + "DATA;\n#1=X(" + "(" * 20000 + ")" * 20000 + ");\n" + tail))
    return [(name, text.encode() if isinstance(text, str) else text) for name, text in out]


def rss_kib(pid):
    try:
        for line in pathlib.Path("/proc/%d/status" % pid).read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--fuzz-every", type=int, default=5)
    parser.add_argument("--daemon", default=str(REPO / "build" / "bin" / "rdmeshd"))
    parser.add_argument("--address", help="use a running daemon instead of starting one")
    parser.add_argument("--models", nargs="+", default=[str(m) for m in DEFAULT_MODELS])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", help="also write the report here")
    args = parser.parse_args()

    models = [pathlib.Path(m) for m in args.models if pathlib.Path(m).exists()]
    rng = random.Random(args.seed)
    hostile = []
    for model in models[:4]:
        hostile += mutants(model.read_text(errors="replace"), rng)

    proc = None
    daemon_pid = None
    if args.address:
        address = args.address
    else:
        log_path = pathlib.Path(tempfile.mkdtemp(prefix="soak-")) / "rdmeshd.log"
        log = open(log_path, "w")
        proc = subprocess.Popen([args.daemon, "--listen", "127.0.0.1:0", "--max-queue", "64",
                                 "--worker-cpu-seconds", "60"], stdout=log,
                                stderr=subprocess.STDOUT)
        daemon_pid = proc.pid
        for _ in range(400):
            match = re.search(r"listening on (\S+):(\d+)", log_path.read_text())
            if match:
                break
            time.sleep(0.05)
        address = "%s:%s" % match.groups()
        print("rdmeshd pid %d on %s, log %s" % (proc.pid, address, log_path))

    lock = threading.Lock()
    outcomes = collections.Counter()
    messages = collections.Counter()
    hashes = {}
    mismatches = []
    done = [0]
    stop = time.monotonic() + args.minutes * 60

    def client_loop(index):
        local = random.Random(args.seed * 1000 + index)
        client = Client(address)
        count = 0
        while time.monotonic() < stop:
            count += 1
            rel = local.choice(DEVIATIONS)
            if args.fuzz_every and count % args.fuzz_every == 0:
                name, data = local.choice(hostile)
                key = None
            else:
                path = local.choice(models)
                name, data, key = path.name, path.read_bytes(), (path.name, rel)
            try:
                info = client.upload(data, name=name + ".step", timeout=60)
                result = client.mesh(info, max_deviation_rel=rel, timeout=30)
                digest = hashlib.sha256(result.xyz.tobytes() + result.triangles.tobytes()
                                        ).hexdigest()
                outcome = "OK"
                with lock:
                    if key is not None:
                        if hashes.setdefault(key, digest) != digest:
                            mismatches.append(key)
            except RdmeshError as error:
                outcome = error.code.name if error.code else "UNKNOWN"
                if key is not None:
                    outcome += " (well-formed %s)" % name
                detail = re.sub(r"'[^']*'", "'...'", str(error.details))
                with lock:
                    messages[(outcome, re.sub(r"[0-9.]+ s\b", "N s", detail))] += 1
            except grpc.RpcError as error:
                outcome = "RPC " + error.code().name
            with lock:
                outcomes[outcome] += 1
                done[0] += 1
        client.close()

    def pids():
        found = []
        if daemon_pid:
            for task in pathlib.Path("/proc/%d/task" % daemon_pid).iterdir():
                try:
                    found += [int(p) for p in (task / "children").read_text().split()]
                except OSError:
                    pass
        return found

    marks = [1, 5, 10] if args.minutes >= 10 else [args.minutes * f for f in (0.1, 0.5, 1.0)]
    samples = []
    threads = [threading.Thread(target=client_loop, args=(i,)) for i in range(args.clients)]
    start = time.monotonic()
    for thread in threads:
        thread.start()
    for mark in marks:
        while time.monotonic() - start < mark * 60 and any(t.is_alive() for t in threads):
            time.sleep(0.5)
        workers = pids()
        samples.append({"minute": round(mark, 2), "requests": done[0],
                        "daemon_rss_mib": round(rss_kib(daemon_pid) / 1024, 1)
                        if daemon_pid else None,
                        "workers": len(workers),
                        "workers_rss_mib": round(sum(rss_kib(p) for p in workers) / 1024, 1)})
        print("minute %.1f: %s" % (mark, samples[-1]), flush=True)
    for thread in threads:
        thread.join()
    status = Client(address).server_status()
    alive = proc is None or proc.poll() is None
    report = {"minutes": args.minutes, "clients": args.clients, "requests": done[0],
              "outcomes": dict(outcomes),
              "messages": ["%d x %s: %s" % (n, o, m) for (o, m), n in messages.most_common()],
              "mismatches": mismatches, "samples": samples,
              "daemon_alive": alive, "workers_lost": status.workers_lost,
              "refused_models": status.refused_models, "jobs_completed": status.jobs_completed}
    if daemon_pid and len(samples) >= 2 and samples[0]["daemon_rss_mib"]:
        growth = samples[-1]["daemon_rss_mib"] / samples[0]["daemon_rss_mib"] - 1
        report["daemon_rss_growth_after_warmup"] = round(growth, 3)
        report["flat_within_10pct"] = abs(growth) <= 0.10
    print(json.dumps(report, indent=1))
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(report, indent=1))
    if proc:
        proc.terminate()
        proc.wait()


if __name__ == "__main__":
    main()
