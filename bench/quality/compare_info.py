#!/usr/bin/env python3
"""Whether two rdmesh builds load models the same: `rdmesh info MODEL --json` with each, every
field but `load_seconds` compared exactly, and both load times. For load-path changes that must
not change what is loaded (the bounding box and diagonal set every relative deviation).

    /usr/bin/python3 bench/quality/compare_info.py --before OLD/rdmesh --after NEW/rdmesh [MODEL ...]

Default models: tests/data and ../shared/corpus. Exits 1 when any model differs.
"""

import argparse
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def info(binary, model):
    run = subprocess.run([binary, "info", str(model), "--json"], capture_output=True, text=True,
                         timeout=600)
    report = json.loads(run.stdout.strip().splitlines()[-1])
    return report.pop("load_seconds", None), report


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", required=True)
    parser.add_argument("--after", required=True)
    parser.add_argument("models", nargs="*")
    args = parser.parse_args()
    models = args.models or sorted(ROOT.glob("tests/data/*.st*p")) + sorted(
        (ROOT.parent / "shared" / "corpus").glob("*.st*p"))
    differ = 0
    for model in models:
        before_s, before = info(args.before, model)
        after_s, after = info(args.after, model)
        same = before == after
        differ += not same
        print("%-4s %-50s load %6.2f s -> %6.2f s" % ("same" if same else "DIFF",
                                                   pathlib.Path(model).name, before_s, after_s))
        if not same:
            for key in sorted(set(before) | set(after)):
                if before.get(key) != after.get(key):
                    print("     %s: %s -> %s" % (key, before.get(key), after.get(key)))
    print("%d of %d models differ" % (differ, len(models)))
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
