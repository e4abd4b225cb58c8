#!/usr/bin/env python3
"""What levels of detail in one run cost (issue 15 item 4: 3 watertight levels for less than
1.6x the time of the finest alone).

    /usr/bin/python3 bench/performance/lod_cost.py [--runs 5] [--lod 1e-2,1e-3,1e-4] [MODEL.step ...]

For each model, round by round, in turn: `rdmesh mesh MODEL --lod LEVELS` (one process: the
model read once, one mesh per level), the finest level alone (`--max-deviation-rel FINEST`), and
each level as a separate run (one process per level, summed). Every run writes .msh into a
temporary folder and runs in one process (RDMESH_NO_FORK=1). Reports the medians over the rounds
of each variant's wall and CPU seconds (user + system of the child, os.times()), the meshing
seconds alone (the --json `seconds` of each mesh, summed over levels, loading and writing left
out), and the ratios of the --lod run to the finest alone and to the separate runs. The default
models are nist_mbe_pmi_2 and nist_ctc_02_asme1_ap242 of the corpus and the bundled
nist_mbe_pmi_11.
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORPUS = ROOT.parent / "shared" / "corpus"
DEFAULT_MODELS = [CORPUS / "nist_mbe_pmi_2.stp", CORPUS / "nist_ctc_02_asme1_ap242.stp",
                  ROOT / "tests" / "data" / "nist_mbe_pmi_11.stp"]


def timed(command, env):
    """(wall seconds, CPU seconds, the --json report) of one run of `command`."""
    before = os.times()
    start = time.perf_counter()
    proc = subprocess.run(command, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    after = os.times()
    if proc.returncode != 0:
        raise SystemExit("%s failed (%d): %s" % (" ".join(command), proc.returncode, proc.stderr))
    cpu = (after.children_user - before.children_user) + (after.children_system -
                                                          before.children_system)
    return wall, cpu, json.loads(proc.stdout.strip().splitlines()[-1])


def mesh_seconds(report):
    return sum(r["seconds"] for r in report.get("levels", [report]))


def triangles(report):
    return [r["triangles"] for r in report.get("levels", [report])]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="*", default=[str(m) for m in DEFAULT_MODELS])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--lod", default="1e-2,1e-3,1e-4")
    parser.add_argument("--rdmesh", default=str(ROOT / "build" / "bin" / "rdmesh"))
    args = parser.parse_args()
    levels = sorted(args.lod.split(","), key=float, reverse=True)
    env = dict(os.environ, RDMESH_NO_FORK="1")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp)
        for model in args.models:
            base = [args.rdmesh, "mesh", model, "--json", "--quiet"]
            samples = {"lod": [], "finest": [], "separate": []}
            counts = None
            for _ in range(args.runs):
                wall, cpu, report = timed(base + ["-o", str(out / "lod.msh"), "--lod",
                                                  ",".join(levels)], env)
                samples["lod"].append((wall, cpu, mesh_seconds(report)))
                counts = triangles(report)
                wall, cpu, report = timed(base + ["-o", str(out / "finest.msh"),
                                                  "--max-deviation-rel", levels[-1]], env)
                samples["finest"].append((wall, cpu, mesh_seconds(report)))
                total = [0.0, 0.0, 0.0]
                for level in levels:
                    wall, cpu, report = timed(base + ["-o", str(out / "single.msh"),
                                                      "--max-deviation-rel", level], env)
                    total = [total[0] + wall, total[1] + cpu, total[2] + mesh_seconds(report)]
                samples["separate"].append(tuple(total))
            median = {k: [statistics.median(s[i] for s in v) for i in range(3)]
                      for k, v in samples.items()}
            rows.append((pathlib.Path(model).name, counts, median))
    print("levels %s, %d rounds, medians; wall / CPU / meshing seconds" % (",".join(levels),
                                                                         args.runs))
    print()
    print("| model | triangles per level | --lod | finest alone | separate runs "
          "| --lod / finest (wall, CPU, meshing) | --lod / separate (wall, CPU) |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for name, counts, m in rows:
        cell = lambda v: "%.2f / %.2f / %.2f" % tuple(v)  # noqa: E731
        lod, finest, separate = m["lod"], m["finest"], m["separate"]
        print("| %s | %s | %s | %s | %s | %.2fx, %.2fx, %.2fx | %.2fx, %.2fx |" % (
            name, " / ".join(str(c) for c in counts), cell(lod), cell(finest), cell(separate),
            lod[0] / finest[0], lod[1] / finest[1], lod[2] / finest[2],
            lod[0] / separate[0], lod[1] / separate[1]))


if __name__ == "__main__":
    main()
