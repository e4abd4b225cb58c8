#!/usr/bin/env python3
"""Issue 34's end-to-end table: a STEP file to a mesh on disk, `rdmesh mesh` against OCCT's plain
read + BRepMesh + an MSH write (bench/performance/plain_runner.cpp), whole processes, wall time.

    /usr/bin/python3 bench/performance/parse_e2e.py \
        --kicad-root /tmp/kicad/usr/share/kicad/3dmodels \
        --rdmesh build/bin/rdmesh --plain-runner build/bin/plain_runner [--service]

Files: the KiCad 3D model library (Debian's kicad-packages3d; fetched with `apt-get download` and
`dpkg-deb -x` into --kicad-dir unless --kicad-root points at an extracted 3dmodels folder),
sampled with a fixed seed, two per folder (one where a folder has one), plus every STEP file of the
corpus (../shared/corpus). For each file, after one untimed read of it (page cache), three rounds
of `rdmesh mesh FILE -o OUT.msh --max-deviation-rel 1e-3 --json` and `plain_runner FILE OUT.msh`,
the order swapped every round; wall time is time.perf_counter() around subprocess.run, and each
side's figure is the median of its three. Outputs go to a tmpfs directory when /dev/shm exists.
The ratio is rdmesh's median over the plain runner's (below 1: rdmesh is faster).

Also: the load alone (rdmesh's load_seconds against the plain runner's read + transfer), the fixed
cost per process (`rdmesh --help` against `plain_runner` with no arguments, and seven pairs on the
sampled file nearest 50 faces), the load on one core (taskset -c 0) against two on the files with
more than 200 faces, and with --service the first Mesh after UploadModel through a
fresh rdmeshd against the plain runner on a few files. Writes the markdown table (--out) and
every measurement as JSON (--json); --results-only re-renders the markdown from such a JSON file.
"""

import argparse
import concurrent.futures
import datetime
import json
import math
import os
import pathlib
import platform
import random
import re
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[2]
CORPUS = REPO.parent / "shared" / "corpus"
STEP_SUFFIXES = (".step", ".stp")
REL = 1e-3
# Environment variables that would change what a run measures (a model store, no fork, threads,
# the STEP reader); --rdmesh-env sets them explicitly.
DROPPED_ENV = ("RDMESH_CACHE_DIR", "RDMESH_CACHE_DIR_BYTES", "RDMESH_NO_FORK", "RDMESH_THREADS",
               "RDMESH_STEP_READER")
# Both sides' allocator (mimalloc, linked into rdmesh-local and the plain runner alike) on
# transparent huge pages: rdmesh's launcher sets this for the program it runs, and the plain
# runner, started directly, gets it here (docs/TUNING.md, "The allocator").
SHARED_ENV = {"MIMALLOC_LARGE_OS_PAGES": "1"}
SERIAL = True  # one process at a time (--jobs 1): the children's CPU time is the one run's
TIMEOUT = 900.0  # seconds per process (--timeout)


# -- files ------------------------------------------------------------------------------------

def is_step(path):
    return path.suffix.lower() in STEP_SUFFIXES


def kicad_sample(root, seed, per_folder=2):
    """`per_folder` STEP files of every folder of `root` (all of them where it holds fewer),
    chosen by a generator seeded with `seed` and the folder's name: the same files on every
    machine, whatever other folders exist. Folders and files in sorted order."""
    root = pathlib.Path(root)
    chosen = []
    for folder in sorted(p for p in root.iterdir() if p.is_dir()):
        files = sorted((p for p in folder.iterdir() if p.is_file() and is_step(p)),
                       key=lambda p: p.name)
        if not files:
            continue
        rng = random.Random("%s/%s" % (seed, folder.name))
        picked = rng.sample(files, min(per_folder, len(files)))
        chosen.extend(sorted(picked, key=lambda p: p.name))
    return chosen


def corpus_files(corpus):
    return sorted((p for p in pathlib.Path(corpus).iterdir() if p.is_file() and is_step(p)),
                  key=lambda p: p.name)


def fetch_kicad(cache_dir):
    """The 3dmodels folder of kicad-packages3d under `cache_dir`, downloaded and extracted there
    with apt-get download and dpkg-deb -x the first time."""
    cache_dir = pathlib.Path(cache_dir).expanduser()
    root = cache_dir / "usr" / "share" / "kicad" / "3dmodels"
    if root.is_dir():
        return root
    cache_dir.mkdir(parents=True, exist_ok=True)
    debs = sorted(cache_dir.glob("kicad-packages3d_*.deb"))
    if not debs:
        print("fetching kicad-packages3d into %s (apt-get download)" % cache_dir, file=sys.stderr)
        subprocess.run(["apt-get", "download", "kicad-packages3d"], cwd=cache_dir, check=True)
        debs = sorted(cache_dir.glob("kicad-packages3d_*.deb"))
    subprocess.run(["dpkg-deb", "-x", str(debs[-1]), str(cache_dir)], check=True)
    return root


# -- measuring --------------------------------------------------------------------------------

def child_env(extra=()):
    """The environment of every run: ours without DROPPED_ENV, with SHARED_ENV where ours does
    not set it, plus `extra` ("KEY=VALUE")."""
    env = {k: v for k, v in os.environ.items() if k not in DROPPED_ENV}
    for key, value in SHARED_ENV.items():
        env.setdefault(key, value)
    for item in extra:
        key, _, value = item.partition("=")
        env[key] = value
    return env


def last_json(text):
    """The last line of `text` that is a JSON object, or None."""
    for line in reversed(text.splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line)
            except ValueError:
                continue
    return None


def timed(command, env, ok_codes=(0,)):
    """One whole process: {wall, cpu (user + system of the child; None when several run at once,
    --jobs > 1, since os.times() sums all children), code, report (its last JSON line), error}."""
    before = os.times()
    start = time.perf_counter()
    try:
        proc = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
                              timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"wall": time.perf_counter() - start, "cpu": None, "code": None, "report": None,
                "error": "no result after %g s" % TIMEOUT}
    wall = time.perf_counter() - start
    after = os.times()
    cpu = (after.children_user - before.children_user
           + after.children_system - before.children_system) if SERIAL else None
    run = {"wall": wall, "cpu": cpu, "code": proc.returncode,
           "report": last_json(proc.stdout.decode(errors="replace"))}
    if proc.returncode not in ok_codes:
        last = (proc.stderr.decode(errors="replace").strip().splitlines() or [""])[-1]
        # The file's path is in the row already.
        for arg in command[1:3]:
            last = last.replace("'%s'" % arg, "FILE") if arg.endswith(STEP_SUFFIXES) else last
        run["error"] = "exit %s: %s" % (proc.returncode, last[:160])
    return run


def load_stages(report):
    """What rdmesh's --json says about its load beyond load_seconds: any key naming the load or
    its stages (e.g. "load_stages"), as reported."""
    if not report:
        return None
    found = {k: v for k, v in report.items()
             if k != "load_seconds" and ("load" in k or "stage" in k)}
    return found or None


def flat_stages(stages, prefix=""):
    """The numbers in what load_stages() found, one level: {"load_stages": {"parse": 0.1}} gives
    {"parse": 0.1}; deeper keys are joined with '.'."""
    flat = {}
    for key, value in (stages or {}).items():
        if isinstance(value, dict):
            inner = "" if not prefix and len(stages) == 1 else prefix + key + "."
            flat.update(flat_stages(value, inner))
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            flat[prefix + key] = value
    return flat


def rdmesh_command(rdmesh, path, out):
    return [rdmesh, "mesh", str(path), "-o", str(out), "--max-deviation-rel", repr(REL), "--json"]


def plain_command(plain, path, out):
    return [plain, str(path), str(out)]


def measure_file(path, group, args, work_dir, env, rounds):
    """Alternating whole-process runs of both sides on one file; the per-file row."""
    path = pathlib.Path(path)
    path.read_bytes()  # page cache: both sides read a warm file
    tag = re.sub(r"[^A-Za-z0-9_.-]", "_", path.stem)[:60]
    outs = {"rdmesh": work_dir / (tag + ".rdmesh.msh"), "plain": work_dir / (tag + ".plain.msh")}
    commands = {"rdmesh": rdmesh_command(args.rdmesh, path, outs["rdmesh"]),
                "plain": plain_command(args.plain_runner, path, outs["plain"])}
    runs = {"rdmesh": [], "plain": []}
    for r in range(rounds):
        for side in (("rdmesh", "plain") if r % 2 == 0 else ("plain", "rdmesh")):
            run = timed(commands[side], env)
            runs[side].append(run)
            for out in outs.values():
                if out.exists():
                    out.unlink()
    return summarize_file(path, group, runs)


def summarize_file(path, group, runs):
    path = pathlib.Path(path)
    row = {"file": str(path), "name": path.name, "group": group, "folder": path.parent.name,
           "size_bytes": path.stat().st_size}
    errors = {side: next((r["error"] for r in rs if "error" in r), None)
              for side, rs in runs.items()}
    row["errors"] = {k: v for k, v in errors.items() if v}
    for side, rs in runs.items():
        row[side + "_walls"] = [r["wall"] for r in rs]
        row[side + "_cpus"] = [r["cpu"] for r in rs]
    if row["errors"]:
        return row
    ours = [r["report"] or {} for r in runs["rdmesh"]]
    plain = [r["report"] or {} for r in runs["plain"]]
    row["rdmesh_wall"] = statistics.median(row["rdmesh_walls"])
    row["plain_wall"] = statistics.median(row["plain_walls"])
    row["rdmesh_cpu"] = median_or_none(row["rdmesh_cpus"])
    row["plain_cpu"] = median_or_none(row["plain_cpus"])
    row["ratio"] = row["rdmesh_wall"] / row["plain_wall"]
    row["load_seconds"] = median_of(ours, "load_seconds")
    row["mesh_seconds"] = median_of(ours, "seconds")
    row["plain_read_transfer"] = statistics.median(
        [p.get("read_seconds", 0.0) + p.get("transfer_seconds", 0.0) for p in plain])
    row["plain_mesh_seconds"] = median_of(plain, "mesh_seconds")
    row["load_ratio"] = (row["load_seconds"] / row["plain_read_transfer"]
                         if row["load_seconds"] is not None and row["plain_read_transfer"] > 0
                         else None)
    row["load_stages"] = load_stages(ours[-1])
    flats = [flat_stages(load_stages(o)) for o in ours]
    keys = [k for k in flats[-1] if all(k in f for f in flats)]
    row["load_stage_seconds"] = {k: statistics.median(f[k] for f in flats) for k in keys} or None
    faces = ours[-1].get("faces")
    row["faces"] = len(faces) if isinstance(faces, list) else faces
    row["plain_faces"] = plain[-1].get("faces")
    row["triangles"] = ours[-1].get("triangles")
    row["plain_triangles"] = plain[-1].get("triangles")
    row["faces_failed"] = ours[-1].get("faces_failed")
    requested = ours[-1].get("requested_deviation")
    row["deflection_ratio"] = (plain[-1].get("deflection") / requested
                               if requested and plain[-1].get("deflection") else None)
    return row


def median_or_none(values):
    return None if None in values or not values else statistics.median(values)


def median_of(reports, key):
    values = [r[key] for r in reports if isinstance(r.get(key), (int, float))]
    return statistics.median(values) if values else None


def fixed_cost(args, env, work_dir, rows, pairs=7):
    """`rdmesh --help` against `plain_runner` without arguments (process start and dynamic
    loading only), and `pairs` alternating pairs on the measured file nearest 50 faces."""
    out = {"pairs": pairs}
    helps = {"rdmesh": [], "plain": []}
    for r in range(pairs):
        for side in (("rdmesh", "plain") if r % 2 == 0 else ("plain", "rdmesh")):
            command = [args.rdmesh, "--help"] if side == "rdmesh" else [args.plain_runner]
            run = timed(command, env, ok_codes=(0, 2))
            helps[side].append((run["wall"], run["cpu"]))
    for side, samples in helps.items():
        out[side + "_start_wall"] = statistics.median(s[0] for s in samples)
        out[side + "_start_cpu"] = median_or_none([s[1] for s in samples])
    candidates = [r for r in rows if r.get("faces") and not r["errors"]]
    if candidates:
        small = min(candidates, key=lambda r: (abs(r["faces"] - 50), r["name"]))
        row = measure_file(small["file"], small["group"], args, work_dir, env, rounds=pairs)
        out["small"] = {k: row.get(k) for k in ("name", "faces", "rdmesh_wall", "plain_wall",
                                               "ratio", "rdmesh_cpu", "plain_cpu", "errors")}
        if row.get("plain_cpu") and row.get("rdmesh_cpu") is not None:
            out["small"]["cpu_ratio"] = row["rdmesh_cpu"] / row["plain_cpu"]
    return out


def core_scaling(args, env, work_dir, rows, rounds, min_faces=200):
    """The load on one core and on two (issue 34: at least 1.7x): every measured file with more
    than `min_faces` faces, `rounds` alternating runs of `taskset -c 0 rdmesh mesh ...` and the
    plain `rdmesh mesh ...`; per file the medians of load_seconds and of the whole wall."""
    out = {"min_faces": min_faces, "rounds": rounds, "files": []}
    if not shutil.which("taskset"):
        out["error"] = "taskset is not installed (util-linux)"
        return out
    for row in rows:
        if row["errors"] or not row.get("faces") or row["faces"] <= min_faces:
            continue
        target = work_dir / "cores.msh"
        base = rdmesh_command(args.rdmesh, row["file"], target)
        runs = {1: [], 2: []}
        for r in range(rounds):
            for cores in ((1, 2) if r % 2 == 0 else (2, 1)):
                command = (["taskset", "-c", "0"] if cores == 1 else []) + base
                runs[cores].append(timed(command, env))
                if target.exists():
                    target.unlink()
        entry = {"name": row["name"], "group": row["group"], "faces": row["faces"]}
        for cores, samples in runs.items():
            reports = [run["report"] for run in samples if run.get("report")]
            entry["load_%d" % cores] = median_of(reports, "load_seconds")
            entry["wall_%d" % cores] = statistics.median(run["wall"] for run in samples)
        if entry["load_1"] and entry["load_2"]:
            entry["load_speedup"] = entry["load_1"] / entry["load_2"]
        entry["wall_speedup"] = entry["wall_1"] / entry["wall_2"]
        out["files"].append(entry)
    return out


# -- the service ------------------------------------------------------------------------------

def start_daemon(rdmeshd, log_path, env):
    log = open(log_path, "w")
    proc = subprocess.Popen([rdmeshd, "--listen", "127.0.0.1:0"], stdout=log,
                            stderr=subprocess.STDOUT, env=env)
    end = time.monotonic() + 30
    while time.monotonic() < end:
        match = re.search(r"listening on (\S+):(\d+)", pathlib.Path(log_path).read_text())
        if match:
            return proc, "%s:%s" % match.groups()
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    raise RuntimeError("%s did not start:\n%s" % (rdmeshd, pathlib.Path(log_path).read_text()))


def service_files(rows, count):
    """`count` measured KiCad files spread evenly over the face counts (smallest to largest)."""
    ok = sorted((r for r in rows if r["group"] == "kicad" and not r["errors"] and r.get("faces")),
                key=lambda r: (r["faces"], r["name"]))
    if len(ok) <= count:
        return ok
    step = (len(ok) - 1) / (count - 1) if count > 1 else 0
    return [ok[round(i * step)] for i in range(count)]


def measure_service(args, env, work_dir, rows, rounds):
    """Per file and round, a fresh rdmeshd (so the model is parsed anew; no --cache-dir), warmed up
    by one upload and mesh of a tiny model, then the timed UploadModel and the first Mesh of the
    file, alternating with the plain runner."""
    if args.py_gen_dir:
        os.environ["RDMESH_PY_GEN_DIR"] = args.py_gen_dir
    sys.path.insert(0, str(REPO / "clients" / "python"))
    from rdmesh import Client  # noqa: E402 (needs the generated stubs)

    warm = REPO / "tests" / "data" / "cq_red_cube_blue_cylinder.step"
    out_rows = []
    for row in service_files(rows, args.service_files):
        path = row["file"]
        samples = {"upload": [], "mesh": [], "total": [], "plain": []}
        error = None
        for r in range(rounds):
            for side in (("service", "plain") if r % 2 == 0 else ("plain", "service")):
                if side == "plain":
                    out = work_dir / "service.plain.msh"
                    run = timed(plain_command(args.plain_runner, path, out), env)
                    if out.exists():
                        out.unlink()
                    samples["plain"].append(run["wall"])
                    continue
                proc, address = start_daemon(args.rdmeshd, work_dir / "rdmeshd.log", env)
                try:
                    with Client(address) as client:
                        client.mesh(client.upload(warm), max_deviation_rel=REL)
                        start = time.perf_counter()
                        info = client.upload(path)
                        uploaded = time.perf_counter()
                        result = client.mesh(info, max_deviation_rel=REL)
                        done = time.perf_counter()
                    samples["upload"].append(uploaded - start)
                    samples["mesh"].append(done - uploaded)
                    samples["total"].append(done - start)
                    row_triangles = int(result.summary.triangles)
                except Exception as e:  # noqa: BLE001 (a failed call is a row, not the end)
                    error = str(e).splitlines()[0][:200]
                finally:
                    proc.terminate()
                    proc.wait()
        entry = {"name": row["name"], "faces": row["faces"], "error": error}
        if not error:
            entry.update({k: statistics.median(v) for k, v in samples.items()})
            entry["ratio"] = entry["total"] / entry["plain"]
            entry["triangles"] = row_triangles
        out_rows.append(entry)
        print("service %s: %s" % (row["name"], error or "%.3f s vs %.3f s (%.2fx)" % (
            entry["total"], entry["plain"], entry["ratio"])), file=sys.stderr)
    return out_rows


# -- summary and markdown ---------------------------------------------------------------------

def geomean(values):
    values = [v for v in values if v is not None and v > 0]
    if not values:
        return None
    return math.exp(sum(math.log(v) for v in values) / len(values))


def summarize(rows):
    ok = [r for r in rows if not r["errors"]]
    summary = {"files": len(rows), "measured": len(ok), "failed": [
        {"name": r["name"], "errors": r["errors"]} for r in rows if r["errors"]]}
    for group in ("kicad", "corpus", "all"):
        members = [r for r in ok if group == "all" or r["group"] == group]
        summary[group] = {
            "files": len(members),
            "ratio_geomean": geomean([r["ratio"] for r in members]),
            "load_ratio_geomean": geomean([r.get("load_ratio") for r in members]),
            "cpu_ratio_geomean": geomean([r["rdmesh_cpu"] / r["plain_cpu"] for r in members
                                          if r.get("plain_cpu")]),
        }
    if ok:
        worst = max(ok, key=lambda r: r["ratio"])
        summary["max_ratio"] = {"name": worst["name"], "ratio": worst["ratio"]}
        summary["above_1"] = [{"name": r["name"], "group": r["group"], "ratio": r["ratio"]}
                              for r in sorted(ok, key=lambda r: -r["ratio"]) if r["ratio"] > 1.0]
        summary["load_share"] = (sum(r["load_seconds"] or 0 for r in ok)
                                 / sum(r["rdmesh_wall"] for r in ok))
        summary["deflection_ratio_min"] = min(
            (r["deflection_ratio"] for r in ok if r.get("deflection_ratio")), default=None)
        summary["load_stages_reported"] = any(r.get("load_stages") for r in ok)
        totals = {}
        for r in ok:
            for k, v in (r.get("load_stage_seconds") or {}).items():
                totals[k] = totals.get(k, 0.0) + v
        summary["load_stage_totals"] = totals
        summary["load_seconds_total"] = sum(r["load_seconds"] or 0 for r in ok)
    return summary


def fmt(value, spec="%.3f"):
    return "-" if value is None else spec % value


def render(results):
    meta, summary, rows = results["meta"], results["summary"], results["rows"]
    L = ["# Parse: a STEP file to a mesh on disk, rdmesh against OCCT's plain read + BRepMesh", ""]
    L.append("Issue 34's end-to-end table, written by `bench/performance/parse_e2e.py` "
             "(its docstring says how it measures). Made with:")
    L += ["", "```", meta["command"], "```", ""]
    L.append("- date: %s; commit `%s`%s%s" % (
        meta["date"], meta["commit"], " (with uncommitted changes in the tree)"
        if meta.get("dirty") else "", "; the rdmesh binary was built at %s from the working "
        "tree" % meta["rdmesh_built"] if meta.get("rdmesh_built") else ""))
    L.append("- machine: %s, %d cores (nproc), %s" % (meta["cpu"], meta["nproc"], meta["os"]))
    L.append("- load average before: %s; after: %s. The machine is shared: other work was "
             "running during the measurement (the load average above the core count says how "
             "much), so single wall times are noisy; each figure is a median of %d alternating "
             "runs, and the CPU-time ratio (the child's user + system) is given beside the "
             "wall-time one." % (meta["load_before"], meta["load_after"], meta["rounds"]))
    L.append("- rdmesh: `%s` (`mesh FILE -o OUT.msh --max-deviation-rel 1e-3 --json`); plain "
             "runner: `%s` (`FILE OUT.msh`: STEPControl_Reader ReadFile + TransferRoots + "
             "OneShape, BRepMesh_IncrementalMesh at 1e-3 of the BRepBndLib::Add box's diagonal and "
             "0.5 rad in parallel, MSH 4.1 write). Outputs in `%s`." % (
                 meta["rdmesh"], meta["plain_runner"], meta["work_dir"]))
    L.append("- environment of the runs: %s" % (
        ", ".join("`%s`" % e for e in meta["env"]) if meta.get("env") else
        "the caller's, without %s (so rdmesh reads with its default reader, keeps no model "
        "store and runs in a child process), and with %s for both programs unless the caller "
        "set it" % (", ".join(DROPPED_ENV), ", ".join("`%s=%s`" % kv for kv in SHARED_ENV.items()))))
    L.append("- files: %s" % meta["files_note"])
    L += ["", "## Summary", ""]
    L.append("Ratio = rdmesh's median wall time / the plain runner's, per file; the issue's goal "
             "is a geometric mean of at most 0.5x and no file above 1.0x.")
    L += ["", "| files | n | wall ratio (geo. mean) | CPU ratio (geo. mean) "
          "| load / plain read+transfer (geo. mean) |", "|---|---:|---:|---:|---:|"]
    for group in ("kicad", "corpus", "all"):
        g = summary.get(group, {})
        L.append("| %s | %d | %s | %s | %s |" % (
            group, g.get("files", 0), fmt(g.get("ratio_geomean"), "%.2fx"),
            fmt(g.get("cpu_ratio_geomean"), "%.2fx"), fmt(g.get("load_ratio_geomean"), "%.2fx")))
    L.append("")
    if summary.get("max_ratio"):
        L.append("- max ratio: %.2fx (%s)" % (summary["max_ratio"]["ratio"],
                                              summary["max_ratio"]["name"]))
        above = summary.get("above_1", [])
        L.append("- files above 1.0x: %d of %d%s" % (
            len(above), summary["measured"], (": " + ", ".join(
                "%s %.2fx" % (a["name"], a["ratio"]) for a in above[:40])
                + (" ..." if len(above) > 40 else "")) if above else ""))
        L.append("- rdmesh's load_seconds is %.0f%% of its whole-process wall time (sums over "
                 "the measured files)" % (100 * summary["load_share"]))
        totals = summary.get("load_stage_totals")
        if totals:
            L.append("- rdmesh's load stages (its --json), summed over the files, against the sum "
                     "of load_seconds (%.2f s): %s" % (summary["load_seconds_total"], ", ".join(
                         "%s %.2f s (%.0f%%)" % (k, v, 100 * v / summary["load_seconds_total"])
                         for k, v in totals.items())))
        else:
            L.append("- load stages in rdmesh's --json: none reported (only load_seconds)")
        if summary.get("deflection_ratio_min") is not None:
            L.append("- the plain runner's deflection / rdmesh's requested deviation: at least "
                     "%.3f on every file (its box is OCCT's loose one, so BRepMesh is never asked "
                     "for a finer mesh than rdmesh)" % summary["deflection_ratio_min"])
    if summary.get("failed"):
        L.append("- not measured (a side failed): " + "; ".join(
            "%s (%s)" % (f["name"], ", ".join("%s: %s" % kv for kv in f["errors"].items()))
            for f in summary["failed"]))
    fixed = results.get("fixed")
    if fixed:
        L += ["", "### Fixed cost per process", ""]
        L.append("Medians of %d alternating runs." % fixed["pairs"])
        L += ["", "| | rdmesh | plain runner | ratio |", "|---|---:|---:|---:|"]
        L.append("| start-up wall s (`rdmesh --help` / `plain_runner` usage) "
                 "| %.3f | %.3f | %.2fx |" % (fixed["rdmesh_start_wall"], fixed["plain_start_wall"],
                    fixed["rdmesh_start_wall"] / fixed["plain_start_wall"]))
        L.append("| start-up CPU s | %s | %s | %s |" % (
            fmt(fixed["rdmesh_start_cpu"]), fmt(fixed["plain_start_cpu"]),
            fmt(fixed["rdmesh_start_cpu"] / fixed["plain_start_cpu"]
                if fixed["plain_start_cpu"] else None, "%.2fx")))
        small = fixed.get("small")
        if small and not small.get("errors"):
            L.append("| %s (%s faces), wall s | %.3f | %.3f | %.2fx |" % (
                small["name"], small["faces"], small["rdmesh_wall"], small["plain_wall"],
                small["ratio"]))
            L.append("| the same, CPU s | %s | %s | %s |" % (
                fmt(small["rdmesh_cpu"]), fmt(small["plain_cpu"]),
                fmt(small.get("cpu_ratio"), "%.2fx")))
    cores = results.get("cores")
    if cores:
        L += ["", "### The load on one core and on two", ""]
        if cores.get("error"):
            L.append("Not measured: %s." % cores["error"])
        else:
            files = cores["files"]
            L.append("Every measured file with more than %d faces: %d alternating runs of "
                     "`taskset -c 0 rdmesh mesh ...` (one core) and `rdmesh mesh ...` (both); "
                     "medians. The issue asks for a load at least 1.7x faster on two cores."
                     % (cores["min_faces"], cores["rounds"]))
            L += ["", "| files | n | load 1 core / 2 cores (geo. mean) | whole wall (geo. mean) "
                  "| lowest load speed-up |", "|---|---:|---:|---:|---|"]
            low = min(files, key=lambda f: f.get("load_speedup") or 99, default=None)
            L.append("| > %d faces | %d | %s | %s | %s |" % (
                cores["min_faces"], len(files),
                fmt(geomean([f.get("load_speedup") for f in files]), "%.2fx"),
                fmt(geomean([f.get("wall_speedup") for f in files]), "%.2fx"),
                "%s %.2fx" % (low["name"], low["load_speedup"])
                if low and low.get("load_speedup") else "-"))
            L += ["", "| file | faces | load s, 1 core | load s, 2 cores | speed-up | wall "
                  "speed-up |", "|---|---:|---:|---:|---:|---:|"]
            for f in files:
                L.append("| %s | %s | %s | %s | %s | %s |" % (
                    f["name"], f["faces"], fmt(f.get("load_1")), fmt(f.get("load_2")),
                    fmt(f.get("load_speedup"), "%.2fx"), fmt(f.get("wall_speedup"), "%.2fx")))
    service = results.get("service")
    if service:
        L += ["", "## The service: first Mesh after UploadModel", ""]
        L.append("Per file and round a fresh `rdmeshd --listen 127.0.0.1:0` (defaults: no "
                 "--cache-dir), warmed up with one upload and mesh of a 9-face model, then the "
                 "timed `Client.upload(FILE)` (the worker parses it) and the first "
                 "`Client.mesh(model, max_deviation_rel=1e-3)` (the mesh arrives in the Python "
                 "client's memory; no file is written), against the plain runner's whole process; "
                 "medians of %d alternating rounds." % meta.get("service_rounds", meta["rounds"])
                 + (" Here %s." % meta["service_note"] if meta.get("service_note") else ""))
        L += ["", "| file | faces | upload s | first Mesh s | upload + Mesh s | plain s | ratio |",
              "|---|---:|---:|---:|---:|---:|---:|"]
        for s in service:
            if s.get("error"):
                L.append("| %s | %s | failed: %s | | | | |" % (s["name"], s["faces"], s["error"]))
            else:
                L.append("| %s | %s | %.3f | %.3f | %.3f | %.3f | %.2fx |" % (
                    s["name"], s["faces"], s["upload"], s["mesh"], s["total"], s["plain"],
                    s["ratio"]))
        L.append("")
        L.append("Geometric mean of the ratio: %s" % fmt(
            geomean([s.get("ratio") for s in service]), "%.2fx"))
    L += ["", "## Per file", ""]
    L.append("Wall seconds are medians of %d; `load` is rdmesh's load_seconds, `read+tr` the "
             "plain runner's read + transfer seconds; `mesh` and triangles: rdmesh (its "
             "`seconds`) / BRepMesh (the runner's mesh_seconds); a failed face is marked."
             % meta["rounds"])
    stages = any(r.get("load_stage_seconds") for r in rows)
    head = ("| group | file | faces | rdmesh s | plain s | ratio | CPU ratio | load s | read+tr s "
            "| load ratio | mesh s | triangles |" + (" load stages |" if stages else ""))
    L += ["", head, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
          + ("---|" if stages else "")]
    for r in sorted(rows, key=lambda r: (r["group"] != "kicad", r["folder"], r["name"])):
        name = ("%s/%s" % (r["folder"], r["name"])) if r["group"] == "kicad" else r["name"]
        if r["errors"]:
            L.append("| %s | %s | failed: %s |" % (r["group"], name, "; ".join(
                "%s: %s" % kv for kv in r["errors"].items())))
            continue
        cells = [r["group"], name, str(r.get("faces")), "%.3f" % r["rdmesh_wall"],
                 "%.3f" % r["plain_wall"], "%.2fx" % r["ratio"],
                 fmt(r["rdmesh_cpu"] / r["plain_cpu"] if r.get("plain_cpu") else None, "%.2fx"),
                 fmt(r.get("load_seconds")), fmt(r.get("plain_read_transfer")),
                 fmt(r.get("load_ratio"), "%.2fx"),
                 "%s / %s" % (fmt(r.get("mesh_seconds")), fmt(r.get("plain_mesh_seconds"))),
                 "%s / %s%s" % (r.get("triangles"), r.get("plain_triangles"),
                                " (%s faces failed)" % r["faces_failed"]
                                if r.get("faces_failed") else "")]
        if stages:
            cells.append(", ".join("%s %.3f" % kv for kv in r["load_stage_seconds"].items())
                         if r.get("load_stage_seconds") else "-")
        L.append("| " + " | ".join(cells) + " |")
    return "\n".join(L) + "\n"


# -- main -------------------------------------------------------------------------------------

def machine():
    cpu = "unknown CPU"
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return cpu, os.cpu_count(), "%s %s" % (platform.system(), platform.release())


def load_average():
    return "%.2f %.2f %.2f" % os.getloadavg()


def git(*args):
    try:
        return subprocess.run(["git", "-C", str(REPO), *args], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True).stdout.strip()
    except OSError:
        return ""


def parser():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rdmesh", default=str(REPO / "build" / "bin" / "rdmesh"))
    p.add_argument("--plain-runner", default=str(REPO / "build" / "bin" / "plain_runner"))
    p.add_argument("--rdmeshd", default=None, help="default: rdmeshd beside --rdmesh")
    p.add_argument("--rdmesh-env", action="append", default=[], metavar="KEY=VALUE",
                   help="set for every run, e.g. RDMESH_STEP_READER=rdmesh (the runs otherwise "
                        "drop %s from the environment)" % ", ".join(DROPPED_ENV))
    p.add_argument("--kicad-root", help="an extracted kicad-packages3d 3dmodels folder")
    p.add_argument("--kicad-dir", default="~/.cache/rdmesh-bench",
                   help="where kicad-packages3d is downloaded and extracted without --kicad-root")
    p.add_argument("--no-kicad", action="store_true", help="the corpus only")
    p.add_argument("--corpus", default=str(CORPUS))
    p.add_argument("--seed", default="34")
    p.add_argument("--per-folder", type=int, default=2)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--jobs", type=int, default=1, help="files measured at once (1: timing)")
    p.add_argument("--limit", type=int, default=0, help="the first N files only (quick runs)")
    p.add_argument("--timeout", type=float, default=900.0, help="seconds per process")
    p.add_argument("--service", action="store_true", help="also time rdmeshd's first Mesh")
    p.add_argument("--service-files", type=int, default=10)
    p.add_argument("--service-into", metavar="FILE",
                   help="time rdmeshd's first Mesh alone, on the files of an earlier --json FILE, "
                        "add it to that file and re-render --out")
    p.add_argument("--py-gen-dir", default=os.environ.get("RDMESH_PY_GEN_DIR"),
                   help="the Python client's generated stubs (default: the client's _gen)")
    p.add_argument("--out", default=str(REPO / "bench" / "PARSE.md"))
    p.add_argument("--json", dest="json_out", help="every measurement as JSON")
    p.add_argument("--results-only", metavar="FILE", help="re-render --out from a --json file")
    return p


def service_into(args):
    """The service's timing alone (the first Mesh after UploadModel, with `args.rdmeshd`), added
    to an earlier run's results, whose files it picks; the markdown rendered again."""
    path = pathlib.Path(args.service_into)
    results = json.loads(path.read_text())
    shm = pathlib.Path("/dev/shm")
    work_dir = pathlib.Path(tempfile.mkdtemp(prefix="parse-e2e-",
                                             dir=str(shm) if shm.is_dir() else None))
    try:
        results["service"] = measure_service(args, child_env(args.rdmesh_env), work_dir,
                                             results["rows"], args.rounds)
    finally:
        shutil.rmtree(work_dir, ignore_errors=True)
    results["meta"]["service_rounds"] = args.rounds
    results["meta"]["service_note"] = (
        "the service measured afterwards (%s, %s at commit %s, load average before %s)" % (
            datetime.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z"), args.rdmeshd,
            git("rev-parse", "--short=10", "HEAD"), load_average()))
    path.write_text(json.dumps(results, indent=1))
    pathlib.Path(args.out).write_text(render(results))
    print("wrote %s and %s" % (path, args.out))
    return 0


def main(argv=None):
    global SERIAL, TIMEOUT
    args = parser().parse_args(argv)
    SERIAL, TIMEOUT = args.jobs <= 1, args.timeout
    if args.results_only:
        results = json.loads(pathlib.Path(args.results_only).read_text())
        pathlib.Path(args.out).write_text(render(results))
        print("wrote %s" % args.out)
        return 0
    args.rdmesh = os.path.abspath(args.rdmesh)
    args.plain_runner = os.path.abspath(args.plain_runner)
    args.rdmeshd = os.path.abspath(args.rdmeshd or os.path.join(os.path.dirname(args.rdmesh),
                                                                "rdmeshd"))
    if args.service_into:
        return service_into(args)
    for binary in [args.rdmesh, args.plain_runner] + ([args.rdmeshd] if args.service else []):
        if not os.access(binary, os.X_OK):
            raise SystemExit("no executable at %s" % binary)
    # rdmesh runs rdmesh-local beside it, which loads OCCT's STEP reader (its fallback) and
    # OCCT's document framework (assemblies) from modules beside it: a copied binary needs them
    # copied too, or the files that need them fail instead of being timed.
    for module in ("rdmesh-local", "rdmesh_occt_readers.so", "rdmesh_occt_xcaf.so"):
        module = os.path.join(os.path.dirname(args.rdmesh), module)
        if not os.path.isfile(module):
            print("parse_e2e: warning: no %s beside rdmesh: the files that need it will fail"
                  % module, file=sys.stderr)

    files = []
    notes = []
    if not args.no_kicad:
        root = pathlib.Path(args.kicad_root) if args.kicad_root else fetch_kicad(args.kicad_dir)
        sample = kicad_sample(root, args.seed, args.per_folder)
        folders = len({p.parent for p in sample})
        files += [(p, "kicad") for p in sample]
        notes.append("%d KiCad library files (%s): %d per folder (all of a folder that holds "
                     "fewer) of %d folders, seed %s" % (len(sample), root, args.per_folder,
                                                        folders, args.seed))
    corpus = corpus_files(args.corpus)
    files += [(p, "corpus") for p in corpus]
    notes.append("%d corpus files (%s)" % (len(corpus), args.corpus))
    if args.limit:
        files = files[:args.limit]
        notes.append("limited to the first %d" % args.limit)

    shm = pathlib.Path("/dev/shm")
    work_dir = pathlib.Path(tempfile.mkdtemp(prefix="parse-e2e-",
                                             dir=str(shm) if shm.is_dir() else None))
    env = child_env(args.rdmesh_env)
    cpu, nproc, os_name = machine()
    meta = {"command": " ".join(shlex.quote(a) for a in ["/usr/bin/python3",
                                                           os.path.relpath(__file__, REPO)]
                                + (argv if argv is not None else sys.argv[1:])),
            "date": datetime.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z"),
            "commit": git("rev-parse", "HEAD"), "dirty": bool(git("status", "--porcelain",
                                                                  "--untracked-files=no")),
            "cpu": cpu, "nproc": nproc, "os": os_name, "rounds": args.rounds,
            "rdmesh": args.rdmesh, "plain_runner": args.plain_runner,
            "rdmesh_built": datetime.datetime.fromtimestamp(os.path.getmtime(
                args.rdmesh)).astimezone().strftime("%Y-%m-%d %H:%M %Z"),
            "work_dir": "tmpfs (/dev/shm)" if str(work_dir).startswith("/dev/shm") else
            str(work_dir.parent), "files_note": "; ".join(notes),
            "load_before": load_average(), "env": args.rdmesh_env}
    results = {"meta": meta}
    try:
        rows = []

        def one(item):
            path, group = item
            return measure_file(path, group, args, work_dir, env, args.rounds)

        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            for i, row in enumerate(pool.map(one, files)):
                rows.append(row)
                print("[%d/%d] %s: %s" % (i + 1, len(files), row["name"], (
                    "failed %s" % row["errors"]) if row["errors"] else "%.3f s vs %.3f s (%.2fx)"
                    % (row["rdmesh_wall"], row["plain_wall"], row["ratio"])), file=sys.stderr)
        results["rows"] = rows
        results["summary"] = summarize(rows)
        results["fixed"] = fixed_cost(args, env, work_dir, rows)
        results["cores"] = core_scaling(args, env, work_dir, rows, args.rounds)
        if args.service:
            results["service"] = measure_service(args, env, work_dir, rows, args.rounds)
    finally:
        shutil.rmtree(work_dir, ignore_errors=True)
    meta["load_after"] = load_average()
    if args.json_out:
        pathlib.Path(args.json_out).write_text(json.dumps(results, indent=1))
    pathlib.Path(args.out).write_text(render(results))
    print("wrote %s" % args.out, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
