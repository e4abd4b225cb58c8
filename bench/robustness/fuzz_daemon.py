#!/usr/bin/env python3
"""Many fuzzed models through one rdmeshd, with well-formed jobs beside them. Measures; the bar of
issue 12: the daemon never restarts or drops a connection, every request ends with OK or a
documented status, and the well-formed jobs all complete byte-identical to the local CLI.

    /usr/bin/python3 bench/robustness/fuzz_daemon.py [-n 10000] [--seed 1] [--jobs 3] [--timeout 10]
                                          [--clients 8] [--client-pause 5]
                                          [--rdmeshd build/bin/rdmeshd] [--cli build/bin/rdmesh]

Starts rdmeshd on loopback, runs `bench/robustness/fuzz_mutants.py -n N --daemon ADDRESS --no-cli --jobs J`
(J mutants in flight: each an upload and a mesh at 1e-3 of the diagonal with `timeout_seconds`
--timeout), and meanwhile --clients threads that each loop `rdmesh mesh MODEL -o OUT.msh --remote
ADDRESS` over the bundled models, --client-pause seconds apart, and compare the file with a local
`rdmesh mesh MODEL -o REF.msh` byte for byte. fuzz_mutants.py's progress lines go to stderr. At the end it reports the
mutants' outcomes (fuzz_mutants.py's summary), the well-formed jobs (done, identical, differing,
failed), whether the daemon is the same process as at the start, and its worker counts.
"""

import argparse
import collections
import filecmp
import pathlib
import re
import subprocess
import sys
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "clients" / "python"))
from rdmesh import Client  # noqa: E402

MODELS = sorted(ROOT.glob("tests/data/*.st*p"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-n", "--count", type=int, default=10000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=3, help="mutants in flight (default 3)")
    parser.add_argument("--timeout", type=float, default=10,
                        help="timeout_seconds of each mutant's calls (default 10)")
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--client-pause", type=float, default=5,
                        help="seconds each well-formed client waits between its jobs (default 5)")
    parser.add_argument("--rdmeshd", default=str(ROOT / "build" / "bin" / "rdmeshd"))
    parser.add_argument("--cli", default=str(ROOT / "build" / "bin" / "rdmesh"))
    args = parser.parse_args()

    tmp = pathlib.Path(tempfile.mkdtemp(prefix="fuzz-daemon-"))
    log_path = tmp / "rdmeshd.log"
    log = open(log_path, "w")
    daemon = subprocess.Popen([args.rdmeshd, "--listen", "127.0.0.1:0", "--max-queue", "64"],
                              stdout=log, stderr=subprocess.STDOUT)
    address = None
    for _ in range(600):
        match = re.search(r"listening on (\S+):(\d+)", log_path.read_text())
        if match:
            address = "%s:%s" % match.groups()
            break
        time.sleep(0.05)
    if address is None:
        raise SystemExit("rdmeshd did not start:\n" + log_path.read_text())
    print("rdmeshd pid %d on %s, log %s" % (daemon.pid, address, log_path), flush=True)

    references = {}
    for model in MODELS:
        ref = tmp / (model.stem + ".ref.msh")
        subprocess.run([args.cli, "mesh", str(model), "-o", str(ref), "--quiet"], check=True)
        references[model] = ref

    stop = threading.Event()
    tally = collections.Counter()
    lock = threading.Lock()

    def well_formed(index):
        count = 0
        while not stop.is_set():
            model = MODELS[(index + count) % len(MODELS)]
            count += 1
            out = tmp / ("client%d.msh" % index)
            run = subprocess.run([args.cli, "mesh", str(model), "-o", str(out), "--quiet",
                                  "--remote", address], capture_output=True, text=True)
            if run.returncode != 0:
                outcome = "failed (exit %d: %s)" % (run.returncode, run.stderr.strip()[-200:])
            elif filecmp.cmp(out, references[model], shallow=False):
                outcome = "identical"
            else:
                outcome = "differs (%s)" % model.name
            with lock:
                tally[outcome] += 1
            stop.wait(args.client_pause)

    threads = [threading.Thread(target=well_formed, args=(i,)) for i in range(args.clients)]
    for thread in threads:
        thread.start()
    start = time.monotonic()
    fuzz = subprocess.run([sys.executable, str(ROOT / "bench" / "robustness" / "fuzz_mutants.py"), "-n",
                           str(args.count), "--seed", str(args.seed), "--daemon", address,
                           "--no-cli", "--jobs", str(args.jobs), "--timeout", str(args.timeout),
                           "--progress", "500"], stdout=subprocess.PIPE, text=True)
    stop.set()
    for thread in threads:
        thread.join()
    print(fuzz.stdout[-4000:])
    alive = daemon.poll() is None
    status = Client(address).server_status() if alive else None
    print("%.0f s; well-formed jobs beside them (%d clients): %s" % (
        time.monotonic() - start, args.clients, dict(tally)))
    print("daemon: %s (pid %d), uptime %s s, jobs completed %s, workers lost %s, refused "
          "models %s" % ("alive, never restarted" if alive else "DIED", daemon.pid,
                         round(status.uptime_seconds) if status else "-",
                         status.jobs_completed if status else "-",
                         status.workers_lost if status else "-",
                         status.refused_models if status else "-"))
    daemon.terminate()
    daemon.wait()
    # The daemon's own view of how long each call ran ("req=... ok in S s" / "failed in S s"): a
    # call whose work went on after its deadline would show here, not in the client's outcome.
    seconds = [float(m) for m in re.findall(r"req=\w+ (?:ok|failed) in ([0-9.]+) s",
                                              log_path.read_text())]
    longest_deadline = args.timeout + 30  # fuzz_mutants.py's call deadline (HANG_GRACE)
    over = [s for s in seconds if s > longest_deadline + 2]
    print("daemon log: %d calls ended, the longest after %.1f s; %d ran more than 2 s past the "
          "longest call deadline (%g s)%s" % (
              len(seconds), max(seconds, default=0), len(over), longest_deadline,
              ": " + ", ".join("%.1f s" % s for s in sorted(over)[-10:]) if over else ""))


if __name__ == "__main__":
    main()
