#!/usr/bin/python3
"""Meshes every corpus model with rdmesh and scores it with the yardstick.

Usage: bench/quality/corpus_eval.py [--rdmesh build/bin/rdmesh] [--rel 1e-3] [--out DIR] [MODEL...]

For each model: `rdmesh mesh MODEL -o DIR/NAME.msh --max-deviation-rel REL --json`, then
`meshbench eval MODEL DIR/NAME.msh`. Prints one row per model with flags for what misses the bar
(DEV: hausdorff_rel above 1.2 x REL + the model's own edge tolerance; FREE: free edges on a closed
B-rep; NM: non-manifold edges on a closed B-rep, counted by the yardstick within each solid
(on an open one the faces outside any solid count as one group, where separate shells touch);
INV: inverted triangles; COV: faces without triangles; RC: rdmesh exit code).
"""
import argparse
import glob
import json
import os
import subprocess
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rdmesh", default=os.path.join(HERE, "..", "..", "build", "bin", "rdmesh"))
    ap.add_argument("--rel", type=float, default=1e-3, help="--max-deviation-rel (default 1e-3)")
    ap.add_argument("--out", default="/tmp/rdmesh-corpus", help="directory for meshes and JSON")
    ap.add_argument("models", nargs="*", help="default: every ../shared/corpus/*.st*p")
    a = ap.parse_args()
    # The shared yardstick may be read-only: scripts/yardstick.sh builds a copy to run.
    built = subprocess.run(["sh", os.path.join(HERE, "..", "..", "scripts", "yardstick.sh")], check=True,
                           capture_output=True, text=True).stdout.strip().splitlines()[-1]
    meshbench = os.path.join(built, "meshbench")
    models = a.models or sorted(glob.glob(os.path.join(SHARED, "corpus", "*.st*p")))
    os.makedirs(a.out, exist_ok=True)
    clean = 0
    for model in models:
        name = os.path.splitext(os.path.basename(model))[0]
        msh = os.path.join(a.out, name + ".msh")
        t0 = time.time()
        run = subprocess.run([a.rdmesh, "mesh", model, "-o", msh, "--max-deviation-rel",
                              str(a.rel), "--json", "-q"], capture_output=True, text=True,
                             timeout=600)
        wall = time.time() - t0
        with open(os.path.join(a.out, name + ".json"), "w") as f:
            f.write(run.stdout)
        e = {}
        if os.path.exists(msh):
            ev = subprocess.run([meshbench, "eval", model, msh], capture_output=True, text=True,
                                timeout=600)
            lines = ev.stdout.strip().splitlines()
            e = json.loads(lines[-1]) if lines else {}
        h = e.get("hausdorff_rel", float("inf"))
        tol = e.get("edge_tol_rel", 0.0)
        flags = []
        if h > 1.2 * a.rel + tol:
            flags.append("DEV")
        if e.get("free_edges", 0) and e.get("brep_free_edges", 1) == 0:
            flags.append("FREE")
        if e.get("nonmanifold_edges", 0) and e.get("brep_free_edges", 1) == 0:
            flags.append("NM")
        if e.get("inverted"):
            flags.append("INV")
        if e.get("faces_covered") != e.get("faces"):
            flags.append("COV")
        if run.returncode != 0:
            flags.append("RC%d" % run.returncode)
        clean += not flags
        print("%-31s %6.1fs %7s h=%.2e free %s nm %s inv %s deg %s cov %s/%s tol %.1e bfree %s %s"
              % (name[:31], wall, e.get("triangles"), h, e.get("free_edges"),
                 e.get("nonmanifold_edges"), e.get("inverted"), e.get("degenerate"),
                 e.get("faces_covered"), e.get("faces"), tol, e.get("brep_free_edges"),
                 " ".join(flags)), flush=True)
    print("%d of %d models clean" % (clean, len(models)))


if __name__ == "__main__":
    main()
