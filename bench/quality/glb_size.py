#!/usr/bin/python3
"""Bytes of a .glb per triangle over the corpus: rdmesh's plain and --compress files of the same
mesh, and OCCT's own writer on BRepMesh's mesh at the same measured deviation (issue 37).

Usage: bench/quality/glb_size.py [--build build] [--node-dir BUILD/node_tools] [--out DIR]
                                 [--table bench/GLB.md] [MODEL...]

For each model, at rdmesh's default deviation (1e-3 of the bounding-box diagonal):
- `rdmesh mesh MODEL -o c.glb --compress` (meshed to 98.5% of the deviation, positions rounded
  by at most 1.5% of it), read back as a viewer reads it (bench/quality/decode_glb.mjs: three.js
  with meshoptimizer's decoder) and measured by the yardstick; and the plain file of the same mesh, `rdmesh mesh MODEL -o p.glb
  --max-deviation D` with D 98.5% of the compressed run's requested deviation (the same
  triangles, checked), and its .msh, which the yardstick
  (`meshbench eval`) measures: rdmesh's measured deviation (the rounding adds at most 1.5e-5 of
  the diagonal);
- BRepMesh (bench/brepmesh_runner, angle 0.5 rad) at a deflection set to that measured deviation,
  measured by the yardstick, then once more at the deflection scaled by target / measured; the
  run nearer the target is kept and written by OCCT's RWGltf_CafWriter with its default settings
  (bench/quality/occt_glb_runner: STEPCAFControl_Reader, the same BRepMesh call);
- levels of detail: `rdmesh mesh MODEL -o l.glb --compress --lod 1e-2,3e-3,1e-3`, each level's
  bytes against the finest level's.
Triangles are the triangles drawn (an instanced part counts once per instance). Writes the table
(markdown) to --table and the raw rows as JSON next to it.
"""
import argparse
import glob
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
SHARED = os.path.normpath(os.path.join(REPO, "..", "shared"))
REL = 1e-3
SHARE = 0.015  # kCompressRoundingShare
LEVELS = "1e-2,3e-3,1e-3"
ANGLE = 0.5


def run_json(args, timeout=900, cwd=None):
    done = subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=timeout,
                          cwd=cwd)
    if done.returncode != 0:
        raise RuntimeError("%s: exit %d: %s" % (os.path.basename(str(args[0])), done.returncode,
                                                 done.stderr.strip()[-300:]))
    return json.loads(done.stdout.strip().splitlines()[-1])


def measure(meshbench, model, mesh):
    return run_json([meshbench, "eval", model, mesh])["hausdorff_rel"]


def decoded_msh(a, glb, msh):
    """Writes the triangles a viewer reads from `glb` as MSH 4.1 in the model's frame (mm, +Z up),
    one element block per face id, for the yardstick."""
    # Node resolves `three` from the script's own folder: run a copy inside the node directory.
    script = os.path.join(a.node_dir, "decode_glb.mjs")
    shutil.copyfile(os.path.join(HERE, "decode_glb.mjs"), script)
    objects = run_json(["node", script, os.path.abspath(glb)], cwd=a.node_dir)
    points, blocks = [], {}
    for o in objects:
        base = len(points)
        xyz = o["position"]
        points += [(1000.0 * xyz[i], -1000.0 * xyz[i + 2], 1000.0 * xyz[i + 1])
                   for i in range(0, len(xyz), 3)]
        index = o["index"]
        for t in range(0, len(index), 3):
            corner = [base + index[t + k] + 1 for k in range(3)]
            blocks.setdefault(o["face"][index[t]], []).append(corner)
    with open(msh, "w") as out:
        out.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 %d 1 %d\n2 1 0 %d\n"
                  % (len(points), len(points), len(points)))
        out.write("".join("%d\n" % (i + 1) for i in range(len(points))))
        out.write("".join("%.17g %.17g %.17g\n" % p for p in points))
        count = sum(len(b) for b in blocks.values())
        out.write("$EndNodes\n$Elements\n%d %d 1 %d\n" % (len(blocks), count, count))
        tag = 1
        for face in sorted(blocks):
            out.write("2 %d 2 %d\n" % (face, len(blocks[face])))
            for corner in blocks[face]:
                out.write("%d %d %d %d\n" % (tag, *corner))
                tag += 1
        out.write("$EndElements\n")


def one_model(a, meshbench, model):
    name = os.path.splitext(os.path.basename(model))[0]
    out = os.path.join(a.out, name)
    os.makedirs(out, exist_ok=True)
    rdmesh = os.path.join(a.build, "bin", "rdmesh")
    row = {"model": name}
    packed = run_json([rdmesh, "mesh", model, "-o", os.path.join(out, "c.glb"), "--compress",
                       "--json", "-q"])
    # The absolute deviation the compressed run meshed to, computed as the engine does it.
    plain_abs = repr(packed["requested_deviation"] * (1 - SHARE))
    plain = run_json([rdmesh, "mesh", model, "-o", os.path.join(out, "p.glb"),
                      "--max-deviation", plain_abs, "--json", "-q"])
    if plain["triangles"] != packed["triangles"]:
        raise RuntimeError("the plain and compressed meshes differ")
    run_json([rdmesh, "mesh", model, "-o", os.path.join(out, "p.msh"), "--max-deviation",
              plain_abs, "--json", "-q"])
    row["triangles"] = packed["triangles"]
    row["plain_bytes"] = os.path.getsize(os.path.join(out, "p.glb"))
    row["compressed_bytes"] = os.path.getsize(os.path.join(out, "c.glb"))
    target = measure(meshbench, model, os.path.join(out, "p.msh"))
    row["rdmesh_measured_rel"] = target
    decoded_msh(a, os.path.join(out, "c.glb"), os.path.join(out, "c.msh"))
    row["compressed_measured_rel"] = measure(meshbench, model, os.path.join(out, "c.msh"))
    diagonal = packed["requested_deviation"] / REL
    try:
        row.update(occt_row(a, meshbench, model, out, target, diagonal))
    except (RuntimeError, subprocess.TimeoutExpired, ValueError, KeyError) as error:
        row["occt_error"] = str(error)
    run_json([rdmesh, "mesh", model, "-o", os.path.join(out, "l.glb"), "--compress", "--lod",
              LEVELS, "--json", "-q"])
    row["level_bytes"] = [os.path.getsize(os.path.join(out, "l.lod%d.glb" % i))
                          for i in range(len(LEVELS.split(",")))]
    return row


def occt_row(a, meshbench, model, out, target, diagonal):
    """BRepMesh at the deflection whose measured deviation is nearest `target`, written by
    OCCT's glTF writer."""
    tries = []
    # A mesh that lies on its faces (planes only) measures about 0: aim at the request then.
    if target < 1e-3 * REL:
        target = REL
    deflection = target * diagonal
    for _ in range(2):
        b = run_json([os.path.join(a.build, "bin", "brepmesh_runner"), model, repr(deflection),
                      str(ANGLE), os.path.join(out, "b.msh")])
        measured = measure(meshbench, model, os.path.join(out, "b.msh"))
        tries.append((abs(math.log(measured / target)) if measured > 0 else 1e9, deflection,
                      measured, b["triangles"]))
        if measured <= 0:
            break
        deflection *= target / measured
    _, deflection, measured, triangles = min(tries)
    occt = run_json([os.path.join(a.build, "bin", "occt_glb_runner"), model, repr(deflection),
                     str(ANGLE), os.path.join(out, "o.glb")])
    return dict(occt_deflection=deflection, occt_measured_rel=measured, occt_triangles=triangles,
                occt_bytes=occt["bytes"])


def geomean(values):
    values = [v for v in values if v > 0]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else float("nan")


def table(rows, commands):
    ok = [r for r in rows if "error" not in r]
    occ = [r for r in ok if "occt_bytes" in r]
    lines = [
        "# .glb bytes per triangle (issue 37)",
        "",
        "Made by %s (%s, commit %s), on the %d corpus models of ../shared/corpus at rdmesh's "
        "default deviation, 1e-3 of the bounding-box diagonal. What each column is: the script's "
        "docstring (bench/quality/glb_size.py)." % (
            ", then ".join("`%s`" % c for c in commands), time.strftime("%Y-%m-%d"),
            git_commit(), len(rows)),
        "",
        "- **plain**: `rdmesh mesh` .glb of the mesh that `--compress` writes (the same "
        "triangles: --compress meshes to 98.5% of the deviation), edges included;",
        "- **compressed**: `rdmesh mesh --compress`, edges included;",
        "- **dev**: the yardstick's measured deviation (hausdorff_rel) of the plain mesh and of "
        "the compressed file as three.js decodes it (rounding included);",
        "- **OCCT**: OCCT 7.6's RWGltf_CafWriter (default settings, no edges) on BRepMesh's mesh at "
        "the deflection whose measured deviation (yardstick) is nearest rdmesh's (`dev` columns: "
        "measured hausdorff_rel, rdmesh's without its rounding of at most 1.5e-5);",
        "- **levels**: `--compress --lod %s`, each level's bytes / the finest level's." % LEVELS,
        "",
    ]
    if ok:
        total_t = sum(r["triangles"] for r in ok)
        total_o = sum(r["occt_triangles"] for r in occ)
        lines += [
            "| over %d models (OCCT: %d) | plain | compressed | OCCT |" % (len(ok), len(occ)),
            "|---|---|---|---|",
            "| bytes per triangle, all files together | %.1f | **%.1f** | %.1f |" % (
                sum(r["plain_bytes"] for r in ok) / total_t,
                sum(r["compressed_bytes"] for r in ok) / total_t,
                sum(r["occt_bytes"] for r in occ) / total_o),
            "| bytes per triangle, geometric mean over models | %.1f | **%.1f** | %.1f |" % (
                geomean([r["plain_bytes"] / r["triangles"] for r in ok]),
                geomean([r["compressed_bytes"] / r["triangles"] for r in ok]),
                geomean([r["occt_bytes"] / r["occt_triangles"] for r in occ])),
            "| bytes of the file / compressed, geometric mean | %.2fx | 1 | %.2fx |" % (
                geomean([r["plain_bytes"] / r["compressed_bytes"] for r in ok]),
                geomean([r["occt_bytes"] / r["compressed_bytes"] for r in occ])),
            "| compressed / plain: median, largest | | %.3f, %.3f | |" % (
                statistics.median(r["compressed_bytes"] / r["plain_bytes"] for r in ok),
                max(r["compressed_bytes"] / r["plain_bytes"] for r in ok)),
            "| models where compressed <= 0.25x plain | | %d of %d | |" % (
                sum(r["compressed_bytes"] <= 0.25 * r["plain_bytes"] for r in ok), len(ok)),
            "| triangles, all models (OCCT: at the matched deviation) | %d | %d | %d |" % (
                total_t, total_t, total_o),
            "| measured deviation / 1e-3, largest (compressed: as decoded) | %.3f | %.3f | %.3f |" % (
                max(r["rdmesh_measured_rel"] for r in ok) / REL,
                max(r["compressed_measured_rel"] for r in ok) / REL,
                max(r["occt_measured_rel"] for r in occ) / REL),
            "| levels %s, bytes / finest level, geometric mean | | %s | |" % (
                LEVELS, " / ".join("%.3f" % geomean([r["level_bytes"][i] / r["level_bytes"][-1]
                                                      for r in ok])
                                   for i in range(len(LEVELS.split(","))))),
            "",
        ]
    lines += [
        "| model | triangles | plain B/tri | compressed B/tri | compressed / plain | "
        "rdmesh dev | compressed dev | OCCT triangles | OCCT dev | OCCT B/tri | levels / finest |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "error" in r:
            lines.append("| %s | failed: %s ||||||||||" % (
                r["model"], " ".join(r["error"].replace("|", "/").split())[:200]))
            continue
        occt = ("%d | %.2e | %.1f" % (r["occt_triangles"], r["occt_measured_rel"],
                                       r["occt_bytes"] / r["occt_triangles"])
                if "occt_bytes" in r else "failed: %s | | " % " ".join(
                    r["occt_error"].replace("|", "/").split())[:120])
        lines.append("| %s | %d | %.1f | %.1f | %.3f | %.2e | %.2e | %s | %s |" % (
            r["model"], r["triangles"], r["plain_bytes"] / r["triangles"],
            r["compressed_bytes"] / r["triangles"], r["compressed_bytes"] / r["plain_bytes"],
            r["rdmesh_measured_rel"], r["compressed_measured_rel"], occt,
            " / ".join("%.2f" % (b / r["level_bytes"][-1]) for b in r["level_bytes"][:-1])))
    return "\n".join(lines) + "\n"


def git_commit():
    done = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True)
    return done.stdout.strip() or "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(REPO, "build"),
                    help="build directory with bin/rdmesh, brepmesh_runner, occt_glb_runner")
    ap.add_argument("--node-dir", help="where npm installed three (default BUILD/node_tools, as "
                    "the CLI tests leave it)")
    ap.add_argument("--out", default="/tmp/rdmesh-glb-size", help="directory for the files")
    ap.add_argument("--table", default=os.path.join(REPO, "bench", "GLB.md"))
    ap.add_argument("--update", action="store_true",
                    help="measure only MODELs again and replace their rows in the table's JSON")
    ap.add_argument("models", nargs="*", help="default: every ../shared/corpus/*.st*p")
    a = ap.parse_args()
    a.node_dir = os.path.abspath(a.node_dir or os.path.join(a.build, "node_tools"))
    built = subprocess.run(["sh", os.path.join(REPO, "scripts", "yardstick.sh")], check=True,
                           capture_output=True, text=True).stdout.strip().splitlines()[-1]
    meshbench = os.path.join(built, "meshbench")
    models = a.models or sorted(glob.glob(os.path.join(SHARED, "corpus", "*.st*p")))
    command = "/usr/bin/python3 bench/quality/glb_size.py " + " ".join(sys.argv[1:])
    rows, commands = [], [command.strip()]
    if a.update:
        with open(os.path.splitext(a.table)[0] + ".json") as f:
            saved = json.load(f)
        rows, commands = saved["rows"], saved["commands"] + commands
    for model in models:
        start = time.time()
        try:
            row = one_model(a, meshbench, model)
        except (RuntimeError, subprocess.TimeoutExpired, ValueError, KeyError) as error:
            row = {"model": os.path.splitext(os.path.basename(model))[0], "error": str(error)}
        rows = [r for r in rows if r["model"] != row["model"]] + [row]
        rows.sort(key=lambda r: r["model"])
        print("%-45s %5.1f s  %s" % (row["model"], time.time() - start,
                                     row.get("error") or "%.3f" % (row["compressed_bytes"] /
                                                                   row["plain_bytes"])),
              flush=True)
        with open(os.path.splitext(a.table)[0] + ".json", "w") as f:
            json.dump({"commands": commands, "rows": rows}, f, indent=1)
        with open(a.table, "w") as f:
            f.write(table(rows, commands))


if __name__ == "__main__":
    main()
