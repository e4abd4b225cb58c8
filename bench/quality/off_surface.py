#!/usr/bin/python3
"""Meshing off the surface (issue 36) against the default mode and BRepMesh, measured both ways.

Usage: bench/quality/off_surface.py [--build build] [--rels 1e-3,1e-4] [--out DIR]
                                    [--table bench/OFF_SURFACE.md] [MODEL...]

For each model (default: the yardstick's unit sphere, cylinder and torus and the 17 bench models
of bench/run_bench.py) and each relative deviation:
- `rdmesh mesh MODEL -o OUT.msh --max-deviation-rel REL --json` (the default mode: nodes on the
  surface) and the same with `--off-surface`;
- BRepMesh (`meshbench brepmesh`, deflection REL x the model's diagonal, angle 0.5 rad), the
  yardstick's anchor at the same deflection (not its best-tuned setting: bench/RESULTS.md has
  that);
every mesh scored by the yardstick both ways (`MESHBENCH_BOTH_WAYS=1 meshbench eval`):
hausdorff_sym_rel, the larger of the mesh-to-surface and surface-to-mesh distances, over REL.
The triangles of each kind of face (per face, from --json: sphere-like = sphere; cylinder-like
= cylinder, cone; saddle = a curved face the off-surface run kept on its surface because it
bends both ways; B-spline = the other B-spline faces; other = the rest of the curved faces) are
summed over the models for both modes. The interpolating minimum is the unit sphere's (about
1,396 triangles at 1e-3 of the diagonal, scaling as 1 / deviation). Writes the Markdown table to
--table and the raw rows as JSON next to it.
"""
import argparse
import datetime
import json
import math
import os
import shlex
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
SHARED = os.path.normpath(os.path.join(REPO, "..", "shared"))
ANGLE = 0.5
SPHERE_MINIMUM_1E3 = 1396  # docs/METHOD.md: the interpolating minimum of the unit sphere at 1e-3
BENCH = ["cq_red_cube_blue_cylinder.step", "axom_sliced_cylinder.step", "gmsh_cube_filet.stp",
         "pyoccdemos_face_recognition_sample_part.stp", "nist_mbe_pmi_11.stp",
         "gmsh_kurbelwelle.stp", "gmsh_part.step", "gmsh_angled.step",
         "gmsh_periodic_u_cst.step", "gmsh_mambo_s34.step", "gmsh_wrenchnut.stp",
         "gmsh_zylkopf.stp", "gmsh_solid_56.step", "gmsh_918_pump_carter_sup.stp",
         "brepnet_132907_4ed3eae8_0.stp", "brepnet_52890_dc92327c_3.stp", "pyocc_eight_cyl.stp"]
KINDS = ["sphere-like", "cylinder-like", "saddle", "B-spline", "other curved"]


def last_json(text):
    return json.loads(text.strip().splitlines()[-1])


def run(args, timeout=1800, env=None):
    done = subprocess.run([str(a) for a in args], capture_output=True, text=True,
                          timeout=timeout, env=env)
    if done.returncode not in (0, 1):  # 1: a face over its criteria, still a mesh
        raise RuntimeError("%s: exit %d: %s" % (os.path.basename(str(args[0])), done.returncode,
                                                 done.stderr.strip()[-300:]))
    return done.stdout


def evaluate(meshbench, model, mesh):
    env = dict(os.environ, MESHBENCH_BOTH_WAYS="1")
    return last_json(run([meshbench, "eval", model, mesh], env=env))


def kind(face, off_face):
    t = face["surface_type"]
    if t == "plane":
        return None
    if t == "sphere":
        return "sphere-like"
    if t in ("cylinder", "cone"):
        return "cylinder-like"
    if "both ways" in off_face.get("offset_reason", ""):
        return "saddle"
    if t == "bspline":
        return "B-spline"
    return "other curved"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=os.path.join(REPO, "build"))
    ap.add_argument("--rels", default="1e-3,1e-4")
    ap.add_argument("--out", default="/tmp/rdmesh_off_surface")
    ap.add_argument("--table", default=os.path.join(REPO, "bench", "OFF_SURFACE.md"))
    ap.add_argument("models", nargs="*")
    a = ap.parse_args()
    yard = subprocess.run([os.path.join(REPO, "scripts", "yardstick.sh")], capture_output=True,
                          text=True, check=True).stdout.strip()
    meshbench = os.path.join(yard, "meshbench")
    rdmesh = os.path.join(a.build, "bin", "rdmesh")
    models = a.models or ([os.path.join(yard, "models", m + ".step")
                           for m in ("sphere", "cylinder", "torus")] +
                          [os.path.join(SHARED, "corpus", m) for m in BENCH])
    rels = [float(r) for r in a.rels.split(",")]
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for rel in rels:
        for model in models:
            name = os.path.basename(model)
            row = {"model": name, "rel": rel}
            try:
                for mode, extra in (("on", []), ("off", ["--off-surface"])):
                    out = os.path.join(a.out, "%s.%g.%s.msh" % (name, rel, mode))
                    j = last_json(run([rdmesh, "mesh", model, "-o", out, "--max-deviation-rel",
                                       rel, "--json", "-q"] + extra))
                    e = evaluate(meshbench, model, out)
                    row[mode] = {"triangles": j["triangles"], "seconds": j["seconds"],
                                 "sym": e["hausdorff_sym_rel"] / rel,
                                 "m2s": e["hausdorff_rel"] / rel,
                                 "s2m": e["surface_to_mesh_rel"] / rel,
                                 "free": e["free_edges"], "inverted": e["inverted"],
                                 "faces": j["faces"], "diagonal_request":
                                 j["requested_deviation"]}
                deflection = row["on"]["diagonal_request"]
                out = os.path.join(a.out, "%s.%g.brepmesh.msh" % (name, rel))
                b = last_json(run([meshbench, "brepmesh", model, deflection, ANGLE, out]))
                e = evaluate(meshbench, model, out)
                row["brepmesh"] = {"triangles": b.get("triangles", e["triangles"]),
                                   "sym": e["hausdorff_sym_rel"] / rel}
            except (RuntimeError, subprocess.TimeoutExpired, KeyError, ValueError) as error:
                row["error"] = str(error)[:300]
            rows.append(row)
            print(json.dumps({k: v for k, v in row.items() if k not in ("on", "off")} |
                             {m: {k: row[m][k] for k in ("triangles", "sym")}
                              for m in ("on", "off") if m in row}), flush=True)
    write(a, rows, rels)


def write(a, rows, rels):
    commit = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    script = os.path.relpath(os.path.abspath(sys.argv[0]), REPO)
    command = " ".join(["/usr/bin/python3", script] + [shlex.quote(x) for x in sys.argv[1:]])
    rdmesh = os.path.join(a.build, "bin", "rdmesh")
    load = os.getloadavg()
    L = ["# Off the surface: triangles at the same request, measured both ways", "",
         "Written by `bench/quality/off_surface.py` (its docstring says how). Made with:", "",
         "```", command, "```", "",
         "- %s UTC, commit `%s`; load average at the end %.1f %.1f %.1f (2 cores, shared)" %
         (datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"), commit, *load),
         "- rdmesh: `%s`" % rdmesh,
         "- sym = the yardstick's hausdorff_sym_rel over the request (the larger of mesh to "
         "surface and surface to mesh); off / on = triangles of `--off-surface` over the "
         "default mode's, at the same request", ""]
    for rel in rels:
        sub = [r for r in rows if r["rel"] == rel and "error" not in r]
        L += ["## %g of the diagonal" % rel, "",
              "| model | default triangles | sym | off-surface triangles | sym | off / on | "
              "BRepMesh triangles | sym |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
        ratios = []
        for r in sub:
            ratio = r["off"]["triangles"] / r["on"]["triangles"]
            curved = any(f["surface_type"] != "plane" for f in r["on"]["faces"])
            if curved and r["model"] not in ("sphere.step", "cylinder.step", "torus.step"):
                ratios.append(ratio)
            L.append("| %s | %d | %.3f | %d | %.3f | %.3f | %d | %.3f |" % (
                r["model"], r["on"]["triangles"], r["on"]["sym"], r["off"]["triangles"],
                r["off"]["sym"], ratio, r["brepmesh"]["triangles"], r["brepmesh"]["sym"]))
        for r in rows:
            if r["rel"] == rel and "error" in r:
                L.append("| %s | error: %s |||||||" % (r["model"], r["error"][:120]))
        L.append("")
        if ratios:
            geo = math.exp(sum(math.log(x) for x in ratios) / len(ratios))
            L.append("- off / on over the %d bench models (geometric mean): **%.3f**" %
                     (len(ratios), geo))
        worst = max((max(r["on"]["sym"], r["off"]["sym"]), r["model"]) for r in sub) if sub \
            else None
        if worst:
            L.append("- largest sym reading: %.3f (%s)" % worst)
        sphere = [r for r in sub if r["model"] == "sphere.step"]
        if sphere:
            minimum = SPHERE_MINIMUM_1E3 * 1e-3 / rel
            L.append("- unit sphere: default %.3fx the interpolating minimum (%d), off the "
                     "surface %.3fx" % (sphere[0]["on"]["triangles"] / minimum, minimum,
                                        sphere[0]["off"]["triangles"] / minimum))
        by_kind = {k: [0, 0, 0] for k in KINDS}  # on, off, faces
        for r in sub:
            if r["model"] in ("sphere.step", "cylinder.step", "torus.step"):
                continue
            off_faces = {f["id"]: f for f in r["off"]["faces"]}
            for f in r["on"]["faces"]:
                g = off_faces.get(f["id"])
                k = kind(f, g or {})
                if k is None or g is None:
                    continue
                by_kind[k][0] += f["triangles"]
                by_kind[k][1] += g["triangles"]
                by_kind[k][2] += 1
        L += ["", "Per kind of face, summed over the bench models:", "",
              "| kind | faces | default triangles | off-surface triangles | off / on |",
              "|---|---:|---:|---:|---:|"]
        for k in KINDS:
            on, off, n = by_kind[k]
            if n:
                L.append("| %s | %d | %d | %d | %.3f |" % (k, n, on, off, off / on))
        L.append("")
    with open(a.table, "w") as f:
        f.write("\n".join(L) + "\n")
    with open(os.path.splitext(a.table)[0] + ".json", "w") as f:
        json.dump(rows, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
