#!/usr/bin/env python3
"""Meshing time against output triangles over the corpus, on log-log axes (issue 13: "cost per
output triangle should not grow with model size ... a slope near 1 is the aim").

    /usr/bin/python3 bench/performance/cost_scaling.py [--tolerances 1e-3,1e-4] [--runs 1] [--time cpu]
        [--rdmesh build/bin/rdmesh] [--timeout 300] [--out bench/performance/cost_scaling] [MODEL ...]

Meshes every model of /work/shared/corpus (or the models given) at each relative tolerance with
`rdmesh mesh MODEL -o OUT.msh --max-deviation-rel TOL --threads 1 --json -q`, one run at a time.
The time plotted is the meshing CPU time (`mesh_cpu_seconds` of the --json report: user + system
of the process while meshing, loading and writing left out), or with `--time wall` the meshing
wall time (`seconds`). On a shared machine the wall time counts the waits for other processes,
the CPU time does not. With `--runs N` each point is the median of N runs (rounds over the whole
list, so a burst of load hits one round, not one model).

A model that fails (exit code other than 0, no JSON, or a face that failed to mesh) is listed with
its reason in the report and in the JSON, never left out silently; a run with failed faces is
still plotted (its triangles are what the user gets) and marked.

Fits log10(time) = a + b log10(triangles) by least squares per tolerance and over all points,
prints the slopes b, and lists the outliers: the points more than `--outlier` times (default 2)
above their tolerance's line. The machine's load average (1 minute) is read before every run and
summarised.

Writes OUT.png (the plot), OUT.json (points, fits, outliers, failures, load, commands) and OUT.csv
(one row per model and tolerance).
"""

import argparse
import csv
import hashlib
import json
import math
import os
import pathlib
import platform
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORPUS = pathlib.Path("/work/shared/corpus")
MODEL_SUFFIXES = {".step", ".stp", ".iges", ".igs", ".brep"}


def corpus_models():
    return sorted(p for p in CORPUS.iterdir() if p.suffix.lower() in MODEL_SUFFIXES)


def run_mesh(rdmesh, model, tol, timeout, out):
    """One `rdmesh mesh MODEL -o OUT --max-deviation-rel TOL --threads 1 --json -q` run: its --json
    report, or a string saying why there is none. `tol` as the command line takes it."""
    command = [rdmesh, "mesh", str(model), "-o", str(out), "--max-deviation-rel", tol,
               "--threads", "1", "--json", "-q", "--timeout", str(timeout)]
    try:
        proc = subprocess.run(command, capture_output=True, text=True, timeout=timeout + 30)
    except subprocess.TimeoutExpired:
        return "killed after %g s" % (timeout + 30)
    lines = proc.stdout.strip().splitlines()
    try:
        report = json.loads(lines[-1]) if lines else {}
    except json.JSONDecodeError:
        report = {}
    if proc.returncode != 0 or "triangles" not in report:
        message = report.get("error", {}).get("message") if isinstance(report.get("error"),
                                                                        dict) else None
        return "exit %d: %s" % (proc.returncode, message or proc.stderr.strip()[-300:])
    return report


def run_once(rdmesh, model, tol, timeout, out_dir):
    """One meshing run: a dict with the --json fields this script uses, or an 'error'."""
    load = os.getloadavg()[0]
    start = time.perf_counter()
    report = run_mesh(rdmesh, model, repr(tol), timeout, pathlib.Path(out_dir) / "mesh.msh")
    wall = time.perf_counter() - start
    if isinstance(report, str):
        return {"error": report, "load1": load}
    faces = report.get("faces", [])
    return {
        "triangles": report["triangles"],
        "seconds": report["seconds"],
        "mesh_cpu_seconds": report["mesh_cpu_seconds"],
        "edge_seconds": report["edge_seconds"],
        "face_seconds": report["face_seconds"],
        "load_seconds": report["load_seconds"],
        "max_face_seconds": max((f["seconds"] for f in faces), default=0.0),
        "faces": len(faces),
        "faces_failed": report["faces_failed"],
        "process_wall": wall,
        "load1": load,
    }


def fit(points):
    """Least squares of log10(y) on log10(x): (intercept, slope, r2)."""
    xs = [math.log10(x) for x, _ in points]
    ys = [math.log10(y) for _, y in points]
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    syy = sum((y - my) ** 2 for y in ys)
    slope = sxy / sxx
    intercept = my - slope * mx
    r2 = (sxy * sxy) / (sxx * syy) if syy > 0 else 1.0
    return intercept, slope, r2


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="*", help="model files (default: the whole corpus)")
    parser.add_argument("--tolerances", default="1e-3,1e-4")
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--time", choices=["cpu", "wall"], default="cpu")
    parser.add_argument("--rdmesh", default=str(ROOT / "build" / "bin" / "rdmesh"))
    parser.add_argument("--timeout", type=float, default=300)
    parser.add_argument("--outlier", type=float, default=2.0)
    parser.add_argument("--out", default=str(ROOT / "bench" / "performance" / "cost_scaling"))
    args = parser.parse_args()

    models = [pathlib.Path(m) for m in args.models] or corpus_models()
    tolerances = [float(t) for t in args.tolerances.split(",")]
    field = "mesh_cpu_seconds" if args.time == "cpu" else "seconds"
    # The launcher and the program it runs (rdmesh-local beside it), so that the cache key moves
    # with the engine.
    digest = hashlib.sha256(pathlib.Path(args.rdmesh).read_bytes())
    local = pathlib.Path(args.rdmesh).with_name("rdmesh-local")
    if local.is_file():
        digest.update(local.read_bytes())
    sha = digest.hexdigest()[:16]
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()

    runs = {}  # (model name, tol) -> [run dicts]
    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    with tempfile.TemporaryDirectory(prefix="cost_scaling_") as tmp:
        for r in range(args.runs):
            for model in models:
                for tol in tolerances:
                    result = run_once(args.rdmesh, model, tol, args.timeout, tmp)
                    runs.setdefault((model.name, tol), []).append(result)
                    shown = ("%d triangles, %s %.3f s" % (result["triangles"], field,
                                                          result[field])
                             if "error" not in result else result["error"])
                    print("[%d/%d] %s %g: %s (load %.2f)" % (r + 1, args.runs, model.name, tol,
                                                             shown, result["load1"]),
                          file=sys.stderr, flush=True)
    finished = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())

    points, failures = [], []
    for (name, tol), results in runs.items():
        good = [x for x in results if "error" not in x]
        if len(good) < len(results):
            failures.append({"model": name, "tolerance": tol,
                             "errors": sorted({x["error"] for x in results if "error" in x})})
        if not good:
            continue
        point = {"model": name, "tolerance": tol, "runs": len(good)}
        for key in ("triangles", "faces", "faces_failed"):
            point[key] = good[0][key]
        for key in ("seconds", "mesh_cpu_seconds", "edge_seconds", "face_seconds",
                    "load_seconds", "max_face_seconds", "process_wall"):
            point[key] = statistics.median(x[key] for x in good)
        if point["faces_failed"]:
            failures.append({"model": name, "tolerance": tol,
                             "errors": ["%d of %d faces failed" % (point["faces_failed"],
                                                                   point["faces"])]})
        points.append(point)

    fits, outliers = {}, []
    for tol in tolerances + [None]:
        sel = [p for p in points if (tol is None or p["tolerance"] == tol)
               and p["triangles"] > 0 and p[field] > 0]
        if len(sel) < 3:
            continue
        a, b, r2 = fit([(p["triangles"], p[field]) for p in sel])
        key = "all" if tol is None else repr(tol)
        fits[key] = {"intercept": a, "slope": b, "r2": r2, "points": len(sel),
                     "us_per_triangle_at_10k": 1e6 * 10 ** (a + b * 4) / 1e4}
        if tol is None:
            continue
        for p in sel:
            ratio = p[field] / 10 ** (a + b * math.log10(p["triangles"]))
            p["above_fit"] = ratio
            if ratio > args.outlier:
                outliers.append({"model": p["model"], "tolerance": tol, "triangles":
                                 p["triangles"], field: p[field], "above_fit": ratio})
    outliers.sort(key=lambda o: -o["above_fit"])
    loads = [x["load1"] for results in runs.values() for x in results]
    load = {"min": min(loads), "median": statistics.median(loads), "max": max(loads)}

    command = " ".join(["/usr/bin/python3", "bench/performance/cost_scaling.py"] + sys.argv[1:])
    summary = {
        "command": command,
        "per_run": "%s mesh MODEL -o OUT.msh --max-deviation-rel TOL --threads 1 --json -q "
                   "--timeout %g" % (args.rdmesh, args.timeout),
        "time": field, "commit": commit, "rdmesh_sha256_16": sha, "host": platform.node(),
        "cpus": os.cpu_count(), "started": started, "finished": finished, "load1": load,
        "fits": fits, "outliers": outliers, "failures": failures, "points": points,
    }
    out = pathlib.Path(args.out)
    out.with_suffix(".json").write_text(json.dumps(summary, indent=1) + "\n")
    with open(out.with_suffix(".csv"), "w", newline="") as f:
        keys = ["model", "tolerance", "triangles", "mesh_cpu_seconds", "seconds", "edge_seconds",
                "face_seconds", "max_face_seconds", "load_seconds", "faces", "faces_failed",
                "runs", "above_fit"]
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        for p in sorted(points, key=lambda p: (p["tolerance"], p["triangles"])):
            w.writerow(p)
    plot(points, fits, tolerances, field, outliers, load, commit, out.with_suffix(".png"))

    print("time: %s; load average (1 min) %.2f-%.2f, median %.2f; %d points, %d failures"
          % (field, load["min"], load["max"], load["median"], len(points), len(failures)))
    for key, f in fits.items():
        print("slope %-6s %.3f (r2 %.3f, n=%d, %.1f us/triangle at 10k triangles)"
              % (key, f["slope"], f["r2"], f["points"], f["us_per_triangle_at_10k"]))
    for o in outliers:
        print("outlier %s %g: %d triangles, %.3f s, %.1fx the fit"
              % (o["model"], o["tolerance"], o["triangles"], o[field], o["above_fit"]))
    for f in failures:
        print("failure %s %g: %s" % (f["model"], f["tolerance"], "; ".join(f["errors"])))


def plot(points, fits, tolerances, field, outliers, load, commit, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 6), dpi=110)
    styles = ["o", "s", "^", "D", "v"]
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]
    for i, tol in enumerate(tolerances):
        sel = [p for p in points if p["tolerance"] == tol and p["triangles"] > 0 and p[field] > 0]
        if not sel:
            continue
        xs = [p["triangles"] for p in sel]
        label = "%g of the diagonal" % tol
        f = fits.get(repr(tol))
        if f:
            label += ": slope %.2f" % f["slope"]
        ax.scatter(xs, [p[field] for p in sel], marker=styles[i % 5], color=colors[i % 5],
                   label=label, alpha=0.75, s=22)
        failed = [p for p in sel if p["faces_failed"]]
        if failed:
            ax.scatter([p["triangles"] for p in failed], [p[field] for p in failed],
                       marker="x", color="black", s=30)
        if f:
            lo, hi = min(xs), max(xs)
            ax.plot([lo, hi], [10 ** (f["intercept"] + f["slope"] * math.log10(x))
                               for x in (lo, hi)], color=colors[i % 5], lw=1)
    if "all" in fits:
        # Slope 1 through the centre of all points: constant cost per triangle.
        allp = [p for p in points if p["triangles"] > 0 and p[field] > 0]
        mx = statistics.mean(math.log10(p["triangles"]) for p in allp)
        my = statistics.mean(math.log10(p[field]) for p in allp)
        lo = min(p["triangles"] for p in allp)
        hi = max(p["triangles"] for p in allp)
        ax.plot([lo, hi], [10 ** (my + math.log10(x) - mx) for x in (lo, hi)], "k--", lw=0.8,
                label="slope 1 (constant time per triangle)")
    for o in outliers:
        ax.annotate(o["model"].rsplit(".", 1)[0], (o["triangles"], o[field]), fontsize=6,
                    xytext=(3, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("output triangles")
    ax.set_ylabel("meshing %s seconds, --threads 1" % ("CPU" if field == "mesh_cpu_seconds"
                                                         else "wall"))
    ax.set_title("rdmesh %s over the corpus (x: a face failed); load avg %.1f-%.1f"
                 % (commit, load["min"], load["max"]), fontsize=9)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)


if __name__ == "__main__":
    main()
