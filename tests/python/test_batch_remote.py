"""`rdmesh-py batch` and Client.batch (clients/python/rdmesh/batch.py, docs/BATCH.md "Through the
service"): a tree of models through rdmeshd into a mirrored tree of meshes and
OUTDIR/manifest.jsonl with the C++ `rdmesh batch`'s fields and statuses."""

import hashlib
import io
import json
import os
import shutil
import signal
import subprocess
import time

import grpc

from conftest import CUBE, CYLINDER, DATA, EIGHT_CYL, NIST, RDMESH_PY, Daemon, wait_until
from test_isolation import _oriented_edge_chain

from rdmesh import batch as rbatch

# The C++ batch's manifest fields (tests/cli/test_batch.py), then the gRPC status of the call.
FIELDS = ["path", "sha256", "bytes", "status", "reason", "faces", "faces_failed", "triangles",
          "requested_deviation", "estimated_deviation", "seconds", "output", "reader", "exit_code",
          "signal", "options", "grpc_code"]
GOOD = [CUBE, CYLINDER, NIST, EIGHT_CYL]
SLOW = DATA / "fuzz" / "slow_mesher_absurd_point.step"  # meshes for ~48 s: stopped at --timeout
KICAD = DATA / "kicad" / "LED_D3.0mm_Horizontal_O1.27mm_Z2.0mm.step"


def batch(address, *args, timeout=120):
    """Runs `rdmesh-py --address ADDRESS batch ARGS --json`; (exit code, summary, stderr)."""
    proc = subprocess.run(["/usr/bin/python3", str(RDMESH_PY), "--address", address, "batch",
                           *map(str, args), "--json"], capture_output=True, text=True,
                          timeout=timeout)
    lines = proc.stdout.strip().splitlines()
    summary = json.loads(lines[-1]) if lines and lines[-1].startswith("{") else None
    return proc.returncode, summary, proc.stderr


def run_cli(capsys, address, *args):
    """The same in this process (rdmesh.cli.main): no interpreter start-up per run."""
    from rdmesh.cli import main
    capsys.readouterr()
    code = main(["--address", address, "batch", *map(str, args), "--json"])
    captured = capsys.readouterr()
    lines = captured.out.strip().splitlines()
    summary = json.loads(lines[-1]) if lines and lines[-1].startswith("{") else None
    return code, summary, captured.err


def manifest(out):
    with open(out / "manifest.jsonl") as file:
        return {e["path"]: e for e in map(json.loads, file)}


def msh_triangles(path):
    """The triangle count of an MSH 4.1 file (the $Elements header's second number)."""
    lines = path.read_text().splitlines()
    return int(lines[lines.index("$Elements") + 1].split()[1])


def good_tree(root):
    """The four bundled models and the KiCad one in a tree, plus a file that is not a model."""
    (root / "a").mkdir(parents=True)
    (root / "a" / "b").mkdir()
    for model in (CUBE, CYLINDER):
        shutil.copy(model, root / "a" / model.name)
    for model in (NIST, EIGHT_CYL):
        shutil.copy(model, root / "a" / "b" / model.name)
    shutil.copy(KICAD, root / "LED.STEP")  # upper case: still a model file
    (root / "notes.txt").write_text("not a model\n")
    return {root / "a" / CUBE.name: "a/cq_red_cube_blue_cylinder.msh",
            root / "a" / CYLINDER.name: "a/axom_sliced_cylinder.msh",
            root / "a" / "b" / NIST.name: "a/b/nist_mbe_pmi_11.msh",
            root / "a" / "b" / EIGHT_CYL.name: "a/b/pyocc_eight_cyl.msh",
            root / "LED.STEP": "LED.msh"}


def test_bad_files_cost_themselves_only(daemon, tmp_path):
    """Good models ok, a garbage file unreadable, one that meshes past --timeout timed_out,
    outputs mirroring the inputs, exit 1; then a model that crashes the server's reader:
    crashed (in a run of its own, without --timeout: its parse takes seconds)."""
    models = tmp_path / "models"
    expected = good_tree(models)
    (models / "a" / "garbage.stp").write_text("this is not STEP\n")
    shutil.copy(SLOW, models / "slow.step")
    out = tmp_path / "out"
    start = time.monotonic()
    code, summary, err = batch(daemon.address, models, "-o", out, "--timeout", 4, "--jobs", 4)
    seconds = time.monotonic() - start
    assert code == 1, err
    entries = manifest(out)
    assert len(entries) == 7
    for entry in entries.values():
        assert list(entry) == FIELDS
    for path, output in expected.items():
        e = entries[str(path)]
        assert e["status"] == "ok", e
        assert e["output"] == output and e["grpc_code"] == "OK"
        assert e["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
        assert e["bytes"] == path.stat().st_size
        assert e["faces"] > 0 and e["faces_failed"] == 0 and e["triangles"] > 0
        assert 0 < e["estimated_deviation"] and 0 < e["requested_deviation"]
        assert msh_triangles(out / output) == e["triangles"]
    garbage = entries[str(models / "a" / "garbage.stp")]
    assert garbage["status"] == "unreadable" and garbage["grpc_code"] == "INVALID_ARGUMENT"
    assert "not a STEP file" in garbage["reason"] and garbage["output"] is None
    slow = entries[str(models / "slow.step")]
    assert slow["status"] == "timed_out" and slow["grpc_code"] == "DEADLINE_EXCEEDED", slow
    assert "no result within --timeout 4 s (meshing)" in slow["reason"]
    assert 3.9 < slow["seconds"] < 8.0
    # Nothing but the meshes, the manifest and the lock: no partial files, no empty folders.
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert written == sorted(list(expected.values()) + [".rdmesh-batch.lock",
                                                        "manifest.jsonl"])
    assert summary["counts"] == {"ok": 5, "failed": 0, "crashed": 0, "timed_out": 1,
                                 "unreadable": 1}
    assert summary["meshed"] == 7 and summary["skipped"] == 0
    assert summary["slowest"][0] == str(models / "slow.step")
    assert "unreadable: %s" % (models / "a" / "garbage.stp") in err
    # The slow file cost its own --timeout: the others ran beside it.
    assert seconds < 4 + 15, seconds

    crashing = tmp_path / "crashing"
    crashing.mkdir()
    (crashing / "chain.step").write_bytes(_oriented_edge_chain())
    shutil.copy(CUBE, crashing / "cube.step")
    summary = daemon.client().batch([str(crashing)], str(tmp_path / "out2"), jobs=2)
    assert summary.exit_code == 1
    entries = manifest(tmp_path / "out2")
    chain = entries[str(crashing / "chain.step")]
    assert chain["status"] == "crashed" and chain["grpc_code"] == "INVALID_ARGUMENT", chain
    assert "the STEP reader crashed (SIGSEGV)" in chain["reason"] and chain["output"] is None
    assert entries[str(crashing / "cube.step")]["status"] == "ok"
    assert daemon.alive()


def test_resume_skips_what_is_done(daemon, tmp_path, capsys):
    models = tmp_path / "models"
    expected = good_tree(models)
    out = tmp_path / "out"
    listing = tmp_path / "list.txt"
    listing.write_text("# the good ones\nmodels/a\n\nmodels/LED.STEP\n")
    code, first, err = run_cli(capsys, daemon.address, "@%s" % listing, "-o", out, "--jobs", 3)
    assert code == 0, err
    assert first["meshed"] == 5 and first["counts"]["ok"] == 5
    before = manifest(out)
    # Listed relative to the list's folder: mirrored as models/...
    assert sorted(e["output"] for e in before.values()) == sorted(
        "models/" + o for o in expected.values())
    stamps = {p: (out / e["output"]).stat().st_mtime_ns for p, e in before.items()}

    # A killed run's leftovers: a partial file and a torn last manifest line.
    partial = out / "models" / "a" / ".x.msh.partial.msh"
    partial.write_text("half")
    with open(out / "manifest.jsonl", "a") as file:
        file.write('{"path": "/torn", "sta')
    # One model changes (a comment in its header): done again; the rest skipped.
    changed = models / "a" / CUBE.name
    changed.write_bytes(CUBE.read_bytes().replace(b"HEADER;", b"HEADER;\n/* v2 */", 1))
    code, second, err = run_cli(capsys, daemon.address, "@%s" % listing, "-o", out)
    assert code == 0, err
    assert second["skipped"] == 4 and second["meshed"] == 1
    after = manifest(out)
    assert after[str(changed)]["sha256"] != before[str(changed)]["sha256"]
    for path, entry in before.items():
        if path != str(changed):
            assert after[path] == entry
            assert (out / entry["output"]).stat().st_mtime_ns == stamps[path]
    assert not partial.exists()
    assert "/torn" not in after and len(after) == 5

    # Other mesh options: every file again, and the options recorded.
    code, third, err = run_cli(capsys, daemon.address, "@%s" % listing, "-o", out,
                             "--max-deviation-rel", "2e-3")
    assert code == 0 and third["meshed"] == 5, err
    assert all(e["options"] == {"--max-deviation-rel": "0.002"} for e in manifest(out).values())
    # A deleted output: that file again.
    os.remove(out / after[str(models / "LED.STEP")]["output"])
    code, fourth, err = run_cli(capsys, daemon.address, "@%s" % listing, "-o", out,
                              "--max-deviation-rel", "2e-3")
    assert code == 0 and fourth["meshed"] == 1 and fourth["skipped"] == 4, err


def test_usage_errors(daemon, tmp_path, capsys):
    code, _, err = run_cli(capsys, daemon.address, CUBE, "-o", tmp_path / "o", "--format", "glb")
    assert code == 2 and "--format glb: not written by rdmesh-py" in err
    code, _, err = run_cli(capsys, daemon.address, CUBE, "-o", tmp_path / "o", "--format", "xyz")
    assert code == 2 and "msh, stl, obj, ply, vtu" in err
    code, _, err = run_cli(capsys, daemon.address, tmp_path / "missing.step", "-o", tmp_path / "o")
    assert code == 2 and "no such file or folder" in err
    (tmp_path / "x").mkdir()
    (tmp_path / "y").mkdir()
    shutil.copy(CUBE, tmp_path / "x" / "m.step")
    shutil.copy(CUBE, tmp_path / "y" / "m.step")
    code, _, err = run_cli(capsys, daemon.address, tmp_path / "x", tmp_path / "y", "-o",
                           tmp_path / "o")
    assert code == 2 and "would both write 'm.msh'" in err
    # Options the server refuses: refused once, before anything runs (as the C++ batch).
    code, _, err = run_cli(capsys, daemon.address, CUBE, "-o", tmp_path / "o",
                           "--max-deviation-rel", "1e-9")
    assert code == 2 and "the server refuses the mesh options: max_deviation_rel" in err
    code, _, err = run_cli(capsys, "127.0.0.1:1", CUBE, "-o", tmp_path / "o")
    assert code == 2 and "cannot reach rdmeshd" in err
    assert not (tmp_path / "o" / "manifest.jsonl").exists()


def test_client_batch_api(daemon, tmp_path):
    shutil.copy(CUBE, tmp_path / "cube.step")
    shutil.copy(CUBE, tmp_path / "cube.stp")  # same stem: both keep their extension
    lines, shown = [], []
    summary = daemon.client().batch([str(tmp_path)], str(tmp_path / "out"), format="ply",
                                    jobs=2, progress=shown.append, problem=lines.append,
                                    max_deviation_rel=2e-3)
    assert summary.exit_code == 0 and summary.counts["ok"] == 2 and not lines
    outputs = sorted(e["output"] for e in summary.entries)
    assert outputs == ["cube.step.ply", "cube.stp.ply"]
    header = (tmp_path / "out" / "cube.step.ply").read_text().split("end_header")[0]
    assert "property int face_id" in header and "property double deviation" in header
    assert shown and shown[-1].done == 2 and shown[-1].total == 2
    # Progress and problems as a terminal shows them.
    tty = io.StringIO()
    tty.isatty = lambda: True
    display = rbatch.Display(False, tty)
    display.progress(rbatch.BatchProgress(done=3, total=10, processed=3, failures=1,
                                          seconds=6.0))
    display.problem("crashed: x.step: the STEP reader crashed (SIGSEGV)")
    assert tty.getvalue() == ("\r\033[Krdmesh-py batch: 3/10 done, 1 not ok, 30.0 files/min, "
                              "ETA 14s\r\033[Krdmesh-py batch: crashed: x.step: the STEP reader "
                              "crashed (SIGSEGV)\n")


def test_ctrl_c_finishes_running_files_then_kill(daemon, tmp_path):
    """First Ctrl-C: the running file finishes and is recorded, no other starts (exit 4). Ctrl-C
    twice: the running call is cancelled, nothing recorded, no partial file."""
    models = tmp_path / "models"
    models.mkdir()
    shutil.copy(SLOW, models / "a_slow.step")  # sorted first: --jobs 1 runs it first
    for model in GOOD:
        shutil.copy(model, models / model.name)
    out = tmp_path / "out"
    cmd = ["/usr/bin/python3", str(RDMESH_PY), "--address", daemon.address, "batch", str(models),
           "-o", str(out), "--jobs", "1", "--timeout", "3", "--json"]
    status = daemon.client()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert wait_until(lambda: status.server_status().active_jobs == 1, 30) is not None
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=30)
    assert proc.returncode == 4, stderr
    entries = manifest(out)
    assert list(entries) == [str(models / "a_slow.step")]
    assert entries[str(models / "a_slow.step")]["status"] == "timed_out"
    summary = json.loads(stdout.strip().splitlines()[-1])
    assert summary["interrupted"] and summary["not_done"] == 4

    assert wait_until(lambda: status.server_status().active_jobs == 0, 10) is not None
    older = out / "a_slow.msh"  # as an earlier run with other options would have left it
    older.write_text("an older mesh")
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert wait_until(lambda: status.server_status().active_jobs == 1, 30) is not None
    start = time.monotonic()
    proc.send_signal(signal.SIGINT)
    time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=30)
    assert proc.returncode == 4, stderr
    assert time.monotonic() - start < 5.0
    assert manifest(out)[str(models / "a_slow.step")] == entries[str(models / "a_slow.step")]
    assert not [p for p in out.rglob("*partial*")]
    assert older.read_text() == "an older mesh"  # a stopped file is not done: nothing removed


def test_replicas_behind_nginx(daemon, tmp_path):
    """Two replicas behind the shipped nginx config: the same manifest as one daemon's (each
    model's calls routed to one replica by its sha256, so each file is uploaded once)."""
    from test_routing import Nginx
    models = tmp_path / "models"
    good_tree(models)
    replicas = [Daemon(tmp_path / ("r%d.log" % i), ["--max-jobs", "1"]) for i in range(2)]
    nginx = None
    try:
        for replica in replicas:
            replica.wait_serving()
        nginx = Nginx(tmp_path, [r.address for r in replicas])
        code, summary, err = batch(nginx.address, models, "-o", tmp_path / "fleet", "--jobs", 4)
        assert code == 0, err
        assert summary["counts"]["ok"] == 5
        one = daemon.client().batch([str(models)], str(tmp_path / "one"), jobs=4)
        assert one.exit_code == 0
        fleet, one = manifest(tmp_path / "fleet"), manifest(tmp_path / "one")
        keys = ("sha256", "status", "faces", "triangles", "estimated_deviation", "output")
        assert {p: [e[k] for k in keys] for p, e in fleet.items()} == \
            {p: [e[k] for k in keys] for p, e in one.items()}
        # Every model was uploaded once, to one replica.
        uploads = sum(r.log().count("UploadModel from") for r in replicas)
        assert uploads == 5, [r.log() for r in replicas]
    finally:
        if nginx is not None:
            nginx.stop()
        for replica in replicas:
            assert replica.stop() == 0


def test_statuses_from_grpc_codes():
    """The server's answers (docs/SERVICE.md, "Crash isolation") as the C++ batch's statuses."""
    code = grpc.StatusCode
    cases = [
        (code.DEADLINE_EXCEEDED, "Deadline Exceeded", "mesh", "timed_out"),
        (code.RESOURCE_EXHAUSTED, "cannot use model 'a.step': the worker passed its CPU time "
         "limit of 300 s (--worker-cpu-seconds) while reading the model", "upload", "timed_out"),
        (code.INVALID_ARGUMENT, "cannot use model 'a.step': the STEP reader crashed (SIGSEGV) on "
         "this model", "upload", "crashed"),
        (code.INVALID_ARGUMENT, "cannot use model 'a.step': the STEP reader crashed (SIGSEGV) on "
         "this model before; refused without parsing it again", "upload", "crashed"),
        (code.INVALID_ARGUMENT, "the mesher crashed (SIGABRT) on this model", "mesh", "crashed"),
        (code.RESOURCE_EXHAUSTED, "the worker reached its memory limit of 8192 MiB "
         "(--worker-memory) while meshing the model", "mesh", "crashed"),
        (code.RESOURCE_EXHAUSTED, "the worker was killed (SIGKILL, most likely out of memory) "
         "while reading the model", "upload", "crashed"),
        (code.INTERNAL, "something broke", "mesh", "crashed"),
        (code.INVALID_ARGUMENT, "cannot use model 'b.step': not a STEP file", "upload",
         "unreadable"),
        (code.INVALID_ARGUMENT, "cannot use model 'b.step': broken STEP data at #38", "mesh",
         "unreadable"),
        (code.RESOURCE_EXHAUSTED, "the model is 300000000 bytes, more than the server's "
         "--max-model-bytes of 268435456", "upload", "unreadable"),
        (code.INVALID_ARGUMENT, "face id 99 is beyond the model's 9 faces", "mesh", "failed"),
        (code.RESOURCE_EXHAUSTED, "the mesh passes the server's --max-triangles limit of 10 "
         "triangles; ask for a coarser mesh or a max_triangles budget", "mesh", "failed"),
        (code.FAILED_PRECONDITION, "face 3 failed", "mesh", "failed"),
    ]
    for grpc_code, details, phase, status in cases:
        assert rbatch.classify(grpc_code, details, phase) == status, details
    assert rbatch._transient(code.UNAVAILABLE, "the server is shutting down")
    assert rbatch._transient(code.RESOURCE_EXHAUSTED, "the job queue is full (2 running, 16 "
                                                      "waiting); retry later")
    assert not rbatch._transient(code.RESOURCE_EXHAUSTED, "the worker reached its memory limit")


def test_inputs_as_the_cpp_batch_collects_them(daemon, tmp_path):
    """A listed file that does not exist is recorded unreadable (the others run); a list whose
    entries lie outside its folder mirrors relative to the deepest folder holding them."""
    (tmp_path / "data" / "p" / "q").mkdir(parents=True)
    (tmp_path / "lists").mkdir()
    shutil.copy(CUBE, tmp_path / "data" / "p" / "cube.step")
    shutil.copy(CYLINDER, tmp_path / "data" / "p" / "q" / "cyl.step")
    listing = tmp_path / "lists" / "l.txt"
    listing.write_text("%s\n../data/p/q\n../data/p/gone.step\n"
                       % (tmp_path / "data" / "p" / "cube.step"))
    inputs = rbatch.collect_inputs(["@%s" % listing], ".stl", str(tmp_path / "out"))
    assert [(os.path.relpath(i.path, tmp_path), i.output) for i in inputs] == [
        ("data/p/cube.step", "cube.stl"), ("data/p/q/cyl.step", "q/cyl.stl"),
        ("data/p/gone.step", "gone.stl")]
    summary = daemon.client().batch(["@%s" % listing], str(tmp_path / "out"), format="stl")
    assert summary.exit_code == 1 and summary.counts["ok"] == 2
    gone = manifest(tmp_path / "out")[str(tmp_path / "data" / "p" / "gone.step")]
    assert gone["status"] == "unreadable" and gone["reason"] == "no such file"
    assert gone["sha256"] is None and gone["grpc_code"] is None
    assert (tmp_path / "out" / "q" / "cyl.stl").stat().st_size > 84
