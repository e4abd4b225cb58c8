#!/usr/bin/env python3
"""Cost per output triangle face by face (issue 13: "cost per output triangle should not grow
with model size").

    /usr/bin/python3 bench/performance/face_cost.py [--tolerances 1e-3,1e-4,3e-5] [--min-triangles 20]
        [--rdmesh build/bin/rdmesh] [--timeout 300] [--out OUT.json] [MODEL ...]

Meshes every model of /work/shared/corpus (or the models given) once per relative tolerance with
`rdmesh mesh MODEL -o OUT.msh --max-deviation-rel TOL --threads 1 --json -q`, and keeps each
face's triangles and seconds (`faces[].seconds`: that face's own meshing wall time, one thread).
Prints, per tolerance and kind of surface: the faces, their seconds, microseconds per triangle,
and the slope of log(seconds) on log(triangles) over the faces with at least --min-triangles.
Then, between each two consecutive tolerances, the slope of every face on its own: log(s2 / s1)
/ log(n2 / n1), for the faces meshed ok at both with at least --min-triangles at the coarser and
1.5x as many at the finer; the median per kind of surface, and the mean weighted by the seconds
at the finer tolerance. A face's own slope near 1 means it costs the same per triangle when it
gets more of them: a slope of the whole corpus above 1 then comes from which surfaces the larger
models have, not from work that grows faster than the mesh. Models that fail are listed.
"""

import argparse
import collections
import json
import math
import pathlib
import statistics
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from cost_scaling import ROOT, corpus_models, fit, run_mesh  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="*", help="model files (default: the whole corpus)")
    parser.add_argument("--tolerances", default="1e-3,1e-4,3e-5")
    parser.add_argument("--min-triangles", type=int, default=20)
    parser.add_argument("--rdmesh", default=str(ROOT / "build" / "bin" / "rdmesh"))
    parser.add_argument("--timeout", type=float, default=300)
    parser.add_argument("--out", help="write every face's figures here (JSON)")
    args = parser.parse_args()

    models = [pathlib.Path(m) for m in args.models] or corpus_models()
    tolerances = args.tolerances.split(",")
    faces = {}  # (tolerance, model name, face id) -> face report
    failures = []
    with tempfile.TemporaryDirectory(prefix="face_cost_") as tmp:
        for tol in tolerances:
            for model in models:
                got = run_mesh(args.rdmesh, model, tol, args.timeout, pathlib.Path(tmp) / "m.msh")
                if isinstance(got, str):
                    failures.append((model.name, tol, got))
                    continue
                for f in got["faces"]:
                    if f["status"] == "ok" and f["triangles"] > 0 and f["seconds"] > 0:
                        faces[(tol, model.name, f["id"])] = f

    print("## Faces by kind of surface, one thread\n")
    print("| tol | surface | faces | seconds | µs / triangle | slope (faces >= %d triangles) |"
          % args.min_triangles)
    print("|---|---|---:|---:|---:|---|")
    for tol in tolerances:
        by_kind = collections.defaultdict(list)
        for (t, _, _), f in faces.items():
            if t == tol:
                by_kind[f["surface_type"]].append(f)
        for kind, fs in sorted(by_kind.items(), key=lambda kv: -sum(f["seconds"] for f in kv[1])):
            seconds = sum(f["seconds"] for f in fs)
            triangles = sum(f["triangles"] for f in fs)
            big = [(f["triangles"], f["seconds"]) for f in fs
                   if f["triangles"] >= args.min_triangles]
            slope = ("%.2f (r² %.2f, %d faces)" % (fit(big)[1], fit(big)[2], len(big))
                     if len(big) >= 10 else "-")
            print("| %s | %s | %d | %.2f | %.1f | %s |" % (tol, kind, len(fs), seconds,
                                                           1e6 * seconds / triangles, slope))

    print("\n## Each face against itself, between two tolerances\n")
    print("| tolerances | surface | faces | median slope | slope weighted by seconds |")
    print("|---|---|---:|---:|---:|")
    for coarse, fine in zip(tolerances, tolerances[1:]):
        by_kind = collections.defaultdict(list)
        for (t, name, fid), a in faces.items():
            b = faces.get((fine, name, fid))
            if t != coarse or b is None or a["triangles"] < args.min_triangles:
                continue
            if b["triangles"] < 1.5 * a["triangles"]:
                continue
            slope = math.log(b["seconds"] / a["seconds"]) / math.log(b["triangles"] / a["triangles"])
            by_kind[a["surface_type"]].append((slope, b["seconds"]))
            by_kind["all"].append((slope, b["seconds"]))
        for kind, pairs in sorted(by_kind.items(), key=lambda kv: -sum(s for _, s in kv[1])):
            weight = sum(s for _, s in pairs)
            print("| %s -> %s | %s | %d | %.2f | %.2f |" % (
                coarse, fine, kind, len(pairs), statistics.median(p for p, _ in pairs),
                sum(p * s for p, s in pairs) / weight))
    for name, tol, why in failures:
        print("\nfailed: %s at %s: %s" % (name, tol, why))
    print("\n%d models, tolerances %s; %s; %s" % (len(models), ",".join(tolerances), args.rdmesh,
                                                 time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())))
    if args.out:
        rows = [dict(f, tolerance=t, model=name) for (t, name, _), f in sorted(faces.items())]
        pathlib.Path(args.out).write_text(json.dumps({"faces": rows, "failures": failures}))


if __name__ == "__main__":
    main()
