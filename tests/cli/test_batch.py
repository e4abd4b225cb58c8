"""`rdmesh batch` (clients/cli/batch.h, docs/BATCH.md): a tree of models in, a mirrored tree of
meshes and OUTDIR/manifest.jsonl out, each file in a process of its own.

Hangs, crashes and half-written outputs are acted out by a stand-in mesher (FAKE below, put in
the real one's place with RDMESH_BATCH_MESHER): a model whose first line is `FAKE ACTION ...`
makes it do ACTION; it hands any other model to the real `rdmesh mesh`."""

import hashlib
import json
import os
import pathlib
import pty
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest

from test_fuzz_regressions import documented_cases

GOOD = ["axom_sliced_cylinder.step", "cq_red_cube_blue_cylinder.step", "nist_mbe_pmi_11.stp",
        "pyocc_eight_cyl.stp"]
FIELDS = ["path", "sha256", "bytes", "status", "reason", "faces", "faces_failed", "triangles",
          "requested_deviation", "estimated_deviation", "seconds", "output", "reader", "exit_code",
          "signal", "options"]

FAKE = r'''#!/usr/bin/python3
import json, os, signal, subprocess, sys, time
args = sys.argv[1:]
model, out = args[1], args[args.index("-o") + 1]
with open(model, "rb") as f:
    words = f.readline().decode(errors="replace").split()
if words[:1] != ["FAKE"]:
    real = os.environ["RDMESH_CLI"]
    os.execv(real, [real] + args)
action = words[1]

def note(*pids):  # the pids this run started, for the test to check they are gone
    with open(words[2], "a") as f:
        f.write("".join("%d\n" % pid for pid in pids))

if action == "segv":
    os.kill(os.getpid(), signal.SIGSEGV)
elif action == "hang":  # ignores --timeout, and starts a process of its own
    sleeper = subprocess.Popen(["sleep", "1000"])
    note(os.getpid(), sleeper.pid)
    time.sleep(1000)
elif action == "partial":  # writes half of its output, then hangs
    with open(out, "wb") as f:
        f.write(b"glTF half")
    note(os.getpid())
    time.sleep(1000)
elif action == "slow":  # takes its time, then writes a mesh and a report
    time.sleep(float(words[2]))
    with open(out, "wb") as f:
        f.write(b"glTF fake mesh")
    print(json.dumps({"model": model, "output": out, "triangles": 12, "faces_ok": 6,
                      "faces_failed": 0, "faces_skipped": 0, "faces_over_criteria": 0,
                      "requested_deviation": 0.01, "estimated_deviation": 0.005, "faces": []}))
'''


@pytest.fixture
def fake(tmp_path):
    """The environment that runs the stand-in mesher in the children."""
    path = tmp_path / "fake_mesher.py"
    path.write_text(FAKE)
    path.chmod(0o755)
    return dict(os.environ, RDMESH_BATCH_MESHER=str(path))


def batch(cli, *args, env=None, timeout=600):
    """Runs `rdmesh batch ARGS --json`; returns (exit code, summary or None, stderr)."""
    completed = subprocess.run([str(cli), "batch", *map(str, args), "--json"],
                               capture_output=True, text=True, timeout=timeout, env=env)
    lines = [line for line in completed.stdout.splitlines() if line.strip()]
    summary = json.loads(lines[-1]) if lines else None
    return completed.returncode, summary, completed.stderr


def manifest(out):
    """OUTDIR/manifest.jsonl as {input path: entry}, checking one line per input."""
    entries = [json.loads(line) for line in (out / "manifest.jsonl").read_text().splitlines()]
    by_path = {entry["path"]: entry for entry in entries}
    assert len(by_path) == len(entries)
    return by_path


def sha256(path):
    return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()


def gone(pid, wait=10.0):
    """Whether process `pid` has ended (or is a zombie) within `wait` seconds."""
    deadline = time.monotonic() + wait
    while time.monotonic() < deadline:
        try:
            state = pathlib.Path("/proc/%d/stat" % pid).read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            return True
        if state == "Z":
            return True
        time.sleep(0.05)
    return False


def fake_model(path, *words):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("FAKE " + " ".join(map(str, words)) + "\n")
    return path


def wait_for(predicate, wait=30.0):
    deadline = time.monotonic() + wait
    while not predicate():
        assert time.monotonic() < deadline, "timed out waiting"
        time.sleep(0.05)


@pytest.fixture
def dataset(data_dir, tmp_path):
    """in/: the good models (two in a subfolder), an empty file and a malformed one."""
    root = tmp_path / "in"
    (root / "sub" / "deeper").mkdir(parents=True)
    shutil.copy(data_dir / GOOD[0], root / GOOD[0])
    shutil.copy(data_dir / GOOD[1], root / GOOD[1])
    shutil.copy(data_dir / GOOD[2], root / "sub" / GOOD[2])
    shutil.copy(data_dir / GOOD[3], root / "sub" / "deeper" / GOOD[3])
    (root / "sub" / "empty.step").write_bytes(b"")
    shutil.copy(data_dir / "fuzz" / "refused_dangling_face_surface.step",
                root / "sub" / "malformed.step")
    (root / "notes.txt").write_text("not a model")
    return root


def test_tree_manifest_and_exit_code(cli, run, dataset, tmp_path):
    out = tmp_path / "out"
    code, summary, stderr = batch(cli, dataset, "-o", out, "--jobs", 2)
    assert code == 1, stderr  # two files are not ok
    entries = manifest(out)
    rel = {str(pathlib.Path(path).relative_to(dataset)): entry for path, entry in entries.items()}
    assert sorted(rel) == sorted([GOOD[0], GOOD[1], "sub/" + GOOD[2], "sub/deeper/" + GOOD[3],
                                  "sub/empty.step", "sub/malformed.step"])
    for name, entry in rel.items():
        assert list(entry) == FIELDS
        assert entry["sha256"] == sha256(dataset / name)
        assert entry["bytes"] == (dataset / name).stat().st_size
        assert entry["seconds"] > 0
    for name in [GOOD[0], GOOD[1], "sub/" + GOOD[2], "sub/deeper/" + GOOD[3]]:
        entry = rel[name]
        assert entry["status"] == "ok" and entry["reason"] == "", entry
        # The output mirrors the input's path, in the default format (.glb).
        assert entry["output"] == str(pathlib.Path(name).with_suffix(".glb"))
        assert (out / entry["output"]).read_bytes()[:4] == b"glTF"
        info = run("info", dataset / name, "--json").json
        assert entry["faces"] == info["faces"] and entry["faces_failed"] == 0
        assert entry["triangles"] > 0
        assert 0 < entry["estimated_deviation"] <= entry["requested_deviation"]
        assert entry["exit_code"] == 0 and entry["signal"] is None
        assert entry["reader"] == info["reader"]  # whichever reader read it
    empty = rel["sub/empty.step"]
    assert empty["status"] == "unreadable" and "empty" in empty["reason"]
    assert empty["output"] is None and empty["triangles"] is None
    malformed = rel["sub/malformed.step"]
    assert malformed["status"] == "unreadable" and malformed["reason"]
    assert summary["counts"] == {"ok": 4, "failed": 0, "crashed": 0, "timed_out": 0,
                                 "unreadable": 2}
    assert summary["files"] == 6 and summary["meshed"] == 6 and summary["skipped"] == 0
    assert summary["files_per_minute"] > 0
    # Nothing else in the tree: no mesh for the files that failed, no partial files.
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert written == sorted([".rdmesh-batch.lock", "manifest.jsonl", "axom_sliced_cylinder.glb",
                              "cq_red_cube_blue_cylinder.glb", "sub/nist_mbe_pmi_11.glb",
                              "sub/deeper/pyocc_eight_cyl.glb"])


def test_all_ok_exits_0_and_options_reach_the_child(cli, run, data_dir, tmp_path):
    out = tmp_path / "out"
    args = ["--format", "msh", "--max-deviation-rel", "2e-3", "--no-edges"]
    code, summary, stderr = batch(cli, *[data_dir / name for name in GOOD], "-o", out, *args)
    assert code == 0, stderr
    assert summary["counts"]["ok"] == 4
    for name in GOOD:
        entry = manifest(out)[str(data_dir / name)]
        assert entry["options"] == {"--max-deviation-rel": "2e-3", "--edges": "false"}
        # The same mesh, byte for byte, as `rdmesh mesh` with those options.
        alone = tmp_path / (name + ".msh")
        report = run("mesh", data_dir / name, "-o", alone, "--json", "--max-deviation-rel",
                     "2e-3", "--no-edges").json
        assert (out / entry["output"]).read_bytes() == alone.read_bytes()
        assert entry["triangles"] == report["triangles"]
        assert entry["estimated_deviation"] == report["estimated_deviation"]


def test_resume(cli, data_dir, tmp_path):
    models = tmp_path / "in"
    models.mkdir()
    for name in GOOD:
        shutil.copy(data_dir / name, models / name)
    out = tmp_path / "out"
    code, summary, _ = batch(cli, models, "-o", out)
    assert code == 0 and summary["meshed"] == 4
    first = manifest(out)
    mtimes = {p: p.stat().st_mtime_ns for p in out.glob("*.glb")}

    code, summary, _ = batch(cli, models, "-o", out)
    assert code == 0 and summary["meshed"] == 0 and summary["skipped"] == 4
    assert summary["counts"]["ok"] == 4
    assert manifest(out) == first
    assert {p: p.stat().st_mtime_ns for p in out.glob("*.glb")} == mtimes

    # New bytes (a comment after the data), a deleted output: those two run again.
    with open(models / GOOD[0], "a") as f:
        f.write("/* changed */\n")
    (out / "cq_red_cube_blue_cylinder.glb").unlink()
    code, summary, _ = batch(cli, models, "-o", out)
    assert code == 0 and summary["meshed"] == 2 and summary["skipped"] == 2
    again = manifest(out)
    assert again[str(models / GOOD[0])]["sha256"] == sha256(models / GOOD[0])
    assert again[str(models / GOOD[0])]["sha256"] != first[str(models / GOOD[0])]["sha256"]
    assert (out / "cq_red_cube_blue_cylinder.glb").is_file()

    # Other meshing options make other meshes: everything runs again; --threads does not.
    code, summary, _ = batch(cli, models, "-o", out, "--threads", 1)
    assert summary["skipped"] == 4
    code, summary, _ = batch(cli, models, "-o", out, "--max-deviation-rel", "5e-3")
    assert code == 0 and summary["meshed"] == 4


def test_fuzz_files_status_is_what_rdmesh_mesh_does(cli, data_dir, tmp_path):
    """Each file of tests/data/fuzz (crashes and hangs found by fuzzing, README there) gets the
    status that a run of `rdmesh mesh` in one process (RDMESH_NO_FORK=1, as the batch's children
    run) leads to: a signal is a crash, exit 3 unreadable, 4 timed out, 1 or failed faces failed."""
    out = tmp_path / "out"
    code, summary, stderr = batch(cli, data_dir / "fuzz", "-o", out, "--timeout", 2, timeout=300)
    assert code == 1, stderr
    entries = manifest(out)
    names = sorted(documented_cases(data_dir))
    assert sorted(entries) == [str(data_dir / "fuzz" / name) for name in names]
    for name in names:
        entry = entries[str(data_dir / "fuzz" / name)]
        alone = subprocess.run([str(cli), "mesh", str(data_dir / "fuzz" / name), "-o",
                                str(tmp_path / "alone.glb"), "--json", "--timeout", "2"],
                               capture_output=True, text=True, timeout=60,
                               env=dict(os.environ, RDMESH_NO_FORK="1"))
        lines = [line for line in alone.stdout.splitlines() if line.strip()]
        report = json.loads(lines[-1]) if lines else {}
        if alone.returncode < 0:
            assert entry["status"] == "crashed", entry
            assert entry["signal"] == signal.Signals(-alone.returncode).name
        elif alone.returncode == 4:  # stopped by itself, or killed 0.5 s later
            assert entry["status"] == "timed_out", entry
        elif alone.returncode == 0 and report["faces_failed"] == 0:
            assert entry["status"] == "ok", entry
        else:
            status = {0: "failed", 1: "failed", 3: "unreadable"}[alone.returncode]
            assert entry["status"] == status, entry
            if "error" in report:
                assert entry["reason"] == report["error"]["message"]
            else:
                assert entry["faces_failed"] == report["faces_failed"] > 0
                assert entry["triangles"] == report["triangles"]
        assert entry["seconds"] < 30
    assert sum(summary["counts"].values()) == len(entries)


def test_timeout_on_a_real_slow_file(cli, data_dir, tmp_path):
    out = tmp_path / "out"
    slow = data_dir / "fuzz" / "slow_mesher_absurd_point.step"  # meshes for ~48 s unstopped
    start = time.monotonic()
    code, summary, _ = batch(cli, slow, data_dir / GOOD[0], "-o", out, "--timeout", 1)
    assert code == 1
    entries = manifest(out)
    assert entries[str(slow)]["status"] == "timed_out"
    assert entries[str(slow)]["seconds"] < 3  # stopped by itself, or killed at 1.5 s
    assert entries[str(data_dir / GOOD[0])]["status"] == "ok"
    assert time.monotonic() - start < 20
    assert summary["counts"]["timed_out"] == 1


def test_a_hang_is_killed_with_what_it_started(cli, data_dir, fake, tmp_path):
    pids = tmp_path / "pids"
    models = tmp_path / "in"
    fake_model(models / "hang.step", "hang", pids)
    shutil.copy(data_dir / GOOD[1], models / GOOD[1])
    code, summary, _ = batch(cli, models, "-o", tmp_path / "out", "--timeout", 1, env=fake)
    assert code == 1
    entries = manifest(tmp_path / "out")
    hang = entries[str(models / "hang.step")]
    assert hang["status"] == "timed_out" and hang["signal"] == "SIGKILL"
    assert "killed after 1.5 s" in hang["reason"]
    assert 1.5 <= hang["seconds"] < 5
    assert entries[str(models / GOOD[1])]["status"] == "ok"
    started = [int(pid) for pid in pids.read_text().split()]
    assert len(started) == 2 and all(gone(pid) for pid in started)


def test_a_crash_costs_its_file_only(cli, data_dir, fake, tmp_path):
    models = tmp_path / "in"
    fake_model(models / "a_crash.step", "segv")
    for name in GOOD:
        shutil.copy(data_dir / name, models / name)
    code, summary, _ = batch(cli, models, "-o", tmp_path / "out", env=fake)
    assert code == 1
    entries = manifest(tmp_path / "out")
    crash = entries[str(models / "a_crash.step")]
    assert crash["status"] == "crashed" and crash["signal"] == "SIGSEGV"
    assert "SIGSEGV" in crash["reason"] and crash["output"] is None
    assert summary["counts"] == {"ok": 4, "failed": 0, "crashed": 1, "timed_out": 0,
                                 "unreadable": 0}


def test_memory_limit(cli, data_dir, tmp_path):
    # 64 MiB of address space is less than the process needs to start meshing (it maps some
    # 70 libraries; 100 MiB was enough once OCCT's STEP readers were no longer loaded at start).
    code, summary, _ = batch(cli, data_dir / GOOD[2], "-o", tmp_path / "out", "--memory-limit",
                             "64MiB")
    assert code == 1 and summary["memory_limit"] == 64 << 20
    entry = manifest(tmp_path / "out")[str(data_dir / GOOD[2])]
    assert entry["status"] == "crashed" and "out of memory" in entry["reason"]
    assert "--memory-limit 64 MiB" in entry["reason"]
    code, summary, _ = batch(cli, data_dir / GOOD[2], "-o", tmp_path / "out", "--memory-limit",
                             "2GiB")
    assert code == 0


def test_killed_run_leaves_no_half_written_output(cli, data_dir, fake, tmp_path):
    pids = tmp_path / "pids"
    models = tmp_path / "in"
    fake_model(models / "sub" / "half.step", "partial", pids)
    shutil.copy(data_dir / GOOD[0], models / GOOD[0])
    out = tmp_path / "out"
    process = subprocess.Popen([str(cli), "batch", str(models), "-o", str(out), "--jobs", "1"],
                               env=fake, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    partial = out / "sub" / ".half.glb.partial.glb"
    wait_for(lambda: pids.exists() and partial.exists())
    process.kill()  # SIGKILL: no chance to clean up
    process.wait()
    [child] = [int(pid) for pid in pids.read_text().split()]
    assert gone(child)  # PR_SET_PDEATHSIG
    assert not (out / "sub" / "half.glb").exists()
    assert (out / "axom_sliced_cylinder.glb").read_bytes()[:4] == b"glTF"
    # The next run completes it and removes the partial file.
    fake_model(models / "sub" / "half.step", "slow", 0.1)
    code, summary, _ = batch(cli, models, "-o", out, env=fake)
    assert code == 0 and summary["skipped"] == 1 and summary["meshed"] == 1
    assert (out / "sub" / "half.glb").read_bytes() == b"glTF fake mesh"
    assert not partial.exists()


def test_sigterm_stops_now_and_removes_partials(cli, fake, tmp_path):
    pids = tmp_path / "pids"
    models = tmp_path / "in"
    fake_model(models / "half.step", "partial", pids)
    fake_model(models / "later.step", "slow", 0.1)
    out = tmp_path / "out"
    process = subprocess.Popen([str(cli), "batch", str(models), "-o", str(out), "--jobs", "1",
                                "--json"], env=fake, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    wait_for(lambda: pids.exists() and (out / ".half.glb.partial.glb").exists())
    process.send_signal(signal.SIGTERM)
    stdout, stderr = process.communicate(timeout=30)
    assert process.returncode == 4, stderr
    summary = json.loads(stdout.splitlines()[-1])
    assert summary["interrupted"] and summary["not_done"] == 2
    assert gone(int(pids.read_text().split()[0]))
    assert sorted(p.name for p in out.iterdir()) == [".rdmesh-batch.lock", "manifest.jsonl"]
    assert (out / "manifest.jsonl").read_text() == ""


def test_ctrl_c_finishes_the_running_files(cli, fake, tmp_path):
    models = tmp_path / "in"
    for i in range(4):
        fake_model(models / ("m%d.step" % i), "slow", 1.5)
    out = tmp_path / "out"
    process = subprocess.Popen([str(cli), "batch", str(models), "-o", str(out), "--jobs", "2",
                                "--json"], env=fake, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    time.sleep(0.7)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=30)
    assert process.returncode == 4, stderr
    assert "Ctrl-C again" in stderr
    summary = json.loads(stdout.splitlines()[-1])
    assert summary["meshed"] == 2 and summary["not_done"] == 2
    assert sorted(manifest(out)) == [str(models / "m0.step"), str(models / "m1.step")]
    code, summary, _ = batch(cli, models, "-o", out, env=fake)
    assert code == 0 and summary["skipped"] == 2 and summary["meshed"] == 2


def test_second_ctrl_c_stops_now(cli, fake, tmp_path):
    pids = tmp_path / "pids"
    models = tmp_path / "in"
    fake_model(models / "half.step", "partial", pids)
    out = tmp_path / "out"
    process = subprocess.Popen([str(cli), "batch", str(models), "-o", str(out)], env=fake,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for(lambda: pids.exists())
    process.send_signal(signal.SIGINT)
    time.sleep(0.5)
    assert process.poll() is None  # waits for the running file
    process.send_signal(signal.SIGINT)
    process.communicate(timeout=30)
    assert process.returncode == 4
    assert not list(out.glob("*.glb")) and not list(out.glob(".*partial*"))


def test_one_run_per_output_folder(cli, fake, tmp_path):
    models = tmp_path / "in"
    fake_model(models / "slow.step", "slow", 2)
    out = tmp_path / "out"
    process = subprocess.Popen([str(cli), "batch", str(models), "-o", str(out)], env=fake,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        wait_for(lambda: (out / ".rdmesh-batch.lock").exists())
        time.sleep(0.3)
        code, _, stderr = batch(cli, models, "-o", out, env=fake)
        assert code == 2 and "another rdmesh batch is writing" in stderr
    finally:
        process.wait(timeout=30)
    assert process.returncode == 0


def test_inputs_lists_files_and_collisions(cli, data_dir, fake, tmp_path):
    models = tmp_path / "data"
    fake_model(models / "a" / "x.step", "slow", 0)
    fake_model(models / "a" / "x.stp", "slow", 0)
    fake_model(models / "b" / "y.iges", "slow", 0)
    fake_model(tmp_path / "elsewhere" / "z.brep", "slow", 0)
    listing = models / "list.txt"
    listing.write_text("# a comment\n\na/x.step\na/x.stp\r\nb\nmissing.step\n")
    out = tmp_path / "out"
    code, summary, stderr = batch(cli, "@%s" % listing, tmp_path / "elsewhere" / "z.brep",
                                  data_dir / GOOD[0], "-o", out, "--format", "stl", env=fake)
    assert code == 1, stderr  # missing.step
    entries = manifest(out)
    outputs = {str(pathlib.Path(p).relative_to(tmp_path)): e["output"]
               for p, e in entries.items() if p.startswith(str(tmp_path) + "/")}
    assert outputs == {"data/a/x.step": "a/x.step.stl", "data/a/x.stp": "a/x.stp.stl",
                       "data/b/y.iges": "b/y.stl", "data/missing.step": None,
                       "elsewhere/z.brep": "z.stl"}
    assert entries[str(models / "missing.step")]["status"] == "unreadable"
    assert entries[str(models / "missing.step")]["reason"] == "no such file"
    assert entries[str(data_dir / GOOD[0])]["output"] == "axom_sliced_cylinder.stl"
    for entry in entries.values():
        if entry["output"]:
            assert (out / entry["output"]).is_file()
    # Two inputs that would write one output are refused before anything runs.
    code, _, stderr = batch(cli, models / "a" / "x.step", tmp_path / "elsewhere", models / "a",
                            "-o", tmp_path / "out2", env=fake)
    assert code == 0  # x.step named twice counts once; z.brep and a/ do not collide
    fake_model(tmp_path / "other" / "x.step", "slow", 0)
    code, _, stderr = batch(cli, models / "a" / "x.step", tmp_path / "other" / "x.step", "-o",
                            tmp_path / "out3", env=fake)
    assert code == 2 and "would both write 'x.glb'" in stderr
    assert not (tmp_path / "out3").exists()
    code, _, stderr = batch(cli, tmp_path / "nothing_here", "-o", tmp_path / "out4")
    assert code == 2 and "no such file or folder" in stderr
    code, _, stderr = batch(cli, models, "-o", tmp_path / "out5", "--format", "wrl")
    assert code == 2 and "--format" in stderr


def test_output_folder_inside_the_input_folder(cli, fake, tmp_path):
    fake_model(tmp_path / "m.step", "slow", 0)
    code, summary, _ = batch(cli, tmp_path, "-o", tmp_path / "meshes", env=fake)
    assert code == 0 and summary["files"] == 1
    (tmp_path / "meshes" / "copy.step").write_text("FAKE slow 0\n")  # not an input
    code, summary, _ = batch(cli, tmp_path, "-o", tmp_path / "meshes", env=fake)
    assert summary["files"] == 1 and summary["skipped"] == 1


def test_lod_writes_every_level(cli, data_dir, tmp_path):
    out = tmp_path / "out"
    code, _, stderr = batch(cli, data_dir / GOOD[1], "-o", out, "--lod", "1e-2,1e-3")
    assert code == 0, stderr
    entry = manifest(out)[str(data_dir / GOOD[1])]
    levels = entry["levels"]
    assert [level["output"] for level in levels] == [
        "cq_red_cube_blue_cylinder.lod0.glb", "cq_red_cube_blue_cylinder.lod1.glb"]
    assert entry["output"] == levels[-1]["output"]
    assert levels[0]["triangles"] < levels[1]["triangles"] == entry["triangles"]
    assert all((out / level["output"]).is_file() for level in levels)
    code, summary, _ = batch(cli, data_dir / GOOD[1], "-o", out, "--lod", "1e-2,1e-3")
    assert summary["skipped"] == 1


def test_progress_on_a_terminal(cli, fake, tmp_path):
    models = tmp_path / "in"
    for i in range(6):
        fake_model(models / ("m%d.step" % i), "slow", 0.3)
    fake_model(models / "crash.step", "segv")
    main, replica = pty.openpty()
    process = subprocess.Popen([str(cli), "batch", str(models), "-o", str(tmp_path / "out"),
                                "--jobs", "2"], env=fake, stdout=subprocess.PIPE,
                               stderr=replica, text=True)
    os.close(replica)
    shown = b""
    while True:
        try:
            chunk = os.read(main, 4096)
        except OSError:  # EIO: the process closed the terminal
            break
        if not chunk:
            break
        shown += chunk
    os.close(main)
    stdout, _ = process.communicate(timeout=30)
    assert process.returncode == 1
    text = shown.decode()
    assert re.search(r"\d/7 done, [01] not ok, [\d.]+ files/min, ETA \d+s", text), text
    assert "crashed: %s" % (models / "crash.step") in text
    # The summary: counts per status, throughput, the slowest files.
    assert "ok 6 failed 0 crashed 1 timed_out 0 unreadable 0" in stdout
    assert "files/min" in stdout and "slowest:" in stdout


def test_compress_needs_glb(cli, data_dir, tmp_path):
    code, _, err = batch(cli, data_dir / GOOD[0], "-o", tmp_path / "out", "--format", "msh",
                         "--compress")
    assert code == 2 and "--compress writes .glb only" in err
    code, summary, _ = batch(cli, data_dir / GOOD[0], "-o", tmp_path / "out2", "--compress")
    assert code == 0 and summary["counts"]["ok"] == 1
    out = next((tmp_path / "out2").rglob("*.glb"))
    assert b"EXT_meshopt_compression" in out.read_bytes()[:65536]
