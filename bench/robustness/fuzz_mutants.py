#!/usr/bin/python3
"""Mutation testing of the model reader: broken STEP files through the CLI (and a daemon).

Generates N mutants of seed STEP files with a fixed --seed (byte flips, truncations, dropped or
duplicated lines, references moved to other entities, to themselves or to nothing, ORIENTED_EDGE
cycles, absurd numbers, deep parentheses, an edge repeated in an EDGE_LOOP), runs each through
`rdmesh mesh MUTANT -o out.msh --json --timeout T` and, with --daemon, through rdmeshd with the
Python client, and prints how many ended with each exit code / gRPC status, how many died by a
signal (crashes) and how many outlived --timeout by 30 s (hangs; for the daemon, calls that
ended at their own gRPC deadline of --timeout + 30 s are counted apart).

    /usr/bin/python3 bench/robustness/fuzz_mutants.py -n 200 --seed 1
    /usr/bin/python3 bench/robustness/fuzz_mutants.py -n 100 --daemon start      # starts build/bin/rdmeshd
    /usr/bin/python3 bench/robustness/fuzz_mutants.py -n 100 --daemon 127.0.0.1:50051 --no-cli

Exit status 1 when any CLI run crashed or hung (or the daemon died), else 0.
"""

import argparse
import collections
import json
import os
import pathlib
import random
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
DEFAULT_SEEDS = sorted(ROOT.glob("tests/data/*.st*p"))
REF = re.compile(rb"#(\d+)")
RECORD = re.compile(rb"^\s*#(\d+)\s*=\s*([A-Z0-9_]*)", re.M)
NUMBER = re.compile(rb"(?<![#\w.])-?\d+\.\d*(?:E[-+]?\d+)?")
# How long past --timeout a run may take before it counts as a hang (the CLI's watchdog allows 2).
HANG_GRACE = 30


def data_section(text):
    """(start, end) byte offsets of the DATA section's records."""
    start = text.find(b"DATA;")
    end = text.rfind(b"ENDSEC;")
    if start < 0 or end <= start:
        return 0, len(text)
    return start + 5, end


def records(text, keyword=None):
    """Match objects of '#id = KEYWORD' record starts, optionally of one keyword."""
    return [m for m in RECORD.finditer(text) if keyword is None or m.group(2) == keyword]


def record_end(text, match):
    end = text.find(b";", match.end())
    return len(text) if end < 0 else end


def refs_in(text, match):
    """Match objects of the #n references inside a record (not its own id)."""
    return list(REF.finditer(text, match.end(), record_end(text, match)))


def replace_span(text, start, end, new):
    return text[:start] + new + text[end:]


# Each mutator takes (rng, text) and returns the mutant, or None when it does not apply.

def flip_bytes(rng, text):
    data = bytearray(text)
    start, end = data_section(text)
    for _ in range(rng.randint(1, 8)):
        data[rng.randrange(start, end)] = rng.choice(b"0123456789#,();.-+ E'$*/\x00\xff")
    return bytes(data)


def truncate(rng, text):
    start, end = data_section(text)
    cut = rng.randrange(start, end)
    if rng.random() < 0.5:
        return text[:cut]  # no trailer: the framing check refuses it
    return text[:cut] + b"\nENDSEC;\nEND-ISO-10303-21;\n"


def drop_lines(rng, text):
    lines = text.split(b"\n")
    first = text[:data_section(text)[0]].count(b"\n") + 1
    for _ in range(rng.randint(1, 5)):
        if len(lines) > first + 3:
            del lines[rng.randrange(first, len(lines) - 2)]
    return b"\n".join(lines)


def duplicate_lines(rng, text):
    lines = text.split(b"\n")
    first = text[:data_section(text)[0]].count(b"\n") + 1
    for _ in range(rng.randint(1, 5)):
        i = rng.randrange(first, len(lines) - 2)
        lines.insert(i, lines[i])
    return b"\n".join(lines)


def _retarget(rng, text, target_of):
    """Points 1-3 random references at target_of(record_match, ids)."""
    recs = records(text)
    ids = [int(m.group(1)) for m in recs]
    for _ in range(rng.randint(1, 3)):
        rec = rng.choice(recs)
        refs = refs_in(text, rec)
        if not refs:
            continue
        ref = rng.choice(refs)
        text = replace_span(text, ref.start(), ref.end(), b"#%d" % target_of(rec, ids))
        recs = records(text)
    return text


def reference_other(rng, text):
    return _retarget(rng, text, lambda rec, ids: rng.choice(ids))


def reference_self(rng, text):
    return _retarget(rng, text, lambda rec, ids: int(rec.group(1)))


def reference_missing(rng, text):
    return _retarget(rng, text, lambda rec, ids: max(ids) + rng.randint(1, 1000))


def oriented_edge_cycle(rng, text):
    edges = records(text, b"ORIENTED_EDGE")
    if not edges:
        return None
    chain = rng.sample(edges, min(len(edges), rng.randint(1, 3)))
    ids = [int(m.group(1)) for m in chain]
    # Replace from the back so earlier offsets stay valid.
    for k in sorted(range(len(chain)), key=lambda k: -chain[k].start()):
        refs = refs_in(text, chain[k])
        if refs:
            ref = refs[-1]
            text = replace_span(text, ref.start(), ref.end(), b"#%d" % ids[(k + 1) % len(ids)])
    return text


def absurd_numbers(rng, text):
    values = [b"1.E+308", b"-1.E+308", b"1.E-320", b"0.", b"-0.", b"1.E+999",
              b"99999999999999999999.", b"123456789012345678901234567890."]
    numbers = list(NUMBER.finditer(text, *data_section(text)))
    for m in sorted(rng.sample(numbers, min(len(numbers), rng.randint(1, 6))),
                    key=lambda m: -m.start()):
        text = replace_span(text, m.start(), m.end(), rng.choice(values))
    return text


def deep_parentheses(rng, text):
    depth = rng.choice([500, 5000, 100000])
    start, _ = data_section(text)
    return (text[:start] + b"\n#999999=FOO(" + b"(" * depth + b"1" + b")" * depth + b");"
            + text[start:])


def repeat_loop_edge(rng, text):
    loops = records(text, b"EDGE_LOOP")
    if not loops:
        return None
    loop = rng.choice(loops)
    refs = refs_in(text, loop)
    if not refs:
        return None
    ref = rng.choice(refs)
    return replace_span(text, ref.start(), ref.end(), ref.group(0) + b"," + ref.group(0))


MUTATORS = [flip_bytes, truncate, drop_lines, duplicate_lines, reference_other, reference_self,
            reference_missing, oriented_edge_cycle, absurd_numbers, deep_parentheses,
            repeat_loop_edge]


def make_mutants(seeds, count, rng):
    """Yields `count` mutants (name, bytes, mutator name), round robin over seeds and mutators.
    A generator, so that 10,000 mutants are never all in memory; the order depends on the seed
    only."""
    sources = [(p.stem, p.read_bytes()) for p in seeds]
    made = 0
    while made < count:
        stem, text = rng.choice(sources)
        mutator = MUTATORS[made % len(MUTATORS)]
        mutant = mutator(rng, text)
        if mutant is None or mutant == text:
            continue
        yield ("%05d_%s_%s.step" % (made, mutator.__name__, stem), mutant, mutator.__name__)
        made += 1


def signal_name(number):
    try:
        return signal.Signals(number).name
    except ValueError:
        return "signal %d" % number


def run_cli(cli, path, out, timeout, env):
    """('exit N' | 'crash SIGxxx' | 'hang', seconds, note)."""
    start = time.monotonic()
    try:
        done = subprocess.run([str(cli), "mesh", str(path), "-o", str(out), "--json",
                               "--timeout", str(timeout), "--quiet"], capture_output=True,
                              timeout=timeout + HANG_GRACE, env=env)
    except subprocess.TimeoutExpired:
        return "hang", time.monotonic() - start, ""
    seconds = time.monotonic() - start
    if done.returncode < 0:
        return "crash " + signal_name(-done.returncode), seconds, ""
    note = ""
    lines = [line for line in done.stdout.decode(errors="replace").splitlines() if line.strip()]
    try:
        last = json.loads(lines[-1]) if lines else None
    except ValueError:
        last = None
    if last is None:
        note = "no JSON line"
    elif done.returncode != 0 and last.get("exit_code") != done.returncode:
        note = "JSON exit_code %s" % last.get("exit_code")
    return "exit %d" % done.returncode, seconds, note


class Daemon:
    """A daemon at an address, or one this script starts (and restarts when it dies)."""

    def __init__(self, address, binary):
        self.binary = binary
        self.process = None
        self.address = address if address != "start" else None
        self.deaths = 0
        self.lock = threading.Lock()  # one restart at a time with --jobs > 1
        if self.address is None:
            self.start()

    def start(self):
        self.log = tempfile.TemporaryFile()
        self.process = subprocess.Popen([str(self.binary), "--listen", "127.0.0.1:0"],
                                        stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            self.log.seek(0)
            found = re.search(rb"listening on ([\w.\-\[\]:]+):(\d+)", self.log.read())
            if found:
                self.address = "%s:%s" % (found.group(1).decode(), found.group(2).decode())
                return
            if self.process.poll() is not None:
                break
            time.sleep(0.1)
        raise SystemExit("rdmeshd did not start (no 'listening on' line in its log)")

    def died(self):
        """How the daemon this script runs died ("exit N" or "SIGxxx"), then starts a fresh one;
        None while it lives."""
        with self.lock:
            if self.process is None or self.process.poll() is None:
                return None
            code = self.process.returncode
            self.deaths += 1
            self.start()
            return signal_name(-code) if code < 0 else "exit %d" % code

    def stop(self):
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def run_daemon(daemon, path, timeout):
    """('OK' | grpc status name | 'daemon died', seconds, note)."""
    from rdmesh import Client, RdmeshError  # the build's stubs; see clients/python/rdmesh
    start = time.monotonic()
    try:
        with Client(daemon.address) as client:
            client.mesh(str(path), max_deviation_rel=1e-3, timeout_seconds=timeout,
                        timeout=timeout + HANG_GRACE)
        outcome = "OK"
    except RdmeshError as error:
        outcome = error.code.name if error.code else "UNKNOWN"
        if outcome == "DEADLINE_EXCEEDED" and time.monotonic() - start >= timeout + HANG_GRACE:
            # Not the job's timeout_seconds but the call's own deadline (an upload has no
            # timeout_seconds): gRPC ends the call there whatever the daemon does, so whether the
            # daemon stopped the work too shows in its log (fuzz_daemon.py reports it).
            outcome = "DEADLINE_EXCEEDED (call deadline)"
    seconds = time.monotonic() - start
    death = daemon.died()
    if death:
        return "daemon died", seconds, death
    return outcome, seconds, ""


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("seeds", nargs="*", type=pathlib.Path,
                        help="seed STEP files (default: tests/data/*.step, *.stp)")
    parser.add_argument("-n", "--count", type=int, default=100, help="mutants (default 100)")
    parser.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    parser.add_argument("--cli", type=pathlib.Path, default=ROOT / "build/bin/rdmesh")
    parser.add_argument("--no-cli", action="store_true", help="only the daemon")
    parser.add_argument("--no-fork", action="store_true",
                        help="run the CLI with RDMESH_NO_FORK=1 (its crash protection off)")
    parser.add_argument("--timeout", type=float, default=20, help="--timeout per run (s)")
    parser.add_argument("--daemon", help="HOST:PORT of an rdmeshd, or 'start' to run "
                        "build/bin/rdmeshd --listen 127.0.0.1:0 (restarted when it dies)")
    parser.add_argument("--rdmeshd", type=pathlib.Path, default=ROOT / "build/bin/rdmeshd")
    parser.add_argument("--keep", type=pathlib.Path,
                        help="keep the crashing and hanging mutants in this directory")
    parser.add_argument("--verbose", action="store_true", help="one line per mutant")
    parser.add_argument("--jobs", type=int, default=1,
                        help="mutants in flight at once (default 1); the mutants and their "
                        "order are the same whatever the number")
    parser.add_argument("--progress", type=int, default=0, metavar="N",
                        help="a progress line on stderr every N mutants")
    args = parser.parse_args()

    rng = random.Random(args.seed)
    seeds = args.seeds or DEFAULT_SEEDS
    mutants = make_mutants(seeds, args.count, rng)
    env = dict(os.environ, RDMESH_NO_FORK="1" if args.no_fork else "0")
    if args.daemon:
        sys.path.insert(0, str(ROOT / "clients/python"))
    daemon = Daemon(args.daemon, args.rdmeshd) if args.daemon else None

    tally = {"cli": collections.Counter(), "daemon": collections.Counter()}
    by_mutator = collections.defaultdict(collections.Counter)
    bad = []  # (channel, outcome, name)
    lock = threading.Lock()  # guards the generator and the tallies
    done = [0]
    started = time.monotonic()

    def run_one(tmp, name, data, mutator):
        path = tmp / name
        path.write_bytes(data)
        results = []
        if not args.no_cli:
            results.append(("cli",) + run_cli(args.cli, path, path.with_suffix(".msh"),
                                              args.timeout, env))
        if daemon:
            results.append(("daemon",) + run_daemon(daemon, path, args.timeout))
        path.unlink()
        path.with_suffix(".msh").unlink(missing_ok=True)
        with lock:
            for channel, outcome, seconds, note in results:
                tally[channel][outcome] += 1
                by_mutator[mutator][channel + " " + outcome] += 1
                failed = outcome.startswith("crash") or outcome in ("hang", "daemon died")
                if failed or note:
                    bad.append((channel, outcome + (" (%s)" % note if note else ""), name))
                    if args.keep and failed:
                        args.keep.mkdir(parents=True, exist_ok=True)
                        (args.keep / name).write_bytes(data)
                if args.verbose:
                    print("%-6s %-16s %6.1f s  %s %s" % (channel, outcome, seconds, name, note),
                          flush=True)
            done[0] += 1
            if args.progress and done[0] % args.progress == 0:
                print("progress: %d of %d mutants, %.0f s, %s" % (
                    done[0], args.count, time.monotonic() - started,
                    "; ".join("%s %s" % (c, dict(t)) for c, t in tally.items() if t)),
                    file=sys.stderr, flush=True)

    def stream(tmp):
        while True:
            with lock:
                mutant = next(mutants, None)
            if mutant is None:
                return
            run_one(tmp, *mutant)

    try:
        with tempfile.TemporaryDirectory(prefix="rdmesh_mutants_") as tmp:
            tmp = pathlib.Path(tmp)
            threads = [threading.Thread(target=stream, args=(tmp,)) for _ in range(args.jobs)]
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join()
    finally:
        if daemon:
            daemon.stop()

    print("%d mutants of %d seed files, seed %d, --timeout %g s, %d streams, %.0f s in all%s"
          % (done[0], len(seeds), args.seed, args.timeout, args.jobs, time.monotonic() - started,
             " (RDMESH_NO_FORK=1)" if args.no_fork else ""))
    for channel, counts in tally.items():
        if counts:
            print("%-6s %s" % (channel, ", ".join("%s: %d" % kv for kv in sorted(counts.items()))))
    print("per mutator:")
    for mutator, counts in sorted(by_mutator.items()):
        print("  %-20s %s" % (mutator, ", ".join("%s: %d" % kv for kv in sorted(counts.items()))))
    crashes = sum(1 for channel, outcome, _ in bad if outcome.startswith("crash"))
    hangs = sum(1 for channel, outcome, _ in bad if outcome == "hang")
    print("crashes (death by a signal): %d, hangs: %d, daemon deaths: %d"
          % (crashes, hangs, daemon.deaths if daemon else 0))
    for channel, outcome, name in bad:
        print("  %-6s %-24s %s" % (channel, outcome, name))
    cli_bad = any(c == "cli" and (o.startswith("crash") or o == "hang") for c, o, _ in bad)
    return 1 if cli_bad or (daemon and daemon.deaths) else 0


if __name__ == "__main__":
    sys.exit(main())
