"""rdmeshd --cache-dir: a model that one daemon's worker parsed is read from the shared store by
another daemon (a restart, a replica on the same volume), without a STEP parse, and meshes to the
same bytes."""

import subprocess

from conftest import CLI, EIGHT_CYL


def _mesh_remote(daemon, model, out):
    completed = subprocess.run([CLI, "mesh", str(model), "-o", str(out), "--remote",
                                daemon.address, "--quiet"], capture_output=True, text=True,
                               timeout=300)
    assert completed.returncode == 0, completed.stderr
    return out.read_bytes()


def test_second_daemon_reads_the_store(start_daemon, tmp_path):
    store = tmp_path / "store"
    first = start_daemon("--cache-dir", str(store))
    uploaded = first.client().upload(EIGHT_CYL)
    assert not uploaded.cached and not uploaded.from_store
    first_mesh = _mesh_remote(first, EIGHT_CYL, tmp_path / "first.msh")
    assert "read from the store" not in first.log()
    assert "'%s' parsed in" % EIGHT_CYL.name in first.log()
    entries = list(store.glob("*.rdm"))
    assert [p.name for p in entries] == ["%s-step.rdm" % uploaded.model_id]
    assert first.stop() == 0

    # Another daemon on the same directory, set through the environment this time.
    second = start_daemon(env={"RDMESH_CACHE_DIR": str(store)})
    again = second.client().upload(EIGHT_CYL)
    assert again.model_id == uploaded.model_id
    assert not again.cached  # not in this daemon's memory...
    assert again.from_store
    assert "'%s' read from the store in" % EIGHT_CYL.name in second.log()  # ...nor parsed
    assert "'%s' parsed in" % EIGHT_CYL.name not in second.log()
    assert again.faces == uploaded.faces and list(again.bbox) == list(uploaded.bbox)
    assert not second.client().upload(EIGHT_CYL).from_store  # now cached: no load at all
    assert _mesh_remote(second, EIGHT_CYL, tmp_path / "second.msh") == first_mesh


def test_cli_and_daemon_share_entries(start_daemon, tmp_path):
    store = tmp_path / "store"
    daemon = start_daemon("--cache-dir", str(store))
    daemon.client().upload(EIGHT_CYL)
    completed = subprocess.run([CLI, "info", str(EIGHT_CYL), "--json", "--cache-dir", str(store)],
                               capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr
    assert '"from_store":true' in completed.stdout.replace(" ", "")
