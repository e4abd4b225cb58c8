#!/usr/bin/env python3
"""What rdmesh's model load costs against a plain OCCT STEP read of the same file, in one run
(issue 14 part 3: within 1.2x).

    /usr/bin/python3 bench/performance/load_cost.py [--runs 3] [MODEL.step ...]

For each model, alternately: `rdmesh info MODEL --json` in one process (RDMESH_NO_FORK=1; our
load: STEPCAFControl_Reader with names, colours and layers, the pre-checks, the canonical binary
round trip, instances, exact face areas, the tight bounding box) and `step_read_runner MODEL`
(STEPControl_Reader: read, transfer, one shape; bench/step_read_runner.cpp). Reports the medians
of each process's wall and CPU seconds (user + system, os.times() of the children) and their
ratios. The default
models are the two large ones of the corpus.
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORPUS = ROOT.parent / "shared" / "corpus"
DEFAULT_MODELS = [CORPUS / "voron_bowden_module.step", CORPUS / "gmsh_tough_second_order.step"]


def timed(command, env):
    """(wall seconds, stdout) of one run of `command`; its CPU time is in os.times()'s
    children fields once it has been waited for."""
    start = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    out, err = proc.communicate()
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit("%s failed (%d): %s" % (command[0], proc.returncode, err.decode()))
    return wall, out.decode()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="*", default=[str(m) for m in DEFAULT_MODELS])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--rdmesh", default=str(ROOT / "build" / "bin" / "rdmesh"))
    parser.add_argument("--reader", default=str(ROOT / "build" / "bin" / "step_read_runner"))
    args = parser.parse_args()
    env = dict(os.environ, RDMESH_NO_FORK="1")
    print("| model | faces | rdmesh load wall s | plain read wall s | wall ratio | rdmesh CPU s "
          "| plain CPU s | CPU ratio |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for model in args.models:
        samples = {"ours": [], "plain": []}
        faces = None
        for _ in range(args.runs):
            for kind, command in (("ours", [args.rdmesh, "info", model, "--json"]),
                                  ("plain", [args.reader, model])):
                before = os.times()
                wall, out = timed(command, env)
                after = os.times()
                cpu = (after.children_user - before.children_user
                       + after.children_system - before.children_system)
                report = json.loads(out.strip().splitlines()[-1])
                faces = faces or report.get("faces")
                samples[kind].append((wall, cpu))
        ours = [statistics.median(x[i] for x in samples["ours"]) for i in (0, 1)]
        plain = [statistics.median(x[i] for x in samples["plain"]) for i in (0, 1)]
        print("| %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |" % (
            pathlib.Path(model).name, faces, ours[0], plain[0], ours[0] / plain[0], ours[1],
            plain[1], ours[1] / plain[1]))


if __name__ == "__main__":
    main()
