#!/usr/bin/python3
"""rdmesh benchmark: triangles and seconds to reach a max deviation, against BRepMesh and Gmsh.

  /usr/bin/python3 bench/run_bench.py [--quick] [--models NAME ...] [--out bench/RESULTS.md]
  /usr/bin/python3 bench/run_bench.py --results-only RESULTS.json [--out bench/RESULTS.md]

For each model and mesher a ladder of settings is run and every mesh is scored by the independent
yardstick (meshbench eval, built by scripts/yardstick.sh). Along each mesher's Pareto front of
(triangles, hausdorff_rel) the triangles and seconds needed for a max deviation of 1e-3 and 1e-4 of
the bbox diagonal are interpolated log-log. Every run saves its results as JSON (--results,
default BUILD/bench_results.json) and writes bench/RESULTS.md from that file alone: the ratios
rdmesh/BRepMesh and rdmesh/Gmsh and their geometric means, the analytic models against their
minimum, delivered against requested deviation, and the runs that are not clean (faces left
uncovered, free edges on closed models, inverted triangles, deviation over 1.2x the request,
errors, timeouts). --results-only re-renders RESULTS.md from a saved file. See bench/README.md.

Meshers:
  rdmesh    the CLI (built from a clean export of --rdmesh-rev), --max-deviation-rel ladder
  brepmesh  bench/brepmesh_runner (OCCT BRepMesh linked), absolute deflection ladder x angles
  gmsh      Debian's python3-gmsh through the yardstick's anchors.py (curvature sizing ladder)
Anchor records (brepmesh, gmsh) are cached in BUILD/bench_cache.jsonl; rdmesh records too, keyed
by the binary's hash, so a rerun with an unchanged rdmesh only re-scores nothing.
"""
import argparse, datetime, hashlib, json, math, os, platform, shlex, shutil, statistics, subprocess, sys, tempfile, time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
YARD = "/work/shared/yardstick"
MESHBENCH = os.path.join(YARD, "meshbench")
ANCHORS = os.path.join(YARD, "anchors.py")
CORPUS = "/work/shared/corpus"
PYTHON = "/usr/bin/python3"
TARGETS = [1e-3, 1e-4]
TRIANGLE_CAP = 1_500_000  # finer settings of a ladder are skipped past this many triangles

# ~6 small models, a few minutes in all.
QUICK = ["cq_red_cube_blue_cylinder.step", "axom_sliced_cylinder.step", "gmsh_cube_filet.stp",
         "pyoccdemos_face_recognition_sample_part.stp", "nist_mbe_pmi_11.stp", "gmsh_kurbelwelle.stp"]
# A representative default set: analytic and B-spline, machined parts, freeform, assemblies,
# periodic surfaces, torus fillets. The giant files (>1 MB, several hundred to 2700 faces:
# gmsh_tough_second_order, nist_ctc_02, voron_bowden_module, pyoccdemos_ventilator, nist_mbe_pmi_2/4,
# pyoccdemos_11752, gmsh_u_joint_2, gmsh_block, cadex_omni_wheel, ...) are left out for time, and so are
# the B-spline-heavy nist_mbe_pmi_1 and gmsh_component4 (scoring their 1e-4 meshes takes minutes each).
DEFAULT = QUICK + ["gmsh_part.step", "gmsh_angled.step", "gmsh_periodic_u_cst.step", "gmsh_mambo_s34.step",
                   "gmsh_wrenchnut.stp", "gmsh_zylkopf.stp", "gmsh_solid_56.step", "gmsh_918_pump_carter_sup.stp",
                   "brepnet_132907_4ed3eae8_0.stp", "brepnet_52890_dc92327c_3.stp", "pyocc_eight_cyl.stp"]
# Analytic models with a known minimum (always run unless --no-analytic).
ANALYTIC = {
    "sphere.step": "unit sphere",
    "cylinder.step": "cylinder r=1 h=4",
}


def theoretical_minimum(model, eps):
    """Fewest triangles for max deviation eps * diag (see bench/README.md)."""
    if model == "sphere.step":
        # Unit sphere: ~1396 triangles at 1e-3 of the diagonal (2*sqrt(3)); the count of a
        # near-optimal mesh scales as 1/deviation.
        return 1396.0 * (1e-3 / eps)
    if model == "cylinder.step":
        # r=1, h=4, diag=sqrt(24): n segments per circle with sagitta 1-cos(pi/n) <= eps*diag; the
        # side needs 2n triangles (straight generators are exact), each cap disc n-2.
        d = eps * math.sqrt(24.0)
        n = math.ceil(math.pi / math.acos(1.0 - d))
        return float(2 * n + 2 * (n - 2))
    return None


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def last_json(text):
    for line in reversed(text.strip().splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line)
            except ValueError:
                continue
    return None


def engine_binary(binary):
    """The program that does the work: rdmesh-local beside an rdmesh launcher, or the binary."""
    local = os.path.join(os.path.dirname(binary), "rdmesh-local")
    return local if os.path.basename(binary) == "rdmesh" and os.path.isfile(local) else binary


def allocator(binary):
    """The malloc a program is linked with: "mimalloc", "tcmalloc" or glibc's (CMake's
    RDMESH_MALLOC)."""
    try:
        out = subprocess.run(["ldd", engine_binary(binary)], capture_output=True,
                             text=True).stdout
    except OSError:
        return "?"
    for name in ("mimalloc", "tcmalloc"):
        if "lib" + name in out:
            return name
    return "glibc"


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()[:16]


# Every mesher's allocator (mimalloc, linked into rdmesh-local and brepmesh_runner alike) on
# transparent huge pages, as rdmesh's launcher sets it for the program it runs; a value the caller
# set stays.
RUN_ENV = dict({"MIMALLOC_LARGE_OS_PAGES": "1"}, **os.environ)


def run(cmd, timeout):
    """(stdout, stderr, returncode or 'timeout', wall seconds)."""
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=RUN_ENV)
        return p.stdout, p.stderr, p.returncode, time.perf_counter() - t0
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        return out, "", "timeout", time.perf_counter() - t0


# ---------------------------------------------------------------------------------------------
# Ladders. Each yields (group, label, make_cmd(step, out) -> argv, extra record fields).

def rdmesh_ladder(a, diag):
    for tol in [1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5]:
        def cmd(step, out, tol=tol):
            return [a.rdmesh, "mesh", step, "-o", out, "--max-deviation-rel", repr(tol), "--json", "--quiet",
                    "--threads", str(a.threads), "--timeout", str(a.timeout)]
        yield "all", f"tol={tol:g}", cmd, {"tol": tol}


def brepmesh_ladder(a, diag):
    # Absolute deflection r * diag. BRepMesh's deviation is not monotonic in the deflection and its
    # angle bound adds triangles that no deviation needs, so the ladder is dense near the targets
    # and spans three angles; the best front over all of them is taken.
    rs = [1e-2, 5e-3, 2e-3, 1.4e-3, 1.2e-3, 1e-3, 8.5e-4, 7e-4, 4e-4, 2e-4, 1.4e-4, 1e-4, 8.5e-5,
          7e-5, 5e-5, 3.5e-5, 2.5e-5]
    for ang in [0.5, 1.0, 2.0]:
        for r in rs:
            def cmd(step, out, r=r, ang=ang):
                return [a.brepmesh_runner, step, repr(r * diag), str(ang), out]
            yield f"ang={ang}", f"abs={r:g},ang={ang}", cmd, {"deflection_rel": r, "angle": ang}


def gmsh_ladder(a, diag):
    # Mesh.MeshSizeFromCurvature = n elements per 2*pi of curvature, 2 threads (anchors.py).
    for n in [8, 14, 24, 40, 70, 120]:
        def cmd(step, out, n=n):
            return [PYTHON, ANCHORS, "gmsh", step, out, str(n)]
        yield "all", f"n={n}", cmd, {"n_per_2pi": n}


LADDERS = {"rdmesh": rdmesh_ladder, "brepmesh": brepmesh_ladder, "gmsh": gmsh_ladder}
LABELS = {"rdmesh": "rdmesh", "brepmesh": "BRepMesh", "gmsh": "Gmsh"}


# ---------------------------------------------------------------------------------------------
# Pareto front and interpolation (the method of /work/shared/yardstick/sweep.py).

def valid(r):
    """A mesh leaving more than 1% of the faces uncovered is no comparable result."""
    return "error" not in r and r.get("faces_covered", 0) >= 0.99 * r.get("faces", 1)


def pareto(points):
    """Points no other point beats on both triangles and deviation, by increasing triangles."""
    out, best = [], math.inf
    for p in sorted(points, key=lambda p: (p["triangles"], p["hausdorff_rel"])):
        if p["hausdorff_rel"] < best:
            best = p["hausdorff_rel"]
            out.append(p)
    return out


def interpolate(front, eps, key):
    """key (triangles or seconds) where the front crosses deviation eps, log-log between the two
    neighbouring points; the coarsest point when it already meets eps; None if never reached."""
    if not front:
        return None
    if front[0]["hausdorff_rel"] <= eps:
        return front[0][key]
    for p, q in zip(front, front[1:]):
        hp, hq = p["hausdorff_rel"], q["hausdorff_rel"]
        if hp >= eps >= hq and hp > hq:
            s = math.log(eps / hp) / math.log(hq / hp)
            vp, vq = max(p[key], 1e-6), max(q[key], 1e-6)
            return vp * (vq / vp) ** s
    return None


# ---------------------------------------------------------------------------------------------

class Cache:
    def __init__(self, path):
        self.path, self.records, self.scores = path, {}, {}
        if path and os.path.exists(path):
            for line in open(path):
                try:
                    r = json.loads(line)
                    self.records[r["key"]] = r
                    if "msh_sha" in r and "hausdorff_rel" in r:
                        self.scores[(r["model"], r["msh_sha"])] = r
                except (ValueError, KeyError):
                    pass

    def get(self, key):
        return self.records.get(key)

    def put(self, rec):
        self.records[rec["key"]] = rec
        if self.path:
            with open(self.path, "a") as f:
                f.write(json.dumps(rec) + "\n")


def model_info(step):
    out, err, rc, _ = run([MESHBENCH, "info", step], 300)
    info = last_json(out)
    if rc != 0 or info is None:
        raise RuntimeError(f"meshbench info {step} failed: {err[-500:]}")
    return info


SCORE_FIELDS = ("triangles", "nodes", "area_exact", "area_mesh", "area_deficit", "area_err_l1", "worst_face_area_err",
                "hausdorff_rel", "rms_rel", "free_edges", "nonmanifold_edges", "inverted", "degenerate",
                "faces_covered", "faces", "edge_tol_rel", "brep_free_edges")


def mesh_and_score(a, step, mesher, label, cmd, extra, tmp, scores):
    out = os.path.join(tmp, f"{mesher}.msh")
    if os.path.exists(out):
        os.remove(out)
    rec = {"model": os.path.basename(step), "mesher": mesher, "setting": label}
    rec.update(extra)
    argv = cmd(step, out)
    stdout, stderr, rc, wall = run(argv, a.timeout + 30)
    rec["wall"] = round(wall, 3)
    own = last_json(stdout) or {}
    if rc == "timeout" or (mesher == "rdmesh" and isinstance(own.get("error"), dict) and own["error"].get("code") == "deadline_exceeded"):
        rec["error"] = f"timeout after {a.timeout} s"
        rec["timeout"] = True
        return rec
    if rc != 0 or not os.path.exists(out):
        msg = own.get("error") if isinstance(own.get("error"), dict) else (stderr.strip()[-300:] or stdout.strip()[-300:])
        rec["error"] = f"exit {rc}: {msg}"
        return rec
    rec["seconds"] = own.get("seconds", wall)
    if 0 < a.repeat_below and rec["seconds"] < a.repeat_below and a.repeats > 1:
        # A run of a few milliseconds moves by 2x between runs (scheduling, caches): time it
        # again, the same command for every mesher, and keep the median. The mesh is the same
        # each time (the meshers are deterministic), so the first one is scored.
        times = [rec["seconds"]]
        for _ in range(a.repeats - 1):
            again, _, rc2, wall2 = run(cmd(step, out + ".again.msh"), a.timeout + 30)
            if rc2 != 0:
                break
            times.append((last_json(again) or {}).get("seconds", wall2))
        if os.path.exists(out + ".again.msh"):
            os.remove(out + ".again.msh")
        rec["seconds_runs"] = [round(t, 6) for t in times]
        rec["seconds"] = statistics.median(times)
    if own.get("triangles", 0) > a.score_cap:
        # Too costly to score (see README); the ladder stops here.
        rec["error"] = f"not scored: {own['triangles']} triangles > --score-cap {a.score_cap}"
        rec["over_cap"] = own["triangles"]
        os.remove(out)
        return rec
    if mesher == "rdmesh":
        for k in ("faces_failed", "faces_skipped", "requested_deviation", "estimated_deviation"):
            if k in own:
                rec[k] = own[k]
        failed = [f for f in own.get("faces", []) if f.get("status") not in (None, "ok")]
        if failed:
            rec["failed_faces"] = [{"id": f.get("id"), "status": f.get("status"), "reason": f.get("reason", "")[:120]}
                                   for f in failed[:10]]
    # Scoring dominates the run time on B-spline models (a point projection per sample), and
    # BRepMesh often returns the very same mesh for neighbouring settings: score each mesh once.
    rec["msh_sha"] = sha256(out)
    known = scores.get((rec["model"], rec["msh_sha"]))
    if known is not None:
        rec.update({k: v for k, v in known.items() if k in SCORE_FIELDS})
        rec["score_of"] = known["setting"]
        os.remove(out)
        return rec
    sout, serr, src, swall = run([MESHBENCH, "eval", step, out], max(900, a.timeout * 3))
    score = last_json(sout)
    if src != 0 or score is None:
        rec["error"] = f"eval failed ({src}): {serr.strip()[-300:]}"
        return rec
    rec["eval_wall"] = round(swall, 3)
    rec.update(score)
    scores[(rec["model"], rec["msh_sha"])] = rec
    os.remove(out)
    return rec


def sweep_model(a, step, info, cache, tools, tmp):
    name = os.path.basename(step)
    diag = info["bbox_diag"]
    results = []
    for mesher in a.meshers:
        done_groups, group_seen = set(), {}
        for group, label, cmd, extra in LADDERS[mesher](a, diag):
            if group in done_groups:
                continue
            key = "|".join([name, info["sha"], mesher, tools[mesher], label])
            rec = cache.get(key) if (mesher != "rdmesh" or not a.fresh) else None
            if rec is None:
                rec = mesh_and_score(a, step, mesher, label, cmd, extra, tmp, cache.scores)
                rec["key"] = key
                rec["measured"] = datetime.datetime.now().isoformat(timespec="seconds")
                cache.put(rec)
                status = rec.get("error") or (f"{rec['triangles']} tris, dev {rec['hausdorff_rel']:.3g}, "
                                              f"{rec['seconds']:.3g} s")
                log(f"  {name} {mesher} {label}: {status}")
            results.append(rec)
            seen = group_seen.setdefault(group, [])
            seen.append(rec.get("hausdorff_rel", 1.0))
            # Finer settings only cost time past: a timeout, a huge mesh, the finest target met,
            # or a floor (the model's own tolerance) that three more steps did not move.
            # A floor counts only when the setting asks for well under the deviation measured (a
            # plateau of BRepMesh's angle bound or of a dense ladder is no floor); rdmesh's short
            # ladder always runs to the end, so a mesher stuck above its target shows in the report.
            asked = extra.get("tol", extra.get("deflection_rel"))
            floor = (mesher != "rdmesh" and len(seen) >= 4 and min(seen[-3:]) > 0.9 * min(seen[:-3])
                     and (asked is None or asked < seen[-1] / 3))
            if (rec.get("timeout") or rec.get("over_cap") or rec.get("triangles", 0) > TRIANGLE_CAP
                    or rec.get("hausdorff_rel", 1.0) <= min(TARGETS) or floor):
                done_groups.add(group)
    return results


def summarize(records, info):
    """Per mesher: the interpolated figures and the problems seen."""
    s = {}
    for mesher in {r["mesher"] for r in records}:
        mine = [r for r in records if r["mesher"] == mesher]
        fr = pareto([r for r in mine if valid(r)])
        d = {"runs": len(mine), "front": [(r["setting"], r["triangles"], r["hausdorff_rel"]) for r in fr]}
        for eps in TARGETS:
            d[f"tris@{eps:g}"] = interpolate(fr, eps, "triangles")
            d[f"secs@{eps:g}"] = interpolate(fr, eps, "seconds")
        closed = info.get("brep_free_edges", 1) == 0
        d["problems"] = [(r["setting"], p) for r in mine for p in [defects(r, closed)] if p]
        s[mesher] = d
    return s


def geomean(xs):
    xs = [x for x in xs if x and x > 0]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else None


def fmt_n(x):
    if x is None:
        return "—"
    return f"{x:,.0f}" if x >= 100 else f"{x:.3g}"


def fmt_s(x):
    return "—" if x is None else (f"{x:.3g}" if x < 100 else f"{x:.0f}")


def fmt_r(x):
    return "—" if x is None else (f"{x:.2f}" if x >= 0.1 else f"{x:.2g}")


def fmt_eps(x):
    """1e-3 rather than 0.001."""
    m, e = f"{x:.0e}".split("e")
    return f"{m}e{int(e)}"


def ratio(x, y):
    return x / y if x and y else None


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def git(*args):
    try:
        return subprocess.run(["git", "-C", REPO, *args], capture_output=True, text=True, check=True).stdout.strip()
    except (subprocess.CalledProcessError, OSError):
        return "?"


RESULTS_FORMAT = 1
LADDER_TOLS = [1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5]
MAX_LINES = 200


def defects(r, closed):
    """Why a run is not clean, empty when it is: a clean run is one a user could take as it is, no
    error, every face covered, no free edge on a closed B-rep, no inverted triangle, and a measured
    deviation within 1.2x of what was asked (rdmesh: its tolerance; BRepMesh: its deflection; Gmsh
    asks for no deviation). None for a run that was not scored (over --score-cap)."""
    if r.get("over_cap"):
        return None
    if "error" in r:
        return [" ".join(r["error"].split())[:90]]
    p = []
    if r.get("faces_covered", 0) < r.get("faces", 0):
        p.append(f"{r['faces'] - r['faces_covered']} of {r['faces']} faces uncovered")
    if closed and r.get("free_edges", 0) > 0:
        p.append(f"{r['free_edges']} free edges (closed model)")
    if r.get("inverted", 0) > 0:
        p.append(f"{r['inverted']} inverted")
    asked = r.get("tol", r.get("deflection_rel"))
    if asked is not None and r["hausdorff_rel"] > 1.2 * asked:
        p.append(f"deviation {r['hausdorff_rel'] / asked:.2f}x the request")
    return p


def results_of(a, models, infos, summaries, records, meta):
    """Everything render() reads: the input of RESULTS.md, saved as JSON by every run."""
    settings = {"meshers": list(a.meshers), "threads": a.threads, "timeout": a.timeout,
                "score_cap": a.score_cap, "repeat_below": a.repeat_below, "repeats": a.repeats,
                "rdmesh": os.path.relpath(a.rdmesh, REPO) if a.rdmesh.startswith(REPO) else a.rdmesh}
    return {"format": RESULTS_FORMAT, "meta": meta, "settings": settings, "models": models,
            "infos": infos, "summary": summaries, "records": records}


def render(res):
    """RESULTS.md from a run's results (results_of): one current table, at most MAX_LINES lines."""
    meta, st, models = res["meta"], res["settings"], res["models"]
    infos, summaries, records = res["infos"], res["summary"], res["records"]
    ms = st["meshers"]
    anchors = [m for m in ms if m != "rdmesh"]
    corpus = [m for m in models if m not in ANALYTIC]
    analytic = [m for m in models if m in ANALYTIC]

    def fig(name, mesher, key, eps):
        return summaries.get(name, {}).get(mesher, {}).get(f"{key}@{eps:g}")

    def ratios(key, anchor, eps):
        out = {}
        for name in corpus:
            r = ratio(fig(name, "rdmesh", key, eps), fig(name, anchor, key, eps))
            if r:
                out[name] = r
        return out

    def short(name):
        return os.path.splitext(name)[0]

    L = ["# rdmesh benchmark results", ""]
    L.append("Written by `bench/run_bench.py` from the results file below; the next run overwrites it, "
             "so edit the writer, not this file. Re-render without meshing: "
             "`/usr/bin/python3 bench/run_bench.py --results-only RESULTS.json`. How the figures are "
             "made: [README.md](README.md).")
    L.append("")
    if meta["measured_rev"] == "binary":
        what = (f"the binary `{st['rdmesh']}`" + (f", built at commit `{meta['rdmesh_commit']}`"
                                                   if meta.get("rdmesh_commit") else "") +
                f" (repository at `{meta['head']}`)")
    elif meta["measured_rev"] == "working tree":
        what = f"the working tree at `{meta['head']}`" + (
            f", with uncommitted changes in engine/ or clients/cli/ ({meta['dirty']})" if meta["dirty"] else "")
    else:
        what = f"commit `{meta['measured_rev']}` (built from a clean export; repository at `{meta['head']}`)"
    peers = []
    if "brepmesh" in ms:
        peers.append(f"BRepMesh of OCCT {meta['occt']} (`bench/brepmesh_runner`, InParallel)")
    if "gmsh" in ms:
        peers.append(f"Gmsh {meta['gmsh']} (Debian python3-gmsh {meta['gmsh_deb']}, 2 threads)")
    fresh = sum(1 for r in records if r.get("measured", "") >= meta.get("started", "~"))
    L += ["| | |", "|---|---|",
          f"| rdmesh measured | {what}; `--threads {st['threads']}`; sha256 {meta['rdmesh_sha']} |",
          f"| peers | {'; '.join(peers) or 'none'}; allocators: {meta.get('malloc', '?')} |",
          f"| machine | {meta['nproc']} cores, {meta['cpu']}; load average {meta['load0']} at the start, "
          f"{meta['load1']} at the end (a shared machine: seconds are indicative, triangles exact) |",
          f"| run | ended {meta['date']} after {meta['elapsed'] / 60:.0f} min; {len(records)} meshing runs, "
          f"{fresh} of them measured in this run, the others from the cache |",
          f"| command | `{meta['command']}` |",
          f"| results file | `{meta.get('results', '?')}` |", ""]

    L.append("## Headline\n")
    L.append("rdmesh / peer, geometric mean over the corpus models where both reach the target (n); each "
             "figure interpolated along the mesher's Pareto front at a measured deviation of 1e-3 and 1e-4 "
             "of the bounding-box diagonal. Below 1, rdmesh needs fewer.\n")
    L += ["| | @1e-3 | @1e-4 |", "|---|---:|---:|"]
    for m in anchors:
        for key, what in (("tris", "triangles"), ("secs", "seconds")):
            cells = []
            for eps in TARGETS:
                rs = ratios(key, m, eps)
                g = geomean(list(rs.values()))
                cells.append(f"**{fmt_r(g)}** (n={len(rs)})" if g else "—")
            L.append(f"| {what}, rdmesh / {LABELS[m]} | " + " | ".join(cells) + " |")
        cells = []
        for eps in TARGETS:
            rs = ratios("secs", m, eps)
            worst = max(rs, key=rs.get) if rs else None
            cells.append(f"{fmt_r(rs[worst])} `{short(worst)}`" if worst else "—")
        L.append(f"| largest seconds ratio, rdmesh / {LABELS[m]} | " + " | ".join(cells) + " |")
    for name in analytic:
        cells = []
        for eps in TARGETS:
            v, mn = fig(name, "rdmesh", "tris", eps), theoretical_minimum(name, eps)
            cells.append(f"{v / mn:.2f}x ({fmt_n(v)})" if v and mn else "—")
        L.append(f"| {ANALYTIC[name]}, rdmesh triangles / minimum | " + " | ".join(cells) + " |")
    rd = [r for r in records if r["mesher"] == "rdmesh" and "hausdorff_rel" in r and "tol" in r]

    def worst_delivered(tols):
        xs = [(r["hausdorff_rel"] / r["tol"], r["model"]) for r in rd if r["tol"] in tols]
        if not xs:
            return "—"
        x, name = max(xs)
        return f"{x:.2f}" + (f" `{short(name)}`" if x > 1.0 else "")

    if rd:
        L.append(f"| delivered / requested deviation, rdmesh, largest over the {len(models)} models | "
                 + " | ".join(worst_delivered([eps]) for eps in TARGETS) + " |")
    L.append("")
    if rd:
        L.append(f"- Delivered / requested over every step of rdmesh's ladder ({fmt_eps(LADDER_TOLS[0])} to "
                 f"{fmt_eps(min(r['tol'] for r in rd))}): at most {worst_delivered(LADDER_TOLS)}.")
    clean_cells = []
    for m in ms:
        verdicts = [defects(r, infos[r["model"]].get("brep_free_edges", 1) == 0)
                    for r in records if r["mesher"] == m and r["model"] in infos]
        scored = [v for v in verdicts if v is not None]
        clean_cells.append(f"{LABELS[m]} {sum(1 for v in scored if not v)} of {len(scored)}")
    L.append("- Clean runs, every step of every ladder (bench/README.md, \"Clean\"): " + ", ".join(clean_cells) + ".")
    L.append("")

    head = ["model", "faces"]
    for key in ("triangles", "seconds"):
        head += [f"{key} {LABELS[m]}" for m in ms] + [f"rd/{LABELS[m]}" for m in anchors]
    for eps in TARGETS:
        L.append(f"## Per model at {fmt_eps(eps)}\n")
        L.append("| " + " | ".join(head) + " |")
        L.append("|---|---:|" + "---:|" * (len(head) - 2))
        for name in models:
            row = [f"`{short(name)}`", str(infos[name]["faces"])]
            for key, fmt in (("tris", fmt_n), ("secs", fmt_s)):
                row += [fmt(fig(name, m, key, eps)) for m in ms]
                row += [fmt_r(ratio(fig(name, "rdmesh", key, eps), fig(name, m, key, eps))) for m in anchors]
            L.append("| " + " | ".join(row) + " |")
        L.append("")
    if analytic:
        L.append("Analytic minimum: unit sphere ~1,396 triangles at 1e-3 of the diagonal, scaling as "
                 "1/deviation; cylinder r=1 h=4: n = ceil(pi / acos(1 - eps diag)) segments per circle, "
                 "2n side triangles and n-2 per cap.\n")

    if rd:
        L.append("## Delivered / requested deviation, rdmesh\n")
        L.append("The yardstick's measured deviation over the requested `--max-deviation-rel`, every step "
                 "of the ladder (a ladder stops once 1e-4 is met); bold above 1.\n")
        L.append("| model | " + " | ".join(fmt_eps(t) for t in LADDER_TOLS) + " |")
        L.append("|---|" + "---:|" * len(LADDER_TOLS))
        for name in models:
            cells = []
            for t in LADDER_TOLS:
                r = next((r for r in rd if r["model"] == name and r["tol"] == t), None)
                if r is None:
                    e = any(x["mesher"] == "rdmesh" and x["model"] == name and x.get("tol") == t for x in records)
                    cells.append("error" if e else "")
                else:
                    x = r["hausdorff_rel"] / t
                    cells.append(f"**{x:.2f}**" if x > 1.0 else f"{x:.2f}")
            L.append(f"| `{short(name)}` | " + " | ".join(cells) + " |")
        L.append("")

    L.append("## Runs that are not clean\n")
    problems = []
    for name in models:
        for m in ms:
            probs = summaries[name].get(m, {}).get("problems", [])
            if probs:
                items = "; ".join(f"{lab}: {', '.join(p)}" for lab, p in probs[:3])
                more = f"; {len(probs) - 3} more" if len(probs) > 3 else ""
                problems.append(f"- `{short(name)}` {LABELS[m]} ({len(probs)} of "
                                f"{summaries[name][m]['runs']} runs): {items}{more}")
    # The default set fits in MAX_LINES; larger sets grow the per-model tables, and then this list
    # is the part that gives way.
    room = max(1, MAX_LINES - len(L) - 2)
    if len(problems) > room:
        problems = problems[:room - 1] + [f"- … {len(problems) - room + 1} more in the results file"]
    L += problems or ["None."]
    L.append("")
    return "\n".join(L)


def cmake_build(src, build, targets, extra=()):
    if not os.path.exists(os.path.join(build, "build.ninja")):
        subprocess.run(["cmake", "-S", src, "-B", build, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                        "-DRDMESH_BUILD_SERVER=OFF", "-DRDMESH_BUILD_TESTS=OFF", *extra], check=True,
                       stdout=subprocess.DEVNULL)
    subprocess.run(["ninja", "-C", build, "-j2", *targets], check=True, stdout=subprocess.DEVNULL)


def build_snapshot(a, rev):
    """rdmesh built from a clean export of commit `rev` (the shared tree may hold others'
    uncommitted edits), in BUILD/snapshot/REV; returns the binary."""
    root = os.path.join(a.build_dir, "snapshot", rev)
    binary = os.path.join(root, "build", "bin", "rdmesh")
    if os.path.exists(binary):
        return binary
    src = os.path.join(root, "src")
    os.makedirs(src, exist_ok=True)
    log(f"building rdmesh at commit {rev} in {root} ...")
    tar = subprocess.run(["git", "-C", REPO, "archive", rev, "CMakeLists.txt", "engine", "clients/cli"],
                         capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", src], input=tar, check=True)
    cmake_build(src, os.path.join(root, "build"), ["rdmesh"], ["-DRDMESH_BUILD_BENCH=OFF"])
    return binary


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", nargs="+", help="corpus file names (with or without extension) or paths; 'all' = whole corpus")
    ap.add_argument("--quick", action="store_true", help=f"the {len(QUICK)} small models of the quick set")
    ap.add_argument("--out", default=os.path.join(HERE, "RESULTS.md"), help="Markdown report (default bench/RESULTS.md)")
    ap.add_argument("--build-dir", default=os.path.join(REPO, "build-bench"))
    ap.add_argument("--rdmesh-rev", default="HEAD",
                    help="commit whose rdmesh is measured, built from a clean export in BUILD/snapshot/ "
                         "(default HEAD); 'worktree' = the working tree as it is, built in BUILD")
    ap.add_argument("--rdmesh", default=None, help="an rdmesh binary to measure instead (no build)")
    ap.add_argument("--rdmesh-commit", default=None,
                    help="with --rdmesh: the commit the binary was built from, named in the report")
    ap.add_argument("--results", default=None,
                    help="where the run's results are saved as JSON, the input of RESULTS.md "
                         "(default BUILD/bench_results.json)")
    ap.add_argument("--results-only", metavar="FILE.json", default=None,
                    help="write --out from a saved results file, without building or meshing")
    ap.add_argument("--meshers", default="rdmesh,brepmesh,gmsh")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 2, help="rdmesh --threads (default nproc)")
    ap.add_argument("--timeout", type=float, default=300, help="seconds per meshing run (default 300)")
    ap.add_argument("--score-cap", type=int, default=100_000,
                    help="meshes with more triangles are not scored and end their ladder (default 100000)")
    ap.add_argument("--repeat-below", type=float, default=0.05,
                    help="time a meshing run that took less than this many seconds again, --repeats "
                         "times in all, and keep the median (default 0.05; 0 = off)")
    ap.add_argument("--repeats", type=int, default=5, help="runs timed for --repeat-below (default 5)")
    ap.add_argument("--no-analytic", action="store_true", help="skip the sphere and cylinder")
    ap.add_argument("--no-build", action="store_true", help="use the binaries as they are")
    ap.add_argument("--fresh", action="store_true", help="rerun rdmesh even when the cache has this binary's results")
    ap.add_argument("--no-cache", action="store_true",
                    help="measure everything again, reading no earlier record; this run's records go "
                         "to BUILD/bench_run.jsonl (started afresh), which --resume reads")
    ap.add_argument("--resume", action="store_true",
                    help="go on with the last --no-cache run where it stopped (its BUILD/bench_run.jsonl)")
    a = ap.parse_args()
    if a.results_only:
        with open(a.results_only) as f:
            res = json.load(f)
        if res.get("format") != RESULTS_FORMAT:
            sys.exit(f"{a.results_only}: not a results file of this run_bench.py (format {res.get('format')})")
        md = render(res)
        if a.out:
            with open(a.out, "w") as f:
                f.write(md)
            log(f"wrote {a.out} from {a.results_only}")
        else:
            print(md)
        return
    t_start = time.time()
    started = datetime.datetime.now().isoformat(timespec="seconds")
    load0 = " ".join(open("/proc/loadavg").read().split()[:3])

    a.brepmesh_runner = os.path.join(a.build_dir, "bin", "brepmesh_runner")
    a.meshers = [m.strip() for m in a.meshers.split(",") if m.strip()]
    # The shared yardstick may be read-only: scripts/yardstick.sh builds a copy to run.
    global MESHBENCH, ANCHORS
    built = subprocess.run(["sh", os.path.join(REPO, "scripts", "yardstick.sh")], check=True,
                           capture_output=True, text=True).stdout.strip().splitlines()[-1]
    MESHBENCH, ANCHORS = os.path.join(built, "meshbench"), os.path.join(built, "anchors.py")
    if not a.no_build:
        cmake_build(REPO, a.build_dir, ["brepmesh_runner"] + (["rdmesh"] if a.rdmesh_rev == "worktree" else []))
    a.measured_rev = "working tree" if a.rdmesh is None else "binary"
    if a.rdmesh is None and a.rdmesh_rev != "worktree":
        # The newest commit at or before REV that changed what rdmesh is built from: commits
        # elsewhere (docs, server, tests) reuse the same build and cached results.
        a.measured_rev = git("log", "-1", "--format=%h", "--abbrev=10", a.rdmesh_rev, "--",
                             "engine", "clients/cli", "CMakeLists.txt")
        a.rdmesh = build_snapshot(a, a.measured_rev)
    a.rdmesh = a.rdmesh or os.path.join(a.build_dir, "bin", "rdmesh")
    gmsh_version = "n/a"
    if "gmsh" in a.meshers:
        p = subprocess.run([PYTHON, "-c", "import gmsh; print(gmsh.__version__)"], capture_output=True, text=True)
        if p.returncode != 0:
            log("python3-gmsh not installed: Gmsh skipped")
            a.meshers.remove("gmsh")
        else:
            gmsh_version = p.stdout.strip()
    occt = "?"
    try:
        occt = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "libocct-modeling-algorithms-7.6"],
                              capture_output=True, text=True).stdout.strip() or "7.6"
    except OSError:
        pass
    runner_malloc = allocator(a.brepmesh_runner)
    tools = {"rdmesh": "rdmesh-" + sha256(a.rdmesh) + "-" + sha256(engine_binary(a.rdmesh))
             if "rdmesh" in a.meshers else "",
             "brepmesh": f"occt-{occt}-runner-{sha256(os.path.join(HERE, 'brepmesh_runner.cpp'))}"
                         + ("" if runner_malloc == "glibc" else "-" + runner_malloc),
             "gmsh": f"gmsh-{gmsh_version}"}

    names = a.models or (QUICK if a.quick else DEFAULT)
    if names == ["all"]:
        names = sorted(f for f in os.listdir(CORPUS) if f.endswith((".stp", ".step")))
    steps = []
    for n in names:
        if os.path.exists(n):
            steps.append(os.path.abspath(n))
            continue
        cands = [f for f in os.listdir(CORPUS) if f == n or os.path.splitext(f)[0] == n]
        if not cands:
            sys.exit(f"no model {n} in {CORPUS}")
        steps.append(os.path.join(CORPUS, cands[0]))
    if not a.no_analytic:
        steps += [os.path.join(YARD, "models", m) for m in ANALYTIC]

    os.makedirs(a.build_dir, exist_ok=True)
    # A --no-cache run keeps its own records, so that a run longer than a sitting can be resumed;
    # the shared cache is neither read nor written by it.
    run_records = os.path.join(a.build_dir, "bench_run.jsonl")
    if a.no_cache and not a.resume and os.path.exists(run_records):
        os.remove(run_records)
    cache = Cache(run_records if a.no_cache or a.resume else os.path.join(a.build_dir, "bench_cache.jsonl"))
    tmp = tempfile.mkdtemp(prefix="rdmesh-bench-")
    models, infos, summaries, records = [], {}, {}, []
    try:
        for i, step in enumerate(steps):
            name = os.path.basename(step)
            info = model_info(step)
            info["sha"] = sha256(step)
            log(f"[{i + 1}/{len(steps)}] {name}: {info['faces']} faces, diag {info['bbox_diag']:.4g}")
            recs = sweep_model(a, step, info, cache, tools, tmp)
            models.append(name)
            infos[name] = info
            records += recs
            summaries[name] = summarize(recs, info)
            for m in a.meshers:
                s = summaries[name][m]
                log(f"    {m:9s} tris@1e-3 {fmt_n(s['tris@0.001'])}  tris@1e-4 {fmt_n(s['tris@0.0001'])}  "
                    f"secs@1e-3 {fmt_s(s['secs@0.001'])}  secs@1e-4 {fmt_s(s['secs@0.0001'])}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    dirty = git("status", "--porcelain", "--", "engine", "clients/cli")
    meta = {
        "date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M %Z").strip() or time.ctime(),
        "started": started, "rdmesh_commit": a.rdmesh_commit,
        "elapsed": time.time() - t_start,
        "nproc": os.cpu_count(), "cpu": cpu_model(), "load0": load0,
        "load1": " ".join(open("/proc/loadavg").read().split()[:3]),
        "head": git("rev-parse", "--short=10", "HEAD"), "measured_rev": a.measured_rev,
        "engine_commit": git("log", "-1", "--format=%h",
                             a.measured_rev if a.measured_rev not in ("working tree", "binary") else "HEAD",
                             "--", "engine"),
        "dirty": a.measured_rev == "working tree" and len(dirty.splitlines()) and f"{len(dirty.splitlines())} files",
        "rdmesh_sha": tools["rdmesh"].replace("rdmesh-", ""),
        "occt": occt, "gmsh": gmsh_version,
        "malloc": f"rdmesh {allocator(a.rdmesh)}, brepmesh_runner {allocator(a.brepmesh_runner)}",
        "gmsh_deb": subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-gmsh"], capture_output=True,
                                   text=True).stdout.strip() or "n/a",
        "command": "/usr/bin/python3 " + " ".join(shlex.quote(x) for x in
                                                   [os.path.relpath(sys.argv[0], REPO) if sys.argv[0].startswith(REPO) else sys.argv[0]] + sys.argv[1:]),
    }
    results = a.results or os.path.join(a.build_dir, "bench_results.json")
    meta["results"] = os.path.relpath(results, REPO) if os.path.abspath(results).startswith(REPO) else results
    res = results_of(a, models, infos, summaries, records, meta)
    with open(results, "w") as f:
        json.dump(res, f, indent=1)
    md = render(res)
    print(md)
    if a.out:
        with open(a.out, "w") as f:
            f.write(md)
    log(f"wrote {results}" + (f" and {a.out}" if a.out else ""))


if __name__ == "__main__":
    main()
