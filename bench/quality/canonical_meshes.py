#!/usr/bin/python3
"""Meshes models with two rdmesh binaries and compares the results: triangle counts, failed
faces, estimated deviation, and whether the .msh files are byte-identical. Written to measure
what the canonical load (every model read back from OCCT's binary form, see
engine/src/model/model.h ParseCanonical) changes in today's meshes.

  bench/quality/canonical_meshes.py --before OLD/rdmesh --after build/bin/rdmesh MODEL... [-- MESH_FLAGS]

Prints one Markdown table row per model; both runs use the same flags (default: the defaults)."""

import argparse
import json
import os
import subprocess
import sys
import tempfile


def mesh(binary, model, output, flags):
    completed = subprocess.run([binary, "mesh", model, "-o", output, "--json", "--quiet", *flags],
                               capture_output=True, text=True, timeout=3600)
    lines = [line for line in completed.stdout.splitlines() if line.strip()]
    if not lines:
        raise SystemExit(f"{binary} {model}: no output ({completed.stderr.strip()})")
    return json.loads(lines[-1])


def main():
    argv = sys.argv[1:]
    flags = []
    if "--" in argv:
        flags = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True)
    parser.add_argument("--after", required=True)
    parser.add_argument("models", nargs="+")
    args = parser.parse_args(argv)
    print("| model | triangles before | after | failed faces before | after "
          "| est. deviation before | after | .msh identical |")
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for model in args.models:
            outputs = [os.path.join(tmp, name) for name in ("before.msh", "after.msh")]
            runs = [mesh(binary, model, out, flags)
                    for binary, out in zip((args.before, args.after), outputs)]
            same = open(outputs[0], "rb").read() == open(outputs[1], "rb").read()
            cells = [os.path.basename(model)]
            for field in ("triangles", "faces_failed", "estimated_deviation"):
                cells += [f"{run.get(field, 'error')}" for run in runs]
            cells.append("yes" if same else "no")
            print("| " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
